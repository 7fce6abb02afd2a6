"""The calibration's entries of the benchmark: ``softclose fit`` end to end in a fresh
interpreter (start-up, reading, the fit, its statistics, the JSON), on synthetic records of
known truth written to a temporary folder (:mod:`softclose.calibration.synthetic`):

- ``fit_cli_2x1``: 2 keys (the damper and the lid's inertia, the lid weighed) from one 1.1 s
  stroke at 120 Hz (the issue's target: 2 s);
- ``fit_cli_5x3``: 5 keys (damper, inertia, spring rate, preload, friction) from 3 strokes
  (a video at 18 deg, a phone's gyroscope at 14 deg, a video at 10 deg; target 10 s).
"""

from __future__ import annotations

import json
import subprocess
import tempfile
from pathlib import Path

from .timing import fresh_command, fresh_env
from ..config import default_config
from ..calibration.synthetic import angle_track, gyroscope_track, write_csv

#: the README's optimum as a built prototype (a compression spring)
PROTOTYPE = {"design.spring_kind": "compression", "design.spring_k": 1914.709,
             "design.spring_rest_length": 0.07925707, "design.damper_c": 2087.754}
KEYS_2 = ("design.damper_c", "mass.inertia_lid")
KEYS_5 = ("design.damper_c", "mass.inertia_lid", "design.spring_k", "design.spring_preload",
          "friction.torque")


def _sets(values: dict) -> list[str]:
    out = []
    for k, v in values.items():
        out += ["--set", f"{k}={json.dumps(v)}"]
    return out


def fit_entries(rows: list, timed, repeats: int) -> None:
    """Time both fits with ``timed(key, what, fn, repeats)`` (the feature entries' timer: the
    median of the repeats, the machine's load recorded; it appends the row to ``rows``);
    each row's note gives the fit's iterations, samples and identifiability verdict."""
    base = default_config().update(PROTOTYPE)
    truth = base.update({"mass.inertia_lid": 0.0125, "friction.torque": 0.02,
                         "design.spring_preload": 1.0})
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        one = tmp / "stroke.csv"
        write_csv(angle_track(base, seed=1), one)
        three = [tmp / "s18.csv", tmp / "g14.csv", tmp / "s10.csv"]
        write_csv(angle_track(truth, seed=2), three[0])
        write_csv(gyroscope_track(truth.set("stroke.theta0_deg", 14.0), seed=3), three[1])
        write_csv(angle_track(truth.set("stroke.theta0_deg", 10.0), seed=4), three[2])
        for key, what, files, keys, start in (
                ("fit_cli_2x1", "softclose fit: damper and lid inertia from one 1.1 s stroke "
                 "at 120 Hz, fresh interpreter, end to end", [one], KEYS_2, {}),
                ("fit_cli_5x3", "softclose fit: damper, inertia, spring rate, preload and "
                 "friction from 3 strokes (video 18°, gyroscope 14°, video 10°), fresh "
                 "interpreter, end to end", three, KEYS_5,
                 {"design.spring_preload": 0.5, "friction.torque": 0.01})):
            reply = {}

            def call(files=files, keys=keys, start=start, reply=reply):
                argv = [*fresh_command("-m", "softclose"), "fit", *map(str, files),
                        *[a for k in keys for a in ("--free", k)],
                        *_sets({k: v for k, v in PROTOTYPE.items() if k not in keys}),
                        *_sets(start), "--json"]
                r = subprocess.run(argv, capture_output=True, text=True, env=fresh_env())
                if r.returncode not in (0, 3):
                    raise RuntimeError(f"exit {r.returncode}: {r.stderr.strip()[-300:]}")
                reply["out"] = json.loads(r.stdout)
            if timed(key, what, call, repeats) is None and not reply:
                continue
            d = reply["out"]
            rows[-1]["note"] = (
                f"{d['iterations']} Ipopt iterations, {d['samples_used']} samples; "
                f"identifiable: {d['identifiable']}"
                + (f" ({' / '.join(d['collinear'])})" if d.get("collinear") else ""))


__all__ = ["fit_entries", "KEYS_2", "KEYS_5"]

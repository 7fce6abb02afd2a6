"""`softclose state` (SPEC §7): keys, SPEC §8 values, and self-consistent reactions.

The reactions are checked on the whole mechanism, independently of the solver: the sum of
the external forces (ground pins O and B, the three weights, spring and dashpot) equals the
total mass times the acceleration of the mass centre, and the same for moments about O
(accelerations from finite differences of model.kin positions, conftest.body_motion).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from conftest import body_motion, cross2, external_forces, wrap_deg
from softclose import cli
from softclose.config import default_config
from softclose.problem import params_of

STATE_KEYS = {"theta", "theta_dot", "theta_ddot", "phi", "gamma", "phi_dot", "gamma_dot",
              "tip_velocity", "reactions"}


def run_json(capsys, argv):
    rc = cli.main(argv + ["--json"])
    out, err = capsys.readouterr()
    assert rc == 0, err
    lines = [ln for ln in out.splitlines() if ln.strip()]
    assert len(lines) == 1, out        # one JSON object on stdout
    return json.loads(lines[0])


def test_state_json_keys_and_spec8_values(capsys):
    s = run_json(capsys, ["state", "--theta-deg", "18"])
    assert set(s) == STATE_KEYS
    assert set(s["reactions"]) == {"O", "A", "B", "C"}
    assert all(len(v) == 2 for v in s["reactions"].values())
    assert len(s["tip_velocity"]) == 2
    assert s["theta"] == pytest.approx(math.radians(18.0), abs=1e-15)
    assert s["theta_dot"] == 0.0
    assert abs(wrap_deg(math.degrees(s["phi"]) - 108.6655)) <= 0.5e-4     # radians in JSON
    assert abs(wrap_deg(math.degrees(s["gamma"]) - 146.8855)) <= 0.5e-4
    assert abs(s["theta_ddot"] - (-28.5296)) <= 1e-4
    assert s["phi_dot"] == 0.0 and s["gamma_dot"] == 0.0
    assert s["tip_velocity"] == [0.0, 0.0]


def _write_toml(path, cfg):
    g, m = cfg.geometry, cfg.mass
    vec = lambda v: "[" + ", ".join(repr(float(x)) for x in v) + "]"  # noqa: E731
    path.write_text(
        "[geometry]\n"
        f"crank_oa = {g.crank_oa!r}\ncrank_bc = {g.crank_bc!r}\npivot_b = {vec(g.pivot_b)}\n"
        f"spring_anchor = {vec(g.spring_anchor)}\nassembly = {vec(g.assembly)}\n"
        f"[mass]\nlid = {m.lid!r}\n")
    return path


def _whole_mechanism_residuals(model, s, p):
    th, thd, tdd = s["theta"], s["theta_dot"], s["theta_ddot"]
    pos, vel, acc = body_motion(model, th, thd, tdd)
    m = model.mass
    R = {k: np.asarray(v) for k, v in s["reactions"].items()}
    F_s, F_d, M_rot = external_forces(model, pos, vel, thd, p)
    bodies = (("G1", m.lid, m.inertia_lid, "theta"), ("G2", m.crank_oa, m.inertia_oa, "phi"),
              ("G3", m.crank_bc, m.inertia_bc, "gamma"))
    weights = sum(np.array([0.0, -mb * m.gravity]) for _, mb, _, _ in bodies)
    F_ext = R["O"] + R["B"] + weights + F_s + F_d
    ma = sum(mb * acc[g] for g, mb, _, _ in bodies)
    M_ext = (cross2(pos["B"], R["B"]) + cross2(pos["E"], F_s) + cross2(pos["C"], F_d) + M_rot
             + sum(cross2(pos[g], np.array([0.0, -mb * m.gravity])) for g, mb, _, _ in bodies))
    alpha = {"theta": tdd, "phi": acc["phi"], "gamma": acc["gamma"]}
    dH = sum(cross2(pos[g], mb * acc[g]) + Ib * alpha[a] for g, mb, Ib, a in bodies)
    scale = max(max(np.abs(v).max() for v in R.values()), m.lid * m.gravity)
    return F_ext - ma, M_ext - dH, scale


@pytest.mark.parametrize("which", ["default", "second"])
@pytest.mark.parametrize("theta_deg,theta_dot,design", [
    (18.0, 0.0, {}),
    (7.5, -3.2, {"spring_k": 800.0, "spring_rest_length": 0.08, "damper_c": 40.0,
                 "rotary_damper_c": 0.01}),
    (0.0, -4.0, {"spring_k": 2500.0, "spring_rest_length": 0.03, "damper_c": 400.0}),
])
def test_state_reactions_are_self_consistent(capsys, tmp_path, which, theta_deg, theta_dot,
                                            design, model, model2, cfg2):
    mdl = model if which == "default" else model2
    argv = ["state", "--theta-deg", repr(theta_deg), "--theta-dot", repr(theta_dot)]
    if which == "second":
        argv += ["--config", str(_write_toml(tmp_path / "second.toml", cfg2))]
    argv += [f"--set=design.{k}={v!r}" for k, v in design.items()]
    s = run_json(capsys, argv)
    p = params_of(default_config() if which == "default" else cfg2, design)
    assert s["theta_ddot"] == pytest.approx(mdl.theta_ddot(s["theta"], theta_dot, p), rel=1e-12)
    dF, dM, scale = _whole_mechanism_residuals(mdl, s, p)
    assert np.abs(dF).max() < 1e-7 * scale
    assert abs(dM) < 1e-7 * scale * mdl.geo.lid_length
    # tip velocity = theta' x dT/dtheta, |v_T| = tau |theta'|
    pos, vel, _ = body_motion(mdl, s["theta"], theta_dot, 0.0)
    np.testing.assert_allclose(s["tip_velocity"], vel["T"], rtol=1e-8, atol=1e-12)


def test_state_text_output(capsys):
    rc = cli.main(["state", "--theta-deg", "18"])
    out, err = capsys.readouterr()
    assert rc == 0 and err == ""
    assert "theta''" in out and "-28.5295" in out and "108.66" in out

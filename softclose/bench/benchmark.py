"""The whole benchmark (:func:`run`): work precision, speed, optimiser, with the machine, the
date, the commit and the load it ran under (:class:`BenchResult`).
"""

from __future__ import annotations

import datetime
import os
import platform
import subprocess
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..config import Config
from ..present.display import Display, Displayed, Table, num
from ..problem import RELATIVE, TARGETS
from .features import optimiser_study
from .precision import WorkPrecision, work_precision
from .calls import speed
from .timing import SPEED_TARGETS
from ..jsonio import jsonable

def machine() -> str:
    """CPU, cores, OS, Python, NumPy and CasADi versions of this machine."""
    cpu = platform.processor() or ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    import casadi
    return (f"{cpu}, {os.cpu_count()} cores; {platform.system()} {platform.release()}; "
            f"Python {platform.python_version()}, NumPy {np.__version__}, "
            f"CasADi {casadi.__version__}")


def commit() -> str | None:
    """The git commit of this source tree (with "+dirty" if it has changes), if known."""
    root = Path(__file__).resolve().parents[2]
    try:
        h = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=root, text=True,
                           capture_output=True, timeout=10)
        if h.returncode != 0:
            return None
        d = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=root,
                           text=True, capture_output=True, timeout=10)
        return h.stdout.strip() + ("+dirty" if d.stdout.strip() else "")
    except (OSError, subprocess.SubprocessError):
        return None


@dataclass(frozen=True, repr=False)
class BenchResult(Displayed):
    """Everything one benchmark run measured (see the module docstring)."""

    machine: str
    date: str
    commit: str | None
    quick: bool
    work_precision: WorkPrecision
    speed: tuple
    optimiser: tuple
    optimiser_note: str
    elapsed: float
    config: dict = field(default_factory=dict)
    load: tuple = ()  # 1-minute load average at the start and at the end of the run
    #: the NLP structures of the README's commands (:mod:`softclose.bench.structures`)
    structures: tuple = ()
    #: the default design problem in the tools a user would pick instead
    #: (:mod:`softclose.bench.peers`)
    peers: tuple = ()

    @property
    def default(self) -> dict:
        return self.work_precision.default

    @property
    def success(self) -> bool:
        return True

    def _display(self) -> Display:
        d = self.default
        load = " → ".join("—" if v is None else f"{v:.2f}" for v in self.load)
        facts = [("default step", f"{d['method']} at {d['step']:g} s: "
                  + ("confirmed (the cheapest setting that meets the targets)"
                     if d.get("confirmed") else "meets the targets" if d.get("meets_targets")
                     else "does not meet the targets on " + ", ".join(d["failing_designs"]))),
                 ("machine", self.machine), ("date", self.date),
                 ("commit", self.commit or "—"), ("1-min load average", load or "—"),
                 ("run", f"{self.elapsed:.1f} s" + (" (quick)" if self.quick else ""))]
        rows = []
        for r in self.speed:
            t = r.get("median_s")
            tgt = r.get("target") or {}
            target = (f"≤ {_time(tgt['max_s'])}" if "max_s" in tgt else
                      f"≥ {tgt['min_per_s']:,.0f} /s" if "min_per_s" in tgt else
                      f"≤ {num(tgt['max_ratio'], 3)}×" if "max_ratio" in tgt else "")
            value = _time(t)
            rate = f"{r['rate']:,.0f} {r.get('unit') or ''}/s" if r.get("rate") else \
                (f"{r['ratio']:.2f}× import casadi" if r.get("ratio") is not None else "")
            met = {True: "yes", False: "NO", None: ""}[r.get("met")]
            rows.append((r["what"], value, rate, target, met, r.get("note", "")))
        tables = (Table("speed of the user-facing calls (medians)",
                        ("what", "median", "rate", "target", "met", "note"), rows),)
        missed = [r["what"] for r in self.speed if r.get("met") is False]
        msg = ("targets missed: " + "; ".join(missed)) if missed else ""
        return Display("BenchResult: run time against error, speeds and start-up", None, msg,
                       tuple(facts), tables, short=1)

    def text(self) -> str:
        """What ``softclose bench`` prints: the default step, the tables, the fitted orders."""
        from .report import report_text
        return report_text(self)

    def markdown(self) -> str:
        """The run as a Markdown page (``bench.md``)."""
        from .report import report_markdown
        return report_markdown(self)

    def save(self, folder, figure_format: str = "png", figure_style: str | None = None
             ) -> list[Path]:
        """The run's tables (CSV), page (Markdown), JSON records and figures in ``folder``
        (created if missing): what ``softclose bench --out DIR`` writes. Returns the files."""
        from .report import write_files
        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        return write_files(self, folder, figure_format, figure_style)

    def to_json(self) -> dict:
        return jsonable({"machine": self.machine, "date": self.date, "commit": self.commit,
                         "quick": self.quick, "targets": dict(TARGETS),
                         "relative": list(RELATIVE), "speed_targets": SPEED_TARGETS,
                         "default": self.default,
                         "work_precision": self.work_precision.to_json(),
                         "speed": list(self.speed), "optimiser": list(self.optimiser),
                         "optimiser_note": self.optimiser_note, "elapsed": self.elapsed,
                         "load": list(self.load), "config": self.config,
                         "structures": list(self.structures), "peers": list(self.peers)})


def run(cfg: Config, quick: bool = False, log=None, cli: bool = True,
        optimiser: bool = True, features: bool = True, structures: bool = False,
        peers: bool = False) -> BenchResult:
    """The whole benchmark: work precision, speed, optimiser (see the module docstring);
    with ``structures``, the NLP structures of the README's commands too (their size, build
    and compile times: minutes); with ``peers``, the default design problem in rockit and in
    a scipy notebook beside softclose (:mod:`softclose.bench.peers`: minutes; rockit is the
    ``peers`` extra, refused in one line when missing, before anything runs)."""
    log = log or (lambda *a: None)
    if peers:
        from .peers import require_peers
        require_peers()
    t0 = time.perf_counter()
    load0 = _load()
    log("work precision ...")
    wp = work_precision(cfg, quick=quick, log=log)
    log("speed ...")
    sp = speed(cfg, quick=quick, cli=cli, features=features, log=log)
    log("optimiser ...")
    opt, note = optimiser_study(cfg, quick=quick, log=log) if optimiser else \
        ([], "optimiser section not run")
    st = ()
    if structures:
        log("NLP structures ...")
        from .structures import structure_rows
        st = tuple(structure_rows(cfg, log=log))
    pe = ()
    if peers:
        log("peers ...")
        from .peers import peer_rows
        pe = tuple(peer_rows(cfg, log=log))
    return BenchResult(machine=machine(),
                       date=datetime.datetime.now().astimezone().isoformat(timespec="seconds"),
                       commit=commit(), quick=quick, work_precision=wp, speed=tuple(sp),
                       optimiser=tuple(opt), optimiser_note=note,
                       elapsed=time.perf_counter() - t0,
                       config={"integrator": cfg.simulate.integrator,
                               "step": cfg.simulate.step,
                               "nodes": cfg.optimise.nodes,
                               "substeps": cfg.optimise.substeps},
                       load=(load0, _load()), structures=st, peers=pe)


def _time(t) -> str:
    """Seconds as "1.37 s", "41.0 ms" or "3.5 µs"."""
    if t is None:
        return "—"
    return f"{t:.3g} s" if t >= 1 else f"{t * 1e3:.3g} ms" if t >= 1e-3 else \
        f"{t * 1e6:.3g} µs"


def _load() -> float | None:
    """The 1-minute load average (None where the OS does not give it)."""
    try:
        return os.getloadavg()[0]
    except (AttributeError, OSError):
        return None

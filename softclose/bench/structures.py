"""What each NLP structure of the README's commands costs to build: its size, the time to
build it symbolically, the size of its generated C and the time to compile that.

An NLP is keyed by its structure (:func:`softclose.optimiser.cache.nlp_key`,
:class:`softclose.robust.nlp.ScenarioStructure`): the commands below are run in this
process, and every structure they built is measured. Compiling is what ``softclose
prepare`` does once per structure; the rows say what that costs.
"""

from __future__ import annotations

import os
import subprocess
import tempfile
import time
from pathlib import Path
from ..robust import optimise_robust, scenario_cache as rn
from ..optimiser import cache as oc, optimise
from ..optimiser.compiled import CFLAGS, SCENARIO_CFLAGS

#: the attachment points the co-design frees (docs/codesign.md)
POINTS = (("geometry.spring_anchor[0]", -0.09, -0.03), ("geometry.spring_anchor[1]", -0.01, 0.05),
          ("geometry.lid_e[0]", -0.006, 0.044), ("geometry.lid_e[1]", 0.004, 0.024))

#: the commands whose structures are measured: (name, robust, --free pairs)
COMMANDS = (
    ("optimise", False, ()),
    ("optimise --robust", True, ()),
    ("end-damper co-design", False, (("design.end_damper_c", 0.0, 2.0),
                                     ("design.end_damper_angle_deg", 1.0, 10.0))),
    ("points co-design", False, POINTS),
    ("robust points co-design", True, POINTS),
)


def structures_of(cfg, robust: bool, free: tuple) -> list:
    """The NLP structures one optimisation of ``cfg`` (``free``: (key, lo, hi) set free)
    builds: [(kind, structure)]."""
    if free:
        cfg = cfg.update({"optimise.free": {k: [lo, hi] for k, lo, hi in free}})
    oc.forget()
    rn.forget()
    optimise_robust(cfg) if robust else optimise(cfg)
    return [("nominal", s) for s in oc._STRUCTURES.values()] + \
        [("scenarios", s) for s in rn._STRUCTURES.values()]


def measure(structure, compile_flags: tuple | None = CFLAGS) -> dict:
    """Size and cost of one structure: variables, constraints, build time (s), generated C
    (MB, s) and, with ``compile_flags``, the compile time (s)."""
    solver = structure.solver
    row = {"variables": int(solver.size1_in(0)), "constraints": int(solver.size1_out(2)),
           "parameters": int(solver.size1_in(1)),
           "build_s": float(getattr(structure, "build_time", float("nan")))}
    with tempfile.TemporaryDirectory() as tmp:
        t = time.perf_counter()
        old = os.getcwd()
        try:
            os.chdir(tmp)                     # CasADi writes the file where it stands
            solver.generate_dependencies("nlp.c", {"with_header": False})
        finally:
            os.chdir(old)
        path = Path(tmp) / "nlp.c"
        row["generate_s"] = time.perf_counter() - t
        row["c_mb"] = path.stat().st_size / 1e6
        if compile_flags:
            cc = os.environ.get("CC", "cc")
            t = time.perf_counter()
            subprocess.run([cc, *compile_flags, str(path), "-o", str(path.with_suffix(".so")),
                            "-lm"], check=True, capture_output=True, stdin=subprocess.DEVNULL)
            row["compile_s"] = time.perf_counter() - t
            row["flags"] = next((f for f in compile_flags if f.startswith("-O")), "")
            row["derivatives_vm_ms"], row["derivatives_c_ms"] = derivative_times(
                solver, path.with_suffix(".so"))
    row["prepared"] = structure.prepared
    return row


#: the derivatives an Ipopt iteration evaluates once each
DERIVATIVES = ("nlp_hess_l", "nlp_jac_g")


def derivative_times(solver, library: Path, repeats: int = 5) -> tuple[float, float]:
    """One Hessian of the Lagrangian and one constraint Jacobian of ``solver`` (ms, the
    median of ``repeats``): in CasADi's virtual machine, and from the compiled ``library``
    -- what decides whether ``softclose prepare`` compiles a structure."""
    import casadi as ca
    import numpy as np

    def timed(fns) -> float:
        args = [[np.full(f.size_in(i), 0.5) for i in range(f.n_in())] for f in fns]
        for f, a in zip(fns, args):
            f(*a)
        runs = []
        for _ in range(repeats):
            t = time.perf_counter()
            for f, a in zip(fns, args):
                f(*a)
            runs.append(time.perf_counter() - t)
        return 1e3 * float(np.median(runs))

    vm = [solver.get_function(n) for n in DERIVATIVES]
    c = [ca.external(n, str(library)) for n in DERIVATIVES]
    return timed(vm), timed(c)


def structure_rows(cfg, compile: bool = True, log=None) -> list[dict]:
    """One row per structure of :data:`COMMANDS` on ``cfg`` (a structure two commands
    share is measured once); with ``compile``, its C compiled with the flags ``softclose
    prepare`` uses (the nominal NLP's, the scenario NLP's)."""
    log = log or (lambda *a: None)
    rows, seen = [], set()
    for name, robust, free in COMMANDS:
        for kind, st in structures_of(cfg, robust, free):
            key = getattr(st, "key", None)
            if key in seen:
                continue
            seen.add(key)
            flags = (CFLAGS if kind == "nominal" else SCENARIO_CFLAGS) if compile else None
            row = {"command": name, "nlp": kind, **measure(st, flags)}
            rows.append(row)
            log(f"  {name} ({kind}): {row['c_mb']:.2f} MB of C"
                + (f", {row['compile_s']:.1f} s to compile" if "compile_s" in row else ""))
    return rows


__all__ = ["COMMANDS", "structures_of", "measure", "structure_rows"]

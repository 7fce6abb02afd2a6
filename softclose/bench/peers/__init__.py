"""softclose beside the tools a user would pick instead (``softclose bench --peers``).

The default design problem (SPEC §5: minimise J over the spring rate, its rest length and
the dashpot, with the closing-time bounds, no rebound and the holding moment) solved three
ways in one run, each from nothing built in memory to its optimum:

- ``softclose``: :func:`softclose.optimiser.optimise` with its NLP compiled ahead
  (``softclose prepare``), six starts and its own verification included;
- ``rockit``: :mod:`.rockit_ocp`, multiple shooting in rockit on softclose's CasADi model
  with the same grid, integrator and Ipopt options (the ``peers`` extra:
  ``pip install "softclose[peers]"``);
- ``scipy``: :mod:`.scipy_notebook`, single shooting with ``solve_ivp`` inside
  ``minimize(method="SLSQP")``.

Each optimum is then re-simulated by softclose's adaptive reference
(:func:`softclose.optimiser.verify.verify`): its J there, the constraints it violates there,
its closing time. A row holds the tool's wall and CPU time (the process's, so a loaded host
shows in the difference), the ratio of its wall time to softclose's, its iterations and its
own J. Imports are not timed (each tool's modules are imported before its clock starts).
"""

from __future__ import annotations

import time

from ...errors import ConfigError
from ... import interrupt

#: the tools of the table, in its order
TOOLS = ("softclose", "rockit", "scipy")
#: how to install the peers
INSTALL = 'pip install "softclose[peers]"'
#: what each row is
WHAT = {
    "softclose": "softclose.optimise(cfg): multiple shooting, 10 x 4 RK4 steps (Chebyshev "
                 "geometry, Hermite peak), Ipopt, NLP compiled ahead; 6 starts, both spring "
                 "kinds, verified",
    "rockit": "rockit Ocp, MultipleShooting(N=10, M=4, intg='rk', expand=True) on "
              "softclose's CasADi model, Ipopt with softclose's options; 1 start",
    "scipy": "scipy: solve_ivp (DOP853, rtol 1e-10) with a closing event inside "
             "minimize(SLSQP), forward-difference gradients; start from a 3^3 grid",
}


def versions() -> dict:
    """The versions of the tools of the table (None: not installed)."""
    from importlib.metadata import PackageNotFoundError, version
    out = {}
    for tool, dist in (("softclose", "softclose"), ("rockit", "rockit-meco"),
                       ("scipy", "scipy"), ("casadi", "casadi")):
        try:
            out[tool] = version(dist)
        except PackageNotFoundError:
            out[tool] = None
    return out


def require_peers() -> None:
    """Refuse (one line, exit 2) when the peers' extra is not installed."""
    from .rockit_ocp import available
    if not available():
        raise ConfigError(f"softclose bench --peers needs rockit, which is not installed: "
                          f"{INSTALL}")


def _prepare_softclose(cfg) -> None:
    """``softclose prepare``: each spring kind's NLP compiled (not timed), and nothing of
    it kept in memory, so that the timed run loads it as a user's run after a prepare does."""
    from ...optimiser import cache
    from ...optimiser.kinds import kind_config
    for kind in cfg.optimise.spring_kinds:
        ck, why = kind_config(cfg, kind)
        if why is None:
            cache.prepare(ck)
    cache.forget()


def _prepare_rockit(cfg) -> None:
    import rockit  # noqa: F401  (the import is not timed)


def _softclose(cfg, log) -> dict:
    from ...optimiser import optimise
    log("  softclose: optimise ...")
    res = optimise(cfg)
    starts = [s for s in res.starts if isinstance(s, dict)]
    return {"design": res.design, "objective": res.objective,
            "iterations": sum(int(s.get("iterations") or 0) for s in starts) or res.iterations,
            "starts": len(starts), "status": "converged" if res.success else "failed",
            "message": res.message}


def _rockit(cfg, log) -> dict:
    from .rockit_ocp import solve
    return {**solve(cfg, log), "starts": 1}


def _scipy(cfg, log) -> dict:
    from .scipy_notebook import solve
    return {**solve(cfg, log), "starts": 1}


RUNNERS = {"softclose": _softclose, "rockit": _rockit, "scipy": _scipy}
#: what is done before a tool's clock starts
PREPARE = {"softclose": _prepare_softclose, "rockit": _prepare_rockit}


def timed(tool: str, cfg, log) -> dict:
    """One tool's run to its optimum: its answer with its wall and CPU time (s)."""
    run = RUNNERS[tool]
    PREPARE.get(tool, lambda c: None)(cfg)
    t, c = time.perf_counter(), time.process_time()
    out = run(cfg, log)
    out["time_s"], out["cpu_s"] = time.perf_counter() - t, time.process_time() - c
    out.pop("time", None)
    return out


def judged(cfg, out: dict) -> dict:
    """``out`` re-simulated by the adaptive reference: its J, violations, closing time."""
    from ...optimiser.verify import verify
    ver = verify(cfg, out["design"], hand=False)
    bad = [k for k, c in ver.constraints.items() if not c["ok"]]
    ref = ver.stroke
    return {"objective_reference": ver.objective, "violations": bad,
            "violation_text": list(ver.failures),
            "closing_time": None if ref is None else ref.closing_time,
            "impact_theta_dot": None if ref is None else ref.impact_theta_dot,
            "peak_tip_speed": None if ref is None else ref.peak_tip_speed}


def peer_rows(cfg, log=None, tools: tuple = TOOLS) -> list[dict]:
    """The peers' table on ``cfg``: one row per tool of ``tools`` (softclose first), each
    timed to its optimum and judged by the reference; ratios against softclose's row."""
    log = log or (lambda *a: None)
    if "rockit" in tools:
        require_peers()
    rows = []
    for tool in tools:
        interrupt.check()
        log(f"peers: {tool} ...")
        out = timed(tool, cfg, log)
        row = {"tool": tool, "what": WHAT[tool], "time_s": out["time_s"],
               "cpu_s": out["cpu_s"], "iterations": out["iterations"],
               "starts": out["starts"], "evaluations": out.get("evaluations"),
               "status": out["status"], "message": out.get("message", ""),
               "objective_own": out["objective"], "design": out["design"],
               **judged(cfg, out)}
        rows.append(row)
        log(f"  {tool}: {row['time_s']:.1f} s (CPU {row['cpu_s']:.1f} s), "
            f"J in the reference {row['objective_reference']}, "
            f"violations: {', '.join(row['violations']) or 'none'}")
    base = next((r for r in rows if r["tool"] == "softclose"), None)
    for r in rows:
        if base is not None:
            r["ratio"] = r["time_s"] / base["time_s"]
            r["cpu_ratio"] = r["cpu_s"] / base["cpu_s"]
            Jb, J = base["objective_reference"], r["objective_reference"]
            r["objective_relative"] = None if J is None or not Jb else J / Jb - 1.0
    return rows


__all__ = ["peer_rows", "require_peers", "versions", "timed", "judged", "TOOLS", "INSTALL", "WHAT"]

"""The numerical stress survey: strokes at the edges of what softclose accepts.

Every stressed stroke must end in one of three ways: an answer that the adaptive reference
(:class:`softclose.simulation.reference.Reference`) confirms, a clear one-line report of why there is
no answer (with the step that would work, for an unstable stroke), or a config error. A
NaN, a traceback, a hang or an answer the reference contradicts is a finding.

- :func:`stress_cases` lists the cases: damping 0 … 1e6 N s/m, springs up to 1e6 N/m,
  steps far too large and very small, long undamped runs (energy drift), a toggle near or
  inside the stroke, a release angle at the edge of the assembly, the real elements at
  their edges (a stiff torsion spring, friction that just holds or just slips, a preload
  that reverses the stroke, a one-way damper on a rebound), and a few other edges.
- :func:`run_stress_case` runs one case and returns its row (a dict; never raises for a
  softclose failure).
- :func:`confirm` is the criterion: each metric within its accuracy target
  (:func:`softclose.problem.target`) or within 4 x the stroke's own error estimate.

``studies/stress_survey.py`` runs the full list; ``tests/test_stress.py`` a subset.
"""

from __future__ import annotations

import math
import re
import time
from dataclasses import dataclass, field
from types import SimpleNamespace

from ..config import default_config
from ..errors import ConfigError, NumericalError
from ..model.lid import LidModel
from ..problem import RELATIVE, TARGETS, resolve
from ..simulation.reference import Reference
from ..simulation.simulator import Simulator
from ..model.kinematics import branch_of, closure
from ..present.display import num

#: outcomes that are findings (a defect of softclose), not answers or reports
FAILURES = ("MISMATCH", "NaN", "EXCEPTION")
#: relative agreement asked of the spring-length extremes (they have no accuracy target)
LENGTH_RTOL = 1e-6
#: a confirmed metric may also lie within this multiple of the stroke's own error estimate
ESTIMATE_FACTOR = 4.0
#: the metrics compared with the reference
CONFIRM_KEYS = tuple(TARGETS) + ("min_spring_length", "max_spring_length")


@dataclass(frozen=True)
class StressCase:
    """One stressed stroke: config ``overrides`` (section -> keys) of the default config.

    ``expect`` is "answer" (must be confirmed by the reference), "report" (must be a
    one-line report), "config error", or "any" (any of the three, but never a finding).
    """

    name: str
    group: str
    what: str
    overrides: dict = field(hash=False)
    expect: str = "answer"


def assembly_for(geometry: dict, theta_deg: float = 18.0):
    """``geometry.assembly`` ([theta, phi, gamma] in degrees) for changed link lengths, on
    the branch of the default assembly (the side of sin(gamma - phi)); None if the loop
    cannot close at ``theta_deg``."""
    import casadi as ca

    g0 = default_config().geometry
    geo = SimpleNamespace(**{**g0._asdict(), **geometry})
    th0, phi0, gamma0 = g0.assembly
    sigma = branch_of(math.radians(phi0), math.radians(gamma0))
    phi, gamma, u = (float(v) for v in closure(ca.DM(math.radians(theta_deg)), geo, sigma))
    if not abs(u) < 1:
        return None
    return [theta_deg, math.degrees(phi), math.degrees(gamma)]


def geometry_with_assembly(**geometry) -> dict:
    """Geometry overrides plus the matching ``assembly`` (the default one if the loop cannot
    close at 18 deg: the config check then reports it)."""
    g = dict(geometry)
    g["assembly"] = assembly_for(g) or list(default_config().geometry.assembly)
    return g


def _release_moment() -> float:
    """|dV/dtheta| of the default lid at its release (N m): what friction must exceed."""
    cfg = default_config()
    m = LidModel(resolve(cfg))
    return abs(float(m.dV(cfg.stroke.theta0, m.params())))


def stress_cases(fast: bool = False) -> list[StressCase]:
    """Every stress case of the survey (``fast``: a representative subset for the tests)."""
    S = StressCase
    cases = []
    h0 = f"{default_config().simulate.step * 1e3:g} ms"  # the default step, as the cases use it
    # damping from 0 to 1e6 N s/m, default integrator and step
    for c in ([0.0, 1e3, 1e6] if fast else [0.0, 1e1, 1e2, 1e3, 1e4, 1e5, 3e5, 1e6]):
        cases.append(S(f"damper_c={c:g}", "damping", f"dashpot c = {c:g} N s/m, rk4 at {h0}",
                       {"design": {"damper_c": c}},
                       "answer" if c <= 1e5 else ("report" if c >= 1e6 else "any")))
    for integ in ("radau5",) if fast else ("radau5", "gauss4"):
        cases.append(S(f"damper_c=1e6 {integ}", "damping",
                       f"dashpot c = 1e6 N s/m, {integ} at {h0}",
                       {"design": {"damper_c": 1e6}, "simulate": {"integrator": integ}}))
    cases.append(S("rotary_damper_c=1e3", "damping", f"rotary damper 1e3 N m s/rad, rk4 at {h0}",
                   {"design": {"rotary_damper_c": 1e3}}, "report"))
    # spring stiffness up to 1e6 N/m
    for k in ([1e4, 1e6] if fast else [1e3, 1e4, 1e5, 1e6]):
        cases.append(S(f"spring_k={k:g}", "spring", f"spring k = {k:g} N/m, l0 = 0.05 m, "
                       f"no damper, rk4 at {h0}", {"design": {"spring_k": k}}, "any"))
    cases.append(S("spring_k=1e6 c=1e3", "spring", f"k = 1e6 N/m with c = 1e3 N s/m, rk4 at {h0}",
                   {"design": {"spring_k": 1e6, "damper_c": 1e3}}, "any"))
    cases.append(S("spring_k=1e6 gauss4 0.1ms", "spring", "k = 1e6 N/m, gauss4 at 0.1 ms",
                   {"design": {"spring_k": 1e6}, "simulate": {"integrator": "gauss4",
                                                               "step": 1e-4}}))
    cases.append(S("spring opens the lid", "spring",
                   "k = 1e4 N/m, l0 = 0.12 m: the spring pushes the lid open (holding moment < 0)",
                   {"design": {"spring_k": 1e4, "spring_rest_length": 0.12}}, "any"))
    # steps far too large and very small
    for integ, h in ([("rk4", 0.05), ("rk4", 1.0), ("euler_cromer", 0.05)] if fast else
                     [("rk4", 0.02), ("rk4", 0.05), ("rk4", 0.2), ("rk4", 1.0),
                      ("euler_cromer", 0.05), ("gauss4", 0.1), ("radau5", 0.1)]):
        cases.append(S(f"{integ} step={h:g}", "step", f"{integ} at h = {h:g} s (stroke 0.15 s)",
                       {"simulate": {"integrator": integ, "step": h}}, "any"))
    for integ, h in ([("rk4", 1e-6)] if fast else
                     [("rk4", 1e-6), ("rk4", 1e-7), ("euler_cromer", 1e-7), ("gauss4", 1e-6)]):
        cases.append(S(f"{integ} step={h:g}", "step", f"{integ} at h = {h:g} s",
                       {"simulate": {"integrator": integ, "step": h}}))
    # long undamped runs: a spring holds the lid open, it oscillates for t_max
    t_long = 5.0 if fast else 60.0
    for integ in (["rk4"] if fast else ["rk4", "gauss4", "euler_cromer", "radau5"]):
        cases.append(S(f"undamped {t_long:g} s {integ}", "long run",
                       f"k = 2000 N/m, l0 = 0.1 m, no damping: oscillates {t_long:g} s; {integ} "
                       f"at {h0}; energy drift reported",
                       {"design": {"spring_k": 2000.0, "spring_rest_length": 0.1},
                        "stroke": {"t_max": t_long}, "simulate": {"integrator": integ}}))
    # geometry near a toggle position
    cases.append(S("near toggle (closing end)", "toggle",
                   "crank_bc = 0.0925 m: toggle at theta ≈ -2.5°, just below the closed lid",
                   {"geometry": geometry_with_assembly(crank_bc=0.0925)}, "any"))
    cases.append(S("toggle inside the stroke", "toggle",
                   "crank_bc = 0.0935 m: toggle at theta ≈ +2.3°, inside the stroke",
                   {"geometry": geometry_with_assembly(crank_bc=0.0935)}, "config error"))
    cases.append(S("closing at the toggle", "toggle",
                   "crank_bc = 0.0925 m, theta_closed = -2.4°: the stroke ends 0.1° from the toggle",
                   {"geometry": geometry_with_assembly(crank_bc=0.0925),
                    "stroke": {"theta_closed_deg": -2.4}}, "any"))
    # release angle near the edge of the assembly (short crank BC: the loop closes below ~25°)
    edge = geometry_with_assembly(crank_bc=0.0096)
    for th0, exp in ((24.0, "any"), (24.7, "any"), (24.9, "config error")):
        cases.append(S(f"release at {th0:g}° (edge ≈ 24.75°)", "release edge",
                       f"crank_bc = 9.6 mm (the loop closes only below ≈ 24.75°), "
                       f"theta0 = {th0:g}°",
                       {"geometry": edge, "stroke": {"theta0_deg": th0}}, exp))
    cases.append(S("release at 170°", "release edge", "default geometry (Grashof), theta0 = 170°",
                   {"stroke": {"theta0_deg": 170.0}}, "any"))
    # the real elements at their edges
    cases.append(S("stiff torsion spring", "elements",
                   f"torsion spring k_t = 20 N m/rad at pivot O (free at the closed crank angle), "
                   f"no damper: a fast oscillation, rk4 at {h0}",
                   {"design": {"torsion_k": 20.0, "torsion_pivot": "O",
                               "torsion_free_angle_deg": 120.94}}, "any"))
    dV0 = _release_moment()
    for f, what in ((1.0001, "just holds"), (0.9999, "just slips")):
        cases.append(S(f"friction {what}", "elements",
                       f"friction T_f = {f:g} x the release moment {dV0:.4f} N m: the lid "
                       + ("stays where it is released" if f > 1 else
                          "creeps off, then accelerates"),
                       {"friction": {"torque": f * dV0}}))
    if not fast:
        cases.append(S("preload reverses the stroke", "elements",
                       "a gas strut (compression, F0 = 200 N, k = 100 N/m, l0 = 0.12 m) "
                       "pushes the released lid open, past theta0",
                       {"design": {"spring_kind": "compression", "spring_preload": 200.0,
                                   "spring_k": 100.0, "spring_rest_length": 0.12}}, "any"))
        cases.append(S("one-way damper, rebound", "elements",
                       "k = 3000 N/m, l0 = 0.09 m throws the lid up; the one-way dashpot lets "
                       "it rise freely",
                       {"design": {"spring_k": 3000.0, "spring_rest_length": 0.09,
                                   "damper_c": 150.0, "damper_one_way": True}}, "any"))
    # other edges
    cases.append(S("tiny stroke", "other", "theta0 = 0.001°: a stroke of 1.7e-5 rad",
                   {"stroke": {"theta0_deg": 0.001}}))
    cases.append(S("t_max too short", "other", "t_max = 0.05 s: the lid has not closed yet",
                   {"stroke": {"t_max": 0.05}}))
    cases.append(S("no gravity", "other", "gravity = 0, no spring: the lid stays where it is",
                   {"mass": {"gravity": 0.0}}))
    return cases


def confirm(res, ref) -> tuple[bool, dict, dict]:
    """Does the reference ``ref`` confirm the fixed-step stroke ``res`` (both
    :class:`~softclose.simulation.stroke.StrokeResult`)?

    Both must agree on ``closed``; each metric of :data:`CONFIRM_KEYS` must lie within its
    accuracy target, or within :data:`ESTIMATE_FACTOR` x the stroke's own error estimate, of
    the reference. Returns (confirmed, error, allowed): errors and allowances per metric,
    relative for the metrics whose target is relative and for the spring lengths.
    """
    if bool(res.closed) != bool(ref.closed):
        return False, {}, {}
    err, allowed = {}, {}
    for k in CONFIRM_KEYS:
        a, b = getattr(res, k), getattr(ref, k)
        if a is None and b is None:
            continue
        if a is None or b is None:
            return False, err, allowed
        bound = TARGETS.get(k, LENGTH_RTOL)
        scale = max(abs(b), 1e-300) if (k in RELATIVE or k not in TARGETS) else 1.0
        est = ((res.accuracy or {}).get(k) or 0.0) / scale
        err[k] = abs(a - b) / scale
        allowed[k] = max(bound, ESTIMATE_FACTOR * est) + 1e-8
    return all(err[k] <= allowed[k] for k in err), err, allowed


def recommended_step(message: str) -> float | None:
    """The step a report recommends ("simulate.step <= H s"), or None."""
    m = re.search(r"simulate\.step <= ([0-9.eE+-]+) s", message or "")
    return float(m.group(1)) if m else None


def run_stress_case(case: StressCase, ref_tol: float = 1e-12, rerun: bool = True) -> dict:
    """Run one stress case; return its row (never raises for a softclose failure).

    ``outcome``: "confirmed" (the reference reproduces the answer), "reported" (a clear
    one-line report; an unstable stroke is also re-run at the step it recommends, in
    ``rerun``), "config error" (rejected with a one-line message), or a finding of
    :data:`FAILURES`. ``energy_drift`` is the largest rise of the total energy over the
    stroke (J), ``energy_drift_rel`` the same relative to the initial energy;
    ``max_err_ratio`` the worst error / allowed of :func:`confirm` (<= 1 passes).
    """
    t0 = time.perf_counter()
    row = {"name": case.name, "group": case.group, "what": case.what, "expect": case.expect,
           "outcome": "", "status": "", "message": "", "energy_drift": None,
           "energy_drift_rel": None, "max_err_ratio": None, "rerun": "", "time_s": None}
    try:
        cfg = default_config().replace(**case.overrides)
        resolved = resolve(cfg)
        model = LidModel(resolved)
        sim = Simulator(resolved, model=model)
    except ConfigError as exc:
        row.update(outcome="config error", message=str(exc), time_s=time.perf_counter() - t0)
        return row
    except NumericalError as exc:
        row.update(outcome="reported", message=str(exc), time_s=time.perf_counter() - t0)
        return row
    except Exception as exc:  # a defect: reported as a finding
        row.update(outcome="EXCEPTION", message=f"{type(exc).__name__}: {exc}",
                   time_s=time.perf_counter() - t0)
        return row
    try:
        p = model.params()
        res = sim.run(p)
        b = sim.run_batch(p[None, :], threads=1)
        E = float(model.energy_fn([cfg.stroke.theta0, 0.0], p))
        row["energy_drift"] = float(b["energy_rise"][0])
        row["energy_drift_rel"] = float(b["energy_rise"][0]) / max(abs(E), 1e-300)
        row["status"] = res.status.text
        row["steps"] = res.steps
        vals = [getattr(res, k) for k in ("closing_time", "impact_theta_dot",
                                          "impact_tip_speed", "peak_tip_speed",
                                          "min_spring_length", "max_spring_length",
                                          "holding_moment")]
        if any(v is not None and not math.isfinite(v) for v in vals):
            row.update(outcome="NaN", message="a metric is not finite")
        elif not res.ok:
            row.update(outcome="reported", message=res.message or "")
            h_ok = recommended_step(res.message or "")
            if rerun and h_ok is not None:
                overrides = {s: dict(v) for s, v in case.overrides.items()}
                overrides.setdefault("simulate", {})["step"] = h_ok
                sub = run_stress_case(StressCase(case.name + " (rerun)", case.group, "",
                                                 overrides), ref_tol, rerun=False)
                row["rerun"] = f"at {h_ok:.3g} s: {sub['outcome']} ({sub['status']})"
        else:
            ref = Reference(model, ref_tol).simulate(p, resolved)
            ok, err, allowed = confirm(res, ref)
            row["max_err_ratio"] = max((err[k] / allowed[k] for k in err), default=0.0)
            row["ref_closed"] = ref.closed
            for k in ("closing_time", "impact_theta_dot", "peak_tip_speed"):
                row[k] = getattr(res, k)
                row[f"ref_{k}"] = getattr(ref, k)
            row["outcome"] = "confirmed" if ok else "MISMATCH"
            if not ok:
                worst = max(err, key=lambda k: err[k] / allowed[k]) if err else None
                row["message"] = (f"{worst}: fixed step {getattr(res, worst)} vs reference "
                                  f"{getattr(ref, worst)}" if worst else
                                  f"closed {res.closed} vs reference {ref.closed}")
    except NumericalError as exc:
        row.update(outcome="reported", message=str(exc))
    except Exception as exc:  # a defect: reported as a finding
        row.update(outcome="EXCEPTION", message=f"{type(exc).__name__}: {exc}")
    row["time_s"] = time.perf_counter() - t0
    return row


def run_survey(fast: bool = False, log=None) -> list[dict]:
    """Every case of :func:`stress_cases` through :func:`run_stress_case`, in order."""
    rows = []
    for case in stress_cases(fast=fast):
        rows.append(run_stress_case(case))
        if log:
            log(rows[-1])
    return rows


def findings(rows: list[dict]) -> list[dict]:
    """The rows whose outcome is a finding (:data:`FAILURES`)."""
    return [r for r in rows if r["outcome"] in FAILURES]


def stress_markdown(rows: list[dict]) -> str:
    """The survey as a Markdown table (one row per case)."""
    out = ["| case | what | expected | outcome | status | energy drift (rel.) | "
           "err / allowed | time (s) | message / re-run |",
           "|---|---|---|---|---|---:|---:|---:|---|"]
    for r in rows:
        msg = r["message"] + (f" — re-run {r['rerun']}" if r.get("rerun") else "")
        msg = msg.replace("|", "\\|")
        out.append(f"| {r['name']} | {r['what']} | {r['expect']} | **{r['outcome']}** | "
                   f"{r['status']} | {num(r.get('energy_drift_rel'), spec='.1e')} | "
                   f"{num(r.get('max_err_ratio'), spec='.2g')} | {num(r['time_s'], spec='.2f')} | "
                   f"{msg} |")
    return "\n".join(out)


__all__ = ["StressCase", "stress_cases", "run_stress_case", "run_survey", "confirm",
           "findings", "recommended_step", "assembly_for", "geometry_with_assembly",
           "stress_markdown", "FAILURES", "CONFIRM_KEYS"]

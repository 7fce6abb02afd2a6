"""The one-call optimiser: starts, solves, polish, verification, the active limits.

:func:`optimise` solves cfg's problem from several starts (:mod:`.starts`), refines and
corrects the best answer (:mod:`.polish`), re-simulates it with the adaptive reference
(:mod:`.verify`) and reads from Ipopt's multipliers what limits it (:func:`active_set`).
:func:`solve` is one Ipopt solve, cold or warm, for benchmarks and continuation.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

from ..simulation import statics
from ..errors import ConfigError, NumericalError, SoftcloseError
from ..problem import check_reference_temperature, check_new_parts, DESIGN_KEYS, PARAM_COLUMNS, SCALES, UNITS, describe
from ..present.progress import Progress
from .cache import get_model, get_nlp, has_nlp, stroke_simulator
from .spring_part import spring_part
from .diagnose import diagnose
from .discretisation import Discretisation, discretisation
from .interval import END_C
from .kinds import kind_config
from .made_to_order import made_to_order, with_spring
from .ipopt import check_options
from .nlp import J_INDEX, Run, ShootingNLP
from .polish import keep_clear, nlp_objective, refine, tighten
from .result import Active, OptimiseResult
from .starts import MAX_STARTS, design_rows, initial_guess, sweep_starts, sweep_time
from .screening import KEEP, nominal_judge, placement_designs, screen, shared_box
from .verify import get_checker, verify as verify_design
from ..interrupt import check
from .free_points import placed_config, placement_layout
from .keep_out import clearance
from ..config.free import config_value

#: a scaled Ipopt multiplier (J/J_ref per scaled unit) above this marks a limit as active
ACTIVE_LAM = 1e-6


def check_problem(cfg, starts: int | None = None) -> int:
    """Refuse problems that cannot be posed; the number of starts."""
    o = cfg.optimise
    if o.weight_impact == 0 and o.weight_peak_tip == 0:
        raise ConfigError("optimise.weight_impact and optimise.weight_peak_tip are both zero: "
                          "there is nothing to minimise; make one of them positive")
    n = o.starts if starts is None else starts
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise ConfigError(f"starts: expected a whole number >= 1, got {n!r}")
    if n > MAX_STARTS:
        raise ConfigError(f"optimise.starts: {n} starts is more than the limit of {MAX_STARTS} "
                          "(each is a full solve); lower optimise.starts")
    return int(n)


def claims(nlp: ShootingNLP, cfg, run: Run) -> tuple[dict, dict, float]:
    """(design, the NLP's own §4 metrics, its J) at ``run``'s point.

    The peak tip speed is the largest sub-step speed or Hermite maximum at the solution
    (:meth:`ShootingNLP.peak`), never the free epigraph variable; the spring-length extremes
    are those of the exact model over the stroke's angles, the holding moment the model's.
    """
    d, T, X, _ = nlp.unpack(run.x)
    st = cfg.stroke
    model = nlp.model
    p = nlp.param_vector(cfg, d)
    thd = float(X[1, -1])
    vT = np.asarray(model.kin(np.array([st.theta_closed, thd]))[4]).ravel()
    if nlp.placed:      # the exact model at the optimum's attachment points
        cfg = nlp.placed_config(cfg, d)
        model = get_checker(cfg).model
    lmin, lmax = get_checker(cfg).spring_extremes(st.theta_closed, st.theta0)
    peak = nlp.peak(run)
    m = {"closed": True, "closing_time": T, "impact_theta_dot": thd,
         "impact_tip_speed": float(np.hypot(*vT)), "peak_tip_speed": peak,
         "min_spring_length": lmin, "max_spring_length": lmax,
         "holding_moment": model.holding_moment(p),
         "opening_force": statics.opening_force_exact(model, p)}
    eng = nlp.engagement(run.x)
    if eng is not None and p[PARAM_COLUMNS[END_C]] != 0:
        # two phases: the node between them is the end damper's engagement (a damper of
        # no coefficient engages nothing: the reference has no event then)
        m["engage_time"], m["engage_theta_dot"] = eng
    return nlp.design_dict(cfg, d), m, nlp_objective(nlp, cfg, run)


def free_in_bounds(cfg):
    """``cfg`` with each free design variable (``optimise.free``) clipped into its bounds:
    where the starts' sweep holds it."""
    values = {}
    for key, lo, hi in cfg.optimise.free or ():
        v = config_value(cfg, key)
        if not lo <= v <= hi:
            values[key] = float(np.clip(v, lo, hi))
    return cfg.update(values)


def active_set(nlp: ShootingNLP, cfg, run: Run, t_limit: float) -> tuple[Active, ...]:
    """The bounds and constraints that limit ``run``'s answer, with dJ per unit relaxation.

    Ipopt's multipliers (CasADi's sign convention: > 0 at an upper, < 0 at a lower bound)
    are derivatives of the NLP objective J/J_ref with respect to the bounds, in the scaled
    variables; dJ = -J_ref · lam / scale per unit of the upper bound, +J_ref · lam / scale
    per unit the lower bound is lowered.
    """
    if run.lam_x is None:
        return ()
    o, st = cfg.optimise, cfg.stroke
    Jr, lam_x, lam_g = float(run.p[J_INDEX]), run.lam_x, run.lam_g
    out = []
    names = list(nlp.design_dict(cfg, nlp.unpack(run.x)[0]))
    for i, ((lo, hi), key) in enumerate(zip(nlp.design_bounds(cfg), names)):
        lam, sc = float(lam_x[i]), nlp.scales[i]
        for side, b, sign in (("upper", hi, 1.0), ("lower", lo, -1.0)):
            at = abs(run.x[i] - b / sc) <= 1e-7 * max(1.0, abs(b / sc))
            if sign * lam > ACTIVE_LAM or (at and lo != hi):
                out.append(Active(key, "bound", side, float(b), UNITS.get(key, "m"),
                                  -sign * Jr * lam / sc))
                break
    iT = nlp.iT
    lam = float(lam_x[iT])
    if lam > ACTIVE_LAM:
        name, v = (("closing_time_max", o.closing_time_max) if t_limit >= o.closing_time_max
                   else ("stroke.t_max", st.t_max))
        out.append(Active(name, "constraint", "upper", v, "s", -Jr * lam))
    elif lam < -ACTIVE_LAM:
        out.append(Active("closing_time_min", "constraint", "lower", o.closing_time_min, "s",
                          Jr * lam))
    N, iX = nlp.N, nlp.iX
    groups = dict(nlp.groups())
    lam_hm = float(lam_g[groups["holding_moment"]].sum())
    if lam_hm < -ACTIVE_LAM:
        out.append(Active("holding_moment_min", "constraint", "lower", o.holding_moment_min,
                          "N m", Jr * lam_hm))
    # theta' <= 0 at every sub-step and node: relaxed together (theta' <= eps everywhere)
    lam_rb = float(np.maximum(lam_g[groups["theta_dot_nonpositive"]], 0).sum()
                   + np.maximum(lam_x[iX + 1:iX + 1 + 2 * N:2], 0).sum())
    if lam_rb > ACTIVE_LAM:
        out.append(Active("no_rebound", "constraint", "upper", 0.0, "rad/s", -Jr * lam_rb))
    lam_rim = float(np.minimum(lam_g[groups["theta_above_closed"]], 0).sum()
                    + np.minimum(lam_x[iX:iX + 2 * (N - 1):2], 0).sum())
    if lam_rim < -ACTIVE_LAM:
        out.append(Active("theta_above_closed", "constraint", "lower", st.theta_closed, "rad",
                          Jr * lam_rim))
    lam_rel = float(lam_g[groups["release_downwards"]].sum())
    if lam_rel > ACTIVE_LAM:
        out.append(Active("release_downwards", "constraint", "upper", 0.0, "rad/s^2",
                          -Jr * lam_rel))
    if "opening_force" in groups:
        lam_of = float(np.maximum(lam_g[groups["opening_force"]], 0).sum())
        if lam_of > ACTIVE_LAM:
            out.append(Active("opening_force_max", "constraint", "upper", o.opening_force_max,
                              "N", -Jr * lam_of))
    if "self_close" in groups:
        lam_sc = np.minimum(lam_g[groups["self_close"]], 0)
        if -lam_sc.sum() > ACTIVE_LAM:
            # the angle moves the grid: dJ per degree the bound is lowered is -dL/dtheta_sc,
            # dL/dtheta_sc = J_ref lam . dg/dtheta_sc (central differences of the grid's
            # values, nodes and Hermite minima alike)
            p, deg, h = nlp.param_vector(cfg, nlp.unpack(run.x)[0]), o.self_close_min_deg, 1e-3
            dg = (nlp.self_close_moments(p, deg + h) - nlp.self_close_moments(p, deg - h)) \
                / (2 * h)
            out.append(Active("self_close_min_deg", "constraint", "lower", deg, "deg",
                              -Jr * float(lam_sc @ dg)))
    return tuple(out)


def start_row(nlp: ShootingNLP, cfg, start, run: Run, J0) -> dict:
    """One start as reported: where it began, where it ended, how it went."""
    d, T, _, _ = nlp.unpack(run.x)
    row = {"start": nlp.design_dict(cfg, start), "start_objective": J0,
           "design": nlp.design_dict(cfg, d),
           "objective": nlp_objective(nlp, cfg, run) if run.success else None,
           "closing_time": T, "status": run.status, "success": run.success,
           "iterations": run.iterations, "solve_time": run.time}
    if run.origin:
        row["from"] = run.origin
    return row


def distinct(rows: list, rtol: float = 1e-3) -> int:
    """How many distinct designs (scaled distance > rtol) the rows reached."""
    seen: list = []
    keys = list(rows[0]["design"]) if rows else []
    # the design variables scaled: k, l0, c by the NLP's scales, a free one by its largest
    scale = np.r_[SCALES, [max(max(abs(r["design"][k]) for r in rows), 1e-12)
                           for k in keys[len(DESIGN_KEYS):]]]
    for r in rows:
        v = np.array([r["design"][k] for k in keys]) / scale
        if all(np.linalg.norm(v - s) > rtol * max(1.0, np.linalg.norm(s)) for s in seen):
            seen.append(v)
    return len(seen)


def finish(cfg, nlp: ShootingNLP, run: Run, disc: Discretisation, *, verify: bool,
           polish: bool, notes: list, **base) -> OptimiseResult:
    """From a converged run to the result: polish (refine, tighten), the optimiser's claims,
    verification, the active limits."""
    if polish:
        sim = stroke_simulator(cfg)
        nlp, run = refine(cfg, nlp, run, sim, notes)
        run = tighten(cfg, nlp, run, sim, disc.t_limit, notes)
        run = keep_clear(cfg, nlp, run, notes)
    design, own, J = claims(nlp, cfg, run)
    if nlp.placed:       # from here on: the config with the optimum's attachment points
        cfg = nlp.placed_config(cfg, nlp.unpack(run.x)[0])
    active = active_set(nlp, cfg, run, disc.t_limit)
    problem = describe(cfg)
    # the closing-time bounds the NLP was solved with: closing_time_min raised to the NLP's
    # floor, the limit moved by the discretisation error (tighten)
    problem["closing_time_solved"] = [float(run.bounds[0][nlp.iT]), float(run.bounds[1][nlp.iT])]
    common = dict(nodes=nlp.nodes, substeps=nlp.M, substeps_engaged=nlp.M_engaged,
                  hessian=cfg.optimise.hessian,
                  iterations=base.pop("iterations", run.iterations),
                  solve_time=base.pop("solve_time", run.time), problem=problem,
                  config=cfg, run=run, nlp_key=nlp.key, active=active, **base)
    if not verify:
        return OptimiseResult(True, "not verified (verify=False): the numbers in 'optimiser' "
                              "are the NLP's own", run.status, design, J, None,
                              {"objective": J, **own}, notes=tuple(notes), **common)
    ver = verify_design(cfg, design, own, J)
    ok, msg = ver.ok, ver.message and f"the answer is {ver.message}"
    if cfg.optimise.keep_out:          # the exact check of the keep-out regions
        for line, c in clearance(cfg).items():
            notes.append(f"keep-out: the {line}'s line clears the regions by "
                         f"{c['clearance'] * 1e3:.3f} mm at the least (theta = "
                         f"{c['theta_deg']:.1f} deg; exact closure, 2001 angles)")
            if not c["ok"]:
                ok = False
                msg = "; ".join(filter(None, [msg, f"the {line}'s line crosses a keep-out "
                                              f"region by {-c['clearance'] * 1e3:.3f} mm at "
                                              f"theta = {c['theta_deg']:.1f} deg"]))
    return OptimiseResult(ok, msg, run.status,
                          design, J, ver.metrics, {"objective": J, **own}, ver,
                          notes=tuple(notes), **common)


def _points_of(res, cfg):
    """``cfg`` (not the kind's bounds) with the attachment points ``res`` placed."""
    return placed_config(cfg, res.design or {})


def guarded(fn):
    """Turn an exception out of CasADi/Ipopt into a NumericalError with what to change."""
    import functools

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        try:
            return fn(*args, **kwargs)
        except SoftcloseError:
            raise
        except (RuntimeError, ArithmeticError, np.linalg.LinAlgError) as exc:
            msg = str(exc).strip().splitlines()
            msg = msg[-1] if msg else type(exc).__name__
            raise NumericalError(
                f"the optimiser failed ({type(exc).__name__}: {msg[:200]}); try "
                "optimise.hessian = \"limited-memory\", optimise.linear_solver = \"mumps\", or "
                "other optimise.nodes / optimise.substeps") from None
    return wrapper


@guarded
def optimise(cfg, *, starts: int | None = None, verify: bool = True,
             progress: bool = False, nodes: int | None = None,
             substeps: int | None = None) -> OptimiseResult:
    """The verified optimum over the spring kinds the optimiser may choose
    (``optimise.spring_kinds``): one problem per kind (:func:`optimise_kind`), its free
    length bounded so that the spring stays valid over the whole stroke
    (:mod:`.kinds`); the best verified answer is kept, and says what spring to buy
    (``part``: kind, free length, rate, preload, working lengths, largest force, and the
    margins within which it must be made). A kind that cannot be valid, or finds no answer,
    is listed in ``kinds`` with why. With ``[spring]`` material given and its geometry not,
    the answer's coil spring is designed and wound, and the problem solved again at its
    rate (:mod:`.made_to_order`): the part names the spring.
    """
    check_reference_temperature(cfg, "the optimiser")
    check_new_parts(cfg, "the optimiser")
    opts = dict(starts=starts, verify=verify, progress=progress, nodes=nodes,
                substeps=substeps)
    res = _optimise_kinds(cfg, **opts)
    if made_to_order(cfg):
        res = with_spring(cfg, res, lambda c: _optimise_kinds(c, **opts))
    return res


def _optimise_kinds(cfg, *, starts, verify, progress, nodes, substeps) -> OptimiseResult:
    """:func:`optimise` without the spring made to order: every kind, the best kept."""
    t_start = time.perf_counter()
    rows, results, pending, todo = [], [], [], []
    for kind in cfg.optimise.spring_kinds:
        c, why = kind_config(cfg, kind)
        if why is not None:
            rows.append({"kind": kind, "success": False, "objective": None, "message": why})
            continue
        rows.append({"kind": kind})
        todo.append((kind, c))
    # every kind is solved (multistart), one after the other; the polish and the reference's
    # verification, which cost as much, go to the best kind first (then the next, should it
    # fail)
    for kind, c in todo:
        r, later = optimise_kind(c, starts=starts, verify=verify, nodes=nodes,
                                 substeps=substeps, defer=True, progress=progress)
        row = next(row for row in rows if row["kind"] == kind)
        row.update({"success": r.success, "objective": r.objective,
                    "message": r.message, "verified": False})
        results.append((kind, r))
        pending.append(later)
    return _best_kind(cfg, rows, results, pending, verify, t_start)


def _best_kind(cfg, rows, results, pending, verify, t_start) -> OptimiseResult:
    """The kinds' answers to the result: the best polished and verified first."""
    order = sorted(range(len(results)), key=lambda i: (
        results[i][1].objective if results[i][1].success else np.inf))
    row_of = {row["kind"]: row for row in rows}
    for i in order:
        kind, r = results[i]
        if not r.success or pending[i] is None:
            continue
        done = pending[i]()
        results[i] = (kind, done)
        row_of[kind].update(success=done.success, objective=done.objective,
                            message=done.message, verified=done.verified)
        if done.success:
            break
    for row in rows:        # the kinds not finished: the optimiser's own J, not verified
        if row.get("success") and not row.get("verified") and verify:
            row["message"] = ("the optimiser's own J (not polished, not verified: a better "
                              "kind was verified)")
            row["success"] = False
    finished = [(k, r) for k, r in results if r.verification is not None or not verify]
    good = [(k, r) for k, r in finished if r.success]
    pool = good or [(k, r) for k, r in finished if r.design is not None] or \
        [(k, r) for k, r in results if r.design is not None]
    notes = ["spring kinds: " + "; ".join(
        f"{row['kind']}: " + (f"J = {row['objective']:.8g}" if row["objective"] is not None
                              else "no design") + ("" if row["success"] else
                                                   f" ({row['message'] or 'failed'})")
        for row in rows)]
    if not pool and results:     # no kind found a design: the one that came closest speaks
        kind, best = min(results, key=lambda kr: (kr[1].infeasibility or {}).get(
            "least_violation", np.inf))
        others = "; ".join(f"{r['kind']}: {r['message']}" for r in rows if r["kind"] != kind)
        return replace(best, kind=kind, kinds=tuple(rows),
                       message=best.message + (f" (other spring kinds: {others})" if others
                                               else ""),
                       notes=best.notes + tuple(notes),
                       total_time=time.perf_counter() - t_start)
    if not pool:
        return OptimiseResult(False, "no spring kind of optimise.spring_kinds can be valid: "
                              + "; ".join(f"{r['kind']}: {r['message']}" for r in rows),
                              "Infeasible_Problem_Detected", None, None, problem=describe(cfg),
                              notes=tuple(notes), config=cfg, kinds=tuple(rows),
                              total_time=time.perf_counter() - t_start)
    kind, best = min(pool, key=lambda kr: (kr[1].objective if kr[1].objective is not None
                                           else np.inf))
    part = spring_part(best.config, best.design, best.metrics or best.optimiser,
                       model=get_model(best.config)) if best.design is not None else None
    return replace(best, kind=kind, kinds=tuple(rows), part=part,
                   config=_points_of(best, cfg.set("design.spring_kind", kind)),
                   notes=best.notes + tuple(notes), total_time=time.perf_counter() - t_start)


@dataclass(frozen=True)
class Plan:
    """A kind's multistart before its solves: the problem (cfg with the free variables in
    their bounds), its discretisation and NLP, and the starts' designs from the sweep."""
    cfg: object
    disc: Discretisation
    nlp: ShootingNLP
    build: float            # s spent building the NLP here (0 when it was at hand)
    sim: object             # the simulator of the sweep and the initial guesses
    designs: np.ndarray     # (starts, 3): where each start begins
    info: dict              # the sweep's summary
    bounds: tuple
    #: free attachment points: the kernel's screening of their box
    #: (:mod:`.screening`), whose best placements are the first starts, each with its
    #: simulator (the initial guess's stroke at its points); else None and ()
    screening: object = None
    sims: tuple = ()

    @property
    def n_starts(self) -> int:
        return len(self.designs)


def plan_kind(cfg, starts: int | None = None, nodes: int | None = None,
              substeps: int | None = None, bar: Progress | None = None) -> Plan:
    """Everything a kind's starts need: the NLP (built or loaded), the sweep of the design
    box and the starts picked from it."""
    n_starts = check_problem(cfg, starts)
    cfg = free_in_bounds(cfg)
    disc = discretisation(cfg, nodes, substeps)
    if bar is not None and disc.steps > 400:
        bar.update(0, f"building the NLP ({disc.nodes} x {disc.substeps} RK4 steps)", force=True)
    cached = has_nlp(cfg, disc.nodes, disc.substeps)
    nlp = get_nlp(cfg, disc.nodes, disc.substeps)
    sim = stroke_simulator(cfg, sweep_time(cfg, disc.t_limit))
    designs, info = sweep_starts(cfg, n_starts, disc.t_limit, sim)
    screening, sims = None, ()
    if placement_layout(cfg):   # a global look at the points' box first
        box = shared_box(cfg)
        screening = screen(box, lambda V: placement_designs(cfg, sim.table, box, V),
                           nominal_judge(cfg, sim, box, disc.t_limit), 1,
                           keep=min(KEEP, n_starts))
        placed = [placed_config(cfg, screening.placement(i)) for i in screening.kept]
        rows = [design_rows(c, screening.designs[i][None])[0]
                for c, i in zip(placed, screening.kept)]
        designs = np.vstack(rows + list(designs[:max(n_starts - len(rows), 0)]))
        sims = tuple(stroke_simulator(c, sweep_time(c, disc.t_limit)) for c in placed)
    return Plan(cfg, disc, nlp, 0.0 if cached else nlp.build_time, sim, designs, info,
                nlp.bounds(cfg), screening, sims)


def solve_start(plan: Plan, i: int) -> tuple[Run, dict]:
    """Start ``i`` of ``plan``: its initial guess from the simulated stroke, one Ipopt solve,
    and its row of the report. A Ctrl-C noted before it is raised here, first."""
    check()
    nlp, cfg, d0 = plan.nlp, plan.cfg, plan.designs[i]
    p = nlp.params(cfg)
    sim = plan.sims[i] if i < len(plan.sims) else plan.sim
    w0, J0 = initial_guess(nlp, cfg, d0, sim, p, plan.disc.t_limit)
    p[J_INDEX] = max(J0, 1e-8)
    r = nlp.solve(w0, p, *plan.bounds, origin=f"start {i + 1}" + (
        " (a screened placement)" if i < len(plan.sims) else ""))
    check_options(r, cfg)
    return r, start_row(nlp, cfg, d0, r, J0)


@guarded
def optimise_kind(cfg, *, starts: int | None = None, verify: bool = True,
                  progress: bool = False, nodes: int | None = None,
                  substeps: int | None = None, defer: bool = False,
                  plan: Plan | None = None):
    """Solve cfg's soft-close problem, with cfg's spring kind, from several starts; the best
    answer, verified.

    Starts come from a coarse sweep of the design box (``starts`` of them, default
    optimise.starts); each is solved by Ipopt; the best converged one is refined, has its
    closing-time bounds corrected for the NLP's discretisation error and is re-simulated by
    the adaptive reference. ``success`` means: Ipopt converged, every constraint holds in
    the reference simulation and every number the optimiser reports agrees with the
    reference's (objective to 1e-3 relative). Infeasible problems and solver failures are
    reported in the result, never raised. ``progress=True`` draws the starts on a terminal.

    ``plan``: the kind's :func:`plan_kind`, when made already.

    The design for the ``[tolerance]`` box is :func:`softclose.robust.optimise_robust`
    (which builds on this one; ``softclose.optimise(cfg, robust=True)`` calls it).
    """
    t_start = time.perf_counter()
    o = cfg.optimise
    n_starts = check_problem(cfg, starts) if plan is None else plan.n_starts
    bar = Progress(n_starts, "optimise", enabled=progress, unit="")
    plan = plan or plan_kind(cfg, starts, nodes, substeps, bar)
    cfg, disc, nlp = plan.cfg, plan.disc, plan.nlp
    notes = list(disc.notes)
    solved: dict = {}
    with bar:
        for i in range(plan.n_starts):
            bar.update(len(solved), f"start {i + 1} of {plan.n_starts}: solving "
                                    f"({disc.nodes} x {disc.substeps} RK4 steps)", force=True)
            solved[i] = r, _ = solve_start(plan, i)
            bar.update(len(solved), f"start {i + 1}: {r.status}, {r.iterations} iterations",
                       force=True)
        runs = [solved[i][0] for i in range(plan.n_starts)]
        rows = [solved[i][1] for i in range(plan.n_starts)]
        base = dict(starts=tuple(rows), build_time=plan.build, sweep=plan.info)
        if plan.screening is not None:
            base["screening"] = plan.screening.to_json()
            notes.append(plan.screening.line())
        ok = [i for i, r in enumerate(runs) if r.success]
        if not ok:
            msg, inf = diagnose(cfg, nlp, runs)
            best = min(runs, key=lambda r: r.total_violation)
            inf = dict(inf or {}, least_violation=float(best.total_violation))
            failed = OptimiseResult(
                False, msg, best.status, None, None, nodes=nlp.nodes, substeps=nlp.M,
                substeps_engaged=nlp.M_engaged,
                hessian=o.hessian, iterations=sum(r.iterations for r in runs),
                solve_time=sum(r.time for r in runs), problem=describe(cfg),
                infeasibility=inf, notes=tuple(notes), config=cfg,
                total_time=time.perf_counter() - t_start, **base)
            return (failed, None) if defer else failed
        best = runs[min(ok, key=lambda i: rows[i]["objective"])]
        n_opt = distinct([rows[i] for i in ok])
        Js = [rows[i]["objective"] for i in ok]
        same = n_opt > 1 and max(Js) - min(Js) <= 1e-6 * max(abs(min(Js)), 1e-300)
        notes.append(f"{len(ok)} of {len(runs)} starts converged, to {n_opt} distinct "
                     + ("designs of the same J: the optimum is not unique (a spring's preload "
                        "and free length, say, trade against each other)" if same
                        else "optima"))
        if defer:       # the best run as the NLP has it, and how to finish it later
            raw = finish(cfg, nlp, best, disc, verify=False, polish=False,
                         notes=list(notes), **base)

            def later() -> OptimiseResult:
                t0 = time.perf_counter()
                with Progress(1, "optimise", enabled=progress, unit="") as fin:
                    fin.update(0, f"refining and verifying with the adaptive reference "
                                  f"({cfg.design.spring_kind} spring)", force=True)
                    res = finish(cfg, nlp, best, disc, verify=verify, polish=True,
                                 notes=list(notes), **dict(base))
                    fin.update(1, "verified" if res.success else "done", force=True)
                return replace(res, total_time=time.perf_counter() - t0
                               + (raw.total_time or 0.0))
            return replace(raw, total_time=time.perf_counter() - t_start), later
        if verify:
            bar.update(plan.n_starts, "verifying with the adaptive reference", force=True)
        res = finish(cfg, nlp, best, disc, verify=verify, polish=True, notes=notes, **base)
    return replace(res, total_time=time.perf_counter() - t_start)


@guarded
def solve(cfg, nodes: int | None = None, substeps: int | None = None,
          warm: OptimiseResult | None = None, verify: bool = False) -> OptimiseResult:
    """One Ipopt solve (for benchmarks and continuation): no multistart, no polish.

    Cold: from the best point of the coarse sweep. Warm (``warm`` = an earlier result of the
    same NLP): from its primal-dual point -- with the warm-start solver when the problem is
    unchanged, else with the cold solver from its primal point.
    """
    t_start = time.perf_counter()
    check_problem(cfg, 1)
    disc = discretisation(cfg, nodes, substeps)
    cached = has_nlp(cfg, disc.nodes, disc.substeps)
    nlp = get_nlp(cfg, disc.nodes, disc.substeps)
    build = 0.0 if cached else nlp.build_time
    bounds = nlp.bounds(cfg)
    rows, info = [], None
    if warm is not None and warm.run is not None and warm.nlp_key == nlp.key:
        prev: Run = warm.run
        p = nlp.params(cfg, J_ref=float(prev.p[J_INDEX]))
        same = all(np.array_equal(a, b) for a, b in zip(prev.bounds, bounds)) \
            and np.array_equal(p, prev.p)
        if same:
            r = nlp.solve(prev.x, p, *bounds, prev.lam_x, prev.lam_g, warm=True, origin="warm")
        else:
            r = nlp.solve(prev.x, p, *bounds, origin="previous answer")
    else:
        sim = stroke_simulator(cfg, sweep_time(cfg, disc.t_limit))
        designs, info = sweep_starts(cfg, 1, disc.t_limit, sim)
        p = nlp.params(cfg)
        w0, J0 = initial_guess(nlp, cfg, designs[0], sim, p, disc.t_limit)
        p[J_INDEX] = max(J0, 1e-8)
        r = nlp.solve(w0, p, *bounds, origin="best sweep point")
        rows.append(start_row(nlp, cfg, designs[0], r, J0))
    check_options(r, cfg)
    base = dict(starts=tuple(rows), build_time=build, sweep=info)
    if not r.success:
        res = OptimiseResult(
            False, f"Ipopt stopped with status {r.status} after {r.iterations} iterations; "
            "use optimise() (several starts) or raise optimise.max_iter", r.status, None, None,
            nodes=nlp.nodes, substeps=nlp.M, substeps_engaged=nlp.M_engaged,
            hessian=cfg.optimise.hessian,
            iterations=r.iterations,
            solve_time=r.time, problem=describe(cfg), config=cfg, run=r, nlp_key=nlp.key,
            notes=disc.notes, **base)
    else:
        res = finish(cfg, nlp, r, disc, verify=verify, polish=False, notes=list(disc.notes),
                     **base)
    return replace(res, total_time=time.perf_counter() - t_start)


__all__ = ["optimise", "solve", "claims", "active_set", "check_problem", "finish"]

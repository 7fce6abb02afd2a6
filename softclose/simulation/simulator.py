"""Closing strokes: metrics (SPEC §4), stability checks, accuracy estimates, trajectories.

``Simulator(case)`` (a config resolved by :func:`softclose.problem.resolve`; from a config:
``softclose.Simulator.from_config(cfg)``) holds one model, its coefficient table and one
fixed-step method; it runs single strokes (``run``) and batches of designs (``run_batch``)
in the C kernel. Metric-only runs keep no trajectory and evaluate no reactions;
``run(trajectory=True)`` also returns the per-step trajectory with the derived quantities a
figure needs.

``simulate(case)`` is the one-call wrapper (``softclose.simulate(cfg)`` from a config).
Every result knows how far it is from the converged answer: ``accuracy`` holds the
estimated error of each metric (Richardson, from the same stroke at half the step), and a
stroke that the method cannot integrate stably is reported with the step it would need --
never as a NaN.
"""

from __future__ import annotations

import copy
import math
from dataclasses import replace

import numpy as np

from ..model import elements
from .kernel import binding
from . import statics
from ..errors import ConfigError, NumericalError
from ..numerics.integrators import get_method, spectral_radius
from ..model.lid import LidModel, model_key
from ..model.dynamics import COEFFS
from ..model.temperature import at_temperature, parameter_factors
from ..model.resolved import LidCase
from ..problem import (DEFAULT_STEP, ERROR_KEYS, MIN_STEP, STEP_BUDGET, TRAJECTORY_BUDGET,
                       as_params, target)
from .stroke import StrokeResult, StrokeStatus, none_if_nan
from .kernel.table import CoefficientTable

#: the per-step quantities of a trajectory, in order
TRAJECTORY_KEYS = ("t", "theta", "theta_dot", "theta_ddot", "phi", "gamma", "tip_speed",
                   "spring_length", "energy")
#: largest relative interpolation error of the coefficient table that is accepted
TABLE_TOL = 1e-7
#: h |lambda|max above which an explicit method is outside its asymptotic regime
STIFF_H_LAMBDA = 1.0
#: the shortest spring length a stroke at a row's own points may reach (m; shorter: the row
#: is reported as invalid, Simulator.run_batch's ``points``). Near a lid point passing by its
#: anchor at a distance d, l is sqrt(d^2 + v^2 t^2): a cubic piece over a cell (the lid point
#: moves v h ~ 0.1 mm) is off by ~(v h / d)^4 / 384 relative, 1.6e-8 at d = 2 mm, within
#: TABLE_TOL. A table built at such points refines its cells; a row's own pieces do not, so
#: shorter strokes are refused (no spring one can buy is 2 mm long)
MIN_POINT_LENGTH = 2e-3


def _round_down(x: float) -> float:
    """x rounded down to 3 significant digits (a recommendation must not round up)."""
    if not (math.isfinite(x) and x > 0):
        return x
    e = math.floor(math.log10(x)) - 2
    return math.floor(x / 10 ** e) * 10 ** e


def _table(model: LidModel, cached: bool) -> CoefficientTable:
    """The coefficient table of ``model``; with ``cached``, from the disk cache (kept beside
    the model's entry) when it is there."""
    key = getattr(model, "cache_key", None) if cached else None
    if key is None:
        return CoefficientTable(model)
    from .. import buildcache
    entry = buildcache.load("table", key)
    if entry is not None:
        try:
            return CoefficientTable.restore(model, entry)
        except Exception:   # noqa: BLE001  (a damaged entry: build anew)
            pass
    table = CoefficientTable(model)
    buildcache.store("table", key, table.state())
    return table


#: rows of a batch's blocks: the statics of one while the kernel integrates the next
PIPE_ROWS = 4096


def _pipeline(kernel, statics_of, bounds) -> list:
    """[statics_of(a, b, kernel(a, b)) for each block [a, b) of ``bounds``], the kernel of
    the next block running in a thread (its C code releases the GIL) while this one's
    statics run here."""
    import threading
    blocks = list(zip(bounds[:-1], bounds[1:]))
    if len(blocks) == 1:
        (a, b), = blocks
        return [statics_of(a, b, kernel(a, b))]
    box: dict = {}

    def start(j):
        def work():
            try:
                box[j] = kernel(*blocks[j])
            except BaseException as exc:   # noqa: BLE001  (raised below, in this thread)
                box[j] = exc
        t = threading.Thread(target=work, daemon=True)
        t.start()
        return t
    out, t = [], start(0)
    for j, (a, b) in enumerate(blocks):
        t.join()
        got = box.pop(j)
        if isinstance(got, BaseException):
            raise got
        if j + 1 < len(blocks):
            t = start(j + 1)
        out.append(statics_of(a, b, got))
    return out


class Simulator:
    """Strokes of one config's geometry with one fixed-step method."""

    def __init__(self, case: LidCase, model: LidModel | None = None,
                 integrator: str | None = None, step: float | None = None,
                 cached: bool = False):
        """``case``: a config resolved (:func:`softclose.problem.resolve`: the lid, its
        stroke, its design, the solver settings and the temperatures). ``cached``: load the
        model and its table from the disk cache when this software built them before, else
        build and store them (:mod:`softclose.buildcache`; for one config at a time, not for
        the many configs of a sweep)."""
        if not isinstance(case, LidCase):
            raise TypeError(f"Simulator takes a resolved config (softclose.problem.resolve("
                            f"cfg), or Simulator.from_config(cfg)), got {type(case).__name__}")
        self.case = case
        #: the stroke's ends (:class:`softclose.model.resolved.StrokeEnds`)
        self.stroke = case.stroke
        self.model = model or (LidModel.cached(case) if cached else LidModel(case))
        self.method = get_method(integrator or case.solver.integrator)
        self.step = step or case.solver.step
        self.table = _table(self.model, cached)
        #: the parameters' factors at ``operating.temperature_c`` (None: the reference
        #: temperature): every p given to :meth:`run` and :meth:`run_batch` is a design at
        #: the reference temperature, and its stroke runs at the operating one
        self.temperature_factors = parameter_factors(case.temperatures)
        self._aged = statics.Aging(case.life, self.model, self.table)  # (the end of life)
        if self.table.max_rel_error > TABLE_TOL:
            raise NumericalError(
                f"the linkage passes close to a toggle position (transmission angle "
                f"{math.degrees(math.acos(min(self.model.max_abs_u, 1.0))):.2f} deg): the "
                f"tabulated equation of motion is only accurate to "
                f"{self.table.max_rel_error:.1e} there; move the stroke away from the toggle "
                "(geometry, stroke.theta0_deg, stroke.theta_closed_deg)")

    def for_case(self, case: LidCase) -> "Simulator":
        """A simulator of ``case`` on this one's model, coefficient table, method and step:
        ``case`` is of the same model (:func:`softclose.model.lid.model_key`) -- another
        ``stroke.t_max``, other spring length limits, another temperature -- so nothing is
        built again."""
        if model_key(case) != model_key(self.case):
            raise ValueError("Simulator.for_case: the case is of another model (geometry, "
                             "mass, stroke ends or mounting)")
        other = copy.copy(self)
        other.case, other.stroke = case, case.stroke
        other.temperature_factors = parameter_factors(case.temperatures)
        other._aged = statics.Aging(case.life, self.model, self.table)
        return other

    # -- batches ---------------------------------------------------------------------
    def energy_tol(self, P: np.ndarray, lid_mass=None, points=None) -> np.ndarray:
        """Energy rise that flags an unstable stroke: 5 % of the energy to be released
        (``points``: the rows' own attachment points, the kernel's convention)."""
        st = self.stroke
        E0 = statics.potential_energy(self.table, st.theta0, P, lid_mass, points)
        Vc = statics.potential_energy(self.table, st.theta_closed, P, lid_mass, points)
        scale = np.maximum(np.abs(E0 - Vc), 1e-6 * (np.abs(E0) + np.abs(Vc)) + 1e-12)
        return 0.05 * scale

    def run_batch(self, P, threads: int | None = None, lid_mass=None,
                  early_exit: bool = True, explain: bool = True, points=None,
                  opening: bool = False) -> dict:
        """Metrics for rows of P (the parameter vector, :data:`softclose.problem.PARAM_KEYS`):
        a dict of arrays (the metric keys,
        ``status`` as :class:`~softclose.simulation.stroke.StrokeStatus` codes, ``reason`` why an open
        stroke did not close, and the kernel's other outputs).

        ``lid_mass`` (scalar or one per row, kg) runs the rows at another lid mass without
        rebuilding the model (the coefficients are linear in it). ``early_exit`` stops a
        stroke as soon as the energy proves it can no longer close and its metrics can no
        longer change (see :mod:`softclose.simulation.kernel.binding`); the metrics are the same either way.
        ``explain=False``: a stroke that takes an element out of its valid range says only
        that, not where (:func:`softclose.simulation.statics.out_of_range`; faster for large screens).

        ``points`` gives rows their own attachment points without a model per point: an
        array (n, 8) or (8,) of ``geometry.spring_anchor[0]``, ``[1]``, ``lid_e[0]``, ``[1]``,
        ``dashpot_anchor[0]``, ``[1]``, ``dashpot_lid[0]``, ``[1]`` (m; NaN: the config's), or
        a mapping {placement key: a value or one per row} (:func:`softclose.simulation.kernel.binding.point_rows`).
        Every number of such a row -- the stroke, the spring's extremes and valid range, the
        holding moment, energy_tol -- is that of a simulator of the config with those points
        (each row's own pieces of the lengths are those of a table at its points, to the
        rounding of their node values); a row at the config's own points gives the same bits
        as without them. A row whose spring comes shorter than MIN_POINT_LENGTH on the stroke
        is OUT_OF_RANGE with that reason; one whose dashpot's length vanishes stops as not
        finite (:meth:`diagnose` says why).

        ``opening=True`` adds ``opening_force`` (:meth:`opening_forces`). A large batch of
        rows with their own points runs in blocks of PIPE_ROWS, the statics of one block
        (reasons, valid ranges, holding moments, opening efforts) while the kernel's threads
        integrate the next: the same numbers, a row's depend on that row alone.
        """
        P = as_params(np.atleast_2d(np.asarray(P, float)))
        X = binding.point_rows(self.table, points, len(P))
        P = at_temperature(self._aged(P, X), self.temperature_factors)
        st = self.stroke
        m = None if lid_mass is None else \
            np.broadcast_to(np.asarray(lid_mass, float), (len(P),)).copy()
        cols = [binding.kernel_rows(P), self.energy_tol(P, m, X)]
        if m is not None or X is not None:
            cols.append(np.full(len(P), np.nan) if m is None else m)
        if X is not None:
            cols.append(X)
        D = np.column_stack(cols)
        n = len(P)

        def kernel(a, b):
            return binding.run_strokes(self.table, self.method, self.step, st.t_max, st.theta0,
                                      st.theta_closed, D[a:b], threads, early_exit=early_exit)

        def statics_of(a, b, out):
            r = slice(a, b)
            Xr, mr = None if X is None else X[r], None if m is None else m[r]
            res = {name: out[:, i] for i, name in enumerate(binding.OUT_FIELDS)}
            res["status"] = out[:, 0].astype(int)
            res["reason"] = binding.not_closed_reasons(out)
            if Xr is not None:
                self._check_lengths(Xr, res)
            self._check_ranges(P[r], res, explain, Xr)
            res["closed"] = res["status"] == StrokeStatus.CLOSED
            # (Xr is already the kernel's point columns: not checked again)
            res["holding_moment"] = statics.holding_moments(
                self.table, self.stroke.theta_closed, P[r], mr, Xr)
            if opening:
                res["opening_force"] = statics.opening_forces(self.table, self.stroke, P[r],
                                                              mr, Xr)
            return res

        # (in blocks only with the rows' own points, whose statics weigh: a block's end is a
        # barrier for the kernel's threads, ~15 % of a batch at the table's own points)
        piped = X is not None and n > 2 * PIPE_ROWS
        bounds = list(range(0, n, PIPE_ROWS)) + [n] if piped else [0, n]
        parts = _pipeline(kernel, statics_of, bounds)
        res = parts[0] if len(parts) == 1 else \
            {k: np.concatenate([q[k] for q in parts]) for k in parts[0]}
        if X is not None:
            res["points"] = X
        return res

    def _check_lengths(self, X, res: dict) -> None:
        """Rows with their own spring points whose stroke takes the spring's length below
        MIN_POINT_LENGTH (its lid point passes by or through its anchor) become OUT_OF_RANGE
        with that reason; a length that vanishes exactly has already stopped the stroke (not
        finite), which :meth:`diagnose` explains."""
        ok = np.isin(res["status"], (StrokeStatus.CLOSED, StrokeStatus.NOT_CLOSED))
        with np.errstate(invalid="ignore"):
            bad = np.flatnonzero(ok & ~np.isnan(X[:, 0])
                                 & ~(res["min_spring_length"] >= MIN_POINT_LENGTH))
        for i in bad:
            res["status"][i] = StrokeStatus.OUT_OF_RANGE
            res["reason"][i] = (f"geometry.spring_anchor and geometry.lid_e: the spring's "
                                f"length vanishes on the stroke (its lid point passes within "
                                f"{max(res['min_spring_length'][i], 0.0) * 1e3:.2g} mm of its "
                                f"anchor, below {MIN_POINT_LENGTH * 1e3:g} mm); move either "
                                "point")

    def _check_ranges(self, P, res: dict, explain: bool = True, points=None) -> None:
        """Strokes that take an element outside its valid range become OUT_OF_RANGE, their
        reason saying where and by how much (:func:`softclose.simulation.statics.out_of_range`)."""
        ok = np.isin(res["status"], (StrokeStatus.CLOSED, StrokeStatus.NOT_CLOSED))
        if not ok.any():
            return
        idx = np.flatnonzero(ok)
        coord = statics.table_coordinate(self.table, None if points is None else
                                         np.asarray(points)[idx])
        _, why = statics.out_of_range(coord, self.case.lid.mounting, P[idx],
                                      {k: np.asarray(v)[idx] for k, v in res.items()
                                       if k in binding.OUT_FIELDS}, explain)
        bad = why != ""
        if bad.any():
            res["status"][idx[bad]] = StrokeStatus.OUT_OF_RANGE
            res["reason"][idx[bad]] = why[bad]

    def opening_forces(self, P: np.ndarray, lid_mass=None, points=None) -> np.ndarray:
        """The opening effort (N) of rows of P (:func:`softclose.simulation.statics.opening_forces`): not
        part of :meth:`run_batch` (statics, which a search of designs does not need);
        ``points`` as :meth:`run_batch` takes them."""
        P = as_params(np.atleast_2d(np.asarray(P, float)))
        return statics.opening_forces(self.table, self.stroke, P, lid_mass,
                                      binding.point_rows(self.table, points, len(P)))

    def holding_moments(self, P: np.ndarray, lid_mass=None, points=None) -> np.ndarray:
        """dV/dtheta at theta_closed (N m) for rows of P (``points`` as :meth:`run_batch`)."""
        P = as_params(np.atleast_2d(np.asarray(P, float)))
        return statics.holding_moments(self.table, self.stroke.theta_closed, P, lid_mass,
                                       binding.point_rows(self.table, points, len(P)))

    # -- one stroke ------------------------------------------------------------------
    def run(self, p=None, trajectory: bool = False, estimate_error: bool = True) -> StrokeResult:
        p = at_temperature(self._aged(self.model.params() if p is None else as_params(p)),
                           self.temperature_factors)
        st = self.stroke
        design = np.r_[binding.kernel_rows(p), self.energy_tol(p[None, :])]
        if trajectory:
            self._check_trajectory_size(design)
            out, traj = binding.run_stroke_trajectory(self.table, self.method, self.step,
                                                     st.t_max, st.theta0, st.theta_closed, design)
        else:
            out = binding.run_strokes(self.table, self.method, self.step, st.t_max, st.theta0,
                                     st.theta_closed, design[None, :], threads=1)[0]
        res = self._result(out, p)
        if res.ok:
            _, why = statics.out_of_range(statics.table_coordinate(self.table),
                                          self.case.lid.mounting, p[None, :], res.__dict__)
            if why[0]:                # an invalid design: no stroke metrics are its
                res = replace(res, status=StrokeStatus.OUT_OF_RANGE, closed=False,
                              closing_time=None, impact_theta_dot=None,
                              impact_tip_speed=None, peak_tip_speed=None,
                              message=f"invalid design: {why[0]}", reason=why[0])
        if res.ok and estimate_error:
            accuracy, message = self._error_estimate(res, p)
            res = replace(res, accuracy=accuracy, message=message)
        if trajectory and res.ok:
            keys = None if trajectory is True else tuple(trajectory)
            res = replace(res, trajectory=self.derive_trajectory(traj, p, keys))
        return res

    def _check_trajectory_size(self, design) -> None:
        """Refuse a trajectory of more than TRAJECTORY_BUDGET rows (one a step: to the closing,
        or to t_max for a lid that does not close), counted by a stroke without one."""
        st = self.stroke
        if st.t_max / self.step + 2 <= TRAJECTORY_BUDGET:
            return
        out = binding.run_strokes(self.table, self.method, self.step, st.t_max, st.theta0,
                                 st.theta_closed, design[None, :], threads=1)[0]
        closed = StrokeStatus(int(out[0])) is StrokeStatus.CLOSED
        steps = int(out[binding.OUT_FIELDS.index("steps")]) if closed else \
            int(math.ceil(st.t_max / self.step))
        rows = steps + 2                       # the release, each step, the closing or t_max
        if rows > TRAJECTORY_BUDGET:
            h = self.step * rows / TRAJECTORY_BUDGET * (1 - 1e-9)
            h = math.ceil(h / 10 ** (e := math.floor(math.log10(h)) - 1)) * 10 ** e
            fix = f"use simulate.step >= {h:.2g} s" + ("" if closed else
                                                        " or a shorter stroke.t_max")
            raise ConfigError(
                f"simulate.step: the trajectory at {self.step:g} s would have {rows} rows "
                f"({'to the closing' if closed else 'to stroke.t_max'}), above the budget of "
                f"{TRAJECTORY_BUDGET:g} for tables and figures; {fix}")

    def _result(self, out, p) -> StrokeResult:
        status = StrokeStatus(int(out[0]))
        closed = status is StrokeStatus.CLOSED
        col = {name: none_if_nan(out[i]) for i, name in enumerate(binding.OUT_FIELDS)}
        ok = status.ok
        reason = None
        if status is StrokeStatus.NOT_CLOSED:
            reason = str(binding.not_closed_reasons(np.asarray(out)[None, :])[0]) or None
        return StrokeResult(
            closed=closed,
            closing_time=col["closing_time"] if closed else None,
            impact_theta_dot=col["impact_theta_dot"] if closed else None,
            impact_tip_speed=col["impact_tip_speed"] if closed else None,
            peak_tip_speed=col["peak_tip_speed"] if ok else None,
            min_spring_length=col["min_spring_length"] if ok else None,
            max_spring_length=col["max_spring_length"] if ok else None,
            holding_moment=self.model.holding_moment(p), status=status,
            opening_force=float(self.opening_forces(np.asarray(p)[None, :])[0]),
            method=self.method.name, step=self.step, steps=int(out[7]),
            message=None if ok else self.diagnose(status, p), reason=reason,
            theta_min=col["theta_min"] if ok else None, theta_max=col["theta_max"] if ok else None,
            theta_dot_max=col["theta_dot_max"] if ok else None,
            stop_theta=col["stop_theta"] if status is StrokeStatus.NOT_CLOSED else None,
            engage_time=col["engage_time"] if ok else None,
            engage_theta_dot=col["engage_theta_dot"] if ok else None)

    def friction_gain(self, p) -> float:
        """How much dry friction amplifies the table's relative error in a stroke's metrics:
        (|V'| + T_f) / ||V'| - T_f| at the release (1 without friction). A lid whose driving
        moment barely exceeds the friction moves on their small difference, which the
        table knows only to its error times the moments themselves (a lid released at 1.0001
        x T_f closes 4e-7 s off at any step: the table's 7.8e-12, amplified 2e4 times)."""
        if sum(float(e.coulomb(elements.params(np.asarray(p, float)))) for e in
               elements.FRICTIONS) <= 0:
            return 1.0
        Tf = float(self.model.friction_moment(self.stroke.theta0, p))
        dV = abs(float(self.model.dV(self.stroke.theta0, p)))
        return (dV + Tf) / max(abs(dV - Tf), 1e-300 + 1e-15 * (dV + Tf))

    def _error_estimate(self, res: StrokeResult, p) -> tuple[dict, str | None]:
        """|metric(h) - converged| estimated from the stroke at h/2 (Richardson), and a
        warning when the estimate exceeds the accuracy targets or the design is stiff."""
        half = Simulator.__new__(Simulator)
        half.__dict__.update(self.__dict__)
        half.step = self.step / 2
        half.temperature_factors = None        # (p holds the parts at the temperature)
        half._aged = statics.Aging(None, None, None)     # (and at the end of life)
        r2 = half.run(p, estimate_error=False)
        q = 2.0 ** self.method.order
        tab = self.table.max_rel_error * self.friction_gain(p)
        est = {}
        # the end damper's engagement (an event of the stroke, located to the method's order
        # like the closing): estimated the same way where the lid reaches it; no target
        engage = ("engage_time", "engage_theta_dot") if res.engage_time is not None else ()
        for k in ERROR_KEYS + engage:  # step error (Richardson) + what the table error can cause
            a, b = getattr(res, k), getattr(r2, k)
            est[k] = None if a is None or b is None else abs(a - b) * q / (q - 1) + tab * abs(a)
        est["table_rel_error"] = self.table.max_rel_error
        h_lam = self.step * self.max_rate(p)
        est["step_times_max_rate"] = h_lam if math.isfinite(h_lam) else None
        if h_lam > STIFF_H_LAMBDA and self.method.real_stability != math.inf:
            return est, (f"warning: stiff for {self.method.name} at this step "
                         f"(h |lambda|max = {h_lam:.2g}): the error estimate may be too small; "
                         "prefer simulate.integrator = \"radau5\" or a smaller simulate.step")
        over = [k for k in ERROR_KEYS if est[k] is not None
                and est[k] > target(k, getattr(res, k))]
        table_bound = [k for k in over if tab * abs(getattr(res, k)) > target(k, getattr(res, k))]
        if table_bound:       # no step helps: the table's error, amplified by friction
            return est, (f"warning: {', '.join(table_bound)} may be off by about "
                         f"{max(est[k] for k in table_bound):.2g} whatever the step: the lid "
                         f"moves on the small difference between its driving moment and the "
                         f"friction moment (x{self.friction_gain(p):.3g} of the table's error "
                         f"{self.table.max_rel_error:.1e}); the adaptive reference "
                         "(softclose.Reference) has no table")
        if over:
            # error ~ h^order: the step that brings the worst metric within its target (a
            # relative target of a zero value is zero: any error exceeds it, by a large ratio)
            worst = max(est[k] / max(target(k, getattr(res, k)), 1e-300) for k in over)
            h_new = _round_down(0.8 * self.step * worst ** (-1.0 / self.method.order))
            where = (f"use simulate.step <= {h_new:.3g} s" if h_new >= MIN_STEP else
                     f"a step below the smallest admissible ({MIN_STEP:g} s) would be needed")
            return est, (f"warning: the estimated error of {', '.join(over)} exceeds the "
                         f"accuracy targets at simulate.step = {self.step:g} s; for the targets "
                         f"{where}")
        return est, None

    def _jacobians(self, p, lid_mass=None, points=None):
        """Linearised (theta, theta') Jacobian entries at rest along the stroke (at
        ``lid_mass``, kg; None: the table's own; ``points``: the design's own, as
        :meth:`run_batch` takes them)."""
        th = np.linspace(self.stroke.theta_closed, self.stroke.theta0, 41)
        X = binding.point_rows(self.table, points, 1)
        return statics.rest_jacobian(self.table, th, p, lid_mass, None if X is None else X[0])

    def max_rate(self, p, lid_mass=None, points=None) -> float:
        """max |lambda| of the linearised stroke (1/s): what limits an explicit step
        (inf when the linearisation overflows)."""
        a, b = self._jacobians(as_params(p), lid_mass, points)
        with np.errstate(over="ignore", invalid="ignore"):
            disc = np.sqrt((b * b + 4 * a).astype(complex))
            lam = np.abs(np.r_[(b + disc) / 2, (b - disc) / 2])
        return float(np.max(lam)) if np.all(np.isfinite(lam)) else math.inf

    def diagnose(self, status: StrokeStatus, p, lid_mass=None, points=None) -> str:
        """A one-line report of why a stroke failed and what to change (``lid_mass``: the
        stroke ran at that lid mass, kg, through the table's lid-mass column; ``points``:
        at its own attachment points, as :meth:`run_batch` takes them)."""
        m, h = self.method, self.step
        st = self.stroke
        status = StrokeStatus(status)
        p = as_params(p)
        if lid_mass == self.table.lid_mass:
            lid_mass = None
        X = binding.point_rows(self.table, points, 1)
        if status is StrokeStatus.NON_FINITE and X is not None:
            why = self.vanishing_length(X[0])
            if why:
                return why
        a0 = 0.0   # theta'' at release: the model's, or at another lid mass the table's
        if status is StrokeStatus.LEFT_RANGE:
            a0 = (self.model.theta_ddot(st.theta0, 0.0, p) if lid_mass is None and X is None
                  else float(statics.rest_theta_ddot(self.table, st.theta0,
                                                     np.asarray(p)[None, :], lid_mass, X)[0]))
        if a0 > 0:
            return (f"the lid does not close: released at stroke.theta0_deg = {st.theta0_deg} deg "
                    f"it is pushed open (theta'' = {a0:.4g} "
                    "rad/s^2 > 0 at release) and swings away from the rim; lower theta0_deg or "
                    "change the spring (spring_k, spring_rest_length)")
        if not status.ok:
            h_ok = self.stable_step(p, lid_mass, X)
            if h_ok >= h:  # linearly stable: the step is too coarse for the stroke itself
                return (f"{m.name} at step {h:g} s cannot integrate this design ({status}): the "
                        f"step is too coarse to resolve the stroke; use a simulate.step at least "
                        f"10 times smaller (the default is {DEFAULT_STEP:g} s)")
            h_ok = _round_down(0.9 * h_ok)  # a margin inside the stability boundary
            stiff = ("lower design.spring_k, design.damper_c, design.rotary_damper_c or "
                     "design.end_damper_c, or "
                     "raise the masses")
            if h_ok < MIN_STEP:  # no admissible step is stable: the method cannot do it
                hint = (f"no admissible step (>= {MIN_STEP:g} s) is stable for it; "
                        + ("" if m.real_stability == math.inf else
                           "use simulate.integrator = \"radau5\" (L-stable) or ") + stiff)
                return (f"{m.name} at step {h:g} s cannot integrate this design ({status}): "
                        f"its fastest mode is too fast (stiff); {hint}")
            hint = f"use simulate.step <= {h_ok:.3g} s"
            if st.t_max / h_ok > STEP_BUDGET:
                hint += f" with stroke.t_max <= {_round_down(STEP_BUDGET * h_ok):.3g} s"
            alt = "" if m.real_stability == math.inf else \
                " or simulate.integrator = \"radau5\" (L-stable, for stiff damping)"
            return (f"{m.name} at step {h:g} s cannot integrate this design ({status}): its "
                    f"fastest mode needs h|lambda| within the method's stability region; "
                    f"{hint}{alt}")
        return status.text

    def vanishing_length(self, points) -> str:
        """Why a row's own attachment points (one row of the kernel's convention) make a
        length vanish on the tabulated range -- its lid point passes through its anchor,
        where the length has no slope -- or "" (the shortest length on a fine grid, against
        the scale of the linkage)."""
        th = np.linspace(self.table.lo, self.table.hi, 20 * self.table.ncell + 1)
        X = np.asarray(points, float).reshape(1, -1)
        A = self.table.pose_at(th)
        scale = 1e-6 * max(self.model.geo.crank_oa, self.model.geo.crank_bc)
        for name, (blk, _), key in (("spring", statics.POINT_BLOCKS["spring"],
                                     "geometry.spring_anchor and geometry.lid_e"),
                                    ("dashpot", statics.POINT_BLOCKS["dashpot"],
                                     "geometry.dashpot_anchor and geometry.dashpot_lid")):
            if np.isnan(X[0, blk.start]):
                continue
            g = X[0, blk]
            rx = A[:, 0] + A[:, 4] * g[2] - A[:, 5] * g[3] - g[0]
            ry = A[:, 1] + A[:, 5] * g[2] + A[:, 4] * g[3] - g[1]
            l = np.hypot(rx, ry)
            j = int(np.argmin(l))
            if not (l[j] > scale):
                return (f"{key}: the {name}'s length vanishes at theta = "
                        f"{math.degrees(th[j]):.1f} deg (its lid point passes through its "
                        f"anchor, {l[j] * 1e3:.2g} mm); move either point")
        return ""

    def stable_step(self, p, lid_mass=None, points=None) -> float:
        """Largest step at which the linearised stroke is stable (bisection on the step);
        0.0 when none down to 1e-12 s is, or the linearisation is not finite."""
        f_th, f_v = self._jacobians(as_params(p), lid_mass, points)
        if not (np.all(np.isfinite(f_th)) and np.all(np.isfinite(f_v))):
            return 0.0
        Js = [np.array([[0.0, 1.0], [a, b]]) for a, b in zip(f_th, f_v)]
        lams = [np.linalg.eigvals(J) for J in Js]

        def stable(h):  # numerically stable: no faster growth than the exact flow's
            with np.errstate(over="ignore"):
                return all(spectral_radius(self.method, J, h)
                           <= max(1.0, float(np.max(np.abs(np.exp(h * lam))))) * (1 + 1e-6)
                           for J, lam in zip(Js, lams))
        hi = self.step
        if stable(hi):
            return hi
        lo = hi
        while not stable(lo):
            if lo < 1e-12:
                return 0.0
            lo /= 2
        for _ in range(40):
            mid = math.sqrt(lo * hi)
            lo, hi = (mid, hi) if stable(mid) else (lo, mid)
        return lo

    # -- trajectories ----------------------------------------------------------------
    def derive_trajectory(self, traj: np.ndarray, p, keys: tuple | None = None) -> dict:
        """Per-step quantities for figures and CSV: angles, speeds, spring length, energy
        (``keys``: only these, e.g. the optimiser's initial guess needs no energy)."""
        m = self.model
        n = len(traj)
        X = traj[:, 1:3].T
        want = set(TRAJECTORY_KEYS if keys is None else keys)
        out = {"t": traj[:, 0], "theta": traj[:, 1], "theta_dot": traj[:, 2]}
        if want & {"phi", "gamma", "tip_speed"}:
            kin = m.kin.map(n)(X)
            v_T = np.asarray(kin[4])
            out.update({"phi": np.asarray(kin[0]).ravel(), "gamma": np.asarray(kin[1]).ravel(),
                        "tip_speed": np.hypot(v_T[0], v_T[1])})
        if want & {"theta_ddot", "energy"}:
            P = np.repeat(np.asarray(p, float)[:, None], n, axis=1)
            out["theta_ddot"] = np.asarray(m.ode.map(n)(X, P))[1]
            out["energy"] = np.asarray(m.energy_fn.map(n)(X, P)).ravel()
        if "spring_length" in want:
            out["spring_length"] = self.table.evaluate(traj[:, 1])[:, COEFFS.index("l")]
        return {k: out[k] for k in TRAJECTORY_KEYS if k in out and (k in want or k in
                                                                   ("t", "theta", "theta_dot"))}


def simulate(case: LidCase, trajectory: bool = False) -> StrokeResult:
    """One closing stroke of a resolved config's design (``case``,
    :func:`softclose.problem.resolve`) with its integrator and step (from a config:
    ``softclose.simulate(cfg)``).

    Returns a :class:`~softclose.simulation.stroke.StrokeResult`: the metrics, each fixed-step one with
    its estimated distance from the converged answer (``accuracy``), and with
    ``trajectory=True`` the time histories (``.plot()``, ``.trajectory_frame()``). A stroke
    the method cannot integrate is reported (``ok`` False, ``message`` says what to change),
    never raised.
    """
    return Simulator(case, cached=True).run(trajectory=trajectory)

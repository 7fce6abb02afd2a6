"""The adaptive reference: CVODES (through CasADi) on the exact equation of motion.

Independent of the fast path: no table, no fixed step. It integrates on an output grid
(tolerance ``simulate.reference_tol``; :data:`softclose.problem.REFERENCE_TOL` unless given)
and locates each event by Newton's method on the length of a last integration, ``x(tau) =
CVODES(x_k, tau)`` (time scaled to [0, 1] with tau as a parameter); interior maxima of the
tip speed and the lowest angle of a stroke that turns back are located the same way on the
root of their time derivative. With dry friction the direction of motion is a parameter of
the flow: each rest (theta' = 0) is an event, located the same way, where the lid sticks if
the driving moment |dV/dtheta| does not exceed the friction moment T_f, and otherwise moves
on the way -dV/dtheta drives it (so also at the release). An end damper acts only below its
engagement angle: each crossing of that angle is an event, located the same way, at which
the damper engages (moving down) or lets go (moving up); its first engagement gives
``engage_time`` and ``engage_theta_dot``. Between events the flow is smooth (CVODES never
steps across the switch). Used by tests, by ``optimise``'s verification and by ``bench``.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from ..model import elements
from . import statics
from ..errors import NumericalError
from ..interrupt import solving
from ..model.life import aged, at_end_of_life, shut_coordinates
from ..model.temperature import at_temperature, parameter_factors
from ..problem import REFERENCE_TOL, as_params
from ..numerics.roots import hermite_peak, hermite_root, illinois
from .stroke import StrokeResult, StrokeStatus

#: grid steps of the reference integrated in one CVODES run (then scanned for events)
CHUNK = 16
#: most CVODES steps of one such run: a chunk of a stroke takes ~70-120 at tolerance 1e-12;
#: one that runs past the rim towards a toggle position (where the closure has no solution
#: and the equation is NaN) would otherwise grind on, shrinking its steps, for minutes
CHUNK_MAX_STEPS = 4000
#: a tip speed's maximum is located in time to this fraction of the steps searched
PEAK_WIDTH = 1e-8
#: a lid that rings: more than MAX_TURNS turns (the lid stopping and going back) in a
#: stroke, at more than one turn in RINGING_STEPS grid steps -- an oscillation the grid step
#: does not resolve (a stiff spring against a light, little-damped lid: hundreds of turns a
#: second, each a root search of a few CVODES runs, tens of seconds a stroke); the reference
#: stops following it. A lid that swings slowly (a few turns a second) is followed
MAX_TURNS = 20
RINGING_STEPS = 4
#: points of each finer grid that refines a spring length's extreme (one call each)
REFINE_POINTS = 33


class Reference:
    """Adaptive reference simulation of one model (from a config:
    ``softclose.Reference.from_config(cfg)``)."""

    def __init__(self, model, tol: float | None = None, grid_step: float = 2e-3,
                 case=None):
        """``tol``: the CVODES tolerance (a config's ``simulate.reference_tol``,
        :attr:`softclose.model.resolved.SolverSettings.reference_tol`); None: its default
        :data:`softclose.problem.REFERENCE_TOL`. ``case``: the resolved config
        (:class:`softclose.model.resolved.LidCase`) :meth:`simulate` judges and runs at when
        given none."""
        self.model = model
        self.tol = tol if tol is not None else REFERENCE_TOL
        self.case = case
        self.grid_step = grid_step
        x, tau, s = ca.SX.sym("x", 2), ca.SX.sym("tau"), ca.SX.sym("moving")
        eg = ca.SX.sym("engaged", len(elements.ENGAGING))
        p = ca.SX.sym("p", len(elements.PARAMS))
        # s: the way the lid moves (+1 up, -1 down), which sets dry friction's sign; eg: each
        # end damper engaged (1) or not (0)
        f = model.ode_moving(x, p, s, eg)
        opts = {"abstol": self.tol, "reltol": self.tol, "max_num_steps": 200000}
        dae = {"x": x, "p": ca.vertcat(p, s, eg, tau), "ode": tau * f}
        self._flow = ca.integrator("ref_flow", "cvodes", dae, 0.0, 1.0, opts)
        # the same flow with CHUNK grid nodes in one call: CVODES carries on through the
        # nodes instead of starting afresh at each (a start costs ~0.5 ms: its first steps
        # are tiny and of order one; the nodes of a continued run cost ~30 us each)
        self._chunk_flow = ca.integrator("ref_chunk", "cvodes", dae, 0.0,
                                         [i / CHUNK for i in range(1, CHUNK + 1)],
                                         {**opts, "max_num_steps": CHUNK_MAX_STEPS})
        self._ahead: list = []      # the next grid states of the current chunk
        self._ahead_key = None      # (state they continue from, step, direction of motion)
        self._chunk_off = 0         # grid steps to take singly (after a failed chunk: all)
        v_T = model.kin(x)[4]
        # d|v_T|/dt = v.a/|v| with a = dv/dt by AD along the flow; at rest it is |a|
        a_T = ca.jtimes(v_T, x, f)
        speed = ca.norm_2(v_T)
        dspeed = ca.if_else(speed > 0, ca.dot(v_T, a_T) / speed, ca.norm_2(a_T))
        self._speed_fn = ca.Function("speed", [x, p, s, eg], [speed, dspeed])
        # the speeds at a chunk's nodes in one call (a call from Python costs ~0.1 ms)
        self._speed_chunk = self._speed_fn.map(CHUNK)
        self._speeds: dict = {}     # (node, moving, engaged) -> (|v_T|, d|v_T|/dt)
        self._length_maps = None    # the spring length on the coarse and the fine grids
        self._moving = -1.0
        self._engaged = np.zeros(len(elements.ENGAGING))

    def _speed(self, x, p) -> tuple[float, float]:
        """(|v_T|, d|v_T|/dt) at the state x, moving the stroke's current way (a node of the
        current chunk: computed with it)."""
        known = self._speeds.get(self._speed_key(x))
        if known is not None:
            return known
        v, dv = self._speed_fn(x, p, self._moving, self._engaged)
        return float(v), float(dv)

    def _speed_key(self, x) -> tuple:
        return (np.asarray(x, float).tobytes(), self._moving, self._engaged.tobytes())

    def flow(self, x0, p, tau):
        """State after integrating for ``tau`` seconds from ``x0`` (moving the way of the
        stroke's current direction, which matters only with dry friction)."""
        if tau <= 0:
            return np.asarray(x0, float)
        try:
            with solving():      # Ctrl-C: noted, raised when CVODES returns
                out = self._flow(x0=x0, p=np.r_[p, self._moving, self._engaged, tau])["xf"]
            return np.asarray(out).ravel()
        except RuntimeError as exc:   # (a step towards a toggle position: the equation is NaN)
            raise NumericalError(f"the reference integrator (CVODES) failed from theta = "
                                 f"{math.degrees(float(x0[0])):.4g} deg "
                                 f"({str(exc).splitlines()[-1].strip()})") from None

    def step(self, x0, p, h):
        """State after one grid step ``h`` from the node ``x0``: from the chunk (one CVODES
        run over the next :data:`CHUNK` nodes) when ``x0`` is the node it has reached, else
        by a new chunk; singly where a chunk fails (it may run past the rim into a toggle
        position) -- a single step that fails raises as :meth:`flow` does."""
        key = (h, self._moving, tuple(self._engaged))
        if self._ahead and self._ahead_key == key and np.array_equal(self._ahead_x, x0):
            self._ahead_x = self._ahead.pop(0)
            return self._ahead_x
        self._ahead = []
        if self._chunk_off > 0:
            self._chunk_off -= 1
            return self.flow(x0, p, h)
        try:
            with solving():
                xs = np.asarray(self._chunk_flow(x0=x0, p=np.r_[p, self._moving,
                                                                self._engaged,
                                                                CHUNK * h])["xf"])
        except RuntimeError:
            xs = None
        if xs is None or not np.all(np.isfinite(xs)):
            # a chunk that fails is near the end of what the stroke can reach (past the rim,
            # towards a toggle): the rest of the stroke is taken step by step
            self._chunk_off = 1 << 62
            return self.flow(x0, p, h)
        self._ahead = [xs[:, i].copy() for i in range(1, CHUNK)]
        self._ahead_key, self._ahead_x = key, xs[:, 0].copy()
        v, dv = (np.asarray(a).ravel() for a in
                 self._speed_chunk(xs, p, self._moving, self._engaged))
        self._speeds = {self._speed_key(xs[:, i]): (float(v[i]), float(dv[i]))
                        for i in range(CHUNK)}
        return self._ahead_x

    def _newton_time(self, x0, p, h, residual, lo=0.0, hi=None, x_hi=None, guess=None,
                     width=None):
        """Root in (lo, hi] of residual(x(tau)) (a sign change is bracketed) to a bracket of
        ``width`` (default 1e-14 s) or a residual below 1e-15; ``x_hi``: the state at hi when
        known (a node), ``guess``: a first guess of the root (the cubic Hermite
        interpolant's, :mod:`.roots`).

        A search from the step's ends alone takes ~7 fresh CVODES runs of ~1 ms (each starts
        with tiny steps at order one); from a guess good to O(h^4), and a second point just
        past it on the far side, the bracket is that small at once and the search ends in
        ~2 more."""
        hi = h if hi is None else hi
        at = lambda tau: residual(self.flow(x0, p, tau))   # noqa: E731
        r_lo = at(lo)
        r_hi = residual(x_hi) if x_hi is not None else at(hi)
        if guess is not None and lo < guess < hi and (r_lo > 0) != (r_hi > 0):
            slope = (r_hi - r_lo) / (hi - lo)
            r_g = at(guess)
            if r_g == 0:
                return guess
            # the guess ends the bracket on its side; a second point past it, twice its
            # residual's distance along the chord, towards the other end
            step = 2.0 * abs(r_g / slope) + 1e-13 * max(1.0, hi)
            if (r_g > 0) == (r_lo > 0):
                lo, r_lo, probe = guess, r_g, guess + step
            else:
                hi, r_hi, probe = guess, r_g, guess - step
            if lo < probe < hi:
                r_s = at(probe)
                if (r_s > 0) == (r_lo > 0):
                    lo, r_lo = probe, r_s
                else:
                    hi, r_hi = probe, r_s
        return illinois(at, lo, hi, r_lo, r_hi,
                        lambda a, b, tau, r: (r == 0 or b - a < (width or 1e-14 * max(1.0, b))
                                              or abs(r) < 1e-15), 200)

    def _peak_speed(self, xa, p, H, xb) -> float:
        """The tip speed's maximum in (0, H] between the state xa and xb = x(H), its time
        derivative falling through zero there: searched from the maximum of the speed's
        cubic Hermite interpolant (:func:`.roots.hermite_peak`). Only the speed is used, and
        it is flat in time: a time within :data:`PEAK_WIDTH` H of the maximum gives it to
        ~|v''| (1e-8 H)^2 / 2, far below the integrator's tolerance (a search to 1e-14 s
        took ~14 fresh CVODES runs, in the integrator's noise on d|v|/dt)."""
        (ga, da), (gb, db) = self._speed(xa, p), self._speed(xb, p)
        tm = self._newton_time(xa, p, H, lambda y: self._speed(y, p)[1], x_hi=xb,
                               guess=hermite_peak(H, ga, da, gb, db), width=PEAK_WIDTH * H)
        return self._speed(self.flow(xa, p, tm), p)[0]

    def _angle_time(self, x0, p, h, angle, x1):
        """When theta reaches ``angle`` in (0, h] from the node x0 (x1 = x(h) beyond it),
        from the root of theta's cubic Hermite interpolant (:func:`.roots.hermite_root`)."""
        f0, f1 = x0[0] - angle, x1[0] - angle
        guess = hermite_root(h, f0, x0[1], f1, x1[1]) if (f0 > 0) != (f1 > 0) else None
        return self._newton_time(x0, p, h, lambda y: y[0] - angle, x_hi=x1, guess=guess)

    def _cross_time(self, x0, p, h, angle, engaged, x1=None):
        """When theta crosses an end damper's ``angle`` in (0, h] from the node x0, the damper
        ``engaged`` (theta < angle) or not (theta >= angle). A node on the angle itself (a
        release at theta0 = angle) is on the side of its state: it crosses at once (0) if
        it leaves that side at once, else where it comes back (the bracket starts where the
        flow is on its side)."""
        residual = lambda y: y[0] - angle  # noqa: E731
        if x0[0] != angle:
            if x1 is not None:
                return self._angle_time(x0, p, h, angle, x1)
            return self._newton_time(x0, p, h, residual)
        own, s = (-1.0 if engaged else 1.0), 0.5 * h
        while s > 1e-15 * h:
            if own * residual(self.flow(x0, p, s)) > 0:
                return self._newton_time(x0, p, h, residual, lo=s)
            s *= 0.5
        return 0.0

    def simulate(self, p=None, case=None, opening: bool = True) -> StrokeResult:
        """The metrics of one stroke (plus ``theta_min``, ``theta_max``), adaptively.

        Returns the same :class:`~softclose.simulation.stroke.StrokeResult` as the fixed-step
        simulator, with ``method`` "cvodes" and ``tolerance`` the CVODES tolerance. A failure
        of CVODES raises :class:`~softclose.errors.NumericalError`. ``case``: the resolved
        config (:class:`softclose.model.resolved.LidCase`) whose spring length limits
        (``design.spring_min_length``, ``spring_max_length``) the stroke is checked against
        and whose temperatures it runs at -- default the reference's own (``case`` given to
        it), else the model's lid at the reference temperature; a model shared between
        configs (the caches key models by their structure, not by these limits) is given the
        one judged. ``p`` is a design at the
        reference temperature (default the model's); the stroke runs at the case's
        ``operating.temperature_c`` (:mod:`softclose.model.temperature`). ``opening=False``
        leaves the opening effort out (None; its exact search is a fifth of a stroke's time).
        """
        m, st = self.model, self.model.stroke
        case = self.case if case is None else case
        p = m.params() if p is None else as_params(p)
        if case is not None and aged(case.life):    # the parts at the end of their life
            p = at_end_of_life(p, case.life, shut_coordinates(m))
        p = at_temperature(p, None if case is None else parameter_factors(case.temperatures))
        mounting = m.mounting if case is None else case.lid.mounting
        thc, t_max, dt = st.theta_closed, st.t_max, self.grid_step
        x = np.array([st.theta0, 0.0])
        t, peak, th_min, th_max = 0.0, 0.0, st.theta0, st.theta0
        speed = lambda y: self._speed(y, p)[0]  # noqa: E731
        dspeed = lambda y: self._speed(y, p)[1]  # noqa: E731
        prev = None  # (t, x, g) of the previous node
        g_x = None   # the tip speed at x, when known (the previous step's g1)
        closed, out, stuck = False, {}, None
        turns = steps = 0   # the lid's turns and the grid steps so far (:data:`MAX_TURNS`)
        # a spring outside its valid range at every angle from the rim to the release is an
        # invalid design whatever the stroke does: not integrated (such a lid may oscillate
        # wildly, every turn an event); the reason is the one its stroke would give
        invalid = self._invalid_throughout(p, mounting, thc, st.theta0, opening)
        if invalid is not None:
            return invalid
        T_f = sum(float(e.coulomb(elements.params(p))) for e in elements.FRICTIONS)
        self._moving, self._ahead, self._chunk_off, self._speeds = -1.0, [], 0, {}
        # the end dampers' engagement angles (none where a damper has no coefficient): a
        # crossing is an event; engaged where the lid is below the angle
        Pn = elements.params(p)
        angles = np.array([float(Pn[e.engagement]) if float(e.viscous(Pn)) != 0.0 else -np.inf
                           for e in elements.ENGAGING])
        self._engaged = (st.theta0 < angles).astype(float)
        # (t, theta') of the first engagement moving down; released engaged: at once, at rest
        engage = (0.0, 0.0) if self._engaged.any() else None
        if T_f > 0:  # released from rest: it moves only if the driving moment exceeds T_f
            stuck, self._moving = self._rest(st.theta0, p, T_f)
            t = t_max if stuck is not None else t
        while t < t_max - 1e-15:
            h = min(dt, t_max - t)
            steps += 1
            try:
                x1 = self.step(x, p, h)
            except NumericalError as exc:
                raise NumericalError(f"{exc} at t = {t:.4g} s") from None
            if not np.all(np.isfinite(x1)):
                raise NumericalError(f"the reference integrator diverged at t = {t:.4g} s")
            g, g1 = (speed(x) if g_x is None else g_x), speed(x1)
            # an end damper's engagement angle crossed inside (t, t+h] (before the rim: the
            # angle lies above it, else the damper never acts)
            cross = np.flatnonzero((angles > thc) & ((x1[0] < angles) != (self._engaged > 0)))
            if len(cross) and T_f > 0 and x1[1] * self._moving < 0:
                # a rest in the same step: the event that comes first is taken
                tr = self._newton_time(x, p, h, lambda y: y[1] * self._moving, x_hi=x1)
                te = min(self._cross_time(x, p, h, angles[j], self._engaged[j] > 0, x1)
                         for j in cross)
                if tr < te:
                    cross = cross[:0]
            if len(cross):
                taus = [self._cross_time(x, p, h, angles[j], self._engaged[j] > 0, x1)
                        for j in cross]
                j, tau = cross[int(np.argmin(taus))], min(taus)
                xe = self.flow(x, p, tau)
                ge = speed(xe)
                if prev is not None and g >= prev[2] and g > 0:
                    tp, xp, _ = prev
                    if dspeed(xp) > 0 > dspeed(xe):
                        peak = max(peak, self._peak_speed(xp, p, t + tau - tp, xe))
                elif dspeed(x) > 0 > dspeed(xe):
                    peak = max(peak, self._peak_speed(x, p, tau, xe))
                peak = max(peak, g, ge)
                th_min, th_max = min(th_min, float(xe[0])), max(th_max, float(xe[0]))
                down = self._engaged[j] == 0
                if down and engage is None:
                    engage = (t + tau, float(xe[1]))
                self._engaged = self._engaged.copy()
                self._engaged[j] = 1.0 if down else 0.0
                # the flow changes here: nothing carries across (chunks; a maximum of the
                # tip speed is looked for from this node on, as from a node before it)
                t, x, g_x, self._ahead = t + tau, np.array(xe, float), ge, []
                prev = (t, x, -math.inf)
                continue
            if T_f > 0 and x1[1] * self._moving < 0:  # came to rest inside (t, t+h]
                tau = self._newton_time(x, p, h, lambda y: y[1] * self._moving, x_hi=x1)
                xe = self.flow(x, p, tau)
                if xe[0] > thc:  # (a closing event first is the branch below)
                    if prev is not None and g >= prev[2] and g > 0:
                        tp, xp, _ = prev
                        if dspeed(xp) > 0 > dspeed(xe):
                            peak = max(peak, self._peak_speed(xp, p, t + tau - tp, xe))
                    peak = max(peak, g)
                    th_min, th_max = min(th_min, float(xe[0])), max(th_max, float(xe[0]))
                    t, x, prev, g_x = t + tau, np.array([xe[0], 0.0]), None, None
                    stuck, moving = self._rest(float(xe[0]), p, T_f)
                    if stuck is not None:
                        break
                    self._moving = moving
                    continue
            if x1[0] <= thc:  # closing event inside (t, t+h]
                tau = self._angle_time(x, p, h, thc, x1)
                xe = self.flow(x, p, tau)
                ge = speed(xe)
                peak = max(peak, g, ge)
                if dspeed(x) > 0 and dspeed(xe) < 0:
                    peak = max(peak, self._peak_speed(x, p, tau, xe))
                elif prev is not None and g >= prev[2] and g > ge:
                    tp, xp, _ = prev
                    if dspeed(xp) > 0 > dspeed(xe):
                        peak = max(peak, self._peak_speed(xp, p, t + tau - tp, xe))
                t += tau
                closed, th_min = True, thc
                out = {"closing_time": t, "impact_theta_dot": float(xe[1]),
                       "impact_tip_speed": ge}
                break
            if prev is not None and g >= prev[2] and g > g1:
                tp, xp, _ = prev
                if dspeed(xp) > 0 > dspeed(x1):
                    peak = max(peak, self._peak_speed(xp, p, t + h - tp, x1))
            if (x[1] < 0 <= x1[1]) or (x[1] > 0 >= x1[1]):
                turns += 1
                if turns > MAX_TURNS and turns * RINGING_STEPS > steps:
                    raise NumericalError(
                        f"the lid rings: it turned back {turns} times by t = {t:.4g} s (a stiff "
                        f"spring against a light, little-damped lid); the "
                        f"reference does not follow every turn: soften the spring or damp it")
            if x[1] < 0 <= x1[1]:  # turned back: the lowest angle in this interval
                tm = self._newton_time(x, p, h, lambda y: y[1], x_hi=x1)
                th_min = min(th_min, float(self.flow(x, p, tm)[0]))
            if x[1] > 0 >= x1[1]:  # turned down: the highest angle in this interval
                tm = self._newton_time(x, p, h, lambda y: -y[1], x_hi=x1)
                th_max = max(th_max, float(self.flow(x, p, tm)[0]))
            th_min = min(th_min, float(x1[0]))
            th_max = max(th_max, float(x1[0]))
            peak = max(peak, g1)
            prev = (t, x, g)
            t, x, g_x = t + h, x1, g1
        self._moving = -1.0
        self._engaged = np.zeros(len(elements.ENGAGING))
        eng = {} if engage is None else {"engage_time": engage[0],
                                         "engage_theta_dot": engage[1]}
        lmin, lmax = self._l_extremes(th_min, th_max)
        invalid = self._invalid(p, mounting, lmin, lmax, th_min, th_max, opening, **eng)
        if invalid is not None:
            return invalid
        why = None if stuck is None else f"held by friction at theta = {math.degrees(stuck):.1f} deg"
        return StrokeResult(
            opening_force=self._opening(p, opening), reason=why,
            stop_theta=stuck,
            closed=closed, closing_time=out.get("closing_time"),
            impact_theta_dot=out.get("impact_theta_dot"),
            impact_tip_speed=out.get("impact_tip_speed"), peak_tip_speed=float(peak),
            min_spring_length=float(lmin), max_spring_length=float(lmax),
            holding_moment=m.holding_moment(p),
            status=StrokeStatus.CLOSED if closed else StrokeStatus.NOT_CLOSED,
            method="cvodes", tolerance=self.tol, theta_min=float(th_min),
            theta_max=float(th_max), **eng)

    def _invalid(self, p, mounting, lmin, lmax, th_min, th_max, opening: bool = True,
                 **eng) -> StrokeResult | None:
        """The result of a stroke over [th_min, th_max] whose spring lengths lmin..lmax leave
        an element's valid range (with ``mounting``'s limits): an invalid design (with the
        engagement ``eng`` of its end damper, if any); None if the stroke is valid."""
        m = self.model
        _, why = statics.out_of_range(
            lambda e, t: np.asarray(m.coordinate_fns[e.name].map(t.size)(t.ravel())[0]).ravel(),
            mounting, p[None, :],
            {"min_spring_length": [lmin], "max_spring_length": [lmax],
             "theta_min": [th_min], "theta_max": [th_max]})
        if not why[0]:
            return None
        return StrokeResult(
            closed=False, closing_time=None, impact_theta_dot=None, impact_tip_speed=None,
            peak_tip_speed=None, min_spring_length=float(lmin), max_spring_length=float(lmax),
            holding_moment=m.holding_moment(p), status=StrokeStatus.OUT_OF_RANGE,
            method="cvodes", tolerance=self.tol,
            opening_force=self._opening(p, opening),
            message=f"invalid design: {why[0]}", reason=why[0], theta_min=float(th_min),
            theta_max=float(th_max), **eng)

    def _invalid_throughout(self, p, mounting, a, b, opening: bool = True
                            ) -> StrokeResult | None:
        """:meth:`_invalid` for a spring whose every length over theta in [a, b] lies outside
        its valid range (the lid cannot be anywhere there with a valid spring); else None."""
        lmin, lmax = self._l_extremes(a, b)
        P = elements.params(p[None, :])
        lo, hi = (float(np.asarray(v, float).ravel()[0]) for v in
                  elements.BY_NAME["spring"].valid(P, mounting))
        if not (lmin > hi or lmax < lo):
            return None
        return self._invalid(p, mounting, lmin, lmax, a, b, opening)

    def _opening(self, p, opening: bool) -> float | None:
        """The opening effort of the lid at ``p`` (:func:`statics.opening_force_exact`), or
        None when it is not asked for."""
        return statics.opening_force_exact(self.model, p) if opening else None

    def _rest(self, theta, p, T_f):
        """At rest at theta: (theta, None) if dry friction holds the lid there (|dV/dtheta| <=
        T_fr(theta), the friction moment there: ``T_f`` and the strut's F_R |dl/dtheta|), else
        (None, the way -dV/dtheta drives it)."""
        dV = float(self.model.dV(theta, p))
        if abs(dV) <= float(self.model.friction_moment(theta, p)):
            return theta, None
        return None, (1.0 if dV < 0 else -1.0)

    def _l_extremes(self, a, b):
        """min and max of the spring length over theta in [a, b]: the best of an 801-point
        grid, refined on the two cells about it by finer grids of :data:`REFINE_POINTS`
        (each one call) until the cell is ~1e-13 rad."""
        length = self.model.coordinate_fns["spring"]
        if self._length_maps is None:
            self._length_maps = (length.map(801), length.map(REFINE_POINTS))
        coarse, fine = self._length_maps
        grid = np.linspace(a, b, 801)
        lv = np.asarray(coarse(grid)[0]).ravel()
        out = []
        for sgn in (1, -1):
            i = int(np.argmin(sgn * lv))
            best = sgn * lv[i]
            lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, len(grid) - 1)]
            while hi - lo > 1e-13 * max(1.0, abs(hi)):
                th = np.linspace(lo, hi, REFINE_POINTS)
                v = sgn * np.asarray(fine(th)[0]).ravel()
                k = int(np.argmin(v))
                best = min(best, v[k])
                lo, hi = th[max(k - 1, 0)], th[min(k + 1, REFINE_POINTS - 1)]
            out.append(sgn * best)
        return out[0], out[1]

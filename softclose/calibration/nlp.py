"""The least-squares NLP of a fit: multiple shooting on the data's own time grid.

Decision variables (scaled to order one): the fitted keys u (each divided by its first
guess), and per stroke its release angle theta_r, release time t_r, a gyroscope's bias b,
and the state (theta, theta') at every sample surely moving. Constraints: continuity of the
model's fixed-step integrator (``simulate.integrator``) from the release (theta_r, 0) at t_r to the first moving sample and from
sample to sample. Residuals, each divided by the record's noise level: the rest before the
release against theta_r (a gyroscope: against b), the samples just before the first surely
moving one against the model integrated from the release over max(0, t_k - t_r) (zero
before the release; the angle is C1 there), the moving samples against the states; for a
gyroscope one more, the angle at the last moving sample against the rim (the closing lies
within the next frame: mean half a frame of travel, sd 1/sqrt(12) of it).

The integrator is the config's (``simulate.integrator``); its sub-steps start at most
:data:`FIT_STEP` long and are halved until halving them moves no fitted sample by more than
:data:`DEFECT_MAX` of the noise.

Minimise 1/2 |r|^2 with Ipopt and the Gauss-Newton Hessian J^T J (``hess_lag``). Every
number of the data is an NLP parameter, so one NLP serves every record of the same shape
(the 50 noise seeds of the tests, several starts): :func:`get_nlp` caches them.
"""

from __future__ import annotations

import math

import casadi as ca

from ..numerics.integrators import casadi_step, get_method
from ..optimiser.base import NLP, Structure
from ..optimiser.run import Run
from .equation import fit_ode

#: Ipopt options of a fit
IPOPT = {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes", "show_eval_warnings": False,
         "calc_lam_p": False,
         "ipopt.tol": 1e-10, "ipopt.acceptable_tol": 1e-7, "ipopt.max_iter": 200,
         "ipopt.mu_strategy": "adaptive"}

_CACHE: dict = {}


#: longest sub-step a fit starts with (s): the integration error is then checked by halving
#: it (:attr:`FitNLP.defect`) and the sub-steps doubled until it is below
#: :data:`DEFECT_MAX` of the noise; the config's simulate.step is what simulate needs for
#: 1e-7 s metrics, a fit needs its trajectory to a small part of the measurement's noise
FIT_STEP = 0.01
#: largest integration error accepted, in units of the record's noise
DEFECT_MAX = 0.05


def substeps(h: float, step: float = FIT_STEP) -> int:
    return max(1, int(math.ceil(h / step * (1 - 1e-9))))


def _flow(model, cfg, keys, n: int):
    """x1 = F(x0, u, h): ``n`` steps of the config's integrator over h."""
    method = get_method(cfg.simulate.integrator)
    step = casadi_step(method, fit_ode(model, cfg, keys))
    x0, u, h = ca.MX.sym("x0", 2), ca.MX.sym("u", len(keys)), ca.MX.sym("h")
    x = x0
    for _ in range(n):
        x = step(x, u, h / n)
    return ca.Function("flow", [x0, u, h], [x]).expand()


class FitNLP(Structure, NLP):
    """The NLP of one shape: ``shapes`` a tuple per stroke of (kind, rest, window, moving)
    sample counts. Its constraints are one group, the continuity of every stroke
    (lbg = ubg = 0). It is its own structure (built once per shape, no warm starts)."""

    name = "fit"

    #: a re-solve with halved sub-steps starts from the previous answer as Ipopt left it
    clip_start = False

    def __init__(self, model, cfg, keys, shapes, n_move: int, n_release: int):
        self.keys, self.shapes = tuple(keys), tuple(shapes)
        nk = len(keys)
        Fm = _flow(model, cfg, keys, n_move)
        Fr = _flow(model, cfg, keys, n_release)
        Fm2 = _flow(model, cfg, keys, 2 * n_move)      # the step halved: the integration error
        Fr2 = _flow(model, cfg, keys, 2 * n_release)
        defects = []
        u = ca.MX.sym("u", nk)           # scaled keys
        scale = ca.MX.sym("scale", nk)
        uu = u * scale
        w, P, g, r = [u], [scale], [], []
        self.index = []                  # per stroke: slices of its variables and parameters
        nw = nk
        for kind, nr, nwin, nm in self.shapes:
            rate = kind == "rate"
            v = ca.MX.sym("v", 3 if rate else 2)          # theta_r, t_r, (b)
            X = ca.MX.sym("X", 2, nm)
            # parameters: sigma, [rest y], [window y, t], [moving y], h (nm-1), t_first,
            # (rate: terminal scale)
            sig = ca.MX.sym("sig")
            yr, yw, tw = ca.MX.sym("yr", nr), ca.MX.sym("yw", nwin), ca.MX.sym("tw", nwin)
            ym, hm, t1 = ca.MX.sym("ym", nm), ca.MX.sym("hm", nm - 1), ca.MX.sym("t1")
            sc = ca.MX.sym("sc")
            pars = [sig, yr, yw, tw, ym, hm, t1] + ([sc] if rate else [])
            th_r, t_r = v[0], v[1]
            b = v[2] if rate else 0
            xr = ca.vertcat(th_r, 0)
            # continuity
            g.append(X[:, 0] - Fr(xr, uu, t1 - t_r))
            if nm > 1:
                Xn = Fm.map(nm - 1)(X[:, :-1], ca.repmat(uu, 1, nm - 1), hm.T)
                g.append(ca.vec(X[:, 1:] - Xn))
            # the same with the sub-steps halved, in units of the noise
            what = 1 if rate else 0
            d = [X[what, 0] - Fr2(xr, uu, t1 - t_r)[what]]
            if nm > 1:
                Xn2 = Fm2.map(nm - 1)(X[:, :-1], ca.repmat(uu, 1, nm - 1), hm.T)
                d.append((X[what, 1:] - Xn2[what, :]).T)
            defects.append(ca.vertcat(*d) / sig)
            res = []
            if nr:
                res.append(yr - (b if rate else th_r))
            if nwin:
                Xw = Fr.map(nwin)(ca.repmat(xr, 1, nwin), ca.repmat(uu, 1, nwin),
                                  ca.fmax(0, tw - t_r).T)
                res.append(yw - (Xw[1, :].T + b if rate else Xw[0, :].T))
            res.append(ym - (X[1, :].T + b if rate else X[0, :].T))
            r.append(ca.vertcat(*res) / sig)
            if rate:
                r.append(ca.reshape((X[0, -1] - model.stroke.theta_closed - sc / 2)
                                    / (sc / math.sqrt(12.0)), 1, 1))
            w += [v, ca.vec(X)]
            P += pars
            nv = 3 if rate else 2
            self.index.append({"v": slice(nw, nw + nv), "X": slice(nw + nv, nw + nv + 2 * nm),
                               "n_par": sum(p.numel() for p in pars)})
            nw += nv + 2 * nm
        self.w, self.P = ca.vertcat(*w), ca.vertcat(*P)
        self.r, self.g = ca.vertcat(*r), ca.vertcat(*g)
        self.nw, self.nr = self.w.numel(), self.r.numel()
        self.g_sizes, self.n_params = [self.g.numel()], self.P.numel()
        J = ca.jacobian(self.r, self.w)
        lam_f, lam_g = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", self.ng)
        hess = ca.Function("nlp_hess_l", [self.w, self.P, lam_f, lam_g],
                           [lam_f * ca.triu(ca.mtimes(J.T, J))],
                           ["x", "p", "lam_f", "lam_g"], ["hess_gamma_x_x"])
        self.cold_options = {**IPOPT, "hess_lag": hess}
        self.make_solver({"x": self.w, "p": self.P, "f": 0.5 * ca.sumsqr(self.r), "g": self.g})
        self.jac = ca.Function("fit_jac", [self.w, self.P],
                               [self.r, J, ca.jacobian(self.g, self.w)])
        #: the largest change of a fitted sample when the sub-steps are halved (in units of
        #: the record's noise): Richardson's estimate of the integration error
        self.defect = ca.Function("fit_defect", [self.w, self.P],
                                  [ca.mmax(ca.fabs(ca.vertcat(*defects)))])
        self.n_move, self.n_release = n_move, n_release

    def blocks(self) -> list[list[tuple[str, int]]]:
        return [[("continuity", self.ng)]]

    def fit(self, w0, p, lbw, ubw) -> Run:
        """One Ipopt run from ``w0`` within [lbw, ubw], every continuity constraint = 0."""
        return self.solve(w0, p, lbw, ubw, 0, 0)


def get_nlp(model, cfg, keys, shapes, n_move, n_release) -> FitNLP:
    """The fit's NLP of ``cfg``'s ``model`` (cached)."""
    c = cfg     # the keys not fitted are numbers of the NLP's functions
    key = (c.geometry, c.mass, c.design, c.friction, c.stroke, c.simulate.integrator,
           tuple(keys), tuple(shapes), n_move, n_release)
    nlp = _CACHE.get(key)
    if nlp is None:
        nlp = _CACHE[key] = FitNLP(model, cfg, keys, shapes, n_move, n_release)
    return nlp


__all__ = ["FitNLP", "get_nlp", "substeps", "IPOPT", "FIT_STEP", "DEFECT_MAX"]

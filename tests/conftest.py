"""Shared fixtures: the default config and a second geometry, with their model, simulator
and adaptive reference (all session-scoped: a model builds in ~30 ms, a table in ~50 ms).

Names: ``cfg``/``model``/``sim``/``ref`` (default geometry, SPEC §1) and
``cfg2``/``model2``/``sim2``/``ref2`` (a second geometry: other crank lengths, pivot, spring
anchor and lid mass, its assembly angles computed here independently of softclose).

Also a few plain-numpy helpers (``np_closure``, ``assembly_angles``) that the tests use as
an independent check of the CasADi kinematics.
"""

from __future__ import annotations

import atexit
import math
import os
import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest

# the tests run the package as it is installed (pip install ".[test]": the installed files,
# the kernel pip built), not the checkout beside them: `python -m pytest` puts the working
# directory first on sys.path, so it is taken off here, and every process the tests start
# (xdist's workers, `python -m softclose` in the checkout) runs with PYTHONSAFEPATH (no
# working directory on its path). An editable install is the checkout either way.
_ROOT = Path(__file__).resolve().parents[1]
sys.path[:] = [p for p in sys.path if Path(p or os.curdir).resolve() != _ROOT]
os.environ["PYTHONSAFEPATH"] = "1"

# the disk cache of built models and NLPs (softclose.buildcache): a folder of this test run
# (every process it starts inherits it); NLPs are compiled only when asked for -- the tests
# of the cache compile one on purpose (tests/test_startup.py)
_CACHE = tempfile.mkdtemp(prefix="softclose-test-cache-")
atexit.register(shutil.rmtree, _CACHE, True)
os.environ["SOFTCLOSE_CACHE"] = _CACHE

from softclose.config import default_config, from_dict
from softclose.model.lid import LidModel
from softclose.simulation.reference import Reference
from softclose.problem import as_params
from softclose.simulation.simulator import Simulator

#: the second geometry of the test suite (SPEC §6 keys); assembly computed below
GEOMETRY2 = {"crank_oa": 0.05, "crank_bc": 0.09, "pivot_b": [0.065, 0.02],
             "spring_anchor": [-0.05, 0.03]}
MASS2 = {"lid": 0.6}


def _rot(theta, r):
    c, s = math.cos(theta), math.sin(theta)
    return np.array([c * r[0] - s * r[1], s * r[0] + c * r[1]])


def np_closure_all(theta, l2, l3, pivot_b, lid_c, n=3600):
    """Every (phi, gamma) closing the loop at ``theta``, by a scan of phi and bisection.

    Plain numpy, no closed form: |l2 e(phi) + R(theta) AC - B| = l3.
    """
    w = _rot(theta, lid_c) - np.asarray(pivot_b, float)

    def f(phi):
        return (l2 * np.cos(phi) + w[0]) ** 2 + (l2 * np.sin(phi) + w[1]) ** 2 - l3 ** 2
    grid = np.linspace(0.0, 2 * math.pi, n + 1)
    fv = f(grid)
    roots = []
    for i in np.nonzero(np.sign(fv[:-1]) != np.sign(fv[1:]))[0]:
        a, b, fa = grid[i], grid[i + 1], fv[i]
        for _ in range(200):
            mid = 0.5 * (a + b)
            fm = f(mid)
            if (fm > 0) == (fa > 0):
                a, fa = mid, fm
            else:
                b = mid
            if b - a < 1e-15:
                break
        phi = 0.5 * (a + b)
        c_minus_b = l2 * np.array([math.cos(phi), math.sin(phi)]) + w
        roots.append((phi, math.atan2(c_minus_b[1], c_minus_b[0])))
    return roots


def np_closure(theta, geo, near_phi):
    """(phi, gamma) of the assembly whose phi is nearest ``near_phi`` (rad)."""
    roots = np_closure_all(theta, geo.crank_oa, geo.crank_bc, geo.pivot_b, geo.lid_c)
    assert roots, f"the loop does not close at theta = {math.degrees(theta)} deg"

    def dist(r):
        return abs((r[0] - near_phi + math.pi) % (2 * math.pi) - math.pi)
    return min(roots, key=dist)


def assembly_angles(geometry: dict, theta_deg: float, near_phi_deg: float) -> list[float]:
    """[theta, phi, gamma] in degrees (0..360) of the assembly with phi nearest near_phi_deg."""
    geo = from_dict({"geometry": geometry}).geometry if "assembly" in geometry else \
        from_dict({"geometry": {**geometry, "assembly": [theta_deg, 0.0, 0.0]}}).geometry
    phi, gamma = np_closure(math.radians(theta_deg), geo, math.radians(near_phi_deg))
    return [theta_deg, math.degrees(phi) % 360.0, math.degrees(gamma) % 360.0]


def assert_potential(cfg, model, V, angles):
    """At each of ``angles``: the model's dV/dtheta and the kernel table's slope against the
    central difference of an independent potential ``V(theta)``, the table's potential
    energy against V; the model's parameter vector."""
    from softclose.simulation import statics
    sim = Simulator.from_config(cfg, model=model)
    p = model.params()
    h = 1e-5
    for th in angles:
        fd = (V(th + h) - V(th - h)) / (2 * h)
        assert float(model.dV(th, p)) == pytest.approx(fd, rel=1e-7, abs=1e-9)
        assert float(statics.slopes(sim.table, th, p[None, :])[0]) == pytest.approx(
            fd, rel=1e-7, abs=1e-9)
        assert float(statics.potential_energy(sim.table, th, p[None, :])[0]) == pytest.approx(
            V(th), rel=1e-9, abs=1e-9)
    return p


def uniform_states(model, n: int, seed: int, theta_dot=(-6, 3)) -> list:
    """``n`` states (theta, theta') drawn uniformly: theta 0.02 rad inside the model's range,
    theta' in ``theta_dot``."""
    rng = np.random.default_rng(seed)
    lo, hi = model.theta_range
    return [(rng.uniform(lo + 0.02, hi - 0.02), rng.uniform(*theta_dot)) for _ in range(n)]


def assert_formulations_agree(model, absolute, p, states) -> float:
    """theta'' of the reduced model, of its Newton-Euler equations (row 8) and of the lid in
    absolute coordinates (``absolute``: :func:`read_parameters` of the config) agree to 1e-10
    at each of ``states``; the last one's reduced theta''."""
    from softclose.validation.textbook.lid_absolute import compute_theta_ddot
    for th, thd in states:
        red = model.theta_ddot(th, thd, p)
        ne = float(np.asarray(model.newton_euler(th, thd, p)).ravel()[8])
        ab = compute_theta_ddot(absolute, th, thd)
        assert ne == pytest.approx(red, rel=1e-10, abs=1e-10)
        assert ab == pytest.approx(red, rel=1e-10, abs=1e-10)
    return red


def energy_rate(model):
    """A CasADi Function of ([theta, theta'], p): (dE/dt along the model's equation of motion,
    by automatic differentiation; the dampers' power)."""
    import casadi as ca
    from softclose.problem import PARAM_KEYS
    x, ps = ca.SX.sym("x", 2), ca.SX.sym("p", len(PARAM_KEYS))
    E = model.energy_fn(x, ps)
    return ca.Function("r", [x, ps], [ca.jtimes(E, x, model.ode(x, ps)), model.power_fn(x, ps)])


def run_cli(*argv) -> tuple[int, str]:
    """(exit code, stdout) of ``softclose ARGV`` run in this process."""
    import io
    from contextlib import redirect_stdout

    from softclose.cli import main
    buf = io.StringIO()
    with redirect_stdout(buf):
        code = main(list(argv))
    return code, buf.getvalue()


def write_file(folder, name: str, text: str) -> Path:
    """``folder/name`` holding ``text``."""
    p = Path(folder) / name
    p.write_text(text)
    return p


def wrap_deg(a):
    return (a + 180.0) % 360.0 - 180.0


@pytest.fixture(scope="session")
def cfg():
    return default_config()


def lid_fixtures(suffix: str = ""):
    """The session's model, simulator and reference of the config fixture ``cfg<suffix>``,
    as the fixtures ``model<suffix>``, ``sim<suffix>`` and ``ref<suffix>``."""
    def model(request):
        return LidModel.from_config(request.getfixturevalue("cfg" + suffix))

    def sim(request):
        return Simulator.from_config(request.getfixturevalue("cfg" + suffix),
                                     request.getfixturevalue("model" + suffix))

    def ref(request):
        return Reference(request.getfixturevalue("model" + suffix))
    return tuple(pytest.fixture(scope="session", name=f.__name__ + suffix)(f)
                 for f in (model, sim, ref))


model, sim, ref = lid_fixtures()


@pytest.fixture(scope="session")
def cfg2():
    # the same kind of assembly as the default (A above and left of O, phi ~ 110-120 deg)
    asm = assembly_angles(GEOMETRY2, 18.0, 115.0)
    return from_dict({"geometry": {**GEOMETRY2, "assembly": asm}, "mass": MASS2})


model2, sim2, ref2 = lid_fixtures("2")


@pytest.fixture(scope="session", params=["default", "second"])
def geometry_case(request, cfg, model, cfg2, model2):
    """(cfg, model) of each geometry: the foundation checks run on both."""
    return (cfg, model) if request.param == "default" else (cfg2, model2)


# -- plain-numpy body kinematics by finite differences of model.kin positions ----------
_KIN_POINTS = {"A": 5, "C": 6, "E": 7, "T": 8, "G1": 9}


def positions(model, theta):
    """Positions of every named point and the crank angles at ``theta`` (from model.kin)."""
    k = model.kin(np.array([theta, 0.0]))
    out = {name: np.asarray(k[i], float).ravel() for name, i in _KIN_POINTS.items()}
    phi, gamma = float(k[0]), float(k[1])
    B = np.asarray(model.geo.pivot_b, float)
    out["G2"] = 0.5 * out["A"]
    out["G3"] = B + 0.5 * model.geo.crank_bc * np.array([math.cos(gamma), math.sin(gamma)])
    out["B"], out["O"] = B, np.zeros(2)
    out["D"] = np.asarray(model.geo.spring_anchor, float)
    out["phi"], out["gamma"], out["theta"] = phi, gamma, theta
    return out


def fd_derivatives(model, theta, h=2e-3):
    """(value, d/dtheta, d2/dtheta2) of every position and angle: 5-point central differences.

    Truncation ~h^4 f^(6)/90 ~ 1e-13, round-off ~ 1e-16 |f| / h^2 ~ 1e-10 (m, rad).
    """
    samples = [positions(model, theta + j * h) for j in (-2, -1, 0, 1, 2)]
    out = {}
    for key in samples[2]:
        v = [np.asarray(s[key], float) for s in samples]
        if key in ("phi", "gamma"):   # unwrap angles across the stencil
            v = list(v[2] + (np.asarray(v) - v[2] + math.pi) % (2 * math.pi) - math.pi)
        d1 = (v[0] - 8 * v[1] + 8 * v[3] - v[4]) / (12 * h)
        d2 = (-v[0] + 16 * v[1] - 30 * v[2] + 16 * v[3] - v[4]) / (12 * h * h)
        out[key] = (v[2], d1, d2)
    return out


def cross2(a, b):
    return a[0] * b[1] - a[1] * b[0]


def body_motion(model, theta, theta_dot, theta_ddot):
    """Positions, velocities and accelerations of the points, and the body rates (numpy)."""
    d = fd_derivatives(model, theta)
    pos = {k: v[0] for k, v in d.items()}
    vel = {k: v[1] * theta_dot for k, v in d.items()}
    acc = {k: v[2] * theta_dot ** 2 + v[1] * theta_ddot for k, v in d.items()}
    return pos, vel, acc


def external_forces(model, pos, vel, theta_dot, p):
    """Spring force at E, dashpot force at C (both on the lid) and the rotary moment (SPEC §2)."""
    k, l0, c, c_rot = p[:4]
    r_ED = pos["D"] - pos["E"]
    l = float(np.hypot(*r_ED))
    F_s = k * (l - l0) * r_ED / l
    e_OC = pos["C"] / float(np.hypot(*pos["C"]))
    F_d = -c * float(e_OC @ vel["C"]) * e_OC
    return F_s, F_d, -c_rot * theta_dot


def body_residuals(model, theta, theta_dot, p, z):
    """Residuals of the nine Newton-Euler equations, written here independently.

    ``z`` = (R_O, R_A, R_B, R_C, theta''). Returns (force residuals (6,), moment residuals (3,),
    force scale, moment scale).
    """
    m = model.mass
    R_O, R_A, R_B, R_C, tdd = z[0:2], z[2:4], z[4:6], z[6:8], z[8]
    pos, vel, acc = body_motion(model, theta, theta_dot, tdd)
    F_s, F_d, M_rot = external_forces(model, pos, vel, theta_dot, p)
    g = m.gravity
    W = lambda mass: np.array([0.0, -mass * g])  # noqa: E731
    G1, G2, G3 = pos["G1"], pos["G2"], pos["G3"]
    alpha1 = tdd
    alpha2, alpha3 = acc["phi"], acc["gamma"]
    f = np.r_[
        R_A + R_C + W(m.lid) + F_s + F_d - m.lid * acc["G1"],
        R_O - R_A + W(m.crank_oa) - m.crank_oa * acc["G2"],
        R_B - R_C + W(m.crank_bc) - m.crank_bc * acc["G3"],
    ]
    mom = np.array([
        cross2(pos["A"] - G1, R_A) + cross2(pos["C"] - G1, R_C) + cross2(pos["E"] - G1, F_s)
        + cross2(pos["C"] - G1, F_d) + M_rot - m.inertia_lid * alpha1,
        cross2(pos["O"] - G2, R_O) + cross2(pos["A"] - G2, -R_A) - m.inertia_oa * alpha2,
        cross2(pos["B"] - G3, R_B) + cross2(pos["C"] - G3, -R_C) - m.inertia_bc * alpha3,
    ])
    fscale = max(np.abs(z[:8]).max(), m.lid * g, np.abs(F_s).max(), np.abs(F_d).max(),
                 m.lid * np.abs(acc["G1"]).max())
    return f, mom, fscale, fscale * model.geo.lid_length


def np_energy(model, theta, theta_dot, p):
    """Kinetic + gravity + spring potential from the bodies (numpy, finite differences)."""
    m = model.mass
    pos, vel, _ = body_motion(model, theta, theta_dot, 0.0)
    T = 0.5 * (m.lid * vel["G1"] @ vel["G1"] + m.inertia_lid * theta_dot ** 2
               + m.crank_oa * vel["G2"] @ vel["G2"] + m.inertia_oa * vel["phi"] ** 2
               + m.crank_bc * vel["G3"] @ vel["G3"] + m.inertia_bc * vel["gamma"] ** 2)
    V = m.gravity * (m.lid * pos["G1"][1] + m.crank_oa * pos["G2"][1]
                     + m.crank_bc * pos["G3"][1])
    l = float(np.hypot(*(pos["D"] - pos["E"])))
    return float(T + V + 0.5 * p[0] * (l - p[1]) ** 2)


def random_states(model, n, seed, thd_max=6.0):
    """Random (theta, theta', p) over the model's range, spring + dashpot + rotary damper on."""
    rng = np.random.default_rng(seed)
    lo, hi = model.theta_range
    out = []
    for _ in range(n):
        th = rng.uniform(lo + 0.01, hi - 0.01)
        thd = rng.uniform(-thd_max, thd_max)
        p = as_params([rng.uniform(100, 5000), rng.uniform(0.02, 0.12),
                       rng.uniform(10, 3000), rng.uniform(0.001, 0.05)])
        out.append((th, thd, p))
    return out


# -- expensive results shared by several test files (one per test process) -----------------
@pytest.fixture(scope="session")
def default_optimum():
    """``softclose.optimise(default_config())``: the verified optimum of the default problem
    (an immutable result: tests read it, none changes it)."""
    import softclose
    return softclose.optimise(default_config())


@pytest.fixture(scope="session")
def default_robust():
    """``softclose.optimise(default_config(), robust=True)``: the robust design of the
    default problem (immutable)."""
    import softclose
    return softclose.optimise(default_config(), robust=True)

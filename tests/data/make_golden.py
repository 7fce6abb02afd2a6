"""Writes tests/data/golden.npz: the outputs of a fixed set of designs, to hold every later
restructuring to "every number unchanged" (tests/test_golden.py).

Run once at commit b33652c (before the element registry), with
``python tests/data/make_golden.py``; the file it wrote is committed. Running it again on a
later commit rewrites the file from that commit's code: do that only on purpose.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

import softclose
from softclose.simulation.kernel import binding
from softclose.config import default_config, from_dict
from softclose.model.lid import LidModel
from softclose.optimiser.interval import ChebyshevFit, nlp_elements
from softclose.simulation.reference import Reference
from softclose.simulation.simulator import Simulator

OUT = Path(__file__).with_name("golden.npz")
#: the kernel's output columns the file holds (those of b33652c: the columns added since, the
#: end damper's engagement, are NaN on these rows, which have none)
GOLDEN_FIELDS = tuple(k for k in binding.OUT_FIELDS if k not in ("engage_time",
                                                                 "engage_theta_dot"))
#: a second geometry (the test suite's cfg2, its assembly angles as computed there)
GEOMETRY2 = {"crank_oa": 0.05, "crank_bc": 0.09, "pivot_b": [0.065, 0.02],
             "spring_anchor": [-0.05, 0.03]}


def designs(n: int, seed: int) -> np.ndarray:
    """Random rows (k, l0, c, c_rot) over and a little beyond the design box, as parameter
    vectors (the elements added since the seed at zero)."""
    rng = np.random.default_rng(seed)
    P = np.column_stack([rng.uniform(0, 12000, n), rng.uniform(0.02, 0.12, n),
                         rng.uniform(0, 6000, n), rng.uniform(0, 1.0, n)])
    P[: n // 8, 2:] = 0.0          # undamped rows (run to t_max, no early exit)
    P[n // 8: n // 4, 0] = 0.0     # no spring
    try:
        from softclose.problem import PARAM_KEYS
    except ImportError:
        return P
    return np.c_[P, np.zeros((n, len(PARAM_KEYS) - 4))]


def compute() -> dict[str, np.ndarray]:
    """Every array of the golden file, computed by the code at hand."""
    out: dict[str, np.ndarray] = {}
    cfg = default_config()
    geo2 = dict(GEOMETRY2)
    probe = LidModel.from_config(from_dict({"geometry": {**geo2, "assembly": [18.0, 108.0, 150.0]}}))
    phi, gamma = probe.closure(np.radians(18.0))
    geo2["assembly"] = [18.0, float(np.degrees(phi)) % 360, float(np.degrees(gamma)) % 360]
    cfg2 = from_dict({"geometry": geo2, "mass": {"lid": 0.6}})
    out["assembly2"] = np.array(geo2["assembly"])
    for tag, c in (("g1", cfg), ("g2", cfg2)):
        sim = Simulator.from_config(c)
        out[f"{tag}_table_cc"] = sim.table.cc
        P = designs(400, 7 if tag == "g1" else 8)
        out[f"{tag}_P"] = P[:, :4]
        for method in ("rk4", "euler_cromer", "gauss4", "radau5"):
            s = Simulator.from_config(c, model=sim.model, integrator=method)
            r = s.run_batch(P)
            out[f"{tag}_{method}"] = np.column_stack([r[k] for k in GOLDEN_FIELDS])
        masses = np.random.default_rng(3).uniform(0.3, 0.8, len(P))
        r = sim.run_batch(P, lid_mass=masses)
        out[f"{tag}_rk4_masses"] = np.column_stack([r[k] for k in GOLDEN_FIELDS])
        out[f"{tag}_masses"] = masses
        out[f"{tag}_holding"] = sim.holding_moments(P)
        out[f"{tag}_holding_masses"] = sim.holding_moments(P, masses)
        # single strokes with error estimates and a trajectory
        rows = []
        for p in P[:12]:
            res = sim.run(p, trajectory=True)
            acc = res.accuracy or {}
            rows.append([np.nan if v is None else v for v in
                         (res.closing_time, res.impact_theta_dot, res.impact_tip_speed,
                          res.peak_tip_speed, res.min_spring_length, res.max_spring_length,
                          res.holding_moment, acc.get("closing_time"),
                          acc.get("peak_tip_speed"))])
            if res.trajectory is not None and f"{tag}_traj" not in out:
                tr = res.trajectory
                out[f"{tag}_traj"] = np.column_stack([tr[k] for k in sorted(tr)])
        out[f"{tag}_single"] = np.array(rows, float)
        # the adaptive reference and Newton-Euler
        ref = Reference(sim.model)
        refs = []
        for p in P[[1, 40, 60, 100, 150, 300]]:
            rr = ref.simulate(p)
            refs.append([np.nan if v is None else v for v in
                         (rr.closing_time, rr.impact_theta_dot, rr.impact_tip_speed,
                          rr.peak_tip_speed, rr.min_spring_length, rr.max_spring_length,
                          rr.holding_moment, rr.theta_min, rr.theta_max)])
        out[f"{tag}_reference"] = np.array(refs, float)
        states = []
        rng = np.random.default_rng(11)
        for p in P[:8]:
            th, thd = rng.uniform(-0.05, 0.35), rng.uniform(-5, 2)
            s = sim.model.state(th, thd, p)
            states.append([s["theta_ddot"], s["phi"], s["gamma"], s["phi_dot"],
                           s["gamma_dot"], *s["tip_velocity"],
                           *[v for k in "OABC" for v in s["reactions"][k]]])
        out[f"{tag}_states"] = np.array(states)
        fit = ChebyshevFit(sim.model, els=nlp_elements(c))
        if hasattr(fit, "names"):   # named series (since the element registry): the rows
            # of the layout of b33652c, g_grav, g_kl, g_kl0 = +dl/M, g_c, g_dM, g_rot, tau, dtau
            row = {n: fit.coef[i] for i, n in enumerate(fit.names)}
            out[f"{tag}_chebyshev"] = np.array([
                row["gravity:a"], row["spring:b"], -row["spring:a"], row["dashpot:B"],
                row["inertia"], row["rotary:B"], row["tau"], row["dtau"]])
        else:
            out[f"{tag}_chebyshev"] = fit.coef
    # the optimiser and the robust optimiser on the defaults (the idealised spring: since
    # the spring kinds, listing "linear" poses the problem of b33652c)
    if "spring_kinds" in softclose.config.SCHEMA["optimise"]:
        cfg = cfg.set("optimise.spring_kinds", ["linear"])
    res = softclose.optimise(cfg)
    out["optimise"] = np.r_[[res.design[k] for k in ("spring_k", "spring_rest_length",
                                                      "damper_c")], res.objective]
    rob = softclose.optimise(cfg, robust=True)
    out["robust"] = np.r_[[rob.design[k] for k in ("spring_k", "spring_rest_length",
                                                    "damper_c")], rob.objective, rob.yield_]
    return out


def main() -> None:
    out = compute()
    np.savez_compressed(OUT, **out)
    print(f"wrote {OUT} ({OUT.stat().st_size} bytes, {len(out)} arrays)")


if __name__ == "__main__":
    main()

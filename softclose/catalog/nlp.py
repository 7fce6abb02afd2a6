"""The dashpot's c of one catalog spring re-solved by the robust NLP (no damper catalog).

The spring is fixed (its rate and free length bounded to themselves, its kind and preload,
its length limits), its own tolerances replace ``[tolerance]``'s spring spreads (the rate's,
the free length's as an absolute spread), the dashpot carries ``[tolerance]``'s spread of
``design.damper_c``; :func:`softclose.robust.optimise_robust` then chooses c within
``optimise.damper_c`` for the worst scenario of that box. The NLP's own verification is left
to the caller, which re-screens the pair with that c in the kernel and checks every corner
with the reference; nor is the rest of the robust design's report made
(``report=False``: the design, worst-case objective and verdict are the same).

The NLP is the robust scenario NLP (:class:`softclose.robust.nlp.ScenarioStructure`), keyed
by its structure alone -- the scenarios (1 + 2^d of the box's d axes), the discretisation, the
elements, the solver -- and never by a part's numbers: the spring's rate and free length are
held (the design's bounds lo = hi: NLP parameters, :func:`softclose.problem.held_design`),
its preload and kind NLP parameters, its tolerances the scenario maps (parameters too). So one NLP serves every coil spring of a catalog (and one every gas strut: its
own structure, F1 a variable bounded to the part's), built once (in
CasADi's virtual machine) or loaded compiled (``softclose prepare --select FILE``).
"""

from __future__ import annotations

from ..config import Config
from ..errors import SoftcloseError
from .screen import without_limits
from ..robust import optimise_robust


def spring_config(cfg: Config, spring, damper) -> Config:
    """``cfg`` with the spring fixed as the design and its tolerances as the box's. A gas
    strut: its F1 fixed too (``optimise.free`` design.spring_preload = [F1, F1], the other
    free keys kept), its stroke, progression and friction the part's, its force tolerance
    the spread of ``design.spring_preload`` (a strut's rate is 0 and carries none)."""
    values = {"design.spring_kind": spring.spring_kind, "design.spring_k": spring.rate,
              "design.spring_rest_length": spring.free_length,
              "design.spring_preload": spring.preload, "design.damper_c": damper.c,
              "design.rotary_damper_c": 0.0,
              "optimise.spring_k": [spring.rate, spring.rate],
              "optimise.spring_rest_length": [spring.free_length, spring.free_length],
              "optimise.spring_kinds": [spring.spring_kind],
              "tolerance.design.spring_k": spring.rate_tolerance,
              "tolerance.design.spring_rest_length": {"absolute":
                                                      spring.free_length_tolerance},
              "tolerance.design.damper_c": damper.c_tolerance}
    if spring.is_strut:
        free = {k: [a, b] for k, a, b in cfg.optimise.free or ()}
        free["design.spring_preload"] = [spring.preload, spring.preload]
        values.update({"design.spring_k": 0.0, "optimise.spring_k": [0.0, 0.0],
                       "design.strut_stroke": spring.stroke,
                       "design.strut_progression": spring.progression,
                       "design.strut_friction": spring.friction,
                       "optimise.free": free,
                       "tolerance.design.spring_k": 0.0,
                       "tolerance.design.spring_preload": spring.force_tolerance})
    elif spring.min_length is not None:
        values["design.spring_min_length"] = spring.min_length
    if spring.max_length is not None:
        values["design.spring_max_length"] = spring.max_length
    beta = getattr(damper, "temperature_coeff", None)
    if beta is not None:
        values["design.damper_temperature_coeff"] = beta
    return without_limits(cfg).update(values)


#: Monte Carlo samples of the NLP's own yield estimate (the pair is screened again anyway)
NLP_SAMPLES = 1000


def solve_c(cfg: Config, spring, damper) -> dict:
    """The robust NLP's c for ``spring`` (``damper``: the dashpot chosen so far, its c the
    start): {c (None when it found none), success, objective (worst scenario), message}."""
    try:
        c = spring_config(cfg, spring, damper)
        r = optimise_robust(c, samples=NLP_SAMPLES, verify=False, report=False)
    except SoftcloseError as exc:
        return {"c": None, "success": False, "objective": None,
                "message": str(exc).splitlines()[0]}
    d = r.design or {}
    return {"c": None if "damper_c" not in d else float(d["damper_c"]),
            "success": bool(r.design is not None), "objective": r.objective,
            "message": (r.message or "").splitlines()[0] if r.message else ""}

"""The coil spring made to order (``softclose spring --out``): its force and its stress over
its length, from the free length down to the solid length, with the working range and the
limits of EN 13906-1."""

from __future__ import annotations

import numpy as np

from ...coil_spring.standard import shear_stress
from . import plt


def spring_curves(check, n: int = 200) -> dict:
    """Force F = R (L0 - L), shear stress tau = 8 D F / (pi d^3) and its corrected value
    tau_k = k tau of the spring of ``check`` (a :class:`softclose.coil_spring.SpringCheck`)
    over its length L from the free length L0 to the solid length L_c (SI units). An
    extension spring: F = F0 + R (L - L0) from L0 to 1.25 times its longest working
    extension."""
    s, d = check.spring, check.duty
    if check.kind == "extension":
        L = np.linspace(d.free_length, d.free_length + 1.25 * (d.longest_length
                                                               - d.free_length), n)
        F = d.initial_tension + check.rate * (L - d.free_length)
        tau = shear_stress(F, s.wire_d, s.coil_d)
        return {"length": L, "force": F, "stress": tau,
                "stress_corrected": s.stress_correction * tau}
    L = np.linspace(d.free_length, s.solid_length, n)
    F = check.rate * (d.free_length - L)
    tau = shear_stress(F, s.wire_d, s.coil_d)
    return {"length": L, "force": F, "stress": tau, "stress_corrected": s.stress_correction * tau}


def plot_spring(check):
    """Two panels against the spring's length (mm, the free length on the left): the force,
    and the stresses: tau, which at the solid length must stay below 0.56 R_m (static), and
    the corrected tau_k, whose upper value over the stroke must stay below the Goodman
    line's at ``cycles`` (fatigue). The working range L1..L2 is shaded; the buckling length,
    where there is one, is marked."""
    if check.kind == "extension":
        return _plot_extension(check)
    c, fig, (af, at) = _force_and_stress_axes(check)
    s, d, st = check.spring, check.duty, check.stresses
    mm = 1e3 * c["length"]
    for ax in (af, at):
        ax.axvline(1e3 * s.min_working_length, color="0.4", ls=":", lw=1,
                   label="shortest allowed length L_n")
        ax.set_xlabel("spring length (mm)")
        ax.set_xlim(mm[0], mm[-1])
    af.plot(mm, c["force"], color="tab:blue")
    af.set_ylabel("force (N)")
    s_k = check.buckling.get("s_k")
    if s_k is not None and s_k < d.free_length - s.solid_length:
        af.axvline(1e3 * (d.free_length - s_k), color="tab:red", ls="--", lw=1,
                   label="buckles below (unguided)")
    af.legend(fontsize=7, loc="upper left")
    af.set_title(f"{s.material}: d = {1e3 * s.wire_d:g} mm, D = {1e3 * s.coil_d:g} mm, "
                 f"n = {s.active_coils:g}", fontsize=9)
    at.plot(mm[-1], 1e-6 * c["stress"][-1], "o", color="tab:red")
    _stresses(at, check, mm, c, st["tau_c_allowed"],
              "0.56 R_m: tau at the solid length below it", "fatigue check")
    return fig


def _stresses(at, check, mm, c, allowed: float, limit: str, fatigue: str) -> None:
    """The stress panel ``at``: tau of the static check and its limit ``allowed`` (Pa,
    labelled ``limit``), the corrected tau_k of the ``fatigue`` check, the fatigue line and
    the verdict (:func:`_fatigue_and_verdict`)."""
    at.plot(mm, 1e-6 * c["stress"], color="tab:red", label="tau (static check)")
    at.axhline(1e-6 * allowed, color="tab:red", ls="--", lw=1, label=limit)
    at.plot(mm, 1e-6 * c["stress_corrected"], color="tab:purple",
            label=f"tau_k, corrected ({fatigue})")
    _fatigue_and_verdict(at, check)


def _force_and_stress_axes(check):
    """The curves of ``check``'s spring and a figure of its force (left) and stresses (right)
    over its length, the working range L1..L2 shaded on both."""
    c = spring_curves(check)
    d = check.duty
    fig, axes = plt.subplots(1, 2, figsize=(11.0, 3.6), layout="constrained")
    for ax in axes:
        ax.axvspan(1e3 * d.shortest_length, 1e3 * d.longest_length, color="tab:green",
                   alpha=0.15, label="working range L1..L2")
    return c, fig, axes


def _fatigue_and_verdict(at, check) -> None:
    """On the stress axes ``at``: the corrected tau_k's largest value over the stroke for the
    duty's cycles (the fatigue check's line), the legend, and the verdict as the title."""
    st, d = check.stresses, check.duty
    upper = st["tau_k1"] + st["tau_kh_allowed"]
    at.hlines(1e-6 * upper, 1e3 * d.shortest_length, 1e3 * d.longest_length,
              color="tab:purple", ls="-.", lw=1.5,
              label=f"largest tau_k over the stroke for {d.cycles:.3g} cycles")
    at.set_ylabel("shear stress (MPa)")
    at.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    at.set_title("ok: every check met" if check.ok else
                 "fails: " + ", ".join(check.failed), fontsize=9)


def _plot_extension(check):
    """An extension spring's force and stresses over its length (the free length on the
    left): tau at the longest working length below 0.45 R_m (static), the corrected tau_k's
    upper value over the stroke below the Goodman line's (the body's fatigue)."""
    c, fig, (af, at) = _force_and_stress_axes(check)
    s, d, st = check.spring, check.duty, check.stresses
    mm = 1e3 * c["length"]
    for ax in (af, at):
        ax.set_xlabel("spring length (mm)")
        ax.set_xlim(mm[0], mm[-1])
    af.plot(mm, c["force"], color="tab:blue")
    af.axhline(d.initial_tension, color="0.4", ls=":", lw=1, label="initial tension F0")
    af.set_ylabel("force (N)")
    af.legend(fontsize=7, loc="upper left")
    af.set_title(f"extension spring, {s.material}: d = {1e3 * s.wire_d:g} mm, "
                 f"D = {1e3 * s.coil_d:g} mm, n = {s.active_coils:g} (hooks not covered)",
                 fontsize=9)
    _stresses(at, check, mm, c, st["tau_2_allowed"],
              "0.45 R_m: tau at the longest working length below it", "the body's fatigue")
    return fig


__all__ = ["plot_spring", "spring_curves"]

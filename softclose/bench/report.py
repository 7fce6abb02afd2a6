"""The text, Markdown tables and files of a benchmark run (:class:`BenchResult`): what
``softclose bench`` prints and what ``--out DIR`` holds -- ``work_precision.csv``,
``speed.csv``, ``optimiser.csv``, ``bench.md``, ``bench.json``, ``speed.json`` (the speed rows
alone), with ``--structures`` ``structures.csv`` and ``structures.json``, with ``--peers``
``peers.csv`` and ``peers.json``, and the figures
``work_precision``, ``error_vs_step`` and ``optimiser``."""

from __future__ import annotations

import csv
import math
from pathlib import Path

from ..files import replacing, write_text
from ..present.display import num


# -- text ----------------------------------------------------------------------------------
def _ms(step: float) -> str:
    return f"{step * 1e3:g} ms"


def default_text(default: dict) -> str:
    """What the run says about the configured default step, and the cheapest setting on
    its designs, as separate lines."""
    m, h = default["method"], default["step"]
    designs = ", ".join(default["designs"])
    head = f"default: {m} at {_ms(h)} (configured: simulate.integrator, simulate.step)"
    if default["meets_targets"]:
        head += f"; meets the accuracy targets on {designs}"
    else:
        head += (f"; misses the accuracy targets on "
                 f"{', '.join(default['failing_designs']) or 'designs it could not run'}")
    lines = [head]
    c = default["cheapest"]
    if default["confirmed"]:
        lines.append("  confirmed: it is the cheapest setting meeting the targets on every "
                     "design of this run")
    elif default["omitted_designs"]:
        lines.append(f"  the quick set omits {', '.join(default['omitted_designs'])}, so its "
                     f"designs cannot confirm the choice; the full bench (without --quick) "
                     f"is what confirms {_ms(h)}")
    if c["method"] is None:
        lines.append("cheapest meeting the targets on these designs: none of the settings "
                     "tried")
    elif (c["method"], c["step"]) != (m, h):
        lines.append(f"cheapest meeting the targets on these designs: {c['method']} at "
                     f"{_ms(c['step'])} ({c['mean_time_per_stroke'] * 1e6:.1f} µs per stroke, "
                     "mean over the designs)")
    return "\n".join(lines)


def work_precision_markdown(wp) -> str:
    """The work-precision table (one block per design) and the fitted orders, as Markdown."""
    from .precision import METRICS, TRUTH_TOL
    from ..numerics.integrators import METHODS
    d = wp.default
    c = d["cheapest"]
    out = []
    for dname, t in wp.truths.items():
        out.append(f"**{dname}** — truth (CVODES, tol {TRUTH_TOL:g}): closing_time "
                   f"{num(t.closing_time, spec='.10g')} s, impact_theta_dot "
                   f"{num(t.impact_theta_dot, spec='.10g')} rad/s, peak_tip_speed "
                   f"{num(t.peak_tip_speed, spec='.10g')} m/s; truth uncertainty (tol "
                   f"{10 * TRUTH_TOL:g} against it): "
                   + ", ".join(f"{k} {num(v, spec='.0e')}" for k, v in wp.truth_floor[dname].items()))
        out.append("")
        out.append("| method | step / tol | status | µs per stroke | Δ closing_time (s) | "
                   "Δ impact_theta_dot (rad/s) | rel Δ impact_tip_speed | rel Δ peak_tip_speed "
                   "| meets targets |")
        out.append("|---|---|---|---:|---:|---:|---:|---:|:-:|")
        for r in wp.rows:
            if r["design"] != dname:
                continue
            name = r["method"] + (" (seed)" if r["seed"] else "")
            if (r["method"], r["step"]) == (d["method"], d["step"]):
                name += " **(default)**"
            elif (r["method"], r["step"]) == (c["method"], c["step"]):
                name += " (cheapest here)"
            out.append(f"| {name} | {r['step']:g} | {r['status']} | "
                       f"{r['time_per_stroke'] * 1e6:.1f} | "
                       + " | ".join(num(r[f'err_{k}'], spec='.2e') for k in METRICS)
                       + f" | {'yes' if r['meets_targets'] else 'no'} |")
        out.append("")
    out.append("Fitted order (slope of log error against log step, asymptotic points):")
    out.append("")
    out.append("| design | method | " + " | ".join(METRICS) + " | slope against run time "
               "(impact_theta_dot) |")
    out.append("|---|---|" + "---:|" * (len(METRICS) + 1))
    for dname in wp.truths:
        for m in METHODS:
            if (dname, m, METRICS[0]) not in wp.orders:
                continue
            out.append(f"| {dname} | {m} | "
                       + " | ".join(num(wp.orders[(dname, m, k)], spec='.2f') for k in METRICS)
                       + f" | {num(wp.slopes[(dname, m, 'impact_theta_dot')], spec='.2f')} |")
    out += ["", ORDER_DASH]
    return "\n".join(out)


#: what a "—" in the fitted-order table means
ORDER_DASH = ("— : no slope fitted. A slope needs at least 3 steps whose error lies above 30 x "
              "the truth's own uncertainty (the figures' grey band) and below 1 % of the value; "
              "a method whose error reaches the truth's floor within its two largest steps "
              "(radau5 on the smooth designs, say) has fewer, and shows no order there.")


def _duration(s) -> str:
    if s is None or not math.isfinite(s):
        return "—"
    return f"{s * 1e6:.1f} µs" if s < 1e-3 else (f"{s * 1e3:.2f} ms" if s < 1 else f"{s:.2f} s")


def target_text(target: dict | None) -> str:
    if not target:
        return "—"
    if "max_s" in target:
        return f"≤ {_duration(target['max_s'])}"
    if "max_ratio" in target:
        return f"≤ {target['max_ratio']:g}×"
    return f"≥ {target['min_per_s']:,.0f} /s"


def met_text(r: dict) -> str:
    """Whether a row meets its target, and when it does not on a loaded machine, that the
    target is an idle machine's (:data:`softclose.bench.timing.IDLE_LOAD`)."""
    from .timing import IDLE_LOAD
    met = r.get("met")
    if met is None:
        return ""
    if met:
        return "yes"
    load = r.get("load")
    if load is not None and load > IDLE_LOAD:
        return f"**no** (loaded: {load:.1f})"
    return "**no**"


def _load_text(load) -> str:
    return "" if load is None else f"{load:.1f}"


def speed_markdown(rows) -> str:
    """The speed table: median, rate, repeats, target, whether it is met and the load it
    was measured under."""
    from .timing import IDLE_LOAD
    out = ["| what | median | rate | repeats | target | met? | load | note |",
           "|---|---:|---:|---:|---|:-:|---:|---|"]
    for r in rows:
        rate = f"{r['rate']:,.0f} {r['unit']}/s" if r.get("rate") else \
            (f"{r['ratio']:.2f}×" if r.get("ratio") is not None else "")
        out.append(f"| {r['what']} | {_duration(r['median_s'])} | {rate} | {r['repeats']} | "
                   f"{target_text(r.get('target'))} | {met_text(r)} | "
                   f"{_load_text(r.get('load'))} | {r['note']} |")
    out += ["", f"load: the cores other processes used on average while the row was measured "
                f"(the machine's busy CPU time less the benchmark's own). The targets are set "
                f"for an idle machine (load below {IDLE_LOAD:g}); a row measured above it is an "
                "upper bound of the idle time, and its \"no\" is the load's, not a "
                "regression, until it is measured idle."]
    return "\n".join(out)


def structures_markdown(rows) -> str:
    """The NLP structures' table: one row per structure of the README's commands, with one
    Hessian of the Lagrangian and one constraint Jacobian timed in CasADi's virtual machine
    and compiled, and whether ``softclose prepare`` compiles the structure."""
    head = ("| command | NLP | variables | constraints | parameters | build | C | generate "
            "| compile | Hessian + Jacobian: VM / C | prepared |\n"
            "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|:-:|")
    lines = [head]
    for r in rows:
        comp = (f"{r['compile_s']:.1f} s ({r['flags']})" if r.get("compile_s") is not None
                else "—")
        deriv = (f"{r['derivatives_vm_ms']:.1f} / {r['derivatives_c_ms']:.1f} ms"
                 if r.get("derivatives_c_ms") is not None else "—")
        prepared = {True: "yes", False: "no"}.get(r.get("prepared"), "—")
        lines.append(f"| `{r['command']}` | {r['nlp']} | {r['variables']} | "
                     f"{r['constraints']} | {r['parameters']} | {num(r['build_s'], spec='.2f')} s | "
                     f"{r['c_mb']:.2f} MB | {r['generate_s']:.1f} s | {comp} | {deriv} | "
                     f"{prepared} |")
    return "\n".join(lines)


def peers_markdown(rows) -> str:
    """The peers' table: each tool's time to its optimum (wall, CPU, as a multiple of
    softclose's), its J and violations in softclose's adaptive reference, its iterations."""
    head = ("| tool | time | CPU | × softclose | J (reference) | J / softclose's − 1 | "
            "violations (reference) | closing time (reference) | iterations | starts |\n"
            "|---|---:|---:|---:|---:|---:|---|---:|---:|---:|")
    lines = [head]
    for r in rows:
        rel = r.get("objective_relative")
        rel = "—" if rel is None or r["tool"] == "softclose" else f"{rel:+.2e}"
        its = str(r["iterations"]) + (f" ({r['evaluations']} strokes)"
                                      if r.get("evaluations") else "")
        ratio = "1" if r["tool"] == "softclose" else num(r.get("ratio"), spec=".1f")
        closing = r.get("closing_time")
        lines.append(f"| {r['tool']} | {r['time_s']:.2f} s | {r['cpu_s']:.2f} s | {ratio} | "
                     f"{num(r.get('objective_reference'), spec='.8g')} | {rel} | "
                     f"{', '.join(r['violations']) or 'none'} | "
                     f"{'—' if closing is None else f'{closing:.9f} s'} | {its} | "
                     f"{r['starts']} |")
    return "\n".join(lines)


def optimiser_markdown(rows, note="") -> str:
    """The optimiser table (N, sub-steps, objective error, solve time, design)."""
    if not rows:
        return note or "(no optimiser rows)"
    out = ["| N | sub-steps | success | objective J_N | J_reference(design_N) | "
           "abs(J_N - J*) | abs(J_N - J_ref(design_N)) | solve time (s) | k | l0 | c |",
           "|---:|---:|:-:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        if "objective" not in r:
            out.append(f"| {r['nodes']} | {r['substeps']} | no | {r['message']} |" + " |" * 7)
            continue
        out.append(f"| {r['nodes']} | {r['substeps']} | {'yes' if r['success'] else 'no'} | "
                   f"{r['objective']:.8g} | {num(r['objective_reference'], spec='.8g')} | "
                   f"{num(r.get('objective_error'), spec='.2e')} | {num(r['discretisation_error'], spec='.2e')} | "
                   f"{r['solve_time']:.3f} | {r['spring_k']:.5g} | "
                   f"{r['spring_rest_length']:.5g} | {r['damper_c']:.5g} |")
    if rows[0].get("J_star") is not None:
        out += ["", f"J* = {rows[0]['J_star']:.10g} (the reference objective at the design of "
                "the finest setting)"]
    return "\n".join(out)


def run_line(res) -> str:
    """Commit, date, run time and load average of a run."""
    load = ""
    if res.load and None not in res.load:
        load = f"; load average {res.load[0]:.1f} at the start, {res.load[1]:.1f} at the end"
    return (f"commit {res.commit or 'unknown'}, {res.date}{', quick' if res.quick else ''}; "
            f"{res.elapsed:.0f} s{load}")


def report_text(res) -> str:
    """The whole report as text (Markdown tables)."""
    from .precision import TRUTH_TOL
    return "\n".join([
        f"machine: {res.machine}", run_line(res), "",
        f"work precision (errors against CVODES at tol {TRUTH_TOL:g}; µs per stroke in the "
        "C kernel):", work_precision_markdown(res.work_precision), "",
        "speed (median of repeats):", speed_markdown(res.speed), "",
        "optimiser:", optimiser_markdown(res.optimiser, res.optimiser_note), "",
        *(["NLP structures:", structures_markdown(res.structures), ""] if res.structures
          else []),
        *(["peers (the default design problem in each tool, each optimum re-simulated by the "
           "adaptive reference):", peers_markdown(res.peers), ""] if res.peers else []),
        default_text(res.default)])


def report_markdown(res) -> str:
    """``bench.md``: the report with section headings."""
    return (f"Machine: {res.machine}\n\nRun: {run_line(res)}.\n\n"
            f"## Default step\n\n{default_text(res.default)}\n\n"
            f"## Work precision\n\n{work_precision_markdown(res.work_precision)}\n\n"
            f"## Speed\n\n{speed_markdown(res.speed)}\n\n"
            f"## Optimiser\n\n{optimiser_markdown(res.optimiser, res.optimiser_note)}\n"
            + (f"\n## NLP structures\n\n{structures_markdown(res.structures)}\n"
               if res.structures else "")
            + (f"\n## Peers\n\n{peers_markdown(res.peers)}\n" if res.peers else ""))


# -- files ---------------------------------------------------------------------------------
def write_csv(rows, path: Path) -> Path:
    """Rows (dicts) as CSV; the header is the union of their keys; None is an empty cell."""
    keys = []
    for r in rows:
        keys += [k for k in r if k not in keys]
    with replacing(path) as tmp, open(tmp, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        for r in rows:
            w.writerow({k: ("" if r.get(k) is None else r.get(k)) for k in keys})
    return path


def speed_record(res) -> dict:
    """The speed rows of a run with where and when they were measured."""
    from .timing import IDLE_LOAD
    return {"machine": res.machine, "date": res.date, "commit": res.commit,
            "quick": res.quick, "load": list(res.load), "idle_load": IDLE_LOAD,
            "rows": {r["key"]: {k: r.get(k) for k in ("what", "median_s", "rate", "unit",
                                                      "repeats", "target", "met", "load",
                                                      "note")}
                     for r in res.speed}}


def structures_record(res) -> dict:
    """The NLP structures' rows of a run with the machine and load they were measured on."""
    return {"machine": res.machine, "date": res.date, "commit": res.commit,
            "load": list(res.load), "rows": [dict(r) for r in res.structures]}


def write_structures(res, out: Path) -> list[Path]:
    """The NLP structures' table (CSV) and record (JSON: the rows with where they were
    measured, the record the performance page's table is held to: docs/bench_structures.json,
    tests/test_bench_structures.py) into ``out``."""
    from ..jsonio import dumps
    path = Path(out) / "structures.json"
    write_text(path, dumps(structures_record(res), indent=1))
    return [write_csv(list(res.structures), Path(out) / "structures.csv"), path]


def peers_record(res) -> dict:
    """The peers' rows of a run with the machine, the load and the tools' versions."""
    from .peers import versions
    return {"machine": res.machine, "date": res.date, "commit": res.commit,
            "load": list(res.load), "versions": versions(),
            "rows": [dict(r) for r in res.peers]}


def write_peers(res, out: Path) -> list[Path]:
    """The peers' table (CSV) and record (JSON: the rows with where they were measured, the
    record the performance page's table is held to: docs/bench_peers.json,
    tests/test_bench_peers.py) into ``out``."""
    from ..jsonio import dumps
    path = Path(out) / "peers.json"
    write_text(path, dumps(peers_record(res), indent=1))
    rows = [{k: (", ".join(v) if isinstance(v, list) else v) for k, v in r.items()
             if k not in ("design", "violation_text")} for r in res.peers]
    return [write_csv(rows, Path(out) / "peers.csv"), path]


def write_files(res, out: Path, figure_format: str = "png", figure_style: str | None = None
                ) -> list[Path]:
    """Tables, report, JSON and figures of one bench run into ``out`` (which exists), the
    figures as ``figure_format`` (png, pdf, svg) in ``figure_style``."""
    from ..present.figures import save
    from ..present.figures.bench import plot_error_vs_step, plot_optimiser, plot_work_precision
    from ..jsonio import dumps
    out = Path(out)

    def figure(fig, name: str) -> Path:
        return save(fig, out / f"{name}.{figure_format}", figure_style)

    speed_rows = [{**r, "target": target_text(r.get("target"))} for r in res.speed]
    files = [write_csv(res.work_precision.rows, out / "work_precision.csv"),
             write_csv(speed_rows, out / "speed.csv")]
    # the speed rows alone, with the run's machine, date, commit and load: the record the
    # README's timings are held to (docs/bench_speed.json, tests/test_readme_numbers.py)
    write_text(out / "speed.json", dumps(speed_record(res), indent=1))
    files.append(out / "speed.json")
    if res.optimiser:
        files.append(write_csv(res.optimiser, out / "optimiser.csv"))
    if res.structures:
        files += write_structures(res, out)
    if res.peers:
        files += write_peers(res, out)
    write_text(out / "bench.md", report_markdown(res))
    files.append(out / "bench.md")
    files.append(figure(plot_work_precision(res.work_precision), "work_precision"))
    files.append(figure(plot_error_vs_step(res.work_precision), "error_vs_step"))
    fig = plot_optimiser(list(res.optimiser), default=(res.config.get("nodes", 10),
                                                       res.config.get("substeps", 4)))
    if fig is not None:
        files.append(figure(fig, "optimiser"))
    payload = res.to_json()
    payload["files"] = [str(f) for f in files + [out / "bench.json"]]
    write_text(out / "bench.json", dumps(payload, indent=1))
    files.append(out / "bench.json")
    return files


__all__ = ["write_files", "write_structures", "structures_record", "write_peers",
           "peers_record", "peers_markdown", "speed_record", "write_csv",
           "report_text", "report_markdown", "default_text", "work_precision_markdown",
           "speed_markdown", "optimiser_markdown", "structures_markdown", "met_text",
           "target_text", "ORDER_DASH"]

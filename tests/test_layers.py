"""The package's layers, held: every import (at the top of a module or inside a function)
goes to the same layer or a lower one, the modules' imports form no circle, the package
root keeps at most 8 modules, and no module exceeds 600 lines.

The layers are the folders (and the root's modules), lowest first: the foundations (errors,
the version, JSON, the files read and written, Ctrl-C, the build cache); the numerical methods (integrators, root
searches) and the coil spring's standards (EN 13906-1, EN 10270, EN 15800); the model (the
mechanism, its elements and their config keys, what a config resolves to, the CasADi model);
the config; the design problem; what is shown (tables, figures, progress lines); the
simulation (the simulator, its C kernel, the reference, statics, the stroke's result); the
features (optimiser, robust design, sweeps, catalog, calibration, the sign-off report, the
notebook explorer); benchmarks and validation; the command line. Nothing imports the command
line, and nothing below it imports the package root's API (which the command line calls). The config is resolved once,
at the top: no module of the model or the simulation imports the config or has a function
taking a ``cfg`` or ``config``.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "softclose"

LAYERS = [
    ["softclose.errors", "softclose.version", "softclose.jsonio", "softclose.interrupt",
     "softclose.files", "softclose.buildcache"],
    ["softclose.numerics", "softclose.coil_spring"],
    ["softclose.model"],
    ["softclose.config"],
    ["softclose.problem"],
    ["softclose.present"],
    ["softclose.simulation"],
    ["softclose.optimiser", "softclose.robust", "softclose.sweeps", "softclose.catalog",
     "softclose.calibration", "softclose.signoff", "softclose.notebook"],
    ["softclose.bench", "softclose.validation"],
    ["softclose.cli", "softclose.__main__"],
]


def module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {module_name(p): p for p in ROOT.rglob("*.py")}


def layer(module: str) -> int | None:
    best = None
    for i, prefixes in enumerate(LAYERS):
        for pre in prefixes:
            if (module == pre or module.startswith(pre + ".")) and \
                    (best is None or len(pre) > best[1]):
                best = (i, len(pre))
    return None if best is None else best[0]


def imports(module: str) -> set[str]:
    """Every softclose module ``module`` imports, anywhere in its text."""
    path = MODULES[module]
    package = module if path.name == "__init__.py" else module.rsplit(".", 1)[0]
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[:len(package.split(".")) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                out.add(sub if sub in MODULES else target)
        elif isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
    return {t for t in out if t == "softclose" or t.startswith("softclose.")}


GRAPH = {m: imports(m) - {m} for m in MODULES}


def test_the_layers_are_the_folders():
    """Each layer is a list of the package's folders (or root modules), none split."""
    named = [pre for prefixes in LAYERS for pre in prefixes]
    assert all(pre.count(".") == 1 for pre in named), named
    tops = {".".join(m.split(".")[:2]) for m in MODULES if m != "softclose"}
    assert sorted(named) == sorted(tops)


def test_every_module_has_a_layer():
    assert [m for m in MODULES if m != "softclose" and layer(m) is None] == []


@pytest.mark.parametrize("module", sorted(m for m in MODULES if m != "softclose"))
def test_imports_go_down_or_across(module):
    top = layer(module) == len(LAYERS) - 1     # the command line calls the package's API
    upward = [t for t in GRAPH[module]
              if (t == "softclose" and not top)
              or (layer(t) is not None and layer(t) > layer(module))]
    assert upward == [], f"{module} imports a higher layer (or the package root's API)"


def test_the_modules_imports_form_no_circle():
    state: dict[str, int] = {}
    circles = []

    def visit(m, path):
        state[m] = 1
        for t in sorted(GRAPH.get(m, ())):
            if t not in GRAPH or t == "softclose":
                continue
            if state.get(t) == 1:
                circles.append(path[path.index(t):] + [t])
            elif t not in state:
                visit(t, path + [t])
        state[m] = 2

    for m in sorted(GRAPH):
        if m not in state and m != "softclose":
            visit(m, [m])
    assert circles == []


def test_the_root_keeps_the_api_and_at_most_eight_modules():
    root = sorted(p.name for p in ROOT.glob("*.py"))
    assert len(root) <= 8, root


def test_no_module_exceeds_600_lines():
    long = {m: n for m, p in MODULES.items() if (n := len(p.read_text().splitlines())) > 600}
    assert long == {}


#: the layers below the features that take the config resolved, never a Config
RESOLVED = ("softclose.model", "softclose.simulation")


def _below_features(module: str) -> bool:
    return any(module == pre or module.startswith(pre + ".") for pre in RESOLVED)


@pytest.mark.parametrize("module", sorted(m for m in MODULES if _below_features(m)))
def test_the_model_and_the_simulation_take_no_config(module):
    configs = [t for t in GRAPH[module]
               if t == "softclose.config" or t.startswith("softclose.config.")]
    assert configs == [], f"{module} imports the config: take the resolved objects"
    named = sorted({f"{getattr(node, 'name', 'lambda')}({a.arg})"
                    for node in ast.walk(ast.parse(MODULES[module].read_text()))
                    if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda))
                    for a in (node.args.posonlyargs + node.args.args + node.args.kwonlyargs
                              + [x for x in (node.args.vararg, node.args.kwarg) if x])
                    if a.arg in ("cfg", "config")})
    assert named == [], f"{module}: functions that take a config: {named}"

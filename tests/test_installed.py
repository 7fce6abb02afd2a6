"""The tests run the users' path: the package pip installed (its files, the kernel it built),
not the checkout the tests sit in (tests/conftest.py); processes the tests start do too."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from importlib import metadata
from pathlib import Path

import pytest

import softclose
from softclose.simulation.kernel import library

ROOT = Path(__file__).resolve().parents[1]


def _editable() -> bool:
    text = metadata.distribution("softclose").read_text("direct_url.json") or "{}"
    return bool(json.loads(text).get("dir_info", {}).get("editable"))


def _installed_init() -> Path:
    return Path(metadata.distribution("softclose").locate_file("softclose/__init__.py"))


def test_the_package_is_the_installed_one():
    here = Path(softclose.__file__).resolve()
    if _editable():             # (pip install -e: the checkout is what is installed)
        assert here == ROOT / "softclose" / "__init__.py"
    else:
        assert here == _installed_init().resolve()
        assert here != ROOT / "softclose" / "__init__.py"     # (a venv may sit in the checkout)


def test_a_process_started_in_the_checkout_imports_the_installed_package():
    out = subprocess.run([sys.executable, "-c", "import softclose; print(softclose.__file__)"],
                         cwd=ROOT, capture_output=True, text=True, timeout=60, check=True)
    assert Path(out.stdout.strip()).resolve() == Path(softclose.__file__).resolve()
    assert os.environ.get("PYTHONSAFEPATH") == "1"


def test_the_kernel_is_the_extension_pip_built():
    if _editable():
        pytest.skip("an editable install compiles an edited kernel afresh (library.load)")
    built = library._built_extension()
    assert built is not None and built.parent == Path(library.__file__).parent
    assert built.name.startswith("_kernel") and built.suffix == ".so"

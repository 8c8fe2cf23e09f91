"""postprocess/ only reads output folders (docs/design.md, "Layers"): no module of it may import the
solvers, the high-level simulation API, the model, the assembly or the CLI. Checked on the source
(ast), so that it holds without pyvista or matplotlib installed and cannot regress silently."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
POSTPROCESS = ROOT / "postprocess"

#: modules that build or run models; a prefix forbids the module and everything below it
FORBIDDEN = ("flexmbs.solvers", "flexmbs.simulation", "flexmbs.model", "flexmbs.assembly",
             "flexmbs.cli")


def _forbidden(module: str) -> bool:
    return any(module == f or module.startswith(f + ".") for f in FORBIDDEN)


def _allowed_submodule(name: str) -> bool:
    """``from flexmbs import <name>``: only a submodule (not an API name) outside FORBIDDEN."""
    is_module = (ROOT / "flexmbs" / name / "__init__.py").is_file() or \
        (ROOT / "flexmbs" / f"{name}.py").is_file()
    return is_module and not _forbidden(f"flexmbs.{name}")


def forbidden_imports(source: str, filename: str = "<source>") -> list[str]:
    """``"line: what"`` for every import of ``source`` that reaches a forbidden module: ``import
    flexmbs`` (the package namespace is the simulating API: ``simulate``, ``Model``, ...),
    ``from flexmbs import X`` unless X is an allowed submodule, any import of a FORBIDDEN module,
    and ``importlib.import_module``/``__import__`` of one by a literal name."""
    found = []
    for node in ast.walk(ast.parse(source, filename)):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name == "flexmbs" or _forbidden(alias.name):
                    found.append(f"{node.lineno}: import {alias.name}")
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            if node.module == "flexmbs":
                bad = [a.name for a in node.names if not _allowed_submodule(a.name)]
                if bad:
                    found.append(f"{node.lineno}: from flexmbs import {', '.join(bad)}")
            elif _forbidden(node.module):
                found.append(f"{node.lineno}: from {node.module} import ...")
        elif isinstance(node, ast.Call) and node.args and isinstance(node.args[0], ast.Constant):
            fn = node.func
            name = fn.attr if isinstance(fn, ast.Attribute) else getattr(fn, "id", "")
            arg = node.args[0].value
            if name in ("import_module", "__import__") and isinstance(arg, str) and (
                    arg == "flexmbs" or _forbidden(arg)):
                found.append(f"{node.lineno}: {name}({arg!r})")
    return found


def test_postprocess_imports_no_solver_simulation_or_model():
    files = sorted(POSTPROCESS.rglob("*.py"))
    assert files and POSTPROCESS / "__init__.py" in files
    bad = {str(f.relative_to(POSTPROCESS.parent)): hits for f in files
           if (hits := forbidden_imports(f.read_text(encoding="utf-8"), str(f)))}
    assert not bad, ("postprocess/ must only read output folders; scripts that run models belong "
                     f"in examples/figures/: {bad}")


@pytest.mark.parametrize("source", [
    "import flexmbs",
    "import flexmbs as fm",
    "from flexmbs import simulate",
    "from flexmbs import Model",
    "from flexmbs import *",
    "from flexmbs import solvers",
    "import flexmbs.solvers.static",
    "from flexmbs.simulation import simulate",
    "from flexmbs.model import Pose",
    "from flexmbs.cli import main as flexmbs",
    "def f():\n    from flexmbs.solvers.generalized_alpha import integrate\n",
    "import importlib\nimportlib.import_module('flexmbs.simulation')",
])
def test_checker_catches(source):
    assert forbidden_imports(source)


@pytest.mark.parametrize("source", [
    "import numpy as np\nfrom .data import read_run",
    "from flexmbs.io.vtu import read_pvd",
    "from flexmbs import io",
    "from flexmbs.errors import FlexmbsError",
    "import flexmbsx",
])
def test_checker_allows(source):
    assert forbidden_imports(source) == []

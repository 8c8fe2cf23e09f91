"""The figure scripts of examples/figures/ (they run the examples, then draw docs/figures/ with
postprocess/): they load from their new place, find the checkout and its example files, and
parse their options."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
FIGURES = ROOT / "examples" / "figures"


def load(name: str):
    spec = importlib.util.spec_from_file_location(f"figures_{name}", FIGURES / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("name, needs", [
    ("example1", ["examples/curved_beam_sleeve.py", "docs/figures"]),
    ("example2", ["examples/solar_array_wing.toml", "docs/figures"]),
])
def test_figure_script_paths_and_help(name, needs, capsys):
    module = load(name)
    assert module.ROOT == ROOT
    assert all((module.ROOT / p).exists() for p in needs)
    with pytest.raises(SystemExit) as exc:
        module.main(["--help"])
    assert exc.value.code == 0
    assert f"Example {name[-1]} figure set" in capsys.readouterr().out


def test_no_figure_script_left_in_postprocess():
    assert not list((ROOT / "postprocess").glob("example*.py"))

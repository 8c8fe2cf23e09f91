"""The figure scripts of examples/figures/ (they run the examples, then draw docs/figures/ with
postprocess/): they load from their new place, find the checkout and its example files, and
parse their options."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.conftest import load_module

ROOT = Path(__file__).resolve().parents[2]
FIGURES = ROOT / "examples" / "figures"


@pytest.mark.parametrize("name, needs, title", [
    ("example1", ["examples/curved_beam_sleeve.py", "docs/figures"], "Example 1 figure set"),
    ("example2", ["examples/solar_array_wing.toml", "docs/figures"], "Example 2 figure set"),
    ("bowden_lever", ["examples/bowden_lever.toml"], "Bowden lever figure set"),
    ("tendon_robot", ["examples/tendon_robot.toml"], "Tendon robot figure set"),
    ("catheter", ["examples/catheter.toml"], "Catheter figure"),
])
def test_figure_script_paths_and_help(name, needs, title, capsys):
    module = load_module(FIGURES / f"{name}.py", f"figures_{name}")
    assert module.ROOT == ROOT
    assert all((module.ROOT / p).exists() for p in needs)
    with pytest.raises(SystemExit) as exc:
        module.main(["--help"])
    assert exc.value.code == 0
    assert title in capsys.readouterr().out


def test_no_figure_script_left_in_postprocess():
    assert not list((ROOT / "postprocess").glob("example*.py"))

"""examples/rounded_slot_carriage.toml: a carriage with a rounded-rectangular slot on the curved
rail, gravity out of plane (compiled superellipse bore). A short run: the slot runs compiled,
starts on its flat top and, pushed sideways by the out-of-plane gravity, puts its contacts off
the top (the corner or the side wall) within 0.1 s; energy stays bounded (dissipative contact)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from flexmbs.cli import main
from flexmbs.io.scenario import load_scenario
from postprocess import contact_angles

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "rounded_slot_carriage.toml"


def test_example_runs_compiled_and_the_contact_leaves_the_flat_top(tmp_path):
    sc = load_scenario(EXAMPLE)
    (joint,) = sc.model.interactions
    assert joint.compiled_form()
    assert main(["run", str(EXAMPLE), "--t-end", "0.1", "--quiet", "--out", str(tmp_path)]) == 0
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["status"] == "completed"
    _, t, _, ang, _ = contact_angles(tmp_path, "slot")
    assert t.size
    assert np.abs(ang[t <= 0.02] - 90.0).min() < 15.0      # first on the flat top
    assert np.abs(ang[t >= 0.05] - 90.0).min() > 20.0      # then off it
    assert summary["energy_balance"]["change"] <= 1e-6

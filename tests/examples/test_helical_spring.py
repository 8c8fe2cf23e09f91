"""The helical spring example (rods, a rigid end plate on a cylindrical joint) runs, its static
stiffness is the closed form's within the end effect of the plates (0.26 % at 16 elements per
coil), and a step load makes the plate overshoot to about twice its static travel."""

from __future__ import annotations

import csv
import re
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "examples"))

import helical_spring


def test_helical_spring_example(tmp_path, capsys):
    out = tmp_path / "hs"
    assert helical_spring.main(["--t-end", "0.02", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    found = re.search(r"axial stiffness ([\d.]+) N/m; closed form ([\d.]+) N/m", text)
    assert found is not None
    k, k_formula = float(found.group(1)), float(found.group(2))
    assert 0.0 < k / k_formula - 1.0 < 0.005
    with (out / "probes.csv").open() as f:
        rows = list(csv.DictReader(f))
    z = np.array([float(r["plate_z"]) for r in rows]) - 0.008
    torsion = np.array([float(r["torsion_mid"]) for r in rows])
    static = 0.2 / k
    assert 1.8 * static < z.max() < 2.05 * static        # step load: overshoot to ~2 F/k
    # the light wire is in quasi-static equilibrium with the plate's spring force k z: its
    # torsional moment at mid-length is k z R cos(alpha) at the largest travel (the plate's
    # inertia does not enter the wire)
    i = int(np.argmax(z))
    alpha = np.arctan(2e-3 / (2 * np.pi * 0.01))
    assert abs(torsion[i]) / (k * z[i] * 0.01 * np.cos(alpha)) == pytest.approx(1.0, abs=0.03)

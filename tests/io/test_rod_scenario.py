"""The rod (``element = "ancf_rod14"``) through scenario files, the sliding joints, probes and the
VTU output, with the cable as the reference where the two must agree (in-plane problems)."""

from __future__ import annotations

import csv
from pathlib import Path

import meshio
import numpy as np
import pytest

import flexmbs as fm
from flexmbs.cli import main
from flexmbs.io.scenario import load_scenario

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


@pytest.mark.parametrize("example", ["curved_beam_sleeve.toml", "curved_beam_sleeve_ideal.toml"])
def test_the_sliding_joints_carry_a_sleeve_on_a_rod_rail_as_on_a_cable(example):
    """Example 1 (clearance joint) and its clearance-free baseline (sliding joint) with the rail
    made of rods: an in-plane problem, so the sleeve's slide coordinate follows the cable rail's
    to 1e-4 of its travel over 0.1 s (the two elements differ only by the quadrature of the
    bending term) and the rod's twist stays at rounding level."""
    slides = []
    for element in ("ancf_cable", "ancf_rod14"):
        sc = load_scenario(EXAMPLES / example, [f"beams.rail.element={element}"])
        (joint,) = sc.model.interactions
        res = fm.simulate(sc.model, t_end=0.1, dt=1e-4, output_interval=1e-2,
                          integrator=sc.integrator_options(), record_energy=False)
        slides.append(np.array([joint.slide_coordinate(q) for q in res.q]))
        if element == "ancf_rod14":
            beam = sc.model.beams[0]
            tw = res.assembly.beam_dofs(beam).reshape(beam.n_nodes, -1)[:, beam.layout.twist]
            assert np.abs(res.q[:, tw]).max() < 1e-9
    travel = np.abs(slides[0] - slides[0][0]).max()
    assert travel > 1e-3
    assert np.abs(slides[1] - slides[0]).max() < 1e-4 * travel


ROD_TOML = """
name = "twisted"
[simulation]
integrator = "static"
t_end = 1.0
dt = 0.25

[[beams]]
name = "shaft"
element = "ancf_rod14"
geometry = { line = { start = [0.0, 0.0, 0.0], end = [2.0, 0.0, 0.0] } }
elements = 4
axial_stiffness = 1e6
bending_stiffness = 10.0
mass_per_length = 0.5
torsional_stiffness = 0.7

[[constraints]]
type = "clamp"
beam = "shaft"
node = "first"

[[loads]]
type = "point"
beam = "shaft"
node = "last"
moment = [0.3, 0.0, 0.0]
function = { type = "ramp", start = 0.0, end = 1.0, value = 1.0 }

[[probes]]
name = "tip_twist"
type = "beam_point"
beam = "shaft"
s = 2.0
quantity = "twist"

[[probes]]
name = "moment"
type = "beam_point"
beam = "shaft"
s = 0.7
quantity = "torsional_moment"

[[probes]]
name = "curv"
type = "beam_point"
beam = "shaft"
s = 0.7
quantity = "curvature"
"""


def test_a_rod_scenario_writes_twist_and_torsional_moment(tmp_path):
    """An end torque ramped on a clamped straight rod (statics): the twist probe reads
    T L/GJ, the torsional-moment probe T, the curvature probe zero, the VTU frames carry ``twist``,
    ``torsion`` and ``torsional_moment`` as point data (the last frame: linear twist along the
    rod, the moment T everywhere)."""
    path = tmp_path / "twisted.toml"
    path.write_text(ROD_TOML)
    out = tmp_path / "out"
    # the merged frames (one .vtu grid each), which meshio reads
    assert main(["run", str(path), "--quiet", "--out", str(out), "--output-frames", "merged"]) == 0
    with (out / "probes.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert {"curv_x", "curv_y", "curv_z", "tip_twist", "moment"} <= set(rows[0])
    last = rows[-1]
    assert float(last["t"]) == pytest.approx(1.0)
    assert float(last["tip_twist"]) == pytest.approx(0.3 * 2.0 / 0.7, rel=1e-9)
    assert float(last["moment"]) == pytest.approx(0.3, rel=1e-9)
    for row in rows:
        assert float(row["moment"]) == pytest.approx(0.3 * float(row["t"]), rel=1e-9)
    frames = sorted((out / "vtu").glob("*.vtu"))
    mesh = meshio.read(frames[-1])
    pd = mesh.point_data
    x = mesh.points[:, 0]
    assert pd["twist"] == pytest.approx(0.3 * x / 0.7, rel=1e-9, abs=1e-12)
    assert pd["torsional_moment"] == pytest.approx(0.3, rel=1e-9)
    assert pd["torsion"] == pytest.approx(0.3 / 0.7, rel=1e-9)


def test_a_rod_needs_a_torsional_stiffness_and_no_cable_options():
    model = fm.Model()
    with pytest.raises(fm.ModelError, match="needs a torsional stiffness"):
        model.add_beam(fm.line((0, 0, 0), (1, 0, 0), elements=2), element="ancf_rod14",
                       section=fm.BeamStiffness(axial_stiffness=1e6, bending_stiffness=1.0,
                                                mass_per_length=1.0))
    with pytest.raises(fm.ModelError, match="takes none"):
        model.add_beam(fm.line((0, 0, 0), (1, 0, 0), elements=2), element="ancf_rod14",
                       section=fm.BeamStiffness(axial_stiffness=1e6, bending_stiffness=1.0,
                                                mass_per_length=1.0, torsional_stiffness=1.0),
                       options=fm.CableOptions())

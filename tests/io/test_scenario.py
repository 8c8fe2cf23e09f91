"""Scenario files: the examples load, overrides apply, and a file builds the same model as the API."""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.assembly import Assembly
from flexmbs.io.builders import JOINTS
from flexmbs.io.overrides import apply_override
from flexmbs.io.scenario import build_scenario, load_scenario
from flexmbs.io.tables import read_toml

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"
MESHES = ROOT / "meshes"
RTOL = 1e-12


def write(tmp_path: Path, text: str, name: str = "case.toml") -> Path:
    p = tmp_path / name
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_text(text)
    return p


# ------------------------------------------------------------------------------------ examples
def test_cantilever_example_builds_expected_model():
    sc = load_scenario(EXAMPLES / "cantilever.toml")
    assert sc.name == "cantilever"
    m = sc.model
    assert (len(m.beams), len(m.bodies), len(m.constraints), len(m.loads)) == (1, 0, 1, 0)
    rod = m.beams[0]
    assert rod.name == "rod" and rod.n_elem == 16
    assert rod.length == pytest.approx(1.0, rel=RTOL)
    area, second_moment = math.pi * 5e-3**2, math.pi * 5e-3**4 / 4
    assert rod.stiffness.axial_stiffness == pytest.approx(2.1e11 * area, rel=RTOL)
    assert rod.stiffness.bending_stiffness == pytest.approx(2.1e11 * second_moment, rel=RTOL)
    assert rod.stiffness.mass_per_length == pytest.approx(7800 * area, rel=RTOL)
    assert rod.damping == 1e-4
    c = m.constraints[0]
    assert c.kind == "clamp" and c.a.beam is rod and c.a.index == 0
    np.testing.assert_array_equal(m.gravity, [0, 0, -9.81])
    sim = sc.simulation
    assert (sim.t_end, sim.dt, sim.output_interval, sim.integrator) == (1.0, 1e-3, 0.01,
                                                                        "generalized_alpha")
    opts = sc.integrator_options()
    assert isinstance(opts, fm.GeneralizedAlpha) and opts.rho_inf == 0.8
    assert [p.name for p in sc.probes] == ["tip", "energy"]
    tip = sc.probes[0]
    assert type(tip).__name__ == "BeamPointProbe"
    assert tip.beam is rod and tip.s == 1.0 and tip.quantity == "displacement"
    assert tip.columns() == ["tip_x", "tip_y", "tip_z"]
    assert sc.probes[1].columns() == ["energy"]


def test_flexible_pendulum_example_builds_expected_model():
    sc = load_scenario(EXAMPLES / "flexible_pendulum.toml")
    m = sc.model
    (beam,) = m.beams
    assert beam.n_elem == 8 and beam.length == pytest.approx(1.2, rel=RTOL)
    # Berzeri & Shabana: A = 0.0018, I = 1.215e-8, rho = 5540, E = 0.7e6
    assert beam.stiffness.axial_stiffness == pytest.approx(0.7e6 * 0.0018, rel=1e-12)
    assert beam.stiffness.bending_stiffness == pytest.approx(0.7e6 * 1.215e-8, rel=1e-12)
    assert beam.stiffness.mass_per_length == pytest.approx(5540 * 0.0018, rel=1e-12)
    (pin,) = m.constraints
    assert pin.kind == "pin" and pin.a.index == 0
    np.testing.assert_array_equal(m.gravity, [0, 0, -9.81])
    asm = Assembly(m)
    assert asm.n_coords == 9 * 6 and asm.n_mult == 3
    assert sc.simulation.t_end == 1.0 and sc.simulation.dt == 1e-3
    (tip,) = sc.probes
    assert tip.s == pytest.approx(1.2) and tip.quantity == "position"


def test_scenario_equals_python_api_model():
    """The cantilever file and examples/cantilever.py build the same system."""
    sc = load_scenario(EXAMPLES / "cantilever.toml")
    api = fm.Model(gravity=(0.0, 0.0, -9.81), name="cantilever")
    rod = api.add_beam(fm.line((0, 0, 0), (1.0, 0, 0), elements=16),
                       section=fm.CircularSection(5e-3), material=fm.Material(E=2.1e11, rho=7800),
                       damping=1e-4, name="rod")
    api.clamp(rod.first_node)
    a_file, a_api = Assembly(sc.model), Assembly(api)
    assert a_file.n_coords == a_api.n_coords and a_file.n_mult == a_api.n_mult
    np.testing.assert_array_equal(a_file.q_ref, a_api.q_ref)
    w = []
    for asm, beam in ((a_file, sc.model.beams[0]), (a_api, rod)):
        st = fm.solve_static(asm)
        w.append(st.q[asm.node_dofs(beam.last_node)[2]])
    assert w[0] == pytest.approx(w[1], rel=1e-10)
    sec = fm.CircularSection(5e-3)
    w_lin = -7800 * sec.area * 9.81 / (8 * 2.1e11 * sec.second_moment)
    assert w[0] == pytest.approx(w_lin, rel=2e-3)


# ------------------------------------------------------------------------------------ overrides
def test_overrides_scalar_nested_and_array_entry_by_name():
    sc = load_scenario(EXAMPLES / "cantilever.toml", overrides=[
        "simulation.dt=2e-4",
        "beams.rod.elements=8",                       # array-of-tables entry by name
        "simulation.newton.max_iterations=40",        # nested table, created on the way
        "simulation.newton.modified=false",
        "probes.tip.quantity=velocity",               # bare word -> string
        "beams[rod].geometry.line.end=[2.0, 0, 0]",   # bracket form, nested inline table
        "constraints.0.node=last",                    # array entry by index
        "simulation.integrator = hht",
        "simulation.predictor=zero_acceleration",
        "simulation.compiled=false",
        "simulation.newton.refresh_cost=8.0",
        "simulation.constraint_level=position_velocity",
    ])
    assert sc.simulation.dt == 2e-4
    rod = sc.model.beams[0]
    assert rod.n_elem == 8 and rod.length == pytest.approx(2.0)
    assert sc.model.constraints[0].a.index == 8
    assert sc.probes[0].quantity == "velocity"
    opts = sc.integrator_options()
    assert opts.scheme == "hht" and opts.newton.max_iterations == 40 and not opts.newton.modified
    assert opts.predictor == "zero_acceleration" and not opts.compiled
    assert opts.newton.refresh_cost == 8.0
    assert opts.constraint_level == "position_velocity"
    assert load_scenario(EXAMPLES / "cantilever.toml").integrator_options().constraint_level == (
        "position")
    assert sc.raw["simulation"]["newton"] == {"max_iterations": 40, "modified": False,
                                              "refresh_cost": 8.0}
    assert sc.raw["beams"][0]["elements"] == 8


def test_apply_override_values_are_toml():
    raw = {"simulation": {"dt": 1e-3}, "beams": [{"name": "a"}, {"name": "b"}]}
    apply_override(raw, "simulation.gravity=[0, 0, -1.5]")
    apply_override(raw, "simulation.initial_static=true")
    apply_override(raw, 'beams.b.bending="scalar"')
    apply_override(raw, "beams.1.elements=4")
    apply_override(raw, "name=my_run")
    assert raw["simulation"]["gravity"] == [0, 0, -1.5]
    assert raw["simulation"]["initial_static"] is True
    assert raw["beams"][1] == {"name": "b", "bending": "scalar", "elements": 4}
    assert raw["name"] == "my_run"


@pytest.mark.parametrize("assignment, fragment", [
    ("simulation.dt", "expected KEY=VALUE"),
    ("beams.rial.elements=8", "no entry 'rial' in beams (entries: rod)"),
    ("simulation.dt.x=1", "simulation.dt is 0.001, not a table"),
    ("beams=3", None),   # allowed by apply_override, rejected by the loader
])
def test_override_errors(assignment, fragment):
    raw = read_toml(EXAMPLES / "cantilever.toml")
    if fragment is None:
        apply_override(raw, assignment)
        with pytest.raises(fm.ScenarioError, match="beams: expected an array of tables"):
            build_scenario(raw, EXAMPLES / "cantilever.toml")
        return
    with pytest.raises(fm.ScenarioError) as info:
        apply_override(raw, assignment)
    assert fragment in str(info.value)


# ------------------------------------------------------------------------------------ other keys
def test_mesh_geometry_relative_to_the_scenario_file(tmp_path):
    (tmp_path / "meshes").mkdir()
    shutil.copy(MESHES / "arc_r1m_90deg.msh", tmp_path / "meshes" / "arc.msh")
    p = write(tmp_path, """
[simulation]
t_end = 0.1
dt = 1e-3
[[beams]]
name = "rail"
geometry = { mesh = "../meshes/arc.msh", group = "rail" }
radius = 2e-3
youngs_modulus = 2.1e11
density = 7800.0
[[beams]]
name = "coarse"
geometry = { mesh = "../meshes/arc.msh" }
elements = 4
radius = 2e-3
youngs_modulus = 2.1e11
density = 7800.0
""", "scenarios/rail.toml")
    sc = load_scenario(p)
    rail, coarse = sc.model.beams
    assert sc.name == "rail"
    assert rail.n_elem == 16 and coarse.n_elem == 4
    assert rail.length == pytest.approx(math.pi / 2, rel=1e-5)
    assert rail.stiffness.bending_stiffness == pytest.approx(2.639, rel=1e-3)


FULL = """
name = "everything"
description = "every constraint, load and probe type"

[simulation]
t_end = 0.5
dt = 1e-3
integrator = "static"
gravity = [0.0, 0.0, -9.81]
load_steps = 4
redundant_constraints = "drop"
newton = { relative_tolerance = 1e-9, line_search = true }

[[beams]]
name = "arc"
elements = 6
radius = 2e-3
youngs_modulus = 2.1e11
density = 7800.0
shear_modulus = 8e10
bending = "scalar"
axial_rule = "gauss5"
reference_axial_strain = -1e-4
[beams.geometry.arc]   # the same as geometry = { arc = { ... } }
center = [0.0, 0.0, 1.0]
radius = 1.0
start = [0.0, 0.0, 0.0]
angle = 1.0
normal = [0.0, -1.0, 0.0]

[[beams]]
name = "poly"
geometry = { polyline = { points = [[0, 1, 0], [0.5, 1, 0.1], [1, 1, 0]] } }
axial_stiffness = 1e6
bending_stiffness = 2.0
mass_per_length = 0.1
radius = 1e-3

[[rigid_bodies]]
name = "sleeve"
mass = 0.2
inertia = [2e-5, 4e-5, 4e-5]
pose = { on_beam = "arc", s = 0.5, offset = [0.0, 0.0, 5e-4] }
shape = { type = "cylinder", radius = 0.015, length = 0.04, inner_radius = 2.5e-3 }

[[rigid_bodies]]
name = "box"
mass = 1.0
inertia = [[0.1, 0.0, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1]]
pose = { position = [0.0, 2.0, 0.0], quaternion = [0.7071067811865476, 0.0, 0.0, 0.7071067811865476] }
velocity = [0.1, 0.0, 0.0]
angular_velocity = [0.0, 0.0, 1.0]
shape = { type = "box", size = [0.1, 0.2, 0.3] }

[[rigid_bodies]]
name = "slider"
mass = 1.0
inertia = [0.1, 0.1, 0.1]
pose = { position = [0.0, 3.0, 0.0] }

[[constraints]]
type = "clamp"
beam = "arc"
node = "first"

[[constraints]]
name = "tip_pin"
type = "pin"
beam = "poly"
node = -1

[[constraints]]
type = "rigid"
beam = "poly"
node = 0
body = "box"

[[constraints]]
type = "spherical"
body = "box"
point = [0.0, 0.0, 0.0]
ground_point = [0.0, 2.0, 0.0]

[[constraints]]
type = "revolute"
body = "slider"
body2 = "box"
point = [0.0, 2.5, 0.0]
axis = [0.0, 0.0, 1.0]

[[constraints]]
type = "prismatic"
body = "slider"
point = [0.0, 3.0, 0.0]
axis = [1.0, 0.0, 0.0]

[[constraints]]
type = "prescribed"
beam = "arc"
node = "last"
components = [0, 2]
function = { type = "sine", amplitude = 1e-3, frequency = 2.0 }

[[constraints]]
type = "joint"
body = "sleeve"
point = [0.0, 0.0, 0.0]
translation = [0, 1, 1]
rotation = [0, 0, 0]

[[constraints]]
type = "fix_body"
body = "sleeve"

[[loads]]
type = "point"
beam = "arc"
node = "last"
force = [0.0, 0.0, -1.0]
moment = [0.0, 0.1, 0.0]
function = { type = "ramp", start = 0.0, end = 0.1 }

[[loads]]
name = "mid"
type = "point"
beam = "poly"
s = 0.3
force = [0.0, 0.0, 1.0]
function = { type = "half_sine", duration = 0.2, amplitude = 2.0 }

[[loads]]
type = "point"
body = "box"
point = [0.05, 0.0, 0.0]
force = [0.0, 0.0, 2.0]
function = { type = "table", times = [0.0, 1.0], values = [0.0, 1.0] }

[[loads]]
type = "distributed"
beam = "poly"
force = [0.0, 0.0, -0.5]
function = 2.0

[[probes]]
name = "sleeve_pos"
type = "body_position"
body = "sleeve"

[[probes]]
name = "sleeve_rot"
type = "body_orientation"
body = "sleeve"

[[probes]]
name = "mid"
type = "beam_point"
beam = "poly"
s = 0.2

[[probes]]
name = "ekin"
type = "energy"
quantity = "kinetic"
"""


def test_every_constraint_load_and_probe_type(tmp_path):
    sc = load_scenario(write(tmp_path, FULL))
    m = sc.model
    assert sc.description.startswith("every")
    assert [b.name for b in m.beams] == ["arc", "poly"]
    arc, poly = m.beams
    assert arc.options.bending == "scalar" and arc.options.axial_rule == "gauss5"
    assert arc.reference_axial_strain == -1e-4
    assert arc.stiffness.torsional_stiffness == pytest.approx(8e10 * math.pi * 2e-3**4 / 2)
    assert arc.length == pytest.approx(1.0, rel=1e-3)
    assert poly.n_elem == 2 and poly.stiffness.radius == 1e-3
    sleeve, box, slider = m.bodies
    np.testing.assert_allclose(sleeve.pose.position,
                               arc.frame_at(0.5).position + [0, 0, 5e-4], atol=1e-15)
    np.testing.assert_allclose(sleeve.pose.rotation[:, 0], arc.frame_at(0.5).rotation[:, 0])
    assert sleeve.shape == {"type": "cylinder", "radius": 0.015, "length": 0.04,
                            "inner_radius": 2.5e-3}
    np.testing.assert_allclose(box.pose.rotation @ [1, 0, 0], [0, 1, 0], atol=1e-12)
    np.testing.assert_array_equal(box.angular_velocity, [0, 0, 1])
    kinds = [c.kind for c in m.constraints]
    assert kinds == ["clamp", "pin", "rigid", "spherical", "revolute", "prismatic", "prescribed",
                     "joint", "fix_body"]
    assert m.constraints[1].name == "tip_pin" and m.constraints[1].a.index == poly.n_nodes - 1
    assert m.constraints[6].components == (0, 2)
    assert m.constraints[6].function(0.125) == pytest.approx(1e-3)
    assert [ld.kind for ld in m.loads] == ["point", "point", "point", "distributed"]
    assert m.loads[0].function(0.05) == pytest.approx(0.5)
    assert m.loads[1].target == (poly, 0.3) and m.loads[1].function(0.1) == pytest.approx(2.0)
    assert m.loads[3].function(123.0) == 2.0
    assert [p.name for p in sc.probes] == ["sleeve_pos", "sleeve_rot", "mid", "ekin"]
    assert sc.probes[1].columns() == ["sleeve_rot_w", "sleeve_rot_x", "sleeve_rot_y", "sleeve_rot_z"]
    sim = sc.simulation
    assert sim.integrator == "static" and sc.integrator_options() is None
    st = sc.static_options()
    assert st.load_steps == 4 and st.newton.relative_tolerance == 1e-9 and st.newton.line_search
    assert sim.redundant_constraints == "drop"


def test_defaults(tmp_path):
    sc = load_scenario(write(tmp_path, """
[simulation]
t_end = 1.0
dt = 0.01
"""))
    sim = sc.simulation
    assert sc.name == "case" and sc.probes == [] and sc.model.beams == []
    assert sim.integrator == "generalized_alpha" and sim.rho_inf == 0.8
    assert sim.gravity == (0.0, 0.0, 0.0) and sim.output_interval is None
    assert not sim.initial_static and sim.adaptive and sim.newton == {}
    assert sc.integrator_options() == fm.GeneralizedAlpha()


def test_clearance_example_builds_the_joint_and_probes():
    """examples/curved_beam_sleeve.toml: mesh rail (pi/2 long), sleeve on a clearance joint with
    9 sections, the four probes; a missing joint reference is a one-line error."""
    from flexmbs.contact.joint import SlidingClearanceJoint

    sc = load_scenario(EXAMPLES / "curved_beam_sleeve.toml")
    (joint,) = sc.model.interactions
    assert isinstance(joint, SlidingClearanceJoint)
    assert len(joint.stations) == 9 and joint.beam_radius == pytest.approx(2e-3)
    assert sc.model.beams[0].length == pytest.approx(np.pi / 2, rel=1e-6)
    assert [p.name for p in sc.probes] == ["sleeve_s", "lowest_point", "contact_force", "energy"]
    assert {"sliding", "sliding_clearance"} <= set(JOINTS)
    with pytest.raises(fm.ScenarioError, match=r"probes\[sleeve_s\]\.joint: no sliding joint named"):
        load_scenario(EXAMPLES / "curved_beam_sleeve.toml", ["probes.sleeve_s.joint=other"])


def test_loaded_scenario_runs_with_its_settings():
    sc = load_scenario(EXAMPLES / "flexible_pendulum.toml",
                       overrides=["simulation.t_end=0.02", "simulation.output_interval=0.01"])
    sim = sc.simulation
    res = fm.simulate(sc.model, t_end=sim.t_end, dt=sim.dt, integrator=sc.integrator_options(),
                      output_interval=sim.output_interval)
    np.testing.assert_allclose(res.t, [0.0, 0.01, 0.02], atol=1e-12)
    (tip,) = sc.probes
    z = tip.evaluate(res.assembly, res.final_state)[2]
    assert -0.5 * 9.81 * 0.02**2 * 1.6 < z < 0.0    # falling, at most ~1.5x free fall at the tip


def test_clearance_joint_keys_from_scenario():
    """contact law, friction and hole keys of a sliding_clearance joint reach the joint; a key
    of another law is rejected with the allowed list."""
    from flexmbs.contact.laws import Friction, LinearPenalty

    sc = load_scenario(EXAMPLES / "curved_beam_sleeve.toml", [
        "joints.sleeve.contact.friction=0.1", "joints.sleeve.contact.friction_velocity=2e-3",
        "joints.sleeve.contact.stiffness=2e6", "joints.sleeve.hole.sections=5"])
    (joint,) = sc.model.interactions
    assert isinstance(joint.friction, Friction)     # the form of earlier versions: regularised
    assert joint.friction.mu == 0.1 and joint.friction.law == "regularised"
    assert joint.friction.velocity == 2e-3
    assert isinstance(joint.contact, LinearPenalty) and joint.contact.stiffness == 2e6
    assert len(joint.stations) == 5
    with pytest.raises(fm.ScenarioError, match=r"unknown key 'damping' in joints\[sleeve\]\.contact"):
        load_scenario(EXAMPLES / "curved_beam_sleeve.toml", ["joints.sleeve.contact.law=hertz"])

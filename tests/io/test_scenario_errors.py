"""Bad scenario files are rejected before anything runs, with the key path and what was expected."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from flexmbs import ScenarioError
from flexmbs.io.scenario import load_scenario

EXPLICIT = "axial_stiffness = 1e6\nbending_stiffness = 10.0\nmass_per_length = 0.1\n"

SIM = """
[simulation]
t_end = 1.0
dt = 1e-3
"""

BEAM = """
[[beams]]
name = "rail"
geometry = { line = { start = [0.0, 0.0, 0.0], end = [1.0, 0.0, 0.0] } }
elements = 4
radius = 2e-3
youngs_modulus = 2.1e11
density = 7800.0
"""

BODY = """
[[rigid_bodies]]
name = "sleeve"
mass = 0.2
inertia = [2e-5, 4e-5, 4e-5]
pose = { position = [0.5, 0.0, 0.0] }
"""


def sub(text: str, old: str, new: str) -> str:
    assert old in text, old
    return text.replace(old, new)


# (id, file text, message fragment)
CASES = [
    # --- file and top level
    ("broken_toml", SIM + "[[beams]\nname = 'x'\n", "invalid TOML"),
    ("broken_toml_position", "name = \n", "line 1, column"),
    ("unknown_top_key", "beam = 1\n" + SIM, "unknown key 'beam' in the top level; did you mean "
                                            "'beams'?"),
    ("name_not_string", "name = 3\n" + SIM, "name: expected a non-empty string, got 3"),
    ("missing_simulation", BEAM, "simulation: missing required key (expected a table)"),
    ("beams_single_table", SIM + "[beams]\nname = 'x'\n", "beams: expected an array of tables"),
    # --- simulation
    ("missing_t_end", "[simulation]\ndt = 1e-3\n",
     "simulation.t_end: missing required key (expected a number > 0)"),
    ("negative_dt", sub(SIM, "dt = 1e-3", "dt = -1e-3"), "simulation.dt: expected a number > 0, "
                                                         "got -0.001"),
    ("zero_t_end", sub(SIM, "t_end = 1.0", "t_end = 0"), "simulation.t_end: expected a number > 0"),
    ("dt_is_string", sub(SIM, "dt = 1e-3", "dt = '1e-3'"),
     "simulation.dt: expected a number > 0, got '1e-3'"),
    ("dt_is_bool", sub(SIM, "dt = 1e-3", "dt = true"), "simulation.dt: expected a number > 0, "
                                                       "got true"),
    ("dt_nan", sub(SIM, "dt = 1e-3", "dt = nan"), "simulation.dt: expected a finite number"),
    ("dt_larger_than_t_end", sub(SIM, "dt = 1e-3", "dt = 2.0"), "simulation.dt: expected a time "
                                                                "step <= t_end"),
    ("unknown_integrator", SIM + "integrator = 'rk4'\n",
     "simulation.integrator: unknown integrator 'rk4' (known: generalized_alpha, hht, static, quasi_static)"),
    ("rho_inf_range", SIM + "rho_inf = 1.5\n", "simulation.rho_inf: expected a number in [0, 1], "
                                               "got 1.5"),
    ("hht_rho_inf", SIM + "integrator = 'hht'\nrho_inf = 0.3\n",
     "simulation.rho_inf: expected a number in [0.5, 1]"),
    ("output_interval_below_dt", SIM + "output_interval = 1e-4\n",
     "simulation.output_interval: expected a number >= dt"),
    ("gravity_two_numbers", SIM + "gravity = [0.0, -9.81]\n",
     "simulation.gravity: expected 3 numbers [x, y, z], got [0.0, -9.81]"),
    ("unknown_simulation_key", SIM + "tend = 2.0\n",
     "unknown key 'tend' in simulation; did you mean 't_end'?"),
    ("newton_bad_iterations", SIM + "newton = { max_iterations = 0 }\n",
     "simulation.newton.max_iterations: expected an integer >= 1, got 0"),
    ("newton_unknown_key", SIM + "newton = { max_iteration = 5 }\n",
     "unknown key 'max_iteration' in simulation.newton; did you mean 'max_iterations'?"),
    ("newton_refresh_ratio", SIM + "newton = { refresh_ratio = 1.5 }\n",
     "simulation.newton.refresh_ratio: expected a number in (0, 1), got 1.5"),
    ("newton_refresh_cost", SIM + "newton = { refresh_cost = -1 }\n",
     "simulation.newton.refresh_cost: expected a number > 0, got -1"),
    ("unknown_predictor", SIM + "predictor = 'linear'\n",
     "simulation.predictor: unknown predictor 'linear' (known: constant_acceleration, "
     "zero_acceleration)"),
    ("unknown_constraint_level", SIM + "constraint_level = 'index2'\n",
     "simulation.constraint_level: unknown constraint level 'index2' (known: position, "
     "position_velocity)"),
    ("compiled_not_bool", SIM + "compiled = 'yes'\n",
     "simulation.compiled: expected true or false, got 'yes'"),
    ("initial_static_not_bool", SIM + "initial_static = 1\n",
     "simulation.initial_static: expected true or false, got 1"),
    # --- beams
    ("negative_radius", SIM + sub(BEAM, "radius = 2e-3", "radius = -0.002"),
     "beams[rail].radius: expected a number > 0, got -0.002"),
    ("misspelt_youngs_modulus", SIM + sub(BEAM, "youngs_modulus", "youngs_modulous"),
     "unknown key 'youngs_modulous' in beams[rail]; did you mean 'youngs_modulus'?"),
    ("missing_density", SIM + sub(BEAM, "density = 7800.0", ""),
     "beams[rail].density: missing required key (expected a number >= 0)"),
    ("missing_beam_name", SIM + sub(BEAM, 'name = "rail"', ""),
     "beams[0].name: missing required key"),
    ("duplicate_beam_name", SIM + BEAM + BEAM, "beams[1].name: duplicate name 'rail'"),
    ("zero_elements", SIM + sub(BEAM, "elements = 4", "elements = 0"),
     "beams[rail].elements: expected an integer >= 1, got 0"),
    ("float_elements", SIM + sub(BEAM, "elements = 4", "elements = 4.5"),
     "beams[rail].elements: expected an integer >= 1, got 4.5"),
    ("line_without_elements", SIM + sub(BEAM, "elements = 4", ""),
     "beams[rail].elements: missing required key (expected an integer >= 1; a line geometry"),
    ("two_geometries", SIM + sub(BEAM, "geometry = {", "geometry = { mesh = 'a.msh', "),
     "beams[rail].geometry: expected exactly one of 'line', 'arc', 'mesh', 'polyline', got line, "
     "mesh"),
    ("line_start_equals_end", SIM + sub(BEAM, "end = [1.0, 0.0, 0.0]", "end = [0.0, 0.0, 0.0]"),
     "beams[rail].geometry.line: line start and end coincide"),
    ("arc_start_off_circle", SIM + sub(BEAM, "{ line = { start = [0.0, 0.0, 0.0], end = [1.0, 0.0, "
                                             "0.0] } }",
                                       "{ arc = { center = [0, 0, 0], radius = 1.0, start = [2.0, "
                                       "0, 0], angle = 1.0 } }"),
     "beams[rail].geometry.arc: arc start [2.0, 0.0, 0.0] is at distance 2 from the center"),
    ("mesh_file_missing", SIM + sub(BEAM, "{ line = { start = [0.0, 0.0, 0.0], end = [1.0, 0.0, "
                                          "0.0] } }", "{ mesh = 'no/such.msh' }"),
     "beams[rail].geometry.mesh: mesh file not found: "),
    ("group_without_mesh", SIM + sub(BEAM, "geometry = {", "geometry = { group = 'rail', "),
     "beams[rail].geometry.group: 'group' selects a curve of a mesh file"),
    ("rod_without_torsion", SIM + BEAM.replace("radius = 2e-3\nyoungs_modulus = 2.1e11\n"
                                               "density = 7800.0\n", EXPLICIT)
     + "element = 'ancf_rod14'\n",
     "beams[rail].torsional_stiffness: missing: element 'ancf_rod14' carries torsion"),
    ("rod_twist_inertia_with_material", SIM + BEAM + "element = 'ancf_rod14'\ntwist_inertia = 1.0\n",
     "beams[rail].twist_inertia: only with an explicit section"),
    ("cable_twist_inertia", SIM + BEAM + "twist_inertia = 1.0\n",
     "unknown key 'twist_inertia' in beams[rail]"),
    ("unknown_element", SIM + BEAM + "element = 'timoshenko'\n",
     "beams[rail].element: unknown element 'timoshenko' (known: ancf_cable, ancf_rod14)"),
    ("mixed_section", SIM + BEAM + "axial_stiffness = 1e6\n",
     "beams[rail]: give the section either as radius + youngs_modulus + density or as "
     "axial_stiffness"),
    ("explicit_section_incomplete", SIM + """
[[beams]]
name = "rail"
geometry = { line = { start = [0.0, 0.0, 0.0], end = [1.0, 0.0, 0.0] } }
elements = 4
axial_stiffness = 1e6
bending_stiffness = 1.0
""", "beams[rail].mass_per_length: missing required key (expected a number >= 0)"),
    ("poisson_and_shear", SIM + BEAM + "poisson_ratio = 0.3\nshear_modulus = 8e10\n",
     "beams[rail]: give only one of 'poisson_ratio', 'shear_modulus'"),
    ("poisson_out_of_range", SIM + BEAM + "poisson_ratio = 0.7\n",
     "beams[rail].poisson_ratio: expected a number in (-1, 0.5), got 0.7"),
    ("negative_damping", SIM + BEAM + "damping = -1.0\n",
     "beams[rail].damping: expected a number >= 0, got -1.0"),
    ("unknown_bending", SIM + BEAM + "bending = 'exact'\n",
     "beams[rail].bending: unknown value 'exact' (known: vector, scalar)"),
    ("exudyn_with_scalar", SIM + BEAM + "bending = 'scalar'\nexudyn_compatible = true\n",
     "beams[rail]: CableOptions: exudyn_compatible=True"),
    # --- rigid bodies
    ("zero_mass", SIM + sub(BODY, "mass = 0.2", "mass = 0.0"),
     "rigid_bodies[sleeve].mass: expected a number > 0, got 0.0"),
    ("negative_inertia", SIM + sub(BODY, "[2e-5, 4e-5, 4e-5]", "[2e-5, -4e-5, 4e-5]"),
     "rigid_bodies[sleeve].inertia: the inertia must be positive definite (principal moments "
     "-4e-05, 2e-05, 4e-05)"),
    ("inertia_triangle", SIM + sub(BODY, "[2e-5, 4e-5, 4e-5]", "[1e-4, 1e-5, 1e-5]"),
     "rigid_bodies[sleeve].inertia: principal moments"),
    ("quaternion_not_unit", SIM + sub(BODY, "position = [0.5, 0.0, 0.0]",
                                      "position = [0.5, 0.0, 0.0], quaternion = [1, 1, 0, 0]"),
     "rigid_bodies[sleeve].pose.quaternion: expected a unit quaternion"),
    ("pose_on_missing_beam", SIM + sub(BODY, "position = [0.5, 0.0, 0.0]",
                                       "on_beam = 'rial', s = 0.5"),
     "rigid_bodies[sleeve].pose.on_beam: no beam named 'rial' (beams: none)"),
    ("pose_s_outside_beam", SIM + BEAM + sub(BODY, "position = [0.5, 0.0, 0.0]",
                                             "on_beam = 'rail', s = 1.5"),
     "rigid_bodies[sleeve].pose.s: expected an arc length in [0, 1.0]"),
    ("pose_on_beam_and_position", SIM + BEAM + sub(BODY, "position = [0.5, 0.0, 0.0]",
                                                   "on_beam = 'rail', s = 0.5, position = [0,0,0]"),
     "rigid_bodies[sleeve].pose: give either { position, quaternion } or { on_beam, s, offset }"),
    ("unknown_shape", SIM + BODY + "shape = { type = 'sphere' }\n",
     "rigid_bodies[sleeve].shape.type: unknown shape type 'sphere' (known: cylinder, box, mesh)"),
    ("duplicate_name_same_kind", SIM + BEAM + BEAM,
     "beams[1].name: duplicate name 'rail' (also beams[0]); names must be unique"),
    # --- constraints
    ("constraint_unknown_beam", SIM + BEAM + "[[constraints]]\ntype = 'clamp'\nbeam = 'rial'\n"
                                             "node = 'first'\n",
     "constraints[0].beam: no beam named 'rial' (beams: rail)"),
    ("constraint_unknown_type", SIM + BEAM + "[[constraints]]\ntype = 'weld'\nbeam = 'rail'\n",
     "constraints[0].type: unknown constraint type 'weld' (known: clamp, pin, fix_body"),
    ("constraint_misspelt_type", SIM + BEAM + "[[constraints]]\ntyp = 'clamp'\nbeam = 'rail'\n",
     "unknown key 'typ' in constraints[0]; did you mean 'type'?"),
    ("constraint_bad_node", SIM + BEAM + "[[constraints]]\ntype = 'pin'\nbeam = 'rail'\n"
                                         "node = 9\n",
     "constraints[0].node: expected 'first', 'last' or a node index of beam 'rail' in 0..4, got 9"),
    ("constraint_node_word", SIM + BEAM + "[[constraints]]\ntype = 'pin'\nbeam = 'rail'\n"
                                          "node = 'end'\n",
     "constraints[0].node: expected 'first', 'last'"),
    ("constraint_key_of_other_type", SIM + BEAM + "[[constraints]]\ntype = 'clamp'\nbeam = 'rail'"
                                                  "\nnode = 0\naxis = [1, 0, 0]\n",
     "unknown key 'axis' in constraints[0]"),
    ("revolute_zero_axis", SIM + BODY + "[[constraints]]\ntype = 'revolute'\nbody = 'sleeve'\n"
                                        "point = [0, 0, 0]\naxis = [0, 0, 0]\n",
     "constraints[0].axis: expected a non-zero direction"),
    ("spherical_points_apart", SIM + BODY + "[[constraints]]\ntype = 'spherical'\nbody = 'sleeve'"
                                            "\nground_point = [0, 0, 0]\n",
     "constraints[0].ground_point: expected the same global point"),
    ("prescribed_bad_component", SIM + BEAM + "[[constraints]]\ntype = 'prescribed'\nbeam = 'rail'"
                                              "\nnode = 0\ncomponents = [7]\n",
     "constraints[0].components: expected a list of distinct indices in 0..5"),
    ("fix_body_unknown_body", SIM + BODY + "[[constraints]]\ntype = 'fix_body'\nbody = 'slv'\n",
     "constraints[0].body: no rigid body named 'slv' (rigid bodies: sleeve)"),
    # --- loads
    ("load_without_force", SIM + BEAM + "[[loads]]\ntype = 'point'\nbeam = 'rail'\nnode = 1\n",
     "loads[0].force: missing required key"),
    ("load_node_and_s", SIM + BEAM + "[[loads]]\ntype = 'point'\nbeam = 'rail'\nnode = 1\ns = 0.5"
                                     "\nforce = [0, 0, 1]\n",
     "loads[0]: give only one of 'node', 's'"),
    ("load_s_outside", SIM + BEAM + "[[loads]]\nname = 'f'\ntype = 'point'\nbeam = 'rail'\n"
                                    "s = 2.0\nforce = [0, 0, 1]\n",
     "loads[f].s: expected an arc length in [0, 1.0]"),
    ("load_moment_at_s", SIM + BEAM + "[[loads]]\ntype = 'point'\nbeam = 'rail'\ns = 0.5\n"
                                      "moment = [0, 0, 1]\n",
     "loads[0].moment: moments on a beam act at nodes only"),
    ("load_unknown_function", SIM + BEAM + "[[loads]]\ntype = 'distributed'\nbeam = 'rail'\n"
                                           "force = [0, 0, 1]\nfunction = { type = 'step' }\n",
     "loads[0].function.type: unknown time function 'step' (known: constant, ramp, half_sine"),
    ("ramp_end_before_start", SIM + BEAM + "[[loads]]\ntype = 'distributed'\nbeam = 'rail'\n"
                                           "force = [0, 0, 1]\nfunction = { type = 'ramp', "
                                           "start = 1.0, end = 0.5 }\n",
     "loads[0].function.end: expected a time > start = 1, got 0.5"),
    ("table_not_increasing", SIM + BEAM + "[[loads]]\ntype = 'distributed'\nbeam = 'rail'\n"
                                          "force = [0, 0, 1]\nfunction = { type = 'table', "
                                          "times = [0, 1, 1], values = [0, 1, 2] }\n",
     "loads[0].function.times: expected strictly increasing times"),
    ("moves_backwards", SIM + BEAM + "[[loads]]\ntype = 'distributed'\nbeam = 'rail'\n"
                                     "force = [0, 0, 1]\nfunction = { type = 'moves', "
                                     "moves = [[0, 0.4, 1], [0.6, 0.5, 1]] }\n",
     "loads[0].function.moves: expected move 1 ending after it starts (end > start = 0.6)"),
    ("moves_not_triples", SIM + BEAM + "[[loads]]\ntype = 'distributed'\nbeam = 'rail'\n"
                                      "force = [0, 0, 1]\nfunction = { type = 'moves', "
                                      "moves = [[0, 0.4]] }\n",
     "loads[0].function.moves: expected a non-empty list of [start, end, change]"),
    ("load_unknown_type", SIM + BEAM + "[[loads]]\ntype = 'pressure'\nbeam = 'rail'\n",
     "loads[0].type: unknown load type 'pressure' (known: point, distributed)"),
    # --- joints and probes
    ("joint_unknown_type", SIM + "[[joints]]\nname = 'j'\ntype = 'magic'\n",
     "joints[j].type: unknown joint type 'magic' (known: sliding, sliding_clearance, rope, tube)"),
    ("joint_missing_beam", SIM + "[[joints]]\nname = 'j'\ntype = 'sliding'\n",
     "joints[j].beam: missing required key"),
    ("joint_unknown_beam", SIM + BEAM + "[[joints]]\nname = 'j'\ntype = 'sliding'\nbeam = 'rial'\n",
     "joints[j].beam: no beam named 'rial' (beams: rail)"),
    ("probe_s_outside_beam", SIM + BEAM + "[[probes]]\nname = 'tip'\ntype = 'beam_point'\n"
                                          "beam = 'rail'\ns = 1.5\n",
     "probes[tip].s: expected an arc length in [0, 1.0] (length of beam 'rail', tolerance 1e-12), got 1.5"),
    ("probe_unknown_quantity", SIM + BEAM + "[[probes]]\nname = 'tip'\ntype = 'beam_point'\n"
                                            "beam = 'rail'\ns = 0.5\nquantity = 'strain'\n",
     "probes[tip].quantity: unknown quantity 'strain' (known: position, displacement, velocity, "
     "axial_strain, curvature)"),
    ("probe_missing_name", SIM + "[[probes]]\ntype = 'energy'\n",
     "probes[0].name: missing required key"),
    ("probe_unknown_type", SIM + "[[probes]]\nname = 'x'\ntype = 'stress'\n",
     "probes[x].type: unknown probe type 'stress' (known: beam_point"),
    ("probe_contact_force_without_joint", SIM + "[[probes]]\nname = 'x'\ntype = 'contact_force'\n"
                                          "joint = 'sleeve'\n",
     "probes[x].joint: no clearance joint named 'sleeve' (clearance joints: none)"),
    ("probe_name_with_comma", SIM + "[[probes]]\nname = 'a,b'\ntype = 'energy'\n",
     "probes[a,b].name: expected a probe name usable as a CSV column"),
]


@pytest.mark.parametrize("text, fragment", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_bad_scenario_is_rejected(tmp_path: Path, text: str, fragment: str) -> None:
    p = tmp_path / "bad.toml"
    p.write_text(text)
    with pytest.raises(ScenarioError) as info:
        load_scenario(p)
    msg = str(info.value)
    assert fragment in msg
    assert "\n" not in msg


def test_enough_distinct_cases() -> None:
    assert len({c[0] for c in CASES}) == len(CASES) >= 30


def test_missing_file_shows_relative_and_resolved_path(tmp_path: Path,
                                                       monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ScenarioError) as info:
        load_scenario("nope.toml")
    assert f"scenario file not found: nope.toml (resolved: {tmp_path / 'nope.toml'})" in str(info.value)


def test_missing_mesh_file_path_relative_to_scenario(tmp_path: Path,
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    (tmp_path / "scen").mkdir()
    p = tmp_path / "scen" / "s.toml"
    p.write_text(SIM + sub(BEAM, "{ line = { start = [0.0, 0.0, 0.0], end = [1.0, 0.0, 0.0] } }",
                           "{ mesh = '../meshes/arc.msh' }"))
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ScenarioError) as info:
        load_scenario(p)
    resolved = tmp_path / "meshes" / "arc.msh"
    assert (f"beams[rail].geometry.mesh: mesh file not found: {os.path.join('meshes', 'arc.msh')} "
            f"(resolved: {resolved})") in str(info.value)


def test_bad_override_is_reported_with_key_path(tmp_path: Path) -> None:
    p = tmp_path / "ok.toml"
    p.write_text(SIM + BEAM)
    with pytest.raises(ScenarioError, match=r"beams\[rail\]\.elements: expected an integer >= 1, "
                                            "got 'many'"):
        load_scenario(p, ["beams.rail.elements=many"])
    with pytest.raises(ScenarioError, match="unknown key 'radiuss' in beams\\[rail\\]; did you "
                                            "mean 'radius'"):
        load_scenario(p, ["beams.rail.radiuss=1e-3"])


@pytest.mark.parametrize("assignment, fragment", [
    ("probes.tip.s=0.5", "--set probes.tip.s=0.5: no entry 'tip' in probes (entries: none)"),
    ("loads.0.function=true", "loads[0].function: expected a number or a time function table"),
])
def test_override_targets(tmp_path: Path, assignment: str, fragment: str) -> None:
    p = tmp_path / "ok.toml"
    p.write_text(SIM + BEAM + "[[loads]]\ntype = 'distributed'\nbeam = 'rail'\nforce = [0, 0, 1]\n")
    with pytest.raises(ScenarioError) as info:
        load_scenario(p, [assignment])
    assert fragment in str(info.value)

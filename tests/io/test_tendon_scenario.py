"""``[[tendons]]`` in a scenario file: the keys reach the tendon, a run writes the tendon probes,
and every mistake is one line naming its key path."""

from __future__ import annotations

import csv

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.io.scenario import load_scenario

DISKS = "".join(f"""
[[rigid_bodies]]
name = "disk{k}"
mass = 4e-3
inertia = [2e-7, 1e-7, 1e-7]
pose = {{ position = [0.0, 0.0, {0.02 * k}], quaternion = [0.5, -0.5, -0.5, -0.5] }}
shape = {{ type = "cylinder", radius = 0.015, length = 0.002 }}

[[constraints]]
type = "fix_body"
body = "disk{k}"
""" for k in (1, 2, 3))

SCENARIO = """
name = "tendon"

[simulation]
t_end = 0.04
dt = 1e-3
output_interval = 0.01
rho_inf = 0.5
""" + DISKS + """
[[tendons]]
name = "t1"
route = [{ body = "disk1", point = [0.0, 0.01, 0.0] },
         { body = "disk2", point = [0.0, 0.0101, 0.0] },
         { body = "disk3", point = [0.0, 0.01, 0.0] }]
anchor = { body = "disk3", point = [0.003, 0.01, 0.0] }
lead = 0.02
radius = 8e-5
youngs_modulus = 2e11
density = 7850.0
clearance = 2e-5
damping = 1e-3
contact = { law = "linear", stiffness = 1e6 }
tension = { type = "ramp", end = 0.02, value = 2.0, smooth = true }

[[probes]]
name = "N"
type = "tendon_tension"
tendon = "t1"

[[probes]]
name = "pulled"
type = "tendon_displacement"
tendon = "t1"

[[probes]]
name = "F2"
type = "contact_force"
joint = "t1_hole2_disk2"

[[probes]]
name = "A"
type = "reaction"
constraint = "t1_anchor"
part = "disk3"
"""


def test_tendon_scenario_builds_and_runs(tmp_path):
    """The disks' body x is global z (quaternion), the tendon 10 mm off their axis, its middle
    hole 0.1 mm aside; run through the command line like any scenario: probes.csv has the
    tension at the actuator and the three holes (2 N at the end, the frictionless capstan),
    the pulled length, the middle hole's contact force and the anchor's reaction."""
    from flexmbs.cli import main

    path = tmp_path / "tendon.toml"
    path.write_text(SCENARIO)
    sc = load_scenario(path)
    np.testing.assert_allclose(sc.model.body("disk1").pose.rotation @ [1, 0, 0], [0, 0, 1],
                               atol=1e-15)
    beam = sc.model.beam("t1")
    assert [j.name for j in sc.model.interactions] == ["t1_hole1_disk1", "t1_hole2_disk2",
                                                       "t1_hole3_disk3"]
    assert [c.name for c in sc.model.constraints][-2:] == ["t1_anchor", "t1_hold"]
    assert [ld.name for ld in sc.model.loads] == ["t1_tension"]
    assert beam.stiffness.axial_stiffness == pytest.approx(2e11 * np.pi * 8e-5**2)
    assert beam.damping == 1e-3 and sc.model.interactions[0].hole.length == 1e-3
    assert sc.model.loads[0].function(0.01) == pytest.approx(1.0)
    out = tmp_path / "out"
    assert main(["run", str(path), "--out", str(out), "-q"]) == 0
    with open(out / "probes.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert list(rows[0])[:6] == ["t", "N_0", "N_1", "N_2", "N_3", "pulled"]
    last = {k: float(v) for k, v in rows[-1].items()}
    assert last["t"] == pytest.approx(0.04)
    for col in ("N_0", "N_1", "N_2", "N_3"):
        assert last[col] == pytest.approx(2.0, abs=1e-3), col
    assert last["pulled"] > 0.0
    assert abs(last["F2_x"]) > 1e-3
    assert np.hypot(last["A_fx"], last["A_fz"]) == pytest.approx(2.0, abs=1e-3)


@pytest.mark.parametrize("setting, message", [
    ("tendons.t1.route.1.point=[0.0, 0.01495, 0.0]",
     "tendons[t1].route[1].point: the hole (radius 0.0001 m) reaches 5e-05 m beyond body "
     "'disk2'"),
    ("tendons.t1.route.2.body=\"disk1\"",
     "tendons[t1].route[2].body: body 'disk1' is visited twice (route[0] and route[2])"),
    ("tendons.t1.anchor.point=[-0.003, 0.01, 0.0]",
     "tendons[t1].anchor.point: the anchor is 0.003 m behind the last hole"),
    ("tendons.t1.route.1.body=\"disk9\"", "tendons[t1].route[1].body: no rigid body named 'disk9'"),
    ("tendons.t1.route=[]", "tendons[t1].route: expected an array of at least one hole"),
    ("tendons.t1.pulled_length=1e-3", "tendons[t1]: give only one of 'tension', 'pulled_length'"),
    ("tendons.t1.clearance=0.0", "tendons[t1].clearance: expected a number > 0, got 0.0"),
    ("tendons.t1.lead=-0.02", "tendons[t1].lead: expected a number > 0"),
    ("tendons.t1.lead=0.0004", "tendons[t1].lead: 0.0004 m puts the wire's start inside"),
    ("tendons.t1.elements=2", "tendons[t1].elements: 2 is fewer than the route's 4 segments"),
    ("tendons.t1.contact={ law = \"hertz\" }", "tendons[t1].contact.stiffness: missing required"),
    ("tendons.t1.colour=1", "unknown key 'colour' in tendons[t1]"),
    ("probes.N.tendon=\"t9\"", "probes[N].tendon: no tendon named 't9' (tendons: t1)"),
])
def test_tendon_scenario_errors(tmp_path, setting, message):
    path = tmp_path / "tendon.toml"
    path.write_text(SCENARIO)
    with pytest.raises(fm.ScenarioError) as err:
        load_scenario(path, [setting])
    text = str(err.value)
    assert text.startswith(message) and "\n" not in text, text


def test_tendon_scenario_actuation(tmp_path):
    """Neither tension nor pulled_length: an error naming both; pulled_length alone: the hold's
    slide driver; a missing radius with an explicit section: the key."""
    path = tmp_path / "tendon.toml"
    path.write_text(SCENARIO.replace(
        'tension = { type = "ramp", end = 0.02, value = 2.0, smooth = true }', ""))
    with pytest.raises(fm.ScenarioError, match=r"^tendons\[t1\]: missing actuation: give "
                                               "tension"):
        load_scenario(path)
    sc = load_scenario(path, ["tendons.t1.pulled_length={ type = \"ramp\", end = 0.02, "
                              "value = 1e-5 }"])
    (driver,) = [c for c in sc.model.constraints if c.kind == "driver"]
    assert driver.name == "t1_pull" and driver.motion == "slide" and not sc.model.loads
    explicit = ["tendons.t1.pulled_length=1e-5", "tendons.t1.axial_stiffness=4e3",
                "tendons.t1.bending_stiffness=6e-6", "tendons.t1.mass_per_length=1.6e-4"]
    text = path.read_text()
    for k in ("radius", "youngs_modulus", "density"):
        text = "\n".join(line for line in text.splitlines() if not line.startswith(k + " ="))
    path.write_text(text)
    with pytest.raises(fm.ScenarioError, match=r"^tendons\[t1\]\.radius: missing required key"):
        load_scenario(path, explicit)
    sc = load_scenario(path, [*explicit, "tendons.t1.radius=8e-5"])
    assert sc.model.beam("t1").stiffness.axial_stiffness == 4e3

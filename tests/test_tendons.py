"""Tendons (flexmbs.tendons): the route's checks (one message per mistake), the expansion into a
wire, clearance joints, anchor, hold and actuator, and the wire's tension against the
frictionless capstan (constant tension) and the elastic wire (N = EA δ / L)."""

from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.assembly import Assembly
from flexmbs.tendons import sections_per_hole

#: body x = global z, body y = global x, body z = global y: disks whose axis (and holes) run
#: along the robot's z
AXIS_Z = np.column_stack([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
SPACING, DISK_R = 0.02, 0.015
STEEL = fm.Material(E=2e11, rho=7850.0)
WIRE_R, CLEARANCE = 8e-5, 2e-5
EA = 2e11 * math.pi * WIRE_R**2


def _disks(model: fm.Model, n: int = 3) -> list[fm.RigidBody]:
    """``n`` fixed disks (cylinders along body x = global z) at z = 20, 40, ... mm."""
    out = []
    for k in range(n):
        disk = model.add_rigid_body(mass=4e-3, inertia=(2e-7, 1e-7, 1e-7),
                                    pose=fm.Pose((0.0, 0.0, (k + 1) * SPACING), AXIS_Z),
                                    name=f"disk{k + 1}",
                                    shape={"type": "cylinder", "radius": DISK_R, "length": 2e-3})
        model.fix_body(disk, name=f"fix{k + 1}")
        out.append(disk)
    return out


def _tendon(disks: list[fm.RigidBody], name: str = "t1", offsets: tuple[float, ...] = (),
            **kw) -> fm.Tendon:
    """A tendon 10 mm off the axis (global x = 0.01 + offset), anchored 3 mm above the last
    disk, pulled by 2 N unless ``kw`` says otherwise."""
    offsets = offsets or (0.0,) * len(disks)
    args = dict(name=name, route=[(d, (0.0, 0.01 + o, 0.0)) for d, o in zip(disks, offsets,
                                                                             strict=True)],
                anchor=(disks[-1], (0.003, 0.01, 0.0)), lead=0.02, radius=WIRE_R,
                clearance=CLEARANCE, material=STEEL, contact=fm.LinearPenalty(stiffness=1e6),
                tension=2.0)
    args.update(kw)
    return fm.Tendon(**args)


# ------------------------------------------------------------------------------------ expansion
def test_a_straight_route_expands_to_a_straight_wire_and_named_parts():
    model = fm.Model()
    disks = _disks(model)
    parts = model.add_tendon(_tendon(disks))
    assert isinstance(parts, fm.TendonParts) and parts.name == "t1"
    assert [j.name for j in parts.holes] == ["t1_hole1_disk1", "t1_hole2_disk2", "t1_hole3_disk3"]
    assert [j.body for j in parts.holes] == disks and all(j.beam is parts.beam for j in parts.holes)
    assert (parts.anchor.name, parts.anchor.kind, parts.anchor.b) == ("t1_anchor", "spherical",
                                                                      disks[-1])
    assert (parts.hold.name, parts.hold.kind, parts.hold.translation) == ("t1_hold", "joint",
                                                                          (0, 1, 1))
    assert parts.actuator.name == "t1_tension" and parts.actuator in model.loads
    np.testing.assert_array_equal(parts.actuator.force, [0.0, 0.0, -2.0])
    beam = parts.beam
    assert beam.name == "t1" and model.beams == [beam] and beam.element == "ancf_cable"
    cl = beam.centerline
    # exactly straight: every tangent the route's direction, every node on the line
    assert np.all(cl.tangents == [0.0, 0.0, 1.0])
    assert np.all(cl.points[:, :2] == [0.01, 0.0])
    np.testing.assert_allclose(cl.points[[0, -1], 2], [0.0, 0.063], atol=1e-15)
    np.testing.assert_allclose(parts.start, [0.01, 0.0, 0.0], atol=1e-15)
    np.testing.assert_array_equal(parts.pull, [0.0, 0.0, -1.0])
    # the holes' axes along the route (turned into body coordinates), their points nodes;
    # default element length: half the mean segment (20, 20, 20, 20 and 3 mm: 9.3 mm)
    for j, disk in zip(parts.holes, disks, strict=True):
        np.testing.assert_allclose(disk.pose.rotation @ j.axis, [0.0, 0.0, 1.0], atol=1e-15)
        assert j.hole.section.radius == pytest.approx(WIRE_R + CLEARANCE)
        assert (j.hole.length, j.hole.sections) == (1e-3, 1)
        assert np.min(np.abs(cl.points[:, 2] - disk.pose.position[2])) < 1e-15
    assert beam.n_elem == 3 + 3 + 3 + 1 and beam.length == pytest.approx(0.063, rel=1e-14)


def test_a_turning_route_passes_every_hole_along_its_axis():
    """Holes off a straight line: the route's points are nodes with the hole axes (previous
    route point to the next) as slopes; the wire's first segment is straight, ``elements``
    total; a pulled_length makes a slide driver of the hold."""
    model = fm.Model()
    disks = _disks(model)
    parts = model.add_tendon(_tendon(disks, offsets=(0.0, 5e-4, 0.0), elements=12,
                                     tension=None, pulled_length=fm.Ramp(end=0.1, value=1e-5)))
    cl = parts.beam.centerline
    assert cl.n_elem == 12
    holes = np.array([d.pose.position + d.pose.rotation @ j.hole_point
                      for d, j in zip(disks, parts.holes, strict=True)])
    anchor = disks[-1].pose.position + disks[-1].pose.rotation @ [0.003, 0.01, 0.0]
    route = np.vstack([parts.start, holes, anchor])
    for k, (j, disk) in enumerate(zip(parts.holes, disks, strict=True)):
        axis = (route[k + 2] - route[k]) / np.linalg.norm(route[k + 2] - route[k])
        np.testing.assert_allclose(disk.pose.rotation @ j.axis, axis, atol=1e-15)
        node = int(np.argmin(np.linalg.norm(cl.points - holes[k], axis=1)))
        np.testing.assert_allclose(cl.points[node], holes[k], atol=1e-15)
        np.testing.assert_allclose(cl.tangents[node], axis, atol=1e-15)
    first = (holes[1] - holes[0]) / np.linalg.norm(holes[1] - holes[0])
    np.testing.assert_allclose(parts.start, holes[0] - 0.02 * first, atol=1e-15)
    np.testing.assert_allclose(parts.pull, -first, atol=1e-15)
    assert (parts.actuator.name, parts.actuator.kind, parts.actuator.motion) == ("t1_pull",
                                                                               "driver", "slide")
    assert not model.loads


def test_two_tendons_through_the_same_bodies_do_not_collide():
    model = fm.Model()
    disks = _disks(model)
    a = model.add_tendon(_tendon(disks, "t1"))
    b = model.add_tendon(_tendon(disks, "t2", route=[(d, (0.0, -0.01, 0.0)) for d in disks],
                                 anchor=(disks[-1], (0.003, -0.01, 0.0))))
    assert [j.name for j in b.holes] == ["t2_hole1_disk1", "t2_hole2_disk2", "t2_hole3_disk3"]
    assert len(model.interactions) == 6 and {a.beam.name, b.beam.name} == {"t1", "t2"}
    with pytest.raises(fm.ModelError, match="tendon 't1': the name 't1' of its parts is already "
                                            "used by the model's beams and rigid bodies"):
        model.add_tendon(_tendon(disks, "t1"))
    assert len(model.beams) == 2 and len(model.interactions) == 6    # nothing added


# ----------------------------------------------------------------------------------- the checks
def _error(make, match: str) -> None:
    """``make()`` raises one one-line ModelError matching ``match``."""
    with pytest.raises(fm.ModelError, match=match) as err:
        make()
    assert "\n" not in str(err.value), str(err.value)


def test_route_errors_name_the_key():
    """Each bad route is one line naming its key (tendon 't1': <key>: ...); nothing is built."""
    model = fm.Model()
    disks = _disks(model)
    d1, d2, d3 = disks
    loose = model.add_rigid_body(mass=1.0, inertia=(1, 1, 1), position=(0.0, 0.03, 0.04),
                                 name="loose")
    add = model.add_tendon
    _error(lambda: add(_tendon(disks, offsets=(0.0, 0.005 - 1e-5, 0.0))),
           r"tendon 't1': route\[1\]\.point: the hole \(radius 0\.0001 m\) reaches 9e-05 m "
           r"beyond body 'disk2' \(a cylinder of radius 0\.015 m")
    _error(lambda: add(_tendon(disks, route=[(d1, (0, 0.01, 0)), (d2, (0, 0.01, 0)),
                                             (d1, (0, 0.01, 0))])),
           r"route\[2\]\.body: body 'disk1' is visited twice \(route\[0\] and route\[2\]\)")
    _error(lambda: add(_tendon(disks, anchor=(d3, (-0.003, 0.01, 0.0)))),
           r"anchor\.point: the anchor is 0\.003 m behind the last hole \(route\[2\], body "
           r"'disk3'\)")
    _error(lambda: add(_tendon(disks, anchor=(d3, (0.0004, 0.01, 0.0)))),
           r"anchor\.point: the anchor is 0\.0004 m beyond the last hole's centre \(route\[2\]\), "
           "inside the hole")
    _error(lambda: add(_tendon(disks, lead=4e-4)),
           r"lead: 0\.0004 m puts the wire's start inside the first hole")
    _error(lambda: add(_tendon(disks, hole_length=0.05)),
           r"tendon 't1': lead: 0\.02 m puts the wire's start inside the first hole")
    _error(lambda: add(_tendon(disks, lead=0.1, hole_length=0.05)),
           r"hole_length: 0\.05 m: the hole of route\[0\] reaches past route\[1\]")
    _error(lambda: add(_tendon([d1, d2, loose], route=[(d1, (0, 0, 0)), (d2, (0, 0, 0)),
                                                       (loose, (0, 0, 0))],
                               anchor=(loose, (0, 0.01, 0)))),
           r"route\[1\]\.point: the route turns by 90\.0° at this hole \(body 'disk2'\)")
    _error(lambda: add(_tendon(disks, offsets=(0.0, 2e-3, 0.0), hole_length=5e-3)),
           r"route\[0\]\.point: the route bends so much at this hole that the wire leaves its "
           r"axis by [\d.e-]+ m within its length, more than the clearance 2e-05 m")
    _error(lambda: add(_tendon(disks, elements=3)), r"elements: 3 is fewer than the route's 4 "
                                                    "segments")
    other = fm.Model().add_rigid_body(mass=1.0, inertia=(1, 1, 1), name="elsewhere")
    _error(lambda: add(_tendon(disks, anchor=(other, (0, 0, 0)))),
           r"anchor\.body: RigidBody\('elsewhere'.*is not a rigid body of this model")
    assert not model.beams and not model.interactions and len(model.constraints) == 3


def test_spec_errors():
    model = fm.Model()
    disks = _disks(model)
    _error(lambda: _tendon(disks, route=[]), "tendon 't1': route must list at least one hole")
    _error(lambda: _tendon(disks, pulled_length=1e-3),
           "tendon 't1': give exactly one of tension")
    _error(lambda: _tendon(disks, tension=None), "tendon 't1': give exactly one of tension")
    for key in ("clearance", "lead", "radius"):
        _error(lambda key=key: _tendon(disks, **{key: 0.0}),
               f"tendon 't1': {key} must be a finite number > 0 \\(got 0.0\\)")
    _error(lambda: _tendon(disks, section=fm.BeamStiffness(axial_stiffness=1e3,
                                                          bending_stiffness=1e-6,
                                                          mass_per_length=1e-4)),
           "give the wire's material=Material")
    _error(lambda: _tendon(disks, route=[(disks[0], (0.0, 0.01))]),
           r"route\[0\] must be \(body, point\)")


def test_a_beam_node_joint_takes_a_slide_driver():
    """Model.add_driver accepts a generic joint of a beam node (x translation free) as a slide:
    to the ground (the tendon's pull) and to a turned body, whose axis turns with it. Reference:
    the assembled Phi_q and Phi_q^T lam tangent against central differences of the residual at
    a perturbed state with arbitrary multipliers."""
    model = fm.Model()
    beam = model.add_beam(fm.line((0, 0, 0), (1, 0, 0), elements=2),
                          section=fm.CircularSection(1e-3), material=STEEL)
    R = np.linalg.qr(np.array([[1.0, 0.3, -0.2], [0.1, 1.0, 0.4], [-0.3, 0.2, 1.0]]))[0]
    R *= np.sign(np.linalg.det(R))
    body = model.add_rigid_body(mass=1.0, inertia=(1e-2, 2e-2, 3e-2), pose=fm.Pose((1.0, 0.1, 0), R))
    hold = model.joint(beam.first_node, point=(0, 0, 0), axis=(-1, 0.2, 0), translation=(0, 1, 1))
    guide = model.joint(body, beam.last_node, point=(1, 0, 0), axis=(1, 1, 0), translation=(0, 0, 1))
    assert model.add_driver(hold, fm.Sine(amplitude=0.01, frequency=1.0)).motion == "slide"
    pushed = model.add_driver(guide, 0.02, motion="slide").a
    assert (pushed.beam, pushed.index) == (beam, beam.n_nodes - 1)      # the node is a
    with pytest.raises(fm.ModelError, match="a rotation driver needs"):
        model.add_driver(hold, 0.1, motion="rotation")
    asm = Assembly(model)
    rng = np.random.default_rng(5)
    q, v = asm.initial_state()
    q = q + 1e-2 * rng.standard_normal(q.size)
    n, m = asm.n_coords, asm.n_mult
    lam = rng.standard_normal(m)

    def res(qq: np.ndarray) -> np.ndarray:
        r_q, r_l = np.zeros(n), np.zeros(m)
        asm.evaluate(qq, v, None, lam, 0.3, r_q, r_l, with_damping=False)
        return np.concatenate([r_q, r_l])

    asm.evaluate(q, v, None, lam, 0.3, np.zeros(n), np.zeros(m), matrix=(0.0, 0.0, 1.0),
                 with_damping=False)
    A = asm.matrix.toarray()
    h = 1e-6
    Jfd = np.column_stack([(res(q + h * e) - res(q - h * e)) / (2 * h) for e in np.eye(n)])
    assert np.abs(A[:, :n] - Jfd).max() < 1e-6 * np.abs(Jfd).max()
    rows = [i for i, o in enumerate(asm.multiplier_owner) if o.startswith("driver")]
    assert len(rows) == 2 and np.abs(Jfd[n + np.array(rows)]).max() > 0.1


# ------------------------------------------------------------------------------------- physics
def _run(model: fm.Model, t_end: float = 0.05) -> tuple[Assembly, fm.Result]:
    asm = Assembly(model)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = fm.simulate(asm, t_end=t_end, dt=1e-3, output_interval=0.01,
                          integrator=fm.GeneralizedAlpha(rho_inf=0.5))
    return asm, res


def test_frictionless_tendon_carries_its_tension_through_every_hole():
    """Reference: a frictionless wire over supports keeps its tension (the capstan with μ = 0):
    in every span between actuator, holes and anchor N = T, and the anchor holds T. Three fixed disks, the
    middle hole 0.1 mm off the line (the wire bends over it: a contact force of T × the turn,
    ~0.02 N), T = 2 N ramped in over 20 ms, damped wire, state after 50 ms. Tolerance 2e-4 T:
    the bending of the wire over the hole edges (EI/T ~ (1.8 mm)²) changes N by ~ T φ² with the
    turn φ = 5e-3 rad (measured 3e-5 T); the penalty's penetration (~2e-8 m) changes nothing.
    The start moves by the wire's stretch T L/EA, within 1 % (the bent wire also straightens
    between the holes)."""
    model = fm.Model()
    disks = _disks(model)
    T = 2.0
    parts = model.add_tendon(_tendon(disks, offsets=(0.0, 1e-4, 0.0), damping=1e-3,
                                     tension=fm.Ramp(end=0.02, value=T, smooth=True)))
    asm, res = _run(model)
    st = res.final_state
    N = parts.axial_forces(asm, st.q)
    np.testing.assert_allclose(N, T, rtol=0, atol=2e-4 * T)
    assert np.linalg.norm(parts.holes[1].contact_force(st.q, st.v)) > 0.01
    force = res.reaction("t1_anchor", "disk3")[0][-1]
    assert np.linalg.norm(force) == pytest.approx(T, rel=2e-4)
    assert force[2] < -0.99 * T                                   # pulled down, towards the start
    assert parts.pulled(asm, st.q) == pytest.approx(T * 0.063 / EA, rel=1e-2)


def test_a_pulled_length_stretches_the_wire_elastically():
    """Reference: a straight wire fixed at its anchor and pulled by δ at its start has the
    strain δ/L, so N = EA δ/L everywhere (L = 63 mm, δ = 30 µm: N = 1.915 N), the driver's force
    too; the tendon_displacement is δ to rounding."""
    model = fm.Model()
    disks = _disks(model)
    delta, L = 3e-5, 0.063
    parts = model.add_tendon(_tendon(disks, tension=None, damping=1e-3,
                                     pulled_length=fm.Ramp(end=0.02, value=delta, smooth=True)))
    asm, res = _run(model)
    st = res.final_state
    assert parts.pulled(asm, st.q) == pytest.approx(delta, rel=1e-12)
    N = parts.axial_forces(asm, st.q)
    np.testing.assert_allclose(N, EA * delta / L, rtol=1e-4)
    pull = res.reaction("t1_pull")[0][-1]
    assert pull @ parts.pull == pytest.approx(EA * delta / L, rel=1e-4)


def test_sections_per_hole_follow_the_wire_elements():
    """One section where the hole is shorter than an element (several would support one cubic
    at nearly collinear stations), else about one per element length, end faces included."""
    assert sections_per_hole(1e-3, 7e-3) == 1
    assert sections_per_hole(10e-3, 5e-3) == 3
    assert sections_per_hole(12e-3, 5e-3) == 4
    model = fm.Model()
    disks = _disks(model)
    parts = model.add_tendon(dataclasses.replace(_tendon(disks), hole_length=4e-3,
                                                 element_length=1.5e-3))
    assert {j.hole.sections for j in parts.holes} == {4}

"""Consistent public names: hole classes, friction given the same way to both sliding joints."""

from __future__ import annotations

import flexmbs as fm


def _beam_and_body():
    model = fm.Model()
    beam = model.add_beam(fm.line((0, 0, 0), (1, 0, 0), elements=4),
                          section=fm.CircularSection(1e-3), material=fm.Material(E=1e9, rho=1e3))
    body = model.add_rigid_body(mass=0.1, inertia=(1e-5, 1e-5, 1e-5), pose=beam.frame_at(0.5))
    return beam, body


def test_holes_are_classes_with_the_scenario_keys():
    circle = fm.CircleHole(radius=2e-3, length=0.02, sections=3)
    sup = fm.SuperellipseHole(a=2e-3, b=3e-3, exponent=4.0, length=0.01)
    assert isinstance(circle, fm.Hole) and isinstance(circle, fm.CircleHole)
    assert isinstance(sup, fm.Hole) and sup.section.exponent == 4.0 and sup.sections == 9


def test_both_joints_take_friction_as_a_law_or_a_coefficient():
    beam, body = _beam_and_body()
    law = fm.RegularizedCoulomb(mu=0.3, eps_v=2e-3)
    a = fm.SlidingJoint(beam, body, friction=law)
    b = fm.SlidingJoint(beam, body, friction=0.3, friction_velocity=2e-3)
    assert a.friction == b.friction == fm.Friction(mu=0.3, law="regularised", velocity=2e-3)
    assert fm.SlidingJoint(beam, body, friction=0.3).friction == fm.Friction(mu=0.3, law="stick")
    assert fm.SlidingJoint(beam, body, friction=0.0).friction is None
    hole = fm.CircleHole(2e-3, 0.02, 3)
    c = fm.SlidingClearanceJoint(beam, body, hole=hole, friction=0.3, friction_velocity=2e-3)
    d = fm.SlidingClearanceJoint(beam, body, hole=hole, friction=law)
    assert c.friction == d.friction == fm.Friction(mu=0.3, law="regularised", velocity=2e-3)
    assert fm.SlidingClearanceJoint(beam, body, hole=hole, friction=0.3).friction \
        == fm.Friction(mu=0.3, law="stick")
    assert fm.SlidingClearanceJoint(beam, body, hole=hole, friction=0.0).friction is None

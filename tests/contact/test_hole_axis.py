"""A clearance joint's bore along a body direction other than x (``axis``): the same motion as
the default bore in a body turned instead; the section frame, the checks, the scenario key."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.contact.joint import hole_frame
from flexmbs.io.scenario import load_scenario

#: body axes (columns, global) taking body x to global y, body y to z, body z to x: what
#: hole_frame((0, 1, 0)) gives the turned bore's sections
TURN = np.column_stack([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])


def _model(turned_body: bool) -> tuple[fm.Model, fm.RigidBody, fm.SlidingClearanceJoint]:
    """A steel rod along global y (clamped, pinned), a sleeve with an isotropic inertia sliding
    and falling onto it through a superellipse bore (a and b differ: the section's turn about the
    axis matters). ``turned_body``: the body's axes turned (TURN), the bore along body x; else the
    body unturned, the bore along body y (``axis``)."""
    m = fm.Model(gravity=(0.0, 0.0, -9.81))
    beam = m.add_beam(fm.line((0, 0, 0), (0, 0.4, 0), elements=8), section=fm.CircularSection(1e-3),
                      material=fm.Material(E=2e11, rho=7800.0), damping=1e-4)
    m.clamp(beam.first_node)
    m.pin(beam.last_node)
    body = m.add_rigid_body(mass=0.05, inertia=(2e-6, 2e-6, 2e-6),
                            pose=fm.Pose((0.0, 0.2, 0.0), TURN if turned_body else np.eye(3)),
                            velocity=(0.0, 0.3, 0.05), name="sleeve")
    hole = fm.SuperellipseHole(a=1.6e-3, b=1.3e-3, exponent=4.0, length=0.02, sections=5)
    joint = m.add_joint(fm.SlidingClearanceJoint(
        beam, body, hole=hole, contact=fm.LinearPenalty(stiffness=1e5, damping=5.0),
        axis=(1.0, 0.0, 0.0) if turned_body else (0.0, 2.0, 0.0), name="sleeve_bore"))
    return m, body, joint


def test_a_bore_turned_by_axis_moves_as_the_body_turned_instead():
    """Reference: the same bore in space, once by ``axis`` = body y in an unturned body, once
    along body x of a body turned so that its x is global y (and the section's e_y, e_z the same
    global directions). With an isotropic inertia the two models are the same mechanical system:
    the sleeve's path and the contact forces agree to rounding over a run with impacts (the
    sleeve falls onto the rod, slides and bounces)."""
    runs = []
    for turned in (False, True):
        model, body, joint = _model(turned)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = fm.simulate(model, t_end=0.03, dt=1e-3, output_interval=1e-3)
        force = np.array([joint.contact_force(q, v) for q, v in zip(res.q, res.v, strict=True)])
        runs.append((res.body_position(body), force))
    (xa, fa), (xb, fb) = runs
    assert np.abs(fa).max() > 0.5                     # contact: the sleeve hit the rod
    assert np.abs(xa - xa[0]).max() > 5e-3            # and slid along it
    np.testing.assert_allclose(xa, xb, rtol=0, atol=1e-12)
    np.testing.assert_allclose(fa, fb, rtol=0, atol=1e-9 * np.abs(fa).max())


def test_hole_frame_and_the_sections():
    """Body x gives the identity (the default bore is unchanged bit for bit); any axis a proper
    orthonormal frame with the axis first; the sections' origins turn about ``hole_point``."""
    assert np.array_equal(hole_frame(np.array([1.0, 0.0, 0.0])), np.eye(3))
    for a in ([0.0, 1.0, 0.0], [0.3, -0.2, 0.9], [0.0, 0.0, -1.0], [-1.0, 0.0, 0.0]):
        a = np.array(a) / np.linalg.norm(a)
        F = hole_frame(a)
        np.testing.assert_allclose(F.T @ F, np.eye(3), atol=1e-15)
        assert np.linalg.det(F) == pytest.approx(1.0)
        np.testing.assert_allclose(F[:, 0], a, atol=1e-15)
    np.testing.assert_array_equal(hole_frame(np.array([0.0, 1.0, 0.0])), TURN)
    _, _, joint = _model(False)
    ns = len(joint.stations)
    np.testing.assert_allclose(joint.state.origins[:ns], joint.stations[:, None] * [0, 1, 0],
                               atol=1e-15)
    np.testing.assert_allclose(joint.state.axes[:ns], np.repeat(TURN[None], ns, axis=0))
    np.testing.assert_allclose(joint.axis, [0.0, 1.0, 0.0])


def test_axis_errors():
    model, body, _ = _model(False)
    beam = model.beams[0]
    hole = fm.CircleHole(radius=2e-3, length=0.02, sections=3)
    with pytest.raises(fm.ModelError, match=r"joint 'j': axis must be 3 finite numbers, not all "
                                            r"zero \(got \[0\.0, 0\.0, 0\.0\]\)"):
        fm.SlidingClearanceJoint(beam, body, hole=hole, axis=(0, 0, 0), name="j")
    path = fm.line((0, -0.01, 0), (0, 0.01, 0), elements=2)
    with pytest.raises(fm.ModelError, match="a bore along a path runs along its path"):
        fm.SlidingClearanceJoint(beam, body, hole=fm.CurvedBore(path, radius=2e-3, sections=5),
                                 axis=(0, 1, 0))
    # the bore along body x of the unturned body crosses the rod: it does not pass through
    with pytest.raises(fm.ModelError, match="does not pass through the hole"):
        model.add_joint(fm.SlidingClearanceJoint(beam, body, hole=hole, name="j2"))


SCENARIO = """
[simulation]
t_end = 0.01
dt = 1e-3

[[beams]]
name = "rod"
geometry = { line = { start = [0, 0, 0], end = [0, 0.4, 0] } }
elements = 8
radius = 1e-3
youngs_modulus = 2e11
density = 7800.0

[[rigid_bodies]]
name = "sleeve"
mass = 0.05
inertia = [2e-6, 2e-6, 2e-6]
pose = { position = [0.0, 0.2, 0.0] }

[[joints]]
name = "bore"
type = "sliding_clearance"
beam = "rod"
body = "sleeve"
axis = [0.0, 1.0, 0.0]
hole = { shape = "circle", radius = 2e-3, length = 0.02, sections = 3, point = [0.0, 0.001, 0.0] }
contact = { stiffness = 1e5 }
"""


def test_scenario_key_axis(tmp_path):
    """``[[joints]] axis`` reaches the joint (the bore turned about ``hole.point``); a zero axis
    and an axis with a curved bore are one-line errors naming the key."""
    path = tmp_path / "case.toml"
    path.write_text(SCENARIO)
    (joint,) = load_scenario(path).model.interactions
    np.testing.assert_allclose(joint.axis, [0.0, 1.0, 0.0])
    np.testing.assert_allclose(joint.state.origins[:3, 1], [-0.009, 0.001, 0.011], atol=1e-15)
    for setting, text in [
            ("joints.bore.axis=[0, 0, 0]", "joints[bore].axis: expected the hole's direction in "
                                           "body coordinates, not zero, got [0, 0, 0]"),
            ("joints.bore.hole={ radius = 2e-3, sections = 3, path = { line = { start = [0, -0.01, "
             "0], end = [0, 0.01, 0] } } }", "joints[bore].axis: turns a straight bore")]:
        with pytest.raises(fm.ScenarioError) as err:
            load_scenario(path, [setting])
        assert str(err.value).startswith(text) and "\n" not in str(err.value), str(err.value)

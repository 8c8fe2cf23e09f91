"""A beam at the mouth of an open bore (docs/design-notes.md, "The mouth of an open bore"): an end
section ignores a beam whose axis crosses its plane outside the wall (the beam outside the
mouth), and its law lets go as the axis nears the rim, ``w(δ) f(δ)`` with ``w = x²(3 − 2x)``,
``x = (r_b − δ)/(MOUTH_FADE r_b)`` (:func:`flexmbs.contact.laws.mouth_weight`). Before, a beam
whose axis slid in over the rim met a contact of a whole radius of penetration at once:
0 N with the axis 0.01 µm outside the wall, 499.99 N with it 0.01 µm inside (k = 1e6 N/m,
r_b = 0.5 mm).

Independent references: the penetration of a wire parallel to the bore's axis, ``δ = y + r_b − R``
(the wall's nearest point to a line parallel to the axis), the weight's definition and its
slope bound, central differences of the compiled residual (the exact tangent) and of the
contact's potential (the force is its gradient)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.assembly import Assembly
from flexmbs.contact.laws import MOUTH_FADE
from tests.conftest import assert_iteration_matrix_exact

STEEL = fm.Material(E=2e11, rho=7800.0)
R_W, BORE, K = 0.5e-3, 1e-3, 1e6
ELL = MOUTH_FADE * R_W


def _wire_at_mouth(y: float, friction: fm.Friction | None = None, damping: float = 0.0):
    """A wire parallel to the bore's axis at height ``y``, from 5 mm before the mouth (the
    plane x = 0 of the first of five sections, 0..40 mm, of a free rigid body's open bore) to
    5 mm inside; the tip sections off (the wire's end is not at issue)."""
    model = fm.Model(name="mouth", gravity=(0.0, 0.0, 0.0))
    wire = model.add_beam(fm.line((-0.005, y, 0.0), (0.005, y, 0.0), 4),
                          section=fm.CircularSection(R_W), material=STEEL, name="wire")
    tube = model.add_rigid_body(mass=1.0, inertia=(1e-3, 1e-3, 1e-3), name="tube",
                                position=(0.02, 0.0, 0.0))
    hole = fm.Hole(fm.CircleHole(BORE, 0.04).section, 0.04, 5, open_ends=True)
    joint = fm.SlidingClearanceJoint(wire, tube, hole=hole, friction=friction,
                                     contact=fm.LinearPenalty(stiffness=K, damping=damping),
                                     name="tube")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")       # the start inside the wall: meant
        model.add_joint(joint)
    asm = Assembly(model)
    joint.state.tip_on[:] = False
    return asm, wire, tube, joint


def _weight(delta: np.ndarray) -> np.ndarray:
    x = np.clip((R_W - delta) / ELL, 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


def test_the_axis_sliding_over_the_rim_meets_no_jump():
    """The wire's height stepped by 2 µm from well inside the bore to outside its wall: the
    mouth section's force is k δ w(δ) with δ from the geometry, to 1e-9 relative (unchanged,
    k δ, up to δ = (1 − MOUTH_FADE) r_b); 0 with the axis outside the wall; below 1e-9 N with it
    0.01 µm inside (before: 499.99 N); between samples it moves by no more than the weighted
    law's slope allows (k + 1.5 k r_b/ℓ per metre). The compiled residual puts the same force
    on the body."""
    dy = 2e-6
    heights = np.concatenate([np.arange(0.55e-3, 1.05e-3, dy), [BORE - 1e-11, BORE + 1e-11]])
    force, body = [], []
    asm, wire, tube, joint = _wire_at_mouth(0.0)
    n, m = asm.n_coords, asm.n_mult
    for y in heights:
        q = asm.q_ref.copy()
        for i in range(wire.n_nodes):
            q[asm.node_dofs(wire.node(i))[1]] += y
        rows = joint.output(asm, q, np.zeros(n), np.zeros(m), 0.0)
        assert {r["section"] for r in rows} <= {0}, rows
        force.append(sum(r["normal_force"] for r in rows))
        rq, rl = np.zeros(n), np.zeros(m)
        asm.evaluate(q, np.zeros(n), np.zeros(n), np.zeros(m), 0.0, rq, rl)
        body.append(float(np.linalg.norm(rq[asm.body_dofs(tube)[:3]])))
    force_, body_ = np.array(force), np.array(body)
    delta = np.where(heights < BORE, heights + R_W - BORE, 0.0)
    expected = K * np.clip(delta, 0.0, None) * _weight(delta)
    np.testing.assert_allclose(force_, expected, rtol=1e-9, atol=1e-9)
    unchanged = (delta > 0.0) & (delta <= (1.0 - MOUTH_FADE) * R_W)
    assert unchanged.sum() > 50
    np.testing.assert_allclose(force_[unchanged], K * delta[unchanged], rtol=1e-9)
    assert force_[-2] < 1e-9 and force_[-1] == 0.0        # 0.01 µm inside, outside the wall
    assert force_.max() > 0.2 * K * R_W                    # the mouth still holds the wire
    slope = K + 1.5 * K * R_W / ELL
    assert np.abs(np.diff(force_[:-2])).max() <= slope * dy
    np.testing.assert_allclose(body_, force_, rtol=1e-9, atol=1e-9 * force_.max())


@pytest.mark.parametrize("friction", [None, fm.Friction(mu=0.3)], ids=["frictionless", "stick"])
def test_the_tangent_is_exact_where_the_mouth_lets_go(friction, rng):
    """The axis 0.15 mm from the wall (δ = 0.7 r_b, inside the weight): the assembled iteration
    matrix against central differences of the compiled residual in the body's coordinates and
    the crossing elements', 1e-6 relative, with damping and random velocities."""
    y = BORE - 0.15e-3
    asm, wire, tube, joint = _wire_at_mouth(y, friction, damping=5.0)
    n = asm.n_coords
    v = 1e-3 * rng.standard_normal(n)
    rows = joint.output(asm, asm.q_ref, v, np.zeros(asm.n_mult), 0.0)
    assert rows and all(0.0 < _weight(np.array(-r["gap"])) < 1.0 for r in rows), rows
    dofs = asm.beam_dofs(wire)
    assert_iteration_matrix_exact(asm, asm.q_ref, v,
                                  np.concatenate([asm.body_dofs(tube), dofs[12:30]]))


def test_the_mouth_force_is_the_gradient_of_the_contact_energy():
    """Frictionless and undamped, at δ = 0.7 r_b: the contact's potential
    (:meth:`SlidingClearanceJoint.contact_energy`, the weighted law's integral) differenced as
    the wire moves by ±h in y gives the force on the wire in y, to 1e-6."""
    y = BORE - 0.15e-3
    asm, wire, tube, joint = _wire_at_mouth(y)
    n = asm.n_coords
    ys = [asm.node_dofs(wire.node(i))[1] for i in range(wire.n_nodes)]
    h = 1e-9

    def energy(s: float) -> float:
        q = asm.q_ref.copy()
        q[ys] += s
        return joint.contact_energy(q)

    force = -joint.contact_force(asm.q_ref, np.zeros(n))    # on the wire
    dE = (energy(h) - energy(-h)) / (2 * h)
    assert abs(force[1]) > 10.0
    assert abs(-dE - force[1]) <= 1e-6 * abs(force[1]), (-dE, force[1])

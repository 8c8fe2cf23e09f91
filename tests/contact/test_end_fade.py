"""A beam's end reaching a section of the bore (docs/design-notes.md, "A tip reaching a
section"): the section takes its contact in over FADE_LENGTH radii of the end past its plane
(``_detect.end_fade``), so the residual is continuous as a tip passes a section. Before, a tip
tilted towards the wall met a section already δ outside its circle and the section's force
started at k δ (1.61 N in the guide wire that stopped Newton at every step).

Independent references: the penalty law itself (the full force k δ once the end is ℓ past the
plane, none before it reaches the plane), the slope bound of the weight x²(3 − 2x) (its largest
slope 1.5/ℓ), and central differences of the compiled residual for the exact tangent."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.assembly import Assembly
from flexmbs.contact._detect import FADE_LENGTH
from tests.conftest import assert_iteration_matrix_exact

STEEL = fm.Material(E=2e11, rho=7800.0)
R_W, BORE, K = 0.5e-3, 1e-3, 1e6
TILT = 0.02          # the wire rises 0.6 mm over its 30 mm: 0.1 mm into the wall at x = 20 mm
ELL = FADE_LENGTH * R_W


#: a straight wire tilted by TILT whose last node is at x = 20 mm, the plane of the third of
#: five sections (0, 10, ..., 40 mm) of a free rigid body's straight open bore
TILTED = ((-0.01, 0.0, 0.0), (0.02, TILT * 0.03, 0.0), 12)


def _wire_in_bore(friction: fm.Friction | None = None, wire=TILTED):
    """The wire ``(start, end, elements)`` in the bore of a free rigid body (sections at
    0, 10, ..., 40 mm, open ends); the tip sections off."""
    start, end, elements = wire
    model = fm.Model(name="fade", gravity=(0.0, 0.0, 0.0))
    beam = model.add_beam(fm.line(start, end, elements), section=fm.CircularSection(R_W),
                          material=STEEL, name="wire")
    tube = model.add_rigid_body(mass=1.0, inertia=(1e-3, 1e-3, 1e-3), name="tube",
                                position=(0.02, 0.0, 0.0))
    hole = fm.Hole(fm.CircleHole(BORE, 0.04).section, 0.04, 5, open_ends=True)
    joint = fm.SlidingClearanceJoint(beam, tube, hole=hole, friction=friction,
                                     contact=fm.LinearPenalty(stiffness=K, damping=5.0),
                                     name="tube")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")       # the start inside the wall: meant
        model.add_joint(joint)
    asm = Assembly(model)
    joint.state.tip_on[:] = False             # the bore's sections only (the tips: in full)
    return asm, beam, tube, joint


def _assert_tangent_exact(asm, wire, tube, q, v) -> None:
    """The iteration matrix against central differences in the body's coordinates and the
    wire's last element's (whose end node the weight depends on)."""
    assert_iteration_matrix_exact(asm, q, v, np.concatenate([asm.body_dofs(tube),
                                                             asm.beam_dofs(wire)[-12:]]))


def _shifted(asm: Assembly, wire, s: float) -> np.ndarray:
    """The reference state with the wire moved by s along x."""
    q = asm.q_ref.copy()
    for i in range(wire.n_nodes):
        q[asm.node_dofs(wire.node(i))[0]] += s
    return q


def test_a_tip_passing_a_section_meets_no_jump():
    """The wire slid through the section plane in 2 µm steps: the section's force is the
    penalty k δ of the axis' penetration δ (about 0.1 mm) times the weight x²(3 − 2x) of the
    end's distance x ℓ past the plane (0 before it reaches the plane, 1 from ℓ on), to 1e-6
    (less in the first 8 µm, where the contact is the end point's);
    between two samples it changes by no more than the weight's steepest slope allows
    (1.5 k δ Δs/ℓ; before the weight it jumped by k δ at once). The compiled residual and the
    Python path give the same force on the body."""
    asm, wire, tube, joint = _wire_in_bore()
    n, m = asm.n_coords, asm.n_mult
    ds = 2e-6
    shifts = np.arange(-0.2e-3, 0.5e-3 + ds / 2, ds)
    python, compiled = [], []
    for s in shifts:
        q = _shifted(asm, wire, s)
        rows = joint.output(asm, q, np.zeros(n), np.zeros(m), 0.0)
        python.append(sum(r["normal_force"] for r in rows if r["section"] == 2))
        rq, rl = np.zeros(n), np.zeros(m)
        asm.evaluate(q, np.zeros(n), np.zeros(n), np.zeros(m), 0.0, rq, rl)
        compiled.append(float(np.linalg.norm(rq[asm.body_dofs(tube)[:3]])))
    force, body = np.array(python), np.array(compiled)
    # the penetration where the tilted axis crosses the plane x = 20 mm (y = TILT (30 mm − s)):
    # the wall point's distance to the axis, (R − y) cos θ, against the wire's radius
    delta = R_W - (BORE - TILT * (0.03 - shifts)) / np.sqrt(1.0 + TILT**2)
    x = np.clip(shifts / ELL, 0.0, 1.0)           # the end's distance past the plane, in ℓ
    expected = x * x * (3 - 2 * x) * K * delta
    # once the wall point's foot on the axis, (R − y) sin θ ≈ 8 µm ahead of the crossing, is on
    # the beam; before, the contact is the end point's (a smaller depth)
    on_beam = shifts > (BORE - TILT * 0.03) * TILT / np.sqrt(1.0 + TILT**2) + 1e-7
    np.testing.assert_allclose(force[on_beam], expected[on_beam], rtol=1e-6, atol=1e-9)
    assert np.all(force[~on_beam] <= expected[~on_beam] + 1e-12)
    full = K * delta[x > 0].max()
    assert 99.0 < full < 101.0
    assert np.abs(np.diff(force)).max() <= 1.5 * full * ds / ELL    # before: k δ at once
    # the body feels section 2 only (the others: inside the clearance)
    np.testing.assert_allclose(body, force, rtol=1e-9, atol=1e-9 * full)


@pytest.mark.parametrize("friction", [None, fm.Friction(mu=0.3)], ids=["frictionless", "stick"])
def test_the_tangent_is_exact_while_a_section_takes_a_tip_in(friction, rng):
    """Halfway through the weight (the end ℓ/2 past the plane), the assembled iteration
    matrix against central differences of the compiled residual in the body's coordinates
    and the last element's (whose end node the weight depends on): 1e-6 relative."""
    asm, wire, tube, joint = _wire_in_bore(friction)
    n, m = asm.n_coords, asm.n_mult
    q = _shifted(asm, wire, 0.5 * ELL)
    v = 1e-3 * rng.standard_normal(n)
    rows = joint.output(asm, q, v, np.zeros(m), 0.0)
    assert {r["section"] for r in rows} == {2}, rows
    _assert_tangent_exact(asm, wire, tube, q, v)


# a short wire tilted steeply (0.2) towards the wall, free in the bore between the sections at
# 10 and 30 mm, its end about to pass the plane at 20 mm: the wall point's foot on the axis
# lies about (R − y) sin θ ≈ 80 µm ahead of the crossing, past the end while the end is nearer
# the plane than that
STEEP = 0.2


STEEP_WIRE = ((0.015, 0.6e-3 - STEEP * 0.005, 0.0), (0.02, 0.6e-3, 0.0), 4)


def _steep_wire(friction: fm.Friction | None = None):
    return _wire_in_bore(friction, STEEP_WIRE)


def _end_contacts(asm, joint, q):
    n = asm.n_coords
    return [c for c in joint._contacts(q, np.zeros(n), False, False) if c[0] == 2]


def test_a_contact_past_the_end_stays_on_the_beam_and_is_continuous():
    """The detection keeps a contact on the beam (its stationary pair stops at the end point);
    the force kernel used to project the wall point again onto the cubic continued past the
    end, so the two decided the contact on different curves and the force jumped when the end
    point's sphere began to touch (k times the extension's depth; a Newton 2-cycle in the
    catheter trial). Now the kernel keeps ξ_P on the beam too: while the wall point's foot lies
    past the end, ξ_P = 1 (the end point) and the gap is the distance from it. Slid in 1 µm
    steps the section's force moves by no more than its Lipschitz bound
    (1.5 k δ_max Δs/ℓ for the weight, k Δs for the gap), and the compiled residual gives the
    Python path's force."""
    asm, wire, tube, joint = _steep_wire()
    n, m = asm.n_coords, asm.n_mult
    ds = 1e-6
    shifts = np.arange(0.0, 2.0 * ELL, ds)
    force, body, pinned = [], [], 0
    for s in shifts:
        q = _shifted(asm, wire, s)
        found = _end_contacts(asm, joint, q)
        pinned += any(c[4].xi == 1.0 for c in found)
        assert all(c[4].xi <= 1.0 for c in found)
        force.append(sum(c[4].f_n for c in found))
        rq, rl = np.zeros(n), np.zeros(m)
        asm.evaluate(q, np.zeros(n), np.zeros(n), np.zeros(m), 0.0, rq, rl)
        body.append(float(np.linalg.norm(rq[asm.body_dofs(tube)[:3]])))
    force_ = np.array(force)
    assert pinned > 10 and force_.max() > 10.0          # pinned contacts with real force
    delta_max = force_.max() / K + 0.0                   # w ≤ 1: k δ ≥ the force
    bound = 1.5 * K * 2 * delta_max * ds / ELL + K * ds
    assert np.abs(np.diff(force_)).max() <= bound, (np.abs(np.diff(force_)).max(), bound)
    np.testing.assert_allclose(body, force_, rtol=1e-9, atol=1e-9 * force_.max())


@pytest.mark.parametrize("friction", [None, fm.Friction(mu=0.3)], ids=["frictionless", "stick"])
def test_the_tangent_is_exact_at_a_contact_pinned_to_the_end(friction, rng):
    """A contact held at the end point (ξ_P = 1, the end 0.2 ℓ past the plane: the weight and
    the pinned point at once): the assembled iteration matrix against central differences of
    the compiled residual, 1e-6 relative, in the body's coordinates and the last element's."""
    asm, wire, tube, joint = _steep_wire(friction)
    n = asm.n_coords
    q = _shifted(asm, wire, 0.2 * ELL)
    found = _end_contacts(asm, joint, q)
    assert found and all(c[4].xi == 1.0 and 0.0 < c[4].fade < 1.0 for c in found), found
    _assert_tangent_exact(asm, wire, tube, q, 1e-3 * rng.standard_normal(n))

"""The superellipse bore on the compiled path (issue "non-circular bores, compiled"): its
boundary kernel against differences of itself (its detector against brute force:
tests/contact/test_sections.py), a round superellipse against the circle, and the exact
tangent through the shape interface against central differences of the residual."""

from __future__ import annotations

import math

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.assembly import Assembly
from flexmbs.contact.sections import (
    SHAPE_SUPERELLIPSE,
    superellipse_boundary,
)
from flexmbs.contact.shapes.detector import common_normal_points


@pytest.mark.parametrize("n", [2.0, 3.0, 4.0, 10.0])
def test_boundary_kernel_derivatives_and_wall(n):
    A, B = 3e-3, 2e-3
    Y, Yp, Ypp = np.empty(2), np.empty(2), np.empty(2)
    h = 1e-6
    for psi in np.linspace(0.05, 2 * np.pi, 23):
        superellipse_boundary(A, B, n, psi, Y, Yp, Ypp)
        y0, yp, ypp = Y.copy(), Yp.copy(), Ypp.copy()
        assert abs(abs(y0[0] / A) ** n + abs(y0[1] / B) ** n - 1.0) < 1e-12
        superellipse_boundary(A, B, n, psi + h, Y, Yp, Ypp)
        a1, b1 = Y.copy(), Yp.copy()
        superellipse_boundary(A, B, n, psi - h, Y, Yp, Ypp)
        assert np.allclose((a1 - Y) / (2 * h), yp, rtol=0, atol=1e-7 * A)
        # (n = 3: Y‴ jumps at the vertices, so the difference quotient is off by O(h A) there)
        assert np.allclose((b1 - Yp) / (2 * h), ypp, rtol=0, atol=1e-5 * A)


def _sleeve_model(hole: fm.Hole, tangent: str = "exact") -> tuple[fm.Model, object]:
    model = fm.Model(gravity=(0, 0, -9.81))
    beam = model.add_beam(fm.line((0, 0, 0), (1, 0, 0.2), elements=8), name="rail",
                          section=fm.CircularSection(2e-3), material=fm.Material(E=2.1e11, rho=7800))
    model.clamp(beam.first_node)
    model.clamp(beam.last_node)
    pose = beam.frame_at(0.5).shifted((0.0, 2e-4, -6e-4))
    sleeve = model.add_rigid_body(mass=0.2, inertia=(2e-5, 4e-5, 4e-5), pose=pose, name="sleeve")
    joint = model.add_joint(fm.SlidingClearanceJoint(
        beam, sleeve, hole=hole, tangent=tangent,
        contact=fm.LinearPenalty(stiffness=1e6, damping=10.0), friction=0.2))
    return model, joint


def _state(asm: Assembly, seed: int = 4) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    return (asm.q_ref + 1e-6 * rng.standard_normal(asm.n_coords),
            0.02 * rng.standard_normal(asm.n_coords))


def assert_same_as_the_circle(hole: fm.Hole, radius: float) -> None:
    """The sleeve on the compiled path with ``hole`` has the residual and matrix of the same
    sleeve with the circular bore of ``radius`` (closed-form quartic), to rounding."""
    out = []
    for h in (fm.CircleHole(radius, 0.04, 9), hole):
        model, joint = _sleeve_model(h)
        assert joint.compiled_form()
        asm = Assembly(model)
        q, v = _state(asm)
        rq, rl = np.zeros(asm.n_coords), np.zeros(asm.n_mult)
        asm.evaluate(q, v, np.zeros_like(q), np.zeros(asm.n_mult), 0.0, rq, rl,
                     matrix=(1.0, 0.1, 0.01))
        assert joint.output(asm, q, v, np.zeros(asm.n_mult), 0.0)
        out.append((rq.copy(), asm.matrix.toarray()))
    (r1, m1), (r2, m2) = out
    assert np.abs(r1 - r2).max() <= 1e-9 * np.abs(r1).max()
    assert np.abs(m1 - m2).max() <= 1e-9 * np.abs(m1).max()


def test_round_superellipse_is_the_circle():
    """n = 2, a = b = R: the generic compiled detector gives the circle's residual and matrix
    (closed-form quartic) to rounding."""
    assert_same_as_the_circle(fm.SuperellipseHole(2.5e-3, 2.5e-3, 2.0, 0.04, 9), 2.5e-3)


@pytest.mark.parametrize("angle", [0.0, 0.4])
def test_superellipse_tangent_equals_central_differences(angle):
    """A rounded-rectangular bore (n = 4, turned in the body or not) on the compiled path: the
    assembled matrix with the exact contact tangent (friction, damping) equals central
    differences of the residual."""
    model, joint = _sleeve_model(fm.SuperellipseHole(2.6e-3, 2.3e-3, 4.0, 0.04, 5, angle=angle))
    asm = Assembly(model)
    q, v = _state(asm)
    assert joint.output(asm, q, v, np.zeros(asm.n_mult), 0.0), "the bore must touch the beam"
    assert_tangent_is_the_differences(asm, q, v)


def assert_tangent_is_the_differences(asm: Assembly, q: np.ndarray, v: np.ndarray) -> None:
    """The assembled matrix ``cK ∂r/∂q + cC ∂r/∂v`` (the exact contact tangent with friction and
    damping) equals central differences of the residual along ``cK e_j, cC e_j`` (2e-6 of
    its largest entry)."""
    n, m = asm.n_coords, asm.n_mult
    lam, qdd = np.zeros(m), np.zeros(n)
    cK, cC = 1.0, 0.3

    def res(q_: np.ndarray, v_: np.ndarray) -> np.ndarray:
        rq, rl = np.zeros(n), np.zeros(m)
        asm.evaluate(q_, v_, qdd, lam, 0.0, rq, rl)
        return rq

    asm.evaluate(q, v, qdd, lam, 0.0, np.zeros(n), np.zeros(m), matrix=(0.0, cC, cK))
    A = asm.matrix.toarray()[:n, :n]
    step = 1e-8
    fd = np.zeros((n, n))
    for j in range(n):
        e = np.zeros(n)
        e[j] = step
        fd[:, j] = (res(q + cK * e, v + cC * e) - res(q - cK * e, v - cC * e)) / (2 * step)
    assert np.abs(A - fd).max() <= 2e-6 * np.abs(fd).max()


def test_turned_section_detects_the_turned_points():
    """Turning the section and the ellipse together by β turns the detected wall points by β
    and leaves the kinds and depths alone (the orientation is a rigid rotation)."""
    params0 = np.array([3e-3, 2e-3, 6.0, 0.0])
    beta = 0.9
    params1 = np.array([3e-3, 2e-3, 6.0, beta])
    c = np.array([3e-4, -2e-4])
    ea = np.array([math.cos(0.3), math.sin(0.3)])
    rot = np.array([[math.cos(beta), -math.sin(beta)], [math.sin(beta), math.cos(beta)]])
    out = []
    for params, cc, e in ((params0, c, ea), (params1, rot @ c, rot @ ea)):
        psi, phi, kind, depth = np.empty(16), np.empty(16), np.empty(16, np.int64), np.empty(16)
        m = common_normal_points(SHAPE_SUPERELLIPSE, params, cc[0], cc[1], e[0], e[1], 2.2e-3,
                                 1.6e-3, 128, psi, phi, kind, depth)
        out.append(sorted(((psi[i] - params[3]) % (2 * np.pi), int(kind[i]), depth[i])
                          for i in range(m)))
    assert len(out[0]) == len(out[1]) > 0
    for (p0, k0, d0), (p1, k1, d1) in zip(out[0], out[1], strict=True):
        assert k0 == k1
        assert abs(p0 - p1) < 1e-9 and abs(d0 - d1) < 1e-12


def test_a_beam_outside_a_non_circular_bore_is_refused_at_the_start():
    """The start check asks the shape: an axis 2.8 mm above the centre of a 2.5 mm rounded
    square (n = 8) lies inside its bounding circle (3.24 mm) but outside the bore."""
    model = fm.Model()
    beam = model.add_beam(fm.line((0, 0, 0), (1, 0, 0), elements=4),
                          section=fm.CircularSection(5e-4), material=fm.Material(E=2e11, rho=7800))
    body = model.add_rigid_body(mass=1.0, inertia=(1, 1, 1),
                                pose=beam.frame_at(0.5).shifted((0, 0, 2.8e-3)))
    joint = fm.SlidingClearanceJoint(beam, body,
                                     hole=fm.SuperellipseHole(2.5e-3, 2.5e-3, 8.0, 0.02, 3))
    with pytest.raises(fm.ModelError, match="does not pass through the hole"):
        model.add_joint(joint)

"""The rounded-rectangle bore (contact/shapes/rounded_rectangle.py), added as docs/extending.md
says a hole shape is added: one module and a branch in each of the two dispatchers.

Independent references: its own wall equation (the signed distance of a rounded rectangle,
written here from the geometry) and differences of its kernel; brute force (the deepest point
of a densely sampled section ellipse outside the wall is the deepest contact the compiled
detector finds); the circle's closed-form quartic (w = h = r = R is the circle); central
differences of the assembled residual (the exact tangent through the shape interface)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.assembly import Assembly
from flexmbs.contact.sections import get_section
from flexmbs.contact.shapes import (
    SHAPE_ROUNDED_RECTANGLE,
    Ellipse2D,
    section_boundary,
)
from flexmbs.contact.shapes.detector import common_normal_points
from flexmbs.errors import ModelError
from tests.contact.test_superellipse_compiled import (
    _sleeve_model,
    _state,
    assert_same_as_the_circle,
    assert_tangent_is_the_differences,
)

W, H, R = 2.6e-3, 2.1e-3, 0.8e-3


def _signed_distance(w: float, h: float, r: float, y: float, z: float) -> float:
    """Signed distance of (y, z) from the wall of the rounded rectangle (> 0 outside)."""
    dy, dz = abs(y) - (w - r), abs(z) - (h - r)
    if dy > 0 and dz > 0:
        return math.hypot(dy, dz) - r
    return max(abs(y) - w, abs(z) - h)


def _wall(params: np.ndarray, psi: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    Y, Yp, Ypp = np.empty(2), np.empty(2), np.empty(2)
    section_boundary(SHAPE_ROUNDED_RECTANGLE, params, psi, Y, Yp, Ypp)
    return Y, Yp, Ypp


@pytest.mark.parametrize("angle", [0.0, 0.5])
def test_the_kernel_lies_on_the_wall_and_its_derivatives_are_its_differences(angle):
    """Every point on the wall (the signed distance, turned back, is 0 to rounding), the
    speed the perimeter over 2π, Y′ and Y″ central differences of Y and Y′ away from the eight
    joints of flats and corners, and the curve closed and C¹ at ψ = 0 ≡ 2π."""
    params = np.array([W, H, R, angle])
    P = 4 * (W - R) + 4 * (H - R) + 2 * math.pi * R
    ca, sa = math.cos(angle), math.sin(angle)
    d = 1e-7
    checked = 0
    for psi in np.linspace(0.01, 2 * math.pi - 0.01, 157):
        Y, Yp, Ypp = _wall(params, psi)
        y, z = ca * Y[0] + sa * Y[1], -sa * Y[0] + ca * Y[1]
        assert abs(_signed_distance(W, H, R, y, z)) < 1e-15
        assert np.hypot(*Yp) == pytest.approx(P / (2 * math.pi), rel=1e-12)
        (Ym, Ypm, Yppm), (Yq, Ypq, Yppq) = _wall(params, psi - d), _wall(params, psi + d)
        assert np.allclose((Yq - Ym) / (2 * d), Yp, rtol=0, atol=1e-8)
        if np.allclose(Yppm, Yppq, rtol=0, atol=1e-3 * np.hypot(*Yp) ** 2 / R):
            # (both sides on one piece: the curvature does not jump between them)
            assert np.allclose((Ypq - Ypm) / (2 * d), Ypp, rtol=0, atol=1e-8)
            checked += 1
    assert checked > 140
    Y0, Yp0, _ = _wall(params, 0.0)
    Y1, Yp1, _ = _wall(params, 2 * math.pi - 1e-12)
    assert np.allclose(Y0, Y1, atol=1e-14) and np.allclose(Yp0, Yp1, atol=1e-12)
    sec = get_section("rounded_rectangle", w=W, h=H, r=R, angle=angle)
    assert sec.inscribed_radius() == min(W, H)
    Yall = sec.boundary(np.linspace(0, 2 * math.pi, 2000, endpoint=False))[0]
    assert np.hypot(Yall[:, 0], Yall[:, 1]).max() <= sec.bounding_radius()


def test_the_deepest_contact_is_the_deepest_point_of_the_ellipse():
    """Random beam-section ellipses pressed into the section (flats, corners, both): the
    compiled generic detector's deepest maximum equals the deepest of 20 000 ellipse points
    outside the wall (its signed distance), to 1e-9 m."""
    params = np.array([W, H, R, 0.3])
    ca, sa = math.cos(0.3), math.sin(0.3)
    rng = np.random.default_rng(3)
    phi = np.linspace(0.0, 2 * math.pi, 20000, endpoint=False)
    tested = 0
    for _ in range(40):
        c = rng.uniform(-1.5e-3, 1.5e-3, size=2)
        ang = rng.uniform(0, math.pi)
        ell = Ellipse2D(c, np.array([math.cos(ang), math.sin(ang)]), 1.2e-3, 0.9e-3)
        X = ell.point(phi)
        y, z = ca * X[:, 0] + sa * X[:, 1], -sa * X[:, 0] + ca * X[:, 1]
        brute = max(_signed_distance(W, H, R, a, b) for a, b in zip(y, z, strict=True))
        psi, ph, kind, depth = np.empty(16), np.empty(16), np.empty(16, np.int64), np.empty(16)
        m = common_normal_points(SHAPE_ROUNDED_RECTANGLE, params, c[0], c[1], ell.e_a[0],
                                 ell.e_a[1], ell.a, ell.b, 128, psi, ph, kind, depth)
        found = max((depth[i] for i in range(m) if kind[i] > 0), default=-np.inf)
        if brute > 0.0:
            tested += 1
            assert found == pytest.approx(brute, abs=1e-9), (c, ang, found, brute)
    assert tested >= 10


def test_a_round_rounded_rectangle_is_the_circle():
    """w = h = r = R: the generic compiled detector on this shape gives the circle's residual
    and matrix (the closed-form quartic) to rounding."""
    Rb = 2.5e-3
    square = get_section("rounded_rectangle", w=Rb, h=Rb, r=Rb)
    assert_same_as_the_circle(fm.Hole(square, 0.04, 9), Rb)


@pytest.mark.parametrize(("w", "h", "r", "angle", "where"), [
    (2.6e-3, 2.25e-3, 0.6e-3, 0.2, "flat"),
    (2.45e-3, 2.45e-3, 2.2e-3, 1.02, "corner"),
    (2.2e-3, 2.2e-3, 1.4e-3, 1.02, "straddled"),
])
def test_rounded_rectangle_tangent_equals_central_differences(w, h, r, angle, where):
    """The rail pressing a flat, a corner (r larger than the rail: one maximum on the arc), or
    a corner it straddles (r smaller: a maximum on each flat and a minimum on the arc): the
    assembled matrix with the exact contact tangent (friction, damping) equals central
    differences of the residual."""
    params = np.array([w, h, r, angle])
    hole = fm.Hole(get_section("rounded_rectangle", w=w, h=h, r=r, angle=angle), 0.04, 5)
    model, joint = _sleeve_model(hole)
    asm = Assembly(model)
    q, v = _state(asm)
    rows = joint._rows[:joint.detect_rows(q)]
    on_corner = []
    for row in rows:
        _, Yp, Ypp = _wall(params, row[11])
        on_corner.append((int(row[2]), bool(np.hypot(*Ypp) > 0.0)))
    expected = {"flat": {(1, False)}, "corner": {(1, True)},
                "straddled": {(1, False), (-1, True)}}[where]
    assert set(on_corner) == expected, on_corner
    assert joint.output(asm, q, v, np.zeros(asm.n_mult), 0.0), "the bore must touch the beam"
    assert_tangent_is_the_differences(asm, q, v)


def test_bad_parameters_are_one_line_errors_and_the_scenario_reads_the_shape():
    with pytest.raises(ModelError, match="corner radius r = 0.003 is larger"):
        get_section("rounded_rectangle", w=2e-3, h=4e-3, r=3e-3)
    with pytest.raises(ModelError, match="too small for the detector's 128 wall samples.*r >= "):
        get_section("rounded_rectangle", w=5e-3, h=5e-3, r=1e-4)
    with pytest.raises(ModelError, match="h must be a number > 0"):
        get_section("rounded_rectangle", w=5e-3, h=-1.0, r=1e-4)
    from pathlib import Path

    from flexmbs.io.scenario import load_scenario

    example = Path(__file__).resolve().parents[2] / "examples" / "rounded_slot_carriage.toml"
    sc = load_scenario(example, [
        'joints.slot.hole={ shape = "rounded_rectangle", w = 4e-3, h = 2.6e-3, r = 1e-3, '
        'length = 0.04, sections = 9 }'])
    joint = next(j for j in sc.model.interactions if getattr(j, "name", "") == "slot")
    assert joint.hole.section.compiled_shape()[0] == SHAPE_ROUNDED_RECTANGLE
    assert joint.compiled_form()

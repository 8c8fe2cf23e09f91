"""The rounded regular polygon bore (contact/shapes/rounded_polygon.py), added as
docs/extending.md says a hole shape is added (issue 54, item 8).

Independent references: its wall in closed form (the distance to the regular polygon of apothem
a − r, written here from its vertices, minus r) and differences of its kernel; brute force (the
deepest point of a densely sampled section ellipse outside the wall is the deepest contact the
compiled detector finds); the circle's closed-form quartic (r = apothem is the circle); central
differences of the assembled residual (the exact tangent through the shape interface); a beam
pressed into a hexagonal bore, whose contact normal is the flat's."""

from __future__ import annotations

import math

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.assembly import Assembly
from flexmbs.contact.sections import get_section
from flexmbs.contact.shapes import SHAPE_ROUNDED_POLYGON, Ellipse2D, section_boundary, section_contains
from flexmbs.contact.shapes.detector import common_normal_points
from flexmbs.contact.shapes.rounded_polygon import smallest_corner_radius
from flexmbs.errors import ModelError
from tests.contact.test_superellipse_compiled import (
    _sleeve_model,
    _state,
    assert_same_as_the_circle,
    assert_tangent_is_the_differences,
)
from tests.test_codes import _polygon_distance

N, A, R = 6, 2.6e-3, 0.8e-3


def _signed_distance(n: int, a: float, r: float, angle: float, y: float, z: float) -> float:
    """Signed distance of (y, z) from the wall (> 0 outside; near the wall, outside the inner
    polygon): the point turned back by ``angle``, its distance from the inner polygon, less r."""
    c, s = math.cos(angle), math.sin(angle)
    return _polygon_distance(n, a - r, c * y + s * z, -s * y + c * z) - r


def _wall(params: np.ndarray, psi: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    Y, Yp, Ypp = np.empty(2), np.empty(2), np.empty(2)
    section_boundary(SHAPE_ROUNDED_POLYGON, params, psi, Y, Yp, Ypp)
    return Y, Yp, Ypp


@pytest.mark.parametrize(("n", "angle"), [(6, 0.0), (3, 0.5), (5, -1.0)])
def test_the_kernel_lies_on_the_wall_and_its_derivatives_are_its_differences(n, angle):
    """Every point on the wall (its closed-form distance 0 to rounding), the speed the
    perimeter over 2π, Y′ and Y″ central differences of Y and Y′ away from the joints of flats
    and corners, the curve closed and C¹ at ψ = 0 ≡ 2π, the inside test agreeing with the wall,
    and the bounding and inscribed radii bounding it."""
    r = max(R, 1.01 * smallest_corner_radius(n, A))
    params = np.array([n, A, r, angle])
    P = 2 * n * (A - r) * math.tan(math.pi / n) + 2 * math.pi * r
    d = 1e-7
    checked = 0
    for psi in np.linspace(0.01, 2 * math.pi - 0.01, 157):
        Y, Yp, Ypp = _wall(params, psi)
        assert abs(_signed_distance(n, A, r, angle, *Y)) < 1e-15
        assert section_contains(SHAPE_ROUNDED_POLYGON, params, *(Y * (1 - 1e-9)))
        assert not section_contains(SHAPE_ROUNDED_POLYGON, params, *(Y * (1 + 1e-9)))
        assert np.hypot(*Yp) == pytest.approx(P / (2 * math.pi), rel=1e-12)
        (Ym, Ypm, Yppm), (Yq, Ypq, Yppq) = _wall(params, psi - d), _wall(params, psi + d)
        assert np.allclose((Yq - Ym) / (2 * d), Yp, rtol=0, atol=1e-8)
        if np.allclose(Yppm, Yppq, rtol=0, atol=1e-3 * np.hypot(*Yp) ** 2 / r):
            assert np.allclose((Ypq - Ypm) / (2 * d), Ypp, rtol=0, atol=1e-8)
            checked += 1
    assert checked > 140
    Y0, Yp0, _ = _wall(params, 0.0)
    Y1, Yp1, _ = _wall(params, 2 * math.pi - 1e-12)
    assert np.allclose(Y0, Y1, atol=1e-14) and np.allclose(Yp0, Yp1, atol=1e-12)
    assert np.allclose(Y0, A * np.array([math.cos(angle), math.sin(angle)]), atol=1e-15)
    sec = get_section("rounded_polygon", sides=n, apothem=A, r=r, angle=angle)
    assert sec.inscribed_radius() == A
    Yall = sec.boundary(np.linspace(0, 2 * math.pi, 2000, endpoint=False))[0]
    radii = np.hypot(Yall[:, 0], Yall[:, 1])
    assert radii.min() >= A * (1 - 1e-12) and radii.max() <= sec.bounding_radius()
    assert radii.max() > sec.bounding_radius() * (1 - 1e-4)


def test_the_deepest_contact_is_the_deepest_point_of_the_ellipse():
    """Random beam-section ellipses pressed into a turned hexagon (flats, corners, both): the
    compiled generic detector's deepest maximum equals the deepest of 20 000 ellipse points
    outside the wall (its closed-form distance), to 1e-9 m."""
    params = np.array([N, A, R, 0.3])
    rng = np.random.default_rng(3)
    phi = np.linspace(0.0, 2 * math.pi, 20000, endpoint=False)
    tested = 0
    for _ in range(60):
        c = rng.uniform(-2e-3, 2e-3, size=2)
        if not section_contains(SHAPE_ROUNDED_POLYGON, params, *(c * 1.2)):
            continue     # (the beam's axis well inside the bore)
        ang = rng.uniform(0, math.pi)
        ell = Ellipse2D(c, np.array([math.cos(ang), math.sin(ang)]), 1.2e-3, 0.9e-3)
        X = ell.point(phi)
        outside = [x for x in X if not section_contains(SHAPE_ROUNDED_POLYGON, params, *x)]
        brute = max((_signed_distance(N, A, R, 0.3, *x) for x in outside), default=-np.inf)
        psi, ph, kind, depth = np.empty(16), np.empty(16), np.empty(16, np.int64), np.empty(16)
        m = common_normal_points(SHAPE_ROUNDED_POLYGON, params, c[0], c[1], ell.e_a[0],
                                 ell.e_a[1], ell.a, ell.b, 128, psi, ph, kind, depth)
        found = max((depth[i] for i in range(m) if kind[i] > 0), default=-np.inf)
        if brute > 0.0:
            tested += 1
            assert found == pytest.approx(brute, abs=1e-9), (c, ang, found, brute)
    assert tested >= 10


def test_a_polygon_rounded_to_its_apothem_is_the_circle():
    """r = apothem = R: the generic compiled detector on this shape gives the circle's residual
    and matrix (the closed-form quartic) to rounding."""
    Rb = 2.5e-3
    assert_same_as_the_circle(fm.Hole(get_section("rounded_polygon", sides=6, apothem=Rb, r=Rb),
                                      0.04, 9), Rb)


@pytest.mark.parametrize(("n", "a", "r", "angle", "where"), [
    (6, 2.45e-3, 0.6e-3, 1.8925, "flat"),
    (6, 2.45e-3, 2.2e-3, 0.321, "corner"),
    (6, 2.3e-3, 1.5e-3, 1.22, "straddled"),
])
def test_rounded_polygon_tangent_equals_central_differences(n, a, r, angle, where):
    """The rail pressing a flat, a corner (r larger than the rail: one maximum on the arc) or
    a corner it straddles (r smaller: a maximum on a flat and a minimum on the arc) of a
    hexagonal bore: the assembled matrix with the exact contact tangent (friction, damping)
    equals central differences of the residual."""
    params = np.array([n, a, r, angle])
    hole = fm.Hole(get_section("rounded_polygon", sides=n, apothem=a, r=r, angle=angle), 0.04, 5)
    model, joint = _sleeve_model(hole)
    asm = Assembly(model)
    q, v = _state(asm)
    rows = joint._rows[:joint.detect_rows(q)]
    on_corner = set()
    for row in rows:
        _, _Yp, Ypp = _wall(params, row[11])
        on_corner.add((int(row[2]), bool(np.hypot(*Ypp) > 0.0)))
    expected = {"flat": {(1, False)}, "corner": {(1, True)},
                "straddled": {(1, False), (-1, True)}}[where]
    assert on_corner == expected, on_corner
    assert joint.output(asm, q, v, np.zeros(asm.n_mult), 0.0), "the bore must touch the beam"
    assert_tangent_is_the_differences(asm, q, v)


def test_bad_parameters_are_one_line_errors_and_the_scenario_reads_the_shape():
    with pytest.raises(ModelError, match="corner radius r = 0.003 is larger than the apothem"):
        get_section("rounded_polygon", sides=6, apothem=2e-3, r=3e-3)
    with pytest.raises(ModelError, match="too small for the detector's 128 wall samples.*r >= "):
        get_section("rounded_polygon", sides=6, apothem=5e-3, r=1e-5)
    with pytest.raises(ModelError, match=r"^RoundedPolygonSection: sides must be an integer >= 3 "
                       r"\(got 2\)$"):
        get_section("rounded_polygon", sides=2, apothem=5e-3, r=1e-3)
    with pytest.raises(ModelError, match="apothem must be a number > 0"):
        get_section("rounded_polygon", sides=6, apothem=-1.0, r=1e-3)
    from pathlib import Path

    from flexmbs.errors import ScenarioError
    from flexmbs.io.scenario import load_scenario

    example = Path(__file__).resolve().parents[2] / "examples" / "rounded_slot_carriage.toml"
    sc = load_scenario(example, [
        'joints.slot.hole={ shape = "rounded_polygon", sides = 6, apothem = 3e-3, r = 1e-3, '
        'length = 0.04, sections = 9 }'])
    joint = next(j for j in sc.model.interactions if getattr(j, "name", "") == "slot")
    assert joint.hole.section.compiled_shape()[0] == SHAPE_ROUNDED_POLYGON
    assert joint.compiled_form()
    with pytest.raises(ScenarioError, match=r"^joints\[slot\]\.hole: RoundedPolygonSection: the "
                       r"corner radius r = 0.004 is larger than the apothem"):
        load_scenario(example, ['joints.slot.hole={ shape = "rounded_polygon", sides = 6, '
                                'apothem = 3e-3, r = 4e-3, length = 0.04, sections = 9 }'])

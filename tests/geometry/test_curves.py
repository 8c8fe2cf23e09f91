"""Centreline construction: Bessel tangents, arcs, Hermite element lengths, resampling, lookup."""

from __future__ import annotations

import numpy as np
import pytest

from flexmbs.errors import GeometryError
from flexmbs.geometry.curves import (
    Centerline,
    arc,
    bessel_tangents,
    hermite_lengths,
    line,
    polyline,
)

# Tolerances, in one place.
EXACT = 1e-12  # formulas exact in real arithmetic (Bessel on circles, arc nodes): round-off only
# Hermite cubic with unit end slopes scaled by its own length, on a circular arc of angle t:
# L / (R t) - 1 = -t^4/720 + O(t^6) (measured: -5.37e-4 at t = 45 deg, 16x smaller per halving).
HERMITE_C4 = 1.0 / 720.0
# Resampled nodes are equally spaced in *spline* arc length; element lengths are *Hermite* arc
# lengths with the spline's tangents. Their spread is the spline/Hermite mismatch: measured
# <= 4.2e-6 for 25 elements on 30 randomly spaced circle points (seeds 0-4), 2e-5 for 10 elements.
EQUAL_SPREAD = 1e-5


def circle_points(phi: np.ndarray, radius: float = 2.3, center=(1.0, -2.0, 0.5),
                  normal=(1.0, 2.0, 2.0)) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points and unit tangents (increasing phi) on a tilted 3D circle; also the centre."""
    n = np.asarray(normal, float) / np.linalg.norm(normal)
    e1 = np.cross(n, [1.0, 0.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(n, e1)
    c = np.asarray(center, float)
    cos, sin = np.cos(phi)[:, None], np.sin(phi)[:, None]
    return c + radius * (cos * e1 + sin * e2), -sin * e1 + cos * e2, c


def example1_arc(elements: int) -> Centerline:
    """docs/theory.md §III.9: R = 1 m, centre (0, 0, 1), -45..+45 deg about the lowest point."""
    a = np.pi / 4
    return arc((0, 0, 1), 1.0, (-np.sin(a), 0, 1 - np.cos(a)), np.pi / 2, normal=(0, -1, 0),
               elements=elements)


def hermite_curvature(c: Centerline, e: int, xi: np.ndarray) -> np.ndarray:
    """|r' x r''| / |r'|^3 of element e at xi (cubic Hermite with slopes L*T)."""
    i0, i1 = c.element_nodes(e)
    length = c.lengths[e]
    coef = np.stack([c.points[i0], length * c.tangents[i0], c.points[i1], length * c.tangents[i1]])
    d1 = np.stack([6 * xi**2 - 6 * xi, 1 - 4 * xi + 3 * xi**2, 6 * xi - 6 * xi**2,
                   3 * xi**2 - 2 * xi], axis=-1) @ coef
    d2 = np.stack([12 * xi - 6, 6 * xi - 4, 6 - 12 * xi, 6 * xi - 2], axis=-1) @ coef
    return np.linalg.norm(np.cross(d1, d2), axis=-1) / np.linalg.norm(d1, axis=-1) ** 3


# --------------------------------------------------------------------------------------------------
# Bessel tangents


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_bessel_tangents_exact_on_tilted_circle_random_spacing(seed: int) -> None:
    rng = np.random.default_rng(seed)
    phi = np.sort(rng.uniform(0.0, 5.0, 15))  # open arc, spacing varying by orders of magnitude
    p, t, _ = circle_points(phi)
    np.testing.assert_allclose(bessel_tangents(p), t, atol=EXACT)  # incl. reflected end tangents
    np.testing.assert_allclose(bessel_tangents(p[::-1]), -t[::-1], atol=EXACT)


def test_bessel_tangents_closed_circle() -> None:
    rng = np.random.default_rng(3)
    phi = np.sort(rng.uniform(0.0, 2 * np.pi, 9))
    p, t, _ = circle_points(phi)
    np.testing.assert_allclose(bessel_tangents(p, closed=True), t, atol=EXACT)


def test_bessel_tangents_straight_and_two_points() -> None:
    p = np.array([[0, 0, 0], [0.1, 0.2, 0], [1.0, 2.0, 0], [1.5, 3.0, 0]])
    expect = np.array([1.0, 2.0, 0.0]) / np.sqrt(5.0)
    np.testing.assert_allclose(bessel_tangents(p), np.tile(expect, (4, 1)), atol=EXACT)
    np.testing.assert_allclose(bessel_tangents(p[[0, 3]]), np.tile(expect, (2, 1)), atol=EXACT)


# --------------------------------------------------------------------------------------------------
# line and arc


def test_line() -> None:
    c = line((0, 0, 0), (3, 4, 0), elements=5)
    assert (c.n_nodes, c.n_elem, c.closed) == (6, 5, False)
    np.testing.assert_allclose(c.lengths, 1.0, rtol=EXACT)
    np.testing.assert_allclose(c.tangents, np.tile([0.6, 0.8, 0.0], (6, 1)), atol=EXACT)
    np.testing.assert_allclose(c.points[-1], [3, 4, 0], atol=0)
    # a straight Hermite element is exact: the fixed point returns the chord
    np.testing.assert_allclose(hermite_lengths(c.points, c.tangents), c.lengths, rtol=EXACT)


def test_arc_example1_points_and_tangents() -> None:
    c = example1_arc(16)
    assert (c.n_nodes, c.n_elem) == (17, 16)
    np.testing.assert_allclose(np.linalg.norm(c.points - [0, 0, 1], axis=1), 1.0, atol=EXACT)
    np.testing.assert_allclose(c.points[8], [0, 0, 0], atol=EXACT)  # lowest point mid-arc
    np.testing.assert_allclose(c.tangents[8], [1, 0, 0], atol=EXACT)  # moving towards +x
    np.testing.assert_allclose(c.points[-1], [np.sqrt(0.5), 0, 1 - np.sqrt(0.5)], atol=EXACT)
    radial = c.points - [0, 0, 1]
    np.testing.assert_allclose(np.einsum("ij,ij->i", radial, c.tangents), 0.0, atol=EXACT)
    np.testing.assert_allclose(c.tangents[:, 1], 0.0, atol=EXACT)  # stays in the X-Z plane
    np.testing.assert_allclose(c.lengths, np.pi / 32, rtol=EXACT)
    assert c.total_length == pytest.approx(np.pi / 2, rel=EXACT)


def test_arc_negative_angle_turns_the_other_way() -> None:
    a = arc((0, 0, 0), 2.0, (2, 0, 0), np.pi / 2, elements=4)
    b = arc((0, 0, 0), 2.0, (2, 0, 0), -np.pi / 2, elements=4)
    np.testing.assert_allclose(a.points[-1], [0, 2, 0], atol=EXACT)
    np.testing.assert_allclose(b.points[-1], [0, -2, 0], atol=EXACT)
    np.testing.assert_allclose(a.tangents[0], [0, 1, 0], atol=EXACT)
    np.testing.assert_allclose(b.tangents[0], [0, -1, 0], atol=EXACT)


def test_arc_full_circle_is_closed() -> None:
    c = arc((0, 0, 0), 1.5, (0, 1.5, 0), 2 * np.pi, normal=(1, 0, 0), elements=12)
    assert c.closed and c.n_nodes == 12 and c.n_elem == 12
    assert c.total_length == pytest.approx(3 * np.pi, rel=EXACT)


# --------------------------------------------------------------------------------------------------
# Hermite element lengths


def test_hermite_lengths_on_arcs_converge_at_fourth_order() -> None:
    """Relative error of the fixed-point length vs R*theta_e: O(theta_e^4), constant ~ -1/720."""
    elements = np.array([2, 4, 8, 16, 32])
    theta_e = (np.pi / 2) / elements
    err = []
    for n in elements:
        c = example1_arc(int(n))
        length = hermite_lengths(c.points, c.tangents)
        err.append(abs(length.sum() / (np.pi / 2) - 1.0))
        assert np.all(length < c.lengths)  # the Hermite arc is slightly shorter
    err = np.array(err)
    rate = np.polyfit(np.log(theta_e), np.log(err), 1)[0]
    assert rate == pytest.approx(4.0, abs=0.05)
    # leading coefficient (the 16-element Example 1 arc: -1.29e-7, far below 1e-4)
    np.testing.assert_allclose(err[2:] / theta_e[2:] ** 4, HERMITE_C4, rtol=5e-3)


def test_hermite_fixed_point_converged_in_five_iterations() -> None:
    # contraction is fast: change after 5 iterations is round-off for elements up to 45 deg
    for n in (2, 8):
        c = example1_arc(n)
        five = hermite_lengths(c.points, c.tangents, iterations=5)
        many = hermite_lengths(c.points, c.tangents, iterations=50)
        np.testing.assert_allclose(five, many, rtol=1e-8)
    c = example1_arc(16)
    np.testing.assert_allclose(hermite_lengths(c.points, c.tangents, iterations=0),
                               np.linalg.norm(np.diff(c.points, axis=0), axis=1), rtol=EXACT)


def test_hermite_lengths_independent_of_tilt_and_direction() -> None:
    phi = np.linspace(0.3, 2.0, 7)
    p, t, _ = circle_points(phi)
    forward = hermite_lengths(p, t)
    backward = hermite_lengths(p[::-1], -t[::-1])
    np.testing.assert_allclose(backward[::-1], forward, rtol=EXACT)
    dphi = np.diff(phi)
    np.testing.assert_allclose(forward / (2.3 * dphi) - 1, -dphi**4 / 720, atol=1e-7)


# --------------------------------------------------------------------------------------------------
# polyline


def test_polyline_from_arc_points_matches_arc() -> None:
    ref = example1_arc(16)
    c = polyline(ref.points)
    np.testing.assert_allclose(c.tangents, ref.tangents, atol=EXACT)
    assert c.total_length == pytest.approx(np.pi / 2 * (1 - (np.pi / 32) ** 4 * HERMITE_C4),
                                           rel=1e-9)


@pytest.mark.parametrize("with_tangents", [False, True])
def test_polyline_resampling_gives_equal_lengths(with_tangents: bool) -> None:
    rng = np.random.default_rng(7)
    phi = np.concatenate([[0.0], np.sort(rng.uniform(0, 2.5, 30)), [2.5]])
    p, t, center = circle_points(phi)
    c = polyline(p, t if with_tangents else None, elements=25)
    assert (c.n_nodes, c.n_elem) == (26, 25)
    spread = np.ptp(c.lengths) / np.mean(c.lengths)
    assert spread < EQUAL_SPREAD
    np.testing.assert_allclose(c.points[[0, -1]], p[[0, -1]], atol=EXACT)
    # nodes stay on the circle to the spline accuracy (random gaps up to ~0.3 rad: <= 7e-4 m
    # measured over seeds 0-4 for R = 2.3 m)
    np.testing.assert_allclose(np.linalg.norm(c.points - center, axis=1), 2.3, atol=1e-3)
    assert c.total_length == pytest.approx(2.3 * 2.5, rel=1e-4)  # measured <= 4.3e-5, seeds 0-4


def test_resampling_a_centerline_keeps_its_geometry() -> None:
    """With given tangents the resampling spline is the Centerline's own Hermite curve."""
    ref = example1_arc(16)
    c = polyline(ref.points, ref.tangents, elements=32)
    # the new nodes lie on the old Hermite curve: radial error of that curve ~ theta_e^6 / ...
    np.testing.assert_allclose(np.linalg.norm(c.points - [0, 0, 1], axis=1), 1.0, atol=1e-6)
    assert c.total_length == pytest.approx(np.pi / 2, rel=1e-6)
    same = polyline(ref.points, ref.tangents, elements=16)
    np.testing.assert_allclose(same.points, ref.points, atol=1e-12)


def test_polyline_closed_circle() -> None:
    phi = np.linspace(0, 2 * np.pi, 13)  # first point repeated at the end: dropped
    p, t, center = circle_points(phi)
    c = polyline(p, closed=True)
    assert c.closed and c.n_nodes == 12 and c.n_elem == 12
    np.testing.assert_allclose(c.tangents, t[:-1], atol=EXACT)
    theta = 2 * np.pi / 12
    assert c.total_length == pytest.approx(2 * np.pi * 2.3 * (1 - theta**4 * HERMITE_C4),
                                           rel=1e-5)
    p24, _, _ = circle_points(np.linspace(0, 2 * np.pi, 24, endpoint=False))
    r = polyline(p24, closed=True, elements=40)  # periodic spline through 24 points
    assert r.closed and r.n_elem == 40 and r.n_nodes == 40
    assert np.ptp(r.lengths) / np.mean(r.lengths) < EQUAL_SPREAD
    # periodic cubic spline with 15 deg knots: radial error ~ R (dphi)^4 / 384 ~ 2e-5 m
    np.testing.assert_allclose(np.linalg.norm(r.points - center, axis=1), 2.3, atol=1e-4)
    assert r.total_length == pytest.approx(2 * np.pi * 2.3, rel=1e-5)


def test_polyline_accepts_planar_points() -> None:
    c = polyline([[0, 0], [1, 0], [2, 0]])
    np.testing.assert_allclose(c.points[:, 2], 0.0)
    np.testing.assert_allclose(c.lengths, 1.0, rtol=EXACT)


# --------------------------------------------------------------------------------------------------
# locate and frame_at


def test_locate_and_frame_at_on_arc() -> None:
    c = example1_arc(16)
    s_nodes = c.arc_length_of_nodes()
    assert s_nodes.shape == (17,) and s_nodes[0] == 0.0
    np.testing.assert_allclose(s_nodes[-1], c.total_length, rtol=EXACT)
    np.testing.assert_allclose(np.diff(s_nodes), c.lengths, rtol=EXACT)
    assert c.locate(0.0) == (0, 0.0)
    assert c.locate(c.total_length) == (15, 1.0)
    e, xi = c.locate(s_nodes[5] + 0.25 * c.lengths[5])
    assert e == 5 and xi == pytest.approx(0.25, abs=EXACT)
    for i in (0, 8, 16):  # nodes: exact positions and tangents
        pos, tan = c.frame_at(s_nodes[i] if i < 16 else c.total_length)
        np.testing.assert_allclose(pos, c.points[i], atol=EXACT)
        np.testing.assert_allclose(tan, c.tangents[i], atol=EXACT)
    # between nodes: the Hermite arc dips inside the circle by R theta_e^4 / 384 at mid-element
    # and its tangent tilts by ~theta_e^3 / 125 rad (both measured for 8, 16, 32 elements)
    theta = np.pi / 32
    radial, tilt = [], []
    for s in np.linspace(0.0, c.total_length, 641):
        pos, tan = c.frame_at(s)
        assert np.linalg.norm(tan) == pytest.approx(1.0, abs=EXACT)
        radial.append(np.linalg.norm(pos - [0, 0, 1]) - 1.0)
        tilt.append(abs(np.dot(pos - [0, 0, 1], tan)))
    assert min(radial) == pytest.approx(-(theta**4) / 384, rel=1e-2)
    assert max(radial) <= EXACT
    assert max(tilt) < theta**3 / 120
    # the lowest point is reached at s = pi/4 (the arc is symmetric)
    np.testing.assert_allclose(c.frame_at(c.total_length / 2)[0], [0, 0, 0], atol=EXACT)


def test_curvature_of_hermite_arc_is_close_to_one_over_r() -> None:
    """Hermite arc curvature error is O(theta_e^2): +theta_e^2/12 at the nodes (measured)."""
    xi = np.linspace(0, 1, 11)
    for n in (8, 16, 32):
        c = example1_arc(n)
        theta = np.pi / 2 / n
        kappa = np.concatenate([hermite_curvature(c, e, xi) for e in range(c.n_elem)])
        assert np.max(np.abs(kappa - 1.0)) == pytest.approx(theta**2 / 12, rel=2e-2)


def test_locate_closed_wraps() -> None:
    c = arc((0, 0, 0), 1.0, (1, 0, 0), 2 * np.pi, elements=8)
    e, xi = c.locate(c.total_length + 0.1)
    e0, xi0 = c.locate(0.1)
    assert (e, xi) == (e0, pytest.approx(xi0, abs=1e-12))
    assert c.locate(c.total_length - 1e-9)[0] == 7
    pos_end, _ = c.frame_at(c.total_length * (1 - 1e-15))
    np.testing.assert_allclose(pos_end, c.points[0], atol=1e-12)


def test_locate_outside_raises() -> None:
    c = line((0, 0, 0), (1, 0, 0), elements=2)
    with pytest.raises(GeometryError, match="outside the curve"):
        c.locate(1.5)
    with pytest.raises(GeometryError, match="outside the curve"):
        c.frame_at(-0.1)


# --------------------------------------------------------------------------------------------------
# errors


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: polyline([[0, 0, 0]]), "at least 2 distinct points"),
        (lambda: polyline([[1, 1, 1], [1, 1, 1], [1, 1, 1]]), "at least 2 distinct points"),
        (lambda: polyline([[0, 0, 0], [1, 0, 0], [1, 0, 0], [2, 0, 0]]),
         "points 1 and 2 coincide"),
        (lambda: polyline([[0, 0, 0], [1, 0, 0]], elements=0), "elements must be >= 1"),
        (lambda: polyline([[0, 0, 0], [1, 0, 0]], elements=2.5), "elements must be an integer"),
        (lambda: polyline([[0, 0, 0], [1, 0, 0]], [[1, 0, 0], [0, 0, 0]]),
         "zero-length tangent at node 1"),
        (lambda: polyline([[0, 0, 0], [1, 0, 0]], [[1, 0, 0]]), "tangents shape"),
        (lambda: polyline([[0, 0, 0], [1, 0, 0]], closed=True), "closed polyline needs at least 3"),
        (lambda: polyline([[0, 0, 0], [1, 0, 0], [0.5, 0, 0]]), "reverses at point 1"),
        (lambda: polyline([[0, 0, 0, 0]]), r"shape \(n, 3\)"),
        (lambda: polyline([[0, 0, 0], [np.nan, 0, 0]]), "NaN"),
        (lambda: arc((0, 0, 0), -1, (1, 0, 0), 1.0, elements=4), r"radius must be > 0 \(got -1\)"),
        (lambda: arc((0, 0, 0), 2, (1, 0, 0), 1.0, elements=4), "not on the circle of radius 2"),
        (lambda: arc((0, 0, 0), 1, (1, 0, 0), 0.0, elements=4), "non-zero"),
        (lambda: arc((0, 0, 0), 1, (1, 0, 0), 7.0, elements=4), r"\|angle\| <= 2\*pi"),
        (lambda: arc((0, 0, 0), 1, (1, 0, 0), 1.0, normal=(1, 0, 0), elements=4),
         "perpendicular to the arc normal"),
        (lambda: arc((0, 0, 0), 1, (1, 0, 0), 1.0, normal=(0, 0, 0), elements=4), "non-zero"),
        (lambda: arc((0, 0, 0), 1, (1, 0, 0), 1.0, elements=0), "elements must be >= 1"),
        (lambda: line((1, 2, 3), (1, 2, 3), elements=3), "coincide"),
        (lambda: line((0, 0, 0), (1, 0, 0), elements=-1), "elements must be >= 1"),
        (lambda: Centerline(np.zeros((3, 3)), np.ones((3, 3)), np.ones(3)), "lengths must have"),
        (lambda: Centerline(np.eye(3)[:2], np.ones((2, 3)), [-1.0]), "lengths must be finite"),
        (lambda: hermite_lengths([[0, 0, 0], [0, 0, 0]], [[1, 0, 0], [1, 0, 0]]),
         "coincident end points"),
    ],
)
def test_errors(call, match: str) -> None:
    with pytest.raises(GeometryError, match=match):
        call()


def test_centerline_arrays_are_read_only() -> None:
    c = line((0, 0, 0), (1, 0, 0), elements=2)
    with pytest.raises(ValueError):
        c.points[0, 0] = 1.0

"""3D beam/section kernels on a circular ANCF arc (docs/theory.md §II.2, §II.4)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq, minimize_scalar

from flexmbs.contact.geometry import (
    beam_point,
    closest_point,
    from_section,
    section_crossing,
    section_ellipse,
    to_section,
)
from flexmbs.elements.hermite import shape_functions


def _hermite(q: np.ndarray, L: np.ndarray, e: int, xi: float) -> np.ndarray:
    S, _, _ = shape_functions(np.array(xi), np.array(L[e]))
    return S @ q[e].reshape(4, 3)

#: Hermite interpolation error of a unit-radius arc with 22.5° elements and unit nodal slopes
#: (as ``flexmbs.geometry.curves.arc`` builds it): max radial error 6.2e-5 (measured here; the
#: 1.4e-6 of docs/theory.md §II.4 [V] is not reproduced with unit slopes, see
#: test_closest_point_on_arc); comparisons with the exact circle use this level
HERMITE_TOL = 7e-5
#: comparisons with the exact root of the *Hermite* curve (independent brentq): round-off level
EXACT_TOL = 1e-11


def arc_beam(n_elem: int = 8, dtheta: float = np.pi / 8, radius: float = 1.0
             ) -> tuple[np.ndarray, np.ndarray]:
    """Hermite nodes on the circle of radius ``radius`` about the origin (z = 0), |r'| = 1."""
    th = dtheta * np.arange(n_elem + 1)
    nodes = radius * np.stack([np.cos(th), np.sin(th), 0 * th], axis=1)
    tang = np.stack([-np.sin(th), np.cos(th), 0 * th], axis=1)
    q = np.concatenate([nodes[:-1], tang[:-1], nodes[1:], tang[1:]], axis=1)
    return np.ascontiguousarray(q), np.full(n_elem, radius * dtheta)


def test_beam_point_matches_shape_functions(rng: np.random.Generator) -> None:
    q, L = arc_beam()
    for e, xi in [(0, 0.0), (3, 0.37), (7, 1.0)]:
        r, rx, rxx = beam_point(q, L, e, xi)
        S, dS, ddS = shape_functions(np.array(xi), np.array(L[e]))
        qe = q[e].reshape(4, 3)
        np.testing.assert_allclose(r, S @ qe, atol=1e-14)
        np.testing.assert_allclose(rx, L[e] * dS @ qe, atol=1e-14)
        np.testing.assert_allclose(rxx, L[e] ** 2 * ddS @ qe, atol=1e-13)


@pytest.mark.parametrize("alpha", [0.1, np.pi / 8, 0.9, 1.7, 2.9])
@pytest.mark.parametrize("start", [(0, 0.5), (7, 0.9), (3, 0.0)])
def test_section_crossing_on_arc(alpha: float, start: tuple[int, float]) -> None:
    """Plane through the arc centre at angle α: exact crossing (cos α, sin α, 0); Newton from far
    elements must walk across nodes (the ξ ∓ 1 continuation)."""
    q, L = arc_beam()
    n = np.array([-math.sin(alpha), math.cos(alpha), 0.0])
    O_ = np.array([0.0, 0.0, 0.3])
    e, xi, found = section_crossing(q, L, O_, n, start[0], start[1])
    assert found and 0 <= e < 8 and 0.0 <= xi <= 1.0
    r, _, _ = beam_point(q, L, e, xi)
    assert abs(n @ (r - O_)) < 1e-12
    np.testing.assert_allclose(r, [math.cos(alpha), math.sin(alpha), 0.0], atol=HERMITE_TOL)
    assert e == min(int(alpha / (np.pi / 8)), 7)
    # exact intersection of the Hermite cubic, independent solver
    xs = brentq(lambda x: n @ (_hermite(q, L, e, x) - O_), 0.0, 1.0, xtol=1e-15)
    assert abs(xs - xi) < EXACT_TOL


def test_section_crossing_global_fallback_keeps_closest() -> None:
    """A half circle crosses the plane y = 0.5 twice; with max_distance the crossing near O_ wins."""
    q, L = arc_beam()
    n = np.array([0.0, 1.0, 0.0])
    O_ = np.array([-0.8, 0.5, 0.0])
    e, xi, found = section_crossing(q, L, O_, n, 0, 0.0)  # Newton finds the x > 0 crossing
    r, _, _ = beam_point(q, L, e, xi)
    assert found and r[0] > 0
    e, xi, found = section_crossing(q, L, O_, n, 0, 0.0, max_distance=0.5)
    r, _, _ = beam_point(q, L, e, xi)
    assert found and r[0] < 0
    np.testing.assert_allclose(r, [-math.sqrt(0.75), 0.5, 0.0], atol=HERMITE_TOL)
    # no crossing at all
    _, _, found = section_crossing(q, L, np.array([0.0, 2.0, 0.0]), n, 2, 0.5)
    assert not found


def test_section_ellipse() -> None:
    ey, ez = np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, 1.0])
    n = np.array([1.0, 0.0, 0.0])
    a, b, ea, eb, c = section_ellipse(np.array([2.0, 0.0, 0.0]), n, ey, ez, 0.1)
    assert (a, b, c) == (0.1, 0.1, 1.0)
    np.testing.assert_array_equal(ea, ey)
    th = 0.3
    t = np.array([math.cos(th), 0.0, math.sin(th)])
    a, b, ea, eb, c = section_ellipse(-t, n, ey, ez, 0.1)
    assert c == pytest.approx(math.cos(th)) and a == pytest.approx(0.1 / math.cos(th)) and b == 0.1
    assert abs(ea @ n) < 1e-15 and abs(eb @ n) < 1e-15 and abs(ea @ eb) < 1e-15
    assert abs(eb @ t) < 1e-15 and abs(abs(ea[2]) - 1.0) < 1e-15
    # the ellipse X(φ) lies on the tangent cylinder: distance to the axis line = r_b
    O_ = np.array([0.0, 0.0, 0.0])
    for phi in np.linspace(0, 2 * np.pi, 7):
        X = O_ + a * math.cos(phi) * ea + b * math.sin(phi) * eb
        assert np.linalg.norm(X - (X @ t) * t) == pytest.approx(0.1, rel=1e-12)
    y = to_section(np.array([0.0, 0.2, -0.3]), O_, ey, ez)
    np.testing.assert_allclose(y, [0.2, -0.3])
    np.testing.assert_allclose(from_section(y, O_, ey, ez), [0.0, 0.2, -0.3])


@pytest.mark.parametrize("beta", [0.05, np.pi / 8, 1.0, 2.2, 3.1])
@pytest.mark.parametrize("z", [0.0, 0.004])
def test_closest_point_on_arc(beta: float, z: float) -> None:
    """ℓ = 10 mm outside a unit arc with 22.5° elements: distance error ~1.4e-6 (docs/theory.md §II.4)."""
    q, L = arc_beam()
    rho = 1.0 + math.sqrt(0.01**2 - z**2)
    Q = np.array([rho * math.cos(beta), rho * math.sin(beta), z])
    for e0, xi0 in [(0, 0.5), (7, 0.2), (int(beta / (np.pi / 8)), 0.5)]:
        e, xi, P, rx, rxx = closest_point(q, L, Q, e0, xi0)
        assert abs((P - Q) @ rx) < 1e-12
        assert abs(np.linalg.norm(Q - P) - 0.01) < HERMITE_TOL
        assert abs(math.atan2(P[1], P[0]) - beta) < HERMITE_TOL
        # exact projection on the Hermite curve (independent bounded minimisation of the distance)
        def dist(s: float, Q: np.ndarray = Q) -> float:
            e_s = min(int(s), 7)
            return float(np.linalg.norm(_hermite(q, L, e_s, s - e_s) - Q))

        s_best = minimize_scalar(dist,
                                 bounds=(max(e + xi - 0.6, 0), min(e + xi + 0.6, 8)), method="bounded",
                                 options={"xatol": 1e-10}).x
        assert abs(s_best - (e + xi)) < 1e-7  # bounded Brent: ~sqrt(eps) in the argument
        r, rx2, _ = beam_point(q, L, e, xi)
        np.testing.assert_array_equal(r, P)
        np.testing.assert_array_equal(rx, rx2)
    # error level of the distance over the arc: 6.2e-5 with unit slopes
    # (docs/theory.md §II.4 quotes 1.4e-6)
    errs = []
    for bt in np.linspace(0.01, np.pi - 0.01, 200):
        Q = np.array([1.01 * math.cos(bt), 1.01 * math.sin(bt), 0.0])
        _, _, P, _, _ = closest_point(q, L, Q, 0, 0.0)
        errs.append(abs(np.linalg.norm(Q - P) - 0.01))
    assert 3e-5 < max(errs) < HERMITE_TOL


def test_closest_point_clamps_at_chain_end() -> None:
    q, L = arc_beam()
    e, xi, P, _, _ = closest_point(q, L, np.array([1.2, -0.5, 0.0]), 3, 0.5)
    assert (e, xi) == (0, 0.0)
    np.testing.assert_allclose(P, [1.0, 0.0, 0.0], atol=1e-15)

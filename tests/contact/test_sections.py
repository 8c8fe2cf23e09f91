"""2D hole sections: common-normal detector vs brute force (docs/theory.md §II.3, §II.6)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

from flexmbs.contact.sections import (
    HOLE_SECTIONS,
    CircleSection,
    Ellipse2D,
    SuperellipseSection,
    get_section,
    inside_evolute,
    jamming,
    two_point_possible,
)
from flexmbs.errors import ModelError

#: angle agreement after polishing (brief: 1e-6); brute-force maxima are refined by brentq on an
#: independent derivative formula, so both sides are accurate to ~1e-12 for well-conditioned maxima
ANGLE_TOL = 1e-6
#: a maximum is "well conditioned" (location defined to << ANGLE_TOL) if |D''| exceeds this
#: fraction of a²; flatter ones sit next to a max/min bifurcation and are only checked for realness
CURV_MIN = 1e-3
N_BRUTE = 20000
MARGIN = 0.1
R = 1.0


def _dist_derivs(E: Ellipse2D, phi: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Independent D(φ) = |X|, D' and D'' (chain rule, no quartic)."""
    X = E.point(phi)
    Xp = (-E.a * np.sin(phi))[..., None] * E.e_a + (E.b * np.cos(phi))[..., None] * E.e_b
    Xpp = X - E.center
    Xpp = -Xpp
    D = np.linalg.norm(X, axis=-1)
    g = np.einsum("...i,...i->...", X, Xp)
    Dp = g / D
    gp = np.einsum("...i,...i->...", Xp, Xp) + np.einsum("...i,...i->...", X, Xpp)
    Dpp = gp / D - g * g / D**3
    return D, Dp, Dpp


def _brute_maxima(E: Ellipse2D) -> list[tuple[float, float, float]]:
    """Local maxima (φ, depth, D'') of |X(φ)| − R: dense sampling + brentq on D'."""
    phi = np.linspace(0.0, 2.0 * np.pi, N_BRUTE, endpoint=False)
    D = np.linalg.norm(E.point(phi), axis=-1)
    idx = np.nonzero((np.roll(D, 1) < D) & (np.roll(D, -1) <= D))[0]
    h = 2.0 * np.pi / N_BRUTE
    out = []
    for i in idx:
        def dp(x: float) -> float:
            return float(_dist_derivs(E, np.array(x))[1])
        lo, hi = phi[i] - h, phi[i] + h
        if dp(lo) > 0.0 > dp(hi):
            x = brentq(dp, lo, hi, xtol=1e-15, rtol=1e-15)
        else:
            x = phi[i]
        Dx, _, Dpp = _dist_derivs(E, np.array(x))
        out.append((x % (2.0 * np.pi), float(Dx) - R, float(Dpp)))
    return out


def _adist(x: float, y: float) -> float:
    d = abs(x - y) % (2.0 * np.pi)
    return min(d, 2.0 * np.pi - d)


@settings(max_examples=2000, deadline=None, derandomize=True)
@given(b=st.floats(0.3, 1.0), ratio=st.floats(1.0, 3.0), th=st.floats(0.0, np.pi),
       rc=st.floats(0.0, 1.3), ac=st.floats(0.0, 2.0 * np.pi))
def test_circle_candidates_match_brute_force(b: float, ratio: float, th: float, rc: float,
                                             ac: float) -> None:
    E = Ellipse2D(np.array([rc * math.cos(ac), rc * math.sin(ac)]),
                  np.array([math.cos(th), math.sin(th)]), ratio * b, b)
    if ratio - 1.0 < 1e-9 and rc < 1e-9:
        return  # degenerate f ≡ 0 (tested separately)
    cands = CircleSection(R).candidates(E, margin=MARGIN)
    scale = E.a * E.a
    # no spurious candidates: every one is a true stationary point of the right kind and depth
    for c in cands:
        D, Dp, Dpp = _dist_derivs(E, np.array(c.phi))
        assert abs(Dp) < 1e-9 * scale
        assert c.depth == pytest.approx(float(D) - R, abs=1e-12)
        assert c.depth > -MARGIN
        if abs(Dpp) > 1e-6 * scale:
            assert c.kind == (1 if Dpp < 0 else -1)
        np.testing.assert_allclose(c.Q, R * c.X / np.linalg.norm(c.X), atol=1e-12)
    # completeness: every well-conditioned penetrating-enough maximum is found
    maxima = [c.phi for c in cands if c.kind == 1]
    for phi, depth, Dpp in _brute_maxima(E):
        if depth > -MARGIN + 1e-9 and -Dpp > CURV_MIN * scale:
            assert any(_adist(phi, p) < ANGLE_TOL for p in maxima), (phi, depth, maxima)


def _se_brute(sec: SuperellipseSection, E: Ellipse2D, n: int = N_BRUTE
              ) -> tuple[np.ndarray, np.ndarray]:
    psi = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    Y, N, _, _, _ = sec.boundary(psi)
    X, _ = E.support(N)
    return psi, np.einsum("...i,...i->...", N, X - Y)


@settings(max_examples=150, deadline=None, derandomize=True)
@given(b=st.floats(0.3, 0.8), ratio=st.floats(1.0, 2.0), th=st.floats(0.0, np.pi),
       rc=st.floats(0.0, 0.8), ac=st.floats(0.0, 2.0 * np.pi), A=st.floats(0.8, 1.2),
       B=st.floats(0.8, 1.2), n=st.floats(2.0, 6.0), turn=st.floats(0.0, np.pi))
def test_superellipse_candidates_match_brute_force(b: float, ratio: float, th: float, rc: float,
                                                   ac: float, A: float, B: float, n: float,
                                                   turn: float) -> None:
    """The compiled detector (through ``candidates``) on a superellipse turned by ``turn``.
    Dense sampling of d(ψ) = N·(X(N) − Y) (20000 ψ) locates maxima to 3e-4 rad; the detector
    (128 samples + Newton) must find each well-separated one; depth agrees to O(h²) ~ 1e-6.
    Ellipses that cannot fit the bore (a above 95 % of the inscribed radius: the joint reports
    jamming for them) are excluded: there the stationary points crowd and the bracketing
    tolerance of the detector was seen to leave d' ~ 4e-3."""
    assume(ratio * b < 0.95 * min(A, B))
    sec = SuperellipseSection(a=A, b=B, exponent=n, angle=turn)
    E = Ellipse2D(np.array([rc * math.cos(ac), rc * math.sin(ac)]),
                  np.array([math.cos(th), math.sin(th)]), ratio * b, b)
    cands = sec.candidates(E, margin=MARGIN)
    h = 1e-6
    for c in cands:  # independent check: d'(ψ) ≈ 0 by finite differences
        _, dd = _se_brute_at(sec, E, np.array([c.psi - h, c.psi, c.psi + h]))
        assert abs(dd[2] - dd[0]) / (2 * h) < 1e-6
        assert c.depth == pytest.approx(dd[1], abs=1e-12)
    psi, d = _se_brute(sec, E)
    idx = np.nonzero((d > np.roll(d, 1)) & (d >= np.roll(d, -1)))[0]
    maxima = [(c.psi, c.depth) for c in cands if c.kind == 1]
    hgrid = 2.0 * np.pi / N_BRUTE
    for i in idx:
        curv = (d[i - 1] - 2 * d[i] + d[(i + 1) % len(d)]) / hgrid**2
        if d[i] > -MARGIN + 1e-6 and -curv > 1e-2:
            assert any(_adist(psi[i], p) < 2 * hgrid and abs(dep - d[i]) < 1e-5
                       for p, dep in maxima), (psi[i], d[i], maxima)


def _se_brute_at(sec: SuperellipseSection, E: Ellipse2D, psi: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray]:
    Y, N, _, _, _ = sec.boundary(psi)
    X, _ = E.support(N)
    return psi, np.einsum("...i,...i->...", N, X - Y)


def test_superellipse_n2_equals_circle(rng: np.random.Generator) -> None:
    for _ in range(50):
        b = rng.uniform(0.3, 0.9)
        E = Ellipse2D(rng.uniform(-0.3, 0.3, 2), rng.normal(size=2), b * rng.uniform(1, 2), b)
        c1 = sorted(CircleSection(1.0).candidates(E, 0.2), key=lambda c: c.psi)
        c2 = sorted(SuperellipseSection(a=1.0, b=1.0, exponent=2.0).candidates(E, 0.2), key=lambda c: c.psi)
        assert len(c1) == len(c2)
        for x, y in zip(c1, c2, strict=True):
            np.testing.assert_allclose(x.Q, y.Q, atol=1e-9)
            assert x.kind == y.kind
            assert x.depth == pytest.approx(y.depth, abs=1e-10)
            assert _adist(x.phi, y.phi) < 1e-8


def test_superellipse_boundary_is_consistent() -> None:
    """N ⟂ Y_ψ, speed = |Y_ψ| and κ = |T_ψ|/|Y_ψ| by finite differences; Y on the curve."""
    sec = SuperellipseSection(a=1.2, b=0.8, exponent=4.0)
    psi = np.linspace(0.1, 6.2, 37)
    Y, N, T, speed, kappa = sec.boundary(psi)
    np.testing.assert_allclose(np.abs(Y[:, 0] / 1.2) ** 4 + np.abs(Y[:, 1] / 0.8) ** 4, 1.0, atol=1e-12)
    h = 1e-6
    Yp = (sec.boundary(psi + h)[0] - sec.boundary(psi - h)[0]) / (2 * h)
    Tp = (sec.boundary(psi + h)[2] - sec.boundary(psi - h)[2]) / (2 * h)
    np.testing.assert_allclose(np.linalg.norm(Yp, axis=1), speed, rtol=1e-7)
    np.testing.assert_allclose(np.einsum("ij,ij->i", Yp, N), 0.0, atol=1e-7)
    np.testing.assert_allclose(np.einsum("ij,ij->i", Yp, T), speed, rtol=1e-7)  # CCW
    np.testing.assert_allclose(np.linalg.norm(Tp, axis=1) / speed, kappa, rtol=1e-5, atol=1e-7)
    assert np.all(np.einsum("ij,ij->i", N, Y) > 0)  # outward
    assert sec.inscribed_radius() == 0.8
    assert sec.bounding_radius() >= np.max(np.linalg.norm(Y, axis=1))


def test_astroid_count(rng: np.random.Generator) -> None:
    """4 stationary points iff the hole centre is inside the evolute, else 2 (docs/theory.md §II.3)."""
    checked = 0
    for _ in range(600):
        b = rng.uniform(0.3, 1.0)
        a = b * rng.uniform(1.05, 3.0)
        E = Ellipse2D(rng.uniform(-1.5, 1.5, 2), rng.normal(size=2), a, b)
        d = -E.center
        val = abs(a * d @ E.e_a) ** (2 / 3) + abs(b * d @ E.e_b) ** (2 / 3) - (a * a - b * b) ** (2 / 3)
        if abs(val) < 1e-3 * (a * a - b * b) ** (2 / 3):
            continue  # too close to the cusp curve (double root)
        cands = CircleSection(10.0).candidates(E, margin=100.0)
        assert len(cands) == (4 if inside_evolute(E) else 2)
        assert sum(c.kind == 1 for c in cands) == len(cands) // 2
        checked += 1
    assert checked > 500


@pytest.mark.parametrize("cos_t, n_max", [(0.99, 1), (0.96, 1), (0.93, 2)])
def test_two_point_criterion(cos_t: float, n_max: int) -> None:
    """docs/theory.md §II.3 check: r_b = 1, R = 1.1, centre offset along e_b so that the minor vertex
    penetrates by 1e-3: one max at the vertex for cos θ = 0.99, 0.96; two symmetric maxima with
    equal δ = 0.0098 for cos θ = 0.93 (a²/b = 1.156 > R), the vertex becoming a minimum."""
    Rh = 1.1
    E = Ellipse2D(np.array([0.0, Rh - 1.0 + 1e-3]), np.array([1.0, 0.0]), 1.0 / cos_t, 1.0)
    assert two_point_possible(E, Rh) == (n_max == 2)
    cands = CircleSection(Rh).candidates(E)
    maxima = [c for c in cands if c.kind == 1]
    assert len(maxima) == n_max
    if n_max == 1:
        assert maxima[0].phi == pytest.approx(np.pi / 2, abs=1e-12)
        assert maxima[0].depth == pytest.approx(1e-3, abs=1e-12)
    else:
        assert maxima[0].depth == pytest.approx(maxima[1].depth, abs=1e-12)
        assert maxima[0].depth == pytest.approx(0.0098, abs=5e-5)
        vertex = [c for c in cands if c.kind == -1]
        assert len(vertex) == 1 and vertex[0].phi == pytest.approx(np.pi / 2, abs=1e-12)


def test_degenerate_centred_circle() -> None:
    E = Ellipse2D(np.zeros(2), np.array([1.0, 0.0]), 0.9, 0.9)
    assert CircleSection(1.0).candidates(E, margin=0.5) == []
    assert not jamming(E, CircleSection(1.0))
    E2 = Ellipse2D(np.zeros(2), np.array([1.0, 0.0]), 1.1, 1.1)
    c = CircleSection(1.0).candidates(E2)
    assert len(c) == 4 and all(x.depth == pytest.approx(0.1) for x in c)
    assert np.linalg.norm(sum(x.normal for x in c)) < 1e-12  # uniform: no net force
    assert jamming(E2, CircleSection(1.0))


def test_tilted_beam_centred_gives_axis_points() -> None:
    """d = 0, a > b: f = (b² − a²) sin φ cos φ, roots 0, π/2, π, 3π/2 (incl. the φ = π check)."""
    E = Ellipse2D(np.zeros(2), np.array([0.0, 1.0]), 1.05, 1.0)
    c = sorted(CircleSection(1.0).candidates(E, margin=0.1), key=lambda x: x.phi)
    np.testing.assert_allclose([x.phi for x in c], [0, np.pi / 2, np.pi, 1.5 * np.pi], atol=1e-12)
    assert [x.kind for x in c] == [1, -1, 1, -1]


def test_registry_and_errors() -> None:
    assert set(HOLE_SECTIONS) == {"circle", "rounded_polygon", "rounded_rectangle", "superellipse"}
    assert get_section("circle", radius=2.0) == CircleSection(2.0)
    assert get_section("superellipse", a=1.0, b=2.0, exponent=4.0).inscribed_radius() == 1.0
    with pytest.raises(ModelError, match=r"unknown hole section 'hexagon' \(known: circle, "
                       r"rounded_polygon, rounded_rectangle, superellipse\)"):
        get_section("hexagon")
    with pytest.raises(ModelError, match="radius"):
        get_section("circle", radius=-1.0)
    with pytest.raises(ModelError, match="circle"):
        get_section("circle", diameter=1.0)
    with pytest.raises(ModelError, match="exponent must be >= 2"):
        SuperellipseSection(a=1.0, b=1.0, exponent=1.5)
    with pytest.raises(ModelError, match="a >= b"):
        Ellipse2D(np.zeros(2), np.array([1.0, 0.0]), 0.5, 1.0)


def test_quartic_real_roots_match_numpy(rng: np.random.Generator) -> None:
    """The closed-form quartic solver of the circle detector against ``np.roots`` (companion
    eigenvalues): every real root found to 1e-8 relative (well-separated random roots), no
    spurious root; also with two roots made double (tangency), a tiny leading coefficient and
    the reduced degrees."""
    from flexmbs.contact.sections import quartic_real_roots

    out = np.empty(4)
    for _ in range(500):
        roots = rng.uniform(-3, 3, 4)
        c = rng.uniform(0.1, 10) * np.poly(roots)
        n = quartic_real_roots(*c, out)
        assert n == 4
        np.testing.assert_allclose(np.sort(out[:n]), np.sort(roots), rtol=1e-6, atol=1e-8)
    for _ in range(200):   # two real roots and a complex pair well off the axis: two found
        r1, r2 = rng.uniform(-3, 3, 2)
        c = np.polymul(np.poly([r1, r2]), [1.0, rng.uniform(-2, 2), rng.uniform(5, 9)])
        n = quartic_real_roots(*c, out)
        assert n == 2
        np.testing.assert_allclose(np.sort(out[:n]), np.sort([r1, r2]), rtol=1e-6, atol=1e-8)
    # a double root is reported (at least once) to the accuracy a double root allows
    c = np.poly([0.5, 0.5, -1.0, 2.0])
    n = quartic_real_roots(*c, out)
    assert np.min(np.abs(out[:n] - 0.5)) < 1e-6 and np.min(np.abs(out[:n] + 1.0)) < 1e-9
    # reduced degrees
    assert quartic_real_roots(0.0, 1.0, -6.0, 11.0, -6.0, out) == 3
    np.testing.assert_allclose(np.sort(out[:3]), [1.0, 2.0, 3.0], rtol=1e-9)
    assert quartic_real_roots(0.0, 0.0, 1.0, -3.0, 2.0, out) == 2
    np.testing.assert_allclose(np.sort(out[:2]), [1.0, 2.0], rtol=1e-12)


def test_a_sections_radii_are_computed_once(monkeypatch):
    """Sections are immutable: the bounding radius (a superellipse samples its wall 2 049
    times for it) is computed at the first call and kept, per instance; equal sections stay
    equal and hash alike, and a pickled section keeps working."""
    import pickle

    from flexmbs.contact.shapes.superellipse import SuperellipseSection

    a = SuperellipseSection(a=4e-3, b=2.6e-3, exponent=4.0)
    calls = []
    real = SuperellipseSection.boundary

    def counted(self, psi):
        calls.append(np.size(psi))
        return real(self, psi)

    monkeypatch.setattr(SuperellipseSection, "boundary", counted)
    r = a.bounding_radius()
    assert len(calls) == 1 and a.bounding_radius() == r and len(calls) == 1
    psi = np.linspace(0.0, 0.5 * np.pi, 200001)               # |y/a|^4 + |z/b|^4 = 1 in polar form
    rho = (np.abs(np.cos(psi) / 4e-3) ** 4 + np.abs(np.sin(psi) / 2.6e-3) ** 4) ** -0.25
    assert rho.max() <= r < rho.max() * (1 + 2e-6)
    b = SuperellipseSection(a=4e-3, b=2.6e-3, exponent=4.0)
    assert a == b and hash(a) == hash(b)
    assert b.bounding_radius() == r and len(calls) == 2        # its own, computed once
    c = pickle.loads(pickle.dumps(a))
    assert c == a and c.bounding_radius() == r
    assert a.inscribed_radius() == pytest.approx(2.6e-3)

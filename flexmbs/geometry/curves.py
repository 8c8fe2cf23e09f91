"""Beam centrelines: nodes, unit tangents and element lengths for ANCF cubic Hermite elements.

Pure geometry (numpy/scipy only). The reference configuration of an ANCF cable is
``r_i = points[i]``, ``r'_i = tangents[i]`` (unit) and element length ``lengths[e]``; the element
interpolates ``r(xi) = P0 H1 + L T0 H2 + P1 H3 + L T1 H4`` with the unit-interval Hermite functions
(docs/theory.md §I.1.1 and §I.4).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..budget import require_memory
from ..errors import GeometryError, ModelError

__all__ = [
    "Centerline",
    "arc",
    "bessel_tangents",
    "hermite_lengths",
    "line",
    "polyline",
]

FloatArray = NDArray[np.float64]

# 5-point Gauss-Legendre rule on [0, 1] (docs/theory.md §I.4 steps 1 and 3).
_GX, _GW = np.polynomial.legendre.leggauss(5)
GAUSS_XI: FloatArray = 0.5 * (_GX + 1.0)
GAUSS_W: FloatArray = 0.5 * _GW

# Relative tolerance (to the curve size) below which two points count as the same point.
_POINT_TOL = 1e-12


def _hermite(xi: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Unit-interval cubic Hermite functions H1..H4 and their xi-derivatives, shape (len(xi), 4)."""
    xi = np.asarray(xi, dtype=float)
    h = np.stack([1 - 3 * xi**2 + 2 * xi**3, xi - 2 * xi**2 + xi**3,
                  3 * xi**2 - 2 * xi**3, xi**3 - xi**2], axis=-1)
    dh = np.stack([6 * xi**2 - 6 * xi, 1 - 4 * xi + 3 * xi**2,
                   6 * xi - 6 * xi**2, 3 * xi**2 - 2 * xi], axis=-1)
    return h, dh


def _as_points(points: ArrayLike, what: str = "points") -> FloatArray:
    """(n, 3) float array from (n, 3) or (n, 2) input (z = 0 for planar input)."""
    try:
        p = np.array(points, dtype=float)
    except (TypeError, ValueError) as exc:
        raise GeometryError(f"{what} must be an (n, 3) array of numbers ({exc})") from exc
    if p.ndim != 2 or p.shape[1] not in (2, 3):
        raise GeometryError(f"{what} must have shape (n, 3) or (n, 2), got {p.shape}")
    if p.shape[1] == 2:
        p = np.hstack([p, np.zeros((p.shape[0], 1))])
    if not np.all(np.isfinite(p)):
        raise GeometryError(f"{what} contain NaN or infinite values")
    return p


def _as_vector(v: ArrayLike, what: str) -> FloatArray:
    try:
        a = np.array(v, dtype=float).reshape(-1)
    except (TypeError, ValueError) as exc:
        raise GeometryError(f"{what} must be a 3-vector of numbers ({exc})") from exc
    if a.shape == (2,):
        a = np.append(a, 0.0)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise GeometryError(f"{what} must be a finite 3-vector, got {v!r}")
    return a


def _unit_rows(t: FloatArray, what: str = "tangent") -> FloatArray:
    n = np.linalg.norm(t, axis=-1)
    bad = np.flatnonzero(~(n > 1e-300))
    if bad.size:
        raise GeometryError(f"zero-length {what} at node {int(bad[0])}: give a non-zero direction")
    return t / n[:, None]


def _check_elements(elements: object) -> int:
    if isinstance(elements, bool) or not isinstance(elements, (int, np.integer)):
        raise GeometryError(f"elements must be an integer >= 1 (got {elements!r})")
    if elements < 1:
        raise GeometryError(f"elements must be >= 1 (got {elements})")
    try:
        require_memory(int(elements), what=f"elements = {elements}", fix="use fewer elements")
    except ModelError as exc:
        raise GeometryError(str(exc)) from None
    return int(elements)


def _segments(points: FloatArray, closed: bool) -> tuple[FloatArray, FloatArray]:
    """Start and end points of every element (cyclic for closed curves)."""
    if closed:
        return points, np.roll(points, -1, axis=0)
    return points[:-1], points[1:]


@dataclass(frozen=True, eq=False)
class Centerline:
    """Discretised beam centreline: nodes, unit nodal tangents and element reference lengths.

    ``closed=True`` means the last element joins node ``n_nodes - 1`` back to node 0, so
    ``n_elem == n_nodes``; otherwise ``n_elem == n_nodes - 1``. The reference arc length ``s``
    used by :meth:`locate` and :meth:`frame_at` is the element parameter ``x = xi * L`` summed
    from node 0.

    Made by :func:`line`, :func:`arc`, :func:`polyline` or :func:`read_curve`.

    Parameters
    ----------
    points : ndarray, shape (n_nodes, 3)
        Node positions [m].
    tangents : ndarray, shape (n_nodes, 3)
        Unit tangents at the nodes.
    lengths : ndarray, shape (n_elem,)
        Reference length of each element [m].
    closed : bool, default False
        Whether the last element joins the last node back to node 0.
    """

    points: FloatArray
    tangents: FloatArray
    lengths: FloatArray
    closed: bool = False

    def __post_init__(self) -> None:
        p = _as_points(self.points)
        t = _as_points(self.tangents, "tangents")
        length = np.array(self.lengths, dtype=float).reshape(-1)
        if t.shape != p.shape:
            raise GeometryError(f"tangents shape {t.shape} does not match points shape {p.shape}")
        n_elem = p.shape[0] if self.closed else p.shape[0] - 1
        if n_elem < 1 or (self.closed and p.shape[0] < 2):
            raise GeometryError("a centreline needs at least 2 nodes (1 element)")
        if length.shape != (n_elem,):
            raise GeometryError(f"lengths must have shape ({n_elem},) for {p.shape[0]} nodes "
                                f"({'closed' if self.closed else 'open'}), got {length.shape}")
        if not np.all(np.isfinite(length)) or np.any(length <= 0.0):
            raise GeometryError(f"element lengths must be finite and > 0 (min {length.min()!r})")
        t = _unit_rows(t)
        for name, arr in (("points", p), ("tangents", t), ("lengths", length)):
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)
        object.__setattr__(self, "closed", bool(self.closed))

    @property
    def n_nodes(self) -> int:
        return int(self.points.shape[0])

    @property
    def n_elem(self) -> int:
        return int(self.lengths.shape[0])

    @property
    def total_length(self) -> float:
        return float(np.sum(self.lengths))

    def arc_length_of_nodes(self) -> FloatArray:
        """Reference arc length of every node from node 0, shape (n_nodes,)."""
        s = np.concatenate([[0.0], np.cumsum(self.lengths)])
        return s[: self.n_nodes]

    def locate(self, s: float) -> tuple[int, float]:
        """Element index and ``xi`` in [0, 1] of reference arc length ``s``.

        Open curves accept ``0 <= s <= total_length`` (a 1e-12 relative slack is clipped); closed
        curves wrap ``s`` periodically.
        """
        s = float(s)
        total = self.total_length
        if not np.isfinite(s):
            raise GeometryError(f"arc length s must be finite (got {s})")
        if self.closed:
            s = s % total
        else:
            slack = 1e-12 * total
            if s < -slack or s > total + slack:
                raise GeometryError(f"arc length s = {s:.6g} is outside the curve [0, {total:.6g}]")
            s = min(max(s, 0.0), total)
            if s == total:
                return self.n_elem - 1, 1.0
        ends = np.cumsum(self.lengths)
        e = int(np.searchsorted(ends, s, side="right"))
        e = min(e, self.n_elem - 1)
        start = ends[e] - self.lengths[e]
        xi = min(max((s - start) / self.lengths[e], 0.0), 1.0)
        return e, float(xi)

    def element_nodes(self, e: int) -> tuple[int, int]:
        """Node indices at the start and the end of element ``e``."""
        return e, (e + 1) % self.n_nodes

    def frame_at(self, s: float) -> tuple[FloatArray, FloatArray]:
        """Position (3,) and unit tangent (3,) at reference arc length ``s`` (cubic Hermite)."""
        e, xi = self.locate(s)
        i0, i1 = self.element_nodes(e)
        length = self.lengths[e]
        h, dh = _hermite(np.array([xi]))
        coef = np.stack([self.points[i0], length * self.tangents[i0],
                         self.points[i1], length * self.tangents[i1]])
        pos = h[0] @ coef
        d = dh[0] @ coef
        return pos, d / np.linalg.norm(d)


# --------------------------------------------------------------------------------------------------
# Element lengths and tangents


def hermite_lengths(points: ArrayLike, tangents: ArrayLike, closed: bool = False,
                    iterations: int = 5) -> FloatArray:
    """Element lengths L with L = arc length of the Hermite cubic built with slopes L*T.

    docs/theory.md §I.4 step 3: start from the chord and iterate
    ``L <- int_0^1 |P0 H1' + L T0 H2' + P1 H3' + L T1 H4'| dxi`` (5-point Gauss) ``iterations``
    times (fewer if converged to round-off). Tangents are normalised first. On a circular arc the
    result is ``R theta_e (1 - theta_e^4 / 720 + ...)`` (measured, see tests).
    """
    p = _as_points(points)
    t = _unit_rows(_as_points(tangents, "tangents"))
    if t.shape != p.shape:
        raise GeometryError(f"tangents shape {t.shape} does not match points shape {p.shape}")
    if iterations < 0:
        raise GeometryError(f"iterations must be >= 0 (got {iterations})")
    p0, p1 = _segments(p, closed)
    t0, t1 = _segments(t, closed)
    chord = np.linalg.norm(p1 - p0, axis=1)
    if np.any(chord <= 0.0):
        e = int(np.flatnonzero(chord <= 0.0)[0])
        raise GeometryError(f"element {e} has coincident end points; remove duplicate points")
    _, dh = _hermite(GAUSS_XI)  # (5, 4)
    fixed = dh[:, 0, None, None] * p0 + dh[:, 2, None, None] * p1  # (5, n_elem, 3)
    slope = dh[:, 1, None, None] * t0 + dh[:, 3, None, None] * t1
    length = chord.copy()
    for _ in range(iterations):
        new = GAUSS_W @ np.linalg.norm(fixed + length[None, :, None] * slope, axis=2)
        done = np.max(np.abs(new - length) / length) < 1e-15
        length = new
        if done:
            break
    return length


def bessel_tangents(points: ArrayLike, closed: bool = False) -> FloatArray:
    """Unit Bessel tangents with chord-length weights (docs/theory.md §I.4 step 2).

    ``T_i ~ d_{i-1}^2 (P_{i+1} - P_i) + d_i^2 (P_i - P_{i-1})``: the tangent of the circle through
    three consecutive points, exact on circles for any spacing. Open ends reflect the neighbouring
    tangent about the end chord; a two-point curve gets the chord direction at both ends.
    """
    p = _as_points(points)
    n = p.shape[0]
    if n < 2:
        raise GeometryError("tangents need at least 2 points")
    if closed:
        a = p - np.roll(p, 1, axis=0)     # P_i - P_{i-1}
        b = np.roll(p, -1, axis=0) - p    # P_{i+1} - P_i
    else:
        if n == 2:
            c = _unit_rows((p[1] - p[0])[None], "chord")[0]
            return np.array([c, c])
        a = p[1:-1] - p[:-2]
        b = p[2:] - p[1:-1]
    da2 = np.sum(a * a, axis=1)
    db2 = np.sum(b * b, axis=1)
    t = da2[:, None] * b + db2[:, None] * a
    norm = np.linalg.norm(t, axis=1)
    # a reversal (b anti-parallel to a) has no tangent: the circle through the points degenerates
    cross = np.linalg.norm(np.cross(a, b), axis=1)
    reverse = (np.einsum("ij,ij->i", a, b) < 0.0) & (cross <= 1e-12 * np.sqrt(da2 * db2))
    bad = np.flatnonzero(reverse | ~(norm > 0.0))
    if bad.size:
        i = int(bad[0]) + (0 if closed else 1)
        raise GeometryError(f"the curve reverses at point {i}: consecutive segments point in "
                            "opposite directions, so no tangent exists there")
    t = t / norm[:, None]
    if closed:
        return t
    c0 = (p[1] - p[0]) / np.linalg.norm(p[1] - p[0])
    c1 = (p[-1] - p[-2]) / np.linalg.norm(p[-1] - p[-2])
    first = 2.0 * np.dot(c0, t[0]) * c0 - t[0]
    last = 2.0 * np.dot(c1, t[-1]) * c1 - t[-1]
    return np.vstack([first, t, last])


# --------------------------------------------------------------------------------------------------
# Constructors


def line(start: ArrayLike, end: ArrayLike, elements: int) -> Centerline:
    """Straight centreline from ``start`` to ``end`` with ``elements`` equal elements.

    Parameters
    ----------
    start, end : array_like of 3 floats
        End points [m].
    elements : int
        Number of elements.

    Returns
    -------
    Centerline
        The line's nodes, tangents and element lengths.
    """
    n = _check_elements(elements)
    a = _as_vector(start, "line start")
    b = _as_vector(end, "line end")
    chord = b - a
    length = float(np.linalg.norm(chord))
    if not length > _POINT_TOL * max(1.0, float(np.linalg.norm(a)), float(np.linalg.norm(b))):
        raise GeometryError(f"line start and end coincide ({a.tolist()}): give two distinct points")
    w = np.linspace(0.0, 1.0, n + 1)
    points = a + w[:, None] * chord
    points[-1] = b
    tangents = np.tile(chord / length, (n + 1, 1))
    return Centerline(points, tangents, np.full(n, length / n))


def arc(center: ArrayLike, radius: float, start: ArrayLike, angle: float,
        normal: ArrayLike = (0.0, 0.0, 1.0), *, elements: int) -> Centerline:
    """Circular arc: exact nodes and tangents, element lengths ``radius*|angle|/elements``.

    ``start`` is a point on the circle (``|start - center| == radius`` and perpendicular to
    ``normal``); the arc turns by ``angle`` (rad, right-handed about ``normal``; negative turns the
    other way). ``|angle| == 2 pi`` gives a closed loop with ``elements`` nodes.

    Parameters
    ----------
    center : array_like of 3 floats
        Centre of the circle [m].
    radius : float
        Radius [m].
    start : array_like of 3 floats
        First node, on the circle [m].
    angle : float
        Angle turned [rad].
    normal : array_like of 3 floats, default (0, 0, 1)
        Axis of the circle.
    elements : int
        Number of elements.

    Returns
    -------
    Centerline
        The arc's nodes, tangents and element lengths.
    """
    n = _check_elements(elements)
    c = _as_vector(center, "arc center")
    p0 = _as_vector(start, "arc start")
    try:
        radius = float(radius)
        angle = float(angle)
    except (TypeError, ValueError) as exc:
        raise GeometryError(f"arc radius and angle must be numbers ({exc})") from exc
    if not (np.isfinite(radius) and radius > 0.0):
        raise GeometryError(f"arc radius must be > 0 (got {radius:g})")
    if not np.isfinite(angle) or angle == 0.0:
        raise GeometryError(f"arc angle must be a non-zero finite angle in rad (got {angle:g})")
    full = abs(abs(angle) - 2.0 * np.pi) <= 1e-12 * 2.0 * np.pi
    if abs(angle) > 2.0 * np.pi and not full:
        raise GeometryError(f"arc angle must satisfy |angle| <= 2*pi (got {angle:g}); a longer arc "
                            "overlaps itself")
    nrm = _as_vector(normal, "arc normal")
    nn = np.linalg.norm(nrm)
    if nn == 0.0:
        raise GeometryError("arc normal must be a non-zero vector")
    nrm = nrm / nn
    u = p0 - c
    dist = float(np.linalg.norm(u))
    tol = 1e-9 * radius
    if abs(dist - radius) > tol:
        raise GeometryError(f"arc start {p0.tolist()} is at distance {dist:.9g} from the center, "
                            f"not on the circle of radius {radius:.9g}")
    if abs(np.dot(u, nrm)) > tol:
        raise GeometryError("arc start - center must be perpendicular to the arc normal "
                            f"(dot = {np.dot(u, nrm):.3g}); check 'normal'")
    e1 = u / dist
    e2 = np.cross(nrm, e1)
    n_nodes = n if full else n + 1
    phi = np.arange(n_nodes) * (angle / n)
    cos, sin = np.cos(phi)[:, None], np.sin(phi)[:, None]
    points = c + radius * (cos * e1 + sin * e2)
    tangents = np.sign(angle) * (-sin * e1 + cos * e2)
    return Centerline(points, tangents, np.full(n, radius * abs(angle) / n), closed=full)


def _clean_points(p: FloatArray, closed: bool) -> FloatArray:
    """Check distinct consecutive points; drop a repeated first point closing a closed curve."""
    scale = max(float(np.max(np.ptp(p, axis=0))) if p.shape[0] else 0.0, 1e-300)
    tol = _POINT_TOL * max(scale, float(np.max(np.abs(p))) if p.size else 0.0)
    if p.shape[0] < 2:
        raise GeometryError(f"polyline needs at least 2 distinct points (got {p.shape[0]})")
    if closed and p.shape[0] > 2 and np.linalg.norm(p[-1] - p[0]) <= tol:
        p = p[:-1]
    step = np.linalg.norm(np.diff(p, axis=0), axis=1)
    dup = np.flatnonzero(step <= tol)
    if dup.size and p.shape[0] - dup.size < 2:
        raise GeometryError("polyline needs at least 2 distinct points (all points coincide)")
    if dup.size:
        i = int(dup[0])
        raise GeometryError(f"polyline points {i} and {i + 1} coincide ({p[i].tolist()}): remove "
                            "duplicate consecutive points")
    if closed and p.shape[0] < 3:
        raise GeometryError("a closed polyline needs at least 3 distinct points "
                            f"(got {p.shape[0]})")
    return p


def _gauss_arc(deriv: Any, ua: FloatArray, ub: FloatArray) -> FloatArray:
    """int_ua^ub |c'(u)| du with 5-point Gauss, element-wise."""
    h = ub - ua
    u = ua[:, None] + h[:, None] * GAUSS_XI[None, :]
    speed = np.linalg.norm(deriv(u), axis=-1)
    return h * (speed @ GAUSS_W)


def _resample(p: FloatArray, t: FloatArray | None, closed: bool,
              n_elem: int) -> tuple[FloatArray, FloatArray]:
    """Nodes and unit tangents at equal spline arc length (docs/theory.md §I.4 step 1)."""
    # imported here: scipy.interpolate costs ~0.5 s of start-up for every command
    from scipy.interpolate import CubicHermiteSpline, CubicSpline

    pk = np.vstack([p, p[:1]]) if closed else p
    if t is None:
        # chord-length parametrised interpolating cubic spline (C2)
        u = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pk, axis=0), axis=1))])
        if closed:
            spline = CubicSpline(u, pk, bc_type="periodic")
        elif p.shape[0] == 2:
            spline = CubicSpline(u, pk, bc_type="natural")  # the straight segment
        else:
            spline = CubicSpline(u, pk, bc_type="not-a-knot")
    else:
        # Given unit tangents: parametrise by the Hermite element lengths, so that the spline is the
        # same C1 cubic Hermite curve the ANCF elements interpolate (resampling a Centerline keeps
        # its geometry).
        tk = np.vstack([t, t[:1]]) if closed else t
        u = np.concatenate([[0.0], np.cumsum(hermite_lengths(p, t, closed))])
        spline = CubicHermiteSpline(u, pk, tk)
    deriv = spline.derivative()
    seg = _gauss_arc(deriv, u[:-1], u[1:])
    cum = np.concatenate([[0.0], np.cumsum(seg)])
    total = cum[-1]
    n_nodes = n_elem if closed else n_elem + 1
    target = total * np.arange(n_nodes) / n_elem
    k = np.clip(np.searchsorted(cum, target, side="right") - 1, 0, len(seg) - 1)
    lo, hi = u[k].copy(), u[k + 1].copy()
    # initial guess: linear in the interval, then safeguarded Newton on s(u) = target
    frac = np.clip((target - cum[k]) / seg[k], 0.0, 1.0)
    uu = lo + frac * (hi - lo)
    for _ in range(60):
        f = cum[k] + _gauss_arc(deriv, u[k], uu) - target
        lo = np.where(f < 0.0, uu, lo)
        hi = np.where(f > 0.0, uu, hi)
        step = f / np.linalg.norm(deriv(uu), axis=1)
        new = uu - step
        outside = (new <= lo) | (new >= hi)
        new = np.where(outside, 0.5 * (lo + hi), new)
        if np.max(np.abs(new - uu)) <= 1e-14 * u[-1]:
            uu = new
            break
        uu = new
    uu[0] = u[0]
    if not closed:
        uu[-1] = u[-1]
    points = spline(uu)
    points[0] = p[0]
    if not closed:
        points[-1] = p[-1]
    return points, _unit_rows(deriv(uu))


def polyline(points: ArrayLike, tangents: ArrayLike | None = None, *, closed: bool = False,
             elements: int | None = None) -> Centerline:
    """Centreline through ``points`` (docs/theory.md §I.4).

    - ``tangents=None``: Bessel tangents (exact on circles); otherwise the given directions are
      normalised and used.
    - ``elements``: resample to that many elements of equal arc length along a cubic spline through
      the points (chord-length parametrised ``CubicSpline``, periodic when closed; with given
      tangents the C1 Hermite spline through points and tangents). ``None``: one element per
      segment.
    - Element lengths by the Hermite fixed point (:func:`hermite_lengths`).
    - ``closed``: the last point connects back to the first (a repeated first point is dropped).

    Parameters
    ----------
    points : array_like, shape (n, 3)
        Points on the curve [m].
    tangents : array_like, shape (n, 3), optional
        Directions at the points (default: Bessel tangents).
    closed : bool, default False
        Whether the curve closes back to the first point.
    elements : int, optional
        Resample to this many elements of equal arc length (default: one per segment).

    Returns
    -------
    Centerline
        Nodes, unit tangents and element lengths.
    """
    p = _as_points(points)
    t: FloatArray | None = None
    if tangents is not None:
        t = _as_points(tangents, "tangents")
        if t.shape != p.shape:
            raise GeometryError(f"tangents shape {t.shape} does not match points shape {p.shape}")
    p_clean = _clean_points(p, bool(closed))
    if t is not None:
        t = _unit_rows(t[: p_clean.shape[0]])
    p = p_clean
    if t is None:
        t = bessel_tangents(p, bool(closed)) if elements is None else None
    if elements is not None:
        n = _check_elements(elements)
        if closed and n < 2:
            raise GeometryError(f"a closed curve needs at least 2 elements (got {n})")
        p, t = _resample(p, t, bool(closed), n)
    assert t is not None
    return Centerline(p, t, hermite_lengths(p, t, bool(closed)), closed=bool(closed))


"""3D beam/section kernels of the clearance sliding joint (FORMULATION II §2, §4).

Beam data is an open chain of 12-DOF ANCF cable elements: ``q_e (n_elem, 12)`` with rows
``[r0, r0', r1, r1']`` (``'`` = d/dx) and ``lengths (n_elem,)``; element ``e``'s end node is element
``e+1``'s start node. Positions along the chain use the *global parameter* ``s = e + ξ`` (C¹ across
nodes), so Newton iterations continue into the neighbour element with ``ξ ∓ 1`` when ξ leaves
[0, 1] simply by moving ``s``. Derivatives are w.r.t. the element parameter ξ
(``r_ξ = L r'``, ``r_ξξ = L² r''``).

The public functions with keyword options (:func:`section_crossing`, :func:`closest_point`) are thin
Python wrappers around ``*_kernel`` functions taking every argument positionally (callable from
other numba code; omitted numba defaults would cost ~40 µs of dispatch per call). All kernels are
numba-compiled (``flexmbs._jit.njit``), scalar-loop based and allocate only their
3-vector outputs; inputs must be float64 arrays (``np.ascontiguousarray(..., dtype=float)``).
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import njit
from ..elements.ancf_cable import element_point as _elem_point
from ..elements.ancf_cable import shape_xi

__all__ = [
    "beam_point",
    "shape_xi",
    "section_crossing",
    "section_crossing_kernel",
    "closest_point_kernel",
    "section_ellipse",
    "closest_point",
    "to_section",
    "from_section",
]


@njit(inline="always")
def _clip(x, lo, hi):  # noqa: ANN001, ANN202
    return lo if x < lo else (hi if x > hi else x)


@njit
def beam_point(q_e, lengths, elem, xi):  # noqa: ANN001, ANN201
    """``(r, r_ξ, r_ξξ)`` of element ``elem`` at ξ (FORMULATION II §0, r = S(ξ)e_k)."""
    return _elem_point(q_e[elem], lengths[elem], xi)


@njit(inline="always")
def _locate(s, n):  # noqa: ANN001, ANN202
    """Global parameter s ∈ [0, n] -> (element, ξ); a node belongs to the element it starts."""
    e = int(math.floor(s))
    if e < 0:
        e = 0
    if e > n - 1:
        e = n - 1
    return e, s - e


@njit(inline="always")
def _dot(a, b):  # noqa: ANN001, ANN202
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(inline="always")
def _cross(a, b):  # noqa: ANN001, ANN202
    out = np.empty(3)
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]
    return out


@njit
def _phi_at(q_e, lengths, origin, normal, s):  # noqa: ANN001, ANN202
    n = q_e.shape[0]
    e, xi = _locate(s, n)
    r, rx, _ = _elem_point(q_e[e], lengths[e], xi)
    d = r - origin
    return _dot(normal, d), _dot(normal, rx), e, xi, math.sqrt(_dot(d, d))


@njit
def _solve_in_bracket(q_e, lengths, origin, normal, lo, hi, flo, tol, max_iter):  # noqa: ANN001, ANN202
    """Root of φ(s) in [lo, hi] with φ(lo)φ(hi) ≤ 0: Newton, bisection if it leaves the bracket."""
    s = 0.5 * (lo + hi)
    for _ in range(max_iter + 30):
        f, df, _, _, _ = _phi_at(q_e, lengths, origin, normal, s)
        if abs(f) <= tol:
            return s, True
        if (f < 0.0) == (flo < 0.0):
            lo = s
            flo = f
        else:
            hi = s
        s_new = s - f / df if df != 0.0 else 0.5 * (lo + hi)
        if not (lo < s_new < hi):
            s_new = 0.5 * (lo + hi)
        if hi - lo <= 1e-15 * (1.0 + abs(hi)):
            return s_new, True
        s = s_new
    return s, False


def section_crossing(q_e: np.ndarray, lengths: np.ndarray, origin: np.ndarray, normal: np.ndarray,
                     elem0: int, xi0: float, *, tol: float = 1e-12, max_iter: int = 30,
                     max_distance: float = np.inf) -> tuple[int, float, bool]:
    """Crossing of the beam centreline with a section plane; see :func:`section_crossing_kernel`."""
    e, xi, found = section_crossing_kernel(q_e, lengths, origin, normal, int(elem0), float(xi0),
                                           float(tol), int(max_iter), float(max_distance))
    return int(e), float(xi), bool(found)


@njit
def section_crossing_kernel(q_e, lengths, origin, normal, elem0, xi0, tol, max_iter, max_distance):  # noqa: ANN001, ANN201
    """Crossing of the beam centreline with the plane n·(x − O) = 0 (FORMULATION II §2).

    Safeguarded Newton on φ(s) = n·(r(s) − O) from ``s = elem0 + xi0`` (steps ≤ 1 element, across
    nodes with ξ ∓ 1, bisection once a sign change is bracketed); converged when
    ``|φ| < tol·max(1, |O|)``. If it fails, leaves the chain, or lands farther than
    ``max_distance`` from O, a global search takes every element whose end nodes give opposite
    signs of φ and keeps the crossing closest to O.
    Returns ``(elem, xi, found)``.
    """
    n = q_e.shape[0]
    atol = tol * max(1.0, math.sqrt(_dot(origin, origin)))
    s = _clip(elem0 + xi0, 0.0, float(n))
    have_br = False
    lo = 0.0
    hi = 0.0
    flo = 0.0
    s_prev = -1.0
    f_prev = 0.0
    ends_hit = 0
    for _ in range(max_iter):
        f, df, e, xi, dist = _phi_at(q_e, lengths, origin, normal, s)
        if abs(f) <= atol:
            if dist <= max_distance:
                return e, xi, True
            break
        if s_prev >= 0.0 and (f < 0.0) != (f_prev < 0.0):
            have_br = True
            if s_prev < s:
                lo, hi, flo = s_prev, s, f_prev
            else:
                lo, hi, flo = s, s_prev, f
        elif have_br:
            if (f < 0.0) == (flo < 0.0):
                lo, flo = s, f
            else:
                hi = s
        if df != 0.0:
            ds = -f / df
        else:
            ds = 0.5
        ds = _clip(ds, -1.0, 1.0)
        s_new = s + ds
        if have_br and not (lo < s_new < hi):
            s_new = 0.5 * (lo + hi)
        if s_new < 0.0 or s_new > n:
            s_new = _clip(s_new, 0.0, float(n))
            ends_hit += 1
            if ends_hit > 2:
                break
        s_prev, f_prev = s, f
        s = s_new
    # global fallback over node sign changes (FORMULATION II §2)
    best_d = np.inf
    best_s = -1.0
    fa = _dot(normal, q_e[0, 0:3] - origin)
    for k in range(n):
        fb = _dot(normal, q_e[k, 6:9] - origin)
        if fa == 0.0 or fa * fb < 0.0 or (fb == 0.0 and k == n - 1):
            if fa == 0.0:
                sr, ok = float(k), True
            elif fb == 0.0:
                sr, ok = float(k + 1), True
            else:
                sr, ok = _solve_in_bracket(q_e, lengths, origin, normal, float(k), float(k + 1),
                                           fa, atol, max_iter)
            if ok:
                _, _, _, _, dist = _phi_at(q_e, lengths, origin, normal, sr)
                if dist < best_d:
                    best_d = dist
                    best_s = sr
        fa = fb
    if best_s >= 0.0 and best_d <= max_distance:
        e, xi = _locate(best_s, n)
        return e, xi, True
    return elem0, xi0, False


@njit
def section_ellipse(tangent_vec, normal, e_y, e_z, r_b):  # noqa: ANN001, ANN201
    """Tangent-cylinder section ellipse (FORMULATION II §2): ``(a, b, e_a, e_b, cos θ)``.

    ``b = r_b``, ``a = r_b / cos θ`` with ``cos θ = |t·n|``; ``e_b = t×n/|t×n|`` (minor axis),
    ``e_a = n×e_b`` (in-plane tangent direction, major axis). When ``|t×n| < 1e-10`` the section is
    a circle and ``e_a = e_y``, ``e_b = e_z``. ``cos θ = 0`` (beam in the plane) gives ``a = inf``.
    """
    t = tangent_vec / math.sqrt(_dot(tangent_vec, tangent_vec))
    c = abs(_dot(t, normal))
    eb = _cross(t, normal)
    sn = math.sqrt(_dot(eb, eb))
    if sn < 1e-10:
        return r_b, r_b, e_y.copy(), e_z.copy(), c
    eb = eb / sn
    ea = _cross(normal, eb)
    a = r_b / c if c > 0.0 else np.inf
    return a, r_b, ea, eb, c


def closest_point(q_e: np.ndarray, lengths: np.ndarray, Q: np.ndarray, elem0: int, xi0: float, *,
                  tol: float = 1e-13, max_iter: int = 30
                  ) -> tuple[int, float, np.ndarray, np.ndarray, np.ndarray]:
    """Closest-point projection of Q on the centreline; see :func:`closest_point_kernel`."""
    e, xi, P, rx, rxx = closest_point_kernel(q_e, lengths, Q, int(elem0), float(xi0), float(tol),
                                             int(max_iter))
    return int(e), float(xi), P, rx, rxx


@njit
def closest_point_kernel(q_e, lengths, Q, elem0, xi0, tol, max_iter):  # noqa: ANN001, ANN201
    """Closest-point projection of Q on the centreline (FORMULATION II §4).

    Newton on ``h(s) = (r − Q)·r_ξ`` with ``h_ξ = r_ξ·r_ξ + (r − Q)·r_ξξ`` from ``s = elem0 + xi0``;
    steps ≤ ½ element, continued across nodes; bracket [h < 0, h > 0] with bisection; a descent step
    when ``h_ξ ≤ 0``; clamped at the chain ends (the end point is returned when the minimum lies
    beyond it). Converged when ``|h| ≤ tol·|r_ξ|·max(1, |Q|)`` or the step is below 1e-14.
    Returns ``(elem, xi, P, r_xi, r_xixi)``.
    """
    n = q_e.shape[0]
    scale = tol * max(1.0, math.sqrt(_dot(Q, Q)))
    s = _clip(elem0 + xi0, 0.0, float(n))
    lo = -1.0
    hi = -1.0
    e, xi = _locate(s, n)
    r, rx, rxx = _elem_point(q_e[e], lengths[e], xi)
    for _ in range(max_iter):
        d = r - Q
        h = _dot(d, rx)
        if abs(h) <= scale * math.sqrt(_dot(rx, rx)):
            break
        hx = _dot(rx, rx) + _dot(d, rxx)
        if h < 0.0:
            if lo < 0.0 or s > lo:
                lo = s
        else:
            if hi < 0.0 or s < hi:
                hi = s
        if hx > 0.0:
            ds = -h / hx
        else:
            ds = -0.25 if h > 0.0 else 0.25
        ds = _clip(ds, -0.5, 0.5)
        s_new = s + ds
        if lo >= 0.0 and hi >= 0.0 and lo < hi and not (lo < s_new < hi):
            s_new = 0.5 * (lo + hi)
        s_new = _clip(s_new, 0.0, float(n))
        if abs(s_new - s) <= 1e-14 * (1.0 + s):
            break
        s = s_new
        e, xi = _locate(s, n)
        r, rx, rxx = _elem_point(q_e[e], lengths[e], xi)
    return e, xi, r, rx, rxx


@njit
def to_section(x, origin, e_y, e_z):  # noqa: ANN001, ANN201
    """2D section coordinates ``((x − O)·e_y, (x − O)·e_z)`` of a 3D point (FORMULATION II §2)."""
    d = x - origin
    out = np.empty(2)
    out[0] = _dot(d, e_y)
    out[1] = _dot(d, e_z)
    return out


@njit
def from_section(y, origin, e_y, e_z):  # noqa: ANN001, ANN201
    """3D point ``O + y₀ e_y + y₁ e_z`` of 2D section coordinates."""
    return origin + y[0] * e_y + y[1] * e_z


@njit
def section_state(q_e, lengths, origin, normal, e_y, e_z, elem0, xi0, r_b, max_distance):  # noqa: ANN001, ANN201
    """The beam in one hole section (FORMULATION II §2): the crossing of its axis with the section
    plane ``(origin, normal)`` (warm-started at ``(elem0, xi0)``, within ``max_distance`` of
    the origin) and the ellipse of its cross-section there, in section coordinates (e_y, e_z).

    Returns ``(found, e, xi, cy, cz, a, b, eax, eay)``: element and ξ of the crossing, ellipse
    centre, semi-axes ``a ≥ b`` and unit major axis. The one statement of the section loop used
    by detection, the initial check and the section output."""
    e, xi, found = section_crossing_kernel(q_e, lengths, origin, normal, elem0, xi0, 1e-12,
                                           np.int64(30), max_distance)
    if not found:
        return False, e, xi, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0
    r, rx, _ = beam_point(q_e, lengths, e, xi)
    a, b, ea3, _, _ = section_ellipse(rx, normal, e_y, e_z, r_b)
    cy = 0.0
    cz = 0.0
    for c in range(3):
        cy += (r[c] - origin[c]) * e_y[c]
        cz += (r[c] - origin[c]) * e_z[c]
    eax = _dot(ea3, e_y)
    eay = _dot(ea3, e_z)
    nrm = math.hypot(eax, eay)
    if nrm > 0.0:
        eax /= nrm
        eay /= nrm
    else:
        eax, eay = 1.0, 0.0
    if a < b:
        a = b
    return True, e, xi, cy, cz, a, b, eax, eay

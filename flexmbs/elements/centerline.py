"""Geometry of the centreline of a chain of cable elements (docs/theory.md §II.2, §II.4): point,
plane crossing and closest-point projection. Owned by the element family; the sliding joint
and the clearance joint (contact/geometry.py) call these kernels.

Beam data is an open chain of elements' Hermite centreline coordinates ``q_e (n_elem, 12)`` with
rows ``[r0, r0', r1, r1']`` (``'`` = d/dx) and ``lengths (n_elem,)``; element ``e``'s end node is
element ``e+1``'s start node. Positions along the chain use the *global parameter* ``s = e + ξ``
(C¹ across nodes), so Newton iterations continue into the neighbour element with ``ξ ∓ 1`` when
ξ leaves [0, 1] simply by moving ``s``. Derivatives are w.r.t. ξ (``r_ξ = L r'``).

The public functions with keyword options (:func:`section_crossing`, :func:`closest_point`) are
thin Python wrappers around ``*_kernel`` functions taking every argument positionally.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import njit
from .hermite import element_point as _elem_point
from .hermite import element_point_values

__all__ = ["dot3", "cross3", "beam_point", "section_crossing", "section_crossing_kernel", "closest_point",
           "closest_point_kernel"]

@njit(inline="always")
def _clip(x, lo, hi):
    return lo if x < lo else (hi if x > hi else x)


@njit
def beam_point(q_e, lengths, elem, xi):
    """``(r, r_ξ, r_ξξ)`` of element ``elem`` at ξ (docs/theory.md §II.0, r = S(ξ)e_k)."""
    return _elem_point(q_e[elem], lengths[elem], xi)


@njit(inline="always")
def _locate(s, n):
    """Global parameter s ∈ [0, n] -> (element, ξ); a node belongs to the element it starts."""
    e = int(math.floor(s))
    if e < 0:
        e = 0
    if e > n - 1:
        e = n - 1
    return e, s - e


@njit(inline="always")
def dot3(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(inline="always")
def cross3(a, b):
    out = np.empty(3)
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]
    return out


@njit(refcount=False)
def _phi_at(q_e, lengths, origin, normal, s):
    n = q_e.shape[0]
    e, xi = _locate(s, n)
    r, rx, _ = element_point_values(q_e[e], lengths[e], xi)
    d = (r[0] - origin[0], r[1] - origin[1], r[2] - origin[2])
    return dot3(normal, d), dot3(normal, rx), e, xi, math.sqrt(dot3(d, d))


@njit(inline="always")
def straddles(fa, fb):
    """A root lies in ``[a, b]`` by the signs of ``f(a) = fa``, ``f(b) = fb``: ``fa`` zero, or
    the signs opposite (compared, not multiplied: ``fa fb`` underflows to 0 when both are
    tiny, and a root on a sample went unseen)."""
    return fa == 0.0 or (fa < 0.0 and fb > 0.0) or (fa > 0.0 and fb < 0.0)


@njit
def bracketed_newton_step(s, f, df, lo, hi, flo):
    """One Newton step on a bracketed root, bisection when it would leave the bracket: the
    bracket ``[lo, hi]`` (``flo`` = f(lo)) shrinks to the side of s that keeps the sign change.
    Returns ``(s_new, lo, hi, flo)`` (used by every bracketed root search of the package)."""
    if (f < 0.0) == (flo < 0.0):
        lo = s
        flo = f
    else:
        hi = s
    s_new = s - f / df if df != 0.0 else 0.5 * (lo + hi)
    if not (lo < s_new < hi):
        s_new = 0.5 * (lo + hi)
    return s_new, lo, hi, flo


@njit(refcount=False)
def _solve_in_bracket(q_e, lengths, origin, normal, lo, hi, flo, tol, max_iter, s0):
    """Root of φ(s) in [lo, hi] with φ(lo)φ(hi) ≤ 0: Newton from ``s0`` (the midpoint when
    ``s0`` is not inside the bracket), bisection if it leaves the bracket."""
    s = s0 if lo < s0 < hi else 0.5 * (lo + hi)
    for _ in range(max_iter + 30):
        f, df, _, _, _ = _phi_at(q_e, lengths, origin, normal, s)
        if abs(f) <= tol:
            return s, True
        s_new, lo, hi, flo = bracketed_newton_step(s, f, df, lo, hi, flo)
        if hi - lo <= 1e-15 * (1.0 + abs(hi)):
            return s_new, True
        s = s_new
    return s, False


@njit(inline="always")
def _control_point(q, L, m, c):
    """Component c of the element's Bézier control point m: ``r0``, ``r0 + L r0′/3``,
    ``r1 − L r1′/3``, ``r1`` (the cubic lies in their convex hull)."""
    if m == 0:
        return q[c]
    if m == 1:
        return q[c] + L * q[3 + c] / 3.0
    if m == 2:
        return q[6 + c] - L * q[9 + c] / 3.0
    return q[6 + c]


@njit(inline="always")
def element_bounding_sphere(q, L, centre):
    """A sphere holding the element's centreline (the cubic's Bézier control points ``r0``,
    ``r0 + L r0′/3``, ``r1 − L r1′/3``, ``r1``: the curve lies in their convex hull): writes the
    centre (3,) and returns the radius."""
    for c in range(3):
        centre[c] = 0.25 * (_control_point(q, L, 0, c) + _control_point(q, L, 1, c)
                            + _control_point(q, L, 2, c) + _control_point(q, L, 3, c))
    rho = 0.0
    for m in range(4):
        d2 = 0.0
        for c in range(3):
            d2 += (_control_point(q, L, m, c) - centre[c]) ** 2
        rho = max(rho, math.sqrt(d2))
    return rho


def element_tree_size(n_elem: int) -> int:
    """Rows of :func:`element_tree`'s array for a chain of ``n_elem`` elements: a complete
    binary tree (heap order, root 1) over the next power of two of leaves."""
    leaves = 1
    while leaves < max(1, n_elem):
        leaves *= 2
    return 2 * leaves


@njit
def element_tree(q_e, lengths, tree):
    """Bounding spheres of a chain's elements and of their consecutive runs, for a broad phase
    that visits O(log n) of them (issue 52: a hole's detection no longer touches every element
    of its beam). ``tree`` (:func:`element_tree_size`, 4): rows ``[centre, radius]`` in heap
    order, leaf ``P + e`` element e's :func:`element_bounding_sphere` (``P = rows / 2``), an
    inner node the smallest sphere holding its children's; radius −1: no element below."""
    ne = q_e.shape[0]
    P = tree.shape[0] // 2
    for i in range(P, 2 * P):
        e = i - P
        if e < ne:
            tree[i, 3] = element_bounding_sphere(q_e[e], lengths[e], tree[i, :3])
        else:
            tree[i, 3] = -1.0
    for i in range(P - 1, 0, -1):
        a, b = 2 * i, 2 * i + 1
        ra, rb = tree[a, 3], tree[b, 3]
        if rb < 0.0 or ra < 0.0:
            src = a if rb < 0.0 else b
            for c in range(4):
                tree[i, c] = tree[src, c]
            continue
        d = math.sqrt((tree[b, 0] - tree[a, 0]) ** 2 + (tree[b, 1] - tree[a, 1]) ** 2
                      + (tree[b, 2] - tree[a, 2]) ** 2)
        if d + rb <= ra or d + ra <= rb:
            src = a if d + rb <= ra else b
            for c in range(4):
                tree[i, c] = tree[src, c]
            continue
        R = 0.5 * (d + ra + rb)
        w = (R - ra) / d
        for c in range(3):
            tree[i, c] = tree[a, c] + w * (tree[b, c] - tree[a, c])
        tree[i, 3] = R * (1.0 + 1e-12)     # rounding: the children stay inside


@njit(inline="always")
def element_plane_range(q, L, origin, normal):
    """Least and largest signed distance ``n·(P − O)`` of the element's Bézier control points
    from the plane (the centreline cannot cross the plane unless they straddle it)."""
    lo = np.inf
    hi = -np.inf
    for m in range(4):
        f = 0.0
        for c in range(3):
            f += normal[c] * (_control_point(q, L, m, c) - origin[c])
        lo = min(lo, f)
        hi = max(hi, f)
    return lo, hi


@njit(refcount=False)
def element_crossings(q_e, lengths, e, origin, normal, tol, max_iter, xi_start, s_out):
    """Every crossing of element ``e`` with the plane ``n·(x − O) = 0`` (chain parameter
    ``s = e + ξ`` into ``s_out``, at most 3: a cubic). When the Bézier control values of φ
    are monotone the cubic has one root, found by bracketed Newton from ``xi_start`` (the last
    step's crossing; outside [0, 1]: the chord's); else sign changes of φ at ξ = 0, ¼, ½, ¾, 1,
    each solved by bracketed Newton (:func:`_solve_in_bracket`). A root on the element's end
    node counts for the element that starts there (the last element keeps its end). Returns
    their number."""
    atol = tol * max(1.0, math.sqrt(dot3(origin, origin)))
    q = q_e[e]
    L = lengths[e]
    b0 = 0.0
    b1 = 0.0
    b2 = 0.0
    b3 = 0.0
    for c in range(3):
        b0 += normal[c] * (_control_point(q, L, 0, c) - origin[c])
        b1 += normal[c] * (_control_point(q, L, 1, c) - origin[c])
        b2 += normal[c] * (_control_point(q, L, 2, c) - origin[c])
        b3 += normal[c] * (_control_point(q, L, 3, c) - origin[c])
    if (b0 < b1 < b2 < b3) or (b0 > b1 > b2 > b3):     # monotone: one root at most
        f0, _, _, _, _ = _phi_at(q_e, lengths, origin, normal, float(e))
        if f0 == 0.0:
            s_out[0] = float(e)
            return 1
        f1, _, _, _, _ = _phi_at(q_e, lengths, origin, normal, e + 1.0)
        if f0 * f1 > 0.0 or (f1 == 0.0 and e < q_e.shape[0] - 1):
            return 0                      # no root, or the next element's node
        if f1 == 0.0:
            s_out[0] = e + 1.0
            return 1
        x = xi_start if 0.0 <= xi_start <= 1.0 else f0 / (f0 - f1)
        sr, ok = _solve_in_bracket(q_e, lengths, origin, normal, float(e), e + 1.0, f0, atol,
                                   max_iter, e + min(max(x, 1e-9), 1.0 - 1e-9))
        if not ok:
            return 0
        s_out[0] = sr
        return 1
    count = 0
    f_prev, _, _, _, _ = _phi_at(q_e, lengths, origin, normal, float(e))
    for j in range(1, 5):
        s_j = e + 0.25 * j
        f, _, _, _, _ = _phi_at(q_e, lengths, origin, normal, s_j)
        s_a = e + 0.25 * (j - 1)
        if f_prev == 0.0:
            if count < s_out.shape[0]:
                s_out[count] = s_a
                count += 1
        elif f_prev * f < 0.0:
            sr, ok = _solve_in_bracket(q_e, lengths, origin, normal, s_a, s_j, f_prev, atol,
                                       max_iter, -1.0)
            if ok and count < s_out.shape[0]:
                s_out[count] = sr
                count += 1
        f_prev = f
    if f_prev == 0.0 and e == q_e.shape[0] - 1 and count < s_out.shape[0]:
        s_out[count] = e + 1.0
        count += 1
    return count


def section_crossing(q_e: np.ndarray, lengths: np.ndarray, origin: np.ndarray, normal: np.ndarray,
                     elem0: int, xi0: float, *, tol: float = 1e-12, max_iter: int = 30,
                     max_distance: float = np.inf) -> tuple[int, float, bool]:
    """Crossing of the beam centreline with a section plane; see :func:`section_crossing_kernel`."""
    e, xi, found = section_crossing_kernel(q_e, lengths, origin, normal, int(elem0), float(xi0),
                                           float(tol), int(max_iter), float(max_distance))
    return int(e), float(xi), bool(found)


@njit
def section_crossing_kernel(q_e, lengths, origin, normal, elem0, xi0, tol, max_iter, max_distance):
    """Crossing of the beam centreline with the plane n·(x − O) = 0 (docs/theory.md §II.2).

    Safeguarded Newton on φ(s) = n·(r(s) − O) from ``s = elem0 + xi0`` (steps ≤ 1 element, across
    nodes with ξ ∓ 1, bisection once a sign change is bracketed); converged when
    ``|φ| < tol·max(1, |O|)``. If it fails, leaves the chain, or lands farther than
    ``max_distance`` from O, a global search takes every element whose end nodes give opposite
    signs of φ and keeps the crossing closest to O.
    Returns ``(elem, xi, found)``.
    """
    n = q_e.shape[0]
    atol = tol * max(1.0, math.sqrt(dot3(origin, origin)))
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
    # global fallback over node sign changes (docs/theory.md §II.2)
    best_d = np.inf
    best_s = -1.0
    fa = dot3(normal, q_e[0, 0:3] - origin)
    for k in range(n):
        fb = dot3(normal, q_e[k, 6:9] - origin)
        if straddles(fa, fb) or (fb == 0.0 and k == n - 1):
            if fa == 0.0:
                sr, ok = float(k), True
            elif fb == 0.0:
                sr, ok = float(k + 1), True
            else:
                sr, ok = _solve_in_bracket(q_e, lengths, origin, normal, float(k), float(k + 1),
                                           fa, atol, max_iter, -1.0)
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



def closest_point(q_e: np.ndarray, lengths: np.ndarray, Q: np.ndarray, elem0: int, xi0: float, *,
                  tol: float = 1e-13, max_iter: int = 30
                  ) -> tuple[int, float, np.ndarray, np.ndarray, np.ndarray]:
    """Closest-point projection of Q on the centreline; see :func:`closest_point_kernel`."""
    e, xi, P, rx, rxx = closest_point_kernel(q_e, lengths, Q, int(elem0), float(xi0), float(tol),
                                             int(max_iter))
    return int(e), float(xi), P, rx, rxx


@njit
def closest_point_kernel(q_e, lengths, Q, elem0, xi0, tol, max_iter):
    """Closest-point projection of Q on the centreline (docs/theory.md §II.4).

    Newton on ``h(s) = (r − Q)·r_ξ`` with ``h_ξ = r_ξ·r_ξ + (r − Q)·r_ξξ`` from ``s = elem0 + xi0``;
    steps ≤ ½ element, continued across nodes; bracket [h < 0, h > 0] with bisection; a descent step
    when ``h_ξ ≤ 0``; clamped at the chain ends (the end point is returned when the minimum lies
    beyond it). Converged when ``|h| ≤ tol·|r_ξ|·max(1, |Q|)`` or the step is below 1e-14.
    Returns ``(elem, xi, P, r_xi, r_xixi)``.
    """
    n = q_e.shape[0]
    scale = tol * max(1.0, math.sqrt(dot3(Q, Q)))
    s = _clip(elem0 + xi0, 0.0, float(n))
    lo = -1.0
    hi = -1.0
    e, xi = _locate(s, n)
    r, rx, rxx = _elem_point(q_e[e], lengths[e], xi)
    for _ in range(max_iter):
        d = r - Q
        h = dot3(d, rx)
        if abs(h) <= scale * math.sqrt(dot3(rx, rx)):
            break
        hx = dot3(rx, rx) + dot3(d, rxx)
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



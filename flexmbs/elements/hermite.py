"""The cubic Hermite centreline that the beam elements share (docs/theory.md §I.1.1): an element's
centreline ``r(ξ) = S(ξ) q_c`` from its coordinates ``q_c = [r0, r0′, r1, r1′]`` (12), which
an element type declares in its layout (``ElementLayout.centerline``: the cable's whole
element, the rod's without its twists). The one statement of the basis and of the centreline's
point, for the elements, the joints, the contact and the output alike.
"""

from __future__ import annotations

import numpy as np

from .._jit import njit

__all__ = [
    "CENTERLINE_SIZE",
    "hermite_basis",
    "shape_functions",
    "shape_xi",
    "element_point",
    "element_point_values",
    "centerline_interpolation",
    "interpolate",
    "centerline_points",
]

#: coordinates of an element's Hermite centreline ``[r0, r0′, r1, r1′]``: what the sliding and
#: clearance joints read of a beam element (``LAYOUT.centerline`` selects them)
CENTERLINE_SIZE = 12


@njit(inline="always")
def hermite_basis(xi, L):
    """Cubic Hermite shape functions S1..S4 (docs/theory.md §I.1.1) and their first, second and third
    ξ-derivatives, as four 4-tuples (no allocation): the one statement of the element's basis."""
    x2 = xi * xi
    x3 = x2 * xi
    S = (1.0 - 3.0 * x2 + 2.0 * x3, L * (xi - 2.0 * x2 + x3), 3.0 * x2 - 2.0 * x3, L * (x3 - x2))
    dS = (6.0 * x2 - 6.0 * xi, L * (1.0 - 4.0 * xi + 3.0 * x2), 6.0 * xi - 6.0 * x2,
          L * (3.0 * x2 - 2.0 * xi))
    ddS = (12.0 * xi - 6.0, L * (6.0 * xi - 4.0), 6.0 - 12.0 * xi, L * (6.0 * xi - 2.0))
    d3S = (12.0, 6.0 * L, -12.0, 6.0 * L)
    return S, dS, ddS, d3S


@njit
def _basis_table(xi, L, S, dS, ddS):
    for i in range(xi.size):
        s, d, dd, _ = hermite_basis(xi[i], L[i])
        for n in range(4):
            S[i, n] = s[n]
            dS[i, n] = d[n] / L[i]
            ddS[i, n] = dd[n] / (L[i] * L[i])


def shape_functions(xi: np.ndarray, length: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Hermite shape functions S1..S4 and their x-derivatives (docs/theory.md §I.1.1).

    ``xi`` and ``length`` broadcast against each other (e.g. ``(n,)`` with ``(n,)`` for one
    point per element, or ``xi[None, :]`` with ``L[:, None]`` for a table); each returned array
    has shape ``broadcast(xi, length).shape + (4,)``: ``S``, ``dS = dS/dx``, ``ddS = d²S/dx²``
    (from :func:`hermite_basis`).
    """
    xi, L = np.broadcast_arrays(np.asarray(xi, dtype=float), np.asarray(length, dtype=float))
    shape = xi.shape
    x = np.ascontiguousarray(xi.reshape(-1))
    lf = np.ascontiguousarray(L.reshape(-1))
    S, dS, ddS = (np.empty((x.size, 4)) for _ in range(3))
    _basis_table(x, lf, S, dS, ddS)
    return S.reshape(shape + (4,)), dS.reshape(shape + (4,)), ddS.reshape(shape + (4,))


@njit
def shape_xi(xi, length):
    """S1..S4 and their ξ-derivatives (docs/theory.md §II.0) as arrays (4,) (:func:`hermite_basis`)."""
    s, d, dd, _ = hermite_basis(xi, length)
    S = np.empty(4)
    dS = np.empty(4)
    ddS = np.empty(4)
    for n in range(4):
        S[n] = s[n]
        dS[n] = d[n]
        ddS[n] = dd[n]
    return S, dS, ddS


@njit(inline="always")
def _combine(w, q, c):
    """Component c of ``Σ_m w_m q_m`` over the element's four coordinate triples."""
    return w[0] * q[c] + w[1] * q[3 + c] + w[2] * q[6 + c] + w[3] * q[9 + c]


@njit(inline="always")
def element_point_values(q, L, xi):
    """Centreline point of one element: ``r, r_ξ, r_ξξ`` at ξ as three 3-tuples (no
    allocation: the crossing and projection Newton loops) from its coordinates
    ``q = [r0, r0′, r1, r1′]`` (any real ξ: the cubic is extrapolated), r = S(ξ) q."""
    s, d, dd, _ = hermite_basis(xi, L)
    return ((_combine(s, q, 0), _combine(s, q, 1), _combine(s, q, 2)),
            (_combine(d, q, 0), _combine(d, q, 1), _combine(d, q, 2)),
            (_combine(dd, q, 0), _combine(dd, q, 1), _combine(dd, q, 2)))


@njit
def element_point(q, L, xi):
    """:func:`element_point_values` as arrays (3,) ``r, r_ξ, r_ξξ``."""
    v, vx, vxx = element_point_values(q, L, xi)
    r = np.empty(3)
    rx = np.empty(3)
    rxx = np.empty(3)
    for c in range(3):
        r[c] = v[c]
        rx[c] = vx[c]
        rxx[c] = vxx[c]
    return r, rx, rxx


def centerline_interpolation(element_dofs: np.ndarray, lengths: np.ndarray, elem: np.ndarray,
                             xi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Weights ``S (n, 4)`` and coordinates ``dofs (n, 12)`` of the centreline points at
    (element, ξ) pairs: :func:`interpolate` gives r = S(ξ) q_e (docs/theory.md §I.1.1) from any
    global vector (positions from q, velocities from q̇)."""
    elem = np.asarray(elem, dtype=np.int64).reshape(-1)
    S, _, _ = shape_functions(np.asarray(xi, dtype=float).reshape(-1), np.asarray(lengths)[elem])
    return S, np.asarray(element_dofs)[elem]


def interpolate(S: np.ndarray, dofs: np.ndarray, X: np.ndarray) -> np.ndarray:
    """``Σ_k S[p, k] X[..., dofs[p, 3k:3k+3]]`` -> (..., n, 3): centreline points of the global
    vector(s) ``X`` (..., n_coords) at the points of :func:`centerline_interpolation`."""
    X = np.asarray(X, dtype=float)
    Xe = X[..., dofs].reshape(X.shape[:-1] + (dofs.shape[0], 4, 3))
    return np.einsum("pk,...pkc->...pc", S, Xe)


def centerline_points(q: np.ndarray, element_dofs: np.ndarray, lengths: np.ndarray,
                      elem: np.ndarray, xi: np.ndarray) -> np.ndarray:
    """Positions (n, 3) of the centreline at (element, ξ) pairs in configuration ``q``."""
    return interpolate(*centerline_interpolation(element_dofs, lengths, elem, xi), q)

"""Element B: the 14-DOF ANCF Kirchhoff rod with a nodal twist angle (FORMULATION Part I §2).

Part 1 of the element (issue "torsion rod"): coordinates, nodal triads, the interpolated material
frame, the strain measures and the strain energy, compiled. Not yet registered as an element type:
forces, tangent, mass, loads and the connections to the assembler follow.

Per node ``[r (3), g = r′ (3), φ (1)]``; the centreline is the cable's cubic Hermite
(:func:`flexmbs.elements.ancf_cable.hermite_basis`, the one statement of the basis). Each node has
a fixed base ``(t̄_i, D̄_i)`` from the reference (unit tangent, a unit vector ⟂ it, by parallel
transport along the reference nodes); its triad is

    t_i = g_i/|g_i|,   d2_i = Rot(t_i, φ_i) SR(t̄_i → t_i) D̄_i,   d3_i = t_i × d2_i

with the smallest rotation SR and the rotation Rot of §2.1. At ξ = x/L of an element (§2.2):

    t = r′/|r′|,  t_x = (r″ − t (t·r″))/|r′|,   d̂ = SR(t_0 → t_1) d2_0,
    Δθ = 2 atan(((d̂ × d2_1)·t_1) / (1 + d̂·d2_1)),
    d2(x) = Rot(t, ξΔθ) SR(t_0 → t) d2_0,   d3 = t × d2,
    ε = |r′|/μ − 1,  K = (r′ × r″)/(|r′|² μ),  K2 = K·d2,  K3 = K·d3,
    τ_SR = −t_0·(t × t_x)/(1 + t_0·t),   K1 = (Δθ/L + τ_SR)/μ,
    U_e = ∫₀ᴸ ½ [EA ε² + GJ (K1 − K1⁰)² + EI2 (K2 − K2⁰)² + EI3 (K3 − K3⁰)²] μ dx

(μ = |r′| of the reference, the superscript 0 the same measures in the reference with φ = 0),
5 Gauss points (§2.5). Every interior quantity comes from the current nodal triads through
SR(t_0 → ·), which is equivariant, so U is objective; U(q_ref) = 0 for any reference.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from .._jit import njit
from .ancf_cable import hermite_basis
from .layout import ElementLayout

__all__ = ["LAYOUT", "RodProperties", "RodRest", "base_frames", "nodal_director", "rest_state",
           "rotate_about", "smallest_rotation", "strain_energy", "strain_measures"]

LAYOUT = ElementLayout(name="ancf_rod14",
                       node_coordinates=("x", "y", "z", "dx", "dy", "dz", "twist"),
                       position=(0, 1, 2), slope=(3, 4, 5),
                       output_fields=("axial_strain", "torsion", "curvature"))
NODE_SIZE = LAYOUT.node_size
TWIST = LAYOUT.node_coordinates.index("twist")    #: nodal index of the twist angle φ
N_GAUSS = 5                #: quadrature points of every term (§2.5, as verified)


class RodProperties(NamedTuple):
    """Per element: length L, EA, GJ, EI2 (about d2), EI3 (about d3)."""

    length: np.ndarray
    EA: np.ndarray
    GJ: np.ndarray
    EI2: np.ndarray
    EI3: np.ndarray


class RodRest(NamedTuple):
    """The fixed nodal bases of every element's two nodes and the reference measures at the
    Gauss points."""

    t_bar: np.ndarray      # (n_elem, 2, 3)
    d_bar: np.ndarray      # (n_elem, 2, 3)
    xi: np.ndarray         # (N_GAUSS,) on [0, 1]
    w: np.ndarray          # (N_GAUSS,) weights, sum 1
    mu: np.ndarray         # (n_elem, N_GAUSS) |r′| of the reference
    k0: np.ndarray         # (n_elem, N_GAUSS, 3) K1⁰, K2⁰, K3⁰


# ---------------------------------------------------------------------------------------------
# rotations (§2.1)
@njit(inline="always")
def _dot(a, b):  # noqa: ANN001, ANN202
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(inline="always")
def _cross(a, b):  # noqa: ANN001, ANN202
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


@njit
def smallest_rotation(a, b, v):  # noqa: ANN001, ANN201
    """``SR(a → b) v = (a·b) v + (a×b)×v + ((a×b)·v)/(1 + a·b) (a×b)`` for unit a, b (§2.1;
    singular only at b = −a)."""
    c = _dot(a, b)
    k = _cross(a, b)
    kv = _cross(k, v)
    f = _dot(k, v) / (1.0 + c)
    return c * v + kv + f * k


@njit
def rotate_about(t, phi, v):  # noqa: ANN001, ANN201
    """``Rot(t, φ) v = v cos φ + (t×v) sin φ + t (t·v)(1 − cos φ)`` for unit t (§2.1)."""
    c = math.cos(phi)
    s = math.sin(phi)
    tv = _cross(t, v)
    return c * v + s * tv + (_dot(t, v) * (1.0 - c)) * t


@njit
def nodal_director(g, phi, t_bar, d_bar):  # noqa: ANN001, ANN201
    """``(t_i, d2_i)`` of a node from its slope g, twist φ and base (t̄, D̄) (§2.1)."""
    t = g / math.sqrt(_dot(g, g))
    return t, rotate_about(t, phi, smallest_rotation(t_bar, t, d_bar))


# ---------------------------------------------------------------------------------------------
# strain measures and energy (§2.2)
@njit
def strain_measures(q_e, L, t_bar, d_bar, xi):  # noqa: ANN001, ANN201
    """``(|r′|, c1, c2, c3)`` at ξ of one element ``q_e (14,)``: K1 μ = c1 = Δθ/L + τ_SR,
    K2 μ = c2 = (r′×r″)·d2/|r′|², K3 μ = c3 = (r′×r″)·d3/|r′|² (module docstring; the caller
    divides by μ)."""
    n = NODE_SIZE
    g0 = q_e[3:6]
    g1 = q_e[n + 3:n + 6]
    t0, d20 = nodal_director(g0, q_e[TWIST], t_bar[0], d_bar[0])
    t1, d21 = nodal_director(g1, q_e[n + TWIST], t_bar[1], d_bar[1])
    dhat = smallest_rotation(t0, t1, d20)
    y = _dot(_cross(dhat, d21), t1)
    dtheta = 2.0 * math.atan(y / (1.0 + _dot(dhat, d21)))
    _, dS, ddS, _ = hermite_basis(xi, L)
    rp = np.zeros(3)
    rpp = np.zeros(3)
    for k in range(4):               # [r0, g0, r1, g1] of the 14 coordinates
        o = (k // 2) * n + 3 * (k % 2)
        for c in range(3):
            rp[c] += dS[k] * q_e[o + c] / L
            rpp[c] += ddS[k] * q_e[o + c] / (L * L)
    nrp = math.sqrt(_dot(rp, rp))
    t = rp / nrp
    tx = (rpp - _dot(t, rpp) * t) / nrp
    d2 = rotate_about(t, xi * dtheta, smallest_rotation(t0, t, d20))
    d3 = _cross(t, d2)
    kappa = _cross(rp, rpp)
    tau_sr = -_dot(t0, _cross(t, tx)) / (1.0 + _dot(t0, t))
    inv = 1.0 / (nrp * nrp)
    return nrp, dtheta / L + tau_sr, _dot(kappa, d2) * inv, _dot(kappa, d3) * inv


@njit
def _element_energy(q_e, props, rest, e):  # noqa: ANN001, ANN202
    L = props.length[e]
    total = 0.0
    for k in range(rest.xi.size):
        nrp, c1, c2, c3 = strain_measures(q_e, L, rest.t_bar[e], rest.d_bar[e], rest.xi[k])
        mu = rest.mu[e, k]
        eps = nrp / mu - 1.0
        k1 = c1 / mu - rest.k0[e, k, 0]
        k2 = c2 / mu - rest.k0[e, k, 1]
        k3 = c3 / mu - rest.k0[e, k, 2]
        dens = (props.EA[e] * eps * eps + props.GJ[e] * k1 * k1 + props.EI2[e] * k2 * k2
                + props.EI3[e] * k3 * k3)
        total += 0.5 * dens * mu * rest.w[k] * L
    return total


@njit
def _energies(q_e, props, rest, out):  # noqa: ANN001, ANN202
    for e in range(q_e.shape[0]):
        out[e] = _element_energy(q_e[e], props, rest, e)


def strain_energy(q_e: np.ndarray, props: RodProperties, rest: RodRest) -> np.ndarray:
    """Strain energy of every element, ``q_e (n_elem, 14)``."""
    q = np.ascontiguousarray(q_e, dtype=float)
    out = np.empty(q.shape[0])
    _energies(q, props, rest, out)
    return out


# ---------------------------------------------------------------------------------------------
# reference
def base_frames(slopes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Nodal bases ``(t̄, D̄)`` (n_nodes, 3) of a reference with nodal slopes ``(n_nodes, 3)``:
    D̄ by parallel transport (smallest rotations) from node to node along the curve (§4.6),
    starting from the global axis least aligned with the first tangent. On a closed loop the
    transport does not return to its start (holonomy); the reference twist K1⁰ absorbs it."""
    g = np.asarray(slopes, dtype=float)
    t = g / np.linalg.norm(g, axis=1)[:, None]
    d = np.empty_like(t)
    helper = np.eye(3)[int(np.argmin(np.abs(t[0])))]
    d0 = helper - np.dot(helper, t[0]) * t[0]
    d[0] = d0 / np.linalg.norm(d0)
    for i in range(1, t.shape[0]):
        d[i] = smallest_rotation(t[i - 1], t[i], d[i - 1])
        d[i] -= np.dot(d[i], t[i]) * t[i]
        d[i] /= np.linalg.norm(d[i])
    return t, d


def rest_state(q_ref_e: np.ndarray, props: RodProperties, t_bar: np.ndarray,
               d_bar: np.ndarray) -> RodRest:
    """The reference measures at the Gauss points of every element (with φ = 0 there)."""
    x, w = np.polynomial.legendre.leggauss(N_GAUSS)
    xi, w = 0.5 * (x + 1.0), 0.5 * w
    q = np.array(q_ref_e, dtype=float)
    q[:, TWIST] = 0.0
    q[:, NODE_SIZE + TWIST] = 0.0
    ne = q.shape[0]
    mu = np.empty((ne, N_GAUSS))
    k0 = np.empty((ne, N_GAUSS, 3))
    for e in range(ne):
        for k in range(N_GAUSS):
            nrp, c1, c2, c3 = strain_measures(q[e], float(props.length[e]), t_bar[e], d_bar[e],
                                              float(xi[k]))
            mu[e, k] = nrp
            k0[e, k] = (c1 / nrp, c2 / nrp, c3 / nrp)
    return RodRest(np.ascontiguousarray(t_bar, float), np.ascontiguousarray(d_bar, float),
                   xi, w, mu, k0)

"""Element A: 12-DOF gradient-deficient ANCF cable (docs/theory.md §I.1).

Element coordinates ``q_e = [r0 (3), r0' (3), r1 (3), r1' (3)]`` with cubic Hermite shape
functions (§1.1). Strains are measured relative to a curved stress-free reference ``q_ref``
(§1.3); forces and the consistent tangent are analytic (§1.4); quadrature as in §1.5.

Array layout: element arrays are ``(n_elem, 12)``, element matrices ``(n_elem, 12, 12)``,
quadrature tables ``(n_elem, n_qp, ...)``. Shape-function index ``n = 0..3`` (S1..S4) multiplies
the 3 coordinates ``q_e[3n:3n+3]``.

All functions are stateless. The hot path, :func:`internal_forces`, is a thin wrapper around a
numba kernel that loops over elements and quadrature points and writes into caller-owned arrays.
Residual convention (§0): ``M q̈ + Q_int(q, q̇) − Q_ext = 0`` with ``Q_int = ∂U/∂q`` + damping.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal, NamedTuple

import numpy as np

from .._jit import FLAG, njit
from .group import add_matrix, add_residual, gather_states
from .hermite import shape_functions
from .layout import ELEMENT_TYPES, ElementLayout, ElementType

__all__ = [
    "CableOptions",
    "CableProperties",
    "CableRest",
    "rest_state",
    "mass_matrix",
    "gravity_force",
    "distributed_force",
    "point_force_vector",
    "internal_forces",
    "strain_energy",
    "axial_strain_and_curvature",
]

#: Element A's declared layout: per node [r, r′], 2 nodes, 12 element coordinates (§1.1)
LAYOUT = ElementLayout(
    name="ancf_cable", node_coordinates=("x", "y", "z", "x'", "y'", "z'"), position=(0, 1, 2),
    slope=(3, 4, 5), nodes_per_element=2,
    output_fields=("axial_strain", "curvature"), vector_fields=("curvature",))




def reference_nodal_coordinates(points: np.ndarray, tangents: np.ndarray) -> np.ndarray:
    """Nodal coordinates (n_nodes, 6) of the stress-free reference: ``[r, r′]`` per node."""
    return np.hstack([points, tangents])


_BENDINGS = ("vector", "scalar")
_AXIAL_RULES = ("lobatto3", "gauss5")


@dataclass(frozen=True, kw_only=True)
class CableOptions:
    """Formulation choices of the ANCF cable (docs/theory.md §I.1.3, §I.1.5, §I.1.6).

    - ``bending="vector"``: A-vec, ``½EI|K − K_ref|²`` (Exudyn); ``"scalar"``: A-scal,
      ``½EI(|K|_δ − |K_ref|_δ)²`` (objective for curved references).
    - ``axial_rule``: ``"lobatto3"`` (ξ = 0, ½, 1; free of membrane locking, the default) or
      ``"gauss5"`` (full integration, as Exudyn/Chrono by default).
    - ``bending_points``: 2 or 3 Gauss points for the bending term.
    - ``exudyn_compatible``: Exudyn ObjectANCFCable strains, ``ε_E = |r′| − 1`` with the
      reference offset ``|r′_ref| − 1``, ``K = r′×r″/|r′|²``, integrated over dx (μ = 1);
      requires ``bending="vector"``.

    Parameters
    ----------
    bending : {"vector", "scalar"}, default "vector"
        Bending energy form.
    axial_rule : {"lobatto3", "gauss5"}, default "lobatto3"
        Quadrature of the axial term.
    bending_points : {2, 3}, default 3
        Gauss points of the bending term.
    exudyn_compatible : bool, default False
        Exudyn's ObjectANCFCable strains.
    """

    bending: Literal["vector", "scalar"] = "vector"
    axial_rule: Literal["lobatto3", "gauss5"] = "lobatto3"
    bending_points: int = 3
    exudyn_compatible: bool = False

    def __post_init__(self) -> None:
        if self.bending not in _BENDINGS:
            raise ValueError(f"CableOptions.bending must be one of {_BENDINGS} "
                             f"(got {self.bending!r})")
        if self.axial_rule not in _AXIAL_RULES:
            raise ValueError(f"CableOptions.axial_rule must be one of {_AXIAL_RULES} "
                             f"(got {self.axial_rule!r})")
        if self.bending_points not in (2, 3) or isinstance(self.bending_points, bool):
            raise ValueError(f"CableOptions.bending_points must be 2 or 3 "
                             f"(got {self.bending_points!r})")
        if self.exudyn_compatible and self.bending != "vector":
            raise ValueError("CableOptions: exudyn_compatible=True reproduces Exudyn's A-vec "
                             "bending; use bending='vector' with it (docs/theory.md §I.1.6)")


class CableProperties(NamedTuple):
    """Section resultants per element; every field has shape ``(n_elem,)``."""

    length: np.ndarray                  #: element reference length L [m]
    axial_stiffness: np.ndarray         #: EA [N]
    bending_stiffness: np.ndarray       #: EI [N m²]
    mass_per_length: np.ndarray         #: ρA [kg/m]
    axial_damping: np.ndarray           #: d_ε [N s]:  N = EA(ε − ε0) + d_ε ε̇
    bending_damping: np.ndarray         #: d_K [N m² s]: m = EI(K − K_ref) + d_K K̇
    reference_axial_strain: np.ndarray  #: ε0 [-]: N = EA(ε − ε0) (ε0 < 0: pretension)


class CableRest(NamedTuple):
    """Reference-configuration data precomputed by :func:`rest_state` (docs/theory.md §I.1.3, §I.1.5).

    ``n_ax`` / ``n_b`` are the numbers of axial / bending quadrature points. "Metric" is
    ``μ = |r′_ref|`` (set to 1 everywhere in the Exudyn-compatible variant).
    """

    length: np.ndarray           #: (n_elem,) element reference length L
    q_ref: np.ndarray            #: (n_elem, 12) stress-free reference coordinates
    axial_xi: np.ndarray         #: (n_ax,) axial quadrature points ξ ∈ [0, 1]
    axial_weight: np.ndarray     #: (n_elem, n_ax) dx-weights w_k·L
    axial_metric: np.ndarray     #: (n_elem, n_ax) μ_k (1 for Exudyn)
    axial_offset: np.ndarray     #: (n_elem, n_ax) ε0, plus |r′_ref| − 1 for Exudyn
    axial_dS: np.ndarray         #: (n_elem, n_ax, 4) S′_n(ξ_k)
    bending_xi: np.ndarray       #: (n_b,) bending Gauss points ξ ∈ [0, 1]
    bending_weight: np.ndarray   #: (n_elem, n_b) ds0-weights w_k·L·μ_k (w_k·L for Exudyn)
    bending_metric: np.ndarray   #: (n_elem, n_b) μ_k in K = r′×r″/(|r′|² μ) (1 for Exudyn)
    bending_dS: np.ndarray       #: (n_elem, n_b, 4) S′_n(ξ_k)
    bending_ddS: np.ndarray      #: (n_elem, n_b, 4) S″_n(ξ_k)
    rest_curvature: np.ndarray   #: (n_elem, n_b, 3) K_ref
    rest_curvature_norm: np.ndarray  #: (n_elem, n_b) |K_ref|_δ = sqrt(K_ref·K_ref + δ²)
    delta_sq: np.ndarray         #: (n_elem,) δ² with δ = 1e-8/L (A-scal regularisation)

# ---------------------------------------------------------------------------------------------
# quadrature
def _gauss01(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss–Legendre points and weights on [0, 1] (weights sum to 1)."""
    x, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (x + 1.0), 0.5 * w


def _axial_rule(rule: str) -> tuple[np.ndarray, np.ndarray]:
    """docs/theory.md §I.1.5: 3-point Lobatto (0, ½, 1; 1/6, 4/6, 1/6) or 5-point Gauss on [0, 1]."""
    if rule == "lobatto3":
        return np.array([0.0, 0.5, 1.0]), np.array([1.0, 4.0, 1.0]) / 6.0
    return _gauss01(5)


def _interp(table: np.ndarray, q_e: np.ndarray) -> np.ndarray:
    """Σ_n table[e, k, n] q_e[e, 3n:3n+3] -> (n_elem, n_qp, 3)."""
    return np.einsum("ekn,enc->ekc", table, q_e.reshape(q_e.shape[0], 4, 3))


def rest_state(q_ref: np.ndarray, props: CableProperties, options: CableOptions) -> CableRest:
    """Precompute quadrature tables, metric μ = |r′_ref| and rest curvature K_ref (§1.3, §1.5)."""
    q_ref = np.ascontiguousarray(q_ref, dtype=float)
    L = np.ascontiguousarray(props.length, dtype=float)
    if q_ref.ndim != 2 or q_ref.shape[1] != 12 or L.shape != (q_ref.shape[0],):
        raise ValueError(f"rest_state: q_ref must be (n_elem, 12) and props.length (n_elem,) "
                         f"(got {q_ref.shape} and {L.shape})")
    if np.any(L <= 0.0):
        raise ValueError("rest_state: element lengths must be positive")
    exu = options.exudyn_compatible
    eps0 = np.asarray(props.reference_axial_strain, dtype=float)

    xa, wa = _axial_rule(options.axial_rule)
    _, dSa, _ = shape_functions(xa[None, :], L[:, None])
    a_ref = _interp(dSa, q_ref)
    mu_a = np.linalg.norm(a_ref, axis=-1)
    if np.any(mu_a <= 0.0):
        raise ValueError("rest_state: reference slope |r'_ref| vanishes at a quadrature point")
    if exu:
        axial_metric = np.ones_like(mu_a)
        axial_offset = eps0[:, None] + (mu_a - 1.0)
    else:
        axial_metric = mu_a
        axial_offset = np.broadcast_to(eps0[:, None], mu_a.shape).copy()

    xb, wb = _gauss01(options.bending_points)
    _, dSb, ddSb = shape_functions(xb[None, :], L[:, None])
    a = _interp(dSb, q_ref)
    b = _interp(ddSb, q_ref)
    mu_b = np.linalg.norm(a, axis=-1)
    metric_b = np.ones_like(mu_b) if exu else mu_b
    K_ref = np.cross(a, b) / (np.einsum("ekc,ekc->ek", a, a) * metric_b)[..., None]
    delta_sq = (1e-8 / L) ** 2
    c = np.ascontiguousarray
    return CableRest(
        length=L.copy(), q_ref=q_ref.copy(), axial_xi=xa, axial_weight=c(wa[None, :] * L[:, None]),
        axial_metric=c(axial_metric), axial_offset=c(axial_offset), axial_dS=c(dSa),
        bending_xi=xb, bending_weight=c(wb[None, :] * L[:, None] * metric_b),
        bending_metric=c(metric_b), bending_dS=c(dSb), bending_ddS=c(ddSb),
        rest_curvature=c(K_ref),
        rest_curvature_norm=c(np.sqrt(np.einsum("ekc,ekc->ek", K_ref, K_ref) + delta_sq[:, None])),
        delta_sq=delta_sq)


# ---------------------------------------------------------------------------------------------
# mass and external loads (constant, closed form)
_M4 = np.array([[13 / 35, 11 / 210, 9 / 70, -13 / 420],
                [11 / 210, 1 / 105, 13 / 420, -1 / 140],
                [9 / 70, 13 / 420, 13 / 35, -11 / 210],
                [-13 / 420, -1 / 140, -11 / 210, 1 / 105]])
#: powers of L multiplying the entries of _M4 (besides ρA·L)
_M4_POW = np.array([[0, 1, 0, 1], [1, 2, 1, 2], [0, 1, 0, 1], [1, 2, 1, 2]])


def mass_matrix(props: CableProperties) -> np.ndarray:
    """Consistent mass ``∫ρA SᵀS dx = ρA L M4(L) ⊗ I3`` (docs/theory.md §I.1.2); (n_elem, 12, 12)."""
    L = np.asarray(props.length, dtype=float)
    rhoA = np.asarray(props.mass_per_length, dtype=float)
    M4 = (rhoA * L)[:, None, None] * _M4[None] * L[:, None, None] ** _M4_POW[None]
    return np.einsum("eij,cd->eicjd", M4, np.eye(3)).reshape(L.shape[0], 12, 12)


def distributed_force(props: CableProperties, f: np.ndarray) -> np.ndarray:
    """Constant load per length f: ``∫Sᵀf dx = [L/2, L²/12, L/2, −L²/12] ⊗ f`` (§1.2); (n_elem, 12).

    ``f`` is ``(3,)`` (same for all elements) or ``(n_elem, 3)``.
    """
    L = np.asarray(props.length, dtype=float)
    f = np.broadcast_to(np.asarray(f, dtype=float), (L.shape[0], 3))
    s = np.stack([0.5 * L, L * L / 12.0, 0.5 * L, -L * L / 12.0], axis=-1)
    return (s[:, :, None] * f[:, None, :]).reshape(L.shape[0], 12)


def gravity_force(props: CableProperties, g: np.ndarray) -> np.ndarray:
    """Gravity ``Q_g = ρA [L/2, L²/12, L/2, −L²/12] ⊗ g`` (docs/theory.md §I.1.2); (n_elem, 12)."""
    rhoA = np.asarray(props.mass_per_length, dtype=float)
    return distributed_force(props, rhoA[:, None] * np.asarray(g, dtype=float)[None, :])


def point_force_vector(xi: np.ndarray, length: np.ndarray, force: np.ndarray) -> np.ndarray:
    """Point force at ξ: ``Q = S(ξ)ᵀ F`` (docs/theory.md §I.1.2).

    ``xi``, ``length``: (n,); ``force``: (n, 3); returns (n, 12).
    """
    S, _, _ = shape_functions(np.asarray(xi, dtype=float), np.asarray(length, dtype=float))
    F = np.asarray(force, dtype=float)
    return (S[:, :, None] * F[:, None, :]).reshape(S.shape[0], 12)


# ---------------------------------------------------------------------------------------------
# internal forces: numba kernel (docs/theory.md §I.1.4)
class KernelWork(NamedTuple):
    """Scratch of :func:`_internal_kernel`: its 3-vectors, its nodal shape-function rows, its
    3 × 3 operators and (``mat[9:]``) the node blocks of :func:`_add_point_blocks`
    (:func:`kernel_work`). (The blocks as a fourth array made the 8-element cantilever's
    *residual*, which passes the part, 2.1 → 2.4 µs.)"""

    vec: np.ndarray      # (KERNEL_VECTORS, 3)
    node: np.ndarray     # (2, 4)
    mat: np.ndarray      # (KERNEL_MATRICES, 3, 3)


#: sizes of :class:`KernelWork`
KERNEL_VECTORS, KERNEL_MATRICES = 14, 9 + 8


def kernel_work() -> KernelWork:
    """Fresh scratch for :func:`_internal_kernel` (one per caller: the packed part keeps one)."""
    return KernelWork(np.zeros((KERNEL_VECTORS, 3)), np.zeros((2, 4)),
                      np.zeros((KERNEL_MATRICES, 3, 3)))


@njit(inline="always")
def _at(d, x, e, c):
    """Σ_n d[n] x[e, 3n + c] with the four shape-function values as scalars."""
    return d[0] * x[e, c] + d[1] * x[e, 3 + c] + d[2] * x[e, 6 + c] + d[3] * x[e, 9 + c]


@njit(inline="always")
def _axial_point(q, v, e, k, rest, EA, dA):
    """The axial resultant at axial point k of element e (docs/theory.md §I.1.4): a = S′q, the
    unit tangent t = a/|a|, |a|, t·ȧ, N = EA(|a|/μ − 1 − ε_off) + d_ε t·ȧ/μ and ȧ = S′q̇;
    every quantity a scalar (both kernels: :func:`_internal_forces`, :func:`_internal_kernel`)."""
    d = (rest.axial_dS[e, k, 0], rest.axial_dS[e, k, 1], rest.axial_dS[e, k, 2],
         rest.axial_dS[e, k, 3])
    mu = rest.axial_metric[e, k]
    a0, a1, a2 = _at(d, q, e, 0), _at(d, q, e, 1), _at(d, q, e, 2)
    u0, u1, u2 = _at(d, v, e, 0), _at(d, v, e, 1), _at(d, v, e, 2)
    la = math.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
    t0, t1, t2 = a0 / la, a1 / la, a2 / la
    tad = t0 * u0 + t1 * u1 + t2 * u2
    N = EA * (la / mu - 1.0 - rest.axial_offset[e, k]) + dA * tad / mu
    return t0, t1, t2, la, tad, N, u0, u1, u2


@njit(inline="always")
def _bending_point(q, v, e, k, rest, EI, dB, scalar):
    """The bending terms at bending point k of element e (docs/theory.md §I.1.4): a = S′q,
    b = S″q and their rates ȧ, ḃ, g = μ|a|², the curvature K = a×b/g, its rate
    K̇ = B1 ȧ + B2 ḃ = (a×ḃ − b×ȧ)/g − 2μ(a·ȧ) K/g, the moment m_eff (vector law
    EI(K − K_ref) + d_K K̇; scalar law m_s K/κ, κ = sqrt(K·K + δ²), m_s = EI(κ − |K_ref|_δ) + d_K κ̇)
    and the force directions p = B1ᵀm_eff = (b×m_eff − 2μ(K·m_eff) a)/g and
    s = B2ᵀm_eff = (m_eff×a)/g (B1 = (−b̃ − 2μ K aᵀ)/g, B2 = ã/g); every quantity a scalar.
    Returns a, b, ȧ, ḃ, g, K, K̇, κ, κ̇, m_s (κ, κ̇, m_s zero for the vector law), m_eff, p, s."""
    d = (rest.bending_dS[e, k, 0], rest.bending_dS[e, k, 1], rest.bending_dS[e, k, 2],
         rest.bending_dS[e, k, 3])
    h = (rest.bending_ddS[e, k, 0], rest.bending_ddS[e, k, 1], rest.bending_ddS[e, k, 2],
         rest.bending_ddS[e, k, 3])
    mu = rest.bending_metric[e, k]
    a0, a1, a2 = _at(d, q, e, 0), _at(d, q, e, 1), _at(d, q, e, 2)
    b0, b1, b2 = _at(h, q, e, 0), _at(h, q, e, 1), _at(h, q, e, 2)
    u0, u1, u2 = _at(d, v, e, 0), _at(d, v, e, 1), _at(d, v, e, 2)
    w0, w1, w2 = _at(h, v, e, 0), _at(h, v, e, 1), _at(h, v, e, 2)
    g = mu * (a0 * a0 + a1 * a1 + a2 * a2)
    ig = 1.0 / g
    tm = 2.0 * mu
    K0 = (a1 * b2 - a2 * b1) * ig
    K1 = (a2 * b0 - a0 * b2) * ig
    K2 = (a0 * b1 - a1 * b0) * ig
    c = tm * (a0 * u0 + a1 * u1 + a2 * u2) * ig
    Kd0 = ((a1 * w2 - a2 * w1) - (b1 * u2 - b2 * u1)) * ig - c * K0
    Kd1 = ((a2 * w0 - a0 * w2) - (b2 * u0 - b0 * u2)) * ig - c * K1
    Kd2 = ((a0 * w1 - a1 * w0) - (b0 * u1 - b1 * u0)) * ig - c * K2
    kap = 0.0
    kapd = 0.0
    ms = 0.0
    if scalar:
        kap = math.sqrt(K0 * K0 + K1 * K1 + K2 * K2 + rest.delta_sq[e])
        kapd = (K0 * Kd0 + K1 * Kd1 + K2 * Kd2) / kap
        ms = EI * (kap - rest.rest_curvature_norm[e, k]) + dB * kapd
        m0, m1, m2 = ms / kap * K0, ms / kap * K1, ms / kap * K2
    else:
        m0 = EI * (K0 - rest.rest_curvature[e, k, 0]) + dB * Kd0
        m1 = EI * (K1 - rest.rest_curvature[e, k, 1]) + dB * Kd1
        m2 = EI * (K2 - rest.rest_curvature[e, k, 2]) + dB * Kd2
    c = tm * (K0 * m0 + K1 * m1 + K2 * m2) * ig
    p0 = (b1 * m2 - b2 * m1) * ig - c * a0
    p1 = (b2 * m0 - b0 * m2) * ig - c * a1
    p2 = (b0 * m1 - b1 * m0) * ig - c * a2
    s0 = (m1 * a2 - m2 * a1) * ig
    s1 = (m2 * a0 - m0 * a2) * ig
    s2 = (m0 * a1 - m1 * a0) * ig
    return (a0, a1, a2, b0, b1, b2, u0, u1, u2, w0, w1, w2, g, K0, K1, K2, Kd0, Kd1, Kd2, kap,
            kapd, ms, m0, m1, m2, p0, p1, p2, s0, s1, s2)


@njit(inline="always")
def _internal_forces(q, v, props, rest, scalar, force):
    """Q_int per element without its derivatives (docs/theory.md §I.1.4): the residual's kernel.
    The quadrature points' terms are scalars (:func:`_axial_point`, :func:`_bending_point`),
    held in registers: 4.6 → 2.4 µs for Example 1's 16 elements against the tangent kernel's
    work arrays (:func:`_internal_kernel`, which states its forces with the same functions).
    Inlined into the residual (:func:`beam_residual`): a call passing the section's
    properties and rest state cost 0.06 µs of the 8-element cantilever's 2.07 µs."""
    n_ax = rest.axial_weight.shape[1]
    n_b = rest.bending_weight.shape[1]
    for e in range(q.shape[0]):
        EA = props.axial_stiffness[e]
        EI = props.bending_stiffness[e]
        dA = props.axial_damping[e]
        dB = props.bending_damping[e]
        for i in range(12):
            force[e, i] = 0.0
        for k in range(n_ax):
            t0, t1, t2, _, _, N, _, _, _ = _axial_point(q, v, e, k, rest, EA, dA)
            WN = rest.axial_weight[e, k] * N
            for n in range(4):
                f = WN * rest.axial_dS[e, k, n]
                force[e, 3 * n] += f * t0
                force[e, 3 * n + 1] += f * t1
                force[e, 3 * n + 2] += f * t2
        for k in range(n_b):
            pt = _bending_point(q, v, e, k, rest, EI, dB, scalar)
            W = rest.bending_weight[e, k]
            for n in range(4):
                dn = rest.bending_dS[e, k, n]
                hn = rest.bending_ddS[e, k, n]
                force[e, 3 * n] += W * (dn * pt[25] + hn * pt[28])
                force[e, 3 * n + 1] += W * (dn * pt[26] + hn * pt[29])
                force[e, 3 * n + 2] += W * (dn * pt[27] + hn * pt[30])


@njit(inline="always")
def _add_skew(M, x, s):
    """``M += s x̃`` (x̃ the cross-product matrix of x: x̃ y = x × y)."""
    M[0, 1] -= s * x[2]
    M[0, 2] += s * x[1]
    M[1, 0] += s * x[2]
    M[1, 2] -= s * x[0]
    M[2, 0] -= s * x[1]
    M[2, 1] += s * x[0]


@njit(inline="always")
def _add_point_blocks(mat, e, W, ds, dds, P11, P12, P21, P22, TU):
    """``mat[e] += W Gᵀ [P11 P12; P21 P22] G``, G = [S′ ⊗ I; S″ ⊗ I]: node block (n, m)
    += W (S′_nS′_m P11 + S′_nS″_m P12 + S″_nS′_m P21 + S″_nS″_m P22), in two stages
    T_n = W(S′_n P11 + S″_n P21), U_n = W(S′_n P12 + S″_n P22) (``TU``, (8, 3, 3)), then
    block (n, m) += S′_m T_n + S″_m U_n: 432 products per bending point instead of 576."""
    for n in range(4):
        wd = W * ds[n]
        wh = W * dds[n]
        for c in range(3):
            for d in range(3):
                TU[n, c, d] = wd * P11[c, d] + wh * P21[c, d]
                TU[4 + n, c, d] = wd * P12[c, d] + wh * P22[c, d]
    for n in range(4):
        for m in range(4):
            dm = ds[m]
            hm = dds[m]
            for c in range(3):
                for d in range(3):
                    mat[e, 3 * n + c, 3 * m + d] += TU[n, c, d] * dm + TU[4 + n, c, d] * hm


@njit
def _internal_kernel(q, v, props, rest, scalar, want_k, want_c, force, stiff, damp, work):
    """Q_int, ∂Q_int/∂q, ∂Q_int/∂q̇ per element (docs/theory.md §I.1.4, derivation in the notes).

    Each S′_i has a single non-zero component, so every 12×12 contribution of a quadrature point
    is Σ over 4×4 node pairs (n, m) of scalar products of S′/S″ values times four 3×3 operators.
    Bending (with K = f/g, f = a×b, g = μ|a|²): D_n = S′_n B1 + S″_n B2 with
    B1 = (−b̃ − 2μ K aᵀ)/g, B2 = ã/g; the Hessian contracted with m gives
    Σ_c m_c ∂²K_c/∂q_i∂q_j = S′_nS′_m X + S″_nS′_m (Y − Z) + S′_nS″_m (Yᵀ + Z) with
    X = −2μ(p aᵀ + a pᵀ + (m·K) I)/g, Y = −2μ s aᵀ/g, Z = −m̃/g, p = B1ᵀm, s = B2ᵀm; and the
    Hessian contracted with q̇ (for the damping force's q-dependence) is S′_n E1 + S″_n E2 with
    E1 = (−ḃ̃ − ġB1 − 2μ(K̇aᵀ + Kȧᵀ))/g, E2 = (ȧ̃ − ġB2)/g, ġ = 2μ a·ȧ.
    An element without damping (d_ε = d_K = 0) skips the damping's terms, which are zero:
    ∂Q_int/∂q̇ (zeroed) and E1, E2 (with the two-stage blocks of :func:`_add_point_blocks`:
    the 8-element cantilever's tangent 11.9 → 7.0 µs, Example 1's 16 elements 29.2 → 16.3 µs).
    """
    n_elem = q.shape[0]
    n_ax = rest.axial_weight.shape[1]
    n_b = rest.bending_weight.shape[1]
    EAv = props.axial_stiffness
    EIv = props.bending_stiffness
    dAv = props.axial_damping
    dBv = props.bending_damping
    # views of the caller's work arrays (allocating 25 small arrays per call cost 0.35 µs of
    # the 8-element cantilever's 2.3 µs)
    a = work.vec[0]
    b = work.vec[1]
    ad = work.vec[2]
    bd = work.vec[3]
    t = work.vec[4]
    K = work.vec[5]
    Kd = work.vec[6]
    meff = work.vec[7]
    p = work.vec[8]
    s = work.vec[9]
    al = work.vec[10]
    be = work.vec[11]
    r1 = work.vec[12]
    r2 = work.vec[13]
    ds = work.node[0]
    dds = work.node[1]
    A3 = work.mat[0]
    B1 = work.mat[1]
    B2 = work.mat[2]
    E1 = work.mat[3]
    E2 = work.mat[4]
    P11 = work.mat[5]
    P12 = work.mat[6]
    P21 = work.mat[7]
    P22 = work.mat[8]
    TU = work.mat[9:]

    for e in range(n_elem):
        EA = EAv[e]
        EI = EIv[e]
        dA = dAv[e]
        dB = dBv[e]
        # the damping matrix's terms only where the element has damping (zeroed above else)
        wc = want_c and (dA != 0.0 or dB != 0.0)
        for i in range(12):
            force[e, i] = 0.0
        if want_k:
            for i in range(12):
                for j in range(12):
                    stiff[e, i, j] = 0.0
        if want_c:
            for i in range(12):
                for j in range(12):
                    damp[e, i, j] = 0.0

        # ---- axial: N = EA(|a|/μ − 1 − ε_off) + d_ε t·ȧ/μ,  Q = W N S′ᵀt
        for k in range(n_ax):
            W = rest.axial_weight[e, k]
            mu = rest.axial_metric[e, k]
            for n in range(4):
                ds[n] = rest.axial_dS[e, k, n]
            t0, t1, t2, la, tad, N, u0, u1, u2 = _axial_point(q, v, e, k, rest, EA, dA)
            t[0], t[1], t[2] = t0, t1, t2
            ad[0], ad[1], ad[2] = u0, u1, u2
            WN = W * N
            for n in range(4):
                for c in range(3):
                    force[e, 3 * n + c] += WN * ds[n] * t[c]
            if want_k:
                # ∂N/∂q = S′ᵀ[(EA/μ) t + (d_ε/(μ|a|)) (I − ttᵀ) ȧ];  ∂t/∂q = (I − ttᵀ)S′/|a|
                c1 = EA / mu
                c2 = dA / (mu * la)
                c3 = N / la
                for c in range(3):
                    for d in range(3):
                        pad = ad[d] - t[d] * tad
                        A3[c, d] = t[c] * (c1 * t[d] + c2 * pad) - c3 * t[c] * t[d]
                    A3[c, c] += c3
                for n in range(4):
                    for m in range(4):
                        cw = W * ds[n] * ds[m]
                        for c in range(3):
                            for d in range(3):
                                stiff[e, 3 * n + c, 3 * m + d] += cw * A3[c, d]
            if wc:
                c1 = dA / mu
                for n in range(4):
                    for m in range(4):
                        cw = W * c1 * ds[n] * ds[m]
                        for c in range(3):
                            for d in range(3):
                                damp[e, 3 * n + c, 3 * m + d] += cw * t[c] * t[d]

        # ---- bending
        for k in range(n_b):
            W = rest.bending_weight[e, k]
            mu = rest.bending_metric[e, k]
            for n in range(4):
                ds[n] = rest.bending_dS[e, k, n]
                dds[n] = rest.bending_ddS[e, k, n]
            (a[0], a[1], a[2], b[0], b[1], b[2], ad[0], ad[1], ad[2], bd[0], bd[1], bd[2], g,
             K[0], K[1], K[2], Kd[0], Kd[1], Kd[2], kap, kapd, ms, meff[0], meff[1], meff[2],
             p[0], p[1], p[2], s[0], s[1], s[2]) = _bending_point(q, v, e, k, rest, EI, dB, scalar)
            ig = 1.0 / g
            tm = 2.0 * mu
            for n in range(4):
                for c in range(3):
                    force[e, 3 * n + c] += W * (ds[n] * p[c] + dds[n] * s[c])
            # the tangent's operators B1 = (−b̃ − 2μ K aᵀ)/g, B2 = ã/g (p = B1ᵀm_eff,
            # s = B2ᵀm_eff, K̇ = B1 ȧ + B2 ḃ in _bending_point)
            for c in range(3):
                for d in range(3):
                    B1[c, d] = -tm * K[c] * a[d] * ig
                    B2[c, d] = 0.0
            _add_skew(B1, b, -ig)       # −b̃/g
            _add_skew(B2, a, ig)        # ã/g

            if scalar and (want_k or wc):
                # k_q = DᵀK/κ has node blocks S′_n α + S″_n β
                for c in range(3):
                    al[c] = (B1[0, c] * K[0] + B1[1, c] * K[1] + B1[2, c] * K[2]) / kap
                    be[c] = (B2[0, c] * K[0] + B2[1, c] * K[1] + B2[2, c] * K[2]) / kap

            if want_k:
                if dB != 0.0:
                    gd = tm * (a[0] * ad[0] + a[1] * ad[1] + a[2] * ad[2])
                    # E1 = (−ḃ̃ − ġB1 − 2μ(K̇aᵀ + Kȧᵀ))/g,  E2 = (ȧ̃ − ġB2)/g
                    for c in range(3):
                        for d in range(3):
                            E1[c, d] = (-gd * B1[c, d]
                                        - tm * (Kd[c] * a[d] + K[c] * ad[d])) * ig
                            E2[c, d] = -gd * B2[c, d] * ig
                    _add_skew(E1, bd, -ig)      # −ḃ̃/g
                    _add_skew(E2, ad, ig)       # ȧ̃/g
                # Hessian of K contracted with m_eff: X, Y, Z
                mK = meff[0] * K[0] + meff[1] * K[1] + meff[2] * K[2]
                cx = -tm * ig
                for c in range(3):
                    for d in range(3):
                        P11[c, d] = cx * (p[c] * a[d] + a[c] * p[d])
                        y_cd = cx * s[c] * a[d]
                        y_dc = cx * s[d] * a[c]
                        P21[c, d] = y_cd
                        P12[c, d] = y_dc
                        P22[c, d] = 0.0
                    P11[c, c] += cx * mK
                # Z = −m̃/g:  P12 += Z, P21 −= Z
                z01 = meff[2] * ig
                z02 = -meff[1] * ig
                z12 = meff[0] * ig
                P12[0, 1] += z01
                P12[1, 0] -= z01
                P12[0, 2] += z02
                P12[2, 0] -= z02
                P12[1, 2] += z12
                P12[2, 1] -= z12
                P21[0, 1] -= z01
                P21[1, 0] += z01
                P21[0, 2] -= z02
                P21[2, 0] += z02
                P21[1, 2] -= z12
                P21[2, 1] += z12
                if scalar:
                    # EI k_q k_qᵀ + m_s/κ (DᵀD − k_q k_qᵀ) + d_K k_q (∂κ̇/∂q)ᵀ
                    c0 = ms / kap
                    ce = EI - c0
                    for c in range(3):
                        r1[c] = ce * al[c]
                        r2[c] = ce * be[c]
                        if dB != 0.0:
                            # ∂κ̇/∂q node blocks S′_n γ + S″_n η
                            gam = ((B1[0, c] * Kd[0] + B1[1, c] * Kd[1] + B1[2, c] * Kd[2]
                                    + E1[0, c] * K[0] + E1[1, c] * K[1] + E1[2, c] * K[2])
                                   / kap - kapd / kap * al[c])
                            eta = ((B2[0, c] * Kd[0] + B2[1, c] * Kd[1] + B2[2, c] * Kd[2]
                                    + E2[0, c] * K[0] + E2[1, c] * K[1] + E2[2, c] * K[2])
                                   / kap - kapd / kap * be[c])
                            r1[c] += dB * gam
                            r2[c] += dB * eta
                    for c in range(3):
                        for d in range(3):
                            b11 = B1[0, c] * B1[0, d] + B1[1, c] * B1[1, d] + B1[2, c] * B1[2, d]
                            b12 = B1[0, c] * B2[0, d] + B1[1, c] * B2[1, d] + B1[2, c] * B2[2, d]
                            b21 = B2[0, c] * B1[0, d] + B2[1, c] * B1[1, d] + B2[2, c] * B1[2, d]
                            b22 = B2[0, c] * B2[0, d] + B2[1, c] * B2[1, d] + B2[2, c] * B2[2, d]
                            P11[c, d] += c0 * b11 + al[c] * r1[d]
                            P12[c, d] += c0 * b12 + al[c] * r2[d]
                            P21[c, d] += c0 * b21 + be[c] * r1[d]
                            P22[c, d] += c0 * b22 + be[c] * r2[d]
                else:
                    # EI DᵀD + d_K Dᵀ(∂K̇/∂q)
                    for c in range(3):
                        for d in range(3):
                            b11 = B1[0, c] * B1[0, d] + B1[1, c] * B1[1, d] + B1[2, c] * B1[2, d]
                            b12 = B1[0, c] * B2[0, d] + B1[1, c] * B2[1, d] + B1[2, c] * B2[2, d]
                            b21 = B2[0, c] * B1[0, d] + B2[1, c] * B1[1, d] + B2[2, c] * B1[2, d]
                            b22 = B2[0, c] * B2[0, d] + B2[1, c] * B2[1, d] + B2[2, c] * B2[2, d]
                            P11[c, d] += EI * b11
                            P12[c, d] += EI * b12
                            P21[c, d] += EI * b21
                            P22[c, d] += EI * b22
                            if dB != 0.0:
                                e11 = (B1[0, c] * E1[0, d] + B1[1, c] * E1[1, d]
                                       + B1[2, c] * E1[2, d])
                                e12 = (B1[0, c] * E2[0, d] + B1[1, c] * E2[1, d]
                                       + B1[2, c] * E2[2, d])
                                e21 = (B2[0, c] * E1[0, d] + B2[1, c] * E1[1, d]
                                       + B2[2, c] * E1[2, d])
                                e22 = (B2[0, c] * E2[0, d] + B2[1, c] * E2[1, d]
                                       + B2[2, c] * E2[2, d])
                                P11[c, d] += dB * e11
                                P12[c, d] += dB * e12
                                P21[c, d] += dB * e21
                                P22[c, d] += dB * e22
                _add_point_blocks(stiff, e, W, ds, dds, P11, P12, P21, P22, TU)

            if wc:
                # A-vec: d_K DᵀD;  A-scal: d_K k_q k_qᵀ
                for c in range(3):
                    for d in range(3):
                        if scalar:
                            P11[c, d] = dB * al[c] * al[d]
                            P12[c, d] = dB * al[c] * be[d]
                            P21[c, d] = dB * be[c] * al[d]
                            P22[c, d] = dB * be[c] * be[d]
                        else:
                            P11[c, d] = dB * (B1[0, c] * B1[0, d] + B1[1, c] * B1[1, d]
                                              + B1[2, c] * B1[2, d])
                            P12[c, d] = dB * (B1[0, c] * B2[0, d] + B1[1, c] * B2[1, d]
                                              + B1[2, c] * B2[2, d])
                            P21[c, d] = dB * (B2[0, c] * B1[0, d] + B2[1, c] * B1[1, d]
                                              + B2[2, c] * B1[2, d])
                            P22[c, d] = dB * (B2[0, c] * B2[0, d] + B2[1, c] * B2[1, d]
                                              + B2[2, c] * B2[2, d])
                _add_point_blocks(damp, e, W, ds, dds, P11, P12, P21, P22, TU)


_NO_MATRIX = np.zeros((0, 12, 12))


def internal_forces(q_e: np.ndarray, v_e: np.ndarray, props: CableProperties, rest: CableRest,
                    options: CableOptions, force_out: np.ndarray,
                    stiffness_out: np.ndarray | None = None,
                    damping_out: np.ndarray | None = None) -> None:
    """Internal force ``Q_int = ∂U/∂q`` + damping and its derivatives (docs/theory.md §I.1.4).

    ``q_e``, ``v_e``: (n_elem, 12) float64 C-contiguous. Overwrites ``force_out`` (n_elem, 12),
    and when given ``stiffness_out = ∂Q_int/∂q`` (consistent, including the q-dependence of the
    damping force) and ``damping_out = ∂Q_int/∂q̇``, both (n_elem, 12, 12) (the kernel's
    scratch is made here; the packed part keeps its own).
    """
    want_k = stiffness_out is not None
    want_c = damping_out is not None
    if not (want_k or want_c):
        _internal_forces(q_e, v_e, props, rest, 1 if options.bending == "scalar" else 0,
                         force_out)
        return
    _internal_kernel(q_e, v_e, props, rest, 1 if options.bending == "scalar" else 0,
                     want_k, want_c, force_out,
                     stiffness_out if want_k else _NO_MATRIX,
                     damping_out if want_c else _NO_MATRIX, kernel_work())


# ---------------------------------------------------------------------------------------------
# energy and output (vectorised numpy, independent of the kernel)
def strain_energy(q_e: np.ndarray, props: CableProperties, rest: CableRest,
                  options: CableOptions) -> np.ndarray:
    """Elastic energy per element, ∫½EA(ε − ε_off)² + bending per ds0 (docs/theory.md §I.1.3).

    Returns (n_elem,); damping does not enter.
    """
    q_e = np.asarray(q_e, dtype=float)
    EA = np.asarray(props.axial_stiffness, dtype=float)
    EI = np.asarray(props.bending_stiffness, dtype=float)
    a = _interp(rest.axial_dS, q_e)
    mu = rest.axial_metric
    eps = np.linalg.norm(a, axis=-1) / mu - 1.0 - rest.axial_offset
    U = 0.5 * EA * np.sum(rest.axial_weight * mu * eps * eps, axis=1)
    a = _interp(rest.bending_dS, q_e)
    b = _interp(rest.bending_ddS, q_e)
    K = np.cross(a, b) / (np.einsum("ekc,ekc->ek", a, a) * rest.bending_metric)[..., None]
    if options.bending == "scalar":
        kap = np.sqrt(np.einsum("ekc,ekc->ek", K, K) + rest.delta_sq[:, None])
        dk2 = (kap - rest.rest_curvature_norm) ** 2
    else:
        dK = K - rest.rest_curvature
        dk2 = np.einsum("ekc,ekc->ek", dK, dK)
    return U + 0.5 * EI * np.sum(rest.bending_weight * dk2, axis=1)


def output_fields(q_e: np.ndarray, rest: CableRest, options: CableOptions,
                  xi: np.ndarray) -> dict[str, np.ndarray]:
    """The cable's output fields at ξ: ``axial_strain`` and ``curvature`` (vector) of
    :func:`axial_strain_and_curvature`."""
    eps, K = axial_strain_and_curvature(q_e, rest, options, xi)
    return {"axial_strain": eps, "curvature": K}


def axial_strain_and_curvature(q_e: np.ndarray, rest: CableRest, options: CableOptions,
                               xi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Axial strain and curvature vector at ξ (docs/theory.md §I.1.3), for output.

    Returns ``eps`` (n_elem, m) and ``K`` (n_elem, m, 3). ``eps = |r′|/μ − 1`` (exact) or
    ``|r′| − |r′_ref|`` (Exudyn-compatible), i.e. the strain relative to the stress-free
    reference, without ε0; ``K = r′×r″/(|r′|² μ)`` (μ = 1 for Exudyn-compatible).
    """
    eps, K, _ = centerline_strain_and_curvature(q_e, rest.q_ref, rest.length, xi,
                                                options.exudyn_compatible)
    return eps, K


def centerline_strain_and_curvature(q_e: np.ndarray, q_ref: np.ndarray, length: np.ndarray,
                                    xi: np.ndarray, exudyn_compatible: bool = False
                                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`axial_strain_and_curvature` of Hermite centrelines ``q_e`` (n_elem, 12) on the
    reference ``q_ref`` (n_elem, 12), with the reference metric μ = |r′_ref| (n_elem, m)."""
    q_e = np.asarray(q_e, dtype=float)
    xi = np.atleast_1d(np.asarray(xi, dtype=float))
    _, dS, ddS = shape_functions(xi[None, :], np.asarray(length, dtype=float)[:, None])
    a = _interp(dS, q_e)
    b = _interp(ddS, q_e)
    la = np.linalg.norm(a, axis=-1)
    mu_ref = np.linalg.norm(_interp(dS, np.asarray(q_ref, dtype=float)), axis=-1)
    if exudyn_compatible:
        eps = la - mu_ref
        metric = np.ones_like(mu_ref)
    else:
        eps = la / mu_ref - 1.0
        metric = mu_ref
    K = np.cross(a, b) / (la * la * metric)[..., None]
    return eps, K, mu_ref


# ---------------------------------------------------------------------------------------------
# the beam term of the assembler (flexmbs.terms): all elements of beams sharing CableOptions
class BeamPart(NamedTuple):
    """One group of cable elements (same :class:`CableOptions`), packed for the kernels."""

    dofs: np.ndarray                 # (n_elem, 12) global coordinates
    pos: np.ndarray                  # (n_elem, 144) matrix positions of the element blocks
    props: CableProperties
    rest: CableRest
    scalar: int                      # 1: scalar-curvature bending (CableOptions.bending)
    mass: np.ndarray                 # (n_elem, 12, 12) consistent mass (constant)
    qe: np.ndarray                   # work (n_elem, 12): q, q̇ of the elements, Q_int
    ve: np.ndarray
    force: np.ndarray
    stiff: np.ndarray                # work (n_elem, 12, 12): ∂Q_int/∂q, ∂Q_int/∂q̇
    damp: np.ndarray
    work: KernelWork                 # scratch of _internal_kernel


def pack_beams(element_dofs: np.ndarray, props: CableProperties, options: CableOptions,
               q_ref: np.ndarray, positions: np.ndarray) -> BeamPart:
    """``element_dofs`` (n_elem, 12), the section resultants per element, the reference
    coordinates (global vector) and the matrix positions (n_elem, 144) of the element blocks."""
    D = np.ascontiguousarray(element_dofs, dtype=np.int64)
    ne = D.shape[0]
    rest = rest_state(np.ascontiguousarray(q_ref[D]), props, options) if ne else _empty_rest()
    mass = np.ascontiguousarray(mass_matrix(props))
    return BeamPart(
        dofs=D,
        pos=np.ascontiguousarray(positions, dtype=np.int64).reshape(ne, 144),
        props=props,
        rest=rest,
        scalar=1 if options.bending == "scalar" else 0,
        mass=mass,
        qe=np.zeros((ne, 12)),
        ve=np.zeros((ne, 12)),
        force=np.zeros((ne, 12)),
        stiff=np.zeros((ne, 12, 12)),
        damp=np.zeros((ne, 12, 12)),
        work=kernel_work())


def _empty_rest() -> CableRest:
    z1, z2 = np.zeros(0), np.zeros((0, 1))
    return CableRest(z1, np.zeros((0, 12)), np.zeros(1), z2, z2, z2, np.zeros((0, 1, 4)),
                     np.zeros(1), z2, z2, np.zeros((0, 1, 4)), np.zeros((0, 1, 4)),
                     np.zeros((0, 1, 3)), z2, z1)


@njit
def beam_residual(bm, q, v, qdd, mode, r):
    """``r_q += Q_int(q, q̇) (+ M q̈ with inertia)`` of the elements (docs/theory.md §I.1.2, §I.1.4);
    returns the largest single force (an element force entry or a row of M q̈)."""
    gather_states(bm, q, v, mode)
    _internal_forces(bm.qe, bm.ve, bm.props, bm.rest, bm.scalar, bm.force)
    return add_residual(bm, qdd, mode, r)


@njit
def beam_jacobian(bm, q, v, qdd, mode, cM, cC, cK, data):
    """``cK ∂Q_int/∂q + cC ∂Q_int/∂q̇ + cM M`` into the CSC ``data``; returns the largest
    diagonal stiffness entry (the scale of the rounding floor of the convergence test)."""
    gather_states(bm, q, v, mode)
    _internal_kernel(bm.qe, bm.ve, bm.props, bm.rest, bm.scalar, FLAG[1], FLAG[1], bm.force,
                     bm.stiff, bm.damp, bm.work)
    return add_matrix(bm, cM, cC, cK, data)


def section_properties(beams: list) -> CableProperties:
    """Section resultants per element of ``beams`` (in order): EA, EI, ρA from each beam's
    stiffness, stiffness-proportional damping, reference axial strain."""
    cols: dict[str, list[np.ndarray]] = {f: [] for f in CableProperties._fields}
    for beam in beams:
        ne = beam.n_elem
        st = beam.stiffness
        values = {"length": np.asarray(beam.centerline.lengths, float),
                  "axial_stiffness": st.axial_stiffness, "bending_stiffness": st.bending_stiffness,
                  "mass_per_length": st.mass_per_length,
                  "axial_damping": beam.damping * st.axial_stiffness,
                  "bending_damping": beam.damping * st.bending_stiffness,
                  "reference_axial_strain": beam.reference_axial_strain}
        for f in CableProperties._fields:
            cols[f].append(np.broadcast_to(np.asarray(values[f], float), (ne,)).copy())
    return CableProperties(*(np.concatenate(cols[f]) if cols[f] else np.zeros(0)
                             for f in CableProperties._fields))


#: the cable as the assembler sees it (flexmbs.elements.layout.ElementType)
ELEMENT_TYPES.register("ancf_cable", ElementType(
    layout=LAYOUT, section_properties=section_properties,
    reference_nodal_coordinates=reference_nodal_coordinates, gravity_force=gravity_force,
    distributed_force=distributed_force, point_force=point_force_vector, pack=pack_beams,
    strain_energy=strain_energy, output_fields=output_fields, part_type=BeamPart,
    residual=beam_residual, jacobian=beam_jacobian, default_options=CableOptions(),
    shared_rest_fields=("axial_xi", "bending_xi")))

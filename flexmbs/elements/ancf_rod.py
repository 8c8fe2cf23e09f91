"""Element B: the 14-DOF ANCF Kirchhoff rod with a nodal twist angle (docs/theory.md §I.2).

Per node ``[r (3), g = r′ (3), φ (1)]``; the centreline is the cable's cubic Hermite
(:func:`flexmbs.elements.hermite.hermite_basis`, the one statement of the basis). Each node has
a fixed base ``(t̄_i, D̄_i)`` from the reference (unit tangent, a unit vector ⟂ it, by parallel
transport along the beam's nodes, §4.6); its triad is

    t_i = g_i/|g_i|,   d2_i = Rot(t_i, φ_i) SR(t̄_i → t_i) D̄_i,   d3_i = t_i × d2_i

with the smallest rotation SR and the rotation Rot of §2.1. At ξ = x/L of an element (§2.2):

    t = r′/|r′|,  t_x = (r″ − t (t·r″))/|r′|,   d̂ = SR(t_0 → t_1) d2_0,
    Δθ = atan2((d̂ × d2_1)·t_1, d̂·d2_1)   (an angle in (−π, π]: < 180° of twist per element),
    d2(x) = Rot(t, ξΔθ) SR(t_0 → t) d2_0,   d3 = t × d2,
    ε = |r′|/μ − 1,  K = (r′ × r″)/(|r′|² μ),  K2 = K·d2,  K3 = K·d3,
    τ_SR = −t_0·(t × t_x)/(1 + t_0·t),   K1 = (Δθ/L + τ_SR)/μ,
    U_e = ∫₀ᴸ ½ [EA (ε − ε0)² + GJ (K1 − K1⁰)² + EI2 (K2 − K2⁰)² + EI3 (K3 − K3⁰)²] μ dx

(μ = |r′| of the reference, the superscript 0 the same measures in the reference with φ = 0, ε0
the reference axial strain), the curvatures at 3 Gauss points (§2.5), the axial strain at 3
Lobatto points (0, ½, 1; free of membrane locking like the cable's default, §1.5). Every
interior quantity comes from the current nodal triads through SR(t_0 → ·), which is
equivariant, so U is objective; U(q_ref) = 0 for any reference.

**Derivatives.** The four maps the energy is made of — a node's ``(g, φ) → (t, d2)``, the
triads ``→ Δθ``, a point's ``(r′, r″, t_0, d2_0, Δθ) → (K1, K2, K3)`` and ``r′ → ε`` — are
differentiated exactly (first and second derivatives) by sympy in ``tools/rod_derivatives.py``,
which writes :mod:`flexmbs.elements._rod_derivatives`; :func:`_rod_forces` and
:func:`_rod_tangents` compose them by the chain rule (§2.3, "hand-derived chain rules"). The
generated module is the one statement of the maps: energy, forces, tangent, reference measures
and output all call it.

**Damping** is strain-rate (stiffness-proportional) damping with coefficient β:
each generalized stress is ``C_j (e_j − e_j⁰ + β ė_j)`` (as the cable's ``d_ε = β EA``).

**Mass** (§2.3): the cable's constant translational mass on (r, g) and the constant twist
inertia ``ρJ_p L/6 [[2, 1], [1, 2]]`` on the two φ.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from .._jit import FLAG, njit
from ..codes import ERROR_CODES
from ..errors import ModelError
from ..terms import WITH_INERTIA
from . import ancf_cable as cable
from ._rod_derivatives import (
    axial,
    axial_h,
    curvatures,
    curvatures_wh,
    director_turn,
    director_turn_h,
    spin,
    spin_value,
    triad,
    triad_h,
    twist,
    twist_h,
)
from .group import add_matrix, add_residual, gather_states
from .hermite import hermite_basis
from .layout import ELEMENT_TYPES, ElementLayout, ElementType

__all__ = ["LAYOUT", "RodProperties", "RodRest", "RodPart", "TurnWork", "base_frames",
           "director_turn_at", "new_turn_work", "internal_forces",
           "mass_matrix", "nodal_triads", "rest_state", "strain_energy", "strain_measures",
           "output_fields"]

LAYOUT = ElementLayout(name="ancf_rod14",
                       node_coordinates=("x", "y", "z", "x'", "y'", "z'", "twist"),
                       position=(0, 1, 2), slope=(3, 4, 5), twist=6,
                       output_fields=("axial_strain", "curvature", "twist", "torsion",
                                      "torsional_moment"),
                       vector_fields=("curvature",))
NODE_SIZE = LAYOUT.node_size
ELEMENT_SIZE = LAYOUT.element_size
TWIST: int = LAYOUT.twist if LAYOUT.twist is not None else -1   #: nodal index of the twist φ
SLOPE: int = LAYOUT.slope[0]   #: nodal index of the slope's first component
#: a node whose unit tangent t has t̄·t below this after a converged step is re-based (§2.4:
#: its tangent turned more than 120° from its base t̄)
REBASE_LIMIT = -0.5
#: a node whose tangent turned past this (about 154°) within one step fails the step (the
#: smallest rotation from t̄ is singular at 180°): the integrator retries with a smaller step
TURN_LIMIT = -0.9
#: the error code of that failure (distinct from the joints' codes, flexmbs.driver)
ERR_NODE_TURNED = ERROR_CODES["node_turned"]
N_GAUSS = 3                #: Gauss points of the curvatures (§2.5's recommendation)
N_STRAIN = 4               #: ε, K1, K2, K3
N_Z = 13                   #: inputs of the Gauss-point map: r′, r″, t_0, d2_0, Δθ
N_N = 7                    #: the nodal part of them: t_0, d2_0, Δθ
N_U = 8                    #: their element inputs: g_0, φ_0, g_1, φ_1
N_SPIN = 8                 #: outputs of the generated ``spin`` map: w, b (3), s, c (3)
N_TURN = 10                #: what a section's turn depends on at a point: r′, t_0, d2_0, Δθ
N_TURN_MAP = 9             #: inputs of the generated ``director_turn`` map: t, t_0, d2_0
#: element coordinates of the centreline [r0, g0, r1, g1] and of the nodal inputs [g0, φ0, g1, φ1]
CENTERLINE = LAYOUT.centerline
U_COLS = np.array([a * NODE_SIZE + i for a in range(2) for i in (*LAYOUT.slope, TWIST)], np.int64)


class RodProperties(NamedTuple):
    """Section resultants per element; every field has shape ``(n_elem,)``."""

    length: np.ndarray                  #: L [m]
    EA: np.ndarray                      #: axial stiffness [N]
    GJ: np.ndarray                      #: torsional stiffness [N m²]
    EI2: np.ndarray                     #: bending stiffness about d2 [N m²]
    EI3: np.ndarray                     #: bending stiffness about d3 [N m²]
    mass_per_length: np.ndarray         #: ρA [kg/m]
    twist_inertia: np.ndarray           #: ρJ_p [kg m]
    damping: np.ndarray                 #: β [s]: stresses C (e − e⁰ + β ė)
    reference_axial_strain: np.ndarray  #: ε0 (< 0: pretension)


class RodRest(NamedTuple):
    """The nodal bases of every element's two nodes and the reference measures at the
    quadrature points: the curvatures at 3 Gauss points, the axial strain at 3 Lobatto points
    (0, ½, 1: free of membrane locking, as the cable's default, docs/theory.md §I.1.5, §I.2.5).
    ``t_bar, d_bar`` are the current bases (changed by re-basing, §2.4; a checkpoint carries
    them), ``t_ref, d_ref`` the reference's (with ``q_ref`` they give the reference measures)."""

    t_bar: np.ndarray          # (n_elem, 2, 3)
    d_bar: np.ndarray          # (n_elem, 2, 3)
    t_ref: np.ndarray          # (n_elem, 2, 3)
    d_ref: np.ndarray          # (n_elem, 2, 3)
    gauss_xi: np.ndarray       # (N_GAUSS,) on [0, 1]
    gauss_weight: np.ndarray   # (N_GAUSS,) weights, sum 1
    gauss_mu: np.ndarray       # (n_elem, N_GAUSS) |r′| of the reference
    k0: np.ndarray             # (n_elem, N_GAUSS, 3) K1⁰, K2⁰, K3⁰
    axial_xi: np.ndarray       # (N_AXIAL,)
    axial_weight: np.ndarray   # (N_AXIAL,)
    axial_mu: np.ndarray       # (n_elem, N_AXIAL)
    eps0: np.ndarray           # (n_elem, 1) reference axial strain ε0
    length: np.ndarray         # (n_elem,) L
    q_ref: np.ndarray          # (n_elem, 14) the reference, φ = 0
    stiffness: np.ndarray      # (n_elem, 4) EA, GJ, EI2, EI3 (for output)


class RodWork(NamedTuple):
    """Scratch arrays of the element kernels (zeroed once: the generated maps write the same
    nonzero entries every call)."""

    x_node: np.ndarray    # (4,)
    p_node: np.ndarray    # (6,)
    t_val: np.ndarray     # (2, 6) t_a, d2_a
    t_jac: np.ndarray     # (2, 6, 4)
    t_hes: np.ndarray     # (2, 6, 4, 4)
    x_tw: np.ndarray      # (12,)
    p_none: np.ndarray    # (0,)
    w_val: np.ndarray     # (1,)
    w_jac: np.ndarray     # (1, 12)
    w_hes: np.ndarray     # (1, 12, 12)
    n_jac: np.ndarray     # (N_N, N_U) ∂(t0, d20, Δθ)/∂u
    n_hes: np.ndarray     # (N_N, N_U, N_U)
    n_hv: np.ndarray      # (N_N, N_U) n_hes · u̇
    x_z: np.ndarray       # (N_Z,) r′, r″, t0, d20, Δθ at a point
    p_c: np.ndarray       # (6,) ξ, L, μ (and σ for ``curvatures_wh``)
    p_a: np.ndarray       # (1,) μ
    c_val: np.ndarray     # (3,) K1, K2, K3
    c_jac: np.ndarray     # (3, N_Z)
    c_hes: np.ndarray     # (3, N_Z, N_Z)
    a_val: np.ndarray     # (1,) ε
    a_jac: np.ndarray     # (1, 3)
    a_hes: np.ndarray     # (1, 3, 3)
    ab: np.ndarray        # (2, 4) ∂r′/∂X_m = S′_m/L, ∂r″/∂X_m = S″_m/L² (X_m = r0, g0, r1, g1)
    e_q: np.ndarray       # (3, 14) ∂e/∂q
    sig: np.ndarray       # (3,) generalized stresses
    s_zz: np.ndarray      # (N_Z, N_Z) A = W Σ_j (σ_j ∂²e_j/∂z² + C_j ∂e_j/∂z ∂e_j/∂zᵀ)
    s_zn: np.ndarray      # (N_Z, N_U) scratch: p_nn ∂n/∂u (first N_N rows)
    z_v: np.ndarray       # (N_Z,) ∂z/∂q · q̇
    h_q: np.ndarray       # (3, 14) ∂²e_j/∂q² · q̇
    g_n: np.ndarray       # (N_N,) Σ_points W σ_j ∂e_j/∂n
    hz: np.ndarray        # (N_Z,)
    c_coef: np.ndarray    # (3,) GJ, EI2, EI3 of the element
    a_coef: np.ndarray    # (1,) EA
    s_x: np.ndarray       # (6,) g, ġ of a node (twist inertia)
    s_p: np.ndarray       # (3,) its base tangent t̄
    s_y: np.ndarray       # (2, N_SPIN) w, b, s, c of both nodes
    s_jac: np.ndarray     # (2, N_SPIN, 6) their derivatives with respect to (g, ġ)
    s_d: np.ndarray       # (2, 2, 3) per node: the matrix rows of w and of ẇ (g columns)
    s_m: np.ndarray       # (3, 2) per node: M_φ ω, M_φ ω̇, M_φ ẇ
    s_o: np.ndarray       # (3, 2) per node: ω, ω̇, ẇ
    y_z: np.ndarray       # (N_Z,) W Σ σ_j ∂e_j/∂z at a point
    p_cn: np.ndarray      # (12, N_N) Σ_points centreline-nodal block of A
    p_nn: np.ndarray      # (N_N, N_N) Σ_points nodal-nodal block of A
    h_w: np.ndarray       # (1, N_Z, N_Z) Σ_j σ_j ∂²K_j/∂z² (generated ``curvatures_wh``)
    one: np.ndarray       # (1,) 1.0: the weight of ``h_w``
    w_x: np.ndarray       # (12, N_U) ∂²Δθ/∂t² · ∂t/∂u
    unit: np.ndarray      # (3, 3) identity: weights picking one curvature's Hessian
    p_cc: np.ndarray      # (12, 12) Σ_points centreline-centreline block of (∂z/∂q)ᵀ A ∂z/∂q


class TurnWork(NamedTuple):
    """Scratch of :func:`director_turn_at` (zeroed once, as :class:`RodWork`)."""

    rod: RodWork
    x: np.ndarray         # (N_TURN_MAP,) t, t_0, d2_0: the generated map's inputs
    p: np.ndarray         # (6,) t̄, ȳ
    val: np.ndarray       # (1,) β
    jac: np.ndarray       # (1, N_TURN_MAP)
    hes: np.ndarray       # (1, N_TURN_MAP, N_TURN_MAP)
    zg: np.ndarray        # (N_TURN,) ∂ψ/∂z, z = (r′, t_0, d2_0, Δθ)
    zh: np.ndarray        # (N_TURN, N_TURN) ∂²ψ/∂z²
    zq: np.ndarray        # (N_TURN, ELEMENT_SIZE) ∂z/∂q
    hz: np.ndarray        # (N_TURN, ELEMENT_SIZE) (∂²ψ/∂z²) ∂z/∂q
    q_e: np.ndarray       # (ELEMENT_SIZE,) a caller's element coordinates
    grad: np.ndarray      # (ELEMENT_SIZE,) a caller's ∂ψ/∂q
    hess: np.ndarray      # (ELEMENT_SIZE, ELEMENT_SIZE) a caller's ∂²ψ/∂q²


def new_turn_work() -> TurnWork:
    z = np.zeros
    n, m = ELEMENT_SIZE, N_TURN_MAP
    return TurnWork(new_work(), z(m), z(6), z(1), z((1, m)), z((1, m, m)), z(N_TURN),
                    z((N_TURN, N_TURN)), z((N_TURN, n)), z((N_TURN, n)), z(n), z(n), z((n, n)))


def new_work() -> RodWork:
    z = np.zeros
    n = ELEMENT_SIZE
    nc = CENTERLINE.size
    return RodWork(z(4), z(6), z((2, 6)), z((2, 6, 4)), z((2, 6, 4, 4)), z(12), z(0), z(1),
                   z((1, 12)), z((1, 12, 12)), z((N_N, N_U)), z((N_N, N_U, N_U)), z((N_N, N_U)),
                   z(N_Z), z(6), z(1), z(3), z((3, N_Z)), z((3, N_Z, N_Z)), z(1), z((1, 3)),
                   z((1, 3, 3)), z((2, 4)), z((3, n)), z(3), z((N_Z, N_Z)), z((N_Z, N_U)), z(N_Z),
                   z((3, n)), z(N_N), z(N_Z), z(3), z(1), z(6), z(3), z((2, N_SPIN)),
                   z((2, N_SPIN, 6)), z((2, 2, 3)), z((3, 2)), z((3, 2)), z(N_Z), z((nc, N_N)),
                   z((N_N, N_N)), z((1, N_Z, N_Z)), np.ones(1),
                   z((12, N_U)), np.eye(3), z((nc, nc)))


# ---------------------------------------------------------------------------------------------
# the nodal maps and the strain measures (values; docs/theory.md §I.2.1–2.2)
@njit(refcount=False)
def _node_inputs(q_e, t_bar, d_bar, w, a):
    """Node slot ``a``'s (g, φ) into ``x_node`` and its base (t̄, D̄) into ``p_node``."""
    o = a * NODE_SIZE
    for c in range(3):
        w.x_node[c] = q_e[o + SLOPE + c]
        w.p_node[c] = t_bar[a, c]
        w.p_node[3 + c] = d_bar[a, c]
    w.x_node[3] = q_e[o + TWIST]


@njit(refcount=False)
def _shared_triad(w, hessian):
    """Node 0's triad (and its Hessian) is the previous element's node 1: copy slot 1 to 0."""
    for c in range(6):
        w.t_val[0, c] = w.t_val[1, c]
        for k in range(4):
            w.t_jac[0, c, k] = w.t_jac[1, c, k]
            if hessian:
                for m in range(4):
                    w.t_hes[0, c, k, m] = w.t_hes[1, c, k, m]


@njit(refcount=False)
def _nodal_jacobian(w):
    """``x_tw`` from both triads, and ``n_jac`` = ∂(t_0, d2_0, Δθ)/∂u (after the twist map)."""
    nj = w.n_jac
    for c in range(6):
        for k in range(4):
            nj[c, k] = w.t_jac[0, c, k]
            nj[c, 4 + k] = 0.0
    for a in range(2):
        for k in range(4):
            s = 0.0
            for c in range(6):
                s += w.w_jac[0, 6 * a + c] * w.t_jac[a, c, k]
            nj[6, 4 * a + k] = s


@njit(refcount=False)
def _twist_inputs(w):
    for a in range(2):
        for c in range(6):
            w.x_tw[6 * a + c] = w.t_val[a, c]


@njit(refcount=False)
def _nodal(q_e, t_bar, d_bar, w, shared):
    """Both nodal triads and Δθ of one element, with ``n_jac``: the derivatives of
    n = (t_0, d2_0, Δθ) with respect to u = (g_0, φ_0, g_1, φ_1). ``shared``: node 0 is the
    previous element's node 1, whose triad is still in the work arrays."""
    if shared:
        _shared_triad(w, False)
    for a in range(1 if shared else 0, 2):
        _node_inputs(q_e, t_bar, d_bar, w, a)
        triad(w.x_node, w.p_node, w.t_val[a], w.t_jac[a])
    _twist_inputs(w)
    twist(w.x_tw, w.p_none, w.w_val, w.w_jac)
    _nodal_jacobian(w)


@njit(refcount=False)
def _nodal_hessian(q_e, t_bar, d_bar, w, shared):
    """:func:`_nodal` with the second derivatives ``n_hes`` (the tangent's; ``shared`` as
    there, the previous element's Hessian too)."""
    if shared:
        _shared_triad(w, True)
    for a in range(1 if shared else 0, 2):
        _node_inputs(q_e, t_bar, d_bar, w, a)
        triad_h(w.x_node, w.p_node, w.t_val[a], w.t_jac[a], w.t_hes[a])
    _twist_inputs(w)
    twist_h(w.x_tw, w.p_none, w.w_val, w.w_jac, w.w_hes)
    _nodal_jacobian(w)
    nh = w.n_hes
    for c in range(6):
        for k in range(N_U):
            for m in range(N_U):
                nh[c, k, m] = w.t_hes[0, c, k, m] if (k < 4 and m < 4) else 0.0
    # ∂²Δθ/∂u² = J_tᵀ (∂²Δθ/∂t²) J_t + Σ ∂Δθ/∂t ∂²t/∂u², J_t block diagonal (12 x 8), in
    # two stages: X = (∂²Δθ/∂t²) J_t first
    X = w.w_x
    for i in range(12):
        for b in range(2):
            for m in range(4):
                s = 0.0
                for d in range(6):
                    s += w.w_hes[0, i, 6 * b + d] * w.t_jac[b, d, m]
                X[i, 4 * b + m] = s
    for a in range(2):
        for k in range(4):
            for col in range(N_U):
                s = 0.0
                for c in range(6):
                    s += w.t_jac[a, c, k] * X[6 * a + c, col]
                if col // 4 == a:
                    for c in range(6):
                        s += w.w_jac[0, 6 * a + c] * w.t_hes[a, c, k, col - 4 * a]
                nh[6, 4 * a + k, col] = s


@njit(refcount=False)
def _centerline_rows(q_e, L, xi, w):
    """r′, r″ at ξ into ``x_z`` and their weights ``ab`` (∂z/∂q of the centreline rows: r′ and
    r″ are Σ_m ab[·, m] X_m over the Hermite coordinates X_m = CENTERLINE[3m:3m+3])."""
    _, dS, ddS, _ = hermite_basis(xi, L)
    for m in range(4):
        w.ab[0, m] = dS[m] / L
        w.ab[1, m] = ddS[m] / (L * L)
    for c in range(3):
        a = 0.0
        b = 0.0
        for m in range(4):
            x = q_e[CENTERLINE[3 * m + c]]
            a += w.ab[0, m] * x
            b += w.ab[1, m] * x
        w.x_z[c] = a
        w.x_z[3 + c] = b


@njit(refcount=False)
def _curvature_point(q_e, L, xi, mu, w):
    """(K1, K2, K3) at ξ (after :func:`_nodal`) into ``c_val``, with ``c_jac`` with respect to
    z = (r′, r″, t_0, d2_0, Δθ)."""
    _centerline_rows(q_e, L, xi, w)
    for c in range(3):
        w.x_z[6 + c] = w.t_val[0, c]
        w.x_z[9 + c] = w.t_val[0, 3 + c]
    w.x_z[12] = w.w_val[0]
    w.p_c[0] = xi
    w.p_c[1] = L
    w.p_c[2] = mu
    curvatures(w.x_z, w.p_c, w.c_val, w.c_jac)


@njit(refcount=False)
def _curvature_hessian(w, weights, out):
    """``out = Σ_j weights_j ∂²K_j/∂z²`` at the point of the last :func:`_curvature_point`."""
    for j in range(3):
        w.p_c[3 + j] = weights[j]
    curvatures_wh(w.x_z, w.p_c, out)


@njit(refcount=False)
def _axial_point(q_e, L, xi, mu, w):
    """ε at ξ into ``a_val``, with ``a_jac`` with respect to r′."""
    _centerline_rows(q_e, L, xi, w)
    w.p_a[0] = mu
    axial(w.x_z, w.p_a, w.a_val, w.a_jac)


@njit(refcount=False)
def director_turn_at(q_e, L, t_bar, d_bar, xi, sec_t, sec_y, tw, grad, hes, second):
    """The turn ψ about the tangent of the rod's director ``d2(ξ)`` at the point ξ of an element
    ``q_e`` (ELEMENT_SIZE; nodal bases ``t_bar``, ``d_bar`` (2, 3)), measured from the frame
    carried without spin from a base (``sec_t``, ``sec_y``: ``SR(t̄ → t) ȳ``); its gradient
    ``grad`` (ELEMENT_SIZE) and, with ``second``, its Hessian ``hes`` (ELEMENT_SIZE²) with respect
    to ``q_e``. ``ψ = β + ξΔθ`` (``d2(ξ) = Rot(t, ξΔθ) SR(t0 → t) d2_0`` and both are ⟂ t), β the
    generated ``director_turn`` map of ``(t, t_0, d2_0)``, composed with ``t = r′/|r′|`` and with
    the nodal triads and Δθ (:func:`_nodal_hessian`) by the chain rule, as the curvatures are
    (§2.2). A flexible tube's section turns by ψ with the rod (docs/theory.md §II.9); β is an
    atan2, which the caller keeps far from ±π. ``tw``: :func:`new_turn_work`."""
    w = tw.rod
    if second:
        _nodal_hessian(q_e, t_bar, d_bar, w, False)
    else:
        _nodal(q_e, t_bar, d_bar, w, False)
    _centerline_rows(q_e, L, xi, w)
    x, zq, zg, zh = tw.x, tw.zq, tw.zg, tw.zh
    ell = math.sqrt(w.x_z[0] ** 2 + w.x_z[1] ** 2 + w.x_z[2] ** 2)
    for c in range(3):
        x[c] = w.x_z[c] / ell
        x[3 + c] = w.t_val[0, c]
        x[6 + c] = w.t_val[0, 3 + c]
        tw.p[c] = sec_t[c]
        tw.p[3 + c] = sec_y[c]
    if second:
        director_turn_h(x, tw.p, tw.val, tw.jac, tw.hes)
    else:
        director_turn(x, tw.p, tw.val, tw.jac)
    # to z = (r′, t_0, d2_0, Δθ): ∂t/∂r′ = (I − t tᵀ)/ℓ,
    # ∂²t_c/∂r′_i∂r′_j = (3 t_c t_i t_j − δ_ci t_j − δ_cj t_i − δ_ij t_c)/ℓ²
    for i in range(3):
        s = 0.0
        for c in range(3):
            s += tw.jac[0, c] * ((1.0 if c == i else 0.0) - x[c] * x[i]) / ell
        zg[i] = s
    for i in range(6):
        zg[3 + i] = tw.jac[0, 3 + i]
    zg[9] = xi
    if second:
        for i in range(N_TURN):
            for k in range(N_TURN):
                zh[i, k] = 0.0
        H = tw.hes[0]
        for i in range(3, N_TURN_MAP):       # t_0, d2_0 against themselves
            for k in range(3, N_TURN_MAP):
                zh[i, k] = H[i, k]
        for a in range(3):                   # r′ rows and columns through T = ∂t/∂r′
            for k in range(3, N_TURN_MAP):
                s = 0.0
                for c in range(3):
                    s += ((1.0 if c == a else 0.0) - x[c] * x[a]) / ell * H[c, k]
                zh[a, k] = s
                zh[k, a] = s
            for b in range(3):
                s = 0.0
                for c in range(3):
                    Tac = ((1.0 if c == a else 0.0) - x[c] * x[a]) / ell
                    for d in range(3):
                        s += Tac * H[c, d] * ((1.0 if d == b else 0.0) - x[d] * x[b]) / ell
                zh[a, b] = s
        for i in range(3):                   # + Σ_c ∂β/∂t_c ∂²t_c/∂r′²
            for j in range(3):
                s = 0.0
                for c in range(3):
                    d2t = (3.0 * x[c] * x[i] * x[j] - (x[j] if c == i else 0.0)
                           - (x[i] if c == j else 0.0) - (x[c] if i == j else 0.0))
                    s += tw.jac[0, c] * d2t / (ell * ell)
                zh[i, j] += s
    # ∂z/∂q: r′ from the centreline coordinates, (t_0, d2_0, Δθ) from the nodal inputs u
    for i in range(N_TURN):
        for col in range(ELEMENT_SIZE):
            zq[i, col] = 0.0
    for m in range(4):
        for c in range(3):
            zq[c, CENTERLINE[3 * m + c]] = w.ab[0, m]
    for i in range(N_N):
        for k in range(N_U):
            zq[3 + i, U_COLS[k]] = w.n_jac[i, k]
    for col in range(ELEMENT_SIZE):
        s = 0.0
        for i in range(N_TURN):
            s += zg[i] * zq[i, col]
        grad[col] = s
    psi = tw.val[0] + xi * w.w_val[0]
    if not second:
        return psi
    # ∂²ψ/∂q² = Zᵀ (∂²ψ/∂z²) Z + Σ_i ∂ψ/∂n_i ∂²n_i/∂u² (Z = ∂z/∂q; n = t_0, d2_0, Δθ)
    hz = tw.hz
    for i in range(N_TURN):
        for col in range(ELEMENT_SIZE):
            s = 0.0
            for k in range(N_TURN):
                s += zh[i, k] * zq[k, col]
            hz[i, col] = s
    for a in range(ELEMENT_SIZE):
        for b in range(ELEMENT_SIZE):
            s = 0.0
            for i in range(N_TURN):
                s += zq[i, a] * hz[i, b]
            hes[a, b] = s
    for k in range(N_U):
        for m in range(N_U):
            s = 0.0
            for i in range(N_N):
                s += zg[3 + i] * w.n_hes[i, k, m]
            hes[U_COLS[k], U_COLS[m]] += s
    return psi


@njit(refcount=False)
def _z_dot(ab, n_jac, x, n_z, nodal, out):
    """``out = ∂z/∂q · x`` (the first ``n_z`` inputs z) for an element vector x (14,)."""
    for c in range(3):
        a = 0.0
        b = 0.0
        for m in range(4):
            xm = x[CENTERLINE[3 * m + c]]
            a += ab[0, m] * xm
            b += ab[1, m] * xm
        out[c] = a
        if n_z > 3:
            out[3 + c] = b
    if nodal:
        for c in range(N_N):
            s = 0.0
            for k in range(N_U):
                s += n_jac[c, k] * x[U_COLS[k]]
            out[6 + c] = s


@njit(refcount=False)
def _z_transpose(ab, n_jac, y, n_z, nodal, out):
    """``out += (∂z/∂q)ᵀ y`` for y over the first ``n_z`` inputs z."""
    for m in range(4):
        for c in range(3):
            s = ab[0, m] * y[c]
            if n_z > 3:
                s += ab[1, m] * y[3 + c]
            out[CENTERLINE[3 * m + c]] += s
    if nodal:
        for k in range(N_U):
            s = 0.0
            for c in range(N_N):
                s += n_jac[c, k] * y[6 + c]
            out[U_COLS[k]] += s


@njit(refcount=False)
def _strains_at(q_e, L, t_bar, d_bar, xi, mu, w, out):
    """(ε, K1, K2, K3) at the points ``xi`` of one element into ``out`` (len(xi), 4); μ per point."""
    _nodal(q_e, t_bar, d_bar, w, False)
    for k in range(xi.size):
        _axial_point(q_e, L, xi[k], mu[k], w)
        out[k, 0] = w.a_val[0]
        _curvature_point(q_e, L, xi[k], mu[k], w)
        for j in range(3):
            out[k, 1 + j] = w.c_val[j]


@njit(refcount=False)
def _energies(q_e, props, rest, work, out):
    for e in range(q_e.shape[0]):
        L = props.length[e]
        _nodal(q_e[e], rest.t_bar[e], rest.d_bar[e], work, False)
        total = 0.0
        for k in range(rest.axial_xi.size):
            mu = rest.axial_mu[e, k]
            _axial_point(q_e[e], L, rest.axial_xi[k], mu, work)
            d = work.a_val[0] - rest.eps0[e, 0]
            total += 0.5 * props.EA[e] * d * d * mu * rest.axial_weight[k] * L
        C = (props.GJ[e], props.EI2[e], props.EI3[e])
        for k in range(rest.gauss_xi.size):
            mu = rest.gauss_mu[e, k]
            _curvature_point(q_e[e], L, rest.gauss_xi[k], mu, work)
            dens = 0.0
            for j in range(3):
                d = work.c_val[j] - rest.k0[e, k, j]
                dens += C[j] * d * d
            total += 0.5 * dens * mu * rest.gauss_weight[k] * L
        out[e] = total


def strain_energy(q_e: np.ndarray, props: RodProperties, rest: RodRest) -> np.ndarray:
    """Strain energy of every element ``q_e (n_elem, 14)`` (module docstring); (n_elem,)."""
    q = np.ascontiguousarray(q_e, dtype=float)
    out = np.empty(q.shape[0])
    _energies(q, props, rest, new_work(), out)
    return out


def strain_measures(q_e: np.ndarray, t_bar: np.ndarray, d_bar: np.ndarray, length: np.ndarray,
                    xi: np.ndarray, mu: np.ndarray) -> np.ndarray:
    """(ε, K1, K2, K3) of every element ``q_e (n_elem, 14)`` with nodal bases ``t_bar, d_bar
    (n_elem, 2, 3)`` at the points ``xi (m,)`` with the reference metric ``mu (n_elem, m)``:
    (n_elem, m, 4)."""
    q = np.ascontiguousarray(q_e, dtype=float)
    xi = np.ascontiguousarray(xi, dtype=float)
    out = np.empty((q.shape[0], xi.size, N_STRAIN))
    w = new_work()
    for e in range(q.shape[0]):
        _strains_at(q[e], float(length[e]), t_bar[e], d_bar[e], xi,
                    np.ascontiguousarray(mu[e], dtype=float), w, out[e])
    return out


# ---------------------------------------------------------------------------------------------
# internal force and its exact derivatives (docs/theory.md §I.2.3)
@njit(refcount=False)
def _point_force(val, jac, n_z, coef, ref, W, beta, ve, w, nodal, force):
    """Add one quadrature point's force of the strains ``val`` (with their derivatives ``jac``
    with respect to the first ``n_z`` inputs z; ∂z/∂q is sparse: the Hermite weights ``ab`` on
    the centreline and, with ``nodal``, ``n_jac`` on the nodal inputs u):

        σ_j = C_j (e_j − e_j⁰ + β ė_j),   Q += (∂z/∂q)ᵀ y,   y = W Σ_j σ_j ∂e_j/∂z.

    The centreline rows are added here; the nodal part of y, through the same ∂n/∂u at every
    point, is summed into ``g_n`` for :func:`_nodal_force` to add once per element. Leaves
    σ in ``sig`` and, with damping, ∂z/∂q q̇ in ``z_v`` for :func:`_point_tangent`."""
    ns = val.size
    rated = beta != 0.0
    # the work arrays as locals (a field of the work tuple read in a loop costs a reference
    # count update each time)
    ab = w.ab
    sig = w.sig
    yz = w.y_z
    zv = w.z_v
    if rated:
        _z_dot(ab, w.n_jac, ve, n_z, nodal, zv)
    for a in range(n_z):
        yz[a] = 0.0
    for j in range(ns):
        rate = 0.0
        if rated:
            for a in range(n_z):
                rate += jac[j, a] * zv[a]
        sig[j] = coef[j] * (val[j] - ref[j] + beta * rate)
        f = W * sig[j]
        for a in range(n_z):
            yz[a] += f * jac[j, a]
    if n_z > 3:
        for m in range(4):
            for c in range(3):
                force[CENTERLINE[3 * m + c]] += ab[0, m] * yz[c] + ab[1, m] * yz[3 + c]
    else:
        for m in range(4):
            for c in range(3):
                force[CENTERLINE[3 * m + c]] += ab[0, m] * yz[c]
    if nodal:
        gn = w.g_n
        for c in range(N_N):
            gn[c] += yz[6 + c]


@njit(refcount=False)
def _point_tangent(jac, hes, h_sig, n_z, coef, W, beta, w, nodal, want_c, stiff, damp):
    """Add one quadrature point's tangents (after :func:`_point_force`, with its ``sig`` and
    ``z_v``; ``hes`` the strains' Hessians with respect to z and ``h_sig = sig``, or, without
    damping, their sum weighted by σ, ``hes[0] = Σ_j σ_j ∂²e_j/∂z²`` and ``h_sig = [1]``):

        ∂Q/∂q += (∂z/∂q)ᵀ A ∂z/∂q + β Σ_j C_j ∂e_j/∂q (∂²e_j/∂q² q̇)ᵀ,
        A = W Σ_j (σ_j ∂²e_j/∂z² + C_j ∂e_j/∂z ∂e_j/∂zᵀ),
        ∂Q/∂q̇ += W β Σ_j C_j ∂e_j/∂q ∂e_j/∂qᵀ   (with ``want_c``).

    The centreline-centreline block is summed into ``p_cc`` (:func:`_centerline_tangent` adds
    it once per element); with ``nodal`` the centreline-nodal and nodal-nodal blocks of A into
    ``p_cn``, ``p_nn`` for :func:`_nodal_tangent`."""
    ne = ELEMENT_SIZE
    ns = jac.shape[0]
    nh = h_sig.size
    ab = w.ab
    nj = w.n_jac
    A = w.s_zz
    nc = 2 if n_z > 3 else 1
    for a in range(n_z):
        for b in range(a, n_z):
            s = 0.0
            for j in range(nh):
                s += h_sig[j] * hes[j, a, b]
            for j in range(ns):
                s += coef[j] * jac[j, a] * jac[j, b]
            A[a, b] = W * s
            A[b, a] = W * s
    # centreline-centreline block, Σ_u,u' ab[u, m] A[3u + c, 3u' + c'] ab[u', m'] over the
    # (r′, r″) weights, into ``p_cc`` (scattered once per element): the pairs c ≤ c' only
    # (A is symmetric), each through T = A_cc' ab first
    pcc = w.p_cc
    for c in range(3):
        for cc in range(c, 3):
            for mm in range(4):
                t0 = A[c, cc] * ab[0, mm]
                t1 = 0.0
                if nc == 2:
                    t0 += A[c, 3 + cc] * ab[1, mm]
                    t1 = A[3 + c, cc] * ab[0, mm] + A[3 + c, 3 + cc] * ab[1, mm]
                col = 3 * mm + cc
                for m in range(4):
                    s = ab[0, m] * t0 + ab[1, m] * t1
                    pcc[3 * m + c, col] += s
                    if cc != c:
                        pcc[col, 3 * m + c] += s
    if nodal:
        pcn = w.p_cn
        pnn = w.p_nn
        for m in range(4):
            for c in range(3):
                for k in range(N_N):
                    pcn[3 * m + c, k] += ab[0, m] * A[c, 6 + k] + ab[1, m] * A[3 + c, 6 + k]
        for c in range(N_N):
            for k in range(N_N):
                pnn[c, k] += A[6 + c, 6 + k]
    if beta == 0.0:
        return
    eq = w.e_q
    zv = w.z_v
    for j in range(ns):
        for i in range(ne):
            eq[j, i] = 0.0
        _z_transpose(ab, nj, jac[j], n_z, nodal, eq[j])
    hz = w.hz
    hq = w.h_q
    nhv = w.n_hv
    for j in range(ns):
        for a in range(n_z):
            s = 0.0
            for b in range(n_z):
                s += hes[j, a, b] * zv[b]
            hz[a] = s
        for i in range(ne):
            hq[j, i] = 0.0
        _z_transpose(ab, nj, hz, n_z, nodal, hq[j])
        if nodal:
            for k in range(N_U):
                s = 0.0
                for c in range(N_N):
                    s += jac[j, 6 + c] * nhv[c, k]
                hq[j, U_COLS[k]] += s
        f = W * beta * coef[j]
        for i in range(ne):
            for m in range(ne):
                stiff[i, m] += f * eq[j, i] * hq[j, m]
    if want_c:
        for j in range(ns):
            f = W * beta * coef[j]
            for i in range(ne):
                for m in range(ne):
                    damp[i, m] += f * eq[j, i] * eq[j, m]


@njit(refcount=False)
def _nodal_force(w, force):
    """``Q_u += (∂n/∂u)ᵀ g_n``: the nodal part of an element's force (:func:`_point_force`)."""
    nj = w.n_jac
    gn = w.g_n
    for k in range(N_U):
        s = 0.0
        for c in range(N_N):
            s += nj[c, k] * gn[c]
        force[U_COLS[k]] += s


@njit(refcount=False)
def _centerline_tangent(w, stiff):
    """The centreline-centreline block of an element's tangent, summed over its points in
    ``p_cc`` (:func:`_point_tangent`), into the element matrix."""
    pcc = w.p_cc
    for i in range(CENTERLINE.size):
        row = CENTERLINE[i]
        for j in range(CENTERLINE.size):
            stiff[row, CENTERLINE[j]] += pcc[i, j]


@njit(refcount=False)
def _nodal_tangent(w, stiff):
    """The nodal blocks of an element's tangent (:func:`_point_tangent`) through ∂n/∂u: the
    centreline-nodal ``p_cn ∂n/∂u`` (both ways) and ``(∂n/∂u)ᵀ p_nn ∂n/∂u + Σ_c g_n,c
    ∂²n_c/∂u²``."""
    nj = w.n_jac
    gn = w.g_n
    pcn = w.p_cn
    pnn = w.p_nn
    nh = w.n_hes
    tmp = w.s_zn
    for i in range(CENTERLINE.size):
        row = CENTERLINE[i]
        for k in range(N_U):
            s = 0.0
            for c in range(N_N):
                s += pcn[i, c] * nj[c, k]
            stiff[row, U_COLS[k]] += s
            stiff[U_COLS[k], row] += s
    for c in range(N_N):
        for k in range(N_U):
            s = 0.0
            for d in range(N_N):
                s += pnn[c, d] * nj[d, k]
            tmp[c, k] = s
    for k in range(N_U):
        for kk in range(N_U):
            s = 0.0
            for c in range(N_N):
                s += nj[c, k] * tmp[c, kk] + gn[c] * nh[c, k, kk]
            stiff[U_COLS[k], U_COLS[kk]] += s


@njit(refcount=False)
def _element_coefficients(props, e, w):
    """The section stiffnesses C_j of element ``e`` into the work arrays."""
    w.a_coef[0] = props.EA[e]
    w.c_coef[0] = props.GJ[e]
    w.c_coef[1] = props.EI2[e]
    w.c_coef[2] = props.EI3[e]


@njit(refcount=False)
def _element_forces(q, v, props, rest, w, e, force):
    """Element ``e``'s internal force into ``force`` (zeroed here); :func:`_rod_tangents` makes
    the same pass with the tangents."""
    L = props.length[e]
    beta = props.damping[e]
    qe = q[e]
    ve = v[e]
    for i in range(ELEMENT_SIZE):
        force[i] = 0.0
    _element_coefficients(props, e, w)
    for k in range(rest.axial_xi.size):
        mu = rest.axial_mu[e, k]
        _axial_point(qe, L, rest.axial_xi[k], mu, w)
        _point_force(w.a_val, w.a_jac, 3, w.a_coef, rest.eps0[e], rest.axial_weight[k] * mu * L,
                     beta, ve, w, False, force)
    # a node shared with the previous element has the same inputs: its triad is reused
    _nodal(qe, rest.t_bar[e], rest.d_bar[e], w, e > 0 and _same_node(q, rest, e))
    for c in range(N_N):
        w.g_n[c] = 0.0
    for k in range(rest.gauss_xi.size):
        mu = rest.gauss_mu[e, k]
        _curvature_point(qe, L, rest.gauss_xi[k], mu, w)
        _point_force(w.c_val, w.c_jac, N_Z, w.c_coef, rest.k0[e, k],
                     rest.gauss_weight[k] * mu * L, beta, ve, w, True, force)
    _nodal_force(w, force)


@njit(refcount=False)
def _rod_forces(q, v, props, rest, w, force):
    """Q_int = ∂U/∂q + damping of every element (:func:`_point_force`; docs/theory.md §I.2.2,
    the axial strain at the Lobatto points, the curvatures at the Gauss points, W = w μ L)."""
    for e in range(q.shape[0]):
        _element_forces(q, v, props, rest, w, e, force[e])


@njit(refcount=False)
def _rod_tangents(q, v, props, rest, w, want_c, force, stiff, damp):
    """Q_int, ∂Q_int/∂q and (with ``want_c``) ∂Q_int/∂q̇ of every element, by the chain rule
    through the generated maps: e = e(z(q)), z = (r′, r″, n(u)),

        ∂e/∂q = ∂e/∂z · ∂z/∂q,
        ∂²e/∂q² = (∂z/∂q)ᵀ ∂²e/∂z² (∂z/∂q) + Σ_c ∂e/∂n_c ∂²n_c/∂u²   (r′, r″ are linear in q)."""
    ne = ELEMENT_SIZE
    for e in range(q.shape[0]):
        L = props.length[e]
        beta = props.damping[e]
        qe = q[e]
        ve = v[e]
        fe = force[e]
        ke = stiff[e]
        ce = damp[e if want_c else 0]
        for i in range(ne):
            for j in range(ne):
                ke[i, j] = 0.0
        if want_c:
            for i in range(ne):
                for j in range(ne):
                    ce[i, j] = 0.0
        for i in range(ne):
            fe[i] = 0.0
        _element_coefficients(props, e, w)
        for i in range(CENTERLINE.size):
            for j in range(CENTERLINE.size):
                w.p_cc[i, j] = 0.0
        for k in range(rest.axial_xi.size):
            mu = rest.axial_mu[e, k]
            W = rest.axial_weight[k] * mu * L
            _axial_point(qe, L, rest.axial_xi[k], mu, w)
            axial_h(w.x_z, w.p_a, w.a_val, w.a_jac, w.a_hes)
            _point_force(w.a_val, w.a_jac, 3, w.a_coef, rest.eps0[e], W, beta, ve, w, False, fe)
            _point_tangent(w.a_jac, w.a_hes, w.sig[:1], 3, w.a_coef, W, beta, w, False, want_c,
                           ke, ce)
        # a node shared with the previous element has the same inputs: its triad is reused
        _nodal_hessian(qe, rest.t_bar[e], rest.d_bar[e], w, e > 0 and _same_node(q, rest, e))
        for c in range(N_N):
            w.g_n[c] = 0.0
            for k in range(N_N):
                w.p_nn[c, k] = 0.0
            for i in range(CENTERLINE.size):
                w.p_cn[i, c] = 0.0
            if beta != 0.0:
                for k in range(N_U):
                    s = 0.0
                    for m in range(N_U):
                        s += w.n_hes[c, k, m] * ve[U_COLS[m]]
                    w.n_hv[c, k] = s
        for k in range(rest.gauss_xi.size):
            mu = rest.gauss_mu[e, k]
            W = rest.gauss_weight[k] * mu * L
            _curvature_point(qe, L, rest.gauss_xi[k], mu, w)
            _point_force(w.c_val, w.c_jac, N_Z, w.c_coef, rest.k0[e, k], W, beta, ve, w, True, fe)
            if beta != 0.0:      # the rate terms need each strain's Hessian
                for j in range(3):
                    _curvature_hessian(w, w.unit[j], w.c_hes[j])
                _point_tangent(w.c_jac, w.c_hes, w.sig, N_Z, w.c_coef, W, beta, w, True, want_c,
                               ke, ce)
            else:
                _curvature_hessian(w, w.sig, w.h_w[0])
                _point_tangent(w.c_jac, w.h_w, w.one, N_Z, w.c_coef, W, beta, w, True, want_c,
                               ke, ce)
        _nodal_force(w, fe)
        _centerline_tangent(w, ke)
        _nodal_tangent(w, ke)


@njit(refcount=False)
def _same_node(q, rest, e):
    """Whether node 0 of element ``e`` has exactly the inputs (g, φ, t̄, D̄) of node 1 of
    element ``e − 1`` (a shared node: its triad is the same)."""
    for i in range(SLOPE, NODE_SIZE):
        if q[e, i] != q[e - 1, NODE_SIZE + i]:
            return False
    for c in range(3):
        if rest.t_bar[e, 0, c] != rest.t_bar[e - 1, 1, c] or rest.d_bar[e, 0, c] != rest.d_bar[e - 1, 1, c]:
            return False
    return True


_NO_MATRIX = np.zeros((1, ELEMENT_SIZE, ELEMENT_SIZE))


def internal_forces(q_e: np.ndarray, v_e: np.ndarray, props: RodProperties, rest: RodRest,
                    force_out: np.ndarray, stiffness_out: np.ndarray | None = None,
                    damping_out: np.ndarray | None = None) -> None:
    """``Q_int`` (n_elem, 14) and, when given, ``∂Q_int/∂q`` and ``∂Q_int/∂q̇`` (n_elem, 14, 14)
    into the caller's arrays (:func:`_rod_forces`, :func:`_rod_tangents`; without a tangent,
    no damping matrix)."""
    q = np.ascontiguousarray(q_e, dtype=float)
    v = np.ascontiguousarray(v_e, dtype=float)
    if stiffness_out is None:
        _rod_forces(q, v, props, rest, new_work(), force_out)
        return
    want_c = damping_out is not None
    _rod_tangents(q, v, props, rest, new_work(), want_c, force_out, stiffness_out,
                  damping_out if want_c else _NO_MATRIX)


# ---------------------------------------------------------------------------------------------
# reference
def base_frames(slopes: np.ndarray, connectivity: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Nodal bases ``(t̄, D̄)`` (n_nodes, 3) of a reference with nodal slopes ``(n_nodes, 3)``:
    D̄ by parallel transport (smallest rotations) along the elements ``connectivity (n_elem, 2)``
    in order (§4.6); a chain starts from the global axis least aligned with its first tangent.

    On a closed loop the transport does not return to its start: the element that closes the
    loop would carry the whole holonomy α ∈ (−π, π] as its reference twist Δθ⁰. The bases of
    the loop's m nodes are therefore turned about their tangents by k α/m (k = 0 … m − 1 along
    the loop), which gives every element of the loop the same reference twist α/m. The strain
    measures K − K⁰ do not depend on the bases, but the relative twist Δθ is an angle in
    (−π, π]: a closing element with Δθ⁰ near ±π would wrap after a small deformation and
    its energy would jump."""
    g = np.asarray(slopes, dtype=float)
    t = g / np.linalg.norm(g, axis=1)[:, None]
    d = np.full_like(t, np.nan)
    parent = np.full(t.shape[0], -1, dtype=np.int64)     # the node a node's base came from
    w = new_work()
    val = w.t_val[0]
    for n0, n1 in np.asarray(connectivity, dtype=np.int64):
        if np.isnan(d[n0, 0]):
            helper = np.eye(3)[int(np.argmin(np.abs(t[n0])))]
            d0 = helper - np.dot(helper, t[n0]) * t[n0]
            d[n0] = d0 / np.linalg.norm(d0)
        if np.isnan(d[n1, 0]):
            # d2 of node n1 with φ = 0 and base (t_n0, d_n0): SR(t_n0 → t_n1) d_n0
            triad(np.append(t[n1], 0.0), np.concatenate([t[n0], d[n0]]), val, w.t_jac[0])
            d1 = val[3:] - np.dot(val[3:], t[n1]) * t[n1]
            d[n1] = d1 / np.linalg.norm(d1)
            parent[n1] = n0
        else:
            _spread_holonomy(t, d, parent, n0, n1, w)
    return t, d


def _spread_holonomy(t: np.ndarray, d: np.ndarray, parent: np.ndarray, last: int, first: int,
                     w: RodWork) -> None:
    """Turn the bases of the loop closed by the element ``last → first`` so that its reference
    twist is shared by all the loop's elements (:func:`base_frames`); the loop is the path of
    the transport from ``first`` to ``last`` (nothing is done if ``first`` is not on it).
    Turning D̄ of a node b by β_b about t̄_b adds β_b − β_a to the relative twist of an
    element a → b: with β = k α/m at the k-th node of the loop every element gets α/m."""
    path = [last]
    while path[-1] != first and parent[path[-1]] >= 0:
        path.append(int(parent[path[-1]]))
    if path[-1] != first:
        return
    loop = np.array(path[::-1], dtype=np.int64)           # first, …, last
    for a, node in enumerate((last, first)):
        w.x_tw[6 * a:6 * a + 3] = t[node]
        w.x_tw[6 * a + 3:6 * a + 6] = d[node]
    twist(w.x_tw, w.p_none, w.w_val, w.w_jac)
    step = w.w_val[0] / loop.size
    for k, node in enumerate(loop):
        # Rot(t, β) D̄ is the triad map's director with φ = β on the base (t, D̄) itself
        triad(np.append(t[node], k * step), np.concatenate([t[node], d[node]]), w.t_val[0],
              w.t_jac[0])
        d[node] = w.t_val[0, 3:]


def _rule(kind: str) -> tuple[np.ndarray, np.ndarray]:
    if kind == "lobatto3":
        return np.array([0.0, 0.5, 1.0]), np.array([1.0, 4.0, 1.0]) / 6.0
    x, wts = np.polynomial.legendre.leggauss(N_GAUSS)
    return 0.5 * (x + 1.0), 0.5 * wts


def rest_state(q_ref_e: np.ndarray, props: RodProperties, t_bar: np.ndarray,
               d_bar: np.ndarray) -> RodRest:
    """The reference measures at the quadrature points of every element (with φ = 0 there):
    μ = |r′_ref| and K⁰ = (K1⁰, K2⁰, K3⁰) at the Gauss points, μ at the Lobatto points."""
    q = np.array(q_ref_e, dtype=float).reshape(-1, ELEMENT_SIZE)
    q[:, TWIST] = 0.0
    q[:, NODE_SIZE + TWIST] = 0.0
    ne = q.shape[0]
    L = np.asarray(props.length, dtype=float)
    t_bar = np.ascontiguousarray(t_bar, dtype=float).reshape(ne, 2, 3)
    d_bar = np.ascontiguousarray(d_bar, dtype=float).reshape(ne, 2, 3)
    if np.any(L <= 0.0):
        raise ValueError("rest_state: element lengths must be positive")
    xg, wg = _rule("gauss")
    xa, wa = _rule("lobatto3")
    # with μ = 1 the measures are |r′| − 1 and μ K_j: divide by the true μ
    raw = strain_measures(q, t_bar, d_bar, L, xg, np.ones((ne, xg.size)))
    mu_g = raw[:, :, 0] + 1.0
    k0 = raw[:, :, 1:] / mu_g[:, :, None]
    mu_a = strain_measures(q, t_bar, d_bar, L, xa, np.ones((ne, xa.size)))[:, :, 0] + 1.0
    C = np.column_stack([np.asarray(getattr(props, f), dtype=float).reshape(-1)
                         for f in ("EA", "GJ", "EI2", "EI3")]).reshape(ne, N_STRAIN)
    c = np.ascontiguousarray
    return RodRest(t_bar.copy(), d_bar.copy(), t_bar.copy(), d_bar.copy(), xg, wg, c(mu_g), c(k0),
                   xa, wa, c(mu_a),
                   c(np.asarray(props.reference_axial_strain, dtype=float).reshape(ne, 1)),
                   L.copy(), q, c(C))


@njit
def node_director(q_node, t_bar, d_bar, val, jac, hes, hessian):
    """The director d2 (3,) of a node ``q_node = [r, g, φ]`` on its base (t̄, D̄) into ``val``,
    its derivatives with respect to (g, φ) into ``jac`` (3, 4) and, with ``hessian``, ``hes``
    (3, 4, 4) (what a joint holding the node's section reads, §2.3)."""
    x = np.empty(4)
    p = np.empty(6)
    v6 = np.empty(6)
    j6 = np.zeros((6, 4))
    for c in range(3):
        x[c] = q_node[3 + c]
        p[c] = t_bar[c]
        p[3 + c] = d_bar[c]
    x[3] = q_node[TWIST]
    if hessian:
        h6 = np.zeros((6, 4, 4))
        triad_h(x, p, v6, j6, h6)
        for c in range(3):
            for a in range(4):
                for b in range(4):
                    hes[c, a, b] = h6[3 + c, a, b]
    else:
        triad(x, p, v6, j6)
    for c in range(3):
        val[c] = v6[3 + c]
        for a in range(4):
            jac[c, a] = j6[3 + c, a]


def node_base(element_dofs: np.ndarray, q_ref: np.ndarray, node: int) -> tuple[np.ndarray, np.ndarray]:
    """The base (t̄, D̄) of node ``node`` of a beam with element coordinates ``element_dofs``
    (n_elem, 14): the one :func:`pack_rods` gives the elements (transport along the beam)."""
    t_bar, d_bar = nodal_bases(element_dofs, q_ref)
    e, a = (node, 0) if node < t_bar.shape[0] else (node - 1, 1)
    return t_bar[e, a].copy(), d_bar[e, a].copy()


def nodal_triads(slopes: np.ndarray, twist_angles: np.ndarray, t_bar: np.ndarray,
                 d_bar: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(t_i, d2_i)`` (n, 3) of nodes with slopes ``g (n, 3)`` and twists ``φ (n,)`` on their
    bases (§2.1)."""
    n = len(slopes)
    t = np.empty((n, 3))
    d2 = np.empty((n, 3))
    w = new_work()
    for i in range(n):
        triad(np.append(np.asarray(slopes[i], float), float(twist_angles[i])),
              np.concatenate([t_bar[i], d_bar[i]]), w.t_val[0], w.t_jac[0])
        t[i] = w.t_val[0, :3]
        d2[i] = w.t_val[0, 3:]
    return t, d2


# ---------------------------------------------------------------------------------------------
# mass and external loads (constant; the cable's on the centreline coordinates, §2.3)
def _cable_view(props: RodProperties) -> cable.CableProperties:
    """The rod's centreline as a cable section (for the cable's mass and load integrals)."""
    z = np.zeros_like(np.asarray(props.length, dtype=float))
    return cable.CableProperties(props.length, props.EA, props.EI3, props.mass_per_length, z, z,
                                 props.reference_axial_strain)


def _on_centerline(Q: np.ndarray) -> np.ndarray:
    out = np.zeros((Q.shape[0], ELEMENT_SIZE))
    out[:, CENTERLINE] = Q
    return out


def mass_matrix(props: RodProperties) -> np.ndarray:
    """Constant mass (n_elem, 14, 14): the cable's on (r, g) and ``ρJ_p L/6 [[2, 1], [1, 2]]``
    on the twists (docs/theory.md §I.2.3)."""
    L = np.asarray(props.length, dtype=float)
    M = np.zeros((L.shape[0], ELEMENT_SIZE, ELEMENT_SIZE))
    M[:, CENTERLINE[:, None], CENTERLINE[None, :]] = cable.mass_matrix(_cable_view(props))
    tw = np.array([TWIST, NODE_SIZE + TWIST])
    M[:, tw[:, None], tw[None, :]] = ((np.asarray(props.twist_inertia, float) * L / 6.0)[:, None, None]
                                      * np.array([[2.0, 1.0], [1.0, 2.0]]))
    return M


def gravity_force(props: RodProperties, g: np.ndarray) -> np.ndarray:
    """The cable's gravity on the centreline, none on φ; (n_elem, 14)."""
    return _on_centerline(cable.gravity_force(_cable_view(props), g))


def distributed_force(props: RodProperties, f: np.ndarray) -> np.ndarray:
    """The cable's constant load per length on the centreline; (n_elem, 14)."""
    return _on_centerline(cable.distributed_force(_cable_view(props), f))


def point_force_vector(xi: np.ndarray, length: np.ndarray, force: np.ndarray) -> np.ndarray:
    """The cable's point force ``S(ξ)ᵀ F`` on the centreline; (n, 14)."""
    return _on_centerline(cable.point_force_vector(xi, length, force))


def reference_nodal_coordinates(points: np.ndarray, tangents: np.ndarray) -> np.ndarray:
    """Nodal coordinates (n_nodes, 7) of the stress-free reference: ``[r, r′, φ = 0]``."""
    return np.hstack([points, tangents, np.zeros((len(points), 1))])


# ---------------------------------------------------------------------------------------------
# the element group of the assembler (flexmbs.elements.group)
class RodPart(NamedTuple):
    """One group of rod elements, packed for the kernels."""

    dofs: np.ndarray                 # (n_elem, 14) global coordinates
    pos: np.ndarray                  # (n_elem, 196) matrix positions of the element blocks
    props: RodProperties
    rest: RodRest
    mass: np.ndarray                 # (n_elem, 14, 14)
    work: RodWork
    qe: np.ndarray                   # work (n_elem, 14): q, q̇ of the elements, Q_int
    ve: np.ndarray
    force: np.ndarray
    stiff: np.ndarray                # work (n_elem, 14, 14): ∂Q_int/∂q, ∂Q_int/∂q̇
    damp: np.ndarray
    empty: np.ndarray                # (1, 14, 14): a dummy tangent in the residual
    limits: np.ndarray               # (2,) cosines t̄·t: re-base below [0], fail a step below [1]


def nodal_bases(element_dofs: np.ndarray, q_ref: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(t̄, D̄)`` (n_elem, 2, 3) of both nodes of every element, by :func:`base_frames` along the
    elements in order (a node is known by its twist coordinate)."""
    D = np.asarray(element_dofs, dtype=np.int64)
    keys = D[:, [TWIST, NODE_SIZE + TWIST]]
    nodes, conn = np.unique(keys, return_inverse=True)
    conn = conn.reshape(-1, 2)
    slopes = np.empty((nodes.size, 3))
    slope = np.asarray(LAYOUT.slope)
    slopes[conn[:, 0]] = q_ref[D[:, slope]]
    slopes[conn[:, 1]] = q_ref[D[:, NODE_SIZE + slope]]
    t, d = base_frames(slopes, conn)
    return np.ascontiguousarray(t[conn]), np.ascontiguousarray(d[conn])


def pack_rods(element_dofs: np.ndarray, props: RodProperties, options: object, q_ref: np.ndarray,
              positions: np.ndarray) -> RodPart:
    """``element_dofs`` (n_elem, 14), the section resultants per element, the reference
    coordinates (global vector) and the matrix positions (n_elem, 196) of the element blocks."""
    D = np.ascontiguousarray(element_dofs, dtype=np.int64)
    ne = D.shape[0]
    t_bar, d_bar = nodal_bases(D, q_ref) if ne else (np.zeros((0, 2, 3)), np.zeros((0, 2, 3)))
    rest = rest_state(np.ascontiguousarray(q_ref[D]), props, t_bar, d_bar)
    n = ELEMENT_SIZE
    return RodPart(
        dofs=D,
        pos=np.ascontiguousarray(positions, dtype=np.int64).reshape(ne, n * n),
        props=props,
        rest=rest,
        mass=np.ascontiguousarray(mass_matrix(props)),
        work=new_work(),
        qe=np.zeros((ne, n)),
        ve=np.zeros((ne, n)),
        force=np.zeros((ne, n)),
        stiff=np.zeros((ne, n, n)),
        damp=np.zeros((ne, n, n)),
        empty=np.zeros((1, n, n)),
        limits=np.array([REBASE_LIMIT, TURN_LIMIT]))


@njit(refcount=False)
def rod_residual(rp, q, v, qdd, mode, r):
    """``r_q += Q_int(q, q̇) (+ M q̈ and the sections' spin inertia)`` of the rod elements;
    returns the force scale."""
    gather_states(rp, q, v, mode)
    _rod_forces(rp.qe, rp.ve, rp.props, rp.rest, rp.work, rp.force)
    scale = add_residual(rp, qdd, mode, r)
    if mode[WITH_INERTIA] != 0.0:
        scale = max(scale, _spin_inertia(rp, q, v, qdd, r, r, 0.0, 0.0, 0.0, FLAG[0]))
    return scale


@njit(refcount=False)
def rod_jacobian(rp, q, v, qdd, mode, cM, cC, cK, data):
    """``cK ∂Q/∂q + cC ∂Q/∂q̇ + cM ∂Q/∂q̈`` of the internal and inertial forces into ``data``;
    returns the stiffness scale."""
    gather_states(rp, q, v, mode)
    _rod_tangents(rp.qe, rp.ve, rp.props, rp.rest, rp.work, FLAG[1], rp.force, rp.stiff, rp.damp)
    kscale = add_matrix(rp, cM, cC, cK, data)
    if mode[WITH_INERTIA] != 0.0:
        _spin_inertia(rp, q, v, qdd, data, data, cM, cC, cK, FLAG[1])
    return kscale


@njit(refcount=False)
def _spin_inertia(rp, q, v, qdd, r, data, cM, cC, cK, matrix):
    """The sections' spin inertia beyond the constant ``M_φ φ̈`` (§2.3, §2.4): the twist
    kinetic energy ``½ ωᵀ M_φ ω`` per element counts the spin ``ω_a = φ̇_a + w_a`` of each
    node's section (``w_a = b_a·ġ_a`` the spin of its chart, generated ``spin`` map), so the
    motion does not depend on the charts and a re-basing keeps it. Lagrange's equations add

        ΔQ_φa = (M_φ ẇ)_a,   ΔQ_ga = (M_φ ω̇)_a b_a + (M_φ ω)_a c_a,   ẇ = b·g̈ + s,

    into ``r`` (returns the largest term), or with ``matrix`` their exact derivatives
    ``cK ∂/∂q + cC ∂/∂q̇ + cM ∂/∂q̈`` into ``data``."""
    w = rp.work
    y = w.s_y
    Y = w.s_jac
    D = w.s_d
    o_ = w.s_o
    m_ = w.s_m
    scale = 0.0
    n = ELEMENT_SIZE
    previous = False       # y[1] (and Y[1]) hold node 1 of element e − 1
    for e in range(rp.dofs.shape[0]):
        mp = rp.props.twist_inertia[e] * rp.props.length[e] / 6.0
        if mp == 0.0:
            previous = False
            continue
        for a in range(2):
            o = a * NODE_SIZE + SLOPE
            if a == 0 and previous and _same_spin_node(rp, e):
                for i in range(N_SPIN):
                    y[0, i] = y[1, i]
                    if matrix:
                        for c in range(6):
                            Y[0, i, c] = Y[1, i, c]
            else:
                for c in range(3):
                    w.s_x[c] = q[rp.dofs[e, o + c]]
                    w.s_x[3 + c] = v[rp.dofs[e, o + c]]
                    w.s_p[c] = rp.rest.t_bar[e, a, c]
                if matrix:
                    spin(w.s_x, w.s_p, y[a], Y[a])
                else:
                    spin_value(w.s_x, w.s_p, y[a])
            k = rp.dofs[e, a * NODE_SIZE + TWIST]
            wd = y[a, 4]
            for c in range(3):
                wd += y[a, 1 + c] * qdd[rp.dofs[e, o + c]]
            o_[0, a] = v[k] + y[a, 0]
            o_[1, a] = qdd[k] + wd
            o_[2, a] = wd
        previous = True
        for j in range(3):
            for a in range(2):
                m_[j, a] = mp * (2.0 * o_[j, a] + o_[j, 1 - a])
        if not matrix:
            for a in range(2):
                o = a * NODE_SIZE + SLOPE
                f = m_[2, a]
                r[rp.dofs[e, a * NODE_SIZE + TWIST]] += f
                scale = max(scale, abs(f))
                for c in range(3):
                    f = m_[1, a] * y[a, 1 + c] + m_[0, a] * y[a, 5 + c]
                    r[rp.dofs[e, o + c]] += f
                    scale = max(scale, abs(f))
            continue
        for b in range(2):
            o = b * NODE_SIZE + SLOPE
            for j in range(3):
                D[b, 0, j] = cK * Y[b, 0, j] + cC * Y[b, 0, 3 + j]
                dk = Y[b, 4, j]
                dc = Y[b, 4, 3 + j]
                for i in range(3):
                    gi = qdd[rp.dofs[e, o + i]]
                    dk += gi * Y[b, 1 + i, j]
                    dc += gi * Y[b, 1 + i, 3 + j]
                D[b, 1, j] = cK * dk + cC * dc + cM * y[b, 1 + j]
        for a in range(2):
            ra = a * NODE_SIZE
            for b in range(2):
                cb = b * NODE_SIZE
                mab = mp * (2.0 if a == b else 1.0)
                for j in range(3):
                    col = cb + SLOPE + j
                    data[rp.pos[e, n * (ra + TWIST) + col]] += mab * D[b, 1, j]
                    for i in range(3):
                        val = mab * (y[a, 1 + i] * D[b, 1, j] + y[a, 5 + i] * D[b, 0, j])
                        if a == b:
                            val += (m_[1, a] * (cK * Y[a, 1 + i, j] + cC * Y[a, 1 + i, 3 + j])
                                    + m_[0, a] * (cK * Y[a, 5 + i, j] + cC * Y[a, 5 + i, 3 + j]))
                        data[rp.pos[e, n * (ra + SLOPE + i) + col]] += val
                for i in range(3):
                    data[rp.pos[e, n * (ra + SLOPE + i) + cb + TWIST]] += mab * (
                        y[a, 1 + i] * cM + y[a, 5 + i] * cC)
    return scale


@njit(refcount=False)
def _same_spin_node(rp, e):
    """Whether node 0 of element ``e`` is node 1 of element ``e − 1`` with the same base tangent
    (then its spin map is the same)."""
    for i in range(SLOPE, SLOPE + 3):
        if rp.dofs[e, i] != rp.dofs[e - 1, NODE_SIZE + i]:
            return False
    for c in range(3):  # noqa: SIM110 - a loop, not all(generator), in compiled code
        if rp.rest.t_bar[e, 0, c] != rp.rest.t_bar[e - 1, 1, c]:
            return False
    return True


@njit(refcount=False)
def rod_post_step(rp, q, error):
    """After a converged step: every node's tangent within :data:`TURN_LIMIT` of its base
    tangent (``rp.limits[1]``), else :data:`ERR_NODE_TURNED` with ``error[2]`` = 2 × element +
    node slot."""
    for e in range(rp.dofs.shape[0]):
        for a in range(2):
            if _base_cosine(rp, q, e, a) < rp.limits[1]:
                error[2] = 2 * e + a
                return ERR_NODE_TURNED
    return 0


@njit(inline="always")
def _base_cosine(rp, q, e, a):
    """t̄·t of node slot ``a`` of element ``e``: the cosine of its tangent's turn from its base."""
    o = a * NODE_SIZE + SLOPE
    g0 = q[rp.dofs[e, o]]
    g1 = q[rp.dofs[e, o + 1]]
    g2 = q[rp.dofs[e, o + 2]]
    tb = rp.rest.t_bar[e, a]
    return (tb[0] * g0 + tb[1] * g1 + tb[2] * g2) / math.sqrt(g0 * g0 + g1 * g1 + g2 * g2)


@njit
def rod_rebase(rp, q, v, qdd, acc, log, count):
    """Re-base every node whose tangent turned past :data:`REBASE_LIMIT` (``rp.limits[0]``) from
    its base (§2.4):
    ``t̄ ← t, D̄ ← d2, φ ← 0`` (the triad, hence every strain, unchanged), ``φ̇ ← φ̇ + ω_SR·t``
    (the physical spin kept), ``φ̈`` and the integrator's acceleration-like ``acc`` by the
    rate of that spin (each left out when its array is empty). Each re-based node is appended
    to ``log`` (records of :data:`~flexmbs.elements.layout.BASE_RECORD`: twist coordinate, t̄,
    D̄) from row ``count``; returns the new count. Empty ``v, qdd, acc``: a static solution.
    The spin ``ω = φ̇ + w`` and its rate (the twist inertia's, :func:`_spin_inertia`) are the
    same in both charts, so the motion continues unchanged."""
    x = np.empty(4)
    p = np.empty(6)
    val = np.empty(6)
    jac = np.empty((6, 4))
    xs = np.empty(6)
    ys = np.empty(N_SPIN)
    js = np.zeros((N_SPIN, 6))
    for e in range(rp.dofs.shape[0]):
        for a in range(2):
            if _base_cosine(rp, q, e, a) >= rp.limits[0]:
                continue
            o = a * NODE_SIZE + SLOPE
            k = rp.dofs[e, a * NODE_SIZE + TWIST]
            tb = rp.rest.t_bar[e, a]
            for c in range(3):
                x[c] = q[rp.dofs[e, o + c]]
                xs[c] = x[c]
                xs[3 + c] = v[rp.dofs[e, o + c]] if v.size > 0 else 0.0
                p[c] = tb[c]
                p[3 + c] = rp.rest.d_bar[e, a, c]
            x[3] = q[k]
            triad(x, p, val, jac)
            # the chart's spin w = b·ġ and its rate ẇ = b·g̈ + s (generated ``spin``, §2.4)
            spin(xs, p[:3], ys, js)
            if qdd.size > 0:
                qdd[k] += ys[4]
                for c in range(3):
                    qdd[k] += ys[1 + c] * qdd[rp.dofs[e, o + c]]
            if acc.size > 0:
                acc[k] += ys[4]
                for c in range(3):
                    acc[k] += ys[1 + c] * acc[rp.dofs[e, o + c]]
            if v.size > 0:
                v[k] += ys[0]
            q[k] = 0.0
            # the new base: t̄ = t, D̄ = d2 made exactly orthonormal to it
            dt = val[0] * val[3] + val[1] * val[4] + val[2] * val[5]
            dn = 0.0
            for c in range(3):
                val[3 + c] -= dt * val[c]
                dn += val[3 + c] * val[3 + c]
            dn = math.sqrt(dn)
            log[count, 0] = k
            for c in range(3):
                log[count, 1 + c] = val[c]
                log[count, 4 + c] = val[3 + c] / dn
            count = rod_set_bases(rp, log, count, count + 1)
    return count


@njit
def rod_set_bases(rp, log, start, stop):
    """Give the nodes of ``log[start:stop]`` (records ``[twist coordinate, t̄, D̄]``) their bases in
    every element that holds them; returns ``stop``."""
    for i in range(start, stop):
        k = np.int64(log[i, 0])
        for e in range(rp.dofs.shape[0]):
            for a in range(2):
                if rp.dofs[e, a * NODE_SIZE + TWIST] == k:
                    for c in range(3):
                        rp.rest.t_bar[e, a, c] = log[i, 1 + c]
                        rp.rest.d_bar[e, a, c] = log[i, 4 + c]
    return stop


def rod_bases(rp: RodPart) -> np.ndarray:
    """The current base of every node of the part: (n_nodes, 7) records (what a
    checkpoint carries, :func:`rod_set_bases` takes)."""
    keys = rp.dofs[:, [TWIST, NODE_SIZE + TWIST]].ravel()
    _, first = np.unique(keys, return_index=True)
    e, a = np.divmod(first, 2)
    return np.column_stack([keys[first].astype(float), rp.rest.t_bar[e, a], rp.rest.d_bar[e, a]])


def rod_kinetic_energy(rp: RodPart, q: np.ndarray, v: np.ndarray) -> float:
    """Kinetic energy of the part: the centreline's ``½ q̇ᵀ M q̇`` and the sections' spin
    ``½ ωᵀ M_φ ω`` per element with ``ω = φ̇ + w`` (:func:`_spin_inertia`)."""
    ve = v[rp.dofs]
    phi_dot = ve[:, [TWIST, NODE_SIZE + TWIST]]
    omega = phi_dot.copy()
    ys = np.empty(N_SPIN)
    js = np.zeros((N_SPIN, 6))
    slope = SLOPE + np.arange(3)
    for e in range(rp.dofs.shape[0]):
        for a in range(2):
            cols = rp.dofs[e, a * NODE_SIZE + slope]
            spin(np.concatenate([q[cols], v[cols]]), np.ascontiguousarray(rp.rest.t_bar[e, a]), ys,
                 js)
            omega[e, a] += ys[0]
    m_phi = np.asarray(rp.props.twist_inertia, float) * np.asarray(rp.props.length, float) / 6.0
    def twist_energy(x: np.ndarray) -> np.ndarray:      # ½ xᵀ M_φ x per element
        return m_phi * (x[:, 0] ** 2 + x[:, 0] * x[:, 1] + x[:, 1] ** 2)

    return float(0.5 * np.einsum("ei,eij,ej->", ve, rp.mass, ve)
                 + np.sum(twist_energy(omega) - twist_energy(phi_dot)))


def node_turned_message(beam: object, node: int, q: np.ndarray) -> str:
    """The one-line message of :data:`ERR_NODE_TURNED`."""
    limit = math.degrees(math.acos(TURN_LIMIT))
    return (f"beam '{getattr(beam, 'name', beam)}' node {node}: its tangent turned more than "
            f"{limit:.0f}° from its base within one step (re-basing, docs/theory.md §I.2.4, follows "
            "turns between steps): take a smaller time step or more load steps")


def section_properties(beams: list) -> RodProperties:
    """Section resultants per element of ``beams`` (in order): EA, GJ, EI2 = EI3 = EI, ρA, the
    twist inertia ρJ_p and the damping β of each beam."""
    cols: dict[str, list[np.ndarray]] = {f: [] for f in RodProperties._fields}
    for beam in beams:
        st = beam.stiffness
        if st.torsional_stiffness is None:
            raise ModelError(f"beam '{beam.name}': element 'ancf_rod14' needs a torsional "
                             "stiffness: give BeamStiffness(torsional_stiffness=...) or a "
                             "CircularSection with a Material")
        values = {"length": np.asarray(beam.centerline.lengths, float), "EA": st.axial_stiffness,
                  "GJ": st.torsional_stiffness, "EI2": st.bending_stiffness,
                  "EI3": st.bending_stiffness, "mass_per_length": st.mass_per_length,
                  "twist_inertia": st.polar_mass_moment, "damping": beam.damping,
                  "reference_axial_strain": beam.reference_axial_strain}
        for f in RodProperties._fields:
            cols[f].append(np.broadcast_to(np.asarray(values[f], float), (beam.n_elem,)).copy())
    return RodProperties(*(np.concatenate(cols[f]) if cols[f] else np.zeros(0)
                           for f in RodProperties._fields))


# ---------------------------------------------------------------------------------------------
# output
def output_fields(q_e: np.ndarray, rest: RodRest, options: object,
                  xi: np.ndarray) -> dict[str, np.ndarray]:
    """At the points ξ of every element: ``axial_strain`` ε and the ``curvature`` vector K of
    the centreline (the cable's), the nodal ``twist`` angle φ interpolated linearly, the
    ``torsion`` K1 − K1⁰ and the ``torsional_moment`` GJ (K1 − K1⁰) (§2.2)."""
    q_e = np.asarray(q_e, dtype=float)
    xi = np.atleast_1d(np.asarray(xi, dtype=float))
    eps, K, mu = cable.centerline_strain_and_curvature(q_e[:, CENTERLINE], rest.q_ref[:, CENTERLINE],
                                                       rest.length, xi)
    K1 = strain_measures(q_e, rest.t_bar, rest.d_bar, rest.length, xi, mu)[:, :, 1]
    K1_ref = strain_measures(rest.q_ref, rest.t_ref, rest.d_ref, rest.length, xi, mu)[:, :, 1]
    torsion = K1 - K1_ref
    twist_angle = (q_e[:, TWIST, None] * (1.0 - xi[None, :])
                   + q_e[:, NODE_SIZE + TWIST, None] * xi[None, :])
    return {"axial_strain": eps, "curvature": K, "twist": twist_angle, "torsion": torsion,
            "torsional_moment": rest.stiffness[:, 1, None] * torsion}


def _strain_energy(q_e: np.ndarray, props: RodProperties, rest: RodRest,
                   options: object) -> np.ndarray:
    return strain_energy(q_e, props, rest)


#: the rod as the assembler sees it (flexmbs.elements.layout.ElementType)
ELEMENT_TYPES.register("ancf_rod14", ElementType(
    layout=LAYOUT, section_properties=section_properties,
    reference_nodal_coordinates=reference_nodal_coordinates, gravity_force=gravity_force,
    distributed_force=distributed_force, point_force=point_force_vector, pack=pack_rods,
    strain_energy=_strain_energy, output_fields=output_fields, part_type=RodPart,
    residual=rod_residual, jacobian=rod_jacobian, shared_rest_fields=("gauss_xi", "gauss_weight"),
    node_base=node_base, post_step=rod_post_step, post_step_message=node_turned_message,
    rebase=rod_rebase, set_bases=rod_set_bases, bases=rod_bases,
    kinetic_energy=rod_kinetic_energy))

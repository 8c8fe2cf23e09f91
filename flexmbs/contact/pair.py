"""One contact point of the clearance sliding joint: gap, forces, tangent (docs/theory.md §II.4–§II.5).

Local coordinates of a contact ``q_c = [r_H (3), p (4), e_k (12)]`` (19): the hole body and the
beam element holding the projection point P. The hole point Q is a frozen material point of the
hole (body coordinates ``u_Q``); P is its closest-point projection on the centreline, re-projected
here for the current ``q_elem`` (Newton on the single element, warm-started at the given ξ; ξ may
leave [0, 1] — the caller then moves the contact to the neighbour element).

Conventions (package residual ``M q̈ + Q_int − Q_ext = 0``): ``Q_body``, ``Q_elem`` are *external*
generalized forces (the caller subtracts them from the residual), ``K = −∂Q/∂q_c`` and
``C = −∂Q/∂q̇_c`` are the matrices to *add* to the iteration matrix. The rotation is the
homogeneous ``A(p)`` of :mod:`flexmbs.elements.rigid_body`, so ``∂(A u)/∂p = 2T(u)p`` (Haug's
B(p, u), :func:`~flexmbs.elements.rigid_body.point_jacobian`) and ``∂²(A u)_k/∂p² = 2T_k(u)``
(:func:`~flexmbs.elements.rigid_body.point_tensor_of`) hold exactly.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from .._jit import njit
from ..elements._rod_derivatives import spin as chart_spin
from ..elements.hermite import CENTERLINE_SIZE, element_point, element_point_values, hermite_basis, shape_xi
from ..elements.rigid_body import point_jacobian_of, point_tensor_into, rotation
from .laws import (
    FRICTION_NONE,
    FRICTION_STICK,
    ForceLaw,
    Friction,
    RegularizedCoulomb,
    held_law_force,
    no_friction,
    tangential_force,
)

#: the twist angles of the contact element's two nodes (a rod's; zero columns for a cable)
N_TWIST = 2
#: first of them in the local coordinates
TWIST_OFF = 7 + CENTERLINE_SIZE
#: local coordinates of a contact ``[r_H, p, e_k, φ_k]``: the hole body's 7, the element's
#: centreline and its nodes' twists (they move the beam's surface under friction, not its axis)
N_LOCAL = TWIST_OFF + N_TWIST
#: a contact element's spin data ``[on, φ_0, φ_1, φ̇_0, φ̇_1, t̄_0 (3), t̄_1 (3)]``: ``on`` 0 for
#: a cable (no twist), else its nodes' twists and rates and their charts' base tangents
N_SPIN = 11

__all__ = ["ContactResult", "N_HISTORY", "N_SPIN", "contact_point", "contact_geometry",
           "contact_force", "fresh_history", "no_spin", "spin_map", "stick_trial",
           "twist_increment"]


class ContactResult(NamedTuple):
    """Result of :func:`contact_point` (all vectors global)."""

    gap: float                 #: g_N = |Q − P| − r_b (< 0: penetration)
    normal: np.ndarray         #: (3,) unit n from P to Q
    P: np.ndarray              #: (3,) centreline point r(ξ_P)
    Q: np.ndarray              #: (3,) hole point
    f_n: float                 #: normal force magnitude (≥ 0)
    force_on_hole: np.ndarray  #: (3,) F_H = f_n n + F_t (the beam gets −F_H at P)
    Q_body: np.ndarray         #: (7,) external generalized force on [r_H, p]
    Q_elem: np.ndarray         #: (CENTERLINE_SIZE,) external generalized force on e_k
    Q_twist: np.ndarray        #: (N_TWIST,) on the element's twists (a rod under friction)
    K: np.ndarray              #: (N_LOCAL, N_LOCAL) −∂Q/∂q_c
    C: np.ndarray              #: (N_LOCAL, N_LOCAL) −∂Q/∂q̇_c
    xi: float                  #: re-projected ξ_P (may lie outside [0, 1])
    gap_rate: float            #: ġ_N = n·(v_Q − v_P)
    anchor: np.ndarray         #: (3,) stick law: elastic displacement from the anchor after the
                               #: step (hole body coordinates)
    stuck: float               #: 1.0 if the contact sticks, else 0.0
    fade: float = 1.0          #: weight of a contact a beam's end is passing (_detect.end_fade)


@njit
def contact_map(Bp, S):
    """``W = ∂(x_Q − x_P)/∂q_c = [I, 2T(u_Q)p, −S(ξ_P)]`` (3, N_LOCAL) at fixed u_Q and ξ_P
    (docs/theory.md §II.4): ``Bp`` = 2T(u_Q)p (3, 4), ``S`` the shape functions at ξ_P (4,)
    (:func:`contact_map_into` a new array)."""
    W = np.empty((3, N_LOCAL))
    contact_map_into(Bp, S, W)
    return W


@njit
def contact_map_into(Bp, S, W):
    """:func:`contact_map` written into ``W`` (3, N_LOCAL)."""
    for c in range(3):
        for j in range(N_LOCAL):
            W[c, j] = 0.0
    for c in range(3):
        W[c, c] = 1.0
        for i in range(4):
            W[c, 3 + i] = Bp[c, i]
        for m in range(4):
            W[c, 7 + 3 * m + c] = -S[m]


#: flat work of one contact's kinematics and force (:func:`contact_force`'s ``work``): the
#: offsets of T (3, 4, 4), 2T(u_Q)p (3, 4), Q, P, n, F_H (3 each), W (3, N_LOCAL), B (N_LOCAL)
_WORK_T = 0
_WORK_BP = _WORK_T + 3 * 4 * 4
_WORK_Q = _WORK_BP + 3 * 4
_WORK_P = _WORK_Q + 3
_WORK_N = _WORK_P + 3
_WORK_FH = _WORK_N + 3
_WORK_W = _WORK_FH + 3
_WORK_B = _WORK_W + 3 * N_LOCAL
PAIR_WORK = _WORK_B + N_LOCAL


@njit
def xi_bounds(elem, n_elem):
    """The range a contact's ξ_P may take on element ``elem`` of a beam of ``n_elem``: the
    cubic continued half an element and more past an inner node (the neighbour's domain, the
    projection's own), but not past an end of the beam. A contact whose ξ_P sits on such a
    bound is pinned there (:func:`is_pinned`): the beam's end point, a sphere of radius r_b."""
    return (0.0 if elem == 0 else -1.0), (1.0 if elem == n_elem - 1 else 2.0)


@njit
def is_pinned(xi, xi_lo, xi_hi):
    """ξ_P held on a bound of :func:`xi_bounds` (the beam's end): the tangent's ξ_P does not
    move with the coordinates."""
    return xi == xi_lo or xi == xi_hi  # noqa: SIM109 (compiled: two float comparisons)


@njit
def _kinematics(q_body, v_body, u_Q, q_elem, v_elem, length, xi0, r_b, work, xi_lo, xi_hi):
    """Gap kinematics without the Hessian (the hot path): ``(xi, g, gdot, n, P, Q, B, W, T, dS,
    rx, rxx, ell)``, the arrays views of ``work`` (:data:`PAIR_WORK`; no allocation), dS, rx,
    rxx tuples; see :func:`contact_geometry`. The projection keeps ξ in ``[xi_lo, xi_hi]``
    (:func:`xi_bounds`: at a beam's end, the end)."""
    p = q_body[3:7]
    T = work[_WORK_T:_WORK_BP].reshape((3, 4, 4))
    Bp = work[_WORK_BP:_WORK_Q].reshape((3, 4))
    Q = work[_WORK_Q:_WORK_P]
    P = work[_WORK_P:_WORK_N]
    n = work[_WORK_N:_WORK_FH]
    W = work[_WORK_W:_WORK_B].reshape((3, N_LOCAL))
    B = work[_WORK_B:PAIR_WORK]
    point_tensor_into(u_Q, T)
    point_jacobian_of(T, p, Bp, Q)            # 2T(u_Q)p and A u_Q
    for k in range(3):
        Q[k] += q_body[k]
    # closest-point projection on this element (extrapolating the cubic up to a beam's end)
    xi = max(xi_lo, min(xi_hi, xi0))
    for _ in range(30):
        r, rx, rxx = element_point_values(q_elem, length, xi)
        d = (r[0] - Q[0], r[1] - Q[1], r[2] - Q[2])
        h = d[0] * rx[0] + d[1] * rx[1] + d[2] * rx[2]
        a11 = rx[0] * rx[0] + rx[1] * rx[1] + rx[2] * rx[2]
        if abs(h) <= 1e-14 * math.sqrt(a11) * max(1.0, math.sqrt(Q[0]**2 + Q[1]**2 + Q[2]**2)):
            break
        hx = a11 + d[0] * rxx[0] + d[1] * rxx[1] + d[2] * rxx[2]
        step = -h / hx if hx > 0.0 else (-0.25 if h > 0.0 else 0.25)
        step = max(-0.5, min(0.5, step))
        moved = max(xi_lo, min(xi_hi, xi + step))
        if abs(step) < 1e-15 or moved == xi:
            xi = moved
            break
        xi = moved
    S, dS, _, _ = hermite_basis(xi, length)
    Pv, rx, rxx = element_point_values(q_elem, length, xi)
    for c in range(3):
        P[c] = Pv[c]
    u = (Q[0] - P[0], Q[1] - P[1], Q[2] - P[2])
    ell = math.sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2])
    for c in range(3):
        n[c] = u[c] / ell
    g = ell - r_b
    contact_map_into(Bp, S, W)
    for j in range(N_LOCAL):
        B[j] = n[0] * W[0, j] + n[1] * W[1, j] + n[2] * W[2, j]
    gdot = 0.0
    for c in range(3):      # n · v_rel, v_rel = W q̇_c at fixed u_Q, ξ_P
        acc = v_body[c]
        for i in range(4):
            acc += Bp[c, i] * v_body[3 + i]
        for m in range(4):
            acc -= S[m] * v_elem[3 * m + c]
        gdot += n[c] * acc
    return xi, g, gdot, n, P, Q, B, W, T, dS, rx, rxx, ell


@njit
def _gap_hessian(n, W, T, dS, rx, rxx, ell, pinned):
    """The consistent ``∂²g_N/∂q_c²`` (N_LOCAL, N_LOCAL) of §5 (ξ_P variation, Euler-parameter
    part; ``pinned``: ξ_P held at the beam's end, no ξ_P variation)."""
    H = np.zeros((N_LOCAL, N_LOCAL))
    for i in range(N_LOCAL):
        for j in range(N_LOCAL):
            acc = 0.0
            for c in range(3):
                acc += W[c, i] * W[c, j]
            bi = n[0] * W[0, i] + n[1] * W[1, i] + n[2] * W[2, i]
            bj = n[0] * W[0, j] + n[1] * W[1, j] + n[2] * W[2, j]
            H[i, j] = (acc - bi * bj) / ell            # Wᵀ(I − nnᵀ)W / ℓ
    for i in range(4):
        for j in range(4):
            acc = 0.0
            for k in range(3):
                acc += n[k] * T[k, i, j]
            H[3 + i, 3 + j] += 2.0 * acc
    if pinned:
        return H
    a11 = rx[0] * rx[0] + rx[1] * rx[1] + rx[2] * rx[2]
    den = a11 - ell * (n[0] * rxx[0] + n[1] * rxx[1] + n[2] * rxx[2])
    w = np.zeros(N_LOCAL)
    for j in range(N_LOCAL):
        w[j] = rx[0] * W[0, j] + rx[1] * W[1, j] + rx[2] * W[2, j]
    for m in range(4):
        for c in range(3):
            w[7 + 3 * m + c] += ell * dS[m] * n[c]
    for i in range(N_LOCAL):
        for j in range(N_LOCAL):
            H[i, j] -= w[i] * w[j] / (ell * den)
    return H


@njit
def contact_geometry(q_body, v_body, u_Q, q_elem, v_elem, length, xi0, r_b, want_hessian,
                     xi_lo=-1.0, xi_hi=2.0):
    """Gap kinematics of one contact (docs/theory.md §II.4–§II.5), numba kernel.

    Returns ``(xi, g, gdot, n, P, Q, B (N_LOCAL,), W (3, N_LOCAL), H (N_LOCAL, N_LOCAL))`` with
    ``W = ∂(x_Q − x_P)/∂q_c`` at fixed ξ, ``B = nᵀW = ∂g_N/∂q_c``, and (if ``want_hessian``) the consistent
    ``H = ∂²g_N/∂q_c²`` of §5 including the ξ_P variation and the Euler-parameter Hessian.
    """
    xi, g, gdot, n, P, Q, B, W, T, dS, rx, rxx, ell = _kinematics(
        q_body, v_body, u_Q, q_elem, v_elem, length, xi0, r_b, np.empty(PAIR_WORK), xi_lo, xi_hi)
    H = (_gap_hessian(n, W, T, dS, rx, rxx, ell, is_pinned(xi, xi_lo, xi_hi)) if want_hessian
         else np.zeros((N_LOCAL, N_LOCAL)))
    return xi, g, gdot, n, P, Q, B, W, H


#: history of one contact at the start of the step (what its friction remembers):
#: ``[d_A (3): elastic tangential displacement from the anchor, body coordinates; stuck;
#: r_H, p at the step's start (7); e_P at the step's start (CENTERLINE_SIZE); its nodes'
#: twists at the step's start (N_TWIST)]``
HIST_TWIST = 4 + 7 + CENTERLINE_SIZE
N_HISTORY = HIST_TWIST + N_TWIST
#: ``geo`` of :func:`contact_force`: ``[n, P, Q, F_H, d_new (body coordinates), stuck]``
N_GEO = 16


def fresh_history(q_body: np.ndarray, q_elem: np.ndarray,
                  spin: np.ndarray | None = None) -> np.ndarray:
    """History of a contact without an anchor whose step starts at ``(q_body, q_elem)`` (and
    the element's twists of ``spin``, :data:`N_SPIN`)."""
    h = np.zeros(N_HISTORY)
    h[3] = 1.0
    h[4:11] = q_body
    h[11:HIST_TWIST] = q_elem
    if spin is not None:
        h[HIST_TWIST:] = spin[1:3]
    return h


def no_spin() -> np.ndarray:
    """The spin data (:data:`N_SPIN`) of a contact element without twist (a cable)."""
    return np.zeros(N_SPIN)


@njit
def node_spins(spin, q_elem, v_elem, b, db, w, dw):
    """The contact element's nodes' chart spins (docs/theory.md §I.2.4, the rod's generated
    ``spin`` map, the one its twist inertia uses): node a's section turns about its tangent at
    ``φ̇_a + w_a`` with ``w_a = b_a·ġ_a``; writes ``b`` (2, 3), ``∂b_a/∂g_a`` ``db`` (2, 3, 3),
    ``w`` (2,) and ``∂w_a/∂g_a`` ``dw`` (2, 3)."""
    x = np.empty(6)
    val = np.empty(8)
    jac = np.empty((8, 6))
    for a in range(2):
        for c in range(3):
            x[c] = q_elem[6 * a + 3 + c]
            x[3 + c] = v_elem[6 * a + 3 + c]
        chart_spin(x, spin[5 + 3 * a:8 + 3 * a], val, jac)
        w[a] = val[0]
        for c in range(3):
            b[a, c] = val[1 + c]
            dw[a, c] = jac[0, c]
            for k in range(3):
                db[a, c, k] = jac[1 + c, k]


@njit
def spin_map(spin, q_elem, v_elem, xi, r_b, rx, n, Wf, b, db, w, dw):
    """The beam surface's turn under the contact (docs/design-notes.md "Torque and drag"): the
    surface point ``C = P + r_b n`` of a rod moves by ``ω (t × n) r_b`` with the section spin
    ``ω = Σ N_a (φ̇_a + w_a)`` interpolated as the rod's twist inertia does (N_0 = 1 − ξ,
    N_1 = ξ); adds ``∂(x_Q − x_C)/∂q_c`` of the spin to the friction map ``Wf`` (3, N_LOCAL):
    ``−r_b N_a s`` on twist a and ``−r_b N_a s b_aᵀ`` on slope a, ``s = t × n``. Writes the
    node spins (:func:`node_spins`) and returns ``(ω, s)``."""
    node_spins(spin, q_elem, v_elem, b, db, w, dw)
    nr = math.sqrt(rx[0] * rx[0] + rx[1] * rx[1] + rx[2] * rx[2])
    t = rx / nr
    s = np.empty(3)
    s[0] = t[1] * n[2] - t[2] * n[1]
    s[1] = t[2] * n[0] - t[0] * n[2]
    s[2] = t[0] * n[1] - t[1] * n[0]
    omega = 0.0
    for a in range(2):
        Na = xi if a == 1 else 1.0 - xi
        omega += Na * (spin[3 + a] + w[a])
        for c in range(3):
            Wf[c, TWIST_OFF + a] -= r_b * Na * s[c]
            for k in range(3):
                Wf[c, 7 + 6 * a + 3 + k] -= r_b * Na * s[c] * b[a, k]
    return omega, s


@njit
def twist_increment(spin, hist, q_elem, xi, b, bbar, dg):
    """The section's turn at ξ over the step, ``Δψ = Σ N_a (φ_a − φ_a,n + b̄_a·Δg_a)`` with
    ``b̄_a = ½(b_a(g_a) + b_a(g_a,n))`` on the same chart (the chart spin integrated by the
    trapezoidal rule; ``hist``: the step's start). Writes ``bbar``, ``dg`` (2, 3); returns Δψ."""
    x = np.zeros(6)
    val = np.empty(8)
    jac = np.empty((8, 6))
    dpsi = 0.0
    for a in range(2):
        for c in range(3):
            x[c] = hist[11 + 6 * a + 3 + c]
        chart_spin(x, spin[5 + 3 * a:8 + 3 * a], val, jac)
        psi = spin[1 + a] - hist[HIST_TWIST + a]
        for c in range(3):
            bbar[a, c] = 0.5 * (b[a, c] + val[1 + c])
            dg[a, c] = q_elem[6 * a + 3 + c] - hist[11 + 6 * a + 3 + c]
            psi += bbar[a, c] * dg[a, c]
        dpsi += (xi if a == 1 else 1.0 - xi) * psi
    return dpsi


@njit
def stick_trial(A, hist, u_Q, Q, P, S, n, turn, delta, d):
    """Trial elastic tangential displacement of a sticking contact (docs/design-notes.md
    "Friction that sticks"): ``Δ = A d_A + (Q − P) − (Q_n − P_n) + turn``, ``d = (I − nnᵀ)Δ``,
    with the material points in contact now (hole point u_Q, beam point ξ_P: shape functions
    ``S``) at the step's start ``Q_n = r_H,n + A_n u_Q``, ``P_n = S e_P,n`` (``hist``,
    :data:`N_HISTORY`), the anchor's displacement ``d_A`` carried in the hole's frame and
    ``turn`` the surface's own turn over the step (``−r_b Δψ (t × n)`` on a rod, else zero).
    Writes ``delta``, ``d``."""
    An = rotation(hist[7:11])
    for c in range(3):
        acc = Q[c] - P[c] - hist[4 + c] + turn[c]
        for j in range(3):
            acc += A[c, j] * hist[j] - An[c, j] * u_Q[j]
        for m in range(4):
            acc += S[m] * hist[11 + 3 * m + c]
        delta[c] = acc
    dn = n[0] * delta[0] + n[1] * delta[1] + n[2] * delta[2]
    for c in range(3):
        d[c] = delta[c] - dn * n[c]


@njit
def contact_force(q_body, v_body, u_Q, q_elem, v_elem, spin, length, xi0, r_b, law, fric, hist,
                  approach_velocity, want_tangent, Qc, K, C, geo, work, held=False, xi_lo=-1.0,
                  xi_hi=2.0, mouth=0.0):
    """Penalty force of one contact point and its Gauss–Newton tangent (docs/theory.md §II.4–§II.5).

    ``law`` = :meth:`ForceLaw.parameters`; ``fric`` = :meth:`~flexmbs.contact.laws.Friction.parameters`
    and ``hist`` (:data:`N_HISTORY`) the contact's history, for
    :func:`~flexmbs.contact.laws.tangential_force`; ``spin`` (:data:`N_SPIN`) the element's
    twists: on a rod the friction acts at the turning surface (:func:`spin_map`); None where no
    joint of the model holds a beam with twist (that code is compiled out). Writes ``Qc``
    (N_LOCAL,) = ``W_fᵀ F_H`` (external generalized force on [r_H, p, e_k, φ_k]; W_f = W with
    the surface's turn), with ``want_tangent`` ``K = k_t BᵀB`` plus
    the friction terms at frozen n, u_Q, ξ_P and ``C = c_t BᵀB`` plus friction (N_LOCAL,
    N_LOCAL), and ``geo`` (:data:`N_GEO`) = [n, P, Q, F_H, d_new (body coordinates), stuck];
    ``work`` (:data:`PAIR_WORK`): its scratch (the frictionless path allocates nothing).
    ``held``: the contact is in the active set the Newton iterations hold
    (:func:`~flexmbs.contact.laws.held_law_force`: a linear law pulls at g > 0); ``xi_lo``,
    ``xi_hi``: the range of ξ_P (:func:`xi_bounds`); ``mouth``: r_b at an end section of an
    open bore (:func:`~flexmbs.contact.laws.mouth_weight`), else 0.
    Returns ``(g_N, ġ_N, f_N, ξ_P)``.
    """
    xi, g, gdot, n, P, Q, B, W, _, _, _, _, _ = _kinematics(q_body, v_body, u_Q, q_elem, v_elem,
                                                            length, xi0, r_b, work, xi_lo, xi_hi)
    f, kt, ct = held_law_force(law, -g, -gdot, approach_velocity, held, mouth)
    F_H = work[_WORK_FH:_WORK_W]
    for c in range(3):
        F_H[c] = f * n[c]
    for c in range(12, N_GEO):
        geo[c] = 0.0
    friction = fric[0] != FRICTION_NONE and f > 0.0
    Wf = W                 # the friction map: W and, on a rod, the surface's turn
    if friction:
        turn = np.zeros(3)
        if spin is not None and spin[0] != 0.0:
            Wf = W.copy()
            b = np.empty((2, 3))
            _, rx, _ = element_point(q_elem, length, xi)
            _, sv = spin_map(spin, q_elem, v_elem, xi, r_b, rx, n, Wf, b, np.empty((2, 3, 3)),
                             np.empty(2), np.empty((2, 3)))
            if fric[0] == FRICTION_STICK:
                dpsi = twist_increment(spin, hist, q_elem, xi, b, np.empty((2, 3)),
                                       np.empty((2, 3)))
                for c in range(3):
                    turn[c] = -r_b * dpsi * sv[c]
        vrel = np.zeros(3)
        for c in range(3):
            acc = 0.0
            for j in range(7):
                acc += Wf[c, j] * v_body[j]
            for j in range(CENTERLINE_SIZE):
                acc += Wf[c, 7 + j] * v_elem[j]
            if spin is not None:
                for a in range(N_TWIST):
                    acc += Wf[c, TWIST_OFF + a] * spin[3 + a]
            vrel[c] = acc
        vn = n[0] * vrel[0] + n[1] * vrel[1] + n[2] * vrel[2]
        vt = vrel - vn * n
        d = np.zeros(3)
        A = np.zeros((3, 3))
        if fric[0] == FRICTION_STICK:
            A = rotation(q_body[3:7])
            S, _, _ = shape_xi(xi, length)
            delta = np.empty(3)
            stick_trial(A, hist, u_Q, Q, P, S, n, turn, delta, d)
        Ft = np.empty(3)
        dF_dd = np.empty((3, 3))
        dF_dv = np.empty((3, 3))
        dF_dfn = np.empty(3)
        d_new = np.empty(3)
        geo[15] = tangential_force(fric, hist[3], f, d, vt, Ft, dF_dd, dF_dv, dF_dfn, d_new)
        for c in range(3):
            F_H[c] += Ft[c]
        if fric[0] == FRICTION_STICK:   # the anchor in the hole's frame: A⁻¹ = Aᵀ/|p|⁴
            p4 = (q_body[3] ** 2 + q_body[4] ** 2 + q_body[5] ** 2 + q_body[6] ** 2) ** 2
            for c in range(3):
                geo[12 + c] = (A[0, c] * d_new[0] + A[1, c] * d_new[1] + A[2, c] * d_new[2]) / p4
    for j in range(N_LOCAL):
        Qc[j] = Wf[0, j] * F_H[0] + Wf[1, j] * F_H[1] + Wf[2, j] * F_H[2]
    for c in range(3):
        geo[c] = n[c]
        geo[3 + c] = P[c]
        geo[6 + c] = Q[c]
        geo[9 + c] = F_H[c]
    if want_tangent:
        for i in range(N_LOCAL):
            for j in range(N_LOCAL):
                bb = B[i] * B[j]
                K[i, j] = kt * bb
                C[i, j] = ct * bb
        if friction:
            # at frozen n, u_Q, ξ_P: ∂d/∂q_c = ∂v_t/∂q̇_c = P_n W (P_n = I − nnᵀ), so
            # K += −Wᵀ(∂F/∂d)P_n W + k_t (Wᵀ ∂F/∂f_N) Bᵀ, C += −Wᵀ(∂F/∂v_t)P_n W + c_t (Wᵀ ∂F/∂f_N) Bᵀ
            Md = np.empty((3, 3))
            Mv = np.empty((3, 3))
            for a in range(3):
                dd = dF_dd[a, 0] * n[0] + dF_dd[a, 1] * n[1] + dF_dd[a, 2] * n[2]
                dv = dF_dv[a, 0] * n[0] + dF_dv[a, 1] * n[1] + dF_dv[a, 2] * n[2]
                for b in range(3):
                    Md[a, b] = dF_dd[a, b] - dd * n[b]
                    Mv[a, b] = dF_dv[a, b] - dv * n[b]
            MdW = np.zeros((3, N_LOCAL))
            MvW = np.zeros((3, N_LOCAL))
            WtdF = np.zeros(N_LOCAL)
            for j in range(N_LOCAL):
                for a in range(3):
                    MdW[a, j] = Md[a, 0] * Wf[0, j] + Md[a, 1] * Wf[1, j] + Md[a, 2] * Wf[2, j]
                    MvW[a, j] = Mv[a, 0] * Wf[0, j] + Mv[a, 1] * Wf[1, j] + Mv[a, 2] * Wf[2, j]
                WtdF[j] = Wf[0, j] * dF_dfn[0] + Wf[1, j] * dF_dfn[1] + Wf[2, j] * dF_dfn[2]
            for i in range(N_LOCAL):
                for j in range(N_LOCAL):
                    C[i, j] += ct * WtdF[i] * B[j] - (Wf[0, i] * MvW[0, j] + Wf[1, i] * MvW[1, j]
                                                      + Wf[2, i] * MvW[2, j])
                    K[i, j] += kt * WtdF[i] * B[j] - (Wf[0, i] * MdW[0, j] + Wf[1, i] * MdW[1, j]
                                                      + Wf[2, i] * MdW[2, j])
    return g, gdot, f, xi


def _friction_force(q_c: np.ndarray, v_c: np.ndarray, spin: np.ndarray, u_Q: np.ndarray,
                    length: float, xi: float, r_b: float, law: np.ndarray, fric: np.ndarray,
                    hist: np.ndarray, approach_velocity: float,
                    xi_range: tuple[float, float], mouth: float) -> np.ndarray:
    """Friction part ``W_fᵀ F_t`` of the generalized force (for the finite-difference tangent):
    :func:`contact_force` with and without friction (the twists of ``q_c``, ``v_c`` in
    ``spin``)."""
    sp = spin.copy()
    if sp[0] != 0.0:
        sp[1:3] = q_c[TWIST_OFF:]
        sp[3:5] = v_c[TWIST_OFF:]
    out = []
    spin_arg = _spin_argument(sp)
    for fr in (fric, no_friction()):
        Qc = np.empty(N_LOCAL)
        contact_force(q_c[:7].copy(), v_c[:7].copy(), u_Q, q_c[7:TWIST_OFF].copy(),
                      v_c[7:TWIST_OFF].copy(), spin_arg, float(length), float(xi), float(r_b), law, fr,
                      hist, approach_velocity, False, Qc, np.empty((0, 0)), np.empty((0, 0)),
                      np.empty(N_GEO), np.empty(PAIR_WORK), False, *xi_range, mouth)
        out.append(Qc)
    return out[0] - out[1]


def _spin_argument(spin: np.ndarray) -> np.ndarray | None:
    """The ``spin`` a Python caller passes to :func:`contact_force`: None for an element
    without twist, as the compiled kernel of a cable model passes it (one compiled form)."""
    return spin if spin[0] != 0.0 else None


def friction_vector(friction: Friction | RegularizedCoulomb | None,
                    default_stiffness: float) -> np.ndarray:
    """:meth:`Friction.parameters` of a joint's friction (``None``: frictionless)."""
    from .laws import as_friction

    fr = as_friction(friction)
    return no_friction() if fr is None else fr.parameters(default_stiffness)


def contact_point(q_body: np.ndarray, v_body: np.ndarray, u_Q: np.ndarray, q_elem: np.ndarray,
                  v_elem: np.ndarray, length: float, xi: float, r_b: float, law: ForceLaw,
                  friction: Friction | RegularizedCoulomb | None = None,
                  approach_velocity: float = 0.0, consistent: bool = False, *,
                  history: np.ndarray | None = None,
                  friction_stiffness: float | None = None,
                  spin: np.ndarray | None = None,
                  xi_range: tuple[float, float] = (-1.0, 2.0),
                  mouth: float = 0.0) -> ContactResult:
    """Gap, penalty force and tangent of one beam/hole contact point (docs/theory.md §II.4–§II.5).

    ``g_N = |Q − P| − r_b``, ``n = (Q − P)/|Q − P|``, ``f_N = law(−g_N, −ġ_N, approach_velocity)``,
    ``F_H = f_N n + F_t`` on the hole at Q and ``−F_H`` on the beam at P;
    ``Q_c = Wᵀ F_H`` (= ``f_N Bᵀ`` frictionless, virtual work ``δW = f_N δg_N``).
    ``friction``: its law's ``F_t`` (:func:`~flexmbs.contact.laws.tangential_force`) with the
    contact's ``history`` (:data:`N_HISTORY`; default: no anchor, the step starting here) and
    the stick law's stiffness ``friction_stiffness`` when the law leaves it open (default: the
    normal law's first parameter); ``spin`` (:data:`N_SPIN`, default none) a rod element's
    twists, whose surface turns under the friction (:func:`spin_map`); ``xi_range`` the range
    of ξ_P (:func:`xi_bounds`: at a beam's end, the end); ``mouth`` the beam radius at an end
    section of an open bore (:func:`~flexmbs.contact.laws.mouth_weight`), else 0.

    Tangent: Gauss–Newton ``K = k_t BᵀB`` (+ the friction terms at frozen n, u_Q, ξ_P);
    ``consistent=True`` adds the exact geometric and damping terms of the normal force,
    ``−f_N ∂²g_N + c_t B (∂²g_N q̇)ᵀ`` (analytic, §5), and replaces the friction stiffness by
    central finite differences of ``Wᵀ F_t`` over the N_LOCAL coordinates.
    ``C = c_t BᵀB`` + the friction velocity derivative.
    """
    q_body = np.ascontiguousarray(q_body, dtype=float)
    v_body = np.ascontiguousarray(v_body, dtype=float)
    u_Q = np.ascontiguousarray(u_Q, dtype=float)
    q_elem = np.ascontiguousarray(q_elem, dtype=float)
    v_elem = np.ascontiguousarray(v_elem, dtype=float)
    law_p = law.parameters()
    fric = friction_vector(friction, float(law_p[0] if friction_stiffness is None
                                           else friction_stiffness))
    sp = no_spin() if spin is None else np.ascontiguousarray(spin, dtype=float)
    hist = (fresh_history(q_body, q_elem, sp) if history is None
            else np.ascontiguousarray(history, dtype=float))
    Qc, K, C = np.empty(N_LOCAL), np.empty((N_LOCAL, N_LOCAL)), np.empty((N_LOCAL, N_LOCAL))
    geo = np.empty(N_GEO)
    spin_arg = _spin_argument(sp)
    g, gdot, f, xi_p = contact_force(q_body, v_body, u_Q, q_elem, v_elem, spin_arg, float(length),
                                     float(xi), float(r_b), law_p, fric, hist,
                                     float(approach_velocity), True, Qc, K, C, geo,
                                     np.empty(PAIR_WORK), False, *xi_range, mouth)
    n, P, Q, F_H = geo[0:3], geo[3:6], geo[6:9], geo[9:12]
    if consistent:
        # exact geometric and damping terms of the normal force (§5), and the friction
        # stiffness by central differences in place of its Gauss-Newton part
        _, _, _, _, _, _, B, W, H = contact_geometry(q_body, v_body, u_Q, q_elem, v_elem,
                                                     float(length), float(xi), float(r_b), True,
                                                     *xi_range)
        _, kt, ct = held_law_force(law_p, -g, -gdot, float(approach_velocity), False, mouth)
        v_c = np.concatenate([v_body, v_elem, sp[3:5]])
        K += ct * np.outer(B, H @ v_c) - f * H
        if fric[0] != 0.0 and f > 0.0:
            # the friction stiffness by central differences in place of its Gauss-Newton part
            Qf = np.empty(N_LOCAL)
            Kf, Cf = np.empty((N_LOCAL, N_LOCAL)), np.empty((N_LOCAL, N_LOCAL))
            Kn, Cn = np.empty((N_LOCAL, N_LOCAL)), np.empty((N_LOCAL, N_LOCAL))
            contact_force(q_body, v_body, u_Q, q_elem, v_elem, spin_arg, float(length), float(xi),
                          float(r_b), law_p, fric, hist, float(approach_velocity), True, Qf, Kf,
                          Cf, np.empty(N_GEO), np.empty(PAIR_WORK), False, *xi_range, mouth)
            contact_force(q_body, v_body, u_Q, q_elem, v_elem, spin_arg, float(length), float(xi),
                          float(r_b), law_p, no_friction(), hist, float(approach_velocity), True,
                          Qf, Kn, Cn, np.empty(N_GEO), np.empty(PAIR_WORK), False, *xi_range, mouth)
            K -= Kf - Kn
            q_c = np.concatenate([q_body, q_elem, sp[1:3]])
            hstep = 1e-7 * max(1.0, float(np.max(np.abs(q_c))))
            for j in range(N_LOCAL):
                qp = q_c.copy()
                qm = q_c.copy()
                qp[j] += hstep
                qm[j] -= hstep
                dQ = (_friction_force(qp, v_c, sp, u_Q, length, xi_p, r_b, law_p, fric, hist,
                                      approach_velocity, xi_range, mouth)
                      - _friction_force(qm, v_c, sp, u_Q, length, xi_p, r_b, law_p, fric, hist,
                                        approach_velocity, xi_range, mouth)) / (2.0 * hstep)
                K[:, j] -= dQ
    return ContactResult(gap=float(g), normal=n, P=P, Q=Q, f_n=float(f), force_on_hole=F_H,
                         Q_body=Qc[:7], Q_elem=Qc[7:TWIST_OFF], Q_twist=Qc[TWIST_OFF:], K=K,
                         C=C, xi=float(xi_p),
                         gap_rate=float(gdot), anchor=geo[12:15].copy(), stuck=float(geo[15]))

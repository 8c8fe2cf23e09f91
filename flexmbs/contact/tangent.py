"""Exact linearisation of one detected clearance contact (issue "exact linearisation"; docs/theory.md
§II.2–§II.5 differentiated, implicit-function theorem on the detection's own equations).

The residual of a contact is that of :func:`flexmbs.contact.clearance_term.clearance_forces`: in hole
section k the beam axis crosses the section plane at ξ_I (element e_I), its section is the
ellipse ``X(φ) = c + a cos φ e_a + b sin φ e_b`` (in-plane centre c, major axis e_a, a =
r_b|r′|/|n·r′|, b = r_b); a stationary point φ of ``½|X|²`` (``F(φ) = X·X_φ = 0``) gives the
wall angle ψ = atan2(X_z, X_y) and the hole point ``Q = o + R(cos ψ e_y + sin ψ e_z)``; Q is
held as body coordinates ``u_Q = Aᵀ(Q − r_H)`` and the force acts between the body point
``r_H + A u_Q`` and its closest centreline point P (ξ_P on element e_P):
``g = |Q − P| − r_b``, ``F_H = f(−g, −ġ) n + F_t``, generalized force ``Q_c = Wᵀ F_H`` with
``W = [I, 2T(u_Q)p, −S(ξ_P)]``.

Every quantity is carried with its derivative (forward mode) with respect to the local
coordinates ``[r_H, p (7), e_I (12), e_P (12)]``; the implicit unknowns ξ_I, φ and ξ_P get
theirs from the implicit-function theorem on the crossing, stationarity and closest-point
equations. ``A(p)`` is the homogeneous rotation (``A Aᵀ = |p|⁴ I``), differentiated as such, so
the tangent is exact also off the Euler-parameter constraint (Newton iterates). The result is
the exact ``K = −∂Q_c/∂q`` and ``C = −∂Q_c/∂q̇`` of the residual as implemented (the same
function, evaluated in the same order), which the finite-difference tests confirm.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import njit
from ..elements.hermite import CENTERLINE_SIZE, element_point, shape_xi
from ..elements.rigid_body import point_jacobian_of, point_tensor_of, rotation
from .laws import FRICTION_NONE, FRICTION_STICK, held_law_force, tangential_force
from .pair import (
    HIST_TWIST,
    N_LOCAL,
    N_TWIST,
    TWIST_OFF,
    contact_map,
    spin_map,
    stick_trial,
    twist_increment,
)

__all__ = ["N_EXT", "I_OFF", "P_OFF", "T_OFF", "contact_tangent", "fade_gradient"]

#: local coordinates of the exact tangent's columns: body (7), crossing element e_I, element e_P
#: and e_P's twists (N_TWIST)
N_EXT = 7 + 2 * CENTERLINE_SIZE + N_TWIST
I_OFF = 7
P_OFF = 7 + CENTERLINE_SIZE
T_OFF = 7 + 2 * CENTERLINE_SIZE


@njit
def _body_basis():
    """``T(e_j)`` (3, 3, 4, 4): the point tensors of the body's unit vectors (T is linear in u)."""
    Te = np.zeros((3, 3, 4, 4))
    u = np.zeros(3)
    for j in range(3):
        u[:] = 0.0
        u[j] = 1.0
        Te[j] = point_tensor_of(u)
    return Te


@njit
def _t_times(u, x):
    """``2 T(u) x`` (3, 4) = ∂(A(p)u)/∂p at p = x (with x = p) or the velocity term (x = ṗ)
    (:func:`~flexmbs.elements.rigid_body.point_jacobian_of`)."""
    out = np.empty((3, 4))
    point_jacobian_of(point_tensor_of(u), x, out, np.empty(3))
    return out


@njit
def _d_dot(a, Da, b, Db, out):
    """``out = D(a·b) = Daᵀ b + aᵀ Db`` (vectors a, b (3,), derivatives (3, N_EXT))."""
    for j in range(out.size):
        out[j] = (Da[0, j] * b[0] + Da[1, j] * b[1] + Da[2, j] * b[2]
                  + a[0] * Db[0, j] + a[1] * Db[1, j] + a[2] * Db[2, j])


@njit
def fade_gradient(qb, u_o, frame, qI, LI, end, slope, out):
    """``out`` (N_EXT) = ∂w/∂[r_H, p, e_I] of :func:`~flexmbs.contact._detect.end_fade`'s weight
    ``w(h)``, ``h = n·(r_end − o)``, ``n = A(p) frame[:, 0]``, ``o = r_H + A(p) u_o`` and
    ``r_end`` the end node of the crossing's element ``qI`` (``end`` −1: at ξ = 0, +1: at
    ξ = 1); ``slope`` = dw/dh: ``∂h/∂r_H = −n``, ``∂h/∂p = (2T(f_n)p)ᵀ(r_end − o) −
    (2T(u_o)p)ᵀ n``, ``∂h/∂e_I = S(ξ_end)ᵀ n``."""
    p = qb[3:7]
    A = rotation(p)
    f_n = np.empty(3)
    u = np.empty(3)
    nvec = np.empty(3)
    o = np.empty(3)
    for c in range(3):
        f_n[c] = frame[c, 0]
        u[c] = u_o[c]
    for c in range(3):
        nvec[c] = A[c, 0] * f_n[0] + A[c, 1] * f_n[1] + A[c, 2] * f_n[2]
        o[c] = qb[c] + A[c, 0] * u[0] + A[c, 1] * u[1] + A[c, 2] * u[2]
    xi_end = 0.0 if end < 0 else 1.0
    S, _, _ = shape_xi(xi_end, LI)
    r_end, _, _ = element_point(qI, LI, xi_end)
    Bn = _t_times(f_n, p)
    Bo = _t_times(u, p)
    for j in range(out.size):
        out[j] = 0.0
    for c in range(3):
        out[c] = -slope * nvec[c]
    for i in range(4):
        acc = 0.0
        for c in range(3):
            acc += Bn[c, i] * (r_end[c] - o[c]) - nvec[c] * Bo[c, i]
        out[3 + i] = slope * acc
    for m in range(4):
        for c in range(3):
            out[I_OFF + 3 * m + c] = slope * S[m] * nvec[c]


@njit(internal=True)
def _paper_hole_point(paper, qI, LI, xiI, nvec, Dn, ey, Dey, ez, Dez, o, Do, r_b, phi, Y, Yp,
                      Ypp):
    """Wall point ``Q = o + Y(ψ)`` of the paper's detection and its derivative (3, N_EXT): the
    crossing ξ_I, the section ellipse and the 2-D common normal differentiated implicitly
    (docs/theory.md §II.2–§II.3). ``paper`` None: not used by the model (compiled out; not called)."""
    NX = N_EXT
    if paper is None:
        return np.zeros(3), np.zeros((3, NX))
    # ---- crossing: h(ξ_I) = n·(r_I − o) = 0
    SI, dSI, _ = shape_xi(xiI, LI)
    rI, rxI, rxxI = element_point(qI, LI, xiI)
    d = rI - o
    DrI = np.zeros((3, NX))     # partial (at fixed ξ_I) first
    DrxI = np.zeros((3, NX))
    for m in range(4):
        for c in range(3):
            DrI[c, I_OFF + 3 * m + c] = SI[m]
            DrxI[c, I_OFF + 3 * m + c] = dSI[m]
    Dd = DrI - Do
    Dh = np.empty(NX)
    _d_dot(nvec, Dn, d, Dd, Dh)
    hx = nvec[0] * rxI[0] + nvec[1] * rxI[1] + nvec[2] * rxI[2]
    DxiI = -Dh / hx
    for c in range(3):
        for j in range(NX):
            DrI[c, j] += rxI[c] * DxiI[j]
            DrxI[c, j] += rxxI[c] * DxiI[j]
            Dd[c, j] = DrI[c, j] - Do[c, j]
    # ---- ellipse in section coordinates: c = (d·e_y, d·e_z), e_a ∥ (r′·e_y, r′·e_z),
    # a = r_b |r′| / |n·r′| (section_state / section_ellipse, literally)
    cy = d[0] * ey[0] + d[1] * ey[1] + d[2] * ey[2]
    cz = d[0] * ez[0] + d[1] * ez[1] + d[2] * ez[2]
    Dcy = np.empty(NX)
    Dcz = np.empty(NX)
    _d_dot(d, Dd, ey, Dey, Dcy)
    _d_dot(d, Dd, ez, Dez, Dcz)
    ty = rxI[0] * ey[0] + rxI[1] * ey[1] + rxI[2] * ey[2]
    tz = rxI[0] * ez[0] + rxI[1] * ez[1] + rxI[2] * ez[2]
    Dty = np.empty(NX)
    Dtz = np.empty(NX)
    Dtn = np.empty(NX)
    _d_dot(rxI, DrxI, ey, Dey, Dty)
    _d_dot(rxI, DrxI, ez, Dez, Dtz)
    _d_dot(rxI, DrxI, nvec, Dn, Dtn)
    tn = hx
    tp = math.hypot(ty, tz)
    lrx = math.sqrt(rxI[0] * rxI[0] + rxI[1] * rxI[1] + rxI[2] * rxI[2])
    eax = 1.0
    eay = 0.0
    Deax = np.zeros(NX)
    Deay = np.zeros(NX)
    if tp >= 1e-10 * lrx:    # else section_ellipse's circle: e_a = e_y, fixed
        eax = ty / tp
        eay = tz / tp
        for j in range(NX):
            Dtp = (ty * Dty[j] + tz * Dtz[j]) / tp
            Deax[j] = (Dty[j] - eax * Dtp) / tp
            Deay[j] = (Dtz[j] - eay * Dtp) / tp
    b = r_b
    a = r_b * lrx / abs(tn)
    Da = np.zeros(NX)
    if a < b:
        a = b           # clipped (section_state): a constant there
    else:
        sg = 1.0 if tn > 0.0 else -1.0
        for j in range(NX):
            Dlrx = (rxI[0] * DrxI[0, j] + rxI[1] * DrxI[1, j] + rxI[2] * DrxI[2, j]) / lrx
            Da[j] = a * (Dlrx / lrx - sg * Dtn[j] / abs(tn))
    # ---- common normal (docs/theory.md §II.3, §II.6): the ellipse point X(φ) and the wall point
    # Y(ψ) (section coordinates) lie on one normal of the wall, and the ellipse's tangent is
    # normal to it: E1 = (X − Y) × N = 0, E2 = X_φ·N = 0, N = (Y_ψ,z, −Y_ψ,y). For a circle
    # this is X ∥ Y with X·X_φ = 0, i.e. ψ = atan2(X) at a stationary point of ½|X|².
    # X = c + a cosφ e_a + b sinφ e_b, e_b = (−e_ay, e_ax)
    cf = math.cos(phi)
    sf = math.sin(phi)
    X0 = cy + a * cf * eax - b * sf * eay
    X1 = cz + a * cf * eay + b * sf * eax
    Xp0 = -a * sf * eax - b * cf * eay
    Xp1 = -a * sf * eay + b * cf * eax
    Xpp0 = -a * cf * eax + b * sf * eay
    Xpp1 = -a * cf * eay - b * sf * eax
    N0 = Yp[1]
    N1 = -Yp[0]
    Nq0 = Ypp[1]
    Nq1 = -Ypp[0]
    J11 = Xp0 * N1 - Xp1 * N0
    J12 = (Yp[0] * Yp[0] + Yp[1] * Yp[1]) + (X0 - Y[0]) * Nq1 - (X1 - Y[1]) * Nq0
    J21 = Xpp0 * N0 + Xpp1 * N1
    J22 = Xp0 * Nq0 + Xp1 * Nq1
    det = J11 * J22 - J12 * J21
    # at the bifurcation where one contact splits into two (a maximum turning into two maxima
    # and a minimum, docs/theory.md §II.3) the stationary point moves infinitely fast: its
    # ψ-derivative is dropped there (the section force, summed with signs ±1, stays continuous)
    singular = abs(det) <= 1e-12 * (J11 * J11 + J12 * J12 + J21 * J21 + J22 * J22)
    Qd = np.empty(3)
    DQd = np.empty((3, NX))
    for j in range(NX):
        dX0 = Dcy[j] + Da[j] * cf * eax + a * cf * Deax[j] - b * sf * Deay[j]
        dX1 = Dcz[j] + Da[j] * cf * eay + a * cf * Deay[j] + b * sf * Deax[j]
        dXp0 = -Da[j] * sf * eax - a * sf * Deax[j] - b * cf * Deay[j]
        dXp1 = -Da[j] * sf * eay - a * sf * Deay[j] + b * cf * Deax[j]
        dE1 = dX0 * N1 - dX1 * N0
        dE2 = dXp0 * N0 + dXp1 * N1
        dpsi = 0.0 if singular else -(J11 * dE2 - J21 * dE1) / det
        for c in range(3):
            DQd[c, j] = (Do[c, j] + Y[0] * Dey[c, j] + Y[1] * Dez[c, j]
                         + (Yp[0] * ey[c] + Yp[1] * ez[c]) * dpsi)
    for c in range(3):
        Qd[c] = o[c] + Y[0] * ey[c] + Y[1] * ez[c]
    return Qd, DQd


@njit(internal=True)
def _stationary_hole_point(qP, LP, xiP, o, Do, ey, Dey, ez, Dez, Y, Yp, Ypp, pinned):
    """Wall point ``Q = o + Y₁(ψ) e_y + Y₂(ψ) e_z`` of the consistent pair (docs/theory.md §II.4b)
    and its derivative (3, N_EXT): ψ moves with the coordinates by the implicit-function theorem
    on ``r₁ = (x − Q)·x_ξ = 0``, ``r₂ = (x − Q)·Q_ψ = 0`` (x on e_P at ξ_P), ``[Δξ, Δψ] =
    −H⁻¹[∂r₁, ∂r₂]`` with the Hessian H of ``½|x − Q|²`` in (ξ, ψ). No column of a crossing
    element: the pair depends on the body and e_P only. ``pinned``: ξ_P held at the beam's
    end (:func:`~flexmbs.contact.pair.is_pinned`), ψ stationary alone: ``Δψ = −∂r₂/h22``."""
    NX = N_EXT
    SP, dSP, _ = shape_xi(xiP, LP)
    x, rx, rxx = element_point(qP, LP, xiP)
    Qd = np.empty(3)
    Qp = np.empty(3)
    Qpp = np.empty(3)
    for c in range(3):
        Qd[c] = o[c] + Y[0] * ey[c] + Y[1] * ez[c]
        Qp[c] = Yp[0] * ey[c] + Yp[1] * ez[c]
        Qpp[c] = Ypp[0] * ey[c] + Ypp[1] * ez[c]
    u = x - Qd
    h11 = (rx[0] * rx[0] + rx[1] * rx[1] + rx[2] * rx[2]
           + u[0] * rxx[0] + u[1] * rxx[1] + u[2] * rxx[2])
    h12 = -(rx[0] * Qp[0] + rx[1] * Qp[1] + rx[2] * Qp[2])
    h22 = (-(Qp[0] * Qp[0] + Qp[1] * Qp[1] + Qp[2] * Qp[2])
           + u[0] * Qpp[0] + u[1] * Qpp[1] + u[2] * Qpp[2])
    # r₂ = u·Q_ψ: ∂r₂/∂ξ = x_ξ·Q_ψ = −h12, ∂r₂/∂ψ = h22; r₁: ∂/∂ξ = h11, ∂/∂ψ = h12
    det = h11 * h22 + h12 * h12
    singular = abs(det) <= 1e-12 * (h11 * h11 + 2.0 * h12 * h12 + h22 * h22)
    DQd = np.empty((3, NX))
    for j in range(NX):
        dQ0 = Do[0, j] + Y[0] * Dey[0, j] + Y[1] * Dez[0, j]
        dQ1 = Do[1, j] + Y[0] * Dey[1, j] + Y[1] * Dez[1, j]
        dQ2 = Do[2, j] + Y[0] * Dey[2, j] + Y[1] * Dez[2, j]
        dQp0 = Yp[0] * Dey[0, j] + Yp[1] * Dez[0, j]
        dQp1 = Yp[0] * Dey[1, j] + Yp[1] * Dez[1, j]
        dQp2 = Yp[0] * Dey[2, j] + Yp[1] * Dez[2, j]
        dx0 = 0.0
        dx1 = 0.0
        dx2 = 0.0
        drx0 = 0.0
        drx1 = 0.0
        drx2 = 0.0
        if P_OFF <= j < T_OFF:        # e_P's centreline (its twists move no point)
            m = (j - P_OFF) // 3
            c = (j - P_OFF) % 3
            if c == 0:
                dx0 = SP[m]
                drx0 = dSP[m]
            elif c == 1:
                dx1 = SP[m]
                drx1 = dSP[m]
            else:
                dx2 = SP[m]
                drx2 = dSP[m]
        du0 = dx0 - dQ0
        du1 = dx1 - dQ1
        du2 = dx2 - dQ2
        dr1 = du0 * rx[0] + du1 * rx[1] + du2 * rx[2] + u[0] * drx0 + u[1] * drx1 + u[2] * drx2
        dr2 = du0 * Qp[0] + du1 * Qp[1] + du2 * Qp[2] + u[0] * dQp0 + u[1] * dQp1 + u[2] * dQp2
        # [h11, h12; −h12, h22] [Δξ, Δψ] = −[dr1, dr2]
        if pinned:
            dpsi = 0.0 if h22 == 0.0 else -dr2 / h22
        else:
            dpsi = 0.0 if singular else -(h11 * dr2 + h12 * dr1) / det
        DQd[0, j] = dQ0 + Qp[0] * dpsi
        DQd[1, j] = dQ1 + Qp[1] * dpsi
        DQd[2, j] = dQ2 + Qp[2] * dpsi
    return Qd, DQd


@njit
def contact_tangent(qb, vb, u_o, frame, qI, LI, xiI, qP, vP, spin, LP, xiP, phi, Y, Yp, Ypp,
                    r_b, law, fric, hist, approach_velocity, consistent, paper, Qc, K, C,
                    held=False, pinned=False, mouth=0.0):
    """Force and exact tangent of one detected contact.

    ``qb``, ``vb`` (7): hole body; ``u_o`` (3): body coordinates of the section origin;
    ``frame`` (3, 3): the section's axes in body coordinates (columns: plane normal, e_y, e_z;
    the identity for a straight bore along body x, :meth:`flexmbs.contact.joint.Hole.frames`); ``qI``
    (12), ``LI``, ``xiI``: crossing element, its length and the crossing; ``qP``, ``vP``,
    ``LP``, ``xiP``: the element of the closest point and ξ_P (converged), ``spin``
    (:data:`~flexmbs.contact.pair.N_SPIN`) its twists (a rod's surface turns under the
    friction, :func:`~flexmbs.contact.pair.spin_map`; None: no twisted beam in the model, that
    code compiled out); ``phi``: the
    ellipse parameter of the contact; ``Y``, ``Yp``, ``Ypp`` (2): the wall point of the hole
    section at the contact's ψ and its first and second ψ-derivatives (section coordinates, from
    the hole shape's boundary kernel, e.g. :func:`flexmbs.contact.sections.circle_boundary`);
    ``law``, ``fric``, ``hist``, ``approach_velocity`` as in
    :func:`flexmbs.contact.pair.contact_force` (the stick law's trial displacement
    :func:`~flexmbs.contact.pair.stick_trial` differentiated here too); ``consistent``: the
    contact is a stationary pair
    of docs/theory.md §II.4b (:mod:`flexmbs.contact.stationary`; ``qI``, ``xiI``, ``phi`` unused,
    the e_I columns zero), else the paper's 2-D common normal; ``paper`` None: no contact of
    the model uses the paper's (its code compiled out, ``consistent`` then always set). Writes
    ``Qc`` (N_LOCAL) on ``[r_H, p, e_P, φ_P]``, ``K`` (N_LOCAL, N_EXT) = −∂Q_c/∂[r_H, p, e_I,
    e_P, φ_P] and ``C`` (N_LOCAL, N_LOCAL) = −∂Q_c/∂[ṙ_H, ṗ, ė_P, φ̇_P]. ``pinned``: ξ_P is
    held at the beam's end (:func:`~flexmbs.contact.pair.is_pinned`; it does not move with the
    coordinates); ``mouth``: r_b at an end section of an open bore
    (:func:`~flexmbs.contact.laws.mouth_weight`), else 0. Returns ``(g, ġ, f_N)``.
    """
    NX = N_EXT
    p = qb[3:7]
    A = rotation(p)
    Te = _body_basis()
    # body basis b_j (columns of A) and their derivatives 2T(e_j)p
    bx = A[:, 0].copy()
    by = A[:, 1].copy()
    bz = A[:, 2].copy()
    Dbx = np.zeros((3, NX))
    Dby = np.zeros((3, NX))
    Dbz = np.zeros((3, NX))
    unit = np.zeros(3)
    for j in range(3):
        unit[:] = 0.0
        unit[j] = 1.0
        Bj = _t_times(unit, p)
        for c in range(3):
            for i in range(4):
                if j == 0:
                    Dbx[c, 3 + i] = Bj[c, i]
                elif j == 1:
                    Dby[c, 3 + i] = Bj[c, i]
                else:
                    Dbz[c, 3 + i] = Bj[c, i]
    # the section's normal n, e_y, e_z = A frame (T is linear in u: D(A f) = Σ_j f_j D b_j)
    nvec = np.empty(3)
    ey = np.empty(3)
    ez = np.empty(3)
    Dn = np.zeros((3, NX))
    Dey = np.zeros((3, NX))
    Dez = np.zeros((3, NX))
    for c in range(3):
        nvec[c] = bx[c] * frame[0, 0] + by[c] * frame[1, 0] + bz[c] * frame[2, 0]
        ey[c] = bx[c] * frame[0, 1] + by[c] * frame[1, 1] + bz[c] * frame[2, 1]
        ez[c] = bx[c] * frame[0, 2] + by[c] * frame[1, 2] + bz[c] * frame[2, 2]
        for i in range(3, 7):
            Dn[c, i] = Dbx[c, i] * frame[0, 0] + Dby[c, i] * frame[1, 0] + Dbz[c, i] * frame[2, 0]
            Dey[c, i] = Dbx[c, i] * frame[0, 1] + Dby[c, i] * frame[1, 1] + Dbz[c, i] * frame[2, 1]
            Dez[c, i] = Dbx[c, i] * frame[0, 2] + Dby[c, i] * frame[1, 2] + Dbz[c, i] * frame[2, 2]
    # section origin o = r_H + A u_o
    o = np.empty(3)
    Do = np.zeros((3, NX))
    Bo = _t_times(u_o, p)
    for c in range(3):
        o[c] = qb[c] + A[c, 0] * u_o[0] + A[c, 1] * u_o[1] + A[c, 2] * u_o[2]
        Do[c, c] = 1.0
        for i in range(4):
            Do[c, 3 + i] = Bo[c, i]

    if consistent:
        Qd, DQd = _stationary_hole_point(qP, LP, xiP, o, Do, ey, Dey, ez, Dez, Y, Yp, Ypp,
                                         pinned)
    else:
        Qd, DQd = _paper_hole_point(paper, qI, LI, xiI, nvec, Dn, ey, Dey, ez, Dez, o, Do, r_b, phi, Y,
                                    Yp, Ypp)
    # ---- body coordinates u_Q = Aᵀ(Q − r_H) and the body point Q = r_H + A u_Q it acts at
    w = Qd - qb[0:3]
    uQ = np.empty(3)
    DuQ = np.zeros((3, NX))
    for jj in range(3):
        col = bx if jj == 0 else (by if jj == 1 else bz)
        Dcol = Dbx if jj == 0 else (Dby if jj == 1 else Dbz)
        uQ[jj] = col[0] * w[0] + col[1] * w[1] + col[2] * w[2]
        for j in range(NX):
            acc = 0.0
            for c in range(3):
                dw = DQd[c, j] - (1.0 if j == c else 0.0)
                acc += Dcol[c, j] * w[c] + col[c] * dw
            DuQ[jj, j] = acc
    Bp = _t_times(uQ, p)            # W_p = 2T(u_Q)p
    Q = np.empty(3)
    DQ = np.zeros((3, NX))
    for c in range(3):
        Q[c] = qb[c] + A[c, 0] * uQ[0] + A[c, 1] * uQ[1] + A[c, 2] * uQ[2]
        DQ[c, c] = 1.0
        for i in range(4):
            DQ[c, 3 + i] += Bp[c, i]
        for j in range(NX):
            DQ[c, j] += A[c, 0] * DuQ[0, j] + A[c, 1] * DuQ[1, j] + A[c, 2] * DuQ[2, j]
    # ---- closest point: G(ξ) = (r(ξ) − Q)·r′(ξ) = 0 on e_P
    SP, dSP, _ = shape_xi(xiP, LP)
    P, rxP, rxxP = element_point(qP, LP, xiP)
    vPt, vPx, _ = element_point(vP, LP, xiP)      # S(ξ_P) ė_P and S′(ξ_P) ė_P
    dPQ = P - Q
    Gx = (rxP[0] * rxP[0] + rxP[1] * rxP[1] + rxP[2] * rxP[2]
          + dPQ[0] * rxxP[0] + dPQ[1] * rxxP[1] + dPQ[2] * rxxP[2])
    DxiP = np.empty(NX)
    for j in range(NX):
        acc = 0.0
        for c in range(3):
            acc -= DQ[c, j] * rxP[c]
        DxiP[j] = acc
    for m in range(4):
        for c in range(3):
            DxiP[P_OFF + 3 * m + c] += SP[m] * rxP[c] + dPQ[c] * dSP[m]
    for j in range(NX):
        DxiP[j] = 0.0 if pinned else -DxiP[j] / Gx    # pinned: held at the beam's end
    # ---- gap, normal
    u = Q - P
    ell = math.sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2])
    nc = u / ell
    g = ell - r_b
    Du = DQ.copy()
    for j in range(NX):
        for c in range(3):
            Du[c, j] -= rxP[c] * DxiP[j]
    for m in range(4):
        for c in range(3):
            Du[c, P_OFF + 3 * m + c] -= SP[m]
    Dg = np.empty(NX)
    Dnc = np.empty((3, NX))
    for j in range(NX):
        Dg[j] = nc[0] * Du[0, j] + nc[1] * Du[1, j] + nc[2] * Du[2, j]
        for c in range(3):
            Dnc[c, j] = (Du[c, j] - nc[c] * Dg[j]) / ell
    # ---- relative velocity v_Q − v_P = W q̇_c and its q-derivative
    Bv = _t_times(uQ, vb[3:7])      # ∂(2T(u_Q)p ṗ)/∂p = 2T(u_Q)ṗ
    vrel = np.empty(3)
    for c in range(3):
        acc = vb[c] - vPt[c]
        for i in range(4):
            acc += Bp[c, i] * vb[3 + i]
        vrel[c] = acc
    Dvrel = np.zeros((3, NX))
    # through u_Q: 2 pᵀ T_k(e_jj) ṗ per unit vector
    for jj in range(3):
        unit[:] = 0.0
        unit[jj] = 1.0
        Bj = _t_times(unit, p)
        for c in range(3):
            s = 0.0
            for i in range(4):
                s += Bj[c, i] * vb[3 + i]
            for j in range(NX):
                Dvrel[c, j] += s * DuQ[jj, j]
    for c in range(3):
        for i in range(4):
            Dvrel[c, 3 + i] += Bv[c, i]
        for j in range(NX):
            Dvrel[c, j] -= vPx[c] * DxiP[j]
    gdot = nc[0] * vrel[0] + nc[1] * vrel[1] + nc[2] * vrel[2]
    Dgdot = np.empty(NX)
    _d_dot(nc, Dnc, vrel, Dvrel, Dgdot)
    # W (3, N_LOCAL) on [r_H, p, e_P] and ∂ġ/∂q̇ = nᵀW
    W = contact_map(Bp, SP)
    Bn = np.empty(N_LOCAL)
    for j in range(N_LOCAL):
        Bn[j] = nc[0] * W[0, j] + nc[1] * W[1, j] + nc[2] * W[2, j]
    # ---- force F_H = f n + F_t
    f, kt, ct = held_law_force(law, -g, -gdot, approach_velocity, held, mouth)
    Df = np.empty(NX)
    for j in range(NX):
        Df[j] = -kt * Dg[j] - ct * Dgdot[j]
    F = np.empty(3)
    DF = np.empty((3, NX))
    dFv = np.zeros((3, N_LOCAL))     # ∂F_H/∂q̇_c
    for c in range(3):
        F[c] = f * nc[c]
        for j in range(NX):
            DF[c, j] = Df[j] * nc[c] + f * Dnc[c, j]
        for j in range(N_LOCAL):
            dFv[c, j] = -ct * Bn[j] * nc[c]
    Wf = W                 # the friction map: W and, on a rod, the surface's turn
    on = False
    if spin is not None:    # None: no twisted beam in the model (compiled out)
        on = fric[0] != FRICTION_NONE and f > 0.0 and spin[0] != 0.0
    b = np.zeros((2, 3))
    db = np.zeros((2, 3, 3))
    sv = np.zeros(3)
    Ds = np.zeros((3, NX))
    DN = np.zeros((2, NX))
    Na = np.array([1.0 - xiP, xiP])
    if spin is not None and on:
        # s = t × n, ω = Σ N_a (φ̇_a + w_a) and their derivatives (pair.spin_map)
        Wf = W.copy()
        w_s = np.empty(2)
        dw_s = np.empty((2, 3))
        omega, sv = spin_map(spin, qP, vP, xiP, r_b, rxP, nc, Wf, b, db, w_s, dw_s)
        nr = math.sqrt(rxP[0] * rxP[0] + rxP[1] * rxP[1] + rxP[2] * rxP[2])
        tP = rxP / nr
        Drx = np.zeros((3, NX))
        for c in range(3):
            for j in range(NX):
                Drx[c, j] = rxxP[c] * DxiP[j]
        for m in range(4):
            for c in range(3):
                Drx[c, P_OFF + 3 * m + c] += dSP[m]
        Dt = np.empty((3, NX))
        for j in range(NX):
            tD = tP[0] * Drx[0, j] + tP[1] * Drx[1, j] + tP[2] * Drx[2, j]
            for c in range(3):
                Dt[c, j] = (Drx[c, j] - tP[c] * tD) / nr
        for j in range(NX):
            Ds[0, j] = (Dt[1, j] * nc[2] - Dt[2, j] * nc[1] + tP[1] * Dnc[2, j]
                        - tP[2] * Dnc[1, j])
            Ds[1, j] = (Dt[2, j] * nc[0] - Dt[0, j] * nc[2] + tP[2] * Dnc[0, j]
                        - tP[0] * Dnc[2, j])
            Ds[2, j] = (Dt[0, j] * nc[1] - Dt[1, j] * nc[0] + tP[0] * Dnc[1, j]
                        - tP[1] * Dnc[0, j])
            DN[0, j] = -DxiP[j]
            DN[1, j] = DxiP[j]
        Domega = np.zeros(NX)
        for a in range(2):
            om_a = spin[3 + a] + w_s[a]
            for j in range(NX):
                Domega[j] += DN[a, j] * om_a
            for c in range(3):
                Domega[P_OFF + 6 * a + 3 + c] += Na[a] * dw_s[a, c]
        # the surface's velocity −r_b ω s joins v_Q − v_P (⟂ n: ġ_N is unchanged)
        for c in range(3):
            vrel[c] -= r_b * omega * sv[c]
            for j in range(NX):
                Dvrel[c, j] -= r_b * (Domega[j] * sv[c] + omega * Ds[c, j])
    if fric[0] != FRICTION_NONE and f > 0.0:
        vn = gdot
        vt = vrel - vn * nc
        Dvt = np.empty((3, NX))
        for c in range(3):
            for j in range(NX):
                Dvt[c, j] = Dvrel[c, j] - Dnc[c, j] * vn - nc[c] * Dgdot[j]
        d = np.zeros(3)
        Dd = np.zeros((3, NX))
        if fric[0] == FRICTION_STICK:
            # Δ = A d_A + (Q − P) − (Q_n − P_n) + turn, d = (I − nnᵀ)Δ (pair.stick_trial) and
            # DΔ: D(A d_A) = 2T(d_A)p, D(Q − P) = Du, DQ_n = A_n Du_Q, DP_n = r′_n(ξ_P) Dξ_P,
            # D turn = −r_b (Ds Δψ + s DΔψ) (pair.twist_increment)
            turn = np.zeros(3)
            Dturn = np.zeros((3, NX))
            if spin is not None and on:
                bbar = np.empty((2, 3))
                dg = np.empty((2, 3))
                dpsi = twist_increment(spin, hist, qP, xiP, b, bbar, dg)
                Dpsi = np.zeros(NX)
                for a in range(2):
                    psi_a = spin[1 + a] - hist[HIST_TWIST + a]
                    for c in range(3):
                        psi_a += bbar[a, c] * dg[a, c]
                    for j in range(NX):
                        Dpsi[j] += DN[a, j] * psi_a
                    Dpsi[T_OFF + a] += Na[a]
                    for c in range(3):
                        acc = bbar[a, c]
                        for k in range(3):
                            acc += 0.5 * db[a, k, c] * dg[a, k]
                        Dpsi[P_OFF + 6 * a + 3 + c] += Na[a] * acc
                for c in range(3):
                    turn[c] = -r_b * dpsi * sv[c]
                    for j in range(NX):
                        Dturn[c, j] = -r_b * (Ds[c, j] * dpsi + sv[c] * Dpsi[j])
            delta = np.empty(3)
            stick_trial(A, hist, uQ, Q, P, SP, nc, turn, delta, d)
            An = rotation(hist[7:11])
            _, rxn, _ = element_point(hist[11:], LP, xiP)
            Bd = _t_times(hist[0:3], p)
            Ddelta = np.empty((3, NX))
            for c in range(3):
                for j in range(NX):
                    Ddelta[c, j] = (Du[c, j] + rxn[c] * DxiP[j]
                                    - An[c, 0] * DuQ[0, j] - An[c, 1] * DuQ[1, j]
                                    - An[c, 2] * DuQ[2, j])
                for i in range(4):
                    Ddelta[c, 3 + i] += Bd[c, i]
                for j in range(NX):
                    Ddelta[c, j] += Dturn[c, j]
            ndel = nc[0] * delta[0] + nc[1] * delta[1] + nc[2] * delta[2]
            Dndel = np.empty(NX)
            _d_dot(nc, Dnc, delta, Ddelta, Dndel)
            for c in range(3):
                for j in range(NX):
                    Dd[c, j] = Ddelta[c, j] - Dnc[c, j] * ndel - nc[c] * Dndel[j]
        Ft = np.empty(3)
        dF_dd = np.empty((3, 3))
        dF_dv = np.empty((3, 3))
        dF_dfn = np.empty(3)
        d_new = np.empty(3)
        tangential_force(fric, hist[3], f, d, vt, Ft, dF_dd, dF_dv, dF_dfn, d_new)
        # ∂v_t/∂q̇_c = (I − n nᵀ) W_f
        PW = np.empty((3, N_LOCAL))
        for c in range(3):
            for j in range(N_LOCAL):
                PW[c, j] = Wf[c, j] - nc[c] * Bn[j]
        for c in range(3):
            F[c] += Ft[c]
            for j in range(NX):
                acc = dF_dfn[c] * Df[j]
                for e in range(3):
                    acc += dF_dv[c, e] * Dvt[e, j] + dF_dd[c, e] * Dd[e, j]
                DF[c, j] += acc
            for j in range(N_LOCAL):
                acc = dF_dfn[c] * (-ct * Bn[j])
                for e in range(3):
                    acc += dF_dv[c, e] * PW[e, j]
                dFv[c, j] += acc
    # ---- generalized force Q_c = W_fᵀ F_H and K = −∂Q_c/∂q, C = −∂Q_c/∂q̇
    for j in range(N_LOCAL):
        Qc[j] = Wf[0, j] * F[0] + Wf[1, j] * F[1] + Wf[2, j] * F[2]
    for a_ in range(N_LOCAL):
        for j in range(NX):
            K[a_, j] = -(Wf[0, a_] * DF[0, j] + Wf[1, a_] * DF[1, j] + Wf[2, a_] * DF[2, j])
        for j in range(N_LOCAL):
            C[a_, j] = -(Wf[0, a_] * dFv[0, j] + Wf[1, a_] * dFv[1, j] + Wf[2, a_] * dFv[2, j])
    if on:
        # W_f's turn columns depend on q: σ_a = −r_b N_a s·F on twist a, b_a σ_a on slope a
        sF = sv[0] * F[0] + sv[1] * F[1] + sv[2] * F[2]
        for a in range(2):
            sigma = -r_b * Na[a] * sF
            for j in range(NX):
                Dsig = -r_b * (DN[a, j] * sF + Na[a] * (Ds[0, j] * F[0] + Ds[1, j] * F[1]
                                                          + Ds[2, j] * F[2]))
                K[TWIST_OFF + a, j] -= Dsig
                for c in range(3):
                    K[7 + 6 * a + 3 + c, j] -= b[a, c] * Dsig
            for c in range(3):
                for k in range(3):
                    K[7 + 6 * a + 3 + c, P_OFF + 6 * a + 3 + k] -= db[a, c, k] * sigma
    # W_p = 2T(u_Q)p depends on p and on u_Q: (W_pᵀF)_i = 2 Σ_k F_k (T_k(u_Q) p)_i
    for i in range(4):
        for m in range(4):
            acc = 0.0
            for k in range(3):
                for jj in range(3):
                    acc += F[k] * uQ[jj] * Te[jj, k, i, m]
            K[3 + i, 3 + m] -= 2.0 * acc
        for jj in range(3):
            acc = 0.0
            for k in range(3):
                for m in range(4):
                    acc += F[k] * Te[jj, k, i, m] * p[m]
            for j in range(NX):
                K[3 + i, j] -= 2.0 * acc * DuQ[jj, j]
    # W_e = −S(ξ_P) depends on ξ_P
    for m in range(4):
        for c in range(3):
            for j in range(NX):
                K[7 + 3 * m + c, j] += dSP[m] * F[c] * DxiP[j]
    return g, gdot, f

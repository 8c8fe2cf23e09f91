"""The sections of a flexible tube: a hole section carried by a beam at a material station
(docs/theory.md §II.9).

A tube's section k sits at the station ``ξ_k`` of the outer beam's element ``e_k``; its pose is
that of a body, ``b = [r, p]`` (7), so that the contact kernels of a rigid bore
(:mod:`flexmbs.contact.pair`, :mod:`flexmbs.contact.tangent`) serve it unchanged:

- ``r = S(ξ_k) e`` the centreline point;
- ``p = h(x) ⊗ p̄`` with ``x = S_ξ(ξ_k) e`` the centreline's tangent, ``h(x)`` the smallest
  rotation taking the section's base tangent ``t̄`` to ``x/|x|`` and ``p̄`` the section's base
  frame (Euler parameters, ``A(p̄) e_x = t̄``): the section's plane stays normal to the tube and
  its in-plane axes are carried along without spin (a cable has no twist to turn them);
- on a rod, ``p = h(x) ⊗ R(t̄, ψ) ⊗ p̄``: the section turns about its tangent by ψ, the angle from
  the carried axis ``SR(t̄ → t) ȳ`` to the rod's director ``d2(ξ_k)`` (``ȳ = A(p̄) e_y``, the
  director when the base was taken; :func:`section_turn`), so that a lumen that is not round
  turns with the rod's twist, and the wall's velocity carries the rod's spin. ψ depends on the
  element's centreline and both nodal twists (``e`` then has :data:`SECTION_COORDS`).

With ``ℓ = |x|``, ``a = ℓ + t̄·x``, ``w = t̄ × x``: ``h = (a, w) / √(2ℓa)``, a unit quaternion
whenever ``x`` is not opposite to ``t̄`` (:data:`REBASE_COS` keeps it away: after a step whose
tangent turned further, or a rod's section turned by more than :data:`REBASE_TURN`, the section
takes its current frame as its base, :func:`rebase`, which leaves its pose unchanged).

The generalized force of a contact on the tube's element is ``Jᵀ λ`` with ``J = ∂b/∂e`` and
``λ`` the contact's force on ``b``; its tangent adds ``−Σ_i λ_i ∂²b_i/∂e²`` (only ``p`` is not
linear in ``e``) and, through the pose's rate ``ḃ = J ė``, the term ``C_b ∂(J ė)/∂e``
(:func:`pose_curvature`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from .._jit import njit
from ..elements.ancf_rod import LAYOUT as ROD_LAYOUT
from ..elements.ancf_rod import TurnWork, director_turn_at
from ..elements.hermite import CENTERLINE_SIZE, hermite_basis
from ..elements.layout import ElementLayout

__all__ = ["POSE_SIZE", "REBASE_COS", "REBASE_TURN", "POSE_WORK", "SECTION_COORDS", "TURN_SIZE",
           "ROD_ORDER", "TubeSections", "section_pose", "pose_curvature", "rebase",
           "section_turn", "section_order", "tube_pose", "quaternion_after"]

#: coordinates of a section's pose ``[r (3), p (4)]`` (a rigid body's)
POSE_SIZE = 7
#: a section whose tangent turned by more than 60° from its base tangent takes a new base after
#: the step (:func:`rebase`); the carried rotation is singular only at 180°
REBASE_COS = 0.5
#: a rod tube's section turned by more than this about its tangent (its ψ, :func:`section_turn`)
#: takes a new base after the step: ψ = β + ξΔθ with β an atan2, which jumps at ±π, so β stays
#: within π/4 + |Δθ| of 0 (an element twisted by less than 135°)
REBASE_TURN = 0.25 * math.pi
#: the coordinates a section's pose depends on: its element's centreline (CENTERLINE_SIZE) and,
#: on a rod, the twists of its two nodes after them (a cable's section leaves those out)
SECTION_COORDS = CENTERLINE_SIZE + 2


def section_order(layout: ElementLayout) -> np.ndarray:
    """An element's coordinates in the order of a section's: its centreline, then its nodes'
    twists if it has them (``e = q_e[section_order(layout)]``)."""
    order = [np.asarray(layout.centerline, np.int64)]
    if layout.twist is not None:
        order.append(np.arange(layout.nodes_per_element, dtype=np.int64) * layout.node_size
                     + layout.twist)
    return np.concatenate(order)


#: the rod element's coordinates in the order of a section's (``e = q_e[ROD_ORDER]``)
ROD_ORDER = section_order(ROD_LAYOUT)
#: a section's turn ``[ψ, ∂ψ/∂e (SECTION_COORDS), ∂²ψ/∂e² (SECTION_COORDS²)]``
TURN_SIZE = 1 + SECTION_COORDS + SECTION_COORDS * SECTION_COORDS
#: float work of :func:`section_pose`, :func:`pose_curvature` and :func:`rebase`: x, ẋ (3 each),
#: h (4), ∂h (4, 3), ∂²h (4, 3, 3), the product matrix (4, 4), μ (4), H_x (3, 3), the turned
#: base c and ∂c/∂ψ and (0, t̄) ⊗ p̄ (4 each), M(∂c/∂ψ) (4, 4), M(∂c/∂ψ) h and ν (4 each), a
#: vector over the section coordinates
POSE_WORK = 3 + 3 + 4 + 12 + 36 + 16 + 4 + 9 + 12 + 16 + 8 + SECTION_COORDS


@njit(inline="always")
def _carve(work):
    """The work arrays of :data:`POSE_WORK` (views, nothing allocated)."""
    x = work[0:3]
    xd = work[3:6]
    h = work[6:10]
    Dh = work[10:22].reshape((4, 3))
    D2h = work[22:58].reshape((4, 3, 3))
    M = work[58:74].reshape((4, 4))
    mu = work[74:78]
    Hx = work[78:87].reshape((3, 3))
    return x, xd, h, Dh, D2h, M, mu, Hx


@njit(inline="always")
def _carve_turn(work):
    """The work arrays of a rod section's turn (after :func:`_carve`'s; views): the turned base
    c and ∂c/∂ψ, (0, t̄) ⊗ p̄, M(∂c/∂ψ), M(∂c/∂ψ) h, ν, a vector over the section coordinates.
    Apart from :func:`_carve`, so that a cable's section does not build them."""
    c = work[87:91]
    dc = work[91:95]
    sb = work[95:99]
    Md = work[99:115].reshape((4, 4))
    Mdh = work[115:119]
    nu = work[119:123]
    hv = work[123:123 + SECTION_COORDS]
    return c, dc, sb, Md, Mdh, nu, hv


@njit(inline="always")
def _right_product(p0, M):
    """``M`` (4, 4) with ``M h = h ⊗ p̄`` (Hamilton product; ``A(h ⊗ p̄) = A(h) A(p̄)``)."""
    s, a, b, c = p0[0], p0[1], p0[2], p0[3]
    M[0, 0], M[0, 1], M[0, 2], M[0, 3] = s, -a, -b, -c
    M[1, 0], M[1, 1], M[1, 2], M[1, 3] = a, s, c, -b
    M[2, 0], M[2, 1], M[2, 2], M[2, 3] = b, -c, s, a
    M[3, 0], M[3, 1], M[3, 2], M[3, 3] = c, b, -a, s


@njit
def quaternion_after(h, p0, out):
    """``out = h ⊗ p̄`` (the rotation ``A(p̄)`` followed by ``A(h)``)."""
    s, a, b, c = p0[0], p0[1], p0[2], p0[3]
    h0, h1, h2, h3 = h[0], h[1], h[2], h[3]
    out[0] = s * h0 - a * h1 - b * h2 - c * h3
    out[1] = a * h0 + s * h1 + c * h2 - b * h3
    out[2] = b * h0 - c * h1 + s * h2 + a * h3
    out[3] = c * h0 + b * h1 - a * h2 + s * h3


@njit
def _carried(x, t_bar, h, Dh, D2h, second):
    """The smallest rotation ``h`` (4) from ``t̄`` to ``x/|x|``, its derivative ``Dh`` (4, 3)
    and, with ``second``, its second derivative ``D2h`` (4, 3, 3) with respect to ``x``."""
    ell = math.sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2])
    a = ell + t_bar[0] * x[0] + t_bar[1] * x[1] + t_bar[2] * x[2]
    if not ell > 0.0 or not a > 1e-12 * ell:
        # no tangent (a folded element), or one turned back onto −t̄: no smallest rotation. An
        # iterate, never a state (the bases are renewed long before): NaN, which the Newton
        # loops reject (the step is cut), instead of a division by zero in compiled code
        h[:] = math.nan
        Dh[:] = math.nan
        if second:
            D2h[:] = math.nan
        return
    u0, u1, u2 = x[0] / ell, x[1] / ell, x[2] / ell
    u = (u0, u1, u2)
    w = (t_bar[1] * x[2] - t_bar[2] * x[1], t_bar[2] * x[0] - t_bar[0] * x[2],
         t_bar[0] * x[1] - t_bar[1] * x[0])
    f = 1.0 / math.sqrt(2.0 * ell * a)
    # ∂a = u + t̄; ∂w_i/∂x_j = [t̄]×_ij; g = ∂(ℓa) = a u + ℓ (u + t̄); ∂f = −f³ g
    da = (u0 + t_bar[0], u1 + t_bar[1], u2 + t_bar[2])
    Wx = ((0.0, -t_bar[2], t_bar[1]), (t_bar[2], 0.0, -t_bar[0]), (-t_bar[1], t_bar[0], 0.0))
    g = (a * u0 + ell * da[0], a * u1 + ell * da[1], a * u2 + ell * da[2])
    f3 = f * f * f
    df = (-f3 * g[0], -f3 * g[1], -f3 * g[2])
    h[0] = a * f
    for i in range(3):
        h[1 + i] = w[i] * f
    for j in range(3):
        Dh[0, j] = f * da[j] + a * df[j]
        for i in range(3):
            Dh[1 + i, j] = f * Wx[i][j] + w[i] * df[j]
    if not second:
        return
    # ∂²ℓ = ∂²a = P/ℓ (P = I − u uᵀ); ∂g = (a/ℓ + 1) P + u (∂a)ᵀ + (∂a) uᵀ;
    # ∂²f = 3 f⁵ g gᵀ − f³ ∂g
    f5 = f3 * f * f
    for j in range(3):
        for k in range(3):
            P = (1.0 if j == k else 0.0) - u[j] * u[k]
            dg = (a / ell + 1.0) * P + u[j] * da[k] + da[j] * u[k]
            d2f = 3.0 * f5 * g[j] * g[k] - f3 * dg
            d2a = P / ell
            D2h[0, j, k] = f * d2a + da[j] * df[k] + df[j] * da[k] + a * d2f
            for i in range(3):
                D2h[1 + i, j, k] = Wx[i][j] * df[k] + df[j] * Wx[i][k] + w[i] * d2f


@njit(inline="always")
def _turned(p0, t_bar, psi, c, dc, sb):
    """The base frame turned by ψ about the base tangent, ``c = R(t̄, ψ) ⊗ p̄`` (4), and
    ``dc = ∂c/∂ψ``; ``sb = (0, t̄) ⊗ p̄`` work (a rod's section; a cable's does not turn)."""
    sb[0] = 0.0
    for a in range(3):
        sb[1 + a] = t_bar[a]
    quaternion_after(sb, p0, sb)
    co = math.cos(0.5 * psi)
    si = math.sin(0.5 * psi)
    for a in range(4):
        c[a] = co * p0[a] + si * sb[a]
        dc[a] = 0.5 * (co * sb[a] - si * p0[a])


@njit(inline="always")
def _base_product(p0, t_bar, psi, turns, M, work):
    """``M`` (4, 4) with ``M h = h ⊗ c``: ``c = R(t̄, ψ) ⊗ p̄`` the section's base turned by ψ (a
    rod's section, ``turns``; its ``c``, ``∂c/∂ψ`` into the turn's work, :func:`_carve_turn`)
    or ``c = p̄`` (a cable's)."""
    if turns:
        c, dc, sb, _, _, _, _ = _carve_turn(work)
        _turned(p0, t_bar, psi, c, dc, sb)
        _right_product(c, M)
    else:
        _right_product(p0, M)


@njit
def section_pose(e, width, length, xi, t_bar, p0, turn, ve, pose, vel, J, work):
    """Pose ``b = [r, p]`` (7) of the section at station ``xi`` of the element with section
    coordinates ``e`` (its ``width`` first: the centreline's CENTERLINE_SIZE, a rod's nodal twists
    after them; :data:`SECTION_COORDS`), base tangent ``t̄`` and base frame ``p̄``, turned by a
    rod's ``turn`` (:data:`TURN_SIZE`: ψ, ∂ψ/∂e, ∂²ψ/∂e², :func:`section_turn`; read only for a
    rod); its rate ``ḃ`` (from the rates ``ve``) and ``J = ∂b/∂e`` (7, SECTION_COORDS) (module
    docstring); ``work`` (:data:`POSE_WORK`)."""
    S, dS, _, _ = hermite_basis(xi, length)
    x, xd, h, Dh, D2h, M, _, _ = _carve(work)
    turns = width > CENTERLINE_SIZE
    for cc in range(3):
        r = 0.0
        rd = 0.0
        xc = 0.0
        xdc = 0.0
        for m in range(4):
            r += S[m] * e[3 * m + cc]
            rd += S[m] * ve[3 * m + cc]
            xc += dS[m] * e[3 * m + cc]
            xdc += dS[m] * ve[3 * m + cc]
        pose[cc] = r
        vel[cc] = rd
        x[cc] = xc
        xd[cc] = xdc
    _carried(x, t_bar, h, Dh, D2h, False)
    _base_product(p0, t_bar, turn[0], turns, M, work)
    for i in range(POSE_SIZE):
        for j in range(width):
            J[i, j] = 0.0
    for a in range(4):
        pa = 0.0
        for b in range(4):
            pa += M[a, b] * h[b]
        pose[3 + a] = pa
    for a in range(4):
        for cc in range(3):
            MD = 0.0
            for b in range(4):
                MD += M[a, b] * Dh[b, cc]
            for m in range(4):
                J[3 + a, 3 * m + cc] = MD * dS[m]
    if turns:                        # + M(c′) h ∂ψ/∂e
        _, dc, _, Md, Mdh, _, _ = _carve_turn(work)
        _right_product(dc, Md)
        g = turn[1:1 + SECTION_COORDS]
        for a in range(4):
            s = 0.0
            for b in range(4):
                s += Md[a, b] * h[b]
            Mdh[a] = s
            for j in range(width):
                J[3 + a, j] += s * g[j]
    for cc in range(3):
        for m in range(4):
            J[cc, 3 * m + cc] = S[m]
    for a in range(4):
        s = 0.0
        for j in range(width):
            s += J[3 + a, j] * ve[j]
        vel[3 + a] = s


@njit
def pose_curvature(e, width, length, xi, t_bar, p0, turn, ve, lam, H, G, work):
    """The pose's second-order terms at the section of :func:`section_pose` (``turn`` with its
    Hessian): ``H = Σ_i λ_i ∂²b_i/∂e²`` (SECTION_COORDS, SECTION_COORDS) for the force ``λ`` (7)
    on ``b``, and ``G = ∂(J ė)/∂e`` (7, SECTION_COORDS), the pose rate's derivative at fixed
    ``ė`` (its ``r`` rows are 0: ``r`` is linear in ``e``); ``work`` (:data:`POSE_WORK`).

    With ``p = M(c(ψ)) h(x)`` (``M`` linear, ``c″ = −c/4``), ``μ = M(c)ᵀ λ_p``,
    ``ν = M(c′)ᵀ λ_p``, ``X = ∂x/∂e``, ``g = ∂ψ/∂e``: ``H = Xᵀ (Σ μ_b ∂²h_b) X + X̃ gᵀ + g X̃ᵀ
    − (μ·h/4) g gᵀ + (ν·h) ∂²ψ/∂e²`` with ``X̃ = Xᵀ ∂hᵀ ν``."""
    _, dS, _, _ = hermite_basis(xi, length)
    x, xd, h, Dh, D2h, M, mu, Hx = _carve(work)
    turns = width > CENTERLINE_SIZE
    for cc in range(3):
        xc = 0.0
        xdc = 0.0
        for m in range(4):
            xc += dS[m] * e[3 * m + cc]
            xdc += dS[m] * ve[3 * m + cc]
        x[cc] = xc
        xd[cc] = xdc
    _carried(x, t_bar, h, Dh, D2h, True)
    _base_product(p0, t_bar, turn[0], turns, M, work)
    for b in range(4):                    # μ = Mᵀ λ_p
        mu[b] = 0.0
        for a in range(4):
            mu[b] += M[a, b] * lam[3 + a]
    for cc in range(3):
        for d in range(3):
            Hx[cc, d] = 0.0
            for b in range(4):
                Hx[cc, d] += mu[b] * D2h[b, cc, d]
    for i in range(SECTION_COORDS):
        for j in range(SECTION_COORDS):
            H[i, j] = 0.0
    for m in range(4):
        for n in range(4):
            w = dS[m] * dS[n]
            for cc in range(3):
                for d in range(3):
                    H[3 * m + cc, 3 * n + d] = w * Hx[cc, d]
    for i in range(POSE_SIZE):
        for j in range(SECTION_COORDS):
            G[i, j] = 0.0
    for a in range(4):
        for d in range(3):
            s = 0.0
            for b in range(4):
                t = 0.0
                for cc in range(3):
                    t += D2h[b, cc, d] * xd[cc]
                s += M[a, b] * t
            for n in range(4):
                G[3 + a, 3 * n + d] = s * dS[n]
    if not turns:
        return
    _, dc, _, Md, _, nu, hv = _carve_turn(work)
    g = turn[1:1 + SECTION_COORDS]
    Hpsi = turn[1 + SECTION_COORDS:1 + SECTION_COORDS * (1 + SECTION_COORDS)].reshape(
        (SECTION_COORDS, SECTION_COORDS))
    _right_product(dc, Md)
    muh = 0.0
    nuh = 0.0
    for b in range(4):                    # ν = M(c′)ᵀ λ_p
        nu[b] = 0.0
        for a in range(4):
            nu[b] += Md[a, b] * lam[3 + a]
        muh += mu[b] * h[b]
        nuh += nu[b] * h[b]
    for cc in range(3):                   # ∂hᵀ ν, then X̃ = Xᵀ ∂hᵀ ν into hv
        s = 0.0
        for b in range(4):
            s += Dh[b, cc] * nu[b]
        for m in range(4):
            hv[3 * m + cc] = dS[m] * s
    for j in range(CENTERLINE_SIZE, width):
        hv[j] = 0.0
    for i in range(width):
        for j in range(width):
            H[i, j] += hv[i] * g[j] + g[i] * hv[j] - 0.25 * muh * g[i] * g[j] + nuh * Hpsi[i, j]
    # G += M(c′) ∂h ẋ gᵀ − ¼ p ψ̇ gᵀ + ψ̇ M(c′) ∂h X + M(c′) h (∂²ψ/∂e² ė)ᵀ
    psid = 0.0
    for j in range(width):
        psid += g[j] * ve[j]
    for j in range(width):               # ∂²ψ/∂e² ė into hv
        s = 0.0
        for i in range(width):
            s += Hpsi[j, i] * ve[i]
        hv[j] = s
    for a in range(4):
        Mdh_a = 0.0
        MdDx = 0.0
        p_a = 0.0
        for b in range(4):
            Mdh_a += Md[a, b] * h[b]
            p_a += M[a, b] * h[b]
            for cc in range(3):
                MdDx += Md[a, b] * Dh[b, cc] * xd[cc]
        for j in range(width):
            G[3 + a, j] += (MdDx - 0.25 * p_a * psid) * g[j] + Mdh_a * hv[j]
        for cc in range(3):
            s = 0.0
            for b in range(4):
                s += Md[a, b] * Dh[b, cc]
            for m in range(4):
                G[3 + a, 3 * m + cc] += psid * s * dS[m]


@njit
def rebase(e, width, length, xi, t_bar, p0, psi, work):
    """After a converged step: a section whose tangent turned more than ``acos(REBASE_COS)``
    from its base tangent, or (a rod's) turned by more than :data:`REBASE_TURN` about it, takes
    its current tangent and frame as its base (``t_bar``, ``p0`` updated in place; the pose is
    unchanged, and ψ is 0 on the new base); ``psi`` the section's turn (0 for a cable);
    ``work`` (:data:`POSE_WORK`). Returns whether it did."""
    _, dS, _, _ = hermite_basis(xi, length)
    x, _, h, Dh, D2h, M, p, _ = _carve(work)
    for cc in range(3):
        s = 0.0
        for m in range(4):
            s += dS[m] * e[3 * m + cc]
        x[cc] = s
    ell = math.sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2])
    if ((x[0] * t_bar[0] + x[1] * t_bar[1] + x[2] * t_bar[2]) >= REBASE_COS * ell
            and abs(psi) <= REBASE_TURN):
        return False
    _carried(x, t_bar, h, Dh, D2h, False)
    _base_product(p0, t_bar, psi, width > CENTERLINE_SIZE, M, work)
    for a in range(4):                    # the current frame h ⊗ c
        p[a] = 0.0
        for b in range(4):
            p[a] += M[a, b] * h[b]
    norm = math.sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3])
    for a in range(4):
        p0[a] = p[a] / norm
    for cc in range(3):
        t_bar[cc] = x[cc] / ell
    return True


@njit
def section_turn(e, width, length, xi, t_bar, p0, node_t, node_d, tw, turn, second):
    """``turn`` (:data:`TURN_SIZE`) = ψ, ∂ψ/∂e and, with ``second``, ∂²ψ/∂e² of a rod tube's
    section (section coordinates ``e``, :data:`SECTION_COORDS`; the element's nodal bases
    ``node_t``, ``node_d`` (2, 3)): the turn of the rod's director at the station from the frame
    carried without spin from the section's base (t̄, and ȳ = A(p̄) e_y, the director at the
    base), :func:`~flexmbs.elements.ancf_rod.director_turn_at`. A cable's section
    (``width`` the centreline's) has none: ψ = 0. ``tw``: a rod's
    :class:`~flexmbs.elements.ancf_rod.TurnWork`. Returns ψ."""
    if tw is None:
        turn[0] = 0.0
        return 0.0
    if width <= CENTERLINE_SIZE:
        turn[0] = 0.0
        return 0.0
    q_e, grad, hess = tw.q_e, tw.grad, tw.hess
    for i in range(SECTION_COORDS):
        q_e[ROD_ORDER[i]] = e[i]
    y = tw.p[4:7]       # scratch until director_turn_at writes its parameters: ȳ = A(p̄) e_y
    s0, s1, s2, s3 = p0[0], p0[1], p0[2], p0[3]
    y0 = 2.0 * (s1 * s2 - s0 * s3)
    y1 = s0 * s0 - s1 * s1 + s2 * s2 - s3 * s3
    y2 = 2.0 * (s2 * s3 + s0 * s1)
    y[0], y[1], y[2] = y0, y1, y2
    psi = director_turn_at(q_e, length, node_t, node_d, xi, t_bar, y, tw, grad, hess, second)
    turn[0] = psi
    for i in range(SECTION_COORDS):
        turn[1 + i] = grad[ROD_ORDER[i]]
    if second:
        o = 1 + SECTION_COORDS
        for i in range(SECTION_COORDS):
            for j in range(SECTION_COORDS):
                turn[o + i * SECTION_COORDS + j] = hess[ROD_ORDER[i], ROD_ORDER[j]]
    return psi


@njit(inline="always")
def tube_pose(e, width, length, xi, t_bar, p0, node_t, node_d, tw, turn, ve, pose, vel, J, work):
    """A section's pose, rate and ``J`` from its element's coordinates ``e`` and rates ``ve``:
    its turn (:func:`section_turn`, first order, into ``turn``), then :func:`section_pose`. The
    compiled step and the Python paths place sections through this one function."""
    if width > CENTERLINE_SIZE:      # a cable's section does not turn: no call
        section_turn(e, width, length, xi, t_bar, p0, node_t, node_d, tw, turn, False)
    else:
        turn[0] = 0.0
    section_pose(e, width, length, xi, t_bar, p0, turn, ve, pose, vel, J, work)


class TubeSections(NamedTuple):
    """The sections of the clearance joints whose bore is a flexible tube (a field of
    :class:`~flexmbs.contact.clearance_term.ClearancePart`; None there when no joint of the
    model has one, so that none of this is compiled for it)."""

    on: np.ndarray          # (nj,) the joint's sections ride a beam
    width: np.ndarray       # (nj,) their section coordinates: CENTERLINE_SIZE on a cable,
                            # SECTION_COORDS on a rod (whose sections turn)
    dofs: np.ndarray        # (nj, max_ns, SECTION_COORDS) their element's section coordinates
    length: np.ndarray      # (nj, max_ns) the element's length
    xi: np.ndarray          # (nj, max_ns) the section's station on it
    t_bar: np.ndarray       # (nj, max_ns, 3) state: base tangents (rebase)
    p0: np.ndarray          # (nj, max_ns, 4) state: base frames
    row: np.ndarray         # (nj, max_ns) the window row of the section's element: its rank
                            # among the joint's tube elements (the plan follows each apart)
    node_t: np.ndarray      # (nj, max_ns, 2, 3) state: a rod element's nodal bases t̄, D̄
    node_d: np.ndarray      # (nj, max_ns, 2, 3)   (re-based with the rod's nodes)
    turn: TurnWork | None   # a rod section's turn work (None: no tube is a rod)

"""The sections of a flexible tube: a hole section carried by a beam at a material station
(docs/theory.md §II.9).

A tube's section k sits at the station ``ξ_k`` of the outer beam's element ``e_k``; its pose is
that of a body, ``b = [r, p]`` (7), so that the contact kernels of a rigid bore
(:mod:`flexmbs.contact.pair`, :mod:`flexmbs.contact.tangent`) serve it unchanged:

- ``r = S(ξ_k) e`` the centreline point;
- ``p = h(x) ⊗ p̄`` with ``x = S_ξ(ξ_k) e`` the centreline's tangent, ``h(x)`` the smallest
  rotation taking the section's base tangent ``t̄`` to ``x/|x|`` and ``p̄`` the section's base
  frame (Euler parameters, ``A(p̄) e_x = t̄``): the section's plane stays normal to the tube and
  its in-plane axes are carried along without spin (a cable has no twist to turn them).

With ``ℓ = |x|``, ``a = ℓ + t̄·x``, ``w = t̄ × x``: ``h = (a, w) / √(2ℓa)``, a unit quaternion
whenever ``x`` is not opposite to ``t̄`` (:data:`REBASE_COS` keeps it away: after a step whose
tangent turned further, the section takes its current frame as its base, :func:`rebase`, which
leaves its pose unchanged).

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
from ..elements.hermite import CENTERLINE_SIZE, hermite_basis

__all__ = ["POSE_SIZE", "REBASE_COS", "POSE_WORK", "TubeSections", "section_pose",
           "pose_curvature", "rebase", "quaternion_after"]

#: coordinates of a section's pose ``[r (3), p (4)]`` (a rigid body's)
POSE_SIZE = 7
#: a section whose tangent turned by more than 60° from its base tangent takes a new base after
#: the step (:func:`rebase`); the carried rotation is singular only at 180°
REBASE_COS = 0.5
#: float work of :func:`section_pose`, :func:`pose_curvature` and :func:`rebase`: x, ẋ (3 each),
#: h (4), ∂h (4, 3), ∂²h (4, 3, 3), the product matrix (4, 4), μ (4), H_x (3, 3)
POSE_WORK = 3 + 3 + 4 + 12 + 36 + 16 + 4 + 9


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


@njit
def section_pose(qe, length, xi, t_bar, p0, ve, pose, vel, J, work):
    """Pose ``b = [r, p]`` (7) of the section at station ``xi`` of the element ``qe``
    (CENTERLINE_SIZE) with base tangent ``t̄`` and base frame ``p̄``, its rate ``ḃ`` (from
    the element's rates ``ve``) and ``J = ∂b/∂e`` (7, CENTERLINE_SIZE) (module docstring);
    ``work`` (:data:`POSE_WORK`)."""
    S, dS, _, _ = hermite_basis(xi, length)
    x, xd, h, Dh, D2h, M, _, _ = _carve(work)
    for c in range(3):
        r = 0.0
        rd = 0.0
        xc = 0.0
        xdc = 0.0
        for m in range(4):
            r += S[m] * qe[3 * m + c]
            rd += S[m] * ve[3 * m + c]
            xc += dS[m] * qe[3 * m + c]
            xdc += dS[m] * ve[3 * m + c]
        pose[c] = r
        vel[c] = rd
        x[c] = xc
        xd[c] = xdc
    _carried(x, t_bar, h, Dh, D2h, False)
    _right_product(p0, M)
    for i in range(POSE_SIZE):
        for j in range(CENTERLINE_SIZE):
            J[i, j] = 0.0
    for a in range(4):
        pa = 0.0
        for b in range(4):
            pa += M[a, b] * h[b]
        pose[3 + a] = pa
    for a in range(4):
        for c in range(3):
            MD = 0.0
            for b in range(4):
                MD += M[a, b] * Dh[b, c]
            for m in range(4):
                J[3 + a, 3 * m + c] = MD * dS[m]
    for c in range(3):
        for m in range(4):
            J[c, 3 * m + c] = S[m]
    for a in range(4):
        s = 0.0
        for j in range(CENTERLINE_SIZE):
            s += J[3 + a, j] * ve[j]
        vel[3 + a] = s


@njit
def pose_curvature(qe, length, xi, t_bar, p0, ve, lam, H, G, work):
    """The pose's second-order terms at the section of :func:`section_pose`:
    ``H = Σ_i λ_i ∂²b_i/∂e²`` (CENTERLINE_SIZE, CENTERLINE_SIZE) for the force ``λ`` (7) on
    ``b``, and ``G = ∂(J ė)/∂e`` (7, CENTERLINE_SIZE), the pose rate's derivative at fixed
    ``ė`` (its ``r`` rows are 0: ``r`` is linear in ``e``); ``work`` (:data:`POSE_WORK`)."""
    _, dS, _, _ = hermite_basis(xi, length)
    x, xd, h, Dh, D2h, M, mu, Hx = _carve(work)
    for c in range(3):
        xc = 0.0
        xdc = 0.0
        for m in range(4):
            xc += dS[m] * qe[3 * m + c]
            xdc += dS[m] * ve[3 * m + c]
        x[c] = xc
        xd[c] = xdc
    _carried(x, t_bar, h, Dh, D2h, True)
    _right_product(p0, M)
    for b in range(4):                    # μ = Mᵀ λ_p
        mu[b] = 0.0
        for a in range(4):
            mu[b] += M[a, b] * lam[3 + a]
    for c in range(3):
        for d in range(3):
            Hx[c, d] = 0.0
            for b in range(4):
                Hx[c, d] += mu[b] * D2h[b, c, d]
    for m in range(4):
        for n in range(4):
            w = dS[m] * dS[n]
            for c in range(3):
                for d in range(3):
                    H[3 * m + c, 3 * n + d] = w * Hx[c, d]
    for i in range(POSE_SIZE):
        for j in range(CENTERLINE_SIZE):
            G[i, j] = 0.0
    for a in range(4):
        for d in range(3):
            s = 0.0
            for b in range(4):
                t = 0.0
                for c in range(3):
                    t += D2h[b, c, d] * xd[c]
                s += M[a, b] * t
            for n in range(4):
                G[3 + a, 3 * n + d] = s * dS[n]


@njit
def rebase(qe, length, xi, t_bar, p0, work):
    """After a converged step: a section whose tangent turned more than ``acos(REBASE_COS)``
    from its base tangent takes its current tangent and frame as its base (``t_bar``, ``p0``
    updated in place; the pose is unchanged); ``work`` (:data:`POSE_WORK`). Returns whether
    it did."""
    _, dS, _, _ = hermite_basis(xi, length)
    x, _, h, Dh, D2h, _, p, _ = _carve(work)
    for c in range(3):
        s = 0.0
        for m in range(4):
            s += dS[m] * qe[3 * m + c]
        x[c] = s
    ell = math.sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2])
    if (x[0] * t_bar[0] + x[1] * t_bar[1] + x[2] * t_bar[2]) >= REBASE_COS * ell:
        return False
    _carried(x, t_bar, h, Dh, D2h, False)
    quaternion_after(h, p0, p)
    norm = math.sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3])
    for a in range(4):
        p0[a] = p[a] / norm
    for c in range(3):
        t_bar[c] = x[c] / ell
    return True


class TubeSections(NamedTuple):
    """The sections of the clearance joints whose bore is a flexible tube (a field of
    :class:`~flexmbs.contact.clearance_term.ClearancePart`; None there when no joint of the
    model has one, so that none of this is compiled for it)."""

    on: np.ndarray          # (nj,) the joint's sections ride a beam
    dofs: np.ndarray        # (nj, max_ns, CENTERLINE_SIZE) their element's centreline coordinates
    length: np.ndarray      # (nj, max_ns) the element's length
    xi: np.ndarray          # (nj, max_ns) the section's station on it
    t_bar: np.ndarray       # (nj, max_ns, 3) state: base tangents (rebase)
    p0: np.ndarray          # (nj, max_ns, 4) state: base frames
    row: np.ndarray         # (nj, max_ns) the window row of the section's element: its rank
                            # among the joint's tube elements (the plan follows each apart)

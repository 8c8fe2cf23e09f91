"""The compiled generic detector of a hole section (docs/theory.md §II.6): every stationary point
of the penetration of the beam's section ellipse through a compiled section's wall, by the
common-normal residual sampled, bracketed and solved by safeguarded Newton. The joint's paper
detection (:mod:`flexmbs.contact._detect`) and the sections' Python view
(:meth:`~flexmbs.contact.shapes.base.HoleSection.candidates`) call it."""

from __future__ import annotations

import math

import numpy as np

from ..._jit import njit
from ...elements.centerline import bracketed_newton_step, straddles
from . import section_boundary

__all__ = ["common_normal_points"]


@njit
def _support(cy, cz, eax, eay, a, b, N0, N1):
    """Ellipse point with outward normal N: ``X = c + ΣN/√(NᵀΣN)``, and ``TᵀJ_E T`` for the
    tangent T = (−N1, N0) (docs/theory.md §II.6)."""
    na = N0 * eax + N1 * eay            # components of N along e_a, e_b
    nb = -N0 * eay + N1 * eax
    qq = a * a * na * na + b * b * nb * nb
    sq = math.sqrt(qq)
    xa = a * a * na / sq
    xb = b * b * nb / sq
    X0 = cy + xa * eax - xb * eay
    X1 = cz + xa * eay + xb * eax
    # T in (e_a, e_b): (−nb, na); TᵀΣT − (TᵀΣN)²/NᵀΣN over √(NᵀΣN)
    tst = a * a * nb * nb + b * b * na * na
    tsn = -a * a * na * nb + b * b * na * nb
    rho = (tst - tsn * tsn / qq) / sq
    return X0, X1, rho, xa / a, xb / b


@njit(internal=True)
def _common_normal_f(kind, params, cy, cz, eax, eay, a, b, psi, Y, Yp, Ypp):
    """``F(ψ) = T·(X(N(ψ)) − Y(ψ))``, ``F′``, ``d = N·(X − Y)`` and the ellipse angle of X."""
    section_boundary(kind, params, psi, Y, Yp, Ypp)
    speed = math.hypot(Yp[0], Yp[1])
    T0 = Yp[0] / speed
    T1 = Yp[1] / speed
    N0 = T1
    N1 = -T0
    kappa = (Yp[0] * Ypp[1] - Yp[1] * Ypp[0]) / speed**3
    X0, X1, rho, ca, sb = _support(cy, cz, eax, eay, a, b, N0, N1)
    F = T0 * (X0 - Y[0]) + T1 * (X1 - Y[1])
    d = N0 * (X0 - Y[0]) + N1 * (X1 - Y[1])
    dF = speed * (kappa * (rho - d) - 1.0)
    return F, dF, d, math.atan2(sb, ca)


@njit
def common_normal_points(kind, params, cy, cz, eax, eay, a, b, samples, psi_out, phi_out,
                         kind_out, depth_out):
    """Every stationary point of the penetration of the ellipse through a compiled section
    (generic detector of docs/theory.md §II.6, compiled): ``F(ψ)`` sampled at ``samples`` points,
    sign changes bracketed, safeguarded Newton; writes ψ (wall parameter), φ (ellipse angle),
    kind (+1 maximum of the penetration, −1 minimum) and depth ``N·(X − Y)``; returns their
    number (at most ``psi_out.size``)."""
    Y = np.empty(2)
    Yp = np.empty(2)
    Ypp = np.empty(2)
    h = 2.0 * np.pi / samples
    F0, _, _, _ = _common_normal_f(kind, params, cy, cz, eax, eay, a, b, 0.0, Y, Yp, Ypp)
    Fi = F0
    count = 0
    scale = max(a, params[0])
    for i in range(samples):
        lo = i * h
        hi = lo + h
        if i + 1 < samples:
            Fj, _, _, _ = _common_normal_f(kind, params, cy, cz, eax, eay, a, b, hi, Y, Yp, Ypp)
        else:
            Fj = F0
        if straddles(Fi, Fj):
            flo = Fi
            s = 0.5 * (lo + hi) if Fi != 0.0 else lo
            for _ in range(60):
                f, df, _, _ = _common_normal_f(kind, params, cy, cz, eax, eay, a, b, s, Y, Yp, Ypp)
                if abs(f) <= 1e-13 * scale or hi - lo < 1e-15:
                    break
                s, lo, hi, flo = bracketed_newton_step(s, f, df, lo, hi, flo)
            f, df, d, phi = _common_normal_f(kind, params, cy, cz, eax, eay, a, b, s, Y, Yp, Ypp)
            if count < psi_out.size:
                psi_out[count] = s % (2.0 * np.pi)
                phi_out[count] = phi
                kind_out[count] = 1 if df < 0.0 else -1
                depth_out[count] = d
                count += 1
        Fi = Fj
    return count

"""The consistent contact pair of a hole section (docs/theory.md §II.4b; issue "the clearance contact
as the exact gradient of a potential").

In hole section k the wall is the closed curve ``Y(ψ) = o + Y₁(ψ) e_y + Y₂(ψ) e_z`` (moving with
the hole body) and the beam axis the curve ``x(ξ)``. A contact pair is a stationary point of
``D(ξ, ψ) = ½|x(ξ) − Y(ψ)|²``:

    (x − Y)·x_ξ = 0,   (x − Y)·Y_ψ = 0,   δ = r_b − |x − Y|,

a minimum in ξ (the closest point of the axis to the wall point) and a minimum (contact
point, kind +1) or a maximum (kind −1) of the reduced ``D(ψ) = min_ξ D(ξ, ψ)``. By the envelope
theorem the gradient of ``δ`` at such a pair is that of the distance between the two points
held as material points, so the penalty force ``f(δ) n`` at the pair is exactly ``−∂Φ(δ)/∂q``
(``Φ′ = f``), and the section potential ``Σ_max Φ(δ⁺) − Σ_min Φ(δ⁺)`` (continuous through the
pitchfork at ``a²/b = R`` and through folds) has the signed sum of the point forces as its
gradient.

Seeds: the same stationary points for the tangent line of the axis at the section crossing
(the *line model*): the distance of a wall point ``w`` (in-plane, from the crossing) to that line
is ``ℓ² = wᵀ(I − sin²θ e_a e_aᵀ)w``, a quadratic form, so for a circular bore ``½ dℓ²/dφ`` is
the trigonometric polynomial of :func:`~flexmbs.contact.sections.trig_quadratic_roots`
(closed form, at most four points, the right count on either side of the pitchfork); other
sections sample it. Each seed is then converged on the curved axis by a safeguarded Newton
on the reduced ``D(ψ)`` (inner closest-point projection; ``D″ = H_ψψ − H_ξψ²/H_ξξ``).
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import njit
from ..elements.centerline import bracketed_newton_step, closest_point_kernel, straddles
from ..elements.hermite import element_point_values
from .sections import SHAPE_CIRCLE, section_boundary, trig_quadratic_roots

__all__ = ["line_model_points", "stationary_pair", "PAIR_MAX_ITER", "PAIR_MARGIN"]

#: a line-model point is refined when its penetration exceeds −PAIR_MARGIN × clearance: the
#: line model's distance differs from the axis' by about κ(R tan θ)²/2 (the axis' deviation from
#: its tangent over the pair's axial offset), far below this in every example; points that
#: stay out of contact cost a refinement each, and each costs 2–3 closest-point projections
PAIR_MARGIN = 0.05
#: Newton iterations of the reduced pair problem at most (1–2 from a line-model seed)
PAIR_MAX_ITER = 30
#: converged when the angle between x − Y and the wall's normal is below this [rad]
PAIR_TOL = 1e-11
#: a Newton step this small [rad] is the last one (the next residual is its square)
PAIR_LAST_STEP = 1e-7
#: iterations of the joint (ξ, ψ) Newton before the safeguarded path takes over
PAIR_JOINT_ITER = 8
#: largest step of the section angle per iteration [rad]
PAIR_MAX_STEP = 0.3


@njit(inline="always")
def _in_space(origin, ey, ez, y0, y1, c):
    """Component c of the section point (y0, y1) in space: ``o + y0 e_y + y1 e_z``."""
    return origin[c] + y0 * ey[c] + y1 * ez[c]


@njit(inline="always")
def _line_distance2(w0, w1, eax, eay, s2):
    """Squared distance of the in-plane offset w from the crossing to the axis' tangent line:
    ``ℓ² = wᵀ(I − sin²θ e_a e_aᵀ)w`` (the line model)."""
    wa = w0 * eax + w1 * eay
    return w0 * w0 + w1 * w1 - s2 * wa * wa


@njit(internal=True)
def _line_model_f(kind, params, cy, cz, eax, eay, s2, psi, Y, Yp, Ypp):
    """``f = ½ dℓ²/dψ``, ``f′`` and ``ℓ²`` of the line model at ψ (section coordinates)."""
    section_boundary(kind, params, psi, Y, Yp, Ypp)
    w0 = Y[0] - cy
    w1 = Y[1] - cz
    wa = w0 * eax + w1 * eay
    pa = Yp[0] * eax + Yp[1] * eay
    qa = Ypp[0] * eax + Ypp[1] * eay
    f = w0 * Yp[0] + w1 * Yp[1] - s2 * wa * pa
    df = Yp[0] * Yp[0] + Yp[1] * Yp[1] - s2 * pa * pa + w0 * Ypp[0] + w1 * Ypp[1] - s2 * wa * qa
    return f, df, _line_distance2(w0, w1, eax, eay, s2)


@njit
def line_model_points(kind, params, cy, cz, eax, eay, a, b, samples, psi_out, kind_out,
                      ell_out, work, iwork):
    """Stationary points of the distance between the section wall and the tangent line of the
    beam axis (the seeds of :func:`stationary_pair`): crossing ``(cy, cz)``, major axis
    ``(eax, eay)`` and semi-axes ``a ≥ b`` of the section ellipse (``sin²θ = 1 − b²/a²``).
    Writes ψ, kind (+1 a minimum of the distance, i.e. a maximum of the penetration; −1 a
    maximum) and the line-model distance ℓ; returns their number. Circles in closed form, other
    sections by ``samples`` samples of ``½ dℓ²/dψ``, bracketed Newton. ``work`` (float, ≥ 10)
    and ``iwork`` (int, ≥ 5) are work arrays."""
    s2 = max(0.0, 1.0 - (b / a) ** 2)
    count = 0
    if kind == SHAPE_CIRCLE:
        R = params[0]
        ca = cy * eax + cz * eay
        cb = -cy * eay + cz * eax
        al = R * R * s2
        be = R * ca * (1.0 - s2)
        ga = -R * cb
        scale = R * R + R * math.hypot(cy, cz)
        if max(abs(al), abs(be), abs(ga)) <= 1e-13 * scale:
            return 0          # a centred, aligned axis: the whole wall at one distance
        phis = work[:5]
        signs = iwork[:5]
        n = trig_quadratic_roots(al, be, ga, scale, phis, signs, work[5:10])
        alpha = math.atan2(eay, eax)
        for i in range(n):
            if count >= psi_out.size:
                break
            psi = (alpha + phis[i]) % (2.0 * np.pi)
            ell2 = _line_distance2(R * math.cos(psi) - cy, R * math.sin(psi) - cz, eax, eay, s2)
            psi_out[count] = psi
            kind_out[count] = signs[i]
            ell_out[count] = math.sqrt(max(ell2, 0.0))
            count += 1
        return count
    Y = work[0:2]
    Yp = work[2:4]
    Ypp = work[4:6]
    h = 2.0 * np.pi / samples
    scale = 1e-13 * params[0] * params[0]
    F0, _, _ = _line_model_f(kind, params, cy, cz, eax, eay, s2, 0.0, Y, Yp, Ypp)
    Fi = F0
    for i in range(samples):
        lo = i * h
        hi = lo + h
        Fj = F0
        if i + 1 < samples:
            Fj, _, _ = _line_model_f(kind, params, cy, cz, eax, eay, s2, hi, Y, Yp, Ypp)
        if straddles(Fi, Fj):
            flo = Fi
            s = 0.5 * (lo + hi) if Fi != 0.0 else lo
            for _ in range(60):
                f, df, _ = _line_model_f(kind, params, cy, cz, eax, eay, s2, s, Y, Yp, Ypp)
                if abs(f) <= scale or hi - lo < 1e-15:
                    break
                s, lo, hi, flo = bracketed_newton_step(s, f, df, lo, hi, flo)
            _, df, ell2 = _line_model_f(kind, params, cy, cz, eax, eay, s2, s, Y, Yp, Ypp)
            if count < psi_out.size:
                psi_out[count] = s % (2.0 * np.pi)
                kind_out[count] = 1 if df > 0.0 else -1
                ell_out[count] = math.sqrt(max(ell2, 0.0))
                count += 1
        Fi = Fj
    return count


@njit(internal=True)
def _pair_state(qe, lengths, origin, ey, ez, shape, params, psi, elem, xi, Y, Yp, Ypp):
    """Wall point at ψ, its closest axis point and the reduced ``D′(ψ)``, ``D″(ψ)``."""
    section_boundary(shape, params, psi, Y, Yp, Ypp)
    w0 = _in_space(origin, ey, ez, Y[0], Y[1], 0)
    w1 = _in_space(origin, ey, ez, Y[0], Y[1], 1)
    w2 = _in_space(origin, ey, ez, Y[0], Y[1], 2)
    p0 = Yp[0] * ey[0] + Yp[1] * ez[0]
    p1 = Yp[0] * ey[1] + Yp[1] * ez[1]
    p2 = Yp[0] * ey[2] + Yp[1] * ez[2]
    s0 = Ypp[0] * ey[0] + Ypp[1] * ez[0]
    s1 = Ypp[0] * ey[1] + Ypp[1] * ez[1]
    s2 = Ypp[0] * ey[2] + Ypp[1] * ez[2]
    W = np.empty(3)
    W[0] = w0
    W[1] = w1
    W[2] = w2
    e, x, P, rx, rxx = closest_point_kernel(qe, lengths, W, elem, xi, 1e-14, np.int64(30))
    u0 = P[0] - w0
    u1 = P[1] - w1
    u2 = P[2] - w2
    d1 = -(u0 * p0 + u1 * p1 + u2 * p2)
    h11 = (rx[0] * rx[0] + rx[1] * rx[1] + rx[2] * rx[2]
           + u0 * rxx[0] + u1 * rxx[1] + u2 * rxx[2])
    h12 = -(rx[0] * p0 + rx[1] * p1 + rx[2] * p2)
    h22 = p0 * p0 + p1 * p1 + p2 * p2 - (u0 * s0 + u1 * s1 + u2 * s2)
    d2 = h22 - h12 * h12 / h11 if h11 > 0.0 else h22
    ell = math.sqrt(u0 * u0 + u1 * u1 + u2 * u2)
    speed = math.sqrt(p0 * p0 + p1 * p1 + p2 * p2)
    return e, x, d1, d2, ell, speed, w0, w1, w2


@njit(internal=True, refcount=False)
def _joint_newton(qe, lengths, origin, ey, ez, shape, params, psi, elem, xi, Y, Yp, Ypp):
    """Newton on both unknowns of ``∇D(ξ, ψ) = 0`` at once (one axis point and one wall point
    per iteration, no inner projection), from ξ one projection step off the seed. Returns
    ``(converged, psi, elem, xi, ell, d2)`` (d2: the reduced D″, whose sign is the kind)."""
    n = qe.shape[0]
    s = min(max(elem + xi, 0.0), float(n))     # on the beam: not past its ends (as every step)
    for _ in range(PAIR_JOINT_ITER):
        e = min(max(int(math.floor(s)), 0), n - 1)
        x = s - e
        r, rx, rxx = element_point_values(qe[e], lengths[e], x)
        section_boundary(shape, params, psi, Y, Yp, Ypp)
        u0 = r[0] - _in_space(origin, ey, ez, Y[0], Y[1], 0)
        u1 = r[1] - _in_space(origin, ey, ez, Y[0], Y[1], 1)
        u2 = r[2] - _in_space(origin, ey, ez, Y[0], Y[1], 2)
        p0 = Yp[0] * ey[0] + Yp[1] * ez[0]
        p1 = Yp[0] * ey[1] + Yp[1] * ez[1]
        p2 = Yp[0] * ey[2] + Yp[1] * ez[2]
        g1 = u0 * rx[0] + u1 * rx[1] + u2 * rx[2]
        g2 = -(u0 * p0 + u1 * p1 + u2 * p2)
        rr = rx[0] * rx[0] + rx[1] * rx[1] + rx[2] * rx[2]
        pp = p0 * p0 + p1 * p1 + p2 * p2
        h11 = rr + u0 * rxx[0] + u1 * rxx[1] + u2 * rxx[2]
        h12 = -(rx[0] * p0 + rx[1] * p1 + rx[2] * p2)
        h22 = pp - (u0 * (Ypp[0] * ey[0] + Ypp[1] * ez[0]) + u1 * (Ypp[0] * ey[1] + Ypp[1] * ez[1])
                    + u2 * (Ypp[0] * ey[2] + Ypp[1] * ez[2]))
        ell = math.sqrt(u0 * u0 + u1 * u1 + u2 * u2)
        if h11 <= 0.0:
            break
        d2 = h22 - h12 * h12 / h11
        scale = max(ell, 1e-3 * math.sqrt(pp))
        if (abs(g1) <= PAIR_TOL * math.sqrt(rr) * scale
                and abs(g2) <= PAIR_TOL * math.sqrt(pp) * scale):
            return True, psi, e, x, ell, d2
        det = h11 * h22 - h12 * h12
        if det == 0.0:
            break
        ds = -(h22 * g1 - h12 * g2) / det
        dpsi = -(h11 * g2 - h12 * g1) / det
        if abs(ds) > 0.5 or abs(dpsi) > PAIR_MAX_STEP:
            break                 # far from the seed: the safeguarded path decides
        s = min(max(s + ds, 0.0), float(n))
        psi += dpsi
    return False, psi, elem, xi, 0.0, 0.0


@njit
def stationary_pair(qe, lengths, origin, ey, ez, shape, params, psi0, kind0, elem0, xi0, Y, Yp, Ypp):
    """Converge one contact pair of a section from a seed (docs/theory.md §II.4b).

    First Newton on (ξ, ψ) together (:func:`_joint_newton`, 2–3 iterations, accepted when it
    converges to a point of the seed's kind); else a safeguarded Newton on the reduced
    ``D(ψ) = min_ξ ½|x(ξ) − Y(ψ)|²``: from a kind +1 seed it
    descends to a minimum of D (a maximum of the penetration), from a kind −1 seed it ascends to
    a maximum (a step of ``PAIR_MAX_STEP`` downhill, or uphill, where D″ has the wrong sign);
    each iterate projects the wall point on the axis (:func:`closest_point_kernel`, warm).
    Returns ``(psi, kind, elem, xi, ell, converged, Q₀, Q₁, Q₂)``: section angle, kind by the
    sign of D″ at the result, element and parameter of the axis point, distance ``|x − Y|`` and
    the wall point. ``Y, Yp, Ypp`` (2,): work arrays (the wall point and its derivatives)."""
    # the fast path: Newton on (ξ, ψ) together, from the seed's wall point projected once
    section_boundary(shape, params, psi0, Y, Yp, Ypp)
    r, rx, _ = element_point_values(qe[elem0], lengths[elem0], xi0)
    t = 0.0
    rr = 0.0
    for c in range(3):
        t += (_in_space(origin, ey, ez, Y[0], Y[1], c) - r[c]) * rx[c]
        rr += rx[c] * rx[c]
    ok, psi, e, x, ell, d2 = _joint_newton(qe, lengths, origin, ey, ez, shape, params, psi0,
                                           elem0, xi0 + max(-0.5, min(0.5, t / rr)), Y, Yp, Ypp)
    if ok and d2 * kind0 > 0.0:
        section_boundary(shape, params, psi, Y, Yp, Ypp)
        return (psi % (2.0 * np.pi), kind0, e, x, ell, True,
                _in_space(origin, ey, ez, Y[0], Y[1], 0), _in_space(origin, ey, ez, Y[0], Y[1], 1),
                _in_space(origin, ey, ez, Y[0], Y[1], 2))
    # the safeguarded path: the reduced D(ψ), descending or ascending
    psi = psi0
    e = elem0
    x = xi0
    ok = False
    e, x, d1, d2, ell, speed, w0, w1, w2 = _pair_state(qe, lengths, origin, ey, ez, shape,
                                                       params, psi, e, x, Y, Yp, Ypp)
    for _ in range(PAIR_MAX_ITER):
        # |d1| = |x − Y||Y_ψ| sin(angle from normal): 1e-11 is ~100 roundoffs of the 1 m scale
        # coordinates' difference at mm distances; the force's error is of that order
        if abs(d1) <= PAIR_TOL * speed * max(ell, 1e-3 * speed):
            ok = True
            break
        newton = d2 * kind0 > 0.0
        if newton:
            step = -d1 / d2
        else:
            step = -PAIR_MAX_STEP * kind0 * (1.0 if d1 > 0.0 else -1.0)
        step = max(-PAIR_MAX_STEP, min(PAIR_MAX_STEP, step))
        psi += step
        if newton and abs(step) <= PAIR_LAST_STEP:
            # quadratic convergence: the next residual is ~step² (≤ 1e-14 rad), below
            # PAIR_TOL; the wall point moves by step |Y_ψ| and the axis point and the
            # distance by O(step²): the caller's contact kernel projects the axis point again
            section_boundary(shape, params, psi, Y, Yp, Ypp)
            w0 = _in_space(origin, ey, ez, Y[0], Y[1], 0)
            w1 = _in_space(origin, ey, ez, Y[0], Y[1], 1)
            w2 = _in_space(origin, ey, ez, Y[0], Y[1], 2)
            ok = True
            break
        e, x, d1, d2, ell, speed, w0, w1, w2 = _pair_state(qe, lengths, origin, ey, ez, shape,
                                                           params, psi, e, x, Y, Yp, Ypp)
    kind = 1 if d2 > 0.0 else -1
    return psi % (2.0 * np.pi), kind, e, x, ell, ok, w0, w1, w2

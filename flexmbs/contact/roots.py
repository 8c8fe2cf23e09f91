"""Closed-form roots used by the section detectors (docs/theory.md §II.3): real roots of a quartic
(Ferrari, through the resolvent cubic) and of the quadratic trigonometric polynomial
``al sin φ cos φ + be sin φ + ga cos φ`` whose zeros are the stationary points of a circle's
penetration by an ellipse (:func:`flexmbs.contact.shapes.circle.circle_stationary_points`) and
the line model's seeds (:mod:`flexmbs.contact.stationary`)."""

from __future__ import annotations

import math

import numpy as np

from .._jit import njit

__all__ = ["quartic_real_roots", "trig_quadratic_roots"]


@njit
def _trig_f(phi, al, be, ga):
    """``f = al sin φ cos φ + be sin φ + ga cos φ`` and ``f′`` (the stationarity condition of a
    quadratic trigonometric polynomial, docs/theory.md §II.3)."""
    s = math.sin(phi)
    c = math.cos(phi)
    f = al * s * c + be * s + ga * c
    df = al * (c * c - s * s) + be * c - ga * s
    return f, df


@njit
def _cubic_largest_root(b, c, d):
    """Largest real root of ``m³ + b m² + c m + d`` (Cardano / trigonometric form), polished by
    two Newton steps."""
    p = c - b * b / 3.0
    q = 2.0 * b * b * b / 27.0 - b * c / 3.0 + d
    disc = 0.25 * q * q + p * p * p / 27.0
    if disc > 0.0:
        sq = math.sqrt(disc)
        u = -0.5 * q + sq
        w = -0.5 * q - sq
        m = math.copysign(abs(u) ** (1.0 / 3.0), u) + math.copysign(abs(w) ** (1.0 / 3.0), w)
    elif p < 0.0:
        r = 2.0 * math.sqrt(-p / 3.0)
        arg = 3.0 * q / (p * r)
        arg = max(-1.0, min(1.0, arg))
        m = r * math.cos(math.acos(arg) / 3.0)   # the largest of the three real roots
    else:
        m = 0.0
    m -= b / 3.0
    for _ in range(2):
        f = ((m + b) * m + c) * m + d
        df = (3.0 * m + 2.0 * b) * m + c
        if df == 0.0:
            break
        m -= f / df
    return m


@njit
def _quadratic_seeds(s1, s0, out, n):
    """Real roots of ``y² + s1 y + s0``; complex ones with ``|imag| ≤ 1e-6(1 + |real|)`` count
    as real (near-double roots, polished by the caller)."""
    disc = s1 * s1 - 4.0 * s0
    if disc >= 0.0:
        sq = math.sqrt(disc)
        # stable pair: y1 = (-s1 - sign(s1) sq)/2, y2 = s0 / y1
        y1 = -0.5 * (s1 + math.copysign(sq, s1))
        out[n] = y1
        out[n + 1] = s0 / y1 if y1 != 0.0 else -s1 - y1
        return n + 2
    re = -0.5 * s1
    if 0.5 * math.sqrt(-disc) <= 1e-6 * (1.0 + abs(re)):
        out[n] = re
        return n + 1
    return n


@njit
def quartic_real_roots(c4, c3, c2, c1, c0, out):
    """Real (and nearly real) roots of ``c4 t⁴ + c3 t³ + c2 t² + c1 t + c0`` into ``out`` (≥ 4),
    returns their number. Ferrari's factorisation through the largest root of the resolvent
    cubic; closed form, a few hundred flops (``np.roots`` costs an eigenvalue problem).
    Degree drops when leading coefficients are ≤ 1e-300, as in ``np.roots``."""
    if abs(c4) <= 1e-300:
        if abs(c3) <= 1e-300:
            if abs(c2) <= 1e-300:
                if abs(c1) <= 1e-300:
                    return 0
                out[0] = -c0 / c1
                return 1
            return _quadratic_seeds(c1 / c2, c0 / c2, out, np.int64(0))
        # cubic: one real root by the resolvent routine, then deflate
        b, c, d = c2 / c3, c1 / c3, c0 / c3
        t = _cubic_largest_root(b, c, d)
        out[0] = t
        return _quadratic_seeds(b + t, c + t * (b + t), out, np.int64(1))
    a, b, c, d = c3 / c4, c2 / c4, c1 / c4, c0 / c4
    sh = 0.25 * a
    a2 = a * a
    p = b - 0.375 * a2
    q = c - 0.5 * a * b + 0.125 * a2 * a
    r = d - 0.25 * a * c + a2 * b / 16.0 - 3.0 * a2 * a2 / 256.0
    scale = max(abs(p), math.sqrt(abs(r)), abs(q) ** (2.0 / 3.0), 1e-300)
    n = 0
    if abs(q) <= 1e-14 * scale ** 1.5:
        # biquadratic y⁴ + p y² + r: z = y²
        z = np.empty(2)
        nz = _quadratic_seeds(p, r, z, np.int64(0))
        for i in range(nz):
            if z[i] >= 0.0:
                y = math.sqrt(z[i])
                out[n] = y - sh
                out[n + 1] = -y - sh
                n += 2
            elif -z[i] <= 1e-12 * scale:
                out[n] = -sh
                n += 1
        return n
    m = _cubic_largest_root(p, 0.25 * p * p - r, -0.125 * q * q)
    if m <= 0.0:
        m = 1e-300
    w = math.sqrt(2.0 * m)
    tmp = np.empty(4)
    k = _quadratic_seeds(-w, 0.5 * p + m + q / (2.0 * w), tmp, np.int64(0))
    k = _quadratic_seeds(w, 0.5 * p + m - q / (2.0 * w), tmp, k)
    for i in range(k):
        out[i] = tmp[i] - sh
    return k


_H = math.sqrt(0.5)
#: sin(kπ/4), k = 0..7 (cos(kπ/4) = sin((k + 2)π/4))
_SIN_QUARTER = (0.0, _H, 1.0, _H, 0.0, -_H, -1.0, -_H)


@njit
def trig_quadratic_roots(al, be, ga, scale, phis, signs, seeds):
    """Roots of ``f(φ) = al sin φ cos φ + be sin φ + ga cos φ`` on [0, 2π) into ``phis`` (≥ 5)
    with the sign of ``f′`` into ``signs``; returns their number (at most 4). ``seeds`` (≥ 5)
    is work.

    Closed form (docs/theory.md §II.3): with ``t = tan((φ − φ0)/2)``, ``f (1 + t²)²`` is a quartic
    in t; φ0 ∈ {kπ/4} maximises the leading coefficient ``f(φ0 + π)`` (no root near t = ∞),
    real roots by :func:`quartic_real_roots` (nearly-real ones accepted), 4 Newton polishing
    steps on f, residual check against ``1e-10 scale``, duplicates removed."""
    phi0 = 0.0
    best = -1.0
    s0 = 0.0
    c0 = 1.0
    for k in range(8):    # f(kπ/4 + π) from the table of sin, cos at kπ/4 (no sincos)
        sk = _SIN_QUARTER[k]
        ck = _SIN_QUARTER[(k + 2) % 8]
        f_inf = abs(al * sk * ck - be * sk - ga * ck)
        if f_inf > best:
            best = f_inf
            phi0 = k * 0.25 * np.pi
            s0 = sk
            c0 = ck
    u0 = be * s0 + ga * c0
    u1 = 2.0 * (be * c0 - ga * s0)
    asc = al * s0 * c0
    acs = 2.0 * al * (c0 * c0 - s0 * s0)
    c4, c3, c2, c1, cc0 = asc - u0, u1 - acs, -6.0 * asc, acs + u1, asc + u0
    cmax = max(abs(c4), abs(c3), abs(c2), abs(c1), abs(cc0))
    ns = quartic_real_roots(c4, c3, c2, c1, cc0, seeds)
    for i in range(ns):
        seeds[i] = phi0 + 2.0 * math.atan(seeds[i])
    if abs(c4) <= 1e-8 * cmax:
        seeds[ns] = phi0 + np.pi
        ns += 1
    nf = 0
    ftol = 1e-10 * scale
    for i in range(ns):
        phi = seeds[i]
        for _ in range(4):
            f, df = _trig_f(phi, al, be, ga)
            if df == 0.0:
                break
            step = -f / df
            if abs(step) > 0.3:
                step = 0.3 if step > 0 else -0.3
            phi += step
            if abs(step) <= 1e-15 * (1.0 + abs(phi)):
                break
        f, df = _trig_f(phi, al, be, ga)
        if abs(f) > ftol:
            continue
        phi = phi % (2.0 * np.pi)
        dup = False
        for j in range(nf):
            dd = abs(phi - phis[j])
            if min(dd, 2.0 * np.pi - dd) < 1e-9:
                dup = True
                break
        if dup:
            continue
        phis[nf] = phi
        signs[nf] = 1 if df > 0.0 else -1
        nf += 1
    return nf

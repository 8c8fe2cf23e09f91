"""The superellipse exponents the compiled detector can resolve (issue "nothing lost, part
two"): :func:`exponent_limit` and :func:`check_exponent`, called where a hole is made
(:class:`~flexmbs.contact.joint.Hole`, the scenario's ``hole = { shape = "superellipse" }``).

Two limits, both from the compiled code (experiment: ``tools/superellipse_exponent_limit.py``):

- **Resolution.** The detector samples its residual at ``SHAPE_SAMPLES = 128`` wall angles ψ
  per section (``h = 2π/128 = 0.0491``) and brackets sign changes between samples. At a corner
  of ``|y/a|ⁿ + |z/b|ⁿ = 1`` the wall normal turns by 90°: with ``x = y/a``, ``w = z/b`` the
  normal angle θ has ``tan θ = (a/b)(w/x)ⁿ⁻¹`` and ``tan ψ = (b/a)(w/x)``, so the ψ-width of
  the turn from θ = 5° to 85° is ``atan(r t₈₅^(1/(n−1))) − atan(r t₅^(1/(n−1)))`` with
  ``r = min(a, b)/max(a, b)``, ``t_θ = r tan θ``. It shrinks like 1/n: one sample interval at
  n ≈ 50 (a = b), 40 (b/a = 0.5); at n = 1e6 the corner falls between two samples and the
  contact there is missed or found by a Newton step across a kink. The limit is the largest n
  whose corner spans at least one sample interval.
- **Floating point.** The boundary kernel computes ``|cos ψ/a|ⁿ`` (a in metres) and divides by
  ``g²``: ``Y, Y′, Y″`` are finite at all ψ only while ``n |ln a| ≲ 355`` (``ln(DBL_MAX)/2``;
  measured: a = 1e-4 m up to n = 38.9, 1e-3 m: 51.7, 1e-2 m: 77.2, 10 m: 141.8, 1e3 m: 51.7).
  The limit keeps ``n |ln s| ≤ 320`` for both semi-axes s, a margin of 10 %.
"""

from __future__ import annotations

import math

from ...errors import ModelError
from .base import SHAPE_SAMPLES

__all__ = ["POWER_BUDGET", "check_exponent", "exponent_limit"]

#: largest ``n |ln s|`` (s: a semi-axis in metres) for which the boundary kernel's powers stay
#: finite, with a margin of 10 % below the measured 355
POWER_BUDGET = 320.0
#: the normal's turn that counts as the corner (degrees from either wall)
_CORNER = (5.0, 85.0)


def _corner_width(n: float, r: float) -> float:
    """ψ-width of the corner of the superellipse of exponent ``n`` and axis ratio ``r <= 1``
    where the wall normal turns from 5° to 85° (module docstring)."""
    lo, hi = (math.atan(r * (r * math.tan(math.radians(t))) ** (1.0 / (n - 1.0))) for t in _CORNER)
    return hi - lo


def exponent_limit(a: float, b: float, samples: int | None = None) -> float:
    """The largest exponent the compiled detector resolves for semi-axes ``a``, ``b`` (m) with
    ``samples`` samples per section (default: the detector's ``SHAPE_SAMPLES``): its corner
    spans one sample interval, and its powers stay finite (module docstring)."""
    if samples is None:
        samples = SHAPE_SAMPLES
    r = min(a, b) / max(a, b)
    h = 2.0 * math.pi / samples
    lo, hi = 2.0, 1e6
    if _corner_width(hi, r) >= h:
        resolution = hi
    else:
        for _ in range(100):        # the width decreases monotonically with n
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if _corner_width(mid, r) >= h else (lo, mid)
        resolution = lo
    logs = max(abs(math.log(a)), abs(math.log(b)))
    power = POWER_BUDGET / logs if logs > 0.0 else math.inf
    return min(resolution, power)


def check_exponent(a: float, b: float, exponent: float, *, key: str = "exponent") -> None:
    """Raise :class:`ModelError` naming ``key`` and the limit when ``exponent`` is beyond
    :func:`exponent_limit` of the compiled detector."""
    samples = SHAPE_SAMPLES
    limit = exponent_limit(a, b, samples)
    if exponent > limit:
        raise ModelError(
            f"{key} = {exponent:g}: the contact detector cannot resolve this superellipse (a = "
            f"{a:g} m, b = {b:g} m); the exponent must be <= {math.floor(limit * 10) / 10:g}: "
            f"its corners must span one of the {samples} samples per section, and |y/a|^n must "
            "stay finite in double precision")

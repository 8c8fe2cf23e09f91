"""The rounded regular polygon bore: ``sides`` flats at the distance ``apothem`` a from the
centre, joined by circular corners of radius ``r`` (a hexagonal or triangular bore with
radiused corners; ``r = a`` is the circle of radius a). It is the regular polygon of apothem
``a − r`` grown by r. Its compiled boundary in the arc-length parametrisation scaled to
ψ ∈ [0, 2π) (CCW from the middle of the flat whose outward normal is e_y), inside test and
:class:`RoundedPolygonSection` (scenario shape ``"rounded_polygon"``; the generic detector,
docs/theory.md §II.6). The wall is C¹ (its curvature jumps where a flat meets a corner)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..._jit import njit
from ...codes import SHAPE_CODES
from ...errors import ModelError
from .base import HOLE_SECTIONS, SHAPE_SAMPLES, HoleSection, turned_wall

__all__ = ["SHAPE_ROUNDED_POLYGON", "RoundedPolygonSection", "rounded_polygon_boundary",
           "rounded_polygon_contains", "smallest_corner_radius"]

#: the compiled kind code of the rounded polygon, params ``[sides, apothem, r, angle]``
SHAPE_ROUNDED_POLYGON = SHAPE_CODES["rounded_polygon"]


@njit
def rounded_polygon_boundary(params, psi, Y, Yp, Ypp):
    """Wall point ``Y(ψ)`` of the section ``params = [n, a, r, angle]`` and its first and
    second ψ-derivatives into ``Y``, ``Yp``, ``Ypp`` (2,): arc length ``s = ψ P / 2π`` along
    the perimeter ``P = 2 n h + 2π r`` (``h = (a − r) tan(π/n)``, a flat's half length) from
    (a, 0), CCW, so ``|Y′| = P/2π`` and ``Y″ = (P/2π)² κ N_in`` (zero on the flats,
    ``−(Y − C)/r`` times it on a corner of centre C); the section turned by ``angle`` from
    e_y towards e_z. Each of the n sectors is the first turned by a multiple of ``β = 2π/n``:
    half a flat (normal e_1), a corner of angle β, half the next flat."""
    n = int(params[0] + 0.5)
    a, r, turn = params[1], params[2], params[3]
    beta = 2.0 * math.pi / n
    h = (a - r) * math.tan(0.5 * beta)
    arc = r * beta
    sector = 2.0 * h + arc
    P = n * sector
    k = P / (2.0 * math.pi)
    s = (psi / (2.0 * math.pi)) % 1.0 * P
    j = min(int(s / sector), n - 1)
    s -= j * sector
    if s < h:                       # the first half flat, going up
        y0, y1 = a, s
        t0, t1 = 0.0, 1.0
        c0 = c1 = 0.0
        ang = j * beta
    elif s < h + arc:               # the corner, centre (a − r, h)
        phi = (s - h) / r
        y0, y1 = a - r + r * math.cos(phi), h + r * math.sin(phi)
        t0, t1 = -math.sin(phi), math.cos(phi)
        c0, c1 = -math.cos(phi) / r, -math.sin(phi) / r
        ang = j * beta
    else:                           # the next flat's first half, in its own frame
        y0, y1 = a, s - h - arc - h
        t0, t1 = 0.0, 1.0
        c0 = c1 = 0.0
        ang = (j + 1) * beta
    ang += turn
    turned_wall(ang, k, y0, y1, t0, t1, c0, c1, Y, Yp, Ypp)


@njit
def rounded_polygon_contains(params, y, z):
    """Whether (y, z) lies inside the section ``params = [n, a, r, angle]`` (on the wall
    counts): the point turned into the sector of its nearest flat and mirrored about that
    flat's normal, inside the flat or within r of the corner's centre."""
    n = int(params[0] + 0.5)
    a, r, turn = params[1], params[2], params[3]
    beta = 2.0 * math.pi / n
    phi = math.atan2(z, y) - turn
    j = math.floor(phi / beta + 0.5)
    c = math.cos(j * beta + turn)
    s = math.sin(j * beta + turn)
    x = c * y + s * z               # along the flat's normal
    u = abs(-s * y + c * z)         # along the flat, folded
    h = (a - r) * math.tan(0.5 * beta)
    if u <= h:
        return x <= a
    dx = x - (a - r)
    du = u - h
    return dx * dx + du * du <= r * r


def smallest_corner_radius(sides: int, apothem: float) -> float:
    """The smallest corner radius whose corners span two of the compiled detector's
    :data:`SHAPE_SAMPLES` wall samples (equally spaced along the wall): ``r β ≥ 2 P / S`` with
    ``P = 2 n (a − r) tan(β/2) + 2π r``, ``β = 2π/n``, solved for r."""
    n, a = int(sides), float(apothem)
    t = math.tan(math.pi / n)
    return 4.0 * n * t * a / (2.0 * math.pi * SHAPE_SAMPLES / n - 4.0 * math.pi + 4.0 * n * t)


@HOLE_SECTIONS.register("rounded_polygon")
@dataclass(frozen=True)
class RoundedPolygonSection(HoleSection):
    """Rounded regular polygon bore: ``sides`` flats (an integer >= 3) at the distance
    ``apothem`` from the centre, the first facing body y, corner radius ``r``
    (``0 < r ≤ apothem``; ``r = apothem`` is the circle); ``angle`` turns it in the hole body
    (radians, from body y towards body z). Parameter names as in the scenario. The compiled
    detector samples the wall at 128 points equally spaced along it; a corner must span two
    of them, hence a smallest ``r`` (:func:`smallest_corner_radius`; the error names it);
    ``samples``: the Python path's sampling."""

    sides: int = field(metadata={"unit": "1", "ge": 3})
    apothem: float = field(metadata={"unit": "m", "gt": 0.0})
    r: float = field(metadata={"unit": "m", "gt": 0.0})
    samples: int = field(default=128, metadata={"ge": 64})
    angle: float = field(default=0.0, metadata={"unit": "rad"})

    def __post_init__(self) -> None:
        n = self.sides
        if not (isinstance(n, (int, np.integer)) and not isinstance(n, bool) and n >= 3):
            raise ModelError(f"RoundedPolygonSection: sides must be an integer >= 3 (got {n!r})")
        for name in ("apothem", "r"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and not isinstance(v, bool) and v > 0.0
                    and math.isfinite(v)):
                raise ModelError(f"RoundedPolygonSection: {name} must be a number > 0 "
                                 f"(got {v!r})")
        if self.r > self.apothem * (1.0 + 1e-12):
            raise ModelError(f"RoundedPolygonSection: the corner radius r = {self.r!r} is "
                             f"larger than the apothem ({self.apothem!r}); give r <= apothem")
        if int(self.samples) < 64:
            raise ModelError(f"RoundedPolygonSection: samples must be >= 64 (got "
                             f"{self.samples!r})")
        r_min = smallest_corner_radius(n, self.apothem)
        if self.r < r_min * (1.0 - 1e-12):
            raise ModelError(f"RoundedPolygonSection: the corner radius r = {self.r!r} is too "
                             f"small for the detector's {SHAPE_SAMPLES} wall samples (a contact "
                             f"at a corner could fall between two); give r >= {r_min:.3g}")
        ang = self.angle
        if not (isinstance(ang, (int, float)) and not isinstance(ang, bool) and math.isfinite(ang)):
            raise ModelError(f"RoundedPolygonSection: angle must be a finite number (got "
                             f"{ang!r})")

    def bounding_radius(self) -> float:
        """The inner polygon's circumradius plus r."""
        inner = (self.apothem - self.r) / math.cos(math.pi / self.sides)
        return float(inner + self.r) * (1.0 + 1e-12)

    def inscribed_radius(self) -> float:
        return float(self.apothem)

    def compiled_shape(self) -> tuple[int, np.ndarray]:
        return SHAPE_ROUNDED_POLYGON, np.array([float(self.sides), float(self.apothem),
                                                float(self.r), float(self.angle)])

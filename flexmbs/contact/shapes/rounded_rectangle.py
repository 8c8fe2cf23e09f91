"""The rounded-rectangle bore: a rectangle of half-widths ``w`` (e_y) and ``h`` (e_z) whose
corners are quarter circles of radius ``r`` (a rectangular tube, a slot with radiused corners;
``r = min(w, h)`` is a stadium, ``w = h = r`` the circle). Its compiled boundary in the
arc-length parametrisation scaled to ψ ∈ [0, 2π) (CCW from the middle of the +e_y side), inside
test and :class:`RoundedRectangleSection` (scenario shape ``"rounded_rectangle"``; the generic
detector, docs/theory.md §II.6). The wall is C¹ (its curvature jumps where a flat meets a corner)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..._jit import njit
from ...codes import SHAPE_CODES
from ...errors import ModelError
from .base import HOLE_SECTIONS, SHAPE_SAMPLES, HoleSection, turned_wall

__all__ = ["SHAPE_ROUNDED_RECTANGLE", "RoundedRectangleSection", "rounded_rectangle_boundary",
           "rounded_rectangle_contains"]

#: the compiled kind code of the rounded rectangle, params ``[w, h, r, angle]``
SHAPE_ROUNDED_RECTANGLE = SHAPE_CODES["rounded_rectangle"]


@njit
def rounded_rectangle_boundary(params, psi, Y, Yp, Ypp):
    """Wall point ``Y(ψ)`` of the section ``params = [w, h, r, angle]`` and its first and second
    ψ-derivatives into ``Y``, ``Yp``, ``Ypp`` (2,): arc length ``s = ψ P / 2π`` along the
    perimeter ``P = 4(w − r) + 4(h − r) + 2πr`` from (w, 0), CCW, so ``|Y′| = P/2π`` and
    ``Y″ = (P/2π)² κ N_in`` (zero on the flats, ``−(Y − C)/r`` times it on a corner of centre
    C); the section turned by ``angle`` from e_y towards e_z."""
    w, h, r, beta = params[0], params[1], params[2], params[3]
    a = w - r                       # the flats' half lengths
    b = h - r
    quarter = 0.5 * math.pi * r
    P = 4.0 * a + 4.0 * b + 4.0 * quarter
    k = P / (2.0 * math.pi)
    s = (psi / (2.0 * math.pi)) % 1.0 * P
    # the perimeter in one quadrant's pieces: side (b), corner (quarter), top (a), then the
    # same turned by 90°, 180°, 270°: each quadrant is the first turned by a multiple of 90°
    # about the centre, with the roles of a and b swapped in the odd ones
    q = 0
    half1, half2 = b, a
    while True:
        span = half1 + quarter + half2
        if s < span or q == 3:
            break
        s -= span
        q += 1
        half1, half2 = half2, half1
    # local quadrant frame: the side along +e_2 at e_1 = (half-width of this side)
    ext1 = half2 + r                # the half-width this side lies at (w for q = 0)
    if s < half1:                   # the flat side, going up
        y0, y1 = ext1, s
        t0, t1 = 0.0, 1.0
        c0 = c1 = 0.0
    elif s < half1 + quarter:       # the corner
        phi = (s - half1) / r
        cx, cy = half2, half1
        y0, y1 = cx + r * math.cos(phi), cy + r * math.sin(phi)
        t0, t1 = -math.sin(phi), math.cos(phi)
        c0, c1 = -math.cos(phi) / r, -math.sin(phi) / r
    else:                           # the top, going left to the middle
        y0, y1 = half2 - (s - half1 - quarter), half1 + r
        t0, t1 = -1.0, 0.0
        c0 = c1 = 0.0
    # turn the quadrant (q · 90°) and the section (angle) into section coordinates
    ang = 0.5 * math.pi * q + beta
    turned_wall(ang, k, y0, y1, t0, t1, c0, c1, Y, Yp, Ypp)


@njit
def rounded_rectangle_contains(params, y, z):
    """Whether (y, z) lies inside the section ``params = [w, h, r, angle]`` (on the wall counts)."""
    cb = math.cos(params[3])
    sb = math.sin(params[3])
    yl = abs(cb * y + sb * z)       # the point in the section's own axes, first quadrant
    zl = abs(-sb * y + cb * z)
    w, h, r = params[0], params[1], params[2]
    if yl > w or zl > h:
        return False
    dy = yl - (w - r)
    dz = zl - (h - r)
    if dy > 0.0 and dz > 0.0:
        return dy * dy + dz * dz <= r * r
    return True


@HOLE_SECTIONS.register("rounded_rectangle")
@dataclass(frozen=True)
class RoundedRectangleSection(HoleSection):
    """Rounded-rectangle bore: half-widths ``w`` (body y) and ``h`` (body z), corner radius
    ``r`` (``0 < r ≤ min(w, h)``); ``angle`` turns it in the hole body (radians, from body y
    towards body z). Parameter names as in the scenario: ``w``, ``h``, ``r``, ``angle``. The
    compiled detector samples the wall at 128 points equally spaced along it; a corner must
    span two of them (else a contact at a small corner could fall between samples), hence a
    smallest ``r`` (the error names it); ``samples``: the Python path's sampling."""

    w: float = field(metadata={"unit": "m", "gt": 0.0})
    h: float = field(metadata={"unit": "m", "gt": 0.0})
    r: float = field(metadata={"unit": "m", "gt": 0.0})
    samples: int = field(default=128, metadata={"ge": 64})
    angle: float = field(default=0.0, metadata={"unit": "rad"})

    def __post_init__(self) -> None:
        for name in ("w", "h", "r"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and not isinstance(v, bool) and v > 0.0
                    and math.isfinite(v)):
                raise ModelError(f"RoundedRectangleSection: {name} must be a number > 0 "
                                 f"(got {v!r})")
        if self.r > min(self.w, self.h) * (1.0 + 1e-12):
            raise ModelError(f"RoundedRectangleSection: the corner radius r = {self.r!r} is "
                             f"larger than the half-widths (w = {self.w!r}, h = {self.h!r}); "
                             "give r <= min(w, h)")
        if int(self.samples) < 64:
            raise ModelError(f"RoundedRectangleSection: samples must be >= 64 (got "
                             f"{self.samples!r})")
        straight = 4.0 * (self.w + self.h - 2.0 * self.r)
        # a corner spans two samples: π r / 2 ≥ 2 (straight + 2π r) / SHAPE_SAMPLES
        r_min = 4.0 * straight / (math.pi * (SHAPE_SAMPLES - 8))
        if self.r < r_min:
            raise ModelError(f"RoundedRectangleSection: the corner radius r = {self.r!r} is too "
                             f"small for the detector's {SHAPE_SAMPLES} wall samples (a contact "
                             f"at a corner could fall between two); give r >= {r_min:.3g}")
        ang = self.angle
        if not (isinstance(ang, (int, float)) and not isinstance(ang, bool) and math.isfinite(ang)):
            raise ModelError(f"RoundedRectangleSection: angle must be a finite number (got "
                             f"{ang!r})")

    def bounding_radius(self) -> float:
        return float(math.hypot(self.w - self.r, self.h - self.r) + self.r) * (1.0 + 1e-12)

    def inscribed_radius(self) -> float:
        return float(min(self.w, self.h))

    def compiled_shape(self) -> tuple[int, np.ndarray]:
        return SHAPE_ROUNDED_RECTANGLE, np.array([float(self.w), float(self.h), float(self.r),
                                                  float(self.angle)])

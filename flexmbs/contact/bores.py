"""The bore of a clearance joint: a hole section repeated at stations along an axis, each
station a plane that cuts the beam (docs/theory.md §II.1, §II.8).

A bore gives the kernels its sections as data (:meth:`Hole.frames`): an origin and three axes
(plane normal, e_y, e_z) per section, in the coordinates of the hole (the joint adds its
``hole_point``). :class:`Hole` is the paper's bore, straight along body x; :class:`CurvedBore`
follows a curve (issue "a rod or wire inside a curved tube"): sections normal to the curve,
their e_y carried along it without twist, so a section shape that is not round keeps its
orientation relative to the tube. Both feed the same compiled detection and exact tangent.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from .._jit import njit
from ..budget import MAX_SECTIONS, require_memory
from ..errors import ModelError
from .sections import CircleSection, HoleSection, SuperellipseSection
from .shapes.superellipse_limits import check_exponent

if TYPE_CHECKING:  # pragma: no cover
    from ..geometry.curves import Centerline

__all__ = ["Hole", "CircleHole", "SuperellipseHole", "CurvedBore", "transported_frames",
           "section_tree", "refit_section_tree", "sections_near", "section_between", "TREE_LEAF",
           "BORE_KEYS"]

#: keys of a bore's record beyond its section's parameters (:meth:`Hole.record`, read back by
#: the section view)
BORE_KEYS = ("length", "sections", "open_ends", "path")


def _check_count(n: Any, what: str, fix: str) -> int:
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise ModelError(f"{what} must be an integer >= 1 (got {n!r})")
    if n > MAX_SECTIONS:
        raise ModelError(f"{what} = {n}: more than {MAX_SECTIONS} per hole; {fix}")
    require_memory(n_sections=int(n), what=f"{what} = {n}", fix=fix)
    return int(n)


@dataclass(frozen=True)
class Hole:
    """A bore of constant section along the body x axis, checked at ``sections`` stations
    (both end faces included). ``open_ends``: the beam may enter and leave the bore (a section
    it does not cross is idle); else it must cross every section (a beam that leaves is an
    error: the paper's sleeve on its rail).

    Parameters
    ----------
    section : HoleSection
        The bore's cross-section (a circle, a superellipse, or a registered shape).
    length : float
        Bore length along the body x axis [m].
    sections : int, default 9
        Number of sections checked for contact, both end faces included.
    open_ends : bool, default False
        Whether the beam may enter and leave the bore.
    """

    section: HoleSection
    length: float
    sections: int = 9
    open_ends: bool = False

    def __post_init__(self) -> None:
        if not self.length > 0:
            raise ModelError(f"hole length must be > 0 (got {self.length})")
        n = self.sections
        spacing = self.length / (n - 1) if isinstance(n, (int, np.integer)) and n > 1 else 0.0
        _check_count(n, "hole sections",
                     f"stations {spacing:.3g} m apart resolve nothing the beam elements can, and "
                     "each costs time in every Newton iteration; use fewer sections (9-21 is "
                     "typical)")
        if isinstance(self.section, SuperellipseSection):   # what the detector can resolve
            check_exponent(self.section.a, self.section.b, self.section.exponent)

    def stations(self) -> np.ndarray:
        """Axial positions of the sections along the bore, from -length/2 to +length/2."""
        if self.sections == 1:
            return np.zeros(1)
        return np.linspace(-0.5 * self.length, 0.5 * self.length, int(self.sections))

    def frames(self) -> tuple[np.ndarray, np.ndarray]:
        """Origins ``(n, 3)`` and axes ``(n, 3, 3)`` (columns: plane normal, e_y, e_z) of the
        sections in the hole's coordinates: here ``(ζ_k, 0, 0)`` and the identity."""
        zeta = self.stations()
        origins = np.zeros((zeta.size, 3))
        origins[:, 0] = zeta
        return origins, np.repeat(np.eye(3)[None], zeta.size, axis=0)

    def record(self) -> dict[str, Any]:
        """The bore's geometry beyond its section for ``summary.json["hole_sections"]``."""
        return {"length": float(self.length), "sections": int(self.sections),
                "open_ends": bool(self.open_ends)}


class CircleHole(Hole):
    """Circular bore of ``radius`` (docs/design.md, "Python API":
    ``fm.CircleHole(radius=..., length=..., sections=...)``).

    Parameters
    ----------
    radius : float
        Bore radius [m].
    length : float
        Bore length along the body x axis [m].
    sections : int, default 9
        Number of hole sections checked for contact, both end faces included.
    """

    def __init__(self, radius: float, length: float, sections: int = 9) -> None:
        super().__init__(CircleSection(radius), length, sections)


class SuperellipseHole(Hole):
    """Superellipse bore ``|y/a|^exponent + |z/b|^exponent = 1`` (docs/theory.md §II.6); the
    keys are those of the scenario files (``a``, ``b``, ``exponent``, ``angle``: the section
    turned in the body by that many radians from body y towards body z).

    Parameters
    ----------
    a, b : float
        Semi-axes along the section's y and z [m].
    exponent : float
        Superellipse exponent (2: an ellipse; larger: closer to a rectangle).
    length : float
        Bore length along the body x axis [m].
    sections : int, default 9
        Number of sections checked for contact, both end faces included.
    angle : float, default 0
        Rotation of the section in the body, from body y towards body z [rad].
    """

    def __init__(self, a: float, b: float, exponent: float, length: float,
                 sections: int = 9, angle: float = 0.0) -> None:
        super().__init__(SuperellipseSection(a=a, b=b, exponent=exponent, angle=angle), length,
                         sections)


def transported_frames(points: np.ndarray, tangents: np.ndarray, up: np.ndarray) -> np.ndarray:
    """Axes ``(n, 3, 3)`` (columns: t_k, e_y, e_z) along a curve sampled at ``points`` with unit
    ``tangents``: e_y starts as ``up`` made normal to t_0 and is carried from station to station
    by the double reflection of Wang, Jüttler, Zheng and Liu (ACM TOG 27, 2008), a
    rotation-minimising frame (no twist about the curve; fourth order in the spacing); e_z = t × e_y.
    A straight curve keeps e_y exactly."""
    n = points.shape[0]
    t0 = tangents[0]
    e = up - (up @ t0) * t0
    if not np.linalg.norm(e) > 1e-9 * max(1.0, float(np.linalg.norm(up))):
        raise ModelError("bore: 'up' is along the path's tangent at its start; give a direction "
                         "across it")
    e = e / np.linalg.norm(e)
    out = np.empty((n, 3, 3))
    for k in range(n):
        t = tangents[k]
        if k > 0:
            v1 = points[k] - points[k - 1]
            c1 = v1 @ v1
            tL = tangents[k - 1]
            if c1 > 0.0:
                e = e - (2.0 / c1) * (v1 @ e) * v1
                tL = tL - (2.0 / c1) * (v1 @ tL) * v1
            v2 = t - tL
            c2 = v2 @ v2
            if c2 > 0.0:
                e = e - (2.0 / c2) * (v2 @ e) * v2
            e = e - (e @ t) * t                # round-off only: e stays normal to t
            e = e / np.linalg.norm(e)
        out[k, :, 0] = t
        out[k, :, 1] = e
        out[k, :, 2] = np.cross(t, e)
    return out


class CurvedBore(Hole):
    """A bore of constant ``section`` along a curve ``path`` (a
    :class:`~flexmbs.geometry.curves.Centerline` in the body's coordinates: ``fm.line``,
    ``fm.arc``, ``fm.polyline``, ``fm.read_curve``), cut by sections normal to the curve at
    ``sections`` stations equally spaced in arc length (both ends included) or every
    ``spacing`` (rounded so that both ends are stations). The sections' e_y axis starts as
    ``up`` (default body y, body z if y is along the curve's start) made normal to the curve
    and is carried along it without twist (:func:`transported_frames`). ``radius`` is short
    for ``section = CircleSection(radius)``. ``open_ends`` (default here): the beam may enter
    and leave (a tube); ``False``: it must cross every section. A straight path along body x
    is :class:`Hole`.

    Parameters
    ----------
    path : Centerline
        The bore's axis in body coordinates.
    radius : float, optional
        Short for ``section=CircleSection(radius)`` [m].
    section : HoleSection, optional
        The bore's cross-section (one of ``radius`` and ``section``).
    sections : int, optional
        Number of sections, equally spaced in arc length, both ends included.
    spacing : float, optional
        Instead of ``sections``: the distance between sections [m] (rounded so that both ends
        are sections).
    up : array_like of 3 floats, optional
        The first section's e_y axis (default body y, or body z if y is along the curve's start).
    open_ends : bool, default True
        Whether the beam may enter and leave the bore.
    """

    path: Centerline
    up: np.ndarray

    def __init__(self, path: Centerline, *, radius: float | None = None,
                 section: HoleSection | None = None, sections: int | None = None,
                 spacing: float | None = None, up: Any = None, open_ends: bool = True) -> None:
        if (radius is None) == (section is None):
            raise ModelError("CurvedBore: give either radius= (a circular bore) or section=")
        if section is None:
            section = CircleSection(float(radius))  # type: ignore[arg-type]
        if (sections is None) == (spacing is None):
            raise ModelError("CurvedBore: give either sections= (a count) or spacing= (a "
                             "distance along the path)")
        length = float(path.total_length)
        if spacing is not None:
            if not (isinstance(spacing, (int, float)) and math.isfinite(spacing) and spacing > 0):
                raise ModelError(f"CurvedBore: spacing must be a number > 0 (got {spacing!r})")
            count = max(2, int(math.ceil(length / float(spacing) - 1e-9)) + 1)
            if count > MAX_SECTIONS:
                raise ModelError(f"CurvedBore: spacing = {spacing:g} m gives {count} sections "
                                 f"on the {length:g} m path, more than {MAX_SECTIONS}; use a "
                                 "larger spacing")
            sections = count
        super().__init__(section, length, sections, bool(open_ends))  # type: ignore[arg-type]
        object.__setattr__(self, "path", path)
        t0 = path.frame_at(0.0)[1]
        if up is None:
            up = np.array([0.0, 1.0, 0.0]) if abs(t0[1]) < 0.9 else np.array([0.0, 0.0, 1.0])
        up = np.asarray(up, dtype=float).reshape(3)
        object.__setattr__(self, "up", up)
        s = self.stations()
        points = np.empty((s.size, 3))
        tangents = np.empty((s.size, 3))
        for k, sk in enumerate(s):
            points[k], tangents[k] = path.frame_at(float(sk))
        axes = transported_frames(points, tangents, up)
        self._check_bend(s, tangents)
        for arr in (points, axes):
            arr.setflags(write=False)
        object.__setattr__(self, "_origins", points)
        object.__setattr__(self, "_axes", axes)

    def _check_bend(self, s: np.ndarray, tangents: np.ndarray) -> None:
        """Neighbouring section planes meet at the path's radius of curvature from it: where
        that is inside the bore, the sections overlap and the bore is not a tube."""
        if s.size < 2:
            return
        turn = np.arccos(np.clip(np.einsum("ij,ij->i", tangents[1:], tangents[:-1]), -1.0, 1.0))
        ds = np.diff(s)
        with np.errstate(divide="ignore"):
            rho = np.where(turn > 0.0, ds / np.where(turn > 0.0, turn, 1.0), np.inf)
        k = int(np.argmin(rho))
        R = self.section.bounding_radius()
        if rho[k] <= R:
            raise ModelError(f"CurvedBore: the path bends with a radius of {rho[k]:.4g} m near "
                             f"arc length {s[k]:.4g} m, tighter than the bore's radius {R:.4g} m "
                             "(the sections would overlap); smooth the path")

    def stations(self) -> np.ndarray:
        """Arc lengths of the sections along the path, from 0 to its length."""
        if self.sections == 1:
            return np.zeros(1)
        return np.linspace(0.0, self.length, int(self.sections))

    def frames(self) -> tuple[np.ndarray, np.ndarray]:
        """Origins ``(n, 3)`` (points of the path) and axes ``(n, 3, 3)`` (columns: the path's
        tangent, e_y, e_z) of the sections."""
        return np.array(self._origins), np.array(self._axes)  # type: ignore[attr-defined]

    def record(self) -> dict[str, Any]:
        return {**super().record(), "path": "curve"}

    def __repr__(self) -> str:
        return (f"CurvedBore({type(self.section).__name__}, length={self.length:.6g}, "
                f"sections={self.sections})")


#: sections per leaf of a bore's bounding-sphere tree (:func:`section_tree`)
TREE_LEAF = 4


def section_tree(origins: np.ndarray, reach: float) -> tuple[np.ndarray, ...]:
    """Bounding-sphere tree over consecutive sections (issue 30, "many sections, cheap"): node
    0 covers sections ``[0, n)``, node i's children 2i+1 and 2i+2 its halves, down to
    :data:`TREE_LEAF` sections; a node's sphere holds the discs of radius ``reach`` about its
    sections' origins (body coordinates). Returns ``(centre (m, 3), radius (m,), lo (m,),
    hi (m,))``; unused nodes have ``radius = -1``. Consecutive sections of a bore are close in
    space, so the ranges are compact."""
    n = origins.shape[0]
    m = 1
    while m < 4 * max(1, -(-n // TREE_LEAF)):
        m *= 2
    centre = np.zeros((m, 3))
    radius = np.full(m, -1.0)
    lo = np.zeros(m, np.int64)
    hi = np.zeros(m, np.int64)
    stack = [(0, 0, n)]
    while stack:
        i, a, b = stack.pop()
        c = origins[a:b].mean(axis=0)
        centre[i] = c
        radius[i] = float(np.sqrt(((origins[a:b] - c) ** 2).sum(axis=1)).max()) + reach
        lo[i], hi[i] = a, b
        if b - a > TREE_LEAF:
            mid = (a + b) // 2
            stack += [(2 * i + 1, a, mid), (2 * i + 2, mid, b)]
    return centre, radius, lo, hi


@njit
def refit_section_tree(origins, reach, centre, radius, lo, hi):
    """:func:`section_tree`'s spheres again for sections that moved (a flexible tube's, at
    every evaluation): the same nodes and ranges, each node's centre the mean of its
    sections' ``origins`` and its radius their largest distance plus ``reach``. O(n log n)."""
    for i in range(radius.shape[0]):
        if radius[i] < 0.0:
            continue
        a, b = lo[i], hi[i]
        c0 = 0.0
        c1 = 0.0
        c2 = 0.0
        for k in range(a, b):
            c0 += origins[k, 0]
            c1 += origins[k, 1]
            c2 += origins[k, 2]
        c0 /= b - a
        c1 /= b - a
        c2 /= b - a
        d2 = 0.0
        for k in range(a, b):
            d = ((origins[k, 0] - c0) ** 2 + (origins[k, 1] - c1) ** 2
                 + (origins[k, 2] - c2) ** 2)
            d2 = max(d2, d)
        centre[i, 0] = c0
        centre[i, 1] = c1
        centre[i, 2] = c2
        radius[i] = math.sqrt(d2) + reach


@njit(inline="always")
def sections_near(centre, radius, lo, hi, x, rho, stack, out):
    """Sections whose discs (the tree's ``reach``) may meet the sphere ``(x, rho)`` (body
    coordinates): their indices into ``out`` (ascending within each leaf), returns how many.
    ``stack``: int64 work array of at least 64."""
    count = 0
    if radius.shape[0] == 0 or radius[0] < 0.0:
        return 0
    top = 0
    stack[0] = 0
    while top >= 0:
        i = stack[top]
        top -= 1
        d0 = x[0] - centre[i, 0]
        d1 = x[1] - centre[i, 1]
        d2 = x[2] - centre[i, 2]
        r = radius[i] + rho
        if d0 * d0 + d1 * d1 + d2 * d2 > r * r:
            continue
        left = 2 * i + 1
        if left < radius.shape[0] and radius[left] >= 0.0:
            top += 1
            stack[top] = left + 1      # the right half after the left one
            top += 1
            stack[top] = left
        else:
            for k in range(lo[i], hi[i]):
                out[count] = k
                count += 1
    return count


@njit
def section_between(origins, frames, stations, k, lam, origin, frame):
    """A section plane between sections k and k+1 at the fraction ``lam`` of their distance
    along the bore (a free tip's section, :func:`~flexmbs.contact._detect.place_tips`):
    ``origin`` on the cubic Hermite curve through both origins with the sections' normals as
    unit tangents (``Δs = stations[k+1] − stations[k]``; exact on a line, fourth order in Δs on
    a curve); ``frame`` (columns: normal, e_y, e_z) the section k's axes turned by the
    smallest rotation that takes its normal to the curve's tangent there (twist-free, as
    :func:`transported_frames`). Body coordinates."""
    ds = stations[k + 1] - stations[k]
    l2 = lam * lam
    l3 = l2 * lam
    h00 = 2.0 * l3 - 3.0 * l2 + 1.0
    h10 = l3 - 2.0 * l2 + lam
    h01 = -2.0 * l3 + 3.0 * l2
    h11 = l3 - l2
    d00 = 6.0 * l2 - 6.0 * lam            # the weights' derivatives in lam
    d10 = 3.0 * l2 - 4.0 * lam + 1.0
    d01 = -d00
    d11 = 3.0 * l2 - 2.0 * lam
    t = np.empty(3)
    for c in range(3):
        n0 = frames[k, c, 0]
        n1 = frames[k + 1, c, 0]
        origin[c] = (h00 * origins[k, c] + h10 * ds * n0 + h01 * origins[k + 1, c]
                     + h11 * ds * n1)
        t[c] = (d00 * origins[k, c] + d01 * origins[k + 1, c]) / ds + d10 * n0 + d11 * n1
    nt = math.sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2])
    for c in range(3):
        t[c] /= nt
    # the smallest rotation n0 -> t: v' = v + w × v + w × (w × v) / (1 + n0·t), w = n0 × t
    n0x, n0y, n0z = frames[k, 0, 0], frames[k, 1, 0], frames[k, 2, 0]
    wx = n0y * t[2] - n0z * t[1]
    wy = n0z * t[0] - n0x * t[2]
    wz = n0x * t[1] - n0y * t[0]
    f = 1.0 / (1.0 + n0x * t[0] + n0y * t[1] + n0z * t[2])
    for col in range(3):
        vx, vy, vz = frames[k, 0, col], frames[k, 1, col], frames[k, 2, col]
        cx = wy * vz - wz * vy
        cy = wz * vx - wx * vz
        cz = wx * vy - wy * vx
        frame[0, col] = vx + cx + f * (wy * cz - wz * cy)
        frame[1, col] = vy + cy + f * (wz * cx - wx * cz)
        frame[2, col] = vz + cz + f * (wx * cy - wy * cx)

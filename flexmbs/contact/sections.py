"""2D hole sections and the common-normal contact detector (docs/theory.md §II.3, §II.6).

Section coordinates are ``(y, z)`` with the hole centre at the origin. The beam cuts the section
plane in an ellipse (:class:`Ellipse2D`, docs/theory.md §II.2). A hole section reports every
stationary point of the penetration of that ellipse through its boundary (:meth:`candidates`):
local maxima (``kind=+1``) are contact points, local minima (``kind=-1``) enter the force with the
opposite sign (continuity rule, docs/theory.md §II.3).

Pluggable (docs/design.md "Pluggable parts"): the shapes are one module each in
:mod:`flexmbs.contact.shapes` (a compiled boundary kernel and a :class:`HoleSection` class,
registered in :data:`HOLE_SECTIONS` by scenario name), and the compiled generic detector of §6
is :func:`flexmbs.contact.shapes.detector.common_normal_points`; this module holds
:func:`get_section` and the ellipse-in-circle facts of §2–§3, and re-exports the shapes'
names.
"""

from __future__ import annotations

import numpy as np

from ..errors import ModelError
from .roots import quartic_real_roots, trig_quadratic_roots
from .shapes import (
    HOLE_SECTIONS,
    SHAPE_CIRCLE,
    SHAPE_SAMPLES,
    SHAPE_SUPERELLIPSE,
    Candidate,
    CircleSection,
    Ellipse2D,
    HoleSection,
    SuperellipseSection,
    circle_boundary,
    circle_stationary_points,
    section_boundary,
    section_contains,
    superellipse_boundary,
)

__all__ = [
    "Ellipse2D",
    "Candidate",
    "HoleSection",
    "CircleSection",
    "SuperellipseSection",
    "HOLE_SECTIONS",
    "SECTION_TYPES",
    "SHAPE_CIRCLE",
    "SHAPE_SAMPLES",
    "SHAPE_SUPERELLIPSE",
    "circle_boundary",
    "superellipse_boundary",
    "section_boundary",
    "section_contains",
    "get_section",
    "two_point_possible",
    "inside_evolute",
    "jamming",
    "circle_stationary_points",
    "quartic_real_roots",
    "trig_quadratic_roots",
]


#: the former name of :data:`HOLE_SECTIONS` (same object)
SECTION_TYPES = HOLE_SECTIONS


def get_section(name: str, **params: float) -> HoleSection:
    """Hole section by scenario name, e.g. ``get_section("superellipse", a=2e-3, b=3e-3,
    exponent=4)``; an unknown name lists the known ones (:data:`HOLE_SECTIONS`)."""
    cls = HOLE_SECTIONS.get(name)
    try:
        return cls(**params)
    except TypeError as exc:
        raise ModelError(f"hole section {name!r}: {exc}") from None


def two_point_possible(ellipse: Ellipse2D, R: float) -> bool:
    """Two-point contact at the minor vertex is possible iff ``ρ_max = a²/b > R`` (docs/theory.md §II.3)."""
    return ellipse.a**2 / ellipse.b > R


def inside_evolute(ellipse: Ellipse2D, point: np.ndarray | None = None) -> bool:
    """Is ``point`` (default: hole centre) inside the ellipse's evolute (astroid)?  Then D(φ) has 4
    stationary points, else 2 (docs/theory.md §II.3)."""
    o = np.zeros(2) if point is None else np.asarray(point, dtype=float)
    d = o - ellipse.center
    da, db = float(d @ ellipse.e_a), float(d @ ellipse.e_b)
    a, b = ellipse.a, ellipse.b
    return abs(a * da) ** (2 / 3) + abs(b * db) ** (2 / 3) < (a * a - b * b) ** (2 / 3)


def jamming(ellipse: Ellipse2D, hole: HoleSection) -> bool:
    """True when the ellipse is wider than the hole's inscribed circle (``a > R_in``).

    Exact for the circle (the ellipse cannot fit anywhere: jamming, docs/theory.md §II.2); for other
    shapes a conservative flag (the ellipse may still fit along a wider direction).
    """
    return ellipse.a > hole.inscribed_radius()

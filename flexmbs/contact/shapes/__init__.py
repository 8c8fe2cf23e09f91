"""Hole sections, one module a shape (issue "a house easy to change"): :mod:`.circle`,
:mod:`.superellipse`, :mod:`.rounded_rectangle`, :mod:`.rounded_polygon`; what they share in
:mod:`.base`. A shape
module holds its compiled boundary kernel ``Y, Y′, Y″`` and inside test, its kind code and its
:class:`HoleSection` class (registered in :data:`HOLE_SECTIONS`; the numpy view is derived
from the kernel). The two dispatchers below are the only place that lists the compiled shapes:
numba needs the calls spelt out.
"""

from __future__ import annotations

import numpy as np

from ..._jit import njit
from .base import HOLE_SECTIONS, SHAPE_SAMPLES, Candidate, Ellipse2D, HoleSection
from .circle import (
    SHAPE_CIRCLE,
    CircleSection,
    circle_boundary,
    circle_contains,
    circle_stationary_points,
)
from .rounded_polygon import (
    SHAPE_ROUNDED_POLYGON,
    RoundedPolygonSection,
    rounded_polygon_boundary,
    rounded_polygon_contains,
)
from .rounded_rectangle import (
    SHAPE_ROUNDED_RECTANGLE,
    RoundedRectangleSection,
    rounded_rectangle_boundary,
    rounded_rectangle_contains,
)
from .superellipse import (
    SHAPE_SUPERELLIPSE,
    SuperellipseSection,
    superellipse_boundary,
    superellipse_contains,
    superellipse_section_boundary,
)

__all__ = ["HOLE_SECTIONS", "SHAPE_CIRCLE", "SHAPE_ROUNDED_POLYGON", "SHAPE_ROUNDED_RECTANGLE",
           "SHAPE_SAMPLES", "SHAPE_SUPERELLIPSE",
           "Candidate", "CircleSection", "Ellipse2D", "HoleSection", "RoundedPolygonSection",
           "RoundedRectangleSection",
           "SuperellipseSection", "circle_boundary",
           "circle_stationary_points", "section_boundary", "section_contains",
           "superellipse_boundary"]


@njit
def section_boundary(kind, params, psi, Y, Yp, Ypp):
    """``Y(ψ), Y′, Y″`` of a compiled hole section (``kind``, ``params`` of
    :meth:`HoleSection.compiled_shape`): the detectors and the contact tangent read the wall
    through it. An unknown ``kind`` (a shape module whose code is not dispatched here) gives a
    wall of NaN, never another shape's (tests/test_codes.py dispatches every code)."""
    if kind == SHAPE_CIRCLE:
        circle_boundary(params[0], psi, Y, Yp, Ypp)
    elif kind == SHAPE_ROUNDED_RECTANGLE:
        rounded_rectangle_boundary(params, psi, Y, Yp, Ypp)
    elif kind == SHAPE_SUPERELLIPSE:
        superellipse_section_boundary(params, psi, Y, Yp, Ypp)
    elif kind == SHAPE_ROUNDED_POLYGON:
        rounded_polygon_boundary(params, psi, Y, Yp, Ypp)
    else:
        for c in range(2):
            Y[c] = np.nan
            Yp[c] = np.nan
            Ypp[c] = np.nan


@njit
def section_contains(kind, params, y, z):
    """Whether the point (y, z) lies inside the compiled hole section (on the wall counts);
    an unknown ``kind``: nowhere (the beam axis is then outside the bore at once)."""
    if kind == SHAPE_CIRCLE:
        return circle_contains(params, y, z)
    if kind == SHAPE_ROUNDED_RECTANGLE:
        return rounded_rectangle_contains(params, y, z)
    if kind == SHAPE_SUPERELLIPSE:
        return superellipse_contains(params, y, z)
    if kind == SHAPE_ROUNDED_POLYGON:
        return rounded_polygon_contains(params, y, z)
    return False

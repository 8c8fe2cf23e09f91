"""Section kernels of the clearance sliding joint (docs/theory.md §II.2): the beam's section ellipse
in a hole section, the section state (crossing + ellipse) and section coordinates. The
centreline geometry they build on (point, plane crossing, closest point) is
:mod:`flexmbs.elements.centerline`, re-exported here.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import njit
from ..elements.centerline import (
    beam_point,
    closest_point,
    closest_point_kernel,
    dot3,
    section_crossing,
    section_crossing_kernel,
)
from ..elements.hermite import element_point_values, shape_xi

__all__ = [
    "beam_point",
    "shape_xi",
    "section_crossing",
    "section_crossing_kernel",
    "closest_point_kernel",
    "section_ellipse",
    "section_ellipse_at",
    "closest_point",
    "to_section",
    "from_section",
]


@njit(inline="always")
def _ellipse_axes(tangent_vec, normal, e_y, e_z, r_b):
    """:func:`section_ellipse` with the axes as 3-tuples (no allocation): the one statement."""
    nt = math.sqrt(dot3(tangent_vec, tangent_vec))
    t = (tangent_vec[0] / nt, tangent_vec[1] / nt, tangent_vec[2] / nt)
    c = abs(dot3(t, normal))
    eb = (t[1] * normal[2] - t[2] * normal[1], t[2] * normal[0] - t[0] * normal[2],
          t[0] * normal[1] - t[1] * normal[0])
    sn = math.sqrt(dot3(eb, eb))
    if sn < 1e-10:
        return r_b, r_b, (e_y[0], e_y[1], e_y[2]), (e_z[0], e_z[1], e_z[2]), c
    eb = (eb[0] / sn, eb[1] / sn, eb[2] / sn)
    ea = (normal[1] * eb[2] - normal[2] * eb[1], normal[2] * eb[0] - normal[0] * eb[2],
          normal[0] * eb[1] - normal[1] * eb[0])
    a = r_b / c if c > 0.0 else np.inf
    return a, r_b, ea, eb, c


@njit
def section_ellipse(tangent_vec, normal, e_y, e_z, r_b):
    """Tangent-cylinder section ellipse (docs/theory.md §II.2): ``(a, b, e_a, e_b, cos θ)``.

    ``b = r_b``, ``a = r_b / cos θ`` with ``cos θ = |t·n|``; ``e_b = t×n/|t×n|`` (minor axis),
    ``e_a = n×e_b`` (in-plane tangent direction, major axis). When ``|t×n| < 1e-10`` the section is
    a circle and ``e_a = e_y``, ``e_b = e_z``. ``cos θ = 0`` (beam in the plane) gives ``a = inf``.
    """
    a, b, ea3, eb3, c = _ellipse_axes(tangent_vec, normal, e_y, e_z, r_b)
    ea = np.empty(3)
    eb = np.empty(3)
    for i in range(3):
        ea[i] = ea3[i]
        eb[i] = eb3[i]
    return a, b, ea, eb, c


@njit
def to_section(x, origin, e_y, e_z):
    """2D section coordinates ``((x − O)·e_y, (x − O)·e_z)`` of a 3D point (docs/theory.md §II.2)."""
    d = x - origin
    out = np.empty(2)
    out[0] = dot3(d, e_y)
    out[1] = dot3(d, e_z)
    return out


@njit
def from_section(y, origin, e_y, e_z):
    """3D point ``O + y₀ e_y + y₁ e_z`` of 2D section coordinates."""
    return origin + y[0] * e_y + y[1] * e_z


@njit
def section_state(q_e, lengths, origin, normal, e_y, e_z, elem0, xi0, r_b, max_distance):
    """The beam in one hole section (docs/theory.md §II.2): the crossing of its axis with the section
    plane ``(origin, normal)`` (warm-started at ``(elem0, xi0)``, within ``max_distance`` of
    the origin) and the ellipse of its cross-section there, in section coordinates (e_y, e_z).

    Returns ``(found, e, xi, cy, cz, a, b, eax, eay)``: element and ξ of the crossing, ellipse
    centre, semi-axes ``a ≥ b`` and unit major axis. The one statement of the section loop used
    by detection, the initial check and the section output."""
    e, xi, found = section_crossing_kernel(q_e, lengths, origin, normal, elem0, xi0, 1e-12,
                                           np.int64(30), max_distance)
    if not found:
        return False, e, xi, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0
    cy, cz, a, b, eax, eay = section_ellipse_at(q_e, lengths, e, xi, origin, normal, e_y, e_z,
                                                r_b)
    return True, e, xi, cy, cz, a, b, eax, eay


@njit(refcount=False)
def section_ellipse_at(q_e, lengths, e, xi, origin, normal, e_y, e_z, r_b):
    """The beam's section ellipse where its axis crosses the plane at ``(e, xi)``, in section
    coordinates: ``(cy, cz, a, b, eax, eay)`` (centre, semi-axes a ≥ b, unit major axis)."""
    r, rx, _ = element_point_values(q_e[e], lengths[e], xi)
    a, b, ea3, _, _ = _ellipse_axes(rx, normal, e_y, e_z, r_b)
    cy = 0.0
    cz = 0.0
    for c in range(3):
        cy += (r[c] - origin[c]) * e_y[c]
        cz += (r[c] - origin[c]) * e_z[c]
    eax = dot3(ea3, e_y)
    eay = dot3(ea3, e_z)
    nrm = math.hypot(eax, eay)
    if nrm > 0.0:
        eax /= nrm
        eay /= nrm
    else:
        eax, eay = 1.0, 0.0
    if a < b:
        a = b
    return cy, cz, a, b, eax, eay

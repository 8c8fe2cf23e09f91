"""Compiled narrow phase of the clearance joint for circular bores (all sections in one call).

Chains the numba kernels of :mod:`flexmbs.contact.geometry` and
:func:`flexmbs.contact.sections.circle_stationary_points` (FORMULATION Part II §2-§4): section
crossing (warm-started), ellipse, broad phase, stationary points of the penetration, hole point
Q and its closest-point projection. Python then evaluates forces for the few penetrating points.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import njit
from .geometry import beam_point, closest_point_kernel, section_crossing_kernel, section_ellipse
from .sections import circle_stationary_points

#: columns of a candidate row
COLS = ("section", "index", "kind", "elem", "xi", "qx", "qy", "qz", "a", "b", "depth")


@njit
def detect_circle(qe, lengths, centre, A, stations, elem_ws, xi_ws, update, r_b, R, out):  # noqa: ANN001, ANN201
    """Penetrating candidates of every section into ``out`` (rows of :data:`COLS`); returns the
    number of rows, or ``-1 - k`` if the beam axis lies outside the bore at section k (the gap
    |Q - P| - r_b would read "open" again: the caller must reject the iterate).
    ``A`` = hole body rotation (columns: hole axis, e_y, e_z)."""
    n = A[:, 0].copy()
    ey = A[:, 1].copy()
    ez = A[:, 2].copy()
    origin = np.empty(3)
    count = 0
    for k in range(stations.size):
        for c in range(3):
            origin[c] = centre[c] + stations[k] * n[c]
        e, xi, found = section_crossing_kernel(qe, lengths, origin, n, elem_ws[k], xi_ws[k],
                                               1e-12, 30, 2.0 * R + r_b)
        if not found:
            return -1 - k   # no crossing near the section: the beam left the hole
        if update:
            elem_ws[k] = e
            xi_ws[k] = xi
        r, rx, _ = beam_point(qe, lengths, e, xi)
        a, b, ea3, _, _ = section_ellipse(rx, n, ey, ez, r_b)
        cy = 0.0
        cz = 0.0
        for c in range(3):
            cy += (r[c] - origin[c]) * ey[c]
            cz += (r[c] - origin[c]) * ez[c]
        if math.hypot(cy, cz) > R:
            return -1 - k   # the beam axis left the bore: the penetration is no longer defined
        if math.hypot(cy, cz) + a < R:
            continue   # broad phase: ellipse strictly inside the bore
        eax = ea3[0] * ey[0] + ea3[1] * ey[1] + ea3[2] * ey[2]
        eay = ea3[0] * ez[0] + ea3[1] * ez[1] + ea3[2] * ez[2]
        nrm = math.hypot(eax, eay)
        if nrm > 0.0:
            eax /= nrm
            eay /= nrm
        else:
            eax, eay = 1.0, 0.0
        if a < b:
            a = b
        phis, kinds = circle_stationary_points(cy, cz, eax, eay, a, b, R)
        for j in range(phis.size):
            ca = math.cos(phis[j])
            sa = math.sin(phis[j])
            x = cy + a * ca * eax - b * sa * eay
            y = cz + a * ca * eay + b * sa * eax
            rho = math.hypot(x, y)
            depth = rho - R
            if depth <= 0.0 or rho == 0.0 or count >= out.shape[0]:
                continue
            Q = np.empty(3)
            for c in range(3):
                Q[c] = origin[c] + R * (x / rho) * ey[c] + R * (y / rho) * ez[c]
            eP, xiP, _, _, _ = closest_point_kernel(qe, lengths, Q, e, xi, 1e-13, 30)
            row = out[count]
            row[0] = k
            row[1] = j
            row[2] = kinds[j]
            row[3] = eP
            row[4] = xiP
            row[5] = Q[0]
            row[6] = Q[1]
            row[7] = Q[2]
            row[8] = a
            row[9] = b
            row[10] = depth
            count += 1
    return count

"""Compiled narrow phase of the clearance joint for circular bores (all sections in one call).

Chains the numba kernels of :mod:`flexmbs.contact.geometry` and
:func:`flexmbs.contact.sections.circle_stationary_points` (FORMULATION Part II §2-§4): section
crossing (warm-started), ellipse, broad phase, stationary points of the penetration, hole point
Q and its closest-point projection (:func:`detect_circle`); then the penalty forces of a whole joint
(:func:`clearance_forces`) and its state update after a converged step
(:func:`clearance_post_step`), called by the joint in Python and by the compiled integrator.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import njit
from ..elements.rigid_body import _rotation_single
from .geometry import beam_point, closest_point_kernel, section_crossing_kernel, section_ellipse
from .pair import contact_force
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


@njit
def _frame(q, body_dofs, hole_point):  # noqa: ANN001, ANN202
    """Hole body [r, p], rotation A(p) (homogeneous) and hole centre r + A u_H."""
    qb = np.empty(7)
    for i in range(7):
        qb[i] = q[body_dofs[i]]
    A = _rotation_single(qb[3:7])
    centre = qb[0:3] + A @ hole_point
    return qb, A, centre


@njit
def clearance_forces(q, v, body_dofs, elem_dofs, lengths, hole_point, stations, elem_ws, xi_ws,  # noqa: ANN001, ANN201, PLR0913
                     r_b, R, law, mu, eps_v, approach, qe, rows, want_tangent, r_q,
                     K_out, C_out, elem_out):
    """Residual of one clearance joint with a circular bore (FORMULATION II §8): detection of all
    sections at the warm starts (not updated), penalty force of every penetrating point (sign
    +1 at maxima, −1 at minima, §3) subtracted from ``r_q``. With ``want_tangent`` the signed
    Gauss–Newton blocks (19×19, local [r_H, p, e_k]) go to ``K_out``/``C_out`` and the element
    to ``elem_out``. Returns ``(count, scale)``; ``count = −1 − k`` if the beam axis left the
    bore at section k."""
    qb, A, centre = _frame(q, body_dofs, hole_point)
    vb = np.empty(7)
    for i in range(7):
        vb[i] = v[body_dofs[i]]
    ne = elem_dofs.shape[0]
    for e in range(ne):
        for k in range(12):
            qe[e, k] = q[elem_dofs[e, k]]
    m = detect_circle(qe[:ne], lengths, centre, A, stations, elem_ws, xi_ws, False, r_b, R, rows)
    if m < 0:
        return m, 0.0
    Qc = np.empty(19)
    K = np.empty((19, 19))
    C = np.empty((19, 19))
    geo = np.empty(12)
    ve = np.empty(12)
    u_Q = np.empty(3)
    count = 0
    scale = 0.0
    for i in range(m):
        row = rows[i]
        k, j, eP = int(row[0]), int(row[1]), int(row[3])
        sign = row[2]
        for c in range(3):
            u_Q[c] = (A[0, c] * (row[5] - qb[0]) + A[1, c] * (row[6] - qb[1])
                      + A[2, c] * (row[7] - qb[2]))
        for c in range(12):
            ve[c] = v[elem_dofs[eP, c]]
        g, _, _, _ = contact_force(qb, vb, u_Q, qe[eP], ve, lengths[eP], row[4], r_b, law, mu,
                                   eps_v, approach[k, j], want_tangent, Qc, K, C, geo)
        if g >= 0.0:
            continue
        for c in range(7):
            r_q[body_dofs[c]] -= sign * Qc[c]
        for c in range(12):
            r_q[elem_dofs[eP, c]] -= sign * Qc[7 + c]
        for c in range(19):
            if abs(Qc[c]) > scale:
                scale = abs(Qc[c])
        if want_tangent:
            for a in range(19):
                for b in range(19):
                    K_out[count, a, b] = sign * K[a, b]
                    C_out[count, a, b] = sign * C[a, b]
            elem_out[count] = eP
        count += 1
    return count, scale


@njit
def clearance_post_step(q, v, body_dofs, elem_dofs, lengths, hole_point, stations, elem_ws,  # noqa: ANN001, ANN201, PLR0913
                        xi_ws, r_b, R, law, mu, eps_v, approach, active, qe, rows):
    """After a converged step: warm starts of the section crossings moved to the new state, the
    approach velocity ``−ġ_N`` stored at the onset of every contact point (dissipative laws),
    released for points no longer in contact. Returns 0, or ``−1 − k`` (axis left the bore)."""
    qb, A, centre = _frame(q, body_dofs, hole_point)
    vb = np.empty(7)
    for i in range(7):
        vb[i] = v[body_dofs[i]]
    ne = elem_dofs.shape[0]
    for e in range(ne):
        for k in range(12):
            qe[e, k] = q[elem_dofs[e, k]]
    m = detect_circle(qe[:ne], lengths, centre, A, stations, elem_ws, xi_ws, True, r_b, R, rows)
    if m < 0:
        return m
    Qc = np.empty(19)
    K = np.empty((19, 19))
    geo = np.empty(12)
    ve = np.empty(12)
    u_Q = np.empty(3)
    now = np.zeros(active.shape, dtype=np.bool_)
    for i in range(m):
        row = rows[i]
        k, j, eP = int(row[0]), int(row[1]), int(row[3])
        for c in range(3):
            u_Q[c] = (A[0, c] * (row[5] - qb[0]) + A[1, c] * (row[6] - qb[1])
                      + A[2, c] * (row[7] - qb[2]))
        for c in range(12):
            ve[c] = v[elem_dofs[eP, c]]
        g, gdot, _, _ = contact_force(qb, vb, u_Q, qe[eP], ve, lengths[eP], row[4], r_b, law, mu,
                                      eps_v, approach[k, j], False, Qc, K, K, geo)
        if g < 0.0:
            now[k, j] = True
            if not active[k, j]:
                approach[k, j] = -gdot
    for k in range(active.shape[0]):
        for j in range(active.shape[1]):
            if not now[k, j]:
                approach[k, j] = 0.0
            active[k, j] = now[k, j]
    return 0

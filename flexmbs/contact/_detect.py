"""Compiled narrow phase of the clearance joint (all sections of a joint in one call; circular
bores by the closed form, other compiled sections by the generic common-normal detector).

Chains the numba kernels of :mod:`flexmbs.contact.geometry`, :mod:`flexmbs.contact.stationary`
and :func:`flexmbs.contact.sections.circle_stationary_points` (docs/theory.md §II.2-§II.4):
section crossing (warm-started), ellipse, broad phase, stationary points of the penetration,
hole point Q and its closest-point projection (:func:`detect_section`); the tip sections of an
open bore (:func:`place_tips`). The forces, the tracked contacts and the assembler's term of the
clearance joints are in :mod:`flexmbs.contact.clearance_term`.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import njit
from ..elements.centerline import (
    beam_point,
    element_crossings,
    element_plane_range,
)
from ..elements.hermite import element_point_values
from .bores import section_between, sections_near
from .geometry import closest_point_kernel, section_ellipse_at
from .sections import (
    SHAPE_CIRCLE,
    SHAPE_SAMPLES,
    circle_stationary_points,
    section_boundary,
    section_contains,
)
from .shapes.detector import common_normal_points
from .stationary import PAIR_MARGIN, line_model_points, stationary_pair

#: columns of a candidate row (from ``gap`` on filled by :func:`clearance_forces`; the
#: contact's force and geometry in the last ten: what an output at the state reads)
COLS = ("section", "index", "kind", "elem", "xi", "qx", "qy", "qz", "a", "b", "depth", "psi", "gap",
        "gap_rate", "phi", "dx", "dy", "dz", "stick", "elem_i", "xi_i",
        "f_n", "xi_p", "nx", "ny", "nz", "px", "py", "pz", "cx", "cy", "cz", "fx", "fy", "fz",
        "fade")
#: the contact's gap and gap rate: columns gap, gap_rate
GAP_COL = 12
#: first column of the friction history after the step (``d_new`` (3), ``stick``; pair.N_GEO)
ANCHOR_COL = 15
#: the section crossing a row's contact belongs to (element, ξ): columns elem_i, xi_i
CROSSING_COL = 19
#: the contact's normal force and its beam point's ξ: columns f_n, xi_p
FORCE_COL = 21
#: first column of the contact's ``[n, P, Q, F_H]`` (pair.N_GEO's first 12: normal, beam
#: point, hole point, force on the hole)
GEOMETRY_COL = 23
#: the weight of the contact near the beam's end (:func:`end_fade`): column fade
FADE_COL = COLS.index("fade")
N_COLS = len(COLS)


#: stationary points of one section kept at most (a flat side and two corners can each touch)
MAX_CANDIDATES = 8
#: crossings of one section plane by the beam kept at most (a beam looping back in a tube)
MAX_CROSSINGS = 4
#: :func:`detect_section`'s float work (its vectors and candidate arrays, carved in order)
DETECT_WORK = 4 * 3 + 3 * 2 + 3 * MAX_CANDIDATES + 3 * 3 + 10
#: :func:`detect_section`'s int work past the sections: the search stacks (sections,
#: elements), the candidates' kinds, the line model's signs (its ``work`` holds
#: ``n_sections + DETECT_INT_WORK``)
DETECT_INT_WORK = 64 + MAX_CANDIDATES + 5 + 64
#: section slots of a joint past its bore's sections: one per end of the beam (first node,
#: last node), the tip sections of an open bore (:func:`place_tips`)
N_TIPS = 2
#: a tip section cuts the beam this many beam radii behind its end (measured along the beam)
TIP_SETBACK = 0.5
#: a bore's section takes in a contact near an end of the beam over this many beam radii of
#: the end past its plane (:func:`end_fade`; the tip section, TIP_SETBACK radii behind the
#: end, holds the stretch beyond)
FADE_LENGTH = TIP_SETBACK


@njit(inline="always")
def _section_plane(r_H, A, u_o, frame, origin, n, ey, ez):
    """Origin ``r_H + A u_o`` and axes ``A frame`` (normal, e_y, e_z) of a hole section."""
    for c in range(3):
        origin[c] = r_H[c] + A[c, 0] * u_o[0] + A[c, 1] * u_o[1] + A[c, 2] * u_o[2]
        n[c] = A[c, 0] * frame[0, 0] + A[c, 1] * frame[1, 0] + A[c, 2] * frame[2, 0]
        ey[c] = A[c, 0] * frame[0, 1] + A[c, 1] * frame[1, 1] + A[c, 2] * frame[2, 1]
        ez[c] = A[c, 0] * frame[0, 2] + A[c, 1] * frame[1, 2] + A[c, 2] * frame[2, 2]


@njit
def reset_crossings(elem_out, out_list):
    """``elem_out[k] = −1`` wherever it is set, from its list ``out_list`` (``[count, k₀, k₁,
    …]``, count −1: not known, every section is reset); the list is emptied. Sections never
    crossed cost nothing."""
    count = out_list[0]
    if count < 0:
        for k in range(elem_out.shape[0]):
            elem_out[k] = -1
    else:
        for i in range(count):
            elem_out[out_list[1 + i]] = -1
    out_list[0] = 0


@njit(inline="always")
def _to_body(x, r_H, A, out):
    """Body coordinates ``Aᵀ(x − r_H)`` of the point x (A homogeneous in p: divided by |p|⁴)."""
    scale = A[0, 0] * A[0, 0] + A[1, 0] * A[1, 0] + A[2, 0] * A[2, 0]
    for c in range(3):
        out[c] = ((x[0] - r_H[0]) * A[0, c] + (x[1] - r_H[1]) * A[1, c]
                  + (x[2] - r_H[2]) * A[2, c]) / scale


@njit
def end_fade(qe, lengths, e, origin, n, r_b):
    """Weight of a bore section's contact whose crossing lies on element ``e`` near an end of
    the beam (docs/design-notes.md, "A tip reaching a section"): with ``h = n·(r_end − o)``
    the end node's distance from the section plane (``origin``, normal ``n``) and ``d = σ h``
    how far the end is past it (σ = ±1: the end's tangent side), ``w = x²(3 − 2x)``,
    ``x = d/ℓ`` clipped to [0, 1], ``ℓ = min(FADE_LENGTH r_b, L_e/2)``. A section a tip
    reaches takes its contact in from zero instead of at once (k δ where the tip is δ outside
    the section's wall). Returns ``(w, dw/dh, end)``; ``end`` +1: the last node, −1: the
    first, 0: ``e`` is no end element or the end is ℓ or more past the plane (w = 1)."""
    ne = qe.shape[0]
    best_w, best_s, best_end = 1.0, 0.0, 0
    for side in range(2):
        end = -1 if side == 0 else 1
        ee = 0 if end < 0 else ne - 1
        if e != ee:
            continue
        r, rx, _ = element_point_values(qe[ee], lengths[ee], 0.0 if end < 0 else 1.0)
        h = n[0] * (r[0] - origin[0]) + n[1] * (r[1] - origin[1]) + n[2] * (r[2] - origin[2])
        tn = n[0] * rx[0] + n[1] * rx[1] + n[2] * rx[2]
        sigma = float(end) if tn >= 0.0 else -float(end)
        ell = min(FADE_LENGTH * r_b, 0.5 * lengths[ee])
        x = sigma * h / ell
        if x >= 1.0:
            continue
        w, slope = 0.0, 0.0
        if x > 0.0:
            w = x * x * (3.0 - 2.0 * x)
            slope = 6.0 * x * (1.0 - x) * sigma / ell
        if w < best_w:
            best_w, best_s, best_end = w, slope, end
    return best_w, best_s, best_end


@njit(inline="always")
def _cross_section(qe, lengths, e, k, origin, n, elem_ws, xi_ws, roots, cross_n, cross_e,
                   cross_xi, touched, n_touched):
    """The crossings of element e with the plane of section k (none unless its control points
    straddle the plane; warm-started at the last step's crossing), recorded up to
    :data:`MAX_CROSSINGS`; a section crossed for the first time joins ``touched``. Returns the
    new count of touched sections."""
    lo, hi = element_plane_range(qe[e], lengths[e], origin, n)
    if lo > 0.0 or hi < 0.0:
        return n_touched
    xi0 = xi_ws[k] if elem_ws[k] == e else -1.0     # the last step's crossing
    nr = element_crossings(qe, lengths, e, origin, n, 1e-12, np.int64(30), xi0, roots)
    ne = qe.shape[0]
    for j in range(nr):
        if cross_n[k] == 0:
            touched[n_touched] = k
            n_touched += 1
        if cross_n[k] < MAX_CROSSINGS:
            ee = min(int(math.floor(roots[j])), ne - 1)
            cross_e[k, cross_n[k]] = ee
            cross_xi[k, cross_n[k]] = roots[j] - ee
            cross_n[k] += 1
    return n_touched


@njit(internal=True)
def _lost_crossing(qe, lengths, r_H, A, origins, frames, n_reg, elem_ws, ws_list, elem_out, r_b,
                   shape, params, R_out, origin, n, ey, ez, roots):
    """An open bore: a section crossed inside the bore at the step's start (``elem_ws[k] ≥ 0``)
    and not now. Legitimate if the beam has left the plane there (its end passed: the elements
    around the tracked one no longer cross it); if they cross it outside the bore, at any
    distance, the iterate pushed the axis through the wall (a Newton step can jump farther
    than the section's reach, where the crossing would otherwise read "another part of the
    beam"): ``-1 - k``, else 0. End faces excepted (the beam outside the mouth). The sections
    crossed at the step's start are those of ``ws_list`` (see :func:`reset_crossings`); the
    bore's own sections are the first ``n_reg`` (tip sections move: not checked here)."""
    ns = origins.shape[0]
    ne = qe.shape[0]
    listed = ws_list[0] >= 0
    for i in range(ws_list[0] if listed else ns):
        k = ws_list[1 + i] if listed else i
        if k < 1 or k > n_reg - 2:
            continue
        e0 = elem_ws[k]
        if e0 < 0 or elem_out[k] >= 0:
            continue
        _section_plane(r_H, A, origins[k], frames[k], origin, n, ey, ez)
        for e in range(max(0, e0 - 2), min(ne, e0 + 3)):
            lo, hi = element_plane_range(qe[e], lengths[e], origin, n)
            if lo > 0.0 or hi < 0.0:
                continue
            nr = element_crossings(qe, lengths, e, origin, n, 1e-12, np.int64(30), -1.0, roots)
            for j in range(nr):
                ee = min(int(math.floor(roots[j])), ne - 1)
                cy, cz, _, _, _, _ = section_ellipse_at(qe, lengths, ee, roots[j] - ee, origin,
                                                        n, ey, ez, r_b)
                if not section_contains(shape, params, cy, cz):
                    return -1 - k
    return 0


@njit
def detect_section(qe, lengths, r_H, A, origins, frames, tree_c, tree_r, tree_lo, tree_hi, etree,
                   open_ends, tip_on, cross_n, cross_e, cross_xi, touched, work, elem_ws, xi_ws, ws_list,
                   elem_out, xi_out, out_list, r_b, shape, params, R_out, R_in, consistent, paper,
                   out, fwork):
    """Penetrating candidates of every section into ``out`` (rows of :data:`COLS`); returns the
    number of rows, or ``-1 - k`` if the beam axis lies outside the bore at section k (the gap
    |Q - P| - r_b would read "open" again: the caller must reject the iterate).
    ``r_H``, ``A``: the hole body's position and rotation; section k lies in the plane through
    ``r_H + A origins[k]`` with the axes ``A frames[k]`` (columns: plane normal, e_y, e_z; body
    coordinates, :meth:`flexmbs.contact.joint.Hole.frames`); ``shape``, ``params``: the
    compiled section (:func:`flexmbs.contact.sections.section_boundary`), ``R_out``/``R_in`` its
    bounding and inscribed radii. Circles take the closed-form quartic (§3), other shapes the
    generic common-normal detector (§6); with ``consistent`` each point is instead a stationary
    pair of the wall and the beam axis (§4b, :mod:`flexmbs.contact.stationary`), seeded by the
    line model, and its row's ``depth`` is the penetration ``r_b − |x − Y|`` (``phi`` = ψ).
    ``paper`` None: no joint of the model uses the paper's detection (:func:`_paper_candidates`
    compiled out; ``consistent`` is then always set).

    The crossings (issue 30, "many sections, cheap"; issue 52, "many holes on one beam"): the
    beam's element tree ``etree`` (:func:`~flexmbs.elements.centerline.element_tree` at ``qe``)
    is descended to the elements whose spheres may meet the bore's (its section tree's root),
    and each such element's bounding sphere is put to the bore's section tree
    (:func:`~flexmbs.contact.bores.sections_near`, body coordinates), so an element or a
    section far from the other costs nothing; a section near an element
    whose control points straddle its plane gets the element's crossings
    (:func:`~flexmbs.elements.centerline.element_crossings`), up to :data:`MAX_CROSSINGS` (a
    beam looping back crosses a plane twice). A crossing farther than ``2 R_out + r_b`` from
    the section's centre is another part of the beam, not in the bore; nearer but outside the
    bore it is the axis through the wall (an error), except at an end section of a bore with
    ``open_ends`` (the beam outside the mouth). Without ``open_ends`` every section must be
    crossed inside the bore. ``cross_n`` (zero on entry and on return), ``cross_e``,
    ``cross_xi``, ``touched`` (ns,), ``work`` (int, ns + :data:`DETECT_INT_WORK`) and ``fwork``
    (float, :data:`DETECT_WORK`: nothing is allocated) are work arrays; the first crossing
    inside the bore of each section goes to ``(elem_out, xi_out)`` (the next step's start,
    ``(elem_ws, xi_ws)``; −1: not crossed inside the bore) and every row records its own
    crossing (columns ``elem_i``, ``xi_i``). ``out_list`` and ``ws_list`` list the sections
    whose ``elem_out``, ``elem_ws`` are set (:func:`reset_crossings`): a section far from the
    beam costs nothing.

    The last ``tip_on.size`` sections are the tip sections (:func:`place_tips`): one whose
    ``tip_on`` is set is crossed by the elements at its end of the beam (the first, the last)
    and is otherwise a section like the bore's own."""
    ns = origins.shape[0]
    n_reg = ns - tip_on.shape[0]
    ne = qe.shape[0]
    reach = 2.0 * R_out + r_b
    n = fwork[0:3]
    ey = fwork[3:6]
    ez = fwork[6:9]
    origin = fwork[9:12]
    Y = fwork[12:14]
    Yp = fwork[14:16]
    Ypp = fwork[16:18]
    o = 18
    psis = fwork[o:o + MAX_CANDIDATES]
    phis = fwork[o + MAX_CANDIDATES:o + 2 * MAX_CANDIDATES]
    depths = fwork[o + 2 * MAX_CANDIDATES:o + 3 * MAX_CANDIDATES]
    o += 3 * MAX_CANDIDATES
    xb = fwork[o + 3:o + 6]
    roots = fwork[o + 6:o + 9]
    lm_work = fwork[o + 9:o + 19]
    stack = work[:64]
    kinds = work[64:64 + MAX_CANDIDATES]
    lm_signs = work[64 + MAX_CANDIDATES:64 + MAX_CANDIDATES + 5]
    estack = work[64 + MAX_CANDIDATES + 5:DETECT_INT_WORK]
    near = work[DETECT_INT_WORK:]
    # ---- broad phase: the elements near the bore, the sections each of them comes near,
    # and its crossings with them (elements in ascending order, as a scan of all would)
    n_touched = 0
    P = etree.shape[0] // 2
    if tree_r.shape[0] > 0 and tree_r[0] >= 0.0:
        # an inner node's sphere in body coordinates: |_to_body(x) − _to_body(y)| ≤ f |x − y|
        scale = A[0, 0] * A[0, 0] + A[1, 0] * A[1, 0] + A[2, 0] * A[2, 0]
        f = 0.0
        for a in range(3):
            for c in range(3):
                f += A[a, c] * A[a, c]
        f = math.sqrt(f) / scale
        top = 0
        estack[0] = 1
        while top >= 0:
            i = estack[top]
            top -= 1
            if etree[i, 3] < 0.0:
                continue
            if i < P:
                _to_body(etree[i, :3], r_H, A, xb)
                d2 = ((xb[0] - tree_c[0, 0]) ** 2 + (xb[1] - tree_c[0, 1]) ** 2
                      + (xb[2] - tree_c[0, 2]) ** 2)
                reach_i = tree_r[0] + 1.01 * f * etree[i, 3] + 1e-12
                if d2 <= reach_i * reach_i:
                    top += 1
                    estack[top] = 2 * i + 1     # the right half after the left one
                    top += 1
                    estack[top] = 2 * i
                continue
            e = i - P                           # its element_bounding_sphere
            _to_body(etree[i, :3], r_H, A, xb)
            m = sections_near(tree_c, tree_r, tree_lo, tree_hi, xb, 1.01 * etree[i, 3] + 1e-12,
                              stack, near)
            for ii in range(m):
                k = near[ii]
                _section_plane(r_H, A, origins[k], frames[k], origin, n, ey, ez)
                n_touched = _cross_section(qe, lengths, e, k, origin, n, elem_ws, xi_ws, roots,
                                           cross_n, cross_e, cross_xi, touched, n_touched)
    # the tip sections: crossed by the elements at their end of the beam
    for t in range(tip_on.shape[0]):
        if not tip_on[t]:
            continue
        k = n_reg + t
        _section_plane(r_H, A, origins[k], frames[k], origin, n, ey, ez)
        e_end = 0 if t == 0 else ne - 1
        for e in range(max(0, e_end - 1), min(ne, e_end + 2)):
            n_touched = _cross_section(qe, lengths, e, k, origin, n, elem_ws, xi_ws, roots,
                                       cross_n, cross_e, cross_xi, touched, n_touched)
    reset_crossings(elem_out, out_list)    # crossed inside the bore in this evaluation: below
    # sections in order (deterministic rows, as the sections lie along the bore)
    for i in range(1, n_touched):
        v = touched[i]
        j = i - 1
        while j >= 0 and touched[j] > v:
            touched[j + 1] = touched[j]
            j -= 1
        touched[j + 1] = v
    count = 0
    status = 0
    expect = 0                     # closed bores: the next section that must be crossed
    for t in range(n_touched):
        k = touched[t]
        if not open_ends and k != expect:
            status = -1 - expect   # a section without a crossing: the beam left the hole
            break
        expect = k + 1
        _section_plane(r_H, A, origins[k], frames[k], origin, n, ey, ez)
        first = count
        inside = 0
        for cc in range(cross_n[k]):
            e = cross_e[k, cc]
            xi = cross_xi[k, cc]
            cy, cz, a, b, eax, eay = section_ellipse_at(qe, lengths, e, xi, origin, n, ey, ez,
                                                        r_b)
            if math.hypot(cy, cz) > reach:
                continue           # another part of the beam, away from the bore
            if not section_contains(shape, params, cy, cz):
                if open_ends and (k == 0 or k == n_reg - 1):
                    continue       # the beam crosses an end face outside the mouth
                status = -1 - k    # the axis went through the wall
                break
            if inside == 0:
                elem_out[k] = e
                xi_out[k] = xi
                out_list[0] += 1
                out_list[out_list[0]] = k
            inside += 1
            if math.hypot(cy, cz) + a < R_in:
                continue   # broad phase: ellipse strictly inside the bore
            if consistent:
                # line-model seeds near contact, converged on the axis
                m = line_model_points(shape, params, cy, cz, eax, eay, a, b, SHAPE_SAMPLES,
                                      psis, kinds, depths, lm_work, lm_signs)
                for j in range(m):
                    if r_b - depths[j] <= -PAIR_MARGIN * (R_in - r_b) or count >= out.shape[0]:
                        continue
                    psi, kind, eP, xiP, ell, _, Q0, Q1, Q2 = stationary_pair(
                        qe, lengths, origin, ey, ez, shape, params, psis[j], kinds[j], e, xi,
                        Y, Yp, Ypp)
                    if ell >= r_b:
                        continue
                    dup = False
                    for i in range(first, count):
                        if angle_distance(out[i, 11], psi) < 1e-7:
                            dup = True
                    if dup:
                        continue
                    row = out[count]
                    row[0] = k
                    row[1] = j
                    row[2] = kind
                    row[3] = eP
                    row[4] = xiP
                    row[5] = Q0
                    row[6] = Q1
                    row[7] = Q2
                    row[8] = a
                    row[9] = b
                    row[10] = r_b - ell
                    row[11] = psi
                    row[12] = 0.0
                    row[13] = 0.0
                    row[14] = psi
                    row[CROSSING_COL] = e
                    row[CROSSING_COL + 1] = xi
                    count += 1
                continue
            count = _paper_candidates(paper, qe, lengths, k, e, xi, cy, cz, eax, eay, a, b,
                                      origin, ey, ez, shape, params, psis, phis, kinds, depths,
                                      Y, Yp, Ypp, out, count)

        if status != 0:
            break
        if inside == 0 and not open_ends:
            status = -1 - k
            break
    if status == 0 and not open_ends and expect != n_reg:
        status = -1 - expect
    if status == 0 and open_ends:
        status = _lost_crossing(qe, lengths, r_H, A, origins, frames, n_reg, elem_ws, ws_list,
                                elem_out, r_b, shape, params, R_out, origin, n, ey, ez, roots)
    for t in range(n_touched):
        cross_n[touched[t]] = 0
    if status != 0:
        return status
    return count


@njit(internal=True)
def _paper_candidates(paper, qe, lengths, k, e, xi, cy, cz, eax, eay, a, b, origin, ey, ez,
                      shape, params, psis, phis, kinds, depths, Y, Yp, Ypp, out, count):
    """The paper's detection of the section-k ellipse crossed by element e at ξ (docs/theory.md
    §II.6: common normals of ellipse and bore, then the closest point of the wall point on the
    axis) appended to ``out`` from row ``count``; returns the new count. ``paper`` None: no
    joint of the model uses this detection (its code is compiled out, _compiled_view)."""
    if paper is None:
        return count
    if shape == SHAPE_CIRCLE:
        R = params[0]
        cphi, ckind = circle_stationary_points(cy, cz, eax, eay, a, b, R)
        m = 0
        for j in range(min(cphi.size, MAX_CANDIDATES)):
            ca = math.cos(cphi[j])
            sa = math.sin(cphi[j])
            x = cy + a * ca * eax - b * sa * eay
            y = cz + a * ca * eay + b * sa * eax
            rho = math.hypot(x, y)
            if rho == 0.0:
                continue
            psis[m] = math.atan2(y, x)
            phis[m] = cphi[j]
            kinds[m] = ckind[j]
            depths[m] = rho - R
            m += 1
    else:
        m = common_normal_points(shape, params, cy, cz, eax, eay, a, b, SHAPE_SAMPLES,
                                 psis, phis, kinds, depths)
    for j in range(m):
        if depths[j] <= 0.0 or count >= out.shape[0]:
            continue
        section_boundary(shape, params, psis[j], Y, Yp, Ypp)
        Q = np.empty(3)
        for c in range(3):
            Q[c] = origin[c] + Y[0] * ey[c] + Y[1] * ez[c]
        eP, xiP, _, _, _ = closest_point_kernel(qe, lengths, Q, e, xi, 1e-13,
                                        np.int64(30))
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
        row[10] = depths[j]
        row[11] = psis[j]
        row[12] = 0.0
        row[13] = 0.0
        row[14] = phis[j]
        row[CROSSING_COL] = e
        row[CROSSING_COL + 1] = xi
        count += 1
    return count


@njit
def place_tips(qe, lengths, r_H, A, origins, frames, stations, tree_c, tree_r, tree_lo, tree_hi,
               tip_reach, r_b, shape, params, tip_on, tip_station, work):
    """The tip sections of an open bore at the start of a step (issue 30, "the free tip"):
    an end of the beam inside the bore past the last section it crosses would otherwise go
    into the wall unchecked. For each end (first node, last node) the beam point
    :data:`TIP_SETBACK` radii behind it is located between two neighbouring sections k, k+1
    (signed distances to their planes, ``λ = d_k / (d_k − d_{k+1})``); the tip section is the
    plane there (:func:`~flexmbs.contact.bores.section_between`, into the slot
    ``n_reg + t`` of ``origins``, ``frames``). It is fixed in the body during the step, so it
    is a section like the bore's own: the same detection, contact law, friction history and
    exact tangent. ``tip_on[t]``: placed (the beam crosses it inside the bore);
    ``tip_station[t]``: its station along the bore. ``tip_reach``: the largest distance
    between neighbouring sections; ``work``: int64 (n_sections + 64 at least)."""
    n_tips = tip_on.shape[0]
    n_reg = origins.shape[0] - n_tips
    ne = qe.shape[0]
    u = np.empty(3)
    origin = np.empty(3)
    n = np.empty(3)
    ey = np.empty(3)
    ez = np.empty(3)
    roots = np.empty(3)
    stack = work[:64]
    near = work[64:]
    for t in range(n_tips):
        tip_on[t] = False
        if n_reg < 2 or ne == 0:
            continue
        e_end = 0 if t == 0 else ne - 1
        back = min(TIP_SETBACK * r_b / lengths[e_end], 1.0)
        xi = back if t == 0 else 1.0 - back
        X, _, _ = beam_point(qe, lengths, e_end, xi)
        _to_body(X, r_H, A, u)
        m = sections_near(tree_c, tree_r, tree_lo, tree_hi, u, tip_reach, stack, near)
        best = -1
        best_lam = 0.0
        best_off = np.inf
        for i in range(m):
            k = near[i]
            if k > n_reg - 2:
                continue
            d0 = 0.0
            d1 = 0.0
            off = 0.0
            for c in range(3):
                d0 += frames[k, c, 0] * (u[c] - origins[k, c])
                d1 += frames[k + 1, c, 0] * (u[c] - origins[k + 1, c])
            if d0 < 0.0 or d1 >= 0.0:
                continue
            lam = d0 / (d0 - d1)
            for c in range(3):   # off the chord between the origins (a loop's other pass)
                w = u[c] - origins[k, c] - lam * (origins[k + 1, c] - origins[k, c])
                off += w * w
            if off < best_off:
                best, best_lam, best_off = k, lam, off
        if best < 0:
            continue              # outside the bore's length: no tip section
        j = n_reg + t
        section_between(origins, frames, stations, best, best_lam, origins[j], frames[j])
        _section_plane(r_H, A, origins[j], frames[j], origin, n, ey, ez)
        # the beam must cross it inside the bore: the crossing nearest the setback point
        near_s = -1.0
        for e in range(max(0, e_end - 1), min(ne, e_end + 2)):
            nr = element_crossings(qe, lengths, e, origin, n, 1e-12, np.int64(30), -1.0, roots)
            for r in range(nr):
                if near_s < 0.0 or abs(roots[r] - e_end - xi) < abs(near_s - e_end - xi):
                    near_s = roots[r]
        if near_s < 0.0:
            continue
        ee = min(int(math.floor(near_s)), ne - 1)
        cy, cz, _, _, _, _ = section_ellipse_at(qe, lengths, ee, near_s - ee, origin, n, ey, ez,
                                                r_b)
        if section_contains(shape, params, cy, cz):
            tip_on[t] = True
            tip_station[t] = stations[best] + best_lam * (stations[best + 1] - stations[best])


@njit
def angle_distance(a, b):
    """Distance of two section angles on the circle [rad], in [0, π]."""
    d = abs(a - b) % (2.0 * np.pi)
    return min(d, 2.0 * np.pi - d)

"""The clearance joints' term of the assembler (:mod:`flexmbs.terms`): the penalty forces and
tangent blocks of a joint's detected points (:func:`clearance_forces`, docs/theory.md §II.4-§II.8),
the contacts tracked from step to step (:func:`clearance_update`: approach velocities, friction
anchors, stick states), and the packed part of all clearance joints with the kernels the driver
calls (:class:`ClearancePart`, :func:`clearance_terms`, :func:`clearance_post_step_all`,
:func:`clearance_set_bases`). The detection it calls is :mod:`flexmbs.contact._detect`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .._jit import njit
from ..codes import ERROR_CODES
from ..elements.centerline import element_tree
from ..elements.hermite import CENTERLINE_SIZE
from ..elements.rigid_body import rotation_into
from ._detect import (
    ANCHOR_COL,
    CROSSING_COL,
    DETECT_WORK,
    FADE_COL,
    FORCE_COL,
    GAP_COL,
    GEOMETRY_COL,
    MAX_CANDIDATES,
    N_TIPS,
    _section_plane,
    angle_distance,
    detect_section,
    end_fade,
    place_tips,
    reset_crossings,
)
from .bores import refit_section_tree
from .laws import mouth_radius
from .pair import (
    HIST_TWIST,
    N_GEO,
    N_HISTORY,
    N_LOCAL,
    N_TWIST,
    PAIR_WORK,
    TWIST_OFF,
    contact_force,
    is_pinned,
    xi_bounds,
)
from .sections import section_boundary
from .tangent import I_OFF, N_EXT, P_OFF, T_OFF, contact_tangent, fade_gradient
from .tube import (
    POSE_SIZE,
    POSE_WORK,
    SECTION_COORDS,
    TURN_SIZE,
    TubeSections,
    pose_curvature,
    section_turn,
    tube_pose,
)
from .tube import rebase as rebase_section

#: :func:`clearance_forces`' float work (:attr:`ClearancePart.fwork`): :func:`detect_section`'s,
#: then the hole body's pose, rotation and velocity, a contact's arrays and a tube section's
#: rotation (carved in order)
FORCES_WORK = (DETECT_WORK + 7 + 9 + 7 + N_LOCAL * (2 + 2 * N_LOCAL + N_EXT) + 3 * 2 + N_GEO
               + N_HISTORY + CENTERLINE_SIZE + 3 + PAIR_WORK + 9 + 12 + N_EXT)

#: a tube joint's float work (:attr:`ClearancePart.tube_work`): a section's pose, its rate and
#: its pose at the step's start (7 each), J, G and the pose block's product with J (7 ×
#: SECTION_COORDS each), H (SECTION_COORDS²), the outer element's section coordinates and
#: rates, the unit section (origin 0, axes I), :data:`~flexmbs.contact.tube.POSE_WORK` and a
#: rod section's turn (:data:`~flexmbs.contact.tube.TURN_SIZE`)
TUBE_WORK = (3 * POSE_SIZE + 3 * POSE_SIZE * SECTION_COORDS + SECTION_COORDS * SECTION_COORDS
             + 2 * SECTION_COORDS + 12 + POSE_WORK + TURN_SIZE)

#: two contact points of one section are the same contact from one step to the next if the
#: section angles of their hole points differ by less than this [rad] (docs/theory.md §II.3)
MATCH_ANGLE = 0.5


@njit
def tracked_slot(active, psi_track, k, psi):
    """Slot of the tracked contact of section k nearest to section angle ``psi`` (within
    :data:`MATCH_ANGLE`), −1 for a new contact."""
    best = MATCH_ANGLE
    slot = -1
    for s in range(active.shape[1]):
        if active[k, s]:
            d = angle_distance(psi_track[k, s], psi)
            if d < best:
                best = d
                slot = s
    return slot


@njit
def tracked_approach(approach, active, psi_track, k, psi):
    """Approach velocity stored for the contact of section k nearest to section angle ``psi``
    (:func:`tracked_slot`), 0 for a new contact."""
    slot = tracked_slot(active, psi_track, k, psi)
    return approach[k, slot] if slot >= 0 else 0.0


@njit
def contact_history(anchor, stuck, slot, k, q_start, body_dofs, elem_dofs, twist_dofs, hist):
    """History of a contact (pair.N_HISTORY) from its tracked slot (−1: a new contact, no
    anchor, counted as sticking) and the coordinates the step started from (the element's
    twists where it has them, ``twist_dofs`` ≥ 0)."""
    for c in range(3):
        hist[c] = anchor[k, slot, c] if slot >= 0 else 0.0
    hist[3] = stuck[k, slot] if slot >= 0 else 1.0
    for c in range(7):
        hist[4 + c] = q_start[body_dofs[c]]
    for c in range(CENTERLINE_SIZE):
        hist[11 + c] = q_start[elem_dofs[c]]
    for a in range(N_TWIST):
        hist[HIST_TWIST + a] = q_start[twist_dofs[a]] if twist_dofs[a] >= 0 else 0.0


@njit
def element_spin(q, v, twist_dofs, t_bar, spin):
    """The spin data (pair.N_SPIN) of a contact element: its nodes' twists, their rates and
    their charts' base tangents ``t_bar`` (2, 3); ``spin[0] = 0`` for an element without twist
    (``twist_dofs`` −1, a cable). ``spin`` None: no joint of the model holds a beam with
    twist (the rod's spin is compiled out of the contact, _compiled_view)."""
    if spin is None:
        return
    spin[0] = 1.0 if twist_dofs[0] >= 0 else 0.0
    for a in range(N_TWIST):
        spin[1 + a] = q[twist_dofs[a]] if twist_dofs[a] >= 0 else 0.0
        spin[3 + a] = v[twist_dofs[a]] if twist_dofs[a] >= 0 else 0.0
        for c in range(3):
            spin[5 + 3 * a + c] = t_bar[a, c]


@njit
def clearance_update(rows, m, sections, approach, active, psi_track, anchor, stuck):
    """Contact state after a converged step from the candidate rows of the converged state
    (with ``gap``, ``gap_rate`` and the friction history): every penetrating point is matched
    to the nearest tracked contact of its section (section angle, greedy by distance, within
    :data:`MATCH_ANGLE`) and keeps its approach velocity; a new one stores ``−ġ_N`` (approach
    velocity at onset, used by the dissipative laws); each takes its anchor and stick state
    from its row; tracked contacts not found are released (their anchors cleared). ``rows``
    sorted by section; ``sections`` (``[count, k₀, …]`` sorted, count −1: every section) the
    sections crossed at the step's start, where every tracked contact lies: O(rows + crossed
    sections) per step."""
    P = active.shape[1]
    taken = np.zeros(P, dtype=np.bool_)
    new_app = np.zeros(P)
    new_psi = np.zeros(P)
    new_anchor = np.zeros((P, 4))
    idx = np.empty(max(m, 1), dtype=np.int64)
    slot_of = np.empty(max(m, 1), dtype=np.int64)
    r0 = 0
    listed = sections[0] >= 0
    n_listed = sections[0] if listed else active.shape[0]
    w = 0
    while True:
        # the next section with rows (sorted by section, as detect_section writes them) or
        # tracked contacts (in the list of sections crossed at the step's start)
        k = -1
        if r0 < m:
            k = int(rows[r0, 0])
        if w < n_listed:
            kw = sections[1 + w] if listed else w
            if k < 0 or kw < k:
                k = kw
        if k < 0:
            break
        while w < n_listed and (sections[1 + w] if listed else w) <= k:
            w += 1
        nc = 0
        i = r0
        while i < m and int(rows[i, 0]) == k:
            if rows[i, 12] < 0.0:
                idx[nc] = i
                nc += 1
            i += 1
        r0 = i
        if nc == 0:
            tracked = False
            for s in range(P):
                if active[k, s]:
                    tracked = True
                    break
            if not tracked:
                continue
        taken[:] = False
        slot_of[:nc] = -1
        while True:   # greedy matching, nearest pair first
            best = MATCH_ANGLE
            bi = -1
            bs = -1
            for c in range(nc):
                if slot_of[c] >= 0:
                    continue
                for s in range(P):
                    if active[k, s] and not taken[s]:
                        d = angle_distance(psi_track[k, s], rows[idx[c], 11])
                        if d < best:
                            best = d
                            bi = c
                            bs = s
            if bi < 0:
                break
            slot_of[bi] = bs
            taken[bs] = True
        for c in range(min(nc, P)):
            i = idx[c]
            new_psi[c] = rows[i, 11]
            new_app[c] = approach[k, slot_of[c]] if slot_of[c] >= 0 else -rows[i, 13]
            for a in range(4):
                new_anchor[c, a] = rows[i, ANCHOR_COL + a]
        for s in range(P):
            if s < min(nc, P):
                approach[k, s] = new_app[s]
                psi_track[k, s] = new_psi[s]
                active[k, s] = True
                for a in range(3):
                    anchor[k, s, a] = new_anchor[s, a]
                stuck[k, s] = new_anchor[s, 3]
            else:
                approach[k, s] = 0.0
                psi_track[k, s] = 0.0
                active[k, s] = False
                for a in range(3):
                    anchor[k, s, a] = 0.0
                stuck[k, s] = 0.0


@njit
def _frame(q, body_dofs):
    """Hole body [r, p] and rotation A(p) (homogeneous) (:func:`_frame_into`)."""
    qb = np.empty(7)
    A = np.empty((3, 3))
    _frame_into(q, body_dofs, qb, A)
    return qb, A


@njit(inline="always")
def _frame_into(q, body_dofs, qb, A):
    """Hole body [r, p] into ``qb`` and its rotation A(p) (homogeneous) into ``A``."""
    for i in range(7):
        qb[i] = q[body_dofs[i]]
    rotation_into(qb[3:7], A)


@njit(inline="always")
def _tube_carve(tw):
    """The arrays of a tube joint's work (:data:`TUBE_WORK`; views, nothing allocated)."""
    P, CS = POSE_SIZE, SECTION_COORDS
    pose = tw[0:P]
    vel = tw[P:2 * P]
    start = tw[2 * P:3 * P]
    o = 3 * P
    J = tw[o:o + P * CS].reshape((P, CS))
    o += P * CS
    G = tw[o:o + P * CS].reshape((P, CS))
    o += P * CS
    H = tw[o:o + CS * CS].reshape((CS, CS))
    o += CS * CS
    qo = tw[o:o + CS]
    vo = tw[o + CS:o + 2 * CS]
    o += 2 * CS
    unit_o = tw[o:o + 3]
    unit_f = tw[o + 3:o + 12].reshape((3, 3))
    o += 12
    pw = tw[o:o + POSE_WORK]
    o += POSE_WORK
    turn = tw[o:o + TURN_SIZE]
    o += TURN_SIZE
    KJ = tw[o:o + P * CS].reshape((P, CS))
    return pose, vel, start, J, G, H, qo, vo, unit_o, unit_f, pw, turn, KJ


@njit
def tube_joint(tube, j):
    """Whether clearance joint j's bore is a flexible tube (``tube`` None: none is)."""
    if tube is None:
        return False
    return tube.on[j]


@njit
def window_row(cl, j, k):
    """The row of ``cl.window`` that holds the elements the plan follows section k of clearance
    joint j on: the joint's row, or for a flexible tube the row of the section's element (each
    of a tube's elements couples only with the inner beam near its own sections)."""
    return cl.win_row[j] + _tube_row(cl.tube, j, k)


@njit
def _tube_row(tube, j, k):
    """Section k's element's rank among tube joint j's (0: not a tube; ``tube`` None: none is)."""
    if tube is None:
        return 0
    if not tube.on[j]:
        return 0
    return tube.row[j, k]


@njit
def tube_section(tube, j, k, q, v, tw):
    """Pose, rate and ``J`` of section k of clearance joint j into ``tube_work`` when its bore
    is a flexible tube (:func:`~flexmbs.contact.tube.section_pose`); returns whether it is.
    ``tube`` None: no tube in the model (compiled out)."""
    if tube is None:
        return False
    if not tube.on[j]:
        return False
    pose, vel, _, J, _, _, qo, vo, _, _, pw, turn, _ = _tube_carve(tw)
    width = tube.width[j]
    for c in range(width):
        qo[c] = q[tube.dofs[j, k, c]]
        vo[c] = v[tube.dofs[j, k, c]] if v.size > 0 else 0.0
    tube_pose(qo, width, tube.length[j, k], tube.xi[j, k], tube.t_bar[j, k], tube.p0[j, k],
              tube.node_t[j, k], tube.node_d[j, k], tube.turn, turn, vo, pose, vel, J, pw)
    return True


@njit(inline="always")
def _tube_turn(tube, j, k, e, turn, second):
    """Section k's turn (:func:`~flexmbs.contact.tube.section_turn`) at the section coordinates
    ``e`` into ``turn``; returns ψ (0 for a cable's section)."""
    return section_turn(e, tube.width[j], tube.length[j, k], tube.xi[j, k], tube.t_bar[j, k],
                        tube.p0[j, k], tube.node_t[j, k], tube.node_d[j, k], tube.turn, turn,
                        second)


@njit
def tube_force(tube, j, k, J, Qc, sign, r_q):
    """A contact's force ``sign Qc[:7]`` on section k's pose, taken to the tube's element
    (``Jᵀ``) and subtracted from ``r_q``."""
    if tube is None:
        return
    for c in range(tube.width[j]):
        s = 0.0
        for a in range(7):
            s += J[a, c] * Qc[a]
        r_q[tube.dofs[j, k, c]] -= sign * s


@njit
def tube_start_pose(tube, j, k, q_start, tw):
    """Section k's pose at the step's start ``q_start`` into ``tube_work``'s ``start`` (the
    friction's reference, as a hole body's coordinates at the step's start); uses ``G`` and
    ``H`` as scratch."""
    if tube is None:
        return
    _, _, start, _, G, H, qo, vo, _, _, pw, turn, _ = _tube_carve(tw)
    width = tube.width[j]
    for c in range(width):
        qo[c] = q_start[tube.dofs[j, k, c]]
        vo[c] = 0.0
    tube_pose(qo, width, tube.length[j, k], tube.xi[j, k], tube.t_bar[j, k], tube.p0[j, k],
              tube.node_t[j, k], tube.node_d[j, k], tube.turn, turn, vo, start, H[0, :POSE_SIZE],
              G, pw)


@njit
def tube_place_sections(tube, j, q, n_bore, origins, frames, tree_c, tree_r, tree_lo, tree_hi,
                        reach, tip_on, tw):
    """The world origins and axes of tube joint j's sections at ``q`` into ``origins``,
    ``frames`` (the detection then takes the identity as the hole body's pose), those of its
    placed tip sections (``tip_on``; slots ``n_bore + t``, :func:`tube_tip_slots`), and the
    bore sections' tree refitted (:func:`~flexmbs.contact.bores.refit_section_tree`)."""
    if tube is None:
        return
    if not tube.on[j]:
        return
    pose = _tube_carve(tw)[0]
    for k in range(n_bore + tip_on.shape[0]):
        if k >= n_bore and not tip_on[k - n_bore]:
            continue
        tube_section(tube, j, k, q, q[:0], tw)
        for c in range(3):
            origins[k, c] = pose[c]
        rotation_into(pose[3:7], frames[k])
    refit_section_tree(origins[:n_bore], reach, tree_c, tree_r, tree_lo, tree_hi)


@njit
def tube_tip_slots(tube, j, n_bore, stations, tip_on, tip_station):
    """Tube joint j's tip sections (:func:`~flexmbs.contact._detect.place_tips` found each
    between sections k and k+1, at ``tip_station`` along the tube): slot ``n_bore + t`` rides
    the tube's element of section k (or k+1) at the station's offset from it, and takes that
    section's base (so it turns with the tube as its neighbour does). A station in neither
    neighbour's element (sections farther apart than an element) places no tip."""
    if tube is None:
        return
    if not tube.on[j]:
        return
    for t in range(tip_on.shape[0]):
        if not tip_on[t]:
            continue
        s = tip_station[t]
        k = 0
        while k < n_bore - 2 and stations[k + 1] <= s:
            k += 1
        src = -1
        xi = tube.xi[j, k] + (s - stations[k]) / tube.length[j, k]
        if xi <= 1.0 + 1e-12:
            src = k
        else:
            xi = tube.xi[j, k + 1] - (stations[k + 1] - s) / tube.length[j, k + 1]
            if xi >= -1e-12:
                src = k + 1
        if src < 0:
            tip_on[t] = False
            continue
        slot = n_bore + t
        for c in range(SECTION_COORDS):
            tube.dofs[j, slot, c] = tube.dofs[j, src, c]
        for a in range(2):
            for c in range(3):
                tube.node_t[j, slot, a, c] = tube.node_t[j, src, a, c]
                tube.node_d[j, slot, a, c] = tube.node_d[j, src, a, c]
        tube.length[j, slot] = tube.length[j, src]
        tube.xi[j, slot] = min(max(xi, 0.0), 1.0)
        for c in range(3):
            tube.t_bar[j, slot, c] = tube.t_bar[j, src, c]
        for c in range(4):
            tube.p0[j, slot, c] = tube.p0[j, src, c]
        tube.row[j, slot] = tube.row[j, src]


@njit(internal=True)
def clearance_forces(cl, j, q, v, want_tangent, r_q, K_out, C_out, elem_k, elem_i):
    """Residual of one clearance joint with a circular bore (docs/theory.md §II.8): detection of all
    sections from the warm starts (crossings written to ``elem_out``, ``xi_out``), penalty force
    of every penetrating point (sign +1 at maxima, −1 at minima, §3) subtracted from ``r_q``;
    each candidate row gets its ``gap``, ``gap_rate``, friction history after the step
    (``dx, dy, dz, stick``: the contact's :func:`~flexmbs.contact.laws.tangential_force` from
    its tracked anchor, stick state and the step's start ``q_start``), normal force, and
    normal, beam point, hole point and force on the hole (the output's records of the state:
    :meth:`~flexmbs.contact.joint.SlidingClearanceJoint.keep_records`). With ``want_tangent`` the signed
    tangent blocks go to ``K_out`` (N_LOCAL × N_EXT: rows [r_H, p, e_P], columns [r_H, p, e_I,
    e_P] of :mod:`flexmbs.contact.tangent`) and ``C_out`` (N_LOCAL × N_LOCAL), the elements of
    the contact point and of the section crossing to ``elem_k`` and ``elem_i``: the exact
    linearisation (``exact``) or Gauss–Newton ``k BᵀB`` (frozen hole point, no e_I columns).
    ``spin`` (pair.N_SPIN) work for the contact element's spin, ``paper`` as in
    :func:`detect_section` (None: compiled out); ``fwork`` (:data:`FORCES_WORK`) holds every
    work array (nothing is allocated); ``qe`` and ``etree`` are the beam's element coordinates
    at ``q`` and their tree (:func:`beam_geometry`, shared by the joints on one beam).

    ``hold`` (:attr:`ClearancePart.hold`): with ``hold[0]`` set, the points that match a
    contact of the held active set (``held_on``, ``held_psi``: per section, as the tracked
    contacts, matched by :func:`tracked_slot`) act, penetrating or not
    (:func:`~flexmbs.contact.laws.held_law_force`), the others not, and ``hold[1]`` counts the
    points whose gap disagrees with the set (held and open, or not held and penetrating).

    A flexible tube (joint ``j`` of ``tube``, :class:`~flexmbs.contact.tube.TubeSections`): its
    sections' ``origins`` and ``frames`` are global (:func:`tube_place_sections`) and each
    contact takes its section's pose as the hole body's (:func:`tube_section`, ``tw``
    :data:`TUBE_WORK`); its force goes to the tube's element through ``Jᵀ``, and the tangent
    keeps the section of each contact in ``ksec`` and its force on the pose in ``kforce``
    for :func:`_tube_tangent`. Returns ``(rows, contacts, scale)``; ``rows = −1 − k`` if the
    beam axis left the bore at section k.

    Takes the packed part ``cl`` (:class:`ClearancePart`) and the joint ``j``; its arrays are
    read here under the names above (a joint's slice of each, up to its elements and
    sections)."""
    ne_j = cl.n_elem[j]
    ns = cl.n_sec[j]
    body_dofs, elem_dofs, twist_dofs = cl.body[j], cl.elem_dofs[j, :ne_j], cl.twist_dofs[j, :ne_j]
    t_bar, spin, lengths = cl.t_bar[j, :ne_j], cl.spin, cl.lengths[j, :ne_j]
    origins, frames = cl.origins[j, :ns], cl.frames[j, :ns]
    tree_c, tree_r, tree_lo, tree_hi = cl.tree_c[j], cl.tree_r[j], cl.tree_lo[j], cl.tree_hi[j]
    etree, qe = cl.beam_tree[cl.beam_of[j]], cl.beam_qe[cl.beam_of[j]]
    open_ends, tip_on = cl.open_ends[j], cl.tip_on[j]
    cross_n, cross_e, cross_xi, touched, work = (cl.cross_n, cl.cross_e, cl.cross_xi, cl.touched,
                                                 cl.work)
    elem_ws, xi_ws, ws_list = cl.elem_ws[j, :ns], cl.xi_ws[j, :ns], cl.ws_list[j]
    elem_out, xi_out, out_list = cl.elem_out[j, :ns], cl.xi_out[j, :ns], cl.out_list[j]
    r_b, shape, params, R_out, R_in = cl.r_b[j], cl.shape[j], cl.params[j], cl.R_out[j], cl.R_in[j]
    consistent, paper, law, fric = cl.consistent[j], cl.paper, cl.law[j], cl.fric[j]
    approach, active, psi_track = cl.approach[j, :ns], cl.active[j, :ns], cl.psi[j, :ns]
    anchor, stuck, q_start, rows = cl.anchor[j, :ns], cl.stuck[j, :ns], cl.q_start, cl.rows[j]
    exact, fwork, tube, tw = cl.exact[j], cl.fwork, cl.tube, cl.tube_work
    ksec, kforce, hold = cl.ksec, cl.kforce, cl.hold
    held_on, held_psi = cl.held[j, :ns], cl.held_psi[j, :ns]
    o = DETECT_WORK
    qb = fwork[o:o + 7]
    A = fwork[o + 7:o + 16].reshape((3, 3))
    vb = fwork[o + 16:o + 23]
    o += 23
    pose_k, vel_k, start_k, J_k, _, _, _, _, unit_o, unit_f, _, _, _ = _tube_carve(tw)
    tubular = tube_joint(tube, j)     # a tube: its sections are global, each its own pose
    if tubular:
        for i in range(7):
            qb[i] = 0.0
            vb[i] = 0.0
        qb[3] = 1.0
        for a in range(3):
            unit_o[a] = 0.0
            for c in range(3):
                A[a, c] = 1.0 if a == c else 0.0
                unit_f[a, c] = A[a, c]
    else:
        _frame_into(q, body_dofs, qb, A)
        for i in range(7):
            vb[i] = v[body_dofs[i]]
    ne = elem_dofs.shape[0]
    m = detect_section(qe[:ne], lengths, qb[:3], A, origins, frames, tree_c, tree_r, tree_lo,
                       tree_hi, etree, open_ends, tip_on, cross_n, cross_e, cross_xi, touched, work, elem_ws,
                       xi_ws, ws_list, elem_out, xi_out, out_list, r_b, shape, params, R_out, R_in,
                       consistent, paper, rows, fwork[:DETECT_WORK])
    if m < 0:
        return m, 0, 0.0
    Qc = fwork[o:o + N_LOCAL]
    o += N_LOCAL
    K = fwork[o:o + N_LOCAL * N_LOCAL].reshape((N_LOCAL, N_LOCAL))
    o += N_LOCAL * N_LOCAL
    C = fwork[o:o + N_LOCAL * N_LOCAL].reshape((N_LOCAL, N_LOCAL))
    o += N_LOCAL * N_LOCAL
    KX = fwork[o:o + N_LOCAL * N_EXT].reshape((N_LOCAL, N_EXT))
    o += N_LOCAL * N_EXT
    Qx = fwork[o:o + N_LOCAL]
    o += N_LOCAL
    Y = fwork[o:o + 2]
    Yp = fwork[o + 2:o + 4]
    Ypp = fwork[o + 4:o + 6]
    o += 6
    geo = fwork[o:o + N_GEO]
    o += N_GEO
    hist = fwork[o:o + N_HISTORY]
    o += N_HISTORY
    ve = fwork[o:o + CENTERLINE_SIZE]
    o += CENTERLINE_SIZE
    u_Q = fwork[o:o + 3]
    pair_work = fwork[o + 3:o + 3 + PAIR_WORK]
    o += 3 + PAIR_WORK
    A_k = fwork[o:o + 9].reshape((3, 3))
    o += 9
    plane_o = fwork[o:o + 3]           # a section's plane, global (end_fade)
    plane_n = fwork[o + 3:o + 6]
    plane_y = fwork[o + 6:o + 9]
    plane_z = fwork[o + 9:o + 12]
    Dw = fwork[o + 12:o + 12 + N_EXT]
    n_reg = origins.shape[0] - tip_on.shape[0]
    count = 0
    scale = 0.0
    hold_on = hold[0] != 0
    for i in range(m):
        row = rows[i]
        k, eP = int(row[0]), int(row[3])
        sign = row[2]
        qk, vk, Ak, ok, fk = qb, vb, A, origins[k], frames[k]
        if tubular:      # the section's own pose is the hole body's
            tube_section(tube, j, k, q, v, tw)
            rotation_into(pose_k[3:7], A_k)
            qk, vk, Ak, ok, fk = pose_k, vel_k, A_k, unit_o, unit_f
        for c in range(3):
            u_Q[c] = (Ak[0, c] * (row[5] - qk[0]) + Ak[1, c] * (row[6] - qk[1])
                      + Ak[2, c] * (row[7] - qk[2]))
        for c in range(CENTERLINE_SIZE):
            ve[c] = v[elem_dofs[eP, c]]
        slot = tracked_slot(active, psi_track, k, row[11])
        v_app = approach[k, slot] if slot >= 0 else 0.0
        held = hold_on and tracked_slot(held_on, held_psi, k, row[11]) >= 0
        contact_history(anchor, stuck, slot, k, q_start, body_dofs, elem_dofs[eP],
                        twist_dofs[eP], hist)
        if tubular:
            tube_start_pose(tube, j, k, q_start, tw)
            for c in range(7):
                hist[4 + c] = start_k[c]
        element_spin(q, v, twist_dofs[eP], t_bar[eP], spin)
        xi_lo, xi_hi = xi_bounds(eP, ne)     # not past the beam's ends (the detection's range)
        # an open bore's end section: its law lets go as the axis nears the rim (mouth_weight)
        mouth = mouth_radius(open_ends, k, n_reg, r_b)
        g, gdot, f, xiP = contact_force(qk, vk, u_Q, qe[eP], ve, spin, lengths[eP], row[4], r_b,
                                        law, fric, hist, v_app, want_tangent and not exact, Qc, K,
                                        C, geo, pair_work, held, xi_lo, xi_hi, mouth)
        # a section the beam's end is passing takes its contact in gradually (end_fade; the
        # tip sections, which ride with the tip, in full)
        fade, slope, end = 1.0, 0.0, 0
        if k < n_reg:
            _section_plane(qk, Ak, ok, fk, plane_o, plane_n, plane_y, plane_z)
            fade, slope, end = end_fade(qe[:ne], lengths, int(row[CROSSING_COL]), plane_o,
                                        plane_n, r_b)
        if fade < 1.0:
            f *= fade
            for c in range(N_LOCAL):
                Qc[c] *= fade
                if want_tangent and not exact:
                    for b in range(N_LOCAL):
                        K[c, b] *= fade
                        C[c, b] *= fade
            for c in range(9, 12):
                geo[c] *= fade
        row[FADE_COL] = fade
        row[GAP_COL] = g
        row[GAP_COL + 1] = gdot
        for c in range(4):
            row[ANCHOR_COL + c] = geo[12 + c]
        row[FORCE_COL] = f
        row[FORCE_COL + 1] = xiP
        for c in range(12):
            row[GEOMETRY_COL + c] = geo[c]
        if hold_on:
            if held != (g < 0.0):
                hold[1] += 1
            if not held:
                continue
        elif g >= 0.0:
            continue
        if tubular:      # Jᵀ λ on the tube's element
            tube_force(tube, j, k, J_k, Qc, sign, r_q)
        else:
            for c in range(7):
                r_q[body_dofs[c]] -= sign * Qc[c]
        for c in range(CENTERLINE_SIZE):
            r_q[elem_dofs[eP, c]] -= sign * Qc[7 + c]
        for c in range(N_TWIST):
            if twist_dofs[eP, c] >= 0:
                r_q[twist_dofs[eP, c]] -= sign * Qc[TWIST_OFF + c]
        for c in range(N_LOCAL):
            if abs(Qc[c]) > scale:
                scale = abs(Qc[c])
        if want_tangent and count >= K_out.shape[0]:
            return _OVERFLOW, count, scale
        if want_tangent:
            ksec[count] = k
            for c in range(7):
                kforce[count, c] = sign * Qc[c]
        if want_tangent and exact:
            eI = eP if consistent else int(row[CROSSING_COL])
            section_boundary(shape, params, row[11], Y, Yp, Ypp)
            contact_tangent(qk, vk, ok, fk, qe[eI], lengths[eI],
                            row[CROSSING_COL + 1],
                            qe[eP], ve, spin, lengths[eP], xiP, row[14], Y, Yp, Ypp, r_b, law,
                            fric, hist, v_app, consistent, paper, Qx, KX, C, held,
                            is_pinned(xiP, xi_lo, xi_hi), mouth)
            if fade < 1.0:
                # −∂(w Q)/∂q = w K − Q ⊗ ∂w/∂q; ∂w/∂q on [r_H, p] and the end element, which
                # takes the e_I columns (the crossing's: unused by the consistent detection)
                if slope != 0.0:
                    eI = int(row[CROSSING_COL])
                    fade_gradient(qk, ok, fk, qe[eI], lengths[eI], end, slope, Dw)
                for a in range(N_LOCAL):
                    for b in range(N_EXT):
                        KX[a, b] = fade * KX[a, b] - Qx[a] * Dw[b] if slope != 0.0 else (
                            fade * KX[a, b])
                    for b in range(N_LOCAL):
                        C[a, b] *= fade
            for a in range(N_LOCAL):
                for b in range(N_EXT):
                    K_out[count, a, b] = sign * KX[a, b]
                for b in range(N_LOCAL):
                    C_out[count, a, b] = sign * C[a, b]
            elem_k[count] = eP
            elem_i[count] = eI
        elif want_tangent:
            for a in range(N_LOCAL):
                for b in range(N_EXT):
                    K_out[count, a, b] = 0.0
                for b in range(7):
                    K_out[count, a, b] = sign * K[a, b]
                for b in range(CENTERLINE_SIZE):
                    K_out[count, a, P_OFF + b] = sign * K[a, 7 + b]
                for b in range(N_TWIST):
                    K_out[count, a, T_OFF + b] = sign * K[a, TWIST_OFF + b]
                for b in range(N_LOCAL):
                    C_out[count, a, b] = sign * C[a, b]
            elem_k[count] = eP
            elem_i[count] = eP
        count += 1
    return m, count, scale


# ---------------------------------------------------------------------------------------------
# the clearance-joint term of the assembler (flexmbs.terms): all clearance joints
#: error code: the beam axis left the bore (joint in ``error[1]``, section in ``error[2]``)
ERR_LEFT_BORE = ERROR_CODES["left_bore"]
#: error code: more contacts at once than the tangent's work arrays hold (joint in
#: ``error[1]``, contacts in ``error[2]``; :data:`CONTACTS_PER_SECTION`)
ERR_TOO_MANY_CONTACTS = ERROR_CODES["too_many_contacts"]
#: error code of the tangent: a contact's element lies outside the elements the factorisation's
#: plan follows the joint on (``window``; joint in ``error[1]``, element in ``error[2]``, the
#: window's row in ``error[3]``: :func:`window_row`); the
#: step is retried after a new plan (:meth:`flexmbs.assembly.Assembly.follow_contacts`)
ERR_CONTACT_OFF_PLAN = ERROR_CODES["contact_off_plan"]
#: contacts per section the tangent's work arrays hold on average (plus
#: :data:`EXTRA_CONTACTS`): a section has one, two past a²/b > R, a third with a local minimum;
#: sized by the candidates instead (MAX_CANDIDATES per section) they took 60 kB per section
CONTACTS_PER_SECTION = 2
EXTRA_CONTACTS = 64
#: ``clearance_forces``' first result when the contacts overflow the work arrays
_OVERFLOW = -(1 << 40)


class ClearancePart(NamedTuple):
    body: np.ndarray                 # (nj, 7)
    elem_dofs: np.ndarray            # (nj, max_ne, CENTERLINE_SIZE)
    twist_dofs: np.ndarray           # (nj, max_ne, N_TWIST) the nodes' twists (−1: a cable)
    t_bar: np.ndarray                # (nj, max_ne, 2, 3) their charts' base tangents (a holder
                                     # of the nodal bases: clearance_set_bases)
    n_elem: np.ndarray
    lengths: np.ndarray              # (nj, max_ne)
    origins: np.ndarray              # (nj, max_ns, 3) section origins (body coordinates)
    frames: np.ndarray               # (nj, max_ns, 3, 3) section axes (body coordinates)
    tree_c: np.ndarray               # (nj, max_nodes, 3) the sections' bounding-sphere tree
    tree_r: np.ndarray               # (nj, max_nodes)     (bores.section_tree)
    tree_lo: np.ndarray              # (nj, max_nodes)
    tree_hi: np.ndarray              # (nj, max_nodes)
    open_ends: np.ndarray            # (nj,) the beam may enter and leave the bore
    cross_n: np.ndarray              # work (max_ns,) crossings per section (zero between calls)
    cross_e: np.ndarray              # work (max_ns, MAX_CROSSINGS)
    cross_xi: np.ndarray             # work (max_ns, MAX_CROSSINGS)
    touched: np.ndarray              # work (max_ns,)
    work: np.ndarray                 # work (max_ns + 64,)
    n_sec: np.ndarray
    r_b: np.ndarray
    shape: np.ndarray                # (nj,) compiled section kind (sections.SHAPE_*)
    params: np.ndarray               # (nj, 4) its parameters
    R_out: np.ndarray                # (nj,) bounding radius of the section
    R_in: np.ndarray                 # (nj,) inscribed radius
    consistent: np.ndarray           # (nj,) detection: stationary pairs (§4b), else the paper's
    law: np.ndarray                  # (nj, 5)
    fric: np.ndarray                 # (nj, N_FRICTION) friction law (laws.Friction.parameters)
    enabled: np.ndarray              # (nj,) evaluated here (else by the joint's Python path)
    exact: np.ndarray                # (nj,) exact tangent (else Gauss-Newton)
    elem_ws: np.ndarray              # (nj, max_ns) state: warm starts (−1: not crossed)
    xi_ws: np.ndarray
    ws_list: np.ndarray              # (nj, max_ns + 1) the sections with elem_ws set
                                     # ([count, k...], count −1: not known; reset_crossings)
    approach: np.ndarray             # (nj, max_ns, P) state: tracked contacts (approach
    active: np.ndarray               # (nj, max_ns, P)   velocity, in use, section angle)
    psi: np.ndarray                  # (nj, max_ns, P)
    anchor: np.ndarray               # (nj, max_ns, P, 3) state: friction anchors (elastic
    stuck: np.ndarray                # (nj, max_ns, P)      displacement, body frame; stuck)
    q_start: np.ndarray              # (n,) state: the coordinates the step started from
    pos: np.ndarray                  # (nj, max_ne, N_LOCAL * N_LOCAL): (body, element) blocks
    cross: np.ndarray                # (nj, max_ne, 2, CENTERLINE_SIZE²): (element, element ∓ 1),
                                     # −1 outside the pattern
    qe: np.ndarray                   # work (max_ne, CENTERLINE_SIZE)
    rows: np.ndarray                 # (nj, MAX_CANDIDATES max_ns, N_COLS): last candidates
    n_candidates: np.ndarray         # (nj,) their number
    elem_out: np.ndarray             # (nj, max_ns): section crossings of the last residual
    xi_out: np.ndarray
    out_list: np.ndarray             # (nj, max_ns + 1) the sections with elem_out set
    K: np.ndarray                    # work (n_contacts, N_LOCAL, N_EXT), n_contacts =
    C: np.ndarray                    # work (n_contacts, N_LOCAL, N_LOCAL)  contact_capacity()
    kelem: np.ndarray                # work (n_contacts,): contact point's element
    kelem_i: np.ndarray              # work (n_contacts,): crossing's element
    no_K: np.ndarray                 # (0, N_LOCAL, N_EXT): no tangent in the residual
    no_C: np.ndarray                 # (0, N_LOCAL, N_LOCAL)
    no_elem: np.ndarray              # (0,)
    scratch: np.ndarray              # (n + m,) residual written while assembling the matrix
    stations: np.ndarray             # (nj, max_ns) the sections' stations along the bore
    tip_on: np.ndarray               # (nj, N_TIPS) state: tip section placed (place_tips; its
    tip_station: np.ndarray          # (nj, N_TIPS)   slot n_sec − N_TIPS + t), its station
    tip_reach: np.ndarray            # (nj,) largest distance of neighbouring sections
    tips_due: np.ndarray             # (nj,) state: place the tip sections at q_start first
    spin: np.ndarray                 # work (N_SPIN,) a contact element's spin (element_spin)
    paper: np.ndarray                # (nj,) the paper's detection (not ``consistent``)
    fwork: np.ndarray                # work (FORCES_WORK,) clearance_forces' arrays
    window: np.ndarray               # (n_rows, 2) state: the elements [lo, hi) the
                                     # factorisation's plan holds the joint's (body, beam)
                                     # entries on (the whole beam unless Assembly.follow set
                                     # it); a row per joint, a flexible tube's per element
    win_row: np.ndarray              # (nj,) the joint's first row of ``window`` (window_row)
    beam_of: np.ndarray              # (nj,) the joint's beam: its row of the next three
    beam_joint: np.ndarray           # (nb,) a joint on the beam (its elem_dofs, lengths)
    beam_qe: np.ndarray              # work (nb, max_ne, CENTERLINE_SIZE): the beam's elements
    beam_tree: np.ndarray            # work (nb, element_tree_size(max_ne), 4)  at q (beam_geometry)
    tube: TubeSections               # the sections of flexible tubes (None: no joint has one)
    tube_work: np.ndarray            # work (TUBE_WORK,)
    ksec: np.ndarray                 # work (n_contacts,): contact's section
    kforce: np.ndarray               # work (n_contacts, 7): its force on the section's pose
    indptr: np.ndarray               # the iteration matrix's CSC pattern (a tube's entries are
    indices: np.ndarray              #   found in it: _tube_tangent)
    hold: np.ndarray                 # (2,) int64 state: [held active set in force (1) or not,
                                     # points of the last evaluation at odds with it]
    held: np.ndarray                 # (nj, max_ns, P) state: the held active set (in use,
    held_psi: np.ndarray             # (nj, max_ns, P)   section angle; clearance_hold)
    # (tips_due, spin and paper are None in the kernel's copy when no joint of the model uses
    # them: contact.joint._compiled_view, their code is then not compiled)


@njit
def beam_geometry(q, elem_dofs, lengths, qe, etree):
    """A beam's element coordinates ``qe`` (n_elem, CENTERLINE_SIZE) at ``q`` and their bounding
    spheres' tree ``etree`` (:func:`~flexmbs.elements.centerline.element_tree`): once per
    evaluation for every joint on the beam."""
    ne = elem_dofs.shape[0]
    for e in range(ne):
        for k in range(CENTERLINE_SIZE):
            qe[e, k] = q[elem_dofs[e, k]]
    element_tree(qe[:ne], lengths, etree)


def contact_capacity(max_sections: int) -> int:
    """Contacts at once the tangent's work arrays of a joint with ``max_sections`` hold."""
    return min(MAX_CANDIDATES * max_sections, CONTACTS_PER_SECTION * max_sections + EXTRA_CONTACTS)


@njit(inline="always")
def _joint_forces(cl, j, q, v, want_tangent, r, K, C, elem, elem_i, error):
    """:func:`clearance_forces` of clearance joint j; records the candidates' count and, if the
    beam axis left the bore, the error. Returns (candidates, contacts, scale)."""
    ns = cl.n_sec[j]
    place_due_tips(cl.tips_due, j, cl.q_start, cl.qe, cl.n_elem[j], cl.n_sec[j], cl.elem_dofs[j],
                   cl.body[j], cl.lengths[j], cl.origins[j], cl.frames[j], cl.stations[j],
                   cl.tree_c[j], cl.tree_r[j], cl.tree_lo[j], cl.tree_hi[j], cl.tip_reach[j],
                   cl.r_b[j], cl.shape[j], cl.params[j], cl.tip_on[j], cl.tip_station[j], cl.work,
                   cl.tube, 2.0 * cl.R_out[j] + cl.r_b[j], cl.tube_work)
    tube_place_sections(cl.tube, j, q, ns - N_TIPS, cl.origins[j], cl.frames[j], cl.tree_c[j],
                        cl.tree_r[j], cl.tree_lo[j], cl.tree_hi[j], 2.0 * cl.R_out[j] + cl.r_b[j],
                        cl.tip_on[j], cl.tube_work)
    m, cnt, sc = clearance_forces(cl, j, q, v, want_tangent, r, K, C, elem, elem_i)
    if m == _OVERFLOW:
        cl.n_candidates[j] = 0
        error[0] = ERR_TOO_MANY_CONTACTS
        error[1] = j
        error[2] = cnt
        return m, cnt, sc
    cl.n_candidates[j] = m
    if m < 0:
        error[0] = ERR_LEFT_BORE
        error[1] = j
        error[2] = -1 - m
    return m, cnt, sc


@njit(internal=True)
def clearance_terms(cl, q, v, want_tangent, cC, cK, r, data, error):
    """Contact forces of every (enabled) clearance joint subtracted from ``r_q`` (``r``), or
    with ``want_tangent`` their tangent ``cK K + cC C`` into ``data`` (exact or Gauss–Newton,
    per joint; the residual then goes to ``cl.scratch``); one compiled function for both (its
    callees are optimised and compiled once). Returns ``(scale, error code)``.

    The tangent's columns of the crossing element e_I go to the (body, e_I) block for the
    body's rows and, for the element's rows, to the entries of a neighbouring e_I that the
    pattern holds (the shared node; the others, of order ξ² where the contact and the crossing
    straddle a node, and a crossing two or more elements away, are dropped: the tangent is
    exact whenever the section plane crosses the contact point's element)."""
    if cl is None:   # none in the model: compiled to nothing (driver.OPTIONAL_KINDS)
        return 0.0, 0
    cl.hold[1] = 0
    ne = CENTERLINE_SIZE
    scale = 0.0
    rr = cl.scratch if want_tangent else r
    K = cl.K if want_tangent else cl.no_K
    C = cl.C if want_tangent else cl.no_C
    kelem = cl.kelem if want_tangent else cl.no_elem
    kelem_i = cl.kelem_i if want_tangent else cl.no_elem
    for b in range(cl.beam_joint.size):
        j = cl.beam_joint[b]
        ne_b = cl.n_elem[j]
        beam_geometry(q, cl.elem_dofs[j, :ne_b], cl.lengths[j, :ne_b], cl.beam_qe[b], cl.beam_tree[b])
    for j in range(cl.r_b.size):
        if not cl.enabled[j]:
            continue
        m, cnt, sc = _joint_forces(cl, j, q, v, want_tangent, rr, K, C, kelem, kelem_i, error)
        if m < 0:
            return scale, error[0]
        if sc > scale:
            scale = sc
        if not want_tangent:
            continue
        for i in range(cnt):
            eP = cl.kelem[i]
            eI = cl.kelem_i[i]
            row = window_row(cl, j, cl.ksec[i])
            lo, hi = cl.window[row, 0], cl.window[row, 1]
            if eP < lo or eP >= hi or eI < lo or eI >= hi:
                error[0] = ERR_CONTACT_OFF_PLAN
                error[1] = j
                error[2] = eP if eP < lo or eP >= hi else eI
                error[3] = row
                return scale, ERR_CONTACT_OFF_PLAN
        if tube_joint(cl.tube, j):
            for i in range(cnt):
                _tube_tangent(cl, cl.tube, j, i, q, v, cC, cK, data)
            continue
        for i in range(cnt):
            eP = cl.kelem[i]
            eI = cl.kelem_i[i]
            pos = cl.pos[j, eP]
            # a rod's rows and columns of its twists (a cable has none: −1)
            n_rows = N_LOCAL if cl.twist_dofs[j, eP, 0] >= 0 else TWIST_OFF
            for a in range(n_rows):
                for c in range(7):
                    data[pos[N_LOCAL * a + c]] += cK * cl.K[i, a, c] + cC * cl.C[i, a, c]
                for c in range(ne):
                    kk = cl.K[i, a, P_OFF + c]
                    if eI == eP:
                        kk += cl.K[i, a, I_OFF + c]
                    data[pos[N_LOCAL * a + 7 + c]] += cK * kk + cC * cl.C[i, a, 7 + c]
                for c in range(n_rows - TWIST_OFF):
                    data[pos[N_LOCAL * a + TWIST_OFF + c]] += (cK * cl.K[i, a, T_OFF + c]
                                                               + cC * cl.C[i, a, TWIST_OFF + c])
            if eI == eP:
                continue
            posI = cl.pos[j, eI]
            for a in range(7):
                for c in range(ne):
                    data[posI[N_LOCAL * a + 7 + c]] += cK * cl.K[i, a, I_OFF + c]
            side = 0 if eI == eP - 1 else (1 if eI == eP + 1 else -1)
            if side < 0:
                continue
            cross = cl.cross[j, eP, side]
            for a in range(ne):
                for c in range(ne):
                    at = cross[ne * a + c]
                    if at >= 0:     # the shared node's entries (see clearance_pattern)
                        data[at] += cK * cl.K[i, 7 + a, I_OFF + c]
    return scale, 0


#: :func:`clearance_hold` actions (``HOLD_KEEP``: none, :func:`flexmbs.steploop.hold_action`)
HOLD_OFF, HOLD_TRACKED, HOLD_CURRENT, HOLD_READ = range(4)
HOLD_KEEP = -1


@njit(internal=True)
def clearance_hold(cl, action):
    """The active set the Newton iterations of a step hold (``NewtonOptions.hold_contacts``,
    :func:`flexmbs.steploop.alpha_run`): ``HOLD_TRACKED`` holds the contacts tracked from the
    last converged step (the step's start), ``HOLD_CURRENT`` the penetrating points of the last
    evaluation (their rows: the next evaluation at the same state is the plain one),
    ``HOLD_OFF`` ends the hold (every evaluation outside a step's iterations is plain).
    Returns, for ``HOLD_READ``, the points of the last evaluation whose gap disagrees with the
    held set (:func:`clearance_forces`), else 0."""
    if cl is None:   # none in the model: compiled to nothing (driver.OPTIONAL_KINDS)
        return 0
    if action == HOLD_READ:
        return cl.hold[1] if cl.hold[0] != 0 else 0
    if action == HOLD_OFF:
        cl.hold[0] = 0
        cl.hold[1] = 0
        return 0
    P = cl.held.shape[2]
    for j in range(cl.r_b.size):
        ns = cl.n_sec[j]
        for k in range(ns):
            for p in range(P):
                cl.held[j, k, p] = cl.active[j, k, p] if action == HOLD_TRACKED else False
                cl.held_psi[j, k, p] = cl.psi[j, k, p] if action == HOLD_TRACKED else 0.0
        if action != HOLD_CURRENT or not cl.enabled[j]:
            continue
        for i in range(cl.n_candidates[j]):
            if cl.rows[j, i, GAP_COL] < 0.0:
                k = int(cl.rows[j, i, 0])
                for p in range(P):
                    if not cl.held[j, k, p]:
                        cl.held[j, k, p] = True
                        cl.held_psi[j, k, p] = cl.rows[j, i, 11]
                        break
    cl.hold[0] = 1
    cl.hold[1] = 0
    return 0


@njit(internal=True)
def clearance_set_bases(cl, log, stop, q):
    """Re-based nodes (``log[:stop]``, records ``[twist coordinate, t̄, D̄]``, docs/theory.md
    §I.2.4): the contact elements holding them read the new base tangent; ``q`` (its twists
    changed), unless empty (a resumed run: :func:`~flexmbs.contact.joint._begin_clearance`),
    is the start of the next step, the friction's reference."""
    if cl is None:   # none in the model: compiled to nothing (driver.OPTIONAL_KINDS)
        return
    for j in range(cl.r_b.size):
        for e in range(cl.n_elem[j]):
            for a in range(N_TWIST):
                dof = cl.twist_dofs[j, e, a]
                if dof < 0:
                    continue
                for i in range(stop):
                    if np.int64(log[i, 0]) == dof:
                        for c in range(3):
                            cl.t_bar[j, e, a, c] = log[i, 1 + c]
    _tube_set_bases(cl.tube, log, stop)
    if q.size > 0:
        for i in range(cl.q_start.size):
            cl.q_start[i] = q[i]


@njit
def _tube_set_bases(tube, log, stop):
    """Rod tubes' sections read the new bases (t̄, D̄) of their element's re-based nodes (the
    section's turn is measured through them; it does not change)."""
    if tube is None:
        return
    for j in range(tube.on.size):
        if not tube.on[j] or tube.width[j] <= CENTERLINE_SIZE:
            continue
        for k in range(tube.dofs.shape[1]):
            for a in range(SECTION_COORDS - CENTERLINE_SIZE):
                dof = tube.dofs[j, k, CENTERLINE_SIZE + a]
                for i in range(stop):
                    if np.int64(log[i, 0]) == dof:
                        for c in range(3):
                            tube.node_t[j, k, a, c] = log[i, 1 + c]
                            tube.node_d[j, k, a, c] = log[i, 4 + c]


@njit(internal=True)
def clearance_post_step_all(cl, q):
    """After a converged step (following a residual at that state, whose detection it reuses):
    warm starts moved to the converged crossings, contacts tracked (:func:`clearance_update`),
    ``q`` the start of the next step, where the tip sections of open bores will be placed
    (:func:`place_tips`) by its first evaluation: the output of this state still sees the
    sections its equilibrium was found with."""
    if cl is None:   # none in the model: compiled to nothing (driver.OPTIONAL_KINDS)
        return
    for i in range(cl.q_start.size):
        cl.q_start[i] = q[i]
    for j in range(cl.r_b.size):
        if not cl.enabled[j]:
            continue
        ns = cl.n_sec[j]
        ws_list = cl.ws_list[j]
        out_list = cl.out_list[j]
        clearance_update(cl.rows[j], cl.n_candidates[j], ws_list, cl.approach[j, :ns],
                         cl.active[j, :ns], cl.psi[j, :ns], cl.anchor[j, :ns], cl.stuck[j, :ns])
        reset_crossings(cl.elem_ws[j, :ns], ws_list)
        for i in range(out_list[0]):
            k = out_list[1 + i]
            cl.elem_ws[j, k] = cl.elem_out[j, k]
            cl.xi_ws[j, k] = cl.xi_out[j, k]
            ws_list[1 + i] = k
        ws_list[0] = out_list[0]
        _mark_tips_due(cl.tips_due, j, cl.open_ends[j])
        tube_rebase(cl.tube, j, ns - N_TIPS, q, cl.tube_work)


@njit(internal=True)
def place_due_tips(due, j, q, qe, ne, ns, elem_dofs, body, lengths, origins, frames, stations,
                   tree_c, tree_r, tree_lo, tree_hi, tip_reach, r_b, shape, params, tip_on,
                   tip_station, work, tube, reach, tw):
    """At the step's first evaluation (``due[j]``): :func:`place_tips` of clearance joint j at
    ``q``, the step's start; ``qe`` work (n_elem, CENTERLINE_SIZE). ``due`` None: no joint of
    the model has an open bore (the tip sections' code is compiled out, _compiled_view). A
    flexible tube's sections are placed at ``q`` first (global, the identity as the body's
    pose; ``reach``: the tree's, as :func:`tube_place_sections`), and its tip sections then
    ride the tube (:func:`tube_tip_slots`)."""
    if due is None:
        return
    if not due[j]:
        return
    due[j] = False
    for e in range(ne):
        for c in range(CENTERLINE_SIZE):
            qe[e, c] = q[elem_dofs[e, c]]
    if tube_joint(tube, j):
        _, _, _, _, _, _, _, _, unit_o, unit_f, _, _, _ = _tube_carve(tw)
        for c in range(3):
            unit_o[c] = 0.0
            for d in range(3):
                unit_f[c, d] = 1.0 if c == d else 0.0
        for t in range(tip_on.shape[0]):
            tip_on[t] = False
        tube_place_sections(tube, j, q, ns - N_TIPS, origins[:ns], frames[:ns], tree_c, tree_r,
                            tree_lo, tree_hi, reach, tip_on, tw)
        place_tips(qe[:ne], lengths[:ne], unit_o, unit_f, origins[:ns], frames[:ns],
                   stations[:ns], tree_c, tree_r, tree_lo, tree_hi, tip_reach, r_b, shape,
                   params, tip_on, tip_station, work)
        tube_tip_slots(tube, j, ns - N_TIPS, stations, tip_on, tip_station)
        return
    qb, A = _frame(q, body)
    place_tips(qe[:ne], lengths[:ne], qb[:3], A, origins[:ns], frames[:ns], stations[:ns],
               tree_c, tree_r, tree_lo, tree_hi, tip_reach, r_b, shape, params, tip_on,
               tip_station, work)


@njit
def _mark_tips_due(due, j, open_end):
    """The next step's first evaluation places joint j's tip sections (an open bore)."""
    if due is None:
        return
    due[j] = open_end


@njit
def tube_rebase(tube, j, n_bore, q, tw):
    """After a converged step: the sections of tube joint j whose tangent turned far take new
    bases (:func:`~flexmbs.contact.tube.rebase`; their poses do not change)."""
    if tube is None:
        return
    if not tube.on[j]:
        return
    _, _, _, _, _, _, qo, _, _, _, pw, turn, _ = _tube_carve(tw)
    width = tube.width[j]
    for k in range(n_bore):
        for c in range(width):
            qo[c] = q[tube.dofs[j, k, c]]
        psi = _tube_turn(tube, j, k, qo, turn, False)
        rebase_section(qo, width, tube.length[j, k], tube.xi[j, k], tube.t_bar[j, k],
                       tube.p0[j, k], psi, pw)


@njit(inline="always")
def _csc_add(indptr, indices, data, row, col, value):
    """``data[(row, col)] += value`` if the pattern holds the entry (binary search in the
    column's sorted rows); else nothing (as the rigid bore's entries outside the pattern)."""
    lo = indptr[col]
    hi = indptr[col + 1]
    while lo < hi:
        mid = (lo + hi) // 2
        r = indices[mid]
        if r < row:
            lo = mid + 1
        elif r > row:
            hi = mid
        else:
            data[mid] += value
            return


@njit
def _tube_tangent(cl, tube, j, i, q, v, cC, cK, data):
    """Contact i of tube joint j into the iteration matrix: its rigid-bore blocks
    (``cl.K[i]``, ``cl.C[i]``, columns and rows of the hole body's pose ``b``) taken to the
    tube's element ``e_o`` through ``b = b(e_o)`` (:mod:`flexmbs.contact.tube`):
    ``K_xo = K_xb J + C_xb G``, ``K_ox = Jᵀ K_bx``,
    ``K_oo = Jᵀ (K_bb J + C_bb G) − Σ_a λ_a ∂²b_a/∂e²``, ``C_xo = C_xb J``, ``C_ox = Jᵀ C_bx``
    (x: the beam's element e_P, its twists and the crossing's element e_I). ``tube``
    (``cl.tube``) None: no tube in the model (compiled out)."""
    if tube is None:
        return
    k = cl.ksec[i]
    eP = cl.kelem[i]
    eI = cl.kelem_i[i]
    tw = cl.tube_work
    tube_section(tube, j, k, q, v, tw)
    _, _, _, J, G, H, qo, vo, _, _, pw, turn, KJ = _tube_carve(tw)
    width = tube.width[j]
    _tube_turn(tube, j, k, qo, turn, True)
    pose_curvature(qo, width, tube.length[j, k], tube.xi[j, k], tube.t_bar[j, k], tube.p0[j, k],
                   turn, vo, cl.kforce[i], H, G, pw)
    K = cl.K[i]
    C = cl.C[i]
    CS = CENTERLINE_SIZE
    od = tube.dofs[j, k]
    n_tw = N_TWIST if cl.twist_dofs[j, eP, 0] >= 0 else 0
    ip, ix = cl.indptr, cl.indices
    # the beam's rows (e_P, its twists) and columns (e_P, twists, e_I): the rigid bore's
    for a in range(CS + n_tw):
        ra = cl.elem_dofs[j, eP, a] if a < CS else cl.twist_dofs[j, eP, a - CS]
        la = 7 + a                                  # local row
        for c in range(CS):
            kk = K[la, P_OFF + c]
            if eI == eP:
                kk += K[la, I_OFF + c]
            _csc_add(ip, ix, data, ra, cl.elem_dofs[j, eP, c], cK * kk + cC * C[la, 7 + c])
            if eI != eP:
                _csc_add(ip, ix, data, ra, cl.elem_dofs[j, eI, c], cK * K[la, I_OFF + c])
        for c in range(n_tw):
            _csc_add(ip, ix, data, ra, cl.twist_dofs[j, eP, c],
                     cK * K[la, T_OFF + c] + cC * C[la, TWIST_OFF + c])
        # columns of the tube's element
        for c in range(width):
            s = 0.0
            for b in range(7):
                s += (cK * K[la, b] + cC * C[la, b]) * J[b, c] + cK * C[la, b] * G[b, c]
            _csc_add(ip, ix, data, ra, od[c], s)
    # the tube's rows; KJ = (cK K_bb + cC C_bb) J + cK C_bb G, once
    for b in range(7):
        for c in range(width):
            t = 0.0
            for d in range(7):
                t += (cK * K[b, d] + cC * C[b, d]) * J[d, c] + cK * C[b, d] * G[d, c]
            KJ[b, c] = t
    for r in range(width):
        ro = od[r]
        for c in range(CS):          # against e_P (and e_I)
            s = 0.0
            sI = 0.0
            for b in range(7):
                kk = K[b, P_OFF + c]
                if eI == eP:
                    kk += K[b, I_OFF + c]
                s += J[b, r] * (cK * kk + cC * C[b, 7 + c])
                sI += J[b, r] * cK * K[b, I_OFF + c]
            _csc_add(ip, ix, data, ro, cl.elem_dofs[j, eP, c], s)
            if eI != eP:
                _csc_add(ip, ix, data, ro, cl.elem_dofs[j, eI, c], sI)
        for c in range(n_tw):
            s = 0.0
            for b in range(7):
                s += J[b, r] * (cK * K[b, T_OFF + c] + cC * C[b, TWIST_OFF + c])
            _csc_add(ip, ix, data, ro, cl.twist_dofs[j, eP, c], s)
        for c in range(width):       # against itself: Jᵀ KJ − cK H
            s = -cK * H[r, c]
            for b in range(7):
                s += J[b, r] * KJ[b, c]
            _csc_add(ip, ix, data, ro, od[c], s)

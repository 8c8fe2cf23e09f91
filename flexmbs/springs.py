"""Spring-dampers (issue "multibody basics"): translational between two points, rotational
about a joint axis. Both share the force law below; they differ in the measure ``m(q)`` (the
length ``l`` or the angle θ) and its derivatives ``g = dm/dq``, ``H = d2m/dq2``.

Translational.
Each end is a rigid-body point ``x = r + A(p) s`` (s in the body frame), a beam node's position
or a fixed point of the ground. With ``d = x_b - x_a``, length ``l = |d|``, direction
``n = d / l`` and ``g = dl/dq = D^T n`` (``D = dd/dq = [-J_a, J_b]``), the spring-damper force
(tension positive) is

    f = f_el(l - l0) + f0 + c dl/dt,        dl/dt = g . q'

with ``f_el = k e`` or a piecewise-linear force-elongation table (extrapolated with its end
slopes), preload ``f0`` and damping ``c``. Its generalized internal force is ``f g`` (it enters
``r_q`` like the beams' internal forces), its potential ``V = int_0^e f_el + f0 e``. The
tangent is exact:

    K = k_t g g^T + f H + c g (H q')^T,    C = c g g^T,
    H = d2l/dq2 = D^T (I - n n^T) D / l + sum_k n_k d2d_k/dq2

where the last term is ``+-2 C(s, n)`` on the Euler-parameter block of a body end
(:func:`flexmbs.elements.rigid_body.point_tensor_of`: ``(A(p)s)_k = p^T T_k(s) p``).

Rotational. About the x axis of a joint's frames, θ is the rotation of a's frame relative to
b's, from ``c = cos θ`` and ``s = sin θ`` of :func:`~flexmbs.constraints.joints.relative_angle_table`
(their gradients and exact Hessians are the joint tables'): ``θ = atan2(s, c)``, taken in
``(θ_r - π, θ_r + π]`` around the spring's last converged angle θ_r (state, checkpointed; the
rest angle θ_0 before the first step), so that θ counts whole turns (a spring wound several
turns keeps its torque, issue "nothing lost, part two"), with ``ρ² = c² + s²``

    g = (c s_q - s c_q) / ρ²
    H = (c H_s - s H_c) / ρ² + (s_q c_q^T - c_q s_q^T) / ρ² - 2 g (c c_q + s s_q)^T / ρ²

(symmetric). The "force" is then the torque ``τ = τ_el(θ - θ_0) + τ_0 + c θ'`` resisting an
increase of θ, with the same linear or tabulated law, preload and damping, and the tangent above.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from ._jit import njit
from .constraints.base import Attachment
from .constraints.joints import (
    TermTable,
    TermWork,
    concatenate_tables,
    relative_angle_table,
    term_hessian,
    term_values,
    term_work,
)
from .elements.rigid_body import point_jacobian_of, point_tensor_of
from .errors import ModelError
from .terms import WITH_DAMPING

if TYPE_CHECKING:  # pragma: no cover
    from .terms import DofMap

__all__ = ["SpringDamper", "SpringPart", "add_measure_matrix", "ends_pattern", "length_hessian",
           "length_of", "pack_ends", "pack_springs", "reference_point", "spring_energy",
           "spring_forces", "spring_points", "springs_jacobian", "springs_pattern", "springs_post_step",
           "springs_residual"]

END = 7                  #: coordinates reserved per end (a body's r, p)
GROUND_END, NODE_END, BODY_END = 0, 1, 2
LENGTH, ANGLE = 0, 1     #: the measure of a spring-damper


@dataclass
class SpringDamper:
    """A translational spring-damper (see the module docstring); ``a``/``b`` are a
    :class:`~flexmbs.model.RigidBody`, a beam :class:`~flexmbs.model.Node` or the ground;
    ``point_a``/``point_b`` body-frame points (bodies) or global points (ground)."""

    name: str
    a: Any
    b: Any
    point_a: np.ndarray
    point_b: np.ndarray
    stiffness: float
    damping: float
    rest_length: float
    preload: float
    table: np.ndarray | None      # (m, 2): elongation, force
    #: rotational: the joint frames (body frame of a/b, or global for the ground); the spring
    #: then acts about their x axis, ``rest_length`` is the rest angle, forces are torques
    frame_a: np.ndarray | None = None
    frame_b: np.ndarray | None = None

    @property
    def rotational(self) -> bool:
        return self.frame_a is not None

    def end_position(self, which: int) -> np.ndarray:
        """Reference position of end a (0) or b (1)."""
        obj, s = (self.a, self.point_a) if which == 0 else (self.b, self.point_b)
        return reference_point(obj, s)


def reference_point(obj: Any, s: np.ndarray) -> np.ndarray:
    pose = getattr(obj, "pose", None)
    if pose is not None:                                  # a rigid body
        return np.asarray(pose.position, float) + np.asarray(pose.rotation, float) @ s
    if hasattr(obj, "beam"):                              # a beam node
        return np.asarray(obj.position, float).copy()
    return np.asarray(s, float).copy()                   # the ground


def check_table(table: Any, name: str) -> np.ndarray:
    """A force-elongation table: (m >= 2, 2) finite, elongations strictly increasing."""
    t = np.asarray(table, dtype=float)
    if t.ndim != 2 or t.shape[1] != 2 or t.shape[0] < 2 or not np.all(np.isfinite(t)):
        raise ModelError(f"spring '{name}': table must be >= 2 finite [elongation, force] pairs")
    if not np.all(np.diff(t[:, 0]) > 0):
        raise ModelError(f"spring '{name}': table elongations must increase strictly")
    return t


# ---------------------------------------------------------------------------------------------
# the term of the assembler (flexmbs.terms)
class SpringPart(NamedTuple):
    idx: np.ndarray          # (n, 2*END) coordinates of end a then end b, -1 unused
    measure: np.ndarray      # (n,) LENGTH | ANGLE
    kind: np.ndarray         # (n, 2) GROUND_END | NODE_END | BODY_END
    point: np.ndarray        # (n, 2, 3) body-frame point (bodies), global point (ground)
    T: np.ndarray            # (n, 2, 3, 4, 4) point tensors of body ends
    k: np.ndarray            # (n,)
    c: np.ndarray
    l0: np.ndarray
    f0: np.ndarray
    tab: np.ndarray          # (n, m, 2) force-elongation tables (rows beyond tab_n unused)
    tab_n: np.ndarray        # (n,) rows of the table, 0 = linear
    pos: np.ndarray          # (n, (2*END)**2) CSC positions of the block idx x idx, -1 unused
    table: TermTable         # (cos, sin) equations of the rotational springs, local to idx
    eq_ptr: np.ndarray       # (n + 1,) their equations per spring (none for translational)
    D: np.ndarray            # work (3, 2*END)
    g: np.ndarray            # work (2*END,)
    H: np.ndarray            # work (2*END, 2*END)
    x: np.ndarray            # work (2, 3)
    ql: np.ndarray           # work (2*END,)
    cs: np.ndarray           # work (2,): c, s
    dcs: np.ndarray          # work (2, 2*END)
    lam2: np.ndarray         # work (2,)
    theta_ref: np.ndarray    # (n,) state: the rotational springs' last converged angle (turns)
    work: TermWork           # work of the term kernels


def _end_coords(obj: Any, dofs: DofMap) -> tuple[int, np.ndarray]:
    if getattr(obj, "pose", None) is not None:
        return BODY_END, np.asarray(dofs.body_dofs(obj), np.int64)
    if hasattr(obj, "beam"):
        d = np.asarray(dofs.node_dofs(obj), np.int64)
        return NODE_END, d[list(obj.beam.layout.position)]
    return GROUND_END, np.zeros(0, np.int64)


def pack_ends(ends: Sequence[tuple[Any, Any, Any, Any]], dofs: DofMap
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(idx, kind, point, T, pos)`` of the two-point elements ``(a, point_a, b, point_b)``
    (the spring-dampers, the ropes): their coordinates (END per end, −1 unused), end kinds,
    points, point tensors of body ends and the CSC positions of their block idx × idx."""
    n = len(ends)
    w = 2 * END
    idx = np.full((n, w), -1, np.int64)
    kind = np.zeros((n, 2), np.int64)
    point = np.zeros((n, 2, 3))
    T = np.zeros((n, 2, 3, 4, 4))
    pos = np.full((n, w * w), -1, np.int64)
    for i, (a, point_a, b, point_b) in enumerate(ends):
        for e, (obj, pt) in enumerate(((a, point_a), (b, point_b))):
            kind[i, e], d = _end_coords(obj, dofs)
            idx[i, e * END:e * END + d.size] = d
            point[i, e] = pt
            if kind[i, e] == BODY_END:
                T[i, e] = point_tensor_of(np.asarray(pt, float))
        used = idx[i] >= 0
        block = np.full((w, w), -1, np.int64)
        block[np.ix_(used, used)] = dofs.positions(idx[i][used], idx[i][used]).reshape(
            used.sum(), used.sum())
        pos[i] = block.ravel()
    return idx, kind, point, T, pos


def ends_pattern(a: Any, b: Any, dofs: DofMap) -> list[tuple[np.ndarray, np.ndarray]]:
    """The block a two-point element between ``a`` and ``b`` writes (none between grounds)."""
    d = np.concatenate([_end_coords(a, dofs)[1], _end_coords(b, dofs)[1]])
    return [(d, d)] if d.size else []


def pack_springs(springs: Sequence[SpringDamper], dofs: DofMap) -> SpringPart:
    n = len(springs)
    w = 2 * END
    idx, kind, point, T, pos = pack_ends([(s.a, s.point_a, s.b, s.point_b) for s in springs], dofs)
    m = max((s.table.shape[0] for s in springs if s.table is not None), default=1)
    tab = np.zeros((n, m, 2))
    tab_n = np.zeros(n, np.int64)
    measure = np.array([ANGLE if s.rotational else LENGTH for s in springs], np.int64)
    tables = []
    for i, s in enumerate(springs):
        if s.table is not None:
            tab[i, :s.table.shape[0]] = s.table
            tab_n[i] = s.table.shape[0]
        if s.rotational:
            tables.append(relative_angle_table(_attachment(s.a, s.frame_a),
                                               _attachment(s.b, s.frame_b), END))
        else:
            tables.append(concatenate_tables([])[0])
    table, eq_ptr = concatenate_tables(tables)
    return SpringPart(
        idx=idx,
        measure=measure,
        kind=kind,
        point=point,
        T=T,
        k=np.array([s.stiffness for s in springs], float),
        c=np.array([s.damping for s in springs], float),
        l0=np.array([s.rest_length for s in springs], float),
        f0=np.array([s.preload for s in springs], float),
        tab=tab,
        tab_n=tab_n,
        pos=pos,
        table=table,
        eq_ptr=eq_ptr,
        D=np.zeros((3, w)),
        g=np.zeros(w),
        H=np.zeros((w, w)),
        x=np.zeros((2, 3)),
        ql=np.zeros(w),
        cs=np.zeros(2),
        dcs=np.zeros((2, w)),
        lam2=np.zeros(2),
        theta_ref=np.array([s.rest_length for s in springs], float),
        work=term_work())


def _attachment(obj: Any, frame: np.ndarray | None) -> Attachment:
    """The end of a rotational spring as a joint attachment (offsets END apart, a first)."""
    if getattr(obj, "pose", None) is not None:
        return Attachment.rigid_body(np.arange(END), np.zeros(3), frame)
    return Attachment.ground(np.zeros(3), frame)


def springs_pattern(springs: Sequence[SpringDamper], dofs: DofMap) -> list[tuple[np.ndarray, np.ndarray]]:
    return [b for s in springs for b in ends_pattern(s.a, s.b, dofs)]


@njit
def _elastic(sp, i, e):
    """(force, stiffness) of the elastic law at elongation e."""
    m = sp.tab_n[i]
    if m == 0:
        return sp.k[i] * e, sp.k[i]
    t = sp.tab[i]
    j = 0
    while j < m - 2 and e > t[j + 1, 0]:
        j += 1
    slope = (t[j + 1, 1] - t[j, 1]) / (t[j + 1, 0] - t[j, 0])
    return t[j, 1] + slope * (e - t[j, 0]), slope


@njit
def _kinematics(sp, i, q):
    """Ends into sp.x, D = dd/dq into sp.D; returns (l, n)."""
    D = sp.D
    D[:, :] = 0.0
    p = np.empty(4)
    B = np.empty((3, 4))
    for e in range(2):
        sign = -1.0 if e == 0 else 1.0
        base = e * END
        kd = sp.kind[i, e]
        if kd == GROUND_END:
            for c in range(3):
                sp.x[e, c] = sp.point[i, e, c]
        elif kd == NODE_END:
            for c in range(3):
                sp.x[e, c] = q[sp.idx[i, base + c]]
                D[c, base + c] = sign
        else:
            for c in range(4):
                p[c] = q[sp.idx[i, base + 3 + c]]
            point_jacobian_of(sp.T[i, e], p, B, sp.x[e])      # B = 2T(s)p, x = A s
            for c in range(3):
                sp.x[e, c] += q[sp.idx[i, base + c]]
                D[c, base + c] = sign
                for j in range(4):
                    D[c, base + 3 + j] = sign * B[c, j]
    dx = sp.x[1, 0] - sp.x[0, 0]
    dy = sp.x[1, 1] - sp.x[0, 1]
    dz = sp.x[1, 2] - sp.x[0, 2]
    length = math.sqrt(dx * dx + dy * dy + dz * dz)
    n = np.empty(3)
    if length > 0.0:
        n[0], n[1], n[2] = dx / length, dy / length, dz / length
    else:
        n[0], n[1], n[2] = 0.0, 0.0, 0.0
    return length, n


@njit
def _angle(sp, i, q):
    """θ of a rotational spring (module docstring) with g into sp.g; c, s and their gradients
    in sp.cs, sp.dcs."""
    w = sp.g.size
    for a in range(w):
        sp.ql[a] = q[sp.idx[i, a]] if sp.idx[i, a] >= 0 else 0.0
    term_values(sp.table, sp.eq_ptr[i], sp.eq_ptr[i + 1], sp.ql, sp.cs, sp.dcs, sp.work)
    c, s = sp.cs[0], sp.cs[1]
    rho2 = c * c + s * s
    for a in range(w):
        sp.g[a] = (c * sp.dcs[1, a] - s * sp.dcs[0, a]) / rho2
    ref = sp.theta_ref[i]        # the branch of the last converged angle: turns count
    d = math.atan2(s, c) - ref
    d -= 2.0 * math.pi * math.floor(d / (2.0 * math.pi) + 0.5)
    return ref + d


@njit
def _measure(sp, i, q):
    """The length or angle of spring i, with g = dm/dq into sp.g."""
    if sp.measure[i] == ANGLE:
        return _angle(sp, i, q)
    return length_of(sp, i, q)


@njit
def length_of(sp, i, q):
    """The length ``l`` between the ends of two-point element i of a part with the ends'
    fields of :class:`SpringPart` (``idx, kind, point, T, D, x, g``: a spring, a rope), with
    ``g = dl/dq = D^T n`` into ``sp.g`` (module docstring)."""
    length, n = _kinematics(sp, i, q)
    for a in range(sp.g.size):
        ga = 0.0
        for c in range(3):
            ga += sp.D[c, a] * n[c]
        sp.g[a] = ga
    return length


@njit
def _force(sp, i, q, v, mode):
    """g into sp.g; returns (measure, f, k_t, rate)."""
    value = _measure(sp, i, q)
    rate = 0.0
    for a in range(sp.g.size):
        if sp.idx[i, a] >= 0:
            rate += sp.g[a] * v[sp.idx[i, a]]
    fel, kt = _elastic(sp, i, value - sp.l0[i])
    f = fel + sp.f0[i]
    if mode[WITH_DAMPING] != 0.0:
        f += sp.c[i] * rate
    return value, f, kt, rate


@njit(internal=True)
def springs_residual(sp, q, v, mode, r):
    """``r_q += f g`` for every spring-damper; returns the largest of its parts (elastic,
    preload, damping), the force scale of the convergence test (a preloaded spring in
    equilibrium has f = 0 but is not force-free)."""
    if sp is None:   # none in the model: compiled to nothing (driver.OPTIONAL_KINDS)
        return 0.0
    scale = 0.0
    for i in range(sp.idx.shape[0]):
        _value, f, _kt, _rate = _force(sp, i, q, v, mode)
        for a in range(sp.g.size):
            if sp.idx[i, a] >= 0:
                r[sp.idx[i, a]] += f * sp.g[a]
        scale = max(scale, abs(f), abs(f - sp.f0[i]), abs(sp.f0[i]))
    return scale


@njit
def _second_derivative(sp, i, q):
    """H = d2m/dq2 into sp.H (module docstring); follows :func:`_measure` at the same q."""
    w = sp.g.size
    H = sp.H
    if sp.measure[i] == ANGLE:
        c, s = sp.cs[0], sp.cs[1]
        rho2 = c * c + s * s
        sp.lam2[0] = -s / rho2
        sp.lam2[1] = c / rho2
        term_hessian(sp.table, sp.eq_ptr[i], sp.eq_ptr[i + 1], sp.ql, sp.lam2, H, sp.work)
        for a in range(w):
            for b in range(w):
                dc_a, ds_a = sp.dcs[0, a], sp.dcs[1, a]
                dc_b, ds_b = sp.dcs[0, b], sp.dcs[1, b]
                H[a, b] += (ds_a * dc_b - dc_a * ds_b) / rho2 \
                    - 2.0 * sp.g[a] * (c * dc_b + s * ds_b) / rho2
        for a in range(w):        # exactly symmetric (it is, up to rounding)
            for b in range(a + 1, w):
                h = 0.5 * (H[a, b] + H[b, a])
                H[a, b] = h
                H[b, a] = h
        return
    length_hessian(sp, i, q)


@njit
def length_hessian(sp, i, q):
    """``H = d2l/dq2`` of two-point element i into ``sp.H`` (module docstring; the part as in
    :func:`length_of`, with ``H``)."""
    w = sp.g.size
    H = sp.H
    length, n = _kinematics(sp, i, q)
    for a in range(w):
        for b in range(w):
            s = 0.0
            if length > 0.0:
                for c in range(3):
                    for d in range(3):
                        P = (1.0 if c == d else 0.0) - n[c] * n[d]
                        s += sp.D[c, a] * P * sp.D[d, b]
                s /= length
            H[a, b] = s
    for e in range(2):
        if sp.kind[i, e] != BODY_END:
            continue
        sign = -1.0 if e == 0 else 1.0
        base = e * END + 3
        for j in range(4):
            for m in range(4):
                s = 0.0
                for c in range(3):
                    s += n[c] * sp.T[i, e, c, j, m]
                H[base + j, base + m] += sign * 2.0 * s


@njit(internal=True)
def springs_jacobian(sp, q, v, mode, cC, cK, data):
    """``cK K + cC C`` of every spring-damper into ``data`` (module docstring); returns the
    largest tangent stiffness k_t (the round-off floor of the convergence test)."""
    if sp is None:   # none in the model: compiled to nothing (driver.OPTIONAL_KINDS)
        return 0.0
    w = sp.g.size
    hv = np.empty(w)
    kscale = 0.0
    for i in range(sp.idx.shape[0]):
        _value, f, kt, _rate = _force(sp, i, q, v, mode)
        kscale = max(kscale, abs(kt))
        _second_derivative(sp, i, q)
        c = sp.c[i] if mode[WITH_DAMPING] != 0.0 else 0.0
        add_measure_matrix(sp, i, f, kt, c, v, cC, cK, data, hv)
    return kscale


@njit
def add_measure_matrix(sp, i, f, kt, c, v, cC, cK, data, hv):
    """``cK K + cC C`` of the force ``f(m, dm/dt)`` along the measure m of element i into
    ``data`` (module docstring): ``K = k_t g g^T + f H + c g (H q')^T``, ``C = c g g^T``, with
    ``k_t = df/dm``, ``c = df/d(dm/dt)`` and g, H in ``sp.g``, ``sp.H`` (a spring, a rope);
    ``hv``: work (2*END,)."""
    w = sp.g.size
    for a in range(w):
        s = 0.0
        for b in range(w):
            if sp.idx[i, b] >= 0:
                s += sp.H[a, b] * v[sp.idx[i, b]]
        hv[a] = s
    for a in range(w):
        if sp.idx[i, a] < 0:
            continue
        for b in range(w):
            if sp.idx[i, b] < 0:
                continue
            val = cK * (kt * sp.g[a] * sp.g[b] + f * sp.H[a, b] + c * sp.g[a] * hv[b]) \
                + cC * c * sp.g[a] * sp.g[b]
            data[sp.pos[i, a * w + b]] += val


@njit(internal=True)
def springs_post_step(sp, q):
    """After a converged step: every rotational spring's angle becomes the centre of its next
    branch (``theta_ref``), so that θ follows the joint through whole turns."""
    if sp is None:   # none in the model: compiled to nothing (driver.OPTIONAL_KINDS)
        return
    for i in range(sp.idx.shape[0]):
        if sp.measure[i] == ANGLE:
            sp.theta_ref[i] = _angle(sp, i, q)


def spring_forces(sp: SpringPart, q: np.ndarray, v: np.ndarray, mode: np.ndarray) -> np.ndarray:
    """(n, 3): length (angle), force (torque; tension > 0) and their rate of every spring-damper
    (output)."""
    out = np.zeros((sp.idx.shape[0], 3))
    for i in range(sp.idx.shape[0]):
        value, f, _kt, rate = _force(sp, i, q, v, mode)
        out[i] = (value, f, rate)
    return out


def spring_points(sp: SpringPart, q: np.ndarray) -> np.ndarray:
    """(n, 2, 3): the current end points (translational) or the joint points on a and b
    (rotational) of every spring-damper (output)."""
    out = np.zeros((sp.idx.shape[0], 2, 3))
    for i in range(sp.idx.shape[0]):
        _kinematics(sp, i, q)
        out[i] = sp.x
    return out


def spring_energy(sp: SpringPart, q: np.ndarray) -> float:
    """Potential energy ``sum int_0^e f_el + f0 e`` of the springs (damping dissipates)."""
    total = 0.0
    for i in range(sp.idx.shape[0]):
        e = float(_measure(sp, i, q)) - float(sp.l0[i])
        total += float(sp.f0[i]) * e
        m = int(sp.tab_n[i])
        if m == 0:
            total += 0.5 * float(sp.k[i]) * e * e
            continue
        # integral of the piecewise-linear law from 0 to e (trapezoids between breakpoints)
        xs = [0.0, e]
        tab = sp.tab[i, :m]
        xs += [float(x) for x in tab[:, 0] if min(0.0, e) < x < max(0.0, e)]
        xs.sort()
        sign = 1.0 if e >= 0 else -1.0
        for a, b in zip(xs[:-1], xs[1:], strict=True):
            fa = float(_elastic(sp, i, a)[0])
            fb = float(_elastic(sp, i, b)[0])
            total += sign * 0.5 * (fa + fb) * (b - a)
    return total

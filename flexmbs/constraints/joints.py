"""Joints between rigid bodies, beam nodes and ground (Haug 1989 "dot-1" form; exact Hessians).

Every equation is ``LIN: Φ = P·(u1 − u2)`` (a constant projection) or ``DOT: Φ = (u1 − u2)·(w1 − w2)``
of vectors u, w of five kinds: constants (ground point/direction), body points ``r + A(p)s′``,
body directions ``A(p)f′``, beam node positions ``r`` and slopes ``r′``. With the homogeneous
rotation matrix ``(A(p)s)_k = pᵀT_k(s)p`` (:func:`flexmbs.elements.rigid_body.point_tensor`) each
vector is a polynomial of degree ≤ 2, so ``∂v/∂p = 2T(s)p`` and ``∂²v_k/∂p² = 2T_k(s)`` exactly,
and the Hessian of ``a·b`` is ``Σ_k (b_k ∂²a_k + a_k ∂²b_k) + a_qᵀb_q + b_qᵀa_q``.

The equations of a joint are a declarative :class:`TermTable` (built once in ``__init__``),
evaluated by the numba kernels :func:`term_values` and :func:`term_hessian`; the Python
``evaluate``/``hessian_lambda`` and a compiled integrator (on a :func:`concatenate_tables` of
all joints) share these kernels.

Local coordinate order (``q_local = q[c.coordinates()]``): attachment a first, then b; a rigid
body contributes its 7 dofs ``[r, p]``, a beam node only the dofs the equations read (``r`` for
translation, ``[r, r′]`` for :class:`BeamNodeRigid`), ground nothing.
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from .._jit import FLAG, njit
from ..elements.ancf_rod import TWIST as NODE_TWIST
from ..elements.ancf_rod import node_director
from ..elements.rigid_body import point_jacobian_of, point_tensor, rotation_matrix
from ..errors import ModelError
from .base import Attachment, Constraint

if TYPE_CHECKING:  # pragma: no cover
    from ..terms import DofMap

__all__ = [
    "EulerParameterNormalization",
    "GenericJoint",
    "BeamNodeRigid",
    "BeamNodeSpherical",
    "spherical",
    "revolute",
    "prismatic",
    "fixed",
    "perpendicular_pair",
    "relative_angle_table",
    "slide_table",
    "TermTable",
    "term_values",
    "term_hessian",
    "hessian_pattern",
    "TermWork",
    "term_work",
    "concatenate_tables",
    "CONST",
    "BODY_POINT",
    "BODY_DIR",
    "NODE_POS",
    "NODE_SLOPE",
    "LIN",
    "DOT",
]

_AXES = ("x", "y", "z")
# rotation about joint axis i is locked by (A_a f_a[:, i1]) · (A_b f_b[:, i2]) = 0 (Haug dot-1)
_ROT_PAIRS = {0: (1, 2), 1: (2, 0), 2: (0, 1)}

# vector kinds (TermTable.vec_kind) and equation kinds (TermTable.eq_kind)
CONST, BODY_POINT, BODY_DIR, NODE_POS, NODE_SLOPE, NODE_DIRECTOR = 0, 1, 2, 3, 4, 5
LIN, DOT = 0, 1


# ---------------------------------------------------------------------------------------------
# declarative equations
class TermTable(NamedTuple):
    """Equations ``LIN: Φ = P·(u1 − u2)`` / ``DOT: Φ = (u1 − u2)·(w1 − w2)`` (Haug 1989 dot-1, point).

    A vector row v is ``c`` (CONST), ``r + A(p)s′`` (BODY_POINT, ``s′ = c``, ``[r, p] =
    q_local[o:o+7]``), ``A(p)f′`` (BODY_DIR, ``f′ = c``), ``q_local[o:o+3]`` (NODE_POS) or
    ``q_local[o+3:o+6]`` (NODE_SLOPE) or the director d2 of a node with a twist
    ``[r, g, φ] = q_local[o:o+7]`` on its base (t̄, D̄) = (``c``, ``vec_d``) (NODE_DIRECTOR,
    :func:`flexmbs.elements.ancf_rod.node_director`), with ``o = vec_off[v]``.
    ``eq_vec[i] = (u1, u2, w1, w2)`` index rows of the same table, −1 = zero vector (w unused
    by LIN).
    """

    vec_kind: np.ndarray   # int64 (nv,)
    vec_off: np.ndarray    # int64 (nv,): local offset of the attachment's first coordinate
    vec_c: np.ndarray      # float64 (nv, 3): c, s′ or f′; zeros for beam node kinds
    vec_T: np.ndarray      # float64 (nv, 3, 4, 4): point_tensor(vec_c) for body kinds, else 0
    vec_d: np.ndarray      # float64 (nv, 3): D̄ of NODE_DIRECTOR, else 0
    eq_kind: np.ndarray    # int64 (ne,): LIN or DOT
    eq_vec: np.ndarray     # int64 (ne, 4): (u1, u2, w1, w2), −1 = absent
    eq_P: np.ndarray       # float64 (ne, 3): projection row (LIN), zeros (DOT)
    directors: np.ndarray | None  # int64: the NODE_DIRECTOR rows; None when there are none
    #   (the kernels then compile none of the rod's code: :func:`_node_director`)


def _empty_table() -> TermTable:
    i, f = np.int64, np.float64
    return TermTable(np.zeros(0, i), np.zeros(0, i), np.zeros((0, 3), f), np.zeros((0, 3, 4, 4), f),
                     np.zeros((0, 3), f), np.zeros(0, i), np.zeros((0, 4), i), np.zeros((0, 3), f),
                     None)


def _director_rows(vec_kind: np.ndarray) -> np.ndarray | None:
    rows = np.flatnonzero(vec_kind == NODE_DIRECTOR).astype(np.int64)
    return rows if rows.size else None


def with_directors(part: Any) -> Any:
    """``part`` (a packed part holding a :class:`TermTable` as ``table``) as the complete
    kernel receives it (flexmbs.kernel.prepare): its node directors present, empty when it has
    none, so that the director code is compiled in (``None`` prunes it, :func:`_node_director`)."""
    if part.table.directors is not None:
        return part
    return part._replace(table=part.table._replace(directors=np.zeros(0, np.int64)))


class _TableBuilder:
    """Collects (deduplicated) vector rows and equations into a :class:`TermTable`."""

    def __init__(self) -> None:
        self._vecs: dict[tuple[int, int, bytes, bytes], int] = {}
        self._vec_rows: list[tuple[int, int, np.ndarray, np.ndarray]] = []
        self._eqs: list[tuple[int, tuple[int, int, int, int], np.ndarray]] = []

    def vec(self, kind: int, off: int, c: np.ndarray | None = None,
            d: np.ndarray | None = None) -> int:
        """Row index of vector (kind, off, c, d), added if new."""
        c = np.zeros(3) if c is None else np.array(c, dtype=np.float64).reshape(3)
        d = np.zeros(3) if d is None else np.array(d, dtype=np.float64).reshape(3)
        key = (kind, off, c.tobytes(), d.tobytes())
        if key not in self._vecs:
            self._vecs[key] = len(self._vec_rows)
            self._vec_rows.append((kind, off, c, d))
        return self._vecs[key]

    def point(self, att: Attachment, off: int) -> int:
        """Global position of the attachment point (ground point, body point or node)."""
        if att.kind == "ground":
            return self.vec(CONST, 0, att.point)
        if att.kind == "beam_node":
            return self.vec(NODE_POS, off)
        return self.vec(BODY_POINT, off, att.point)

    def direction(self, att: Attachment, off: int, f: np.ndarray) -> int:
        """Global components of body vector f (rigid body) or of the global vector f (ground)."""
        if att.kind == "ground":
            return self.vec(CONST, 0, f)
        if att.kind != "rigid_body":
            raise ModelError("a beam node has no frame")  # guarded at construction
        return self.vec(BODY_DIR, off, f)

    def lin(self, P: np.ndarray, u1: int, u2: int) -> None:
        """One LIN equation per row of P."""
        for row in np.atleast_2d(np.asarray(P, dtype=np.float64)):
            self._eqs.append((LIN, (u1, u2, -1, -1), row.copy()))

    def dot(self, u1: int, u2: int, w1: int, w2: int) -> None:
        self._eqs.append((DOT, (u1, u2, w1, w2), np.zeros(3)))

    def build(self) -> TermTable:
        t = _empty_table()
        if self._vec_rows:
            c = np.array([r[2] for r in self._vec_rows])
            body = np.array([r[0] in (BODY_POINT, BODY_DIR) for r in self._vec_rows])
            t = t._replace(vec_kind=np.array([r[0] for r in self._vec_rows], dtype=np.int64),
                           vec_off=np.array([r[1] for r in self._vec_rows], dtype=np.int64),
                           vec_c=c, vec_T=np.ascontiguousarray(point_tensor(c) * body[:, None, None, None]),
                           vec_d=np.array([r[3] for r in self._vec_rows]))
            t = t._replace(directors=_director_rows(t.vec_kind))
        if self._eqs:
            t = t._replace(eq_kind=np.array([e[0] for e in self._eqs], dtype=np.int64),
                           eq_vec=np.array([e[1] for e in self._eqs], dtype=np.int64),
                           eq_P=np.array([e[2] for e in self._eqs]))
        return t


def concatenate_tables(tables: list[TermTable]) -> tuple[TermTable, np.ndarray]:
    """One table of all equations and ``eq_ptr`` (equations of ``tables[k]`` = ``eq_ptr[k]:eq_ptr[k+1]``).

    ``eq_vec`` is shifted to the concatenated vector rows; ``vec_off`` stays local to each
    constraint's ``q_local``.
    """
    eq_ptr = np.zeros(len(tables) + 1, dtype=np.int64)
    eq_ptr[1:] = np.cumsum([t.eq_kind.size for t in tables], dtype=np.int64)
    if not tables:
        return _empty_table(), eq_ptr
    shift = np.cumsum([0] + [t.vec_kind.size for t in tables[:-1]], dtype=np.int64)
    fields = {f: np.ascontiguousarray(np.concatenate([getattr(t, f) for t in tables]))
              for f in TermTable._fields if f != "directors"}
    fields["eq_vec"] = np.ascontiguousarray(np.concatenate(
        [np.where(t.eq_vec >= 0, t.eq_vec + s, -1) for t, s in zip(tables, shift, strict=True)]),
        dtype=np.int64)
    return TermTable(**fields, directors=_director_rows(fields["vec_kind"])), eq_ptr


@njit(refcount=False)
def _node_director(directors, q_node, t_bar, d_bar, val, jac, hes, hessian):
    """:func:`flexmbs.elements.ancf_rod.node_director` for a table that has node directors. For
    one without (``directors`` None) numba prunes the call by the argument's type, so models
    without them compile none of the rod's code (about 10 s of a first run)."""
    if directors is not None:
        node_director(q_node, t_bar, d_bar, val, jac, hes, hessian)


# ---------------------------------------------------------------------------------------------
# kernels
@njit(refcount=False)
def _columns(kind: int, o: int) -> tuple[int, int]:
    """First column and count of the ``q_local`` columns a vector row of ``kind`` at offset o
    depends on (the columns of its ∂v/∂q): a body point all 7, a body direction its p, a beam
    node's position or slope 3, a node director (g, φ), a constant none."""
    if kind == BODY_POINT:
        return o, 7
    if kind == BODY_DIR or kind == NODE_DIRECTOR:  # noqa: SIM109 - compiled: no tuple search
        return o + 3, 4
    if kind == NODE_POS:
        return o, 3
    if kind == NODE_SLOPE:
        return o + 3, 3
    return 0, 0


class TermWork(NamedTuple):
    """Scratch of :func:`term_values` / :func:`term_hessian`, allocated once (:func:`term_work`):
    the four vector slots of an equation (values, weights, ∂v/∂q columns) and a node director."""

    val: np.ndarray      # (4, 3)
    wt: np.ndarray       # (4, 3)
    G: np.ndarray        # (4, 3, 7)
    col: np.ndarray      # int64 (4,)
    ncol: np.ndarray     # int64 (4,)
    held: np.ndarray     # int64 (4,)
    d2: np.ndarray       # (3,)
    jd: np.ndarray       # (3, 4)
    hd: np.ndarray       # (3, 4, 4)


def term_work() -> TermWork:
    """A :class:`TermWork` (packed parts hold one; the Python paths make one per call)."""
    return TermWork(np.zeros((4, 3)), np.zeros((4, 3)), np.zeros((4, 3, 7)),
                    np.zeros(4, np.int64), np.zeros(4, np.int64), np.zeros(4, np.int64),
                    np.zeros(3), np.zeros((3, 4)), np.zeros((3, 4, 4)))


@njit(refcount=False)
def _load(table: TermTable, i: int, q: np.ndarray, w: TermWork) -> None:
    """Slots s = (u1, u2, w1, w2) of equation i: ``val[s] = v(q)``, ``∂v/∂q[:, col[s] + j] = G[s, :, j]``.
    ``held[s]``: the vector row slot s holds from the previous equation (−1: none), kept
    as it is (a joint's equations share their vectors: a spherical joint's three rows load
    each body point once, not three times)."""
    val, G, col, ncol, held = w.val, w.G, w.col, w.ncol, w.held
    for s in range(4):
        v = table.eq_vec[i, s]
        if v >= 0 and held[s] == v:
            continue
        held[s] = v
        if v < 0:
            col[s] = 0
            ncol[s] = 0
            for k in range(3):
                val[s, k] = 0.0
            continue
        kind = table.vec_kind[v]
        o = table.vec_off[v]
        col[s], ncol[s] = _columns(kind, o)
        if kind == CONST:
            for k in range(3):
                val[s, k] = table.vec_c[v, k]
        elif kind == NODE_DIRECTOR:
            _node_director(table.directors, q[o:o + 7], table.vec_c[v], table.vec_d[v], w.d2, w.jd,
                           w.hd, FLAG[0])
            for k in range(3):
                val[s, k] = w.d2[k]
                for j in range(4):
                    G[s, k, j] = w.jd[k, j]
        elif kind == NODE_POS or kind == NODE_SLOPE:  # noqa: SIM109 - compiled: no tuple search
            for k in range(3):
                val[s, k] = q[col[s] + k]
                for j in range(3):
                    G[s, k, j] = 1.0 if j == k else 0.0
        else:  # BODY_POINT r + A(p)s′ or BODY_DIR A(p)f′: (A c)_k = pᵀT_k p, ∂/∂p = 2T_k p
            jp = 3 if kind == BODY_POINT else 0
            for k in range(3):
                for j in range(jp):
                    G[s, k, j] = 1.0 if j == k else 0.0
            # 2T(c)p into G's p columns, A c into val (no scratch arrays)
            point_jacobian_of(table.vec_T[v], q[o + 3:o + 7], G[s, :, jp:jp + 4], val[s])
            if kind == BODY_POINT:
                for k in range(3):
                    val[s, k] += q[o + k]


@njit(refcount=False)
def _weights(table: TermTable, i: int, val: np.ndarray, wt: np.ndarray) -> float:
    """Φ_i, and wt with ``∂Φ_i/∂q = Σ_s wt[s]·∂v_s/∂q`` (LIN: ±P; DOT: ±(w1 − w2), ±(u1 − u2))."""
    phi = 0.0
    if table.eq_kind[i] == LIN:
        for k in range(3):
            P = table.eq_P[i, k]
            phi += P * (val[0, k] - val[1, k])
            wt[0, k] = P
            wt[1, k] = -P
            wt[2, k] = 0.0
            wt[3, k] = 0.0
    else:
        for k in range(3):
            a = val[0, k] - val[1, k]
            b = val[2, k] - val[3, k]
            phi += a * b
            wt[0, k] = b
            wt[1, k] = -b
            wt[2, k] = a
            wt[3, k] = -a
    return phi


@njit(refcount=False)
def term_values(table: TermTable, e0: int, e1: int, q_local: np.ndarray, phi: np.ndarray,
                jac: np.ndarray, w: TermWork) -> None:
    """Haug 1989 dot-1/point constraints: ``phi[i−e0] = Φ_i``, ``jac[i−e0] = ∂Φ_i/∂q`` for e0 ≤ i < e1
    (``w``: scratch, :func:`term_work`)."""
    val, wt, G, col, ncol = w.val, w.wt, w.G, w.col, w.ncol
    w.held[:] = -1
    n = jac.shape[1]
    for i in range(e0, e1):
        r = i - e0
        _load(table, i, q_local, w)
        phi[r] = _weights(table, i, val, wt)
        for j in range(n):
            jac[r, j] = 0.0
        for s in range(4):
            for j in range(ncol[s]):
                acc = 0.0
                for k in range(3):
                    acc += wt[s, k] * G[s, k, j]
                jac[r, col[s] + j] += acc


@njit(refcount=False)
def term_hessian(table: TermTable, e0: int, e1: int, q_local: np.ndarray, lam: np.ndarray,
                 H: np.ndarray, w: TermWork) -> None:
    """Haug 1989 dot-1/point constraints: ``H = Σ_i lam[i−e0] ∂²Φ_i/∂q²`` (exactly symmetric;
    ``w``: scratch, :func:`term_work`)."""
    val, wt, G, col, ncol = w.val, w.wt, w.G, w.col, w.ncol
    w.held[:] = -1
    n = H.shape[0]
    for a in range(n):
        for b in range(n):
            H[a, b] = 0.0
    for i in range(e0, e1):
        li = lam[i - e0]
        if li == 0.0:
            continue
        _load(table, i, q_local, w)
        _weights(table, i, val, wt)
        for s in range(4):  # Σ_k wt_k ∂²v_k/∂p² = 2 Σ_k wt_k T_k on the body's p block
            v = table.eq_vec[i, s]
            if v < 0:
                continue
            if table.vec_kind[v] == NODE_DIRECTOR:   # Σ_k wt_k ∂²d2_k/∂(g, φ)²
                o = table.vec_off[v]
                hd = w.hd
                _node_director(table.directors, q_local[o:o + 7], table.vec_c[v], table.vec_d[v],
                               w.d2, w.jd, hd, FLAG[1])
                for a in range(4):
                    for b in range(4):
                        acc = 0.0
                        for k in range(3):
                            acc += wt[s, k] * hd[k, a, b]
                        H[o + 3 + a, o + 3 + b] += li * acc
                continue
            if table.vec_kind[v] != BODY_POINT and table.vec_kind[v] != BODY_DIR:
                continue
            o = table.vec_off[v] + 3
            for a in range(4):
                for b in range(4):
                    acc = 0.0
                    for k in range(3):
                        acc += wt[s, k] * table.vec_T[v, k, a, b]
                    H[o + a, o + b] += 2.0 * li * acc
        if table.eq_kind[i] == DOT:  # u_qᵀw_q + w_qᵀu_q, u = u1 − u2, w = w1 − w2
            for su in range(2):
                for sw in range(2, 4):
                    c = li if (su == 0) == (sw == 2) else -li
                    for x in range(ncol[su]):
                        for y in range(ncol[sw]):
                            acc = 0.0
                            for k in range(3):
                                acc += G[su, k, x] * G[sw, k, y]
                            acc *= c
                            H[col[su] + x, col[sw] + y] += acc
                            H[col[sw] + y, col[su] + x] += acc
    for a in range(n):  # mirrored entries may be summed in a different order: symmetrise exactly
        for b in range(a + 1, n):
            h = 0.5 * (H[a, b] + H[b, a])
            H[a, b] = h
            H[b, a] = h


def hessian_pattern(table: TermTable, e0: int, e1: int, n: int) -> np.ndarray:
    """Where :func:`term_hessian` of equations e0 ≤ i < e1 can be nonzero, (n, n) bool: the
    second derivative of each nonlinear vector (a body's p block, a node director's (g, φ))
    and, for DOT, ``u_qᵀw_q + w_qᵀu_q`` on the columns of u × those of w (:func:`_columns`).
    The assembler reserves only these entries: a joint of LIN rows (global components) has
    no block between its two bodies, a DOT row only u's columns × w's."""
    mask = np.zeros((n, n), bool)
    for i in range(e0, e1):
        cols: list[slice] = []
        for s in range(4):
            v = int(table.eq_vec[i, s])
            kind = int(table.vec_kind[v]) if v >= 0 else CONST
            o = int(table.vec_off[v]) if v >= 0 else 0
            c0, nc = _columns(kind, o)
            cols.append(slice(c0, c0 + nc))
            if kind in (BODY_POINT, BODY_DIR, NODE_DIRECTOR):
                mask[o + 3:o + 7, o + 3:o + 7] = True
        if table.eq_kind[i] == DOT:
            for u in cols[:2]:
                for w in cols[2:]:
                    mask[u, w] = True
                    mask[w, u] = True
    return mask


def _n_used(att: Attachment) -> int:
    """Local coordinates a point/direction of the attachment reads (body [r, p], node r, ground)."""
    return {"rigid_body": 7, "beam_node": 3}.get(att.kind, 0)


class _TermConstraint(Constraint):
    """Constraint whose equations are the :class:`TermTable` ``self.table``."""

    table: TermTable
    _coords: np.ndarray
    _n: int

    def coordinates(self) -> np.ndarray:
        return self._coords

    def _q(self, q_local: np.ndarray) -> np.ndarray:
        q = np.ascontiguousarray(q_local, dtype=np.float64)
        if q.shape != (self._n,):
            raise ValueError(f"{self.name}: q_local needs shape ({self._n},) (got {q.shape})")
        return q

    def evaluate(self, q_local: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
        m = self.n_equations
        phi = np.empty(m)
        jac = np.empty((m, self._n))
        term_values(self.table, 0, m, self._q(q_local), phi, jac, term_work())
        return phi, jac

    def hessian_lambda(self, q_local: np.ndarray, lam: np.ndarray, t: float) -> np.ndarray:
        m = self.n_equations
        lam = np.ascontiguousarray(lam, dtype=np.float64).reshape(-1)
        if lam.shape != (m,):
            raise ValueError(f"{self.name}: lam needs shape ({m},) (got {lam.shape})")
        H = np.empty((self._n, self._n))
        term_hessian(self.table, 0, m, self._q(q_local), lam, H, term_work())
        return H


# ---------------------------------------------------------------------------------------------
class EulerParameterNormalization(Constraint):
    """Haug 1989, docs/theory.md §I.5: ``Φ^p = pᵀp − 1 = 0``.

    ``dofs7`` are the body's global indices ``[r, p]``; only the 4 p indices are returned by
    :meth:`coordinates` (Φ does not depend on r).
    """

    def __init__(self, name: str, dofs7: np.ndarray) -> None:
        dofs7 = np.asarray(dofs7, dtype=np.int64).reshape(-1)
        if dofs7.size != 7:
            raise ModelError(f"{name}: EulerParameterNormalization needs the 7 body dofs "
                             f"(got {dofs7.size})")
        self.name = name
        self.n_equations = 1
        self.equation_labels = ["norm_p"]
        self._coords = dofs7[3:].copy()

    def coordinates(self) -> np.ndarray:
        return self._coords

    def evaluate(self, q_local: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
        p = np.ascontiguousarray(q_local, dtype=float)
        return np.array([euler_norm(p)]), 2.0 * p[None, :]

    def hessian_lambda(self, q_local: np.ndarray, lam: np.ndarray, t: float) -> np.ndarray:
        return 2.0 * float(np.asarray(lam).reshape(-1)[0]) * np.eye(4)


# ---------------------------------------------------------------------------------------------
class GenericJoint(_TermConstraint):
    """Joint locking the relative translations/rotations selected by masks (Haug 1989 §9.2-9.3).

    Joint frames: on a rigid body ``J = A(p)·frame`` at ``x = r + A(p)·point``; on ground ``frame``
    and ``point`` are global; a beam node (attachment a only, translation only) has ``x = r_node``.

    - Translation, all three axes locked: the global components ``x_a − x_b = 0`` (labels x, y,
      z and the multipliers' components are global; linear when the other side is ground or a
      beam node). Between two bodies this has no Hessian block coupling them, so a chain of
      bodies keeps a narrower band (issue 37).
    - Translation, some axes locked: ``(A_b f_b[:,k])·(x_a − x_b) = 0`` for each locked axis k
      (components in b's joint frame, which the free axes need).
    - Rotation (dot-1 form): about joint x ``(A_a f_a[:,1])·(A_b f_b[:,2]) = 0``, about y
      ``(A_a f_a[:,2])·(A_b f_b[:,0]) = 0``, about z ``(A_a f_a[:,0])·(A_b f_b[:,1]) = 0``.
      They assume the frames are aligned (up to the free rotations) at assembly; a dot-1
      equation cannot tell an angle from its supplement, as usual.

    Equation order: translations x, y, z (masked), then rotations x, y, z (masked); labels
    ``"x", "y", "z", "rot_x", "rot_y", "rot_z"``.
    """

    def __init__(self, name: str, a: Attachment, b: Attachment,
                 translation: tuple[int, int, int] | list[int] = (1, 1, 1),
                 rotation: tuple[int, int, int] | list[int] = (0, 0, 0)) -> None:
        tr = tuple(bool(x) for x in translation)
        ro = tuple(bool(x) for x in rotation)
        if len(tr) != 3 or len(ro) != 3 or not any(tr + ro):
            raise ModelError(f"{name}: translation and rotation masks need 3 entries and at "
                             "least one locked direction")
        if a.is_ground and b.is_ground:
            raise ModelError(f"{name}: a joint between ground and ground has no coordinates")
        if b.kind == "beam_node":
            raise ModelError(f"{name}: a beam node must be attachment a (b is projected on "
                             "its joint frame, which a beam node does not have)")
        if a.kind == "beam_node" and any(ro):
            raise ModelError(f"{name}: a beam node has no rotation frame; lock only "
                             "translations, or use BeamNodeRigid for a rigid connection")
        self.name = name
        self.translation = tr
        self.rotation = ro
        self.a = a
        self.b = b
        na, nb = _n_used(a), _n_used(b)
        self._n = na + nb
        self._coords = np.concatenate([a.dofs[:na], b.dofs[:nb]])
        tr_axes = [k for k in range(3) if tr[k]]
        rot_axes = [k for k in range(3) if ro[k]]
        self.global_translation = all(tr)
        self.n_equations = len(tr_axes) + len(rot_axes)
        self.equation_labels = ([_AXES[k] for k in tr_axes] + [f"rot_{_AXES[k]}" for k in rot_axes])
        tb = _TableBuilder()
        if tr_axes:
            xa, xb = tb.point(a, 0), tb.point(b, na)
            if self.global_translation:
                tb.lin(np.eye(3), xa, xb)
            elif b.is_ground:
                tb.lin(b.frame[:, tr_axes].T, xa, xb)
            else:
                for k in tr_axes:
                    tb.dot(tb.direction(b, na, b.frame[:, k]), -1, xa, xb)
        for k in rot_axes:
            ia, ib = _ROT_PAIRS[k]
            tb.dot(tb.direction(a, 0, a.frame[:, ia]), -1, tb.direction(b, na, b.frame[:, ib]), -1)
        self.table = tb.build()


def spherical(name: str, a: Attachment, b: Attachment) -> GenericJoint:
    """Spherical joint: the joint points coincide (3 equations)."""
    return GenericJoint(name, a, b, translation=(1, 1, 1), rotation=(0, 0, 0))


def revolute(name: str, a: Attachment, b: Attachment) -> GenericJoint:
    """Revolute joint: points coincide, rotation about joint y and z locked (5 equations).

    The revolute axis is the **x axis of the joint frame** (``frame[:, 0]`` of a and of b, which
    must be aligned at assembly).
    """
    return GenericJoint(name, a, b, translation=(1, 1, 1), rotation=(0, 1, 1))


def prismatic(name: str, a: Attachment, b: Attachment) -> GenericJoint:
    """Prismatic joint sliding along the joint frame's x axis (translation y, z and all rotations
    locked, 5 equations)."""
    return GenericJoint(name, a, b, translation=(0, 1, 1), rotation=(1, 1, 1))


def fixed(name: str, a: Attachment, b: Attachment) -> GenericJoint:
    """Fixed (welded) joint: all 6 relative motions locked."""
    return GenericJoint(name, a, b, translation=(1, 1, 1), rotation=(1, 1, 1))


def relative_angle_table(a: Attachment, b: Attachment, na: int) -> TermTable:
    """The two equations ``c = (J_b e_y)·(J_a e_y)``, ``s = (J_b e_z)·(J_a e_y)`` of the relative
    rotation of a's joint frame about b's joint x axis: with ``J_a = J_b R_x(θ)`` they are
    ``cos θ`` and ``sin θ`` (Haug 1989 §9.4 rotational drivers). The rotational spring-damper
    (:mod:`flexmbs.springs`, θ = atan2(s, c)) and the rotation driver
    (:mod:`flexmbs.constraints.drivers`, Φ = s cos θ_d − c sin θ_d) both read them; ``na`` is the
    local offset of b's coordinates (a's come first)."""
    for att in (a, b):
        if att.kind == "beam_node":
            raise ModelError("a beam node has no rotation frame; an angle about a joint axis "
                             "needs rigid bodies or ground at both ends")
    tb = _TableBuilder()
    ya = tb.direction(a, 0, a.frame[:, 1])
    tb.dot(tb.direction(b, na, b.frame[:, 1]), -1, ya, -1)
    tb.dot(tb.direction(b, na, b.frame[:, 2]), -1, ya, -1)
    return tb.build()


def slide_table(a: Attachment, b: Attachment, na: int) -> TermTable:
    """The one equation ``(J_b e_x)·(x_a − x_b)``: the slide of a's joint point along b's
    joint x axis (the prismatic driver, :mod:`flexmbs.constraints.drivers`)."""
    if b.kind == "beam_node":
        raise ModelError("a slide is measured along the joint axis of b, which a beam node "
                         "does not have: attach the node as a")
    tb = _TableBuilder()
    tb.dot(tb.direction(b, na, b.frame[:, 0]), -1, tb.point(a, 0), tb.point(b, na))
    return tb.build()


# ---------------------------------------------------------------------------------------------
def perpendicular_pair(t: np.ndarray) -> np.ndarray:
    """Two orthonormal vectors ⟂ t, as columns (3,2), right-handed with t: ``n2 = t̂ × n1``."""
    t = np.asarray(t, dtype=float)
    nt = np.linalg.norm(t)
    if not np.isfinite(nt) or nt == 0.0:
        raise ModelError(f"cannot build normals of a zero or non-finite tangent {t!r}")
    t = t / nt
    helper = np.eye(3)[int(np.argmin(np.abs(t)))]
    n1 = np.cross(t, helper)
    n1 /= np.linalg.norm(n1)
    return np.column_stack([n1, np.cross(t, n1)])


class BeamNodeSpherical(_TermConstraint):
    """Beam node position on a body point or ground point: ``r_i − x_b = 0`` (global, 3 eqs)."""

    def __init__(self, name: str, node: Attachment, body: Attachment) -> None:
        if node.kind != "beam_node":
            raise ModelError(f"{name}: BeamNodeSpherical needs a beam_node attachment first")
        if body.kind == "beam_node":
            raise ModelError(f"{name}: the second attachment must be a rigid body or ground")
        self.name = name
        self.node = node
        self.body = body
        nb = _n_used(body)
        self._n = 3 + nb
        self._coords = np.concatenate([node.dofs[:3], body.dofs[:nb]])
        self.n_equations = 3
        self.equation_labels = ["x", "y", "z"]
        tb = _TableBuilder()
        tb.lin(np.eye(3), tb.point(node, 0), tb.point(body, 3))
        self.table = tb.build()


class BeamNodeRigid(_TermConstraint):
    """Rigid connection of a beam node to a body (docs/theory.md §I.2.3).

    ``r_i − (r_B + A s′) = 0`` (3 eqs, global) and ``(A n₁′)·r′_i = 0``, ``(A n₂′)·r′_i = 0``,
    where ``s′ = body.point`` and n₁′, n₂′ (columns of ``normals_body``, body coordinates, or
    global for ground) are ⟂ the node tangent. The tangential slope component stays free, so
    the beam can stretch at the connection. A node with a twist (the rod: ``node.dofs`` =
    ``[r, r′, φ]``, its base ``(t̄, D̄)``) also holds its section: ``(A n₃′)·d2_i = 0`` with
    n₃′ ⟂ the node's director d2 (i.e. along d3 when built, §2.3's ``(A n₂′)·d3_i = 0``
    for the normal pair taken along the section axes). Use :meth:`from_configuration` to
    freeze the current configuration. Labels ``"x", "y", "z", "slope_n1", "slope_n2"`` and
    ``"twist"``.
    """

    def __init__(self, name: str, node: Attachment, body: Attachment,
                 normals_body: np.ndarray, twist_normal: np.ndarray | None = None,
                 base: tuple[np.ndarray, np.ndarray] | None = None) -> None:
        if node.kind != "beam_node":
            raise ModelError(f"{name}: BeamNodeRigid needs a beam_node attachment first")
        if body.kind == "beam_node":
            raise ModelError(f"{name}: the second attachment must be a rigid body or ground")
        N = np.asarray(normals_body, dtype=float)
        if N.shape != (3, 2) or not np.all(np.isfinite(N)) or np.linalg.matrix_rank(N) < 2:
            raise ModelError(f"{name}: normals_body must be two independent 3-vectors as "
                             f"columns, shape (3, 2) (got shape {N.shape})")
        self.name = name
        self.node = node
        self.body = body
        self.normals_body = N.copy()
        twisted = node.twist
        if twisted and (twist_normal is None or base is None):
            raise ModelError(f"{name}: a node with a twist needs its base (t̄, D̄) and the body "
                             "normal holding its section (use from_configuration)")
        nb = _n_used(body)
        nn = node.dofs.size
        self._n = nn + nb
        self._coords = np.concatenate([node.dofs, body.dofs[:nb]])
        self.n_equations = 6 if twisted else 5
        self.equation_labels = ["x", "y", "z", "slope_n1", "slope_n2"] + (["twist"] if twisted else [])
        tb = _TableBuilder()
        tb.lin(np.eye(3), tb.point(node, 0), tb.point(body, nn))
        g = tb.vec(NODE_SLOPE, 0)
        for j in range(2):
            tb.dot(tb.direction(body, nn, N[:, j]), -1, g, -1)
        if twisted:
            assert twist_normal is not None and base is not None
            d2 = tb.vec(NODE_DIRECTOR, 0, base[0], base[1])
            tb.dot(tb.direction(body, nn, np.asarray(twist_normal, float)), -1, d2, -1)
        self.table = tb.build()

    @classmethod
    def from_configuration(cls, name: str, node: Attachment, body: Attachment,
                           q_node: np.ndarray, q_body: np.ndarray | None = None, *,
                           at_node: bool = True,
                           base: tuple[np.ndarray, np.ndarray] | None = None) -> BeamNodeRigid:
        """Connection frozen at the given configuration.

        ``q_node`` = the node's ``[r, r′]`` (``[r, r′, φ]`` with its ``base`` for a node with a
        twist), ``q_body`` = the body's ``[r, p]`` (None for ground).
        The normals are ⟂ the current tangent, in body coordinates. With ``at_node`` the body
        point is replaced by the node's current position (so Φ = 0 there); otherwise
        ``body.point`` is kept.
        """
        q_node = np.asarray(q_node, dtype=float)
        if body.kind == "rigid_body":
            if q_body is None:
                raise ModelError(f"{name}: q_body is needed for a rigid-body attachment")
            q_body = np.asarray(q_body, dtype=float)
            p = q_body[3:7] / np.linalg.norm(q_body[3:7])
            A = rotation_matrix(p)
            origin = q_body[:3]
        else:
            A = np.eye(3)
            origin = np.zeros(3)
        normals = perpendicular_pair(A.T @ q_node[3:6])
        if at_node:
            body = replace(body, point=A.T @ (q_node[:3] - origin))
        twist_normal = None
        if node.twist:
            if base is None:
                raise ModelError(f"{name}: a node with a twist needs its base (t̄, D̄)")
            d2 = np.empty(3)
            node_director(np.ascontiguousarray(q_node, dtype=float), np.asarray(base[0], float),
                          np.asarray(base[1], float), d2, np.empty((3, 4)), np.empty((3, 4, 4)),
                          FLAG[0])
            t = q_node[3:6] / np.linalg.norm(q_node[3:6])
            twist_normal = A.T @ np.cross(t, d2)
        return cls(name, node, body, normals, twist_normal, base)


# ---------------------------------------------------------------------------------------------
# the joint terms of the assembler (flexmbs.terms)
@njit(refcount=False)
def euler_norm(p):
    """Haug 1989, docs/theory.md §I.5: ``Φ^p = pᵀp − 1`` (its gradient is ``2p``, its Hessian ``2I``)."""
    return p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3] - 1.0


class NormPart(NamedTuple):
    """Euler-parameter normalisation of every body."""

    coords: np.ndarray               # (k, 4) Euler parameters of a body
    rows: np.ndarray                 # (k,) multiplier
    pos_jac: np.ndarray              # (k, 4) positions of Φ_q, Φ_qᵀ, and the Hessian diagonal
    pos_jacT: np.ndarray
    pos_hess: np.ndarray
    p: np.ndarray                    # work (4,)


class JointPart(NamedTuple):
    """The joints whose equations are term tables (:class:`TermTable`), concatenated: the
    ``joints`` part of the packed system."""

    table: TermTable
    eq_ptr: np.ndarray               # (nc + 1,) equations of constraint c
    coord_ptr: np.ndarray            # (nc + 1,) coordinates of constraint c in ``coords``
    coords: np.ndarray
    rows: np.ndarray                 # (n_eq,) multiplier of each equation, −1 if dropped
    jptr: np.ndarray                 # (nc + 1,) into pos_jac / pos_jacT (kept rows × coords)
    pos_jac: np.ndarray
    pos_jacT: np.ndarray
    hptr: np.ndarray                 # (nc + 1,) into hess_a, hess_b, pos_hess: the entries
    hess_a: np.ndarray               # (local row, column) of :func:`hessian_pattern` and
    hess_b: np.ndarray               # their matrix positions
    pos_hess: np.ndarray
    ql: np.ndarray                   # work
    phi: np.ndarray
    jac: np.ndarray
    H: np.ndarray
    lam: np.ndarray
    work: TermWork


def joint_pattern(coords: np.ndarray, rows: np.ndarray, n: int,
                  constraint: object = None) -> list[tuple[np.ndarray, np.ndarray]]:
    """Φ_q (kept rows × coordinates), its transpose, and the Hessian: the whole block, or for
    a joint of a term table (``constraint.table``) the entries of :func:`hessian_pattern`."""
    kept = n + rows[rows >= 0]
    blocks = [(kept, coords), (coords, kept)]
    table = getattr(constraint, "table", None)
    if not isinstance(table, TermTable):
        return blocks + [(coords, coords)]
    mask = hessian_pattern(table, 0, table.eq_kind.size, coords.size)
    return blocks + [(coords[a:a + 1], coords[mask[a]]) for a in range(coords.size)
                     if mask[a].any()]


def _kept_positions(dofs: DofMap, coords: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, ...]:
    """Positions of Φ_q (kept rows × coordinates) and of its transpose, row by row."""
    n = dofs.n_coords
    kept = n + rows[rows >= 0]
    jac = dofs.positions(kept, coords)
    jacT = dofs.positions(coords, kept).reshape(coords.size, kept.size).T.ravel()
    return jac, jacT


def pack_norms(constraints: list[EulerParameterNormalization], dofs: DofMap) -> NormPart:
    k = len(constraints)
    coords = np.array([c.coordinates() for c in constraints], dtype=np.int64).reshape(k, 4)
    rows = np.array([dofs.multiplier_rows(c)[0] for c in constraints], dtype=np.int64)
    pj, pt, ph = [], [], []
    for c, r in zip(coords, rows, strict=True):
        j, t = _kept_positions(dofs, c, np.array([r]))
        h = dofs.positions(c, c)
        pj.append(j)
        pt.append(t)
        ph.append(h.reshape(4, 4).diagonal().copy())
    i64 = np.int64
    return NormPart(
        coords=coords,
        rows=rows,
        pos_jac=np.array(pj, i64).reshape(k, 4),
        pos_jacT=np.array(pt, i64).reshape(k, 4),
        pos_hess=np.array(ph, i64).reshape(k, 4),
        p=np.zeros(4))


def pack_joints(constraints: list, dofs: DofMap) -> JointPart:
    """Joints whose equations are a :class:`TermTable` (``c.table``)."""
    table, eq_ptr = concatenate_tables([c.table for c in constraints])
    coords = [np.asarray(c.coordinates(), np.int64) for c in constraints]
    rows = [np.asarray(dofs.multiplier_rows(c), np.int64) for c in constraints]
    nc = len(constraints)
    cptr = np.zeros(nc + 1, np.int64)
    cptr[1:] = np.cumsum([c.size for c in coords])
    jptr = np.zeros(nc + 1, np.int64)
    hptr = np.zeros(nc + 1, np.int64)
    pj, pt, ha, hb, ph = [], [], [], [], []
    for i, (con, c, r) in enumerate(zip(constraints, coords, rows, strict=True)):
        j, t = _kept_positions(dofs, c, r)
        a, b = np.nonzero(hessian_pattern(con.table, 0, con.table.eq_kind.size, c.size))
        h = dofs.positions_present(c, c).reshape(c.size, c.size)[a, b]
        if (h < 0).any():
            raise ModelError(f"internal: '{con.name}': Hessian entry outside the pattern")
        pj.append(j)
        pt.append(t)
        ha.append(a)
        hb.append(b)
        ph.append(h)
        jptr[i + 1] = jptr[i] + j.size
        hptr[i + 1] = hptr[i] + h.size
    max_nl = max((c.size for c in coords), default=0)
    max_ne = int(np.max(np.diff(eq_ptr), initial=0))
    i64 = np.int64

    def cat(parts: list[np.ndarray]) -> np.ndarray:
        return np.concatenate(parts).astype(i64) if parts else np.zeros(0, i64)

    return JointPart(
        table=table,
        eq_ptr=np.ascontiguousarray(eq_ptr, i64),
        coord_ptr=cptr,
        coords=cat(coords),
        rows=cat(rows),
        jptr=jptr,
        pos_jac=cat(pj),
        pos_jacT=cat(pt),
        hptr=hptr,
        hess_a=cat(ha),
        hess_b=cat(hb),
        pos_hess=cat(ph),
        ql=np.zeros(max_nl),
        phi=np.zeros(max_ne),
        jac=np.zeros((max_ne, max_nl)),
        H=np.zeros((max_nl, max_nl)),
        lam=np.zeros(max_ne),
        work=term_work())


@njit(refcount=False, internal=True)
def norms_residual(nm, n, q, lam, r):
    """``r_λ = pᵀp − 1``, ``r_p += 2p λ`` of every body."""
    if nm is None:   # none in the model: compiled to nothing (driver.OPTIONAL_KINDS)
        return
    for i in range(nm.rows.size):
        row = nm.rows[i]
        for k in range(4):
            nm.p[k] = q[nm.coords[i, k]]
        r[n + row] = euler_norm(nm.p)
        for k in range(4):
            r[nm.coords[i, k]] += 2.0 * nm.p[k] * lam[row]


@njit(refcount=False, internal=True)
def norms_jacobian(nm, q, lam, cK, data):
    if nm is None:   # none in the model: compiled to nothing (driver.OPTIONAL_KINDS)
        return
    for i in range(nm.rows.size):
        lr = lam[nm.rows[i]]
        for k in range(4):
            pk = q[nm.coords[i, k]]
            data[nm.pos_jac[i, k]] += 2.0 * pk
            data[nm.pos_jacT[i, k]] += 2.0 * pk
            data[nm.pos_hess[i, k]] += cK * 2.0 * lr


@njit(inline="always")
def _term_constraint(tm, c, q):
    """Φ, Φ_q of joint c into ``tm.phi``, ``tm.jac``; returns (first coordinate, coordinates,
    first equation, end of equations)."""
    c0 = tm.coord_ptr[c]
    nloc = tm.coord_ptr[c + 1] - c0
    for k in range(nloc):
        tm.ql[k] = q[tm.coords[c0 + k]]
    e0 = tm.eq_ptr[c]
    e1 = tm.eq_ptr[c + 1]
    term_values(tm.table, e0, e1, tm.ql[:nloc], tm.phi, tm.jac[:, :nloc], tm.work)
    return c0, nloc, e0, e1


@njit(refcount=False, internal=True)
def joints_residual(tm, n, q, lam, r):
    """``r_λ = Φ``, ``r_q += Φ_qᵀλ`` of every joint of the term tables."""
    if tm is None:   # none in the model: compiled to nothing (driver.OPTIONAL_KINDS)
        return
    for c in range(tm.coord_ptr.size - 1):
        c0, nloc, e0, e1 = _term_constraint(tm, c, q)
        for i in range(e0, e1):
            row = tm.rows[i]
            if row < 0:
                continue
            r[n + row] = tm.phi[i - e0]
            lr = lam[row]
            for k in range(nloc):
                r[tm.coords[c0 + k]] += tm.jac[i - e0, k] * lr


@njit(internal=True)
def joints_set_bases(tm, log, stop):
    """Re-based nodes (``log[:stop]``, records ``[twist coordinate, t̄, D̄]``, docs/theory.md §I.2.4):
    the directors (NODE_DIRECTOR) of joints holding them read the new bases."""
    if tm is None:   # none in the model: compiled to nothing (driver.OPTIONAL_KINDS)
        return
    table = tm.table
    for c in range(tm.coord_ptr.size - 1):
        c0 = tm.coord_ptr[c]
        for i in range(tm.eq_ptr[c], tm.eq_ptr[c + 1]):
            for s in range(4):
                v = table.eq_vec[i, s]
                if v < 0 or table.vec_kind[v] != NODE_DIRECTOR:
                    continue
                twist = tm.coords[c0 + table.vec_off[v] + NODE_TWIST]
                for j in range(stop):
                    if np.int64(log[j, 0]) == twist:
                        for k in range(3):
                            table.vec_c[v, k] = log[j, 1 + k]
                            table.vec_d[v, k] = log[j, 4 + k]


@njit(refcount=False, internal=True)
def joints_jacobian(tm, q, lam, cK, data):
    """Φ_q, Φ_qᵀ and ``cK Σ λ_i ∂²Φ_i/∂q²`` of every joint of the term tables."""
    if tm is None:   # none in the model: compiled to nothing (driver.OPTIONAL_KINDS)
        return
    for c in range(tm.coord_ptr.size - 1):
        c0, nloc, e0, e1 = _term_constraint(tm, c, q)
        w = tm.jptr[c]
        for i in range(e0, e1):
            row = tm.rows[i]
            tm.lam[i - e0] = lam[row] if row >= 0 else 0.0
            if row < 0:
                continue
            for k in range(nloc):
                data[tm.pos_jac[w]] += tm.jac[i - e0, k]
                data[tm.pos_jacT[w]] += tm.jac[i - e0, k]
                w += 1
        H = tm.H[:nloc, :nloc]
        term_hessian(tm.table, e0, e1, tm.ql[:nloc], tm.lam, H, tm.work)
        for k in range(tm.hptr[c], tm.hptr[c + 1]):     # the entries of hessian_pattern
            data[tm.pos_hess[k]] += cK * H[tm.hess_a[k], tm.hess_b[k]]

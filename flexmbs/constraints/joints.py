"""Joints between rigid bodies, beam nodes and ground (Haug 1989 "dot-1" form; exact Hessians).

Every equation is either a constant projection ``Pᵀv`` of a vector v(q) or a dot product
``u(q)·w(q)``, where u, v, w are body points ``r + A(p)s′``, body directions ``A(p)f′``, beam
node positions/slopes or constants. With the homogeneous rotation matrix ``(A(p)s)_k = pᵀT_k(s)p``
(:func:`flexmbs.elements.rigid_body.point_tensor`) each such vector is a polynomial of degree ≤ 2,
so ``∂v/∂p = 2T(s)p`` and ``∂²v_k/∂p² = 2T_k(s)`` exactly, and the Hessian of a dot product is
``Σ_k (w_k ∂²u_k + u_k ∂²w_k) + u_qᵀw_q + w_qᵀu_q`` (the last terms give the p_a–p_b blocks).

Local coordinate order (``q_local = q[c.coordinates()]``): attachment a first, then b; a rigid
body contributes its 7 dofs ``[r, p]``, a beam node only the dofs the equations read (``r`` for
translation, ``[r, r′]`` for :class:`BeamNodeRigid`), ground nothing.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..elements.rigid_body import point_tensor, rotation_matrix
from ..errors import ModelError
from .base import Attachment, Constraint

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
]

_AXES = ("x", "y", "z")
# rotation about joint axis i is locked by (A_a f_a[:, i1]) · (A_b f_b[:, i2]) = 0 (Haug dot-1)
_ROT_PAIRS = {0: (1, 2), 1: (2, 0), 2: (0, 1)}


# ---------------------------------------------------------------------------------------------
# vector quantities with exact first and second derivatives
class _Vec:
    """A 3-vector v(q_local): value, Jacobian (3, n) and Hessian blocks.

    ``blocks`` is a list of ``(offset, H)`` with H (3,4,4): ``∂²v_k/∂q²`` has ``H_k`` at
    ``[offset:offset+4, offset:offset+4]`` (the Euler parameters of one body), zero elsewhere.
    """

    __slots__ = ("val", "jac", "blocks")

    def __init__(self, val: np.ndarray, jac: np.ndarray,
                 blocks: list[tuple[int, np.ndarray]]) -> None:
        self.val = val
        self.jac = jac
        self.blocks = blocks

    def __sub__(self, other: _Vec) -> _Vec:
        return _Vec(self.val - other.val, self.jac - other.jac,
                    self.blocks + [(o, -H) for o, H in other.blocks])


def _add_blocks(H: np.ndarray, coeff: np.ndarray, v: _Vec) -> None:
    """H += Σ_k coeff_k ∂²v_k/∂q²."""
    for off, T in v.blocks:
        H[off:off + 4, off:off + 4] += np.einsum("k,kij->ij", coeff, T)


class _Side:
    """One attachment placed at ``offset`` in the local coordinates."""

    def __init__(self, att: Attachment, offset: int, n_used: int) -> None:
        self.att = att
        self.kind = att.kind
        self.offset = offset
        self.n_used = n_used
        self.T_point = point_tensor(att.point) if att.kind == "rigid_body" else None
        self._T_dir: dict[int, np.ndarray] = {}

    def used_dofs(self) -> np.ndarray:
        return self.att.dofs[: self.n_used]

    def _rigid(self, q: np.ndarray, n: int, T: np.ndarray, with_r: bool) -> _Vec:
        o = self.offset
        p = q[o + 3:o + 7]
        Tp = T @ p                                   # (3,4)
        val = Tp @ p
        jac = np.zeros((3, n))
        jac[:, o + 3:o + 7] = 2.0 * Tp
        if with_r:
            val = val + q[o:o + 3]
            jac[0, o] = jac[1, o + 1] = jac[2, o + 2] = 1.0
        return _Vec(val, jac, [(o + 3, 2.0 * T)])

    def point(self, q: np.ndarray, n: int) -> _Vec:
        """Global position of the attachment point."""
        o = self.offset
        if self.kind == "ground":
            return _Vec(np.array(self.att.point), np.zeros((3, n)), [])
        if self.kind == "beam_node":
            jac = np.zeros((3, n))
            jac[0, o] = jac[1, o + 1] = jac[2, o + 2] = 1.0
            return _Vec(q[o:o + 3].copy(), jac, [])
        assert self.T_point is not None
        return self._rigid(q, n, self.T_point, with_r=True)

    def direction(self, q: np.ndarray, n: int, f: np.ndarray, key: int) -> _Vec:
        """Global components of the body vector f (rigid) or the global vector f (ground)."""
        if self.kind == "ground":
            return _Vec(np.array(f, dtype=float), np.zeros((3, n)), [])
        if self.kind != "rigid_body":
            raise ModelError("a beam node has no frame")  # guarded at construction
        T = self._T_dir.get(key)
        if T is None:
            T = self._T_dir[key] = point_tensor(f)
        return self._rigid(q, n, T, with_r=False)

    def axis(self, q: np.ndarray, n: int, k: int) -> _Vec:
        return self.direction(q, n, self.att.frame[:, k], key=k)

    def slope(self, q: np.ndarray, n: int) -> _Vec:
        """Beam node slope r′ (needs ``n_used == 6``)."""
        o = self.offset
        jac = np.zeros((3, n))
        jac[0, o + 3] = jac[1, o + 4] = jac[2, o + 5] = 1.0
        return _Vec(q[o + 3:o + 6].copy(), jac, [])


def _n_used(att: Attachment, need_slope: bool = False) -> int:
    if att.kind == "rigid_body":
        return 7
    if att.kind == "beam_node":
        return 6 if need_slope else 3
    return 0


# A term is ("lin", P (m,3), v) -> P v  or  ("dot", u, w) -> u·w (one equation).
_Term = tuple


class _TermConstraint(Constraint):
    """Constraint whose equations are linear projections and dot products of _Vec quantities."""

    _coords: np.ndarray
    _n: int

    def coordinates(self) -> np.ndarray:
        return self._coords

    def _terms(self, q: np.ndarray) -> list[_Term]:
        raise NotImplementedError

    def evaluate(self, q_local: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
        q = np.asarray(q_local, dtype=float)
        phi = np.empty(self.n_equations)
        jac = np.empty((self.n_equations, self._n))
        i = 0
        for term in self._terms(q):
            if term[0] == "lin":
                _, P, v = term
                m = P.shape[0]
                phi[i:i + m] = P @ v.val
                jac[i:i + m] = P @ v.jac
                i += m
            else:
                _, u, w = term
                phi[i] = u.val @ w.val
                jac[i] = w.val @ u.jac + u.val @ w.jac
                i += 1
        return phi, jac

    def hessian_lambda(self, q_local: np.ndarray, lam: np.ndarray, t: float) -> np.ndarray:
        q = np.asarray(q_local, dtype=float)
        lam = np.asarray(lam, dtype=float)
        H = np.zeros((self._n, self._n))
        i = 0
        for term in self._terms(q):
            if term[0] == "lin":
                _, P, v = term
                m = P.shape[0]
                _add_blocks(H, P.T @ lam[i:i + m], v)
                i += m
            else:
                _, u, w = term
                li = lam[i]
                i += 1
                if li == 0.0:
                    continue
                _add_blocks(H, li * w.val, u)
                _add_blocks(H, li * u.val, w)
                if u.jac.any() and w.jac.any():
                    C = li * (u.jac.T @ w.jac)
                    H += C + C.T
        return H


# ---------------------------------------------------------------------------------------------
class EulerParameterNormalization(Constraint):
    """Haug 1989, FORMULATION I §5: ``Φ^p = pᵀp − 1 = 0``.

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
        p = np.asarray(q_local, dtype=float)
        return np.array([p @ p - 1.0]), 2.0 * p[None, :]

    def hessian_lambda(self, q_local: np.ndarray, lam: np.ndarray, t: float) -> np.ndarray:
        return 2.0 * float(np.asarray(lam).reshape(-1)[0]) * np.eye(4)


# ---------------------------------------------------------------------------------------------
class GenericJoint(_TermConstraint):
    """Joint locking the relative translations/rotations selected by masks (Haug 1989 §9.2-9.3).

    Joint frames: on a rigid body ``J = A(p)·frame`` at ``x = r + A(p)·point``; on ground ``frame``
    and ``point`` are global; a beam node (attachment a only, translation only) has ``x = r_node``.

    - Translation, axis k locked: ``(A_b f_b[:,k])·(x_a − x_b) = 0`` (components in b's joint
      frame). If all three are locked and a or b is ground, the equations are the global
      components ``x_a − x_b = 0`` instead (same constraint set, linear when the other side is
      a beam node, labels then mean global x, y, z).
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
        na = _n_used(a)
        self._sa = _Side(a, 0, na)
        self._sb = _Side(b, na, _n_used(b))
        self._n = na + self._sb.n_used
        self._coords = np.concatenate([self._sa.used_dofs(), self._sb.used_dofs()])
        self._tr_axes = [k for k in range(3) if tr[k]]
        self._rot_axes = [k for k in range(3) if ro[k]]
        self.global_translation = all(tr) and (a.is_ground or b.is_ground)
        if self.global_translation:
            self._P = np.eye(3)
        elif b.is_ground:
            self._P = np.ascontiguousarray(b.frame[:, self._tr_axes].T)
        else:
            self._P = None
        self.n_equations = len(self._tr_axes) + len(self._rot_axes)
        self.equation_labels = ([_AXES[k] for k in self._tr_axes]
                                + [f"rot_{_AXES[k]}" for k in self._rot_axes])

    def _terms(self, q: np.ndarray) -> list[_Term]:
        n, sa, sb = self._n, self._sa, self._sb
        terms: list[_Term] = []
        if self._tr_axes:
            d = sa.point(q, n) - sb.point(q, n)
            if self._P is not None:
                terms.append(("lin", self._P, d))
            else:
                terms.extend(("dot", sb.axis(q, n, k), d) for k in self._tr_axes)
        for k in self._rot_axes:
            ia, ib = _ROT_PAIRS[k]
            terms.append(("dot", sa.axis(q, n, ia), sb.axis(q, n, ib)))
        return terms


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
        self._sa = _Side(node, 0, 3)
        self._sb = _Side(body, 3, _n_used(body))
        self._n = 3 + self._sb.n_used
        self._coords = np.concatenate([self._sa.used_dofs(), self._sb.used_dofs()])
        self.n_equations = 3
        self.equation_labels = ["x", "y", "z"]

    def _terms(self, q: np.ndarray) -> list[_Term]:
        n = self._n
        return [("lin", np.eye(3), self._sa.point(q, n) - self._sb.point(q, n))]


class BeamNodeRigid(_TermConstraint):
    """Rigid connection of a cable node to a body (FORMULATION I §2.3, element A: no twist eq).

    ``r_i − (r_B + A s′) = 0`` (3 eqs, global) and ``(A n₁′)·r′_i = 0``, ``(A n₂′)·r′_i = 0``,
    where ``s′ = body.point`` and n₁′, n₂′ (columns of ``normals_body``, body coordinates, or
    global for ground) are ⟂ the node tangent. The tangential slope component stays free, so
    the cable can stretch at the connection. Use :meth:`from_configuration` to freeze the
    current configuration. Labels ``"x", "y", "z", "slope_n1", "slope_n2"``.
    """

    def __init__(self, name: str, node: Attachment, body: Attachment,
                 normals_body: np.ndarray) -> None:
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
        self._sa = _Side(node, 0, 6)
        self._sb = _Side(body, 6, _n_used(body))
        self._n = 6 + self._sb.n_used
        self._coords = np.concatenate([self._sa.used_dofs(), self._sb.used_dofs()])
        self.n_equations = 5
        self.equation_labels = ["x", "y", "z", "slope_n1", "slope_n2"]

    @classmethod
    def from_configuration(cls, name: str, node: Attachment, body: Attachment,
                           q_node: np.ndarray, q_body: np.ndarray | None = None, *,
                           at_node: bool = True) -> BeamNodeRigid:
        """Connection frozen at the given configuration.

        ``q_node`` = the node's ``[r, r′]``, ``q_body`` = the body's ``[r, p]`` (None for ground).
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
        return cls(name, node, body, normals)

    def _terms(self, q: np.ndarray) -> list[_Term]:
        n, sa, sb = self._n, self._sa, self._sb
        g = sa.slope(q, n)
        return [("lin", np.eye(3), sa.point(q, n) - sb.point(q, n)),
                ("dot", sb.direction(q, n, self.normals_body[:, 0], key=100), g),
                ("dot", sb.direction(q, n, self.normals_body[:, 1], key=101), g)]

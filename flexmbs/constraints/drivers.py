"""Joint drivers (motors): the relative rotation of a revolute joint or the relative slide of a
prismatic joint prescribed as a time function (Haug 1989 §9.4, rotational and translational
drivers; issue "multibody basics").

A driver reads the equations of :func:`~flexmbs.constraints.joints.relative_angle_table`
(``c = cos θ``, ``s = sin θ``, θ the rotation of a's joint frame about b's joint x axis) or
:func:`~flexmbs.constraints.joints.slide_table` (``u``, the slide of a's joint point along b's x
axis) and combines them with weights of the target ``d(t) = d_0 + λ_load f(t)`` (``d_0`` the
value in the reference configuration):

    rotation:  Φ = s cos d − c sin d = ρ sin(θ − d)       (no branch cut: any number of turns)
    slide:     Φ = u − d

so ``Φ = Σ_k w_k(d) φ_k(q) − b(d)``, ``Φ_q = Σ_k w_k ∂φ_k/∂q`` and ``λ ∂²Φ/∂q² = Σ_k (λ w_k)
∂²φ_k/∂q²`` (the joint tables' exact Hessians). At the solution ``∂Φ/∂θ = ∂Φ/∂u = 1``, so the
driving torque (force) that b exerts on a about (along) the joint axis is ``−λ``.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from .._jit import njit
from ..errors import ModelError
from ..terms import LOAD_FACTOR
from .base import Attachment, Constraint
from .joints import (
    TermTable,
    TermWork,
    concatenate_tables,
    relative_angle_table,
    slide_table,
    term_hessian,
    term_values,
    term_work,
)

if TYPE_CHECKING:  # pragma: no cover
    from ..loads import TimeFunction
    from ..terms import DofMap, FunctionTable

__all__ = ["ROTATION", "SLIDE", "DriverPart", "JointDriver", "drivers_jacobian", "drivers_residual",
           "pack_drivers"]

ROTATION, SLIDE = 0, 1
MOTIONS = {"rotation": ROTATION, "slide": SLIDE}


@njit
def driver_weights(motion, target, w):
    """Weights ``w`` of the table's equations and the offset b of ``Φ = Σ w_k φ_k − b``."""
    if motion == ROTATION:
        w[0] = -math.sin(target)
        w[1] = math.cos(target)
        return 0.0
    w[0] = 1.0
    w[1] = 0.0
    return target


@njit
def driver_values(table, e0, e1, motion, target, q_local, phi_k, jac_k, w, jac, work):
    """Φ of one driver (returned) and ``Φ_q`` into ``jac`` (module docstring; ``work``: the term
    kernels' scratch)."""
    term_values(table, e0, e1, q_local, phi_k, jac_k, work)
    b = driver_weights(motion, target, w)
    phi = -b
    for k in range(e1 - e0):
        phi += w[k] * phi_k[k]
    for j in range(jac.size):
        acc = 0.0
        for k in range(e1 - e0):
            acc += w[k] * jac_k[k, j]
        jac[j] = acc
    return phi


@njit
def driver_hessian(table, e0, e1, motion, target, q_local, lam, w, lam_k, H, work):
    """``λ ∂²Φ/∂q²`` of one driver into ``H``."""
    driver_weights(motion, target, w)
    for k in range(e1 - e0):
        lam_k[k] = lam * w[k]
    term_hessian(table, e0, e1, q_local, lam_k[:e1 - e0], H, work)


def _n_used(att: Attachment) -> int:
    return {"rigid_body": 7, "beam_node": 3}.get(att.kind, 0)


class JointDriver(Constraint):
    """A motor on a joint: ``motion = "rotation"`` (about the joint x axis, a relative to b) or
    ``"slide"`` (along it) follows ``d(t) = d_0 + function(t)`` (module docstring); ``d_0`` is
    the value in ``q_ref`` (all coordinates of the assembled configuration). One equation,
    labelled by the motion."""

    def __init__(self, name: str, a: Attachment, b: Attachment, motion: str,
                 function: TimeFunction, q_ref: np.ndarray) -> None:
        if motion not in MOTIONS:
            raise ModelError(f"driver '{name}': motion must be one of {sorted(MOTIONS)} "
                             f"(got {motion!r})")
        self.name = name
        self.motion = MOTIONS[motion]
        self.function = function
        na, nb = _n_used(a), _n_used(b)
        self._n = na + nb
        self._coords = np.concatenate([a.dofs[:na], b.dofs[:nb]]).astype(np.int64)
        self.equations: TermTable = (relative_angle_table(a, b, na) if self.motion == ROTATION
                                     else slide_table(a, b, na))
        self.n_equations = 1
        self.equation_labels = [motion]
        self._w = np.zeros(2)
        self.value0 = self.measure(np.asarray(q_ref, float)[self._coords])

    def coordinates(self) -> np.ndarray:
        return self._coords

    def measure(self, q_local: np.ndarray) -> float:
        """The driven coordinate now: the angle θ (atan2, in (−π, π]) or the slide u."""
        ne = self.equations.eq_kind.size
        phi = np.empty(ne)
        term_values(self.equations, 0, ne, np.ascontiguousarray(q_local, float), phi,
                    np.empty((ne, self._n)), term_work())
        return float(math.atan2(phi[1], phi[0])) if self.motion == ROTATION else float(phi[0])

    def target(self, t: float) -> float:
        return self.value0 + float(self.function(t))

    def evaluate(self, q_local: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
        ne = self.equations.eq_kind.size
        jac = np.empty(self._n)
        phi = driver_values(self.equations, 0, ne, self.motion, self.target(t),
                            np.ascontiguousarray(q_local, float), np.empty(ne),
                            np.empty((ne, self._n)), self._w, jac, term_work())
        return np.array([phi]), jac[None, :]

    def hessian_lambda(self, q_local: np.ndarray, lam: np.ndarray, t: float) -> np.ndarray:
        ne = self.equations.eq_kind.size
        H = np.empty((self._n, self._n))
        driver_hessian(self.equations, 0, ne, self.motion, self.target(t),
                       np.ascontiguousarray(q_local, float), float(np.asarray(lam).reshape(-1)[0]),
                       self._w, np.empty(2), H, term_work())
        return H

    def velocity_rhs(self, q_local: np.ndarray, t: float) -> float:
        """``−Φ_t`` (the right-hand side of ``Φ_q v = −Φ_t``)."""
        d1 = float(self.function.d1(t))
        if self.motion == SLIDE or d1 == 0.0:
            return d1
        ne = self.equations.eq_kind.size
        phi = np.empty(ne)
        term_values(self.equations, 0, ne, np.ascontiguousarray(q_local, float), phi,
                    np.empty((ne, self._n)), term_work())
        d = self.target(t)
        return d1 * (phi[1] * math.sin(d) + phi[0] * math.cos(d))

    def acceleration_rhs(self, q_local: np.ndarray, v_local: np.ndarray, t: float) -> float:
        """``−2 Φ_qt v − Φ_tt`` (the time part of the acceleration-level equation)."""
        d = self.target(t)
        d1, d2 = float(self.function.d1(t)), float(self.function.d2(t))
        if self.motion == SLIDE:
            return d2                                           # Φ_t = −d', Φ_tt = −d''
        ne = self.equations.eq_kind.size
        phi = np.empty(ne)
        jac = np.empty((ne, self._n))
        term_values(self.equations, 0, ne, np.ascontiguousarray(q_local, float), phi, jac,
                    term_work())
        c, s = phi
        dc, ds = jac @ np.asarray(v_local, float)
        # Φ_t = −d'(s sin d + c cos d), Φ_tt = −d''(s sin d + c cos d) − d'^2 Φ
        phi_qt_v = -d1 * (ds * math.sin(d) + dc * math.cos(d))
        phi_tt = -d2 * (s * math.sin(d) + c * math.cos(d)) - d1 * d1 * (s * math.cos(d) - c * math.sin(d))
        return -2.0 * phi_qt_v - phi_tt


# ---------------------------------------------------------------------------------------------
# the term of the assembler (flexmbs.terms)
class DriverPart(NamedTuple):
    table: TermTable
    eq_ptr: np.ndarray               # (nd + 1,) equations of driver d
    coord_ptr: np.ndarray            # (nd + 1,) coordinates of driver d in ``coords``
    coords: np.ndarray
    motion: np.ndarray               # (nd,) ROTATION | SLIDE
    fn: np.ndarray                   # (nd,) index of the time function
    value0: np.ndarray               # (nd,) d_0
    rows: np.ndarray                 # (nd,) multiplier, −1 if dropped
    pos_jac: np.ndarray              # coords entries of each driver's row (coord_ptr)
    pos_jacT: np.ndarray
    hptr: np.ndarray                 # (nd + 1,) into pos_hess
    pos_hess: np.ndarray
    ql: np.ndarray                   # work
    phi_k: np.ndarray
    jac_k: np.ndarray
    jac: np.ndarray
    w: np.ndarray
    lam_k: np.ndarray
    H: np.ndarray
    work: TermWork                   # work of the term kernels


def pack_drivers(drivers: list[JointDriver], dofs: DofMap, functions: FunctionTable) -> DriverPart:
    table, eq_ptr = concatenate_tables([d.equations for d in drivers])
    coords = [d.coordinates() for d in drivers]
    nd = len(drivers)
    i64 = np.int64
    cptr = np.zeros(nd + 1, i64)
    cptr[1:] = np.cumsum([c.size for c in coords])
    hptr = np.zeros(nd + 1, i64)
    hptr[1:] = np.cumsum([c.size ** 2 for c in coords])
    rows = np.array([int(dofs.multiplier_rows(d)[0]) for d in drivers], i64)
    n = dofs.n_coords
    pj, pt, ph = [], [], []
    for c, r in zip(coords, rows, strict=True):
        pj.append(dofs.positions(np.array([n + max(r, 0)]), c) if r >= 0 else np.full(c.size, -1))
        pt.append(dofs.positions(c, np.array([n + max(r, 0)])) if r >= 0 else np.full(c.size, -1))
        ph.append(dofs.positions(c, c))
    nl = max((c.size for c in coords), default=0)
    cat = np.concatenate
    return DriverPart(
        table=table,
        eq_ptr=np.ascontiguousarray(eq_ptr, i64),
        coord_ptr=cptr,
        coords=cat(coords).astype(i64) if coords else np.zeros(0, i64),
        motion=np.array([d.motion for d in drivers], i64),
        fn=np.array([functions(d.function) for d in drivers], i64),
        value0=np.array([d.value0 for d in drivers], float),
        rows=rows,
        pos_jac=cat(pj).astype(i64) if pj else np.zeros(0, i64),
        pos_jacT=cat(pt).astype(i64) if pt else np.zeros(0, i64),
        hptr=hptr,
        pos_hess=cat(ph).astype(i64) if ph else np.zeros(0, i64),
        ql=np.zeros(nl),
        phi_k=np.zeros(2),
        jac_k=np.zeros((2, nl)),
        jac=np.zeros(nl),
        w=np.zeros(2),
        lam_k=np.zeros(2),
        H=np.zeros((nl, nl)),
        work=term_work())


@njit(inline="always")
def _driver(dr, d, q, fv, mode):
    """Φ of driver d (returned with its first coordinate and coordinate count); Φ_q in dr.jac."""
    c0 = dr.coord_ptr[d]
    nloc = dr.coord_ptr[d + 1] - c0
    for k in range(nloc):
        dr.ql[k] = q[dr.coords[c0 + k]]
    target = dr.value0[d] + mode[LOAD_FACTOR] * fv[dr.fn[d]]
    e0, e1 = dr.eq_ptr[d], dr.eq_ptr[d + 1]
    phi = driver_values(dr.table, e0, e1, dr.motion[d], target, dr.ql[:nloc], dr.phi_k,
                        dr.jac_k[:, :nloc], dr.w, dr.jac[:nloc], dr.work)
    return phi, c0, nloc, target


@njit(internal=True)
def drivers_residual(dr, n, q, lam, fv, mode, r):
    """``r_λ = Φ``, ``r_q += Φ_qᵀλ`` of every driver."""
    if dr is None:   # none in the model: compiled to nothing (driver.OPTIONAL_KINDS)
        return
    for d in range(dr.rows.size):
        row = dr.rows[d]
        if row < 0:
            continue
        phi, c0, nloc, _target = _driver(dr, d, q, fv, mode)
        r[n + row] = phi
        for k in range(nloc):
            r[dr.coords[c0 + k]] += dr.jac[k] * lam[row]


@njit(internal=True)
def drivers_jacobian(dr, q, lam, fv, mode, cK, data):
    """Φ_q, Φ_qᵀ and ``cK λ ∂²Φ/∂q²`` of every driver."""
    if dr is None:   # none in the model: compiled to nothing (driver.OPTIONAL_KINDS)
        return
    for d in range(dr.rows.size):
        row = dr.rows[d]
        if row < 0:
            continue
        _phi, c0, nloc, target = _driver(dr, d, q, fv, mode)
        for k in range(nloc):
            data[dr.pos_jac[c0 + k]] += dr.jac[k]
            data[dr.pos_jacT[c0 + k]] += dr.jac[k]
        H = dr.H[:nloc, :nloc]
        driver_hessian(dr.table, dr.eq_ptr[d], dr.eq_ptr[d + 1], dr.motion[d], target,
                       dr.ql[:nloc], lam[row], dr.w, dr.lam_k, H, dr.work)
        h0 = dr.hptr[d]
        for a in range(nloc):
            for k in range(nloc):
                data[dr.pos_hess[h0 + a * nloc + k]] += cK * H[a, k]

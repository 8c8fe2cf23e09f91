"""The constraint equations of a model as multiplier rows: the linear rows (clamps, pins,
prescribed coordinates), the nonlinear constraints (joints, beam-node connections, drivers, the
Euler-parameter normalisation, the interactions' constraints), the redundancy check on their
Jacobian at the initial configuration, and the rows kept."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
import scipy.sparse as sp

from ..constraints.base import Attachment, Constraint
from ..constraints.drivers import JointDriver
from ..constraints.joints import BeamNodeRigid, EulerParameterNormalization, GenericJoint
from ..errors import ModelError, RedundantConstraintError
from ..loads import Constant, TimeFunction
from ..model import Ground, Model, Node, RigidBody
from .numbering import Numbering


@dataclass
class NonlinearRows:
    """The kept equations of one nonlinear constraint."""

    constraint: Constraint
    keep: np.ndarray            # equation indices kept (redundant ones dropped)
    rows: np.ndarray            # multiplier indices of kept equations (len(keep),)

    @property
    def coords(self) -> np.ndarray:
        """(nc,) the global coordinates the constraint depends on now (a sliding joint's follow
        its current element)."""
        return np.asarray(self.constraint.coordinates(), np.int64)


class _LinearRow(NamedTuple):
    cols: np.ndarray
    vals: np.ndarray
    rhs: float                  # the value at the reference configuration
    function: TimeFunction | None
    label: str
    owner: str                  # the constraint (spec name) of the row


class ConstraintRows:
    """The multiplier rows of a model's constraints: ``lam[:m_lin]`` the linear rows
    ``lin_matrix q = lin_rhs0 (f(t))``, then every kept equation of the nonlinear ones."""

    def __init__(self, model: Model, numbering: Numbering, *, redundant_constraints: str,
                 rank_tolerance: float, length_scale: float) -> None:
        self._numbering = numbering
        _check_prescribed_twists(model)
        linear = self._linear_rows(model)
        nonlinear = self._nonlinear_constraints(model, length_scale)
        keep_set, self.dropped_equations = _independent_equations(
            linear, nonlinear, numbering, redundant_constraints, rank_tolerance)
        n = numbering.n_coords

        lin_keep = [eq for i, eq in enumerate(linear) if i in keep_set]
        rows_i, cols_i, vals_i = [], [], []
        for new, kept in enumerate(lin_keep):
            rows_i.extend([new] * len(kept.cols))
            cols_i.extend(kept.cols.tolist())
            vals_i.extend(kept.vals.tolist())
        self.m_lin = len(lin_keep)
        self.lin_matrix = sp.csr_matrix((vals_i, (rows_i, cols_i)), shape=(self.m_lin, n))
        self.lin_matrix_T = self.lin_matrix.T.tocsr()
        self.lin_rhs0 = np.array([kept.rhs for kept in lin_keep], float)
        self.lin_functions: list[tuple[int, TimeFunction]] = [
            (new, fn) for new, kept in enumerate(lin_keep) if (fn := kept.function) is not None]
        labels = [kept.label for kept in lin_keep]
        owners = [kept.owner for kept in lin_keep]

        self.nonlinear: list[NonlinearRows] = []
        row = self.m_lin
        base = len(linear)
        for con in nonlinear:
            keep = np.array([j for j in range(con.n_equations) if base + j in keep_set], np.int64)
            base += con.n_equations
            if keep.size == 0:
                continue
            rows = np.arange(row, row + keep.size)
            row += keep.size
            self.nonlinear.append(NonlinearRows(con, keep, rows))
            labels.extend(f"{type(con).__name__} '{con.name}' equation {con.equation_labels[j]}"
                          for j in keep)
            owners.extend([con.name] * keep.size)
        self.n_mult = row
        self.multiplier_labels = labels
        #: the constraint or joint (by name) that owns each multiplier (reactions)
        self.multiplier_owner = owners
        self._rows_of = {id(nl.constraint): nl for nl in self.nonlinear}
        #: the constraints the interactions own (their term kinds reserve and pack them)
        self.interaction_constraints = {id(c) for obj in model.interactions for c in obj.constraints()}

    # ---------------------------------------------------------------- construction
    def _linear_rows(self, model: Model) -> list[_LinearRow]:
        """Clamps, pins and prescribed coordinates (reference values from ``q_ref``)."""
        q0 = self._numbering.q_ref
        out: list[_LinearRow] = []
        for spec in model.constraints:
            k = spec.kind
            if k in ("clamp", "pin"):
                node: Node = spec.a  # type: ignore[assignment]
                d = self._numbering.node_dofs(node)
                for c in range(3):
                    out.append(_LinearRow(d[c:c + 1], np.ones(1), q0[d[c]], None,
                                          f"{k} '{spec.name}' ({node.name}) position {'xyz'[c]}",
                                          spec.name))
                if k == "clamp":
                    slope = d[list(node.beam.layout.slope)]
                    t = q0[slope] / np.linalg.norm(q0[slope])
                    # two unit normals to the reference tangent: axis-aligned when possible so that
                    # the rows stay coordinate constraints for beams along global axes
                    order = np.argsort(np.abs(t))
                    n1 = np.zeros(3)
                    n1[order[0]] = 1.0
                    n1 -= np.dot(n1, t) * t
                    n1 /= np.linalg.norm(n1)
                    n2 = np.cross(t, n1)
                    for j, normal in enumerate((n1, n2)):
                        nz = np.abs(normal) > 1e-14
                        out.append(_LinearRow(slope[nz], normal[nz], 0.0, None,
                                              f"clamp '{spec.name}' ({node.name}) slope normal {j + 1}",
                                              spec.name))
                    tw = node.beam.layout.twist
                    if tw is not None:      # the section's turn about the tangent (§2.3)
                        out.append(_LinearRow(d[tw:tw + 1], np.ones(1), q0[d[tw]], None,
                                              f"clamp '{spec.name}' ({node.name}) twist", spec.name))
            elif k == "prescribed":
                tgt = spec.a
                d = (self._numbering.node_dofs(tgt) if isinstance(tgt, Node)
                     else self._numbering.body_dofs(tgt))  # type: ignore[arg-type]
                out.extend(_LinearRow(d[c:c + 1], np.ones(1), q0[d[c]], spec.function,
                                      f"prescribed '{spec.name}' component {c}", spec.name)
                           for c in spec.components)
        return out

    def _nonlinear_constraints(self, model: Model, length_scale: float) -> list[Constraint]:
        """Joints, beam-node connections and drivers of the model, the bodies' Euler-parameter
        normalisations, the interactions' constraints (checked at the initial configuration)."""
        numbering = self._numbering
        q0 = numbering.q_ref
        out: list[Constraint] = []
        for spec in model.constraints:
            k = spec.kind
            if k in ("clamp", "pin", "prescribed"):
                continue
            if k == "rigid":
                node: Node = spec.a  # type: ignore[assignment]
                body_att = self._attachment(spec.b, None, None)
                node_att = self._attachment(node, None, None)
                q_body = q0[numbering.body_dofs(spec.b)] if isinstance(spec.b, RigidBody) else None
                et = node.beam.element_type
                node_base = (None if et.node_base is None
                             else et.node_base(numbering.element_dofs(node.beam), q0, node.index))
                out.append(BeamNodeRigid.from_configuration(
                    spec.name, node_att, body_att, q0[node_att.dofs], q_body, base=node_base))
            elif k == "driver":
                a = self._attachment(spec.a, spec.point_a, spec.frame_a)
                b = self._attachment(spec.b, spec.point_b, spec.frame_b)
                assert spec.function is not None  # Model.add_driver sets it
                out.append(JointDriver(spec.name, a, b, spec.motion, spec.function, q0))
            else:  # generic joints and presets
                a = self._attachment(spec.a, spec.point_a, spec.frame_a)
                b = self._attachment(spec.b, spec.point_b, spec.frame_b)
                out.append(GenericJoint(spec.name, a, b, translation=spec.translation,
                                        rotation=spec.rotation))
        for body in model.bodies:
            out.append(EulerParameterNormalization(f"{body.name}.normalization",
                                                   numbering.body_dofs(body)))
        for obj in model.interactions:
            for con in obj.constraints():
                phi, _ = con.evaluate(q0[con.coordinates()], 0.0)
                if np.abs(phi).max(initial=0.0) > 1e-6 * max(length_scale, 1e-3):
                    raise ModelError(
                        f"joint '{obj.name}' is violated by {np.abs(phi).max():.3g} in the initial "
                        "configuration: place the body on the beam (e.g. pose = beam.frame_at(s), "
                        "scenario pose = {on_beam, s}) with its hole axis along the tangent")
                out.append(con)
        return out

    def _attachment(self, obj: object, point: np.ndarray | None, frame: np.ndarray | None) -> Attachment:
        if isinstance(obj, RigidBody):
            return Attachment.rigid_body(self._numbering.body_dofs(obj),
                                         np.zeros(3) if point is None else point, frame)
        if isinstance(obj, Node):
            d = self._numbering.node_dofs(obj)
            lay = obj.beam.layout
            cols = [*lay.position, *lay.slope] + ([] if lay.twist is None else [lay.twist])
            return Attachment.beam_node(d[cols], twist=lay.twist is not None)
        if isinstance(obj, Ground):
            return Attachment.ground(point if point is not None else np.zeros(3),
                                     frame if frame is not None else np.eye(3))
        raise ModelError(f"cannot attach a constraint to {obj!r}")

    # ---------------------------------------------------------------- queries
    def multiplier_rows(self, constraint: object) -> np.ndarray:
        """Multiplier indices (into lam) of the equations of ``constraint``, −1 if dropped."""
        nl = self._rows_of.get(id(constraint))
        if nl is None:
            return np.full(getattr(constraint, "n_equations", 0), -1, np.int64)
        out = np.full(nl.constraint.n_equations, -1, np.int64)
        out[nl.keep] = nl.rows
        return out

    def velocity_terms(self, q: np.ndarray, t: float) -> np.ndarray:
        """Right-hand side ``−Phi_t`` of the velocity-level constraints ``Phi_q v = −Phi_t``
        (nonzero only for prescribed motion and drivers)."""
        out = np.zeros(self.n_mult)
        for row, fn in self.lin_functions:
            out[row] += fn.d1(t)
        for nl in self.nonlinear:
            if isinstance(nl.constraint, JointDriver):
                out[nl.rows] += nl.constraint.velocity_rhs(q[nl.coords], t)
        return out

    def drift(self, q: np.ndarray, v: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
        """``(Phi, dPhi/dt = Phi_q v + Phi_t)`` of every kept equation at ``(q, v, t)``, from the
        constraints' own functions (no kernel is run: the steps' state stays as it is)."""
        phi = np.zeros(self.n_mult)
        rate = -self.velocity_terms(q, t)                      # Phi_t
        if self.m_lin:
            phi[:self.m_lin] = self.lin_matrix @ q - self.lin_rhs0
            rate[:self.m_lin] += self.lin_matrix @ v
            for row, fn in self.lin_functions:
                phi[row] -= fn(t)
        for nl in self.nonlinear:
            coords = nl.coords
            values, jac = nl.constraint.evaluate(q[coords], t)
            phi[nl.rows] = values[nl.keep]
            rate[nl.rows] += (jac @ v[coords])[nl.keep]
        return phi, rate

    def velocity_rows(self) -> np.ndarray:
        """(n_mult,) 1.0 for the equations whose velocity form is ``Phi_q v = 0`` (no time in
        Phi), 0.0 for prescribed coordinates with a time function and drivers (``Phi_t != 0``,
        which the velocity corrector leaves as they are)."""
        out = np.ones(self.n_mult)
        for row, _ in self.lin_functions:
            out[row] = 0.0
        for nl in self.nonlinear:
            if isinstance(nl.constraint, JointDriver):
                out[nl.rows] = 0.0
        return out


def _check_prescribed_twists(model: Model) -> None:
    """A rod node's twist is prescribed only with its slope held (clamped, or its three
    slope components prescribed without motion): the twist is the section's turn relative
    to the node's chart, which is re-based when the tangent turns far (docs/theory.md §I.2.4),
    and a prescribed value cannot follow that."""
    held: set[tuple[int, int, int]] = set()
    turned: list[Any] = []
    for spec in model.constraints:
        node = spec.a
        if not isinstance(node, Node):
            continue
        key = (id(node.beam), node.index)
        if spec.kind == "clamp":
            held.update((*key, c) for c in node.beam.layout.slope)
        elif spec.kind == "prescribed":
            if node.beam.layout.twist in spec.components:
                turned.append(spec)
            fn = spec.function
            if isinstance(fn, Constant) and fn.value == 0.0:
                held.update((*key, c) for c in spec.components)
    for spec in turned:
        node = spec.a
        if not all((id(node.beam), node.index, c) in held for c in node.beam.layout.slope):
            raise ModelError(
                f"prescribed '{spec.name}': the twist of node {node.index} of beam "
                f"'{node.beam.name}' is prescribed but its slope is free; hold the slope "
                "too (prescribe components 3, 4, 5 without a function, or clamp the node)")


def _independent_equations(linear: list[_LinearRow], nonlinear: list[Constraint], numbering: Numbering,
                           policy: str, rank_tol: float) -> tuple[set[int], list[str]]:
    """The equations (linear rows, then every nonlinear constraint's) kept after the
    redundancy check on the full Jacobian at the initial configuration (pivoted QR), and the
    labels of those dropped; raises :class:`RedundantConstraintError` for redundant ones
    under ``policy="error"``."""
    q0 = numbering.q_ref
    m_lin = len(linear)
    labels = [row.label for row in linear]
    J = np.zeros((m_lin + sum(con.n_equations for con in nonlinear), numbering.n_coords))
    for i, row in enumerate(linear):
        J[i, row.cols] = row.vals
    r = m_lin
    for con in nonlinear:
        idx = con.coordinates()
        _, jac = con.evaluate(q0[idx], 0.0)
        J[r:r + con.n_equations][:, idx] = jac
        labels.extend(f"{type(con).__name__} '{con.name}' equation {lab}" for lab in con.equation_labels)
        r += con.n_equations
    keep_rows = np.arange(J.shape[0])
    if J.shape[0] > 0:
        norms = np.linalg.norm(J, axis=1)
        zero = norms == 0
        if np.any(zero):
            raise ModelError("constraint equations with an all-zero Jacobian at the initial "
                             f"configuration: {[labels[i] for i in np.flatnonzero(zero)]}")
        Jn = J / norms[:, None]
        import scipy.linalg  # here: its import costs 0.2 s of every start-up

        _, R, perm = scipy.linalg.qr(Jn.T, mode="economic", pivoting=True)
        diag = np.abs(np.diag(R))
        rank = int(np.sum(diag > rank_tol * max(diag[0], 1e-300)))
        if rank < J.shape[0]:
            dependent = np.sort(perm[rank:])
            names = [labels[i] for i in dependent]
            if policy == "error":
                raise RedundantConstraintError(
                    f"{len(dependent)} redundant constraint equation(s) (closed loop or double "
                    f"fixation): {names}. Remove them from the model, or pass "
                    "redundant_constraints='drop' to drop them with a warning.")
            import warnings

            # stacklevel: the caller of Assembly(...)
            warnings.warn(f"dropping {len(dependent)} redundant constraint equation(s): {names}",
                          stacklevel=4)
            keep_rows = np.sort(perm[:rank])
    dropped = [labels[i] for i in sorted(set(range(J.shape[0])) - set(keep_rows))]
    return {int(i) for i in keep_rows}, dropped

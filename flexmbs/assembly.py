"""Global assembly: DOF map, residual, sparse iteration matrix (pattern built once), energies.

Unknowns: coordinates ``q`` (beams: per node the coordinates of its element layout, for the
cable [r, r']; rigid bodies: [r, p], 7 each) and Lagrange multipliers ``lam`` (one per
constraint equation). The dynamic residual follows the convention of FORMULATION §0::

    r_q   = M(q) q'' + Q_int(q, q') + Phi_q^T lam - Q_ext(q, t)
    r_lam = Phi(q, t)

The iteration matrix ``[[cM M + cC C + cK K, Phi_q^T], [Phi_q, 0]]`` (``K`` includes the
constraint Hessian contracted with ``lam``) is stored in CSC form with a fixed pattern; every
refill writes ``data`` in place through precomputed position maps.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp

from . import driver
from .constraints.base import Attachment, Constraint
from .constraints.drivers import JointDriver, pack_drivers
from .constraints.joints import (
    BeamNodeRigid,
    EulerParameterNormalization,
    GenericJoint,
    joint_pattern,
    pack_norms,
    pack_terms,
)
from .constraints.linear import linear_pattern, pack_linear
from .elements import rigid_body as rb
from .elements.group import MAX_GROUPS
from .elements.layout import BASE_RECORD, ELEMENT_TYPES, ElementType
from .errors import FlexmbsError, ModelError, RedundantConstraintError
from .kernel import OP_JACOBIAN, OP_POST_STEP, OP_REBASE, OP_RESIDUAL, OP_SET_BASES, kernel, prepare
from .loads import Constant, TimeFunction, moments_pattern, pack_loads
from .model import Beam, Ground, Model, Node, RigidBody
from .solvers._compiled import idle_run
from .springs import pack_springs, spring_energy, springs_pattern
from .terms import FunctionTable, dynamic_mode, static_mode


@dataclass
class BeamGroup:
    """Beams sharing an element type and its options: one packed part, one kernel call."""

    element_type: ElementType
    options: Any                     # the element's options (CableOptions for the cable)
    beams: list[Beam]
    part: Any                        # the element's packed part (flexmbs.elements.group)

    @property
    def dofs(self) -> np.ndarray:
        return np.asarray(self.part.dofs)

    @property
    def props(self) -> Any:
        return self.part.props

    @property
    def rest(self) -> Any:
        return self.part.rest

    @property
    def mass(self) -> np.ndarray:
        return self.part.mass


@dataclass
class _NonlinearRows:
    constraint: Constraint
    coords: np.ndarray          # (nc,) global coordinate indices
    keep: np.ndarray            # equation indices kept (redundant ones dropped)
    rows: np.ndarray            # multiplier indices of kept equations (len(keep),)


#: the term kinds of interactions: (pattern, packer) of the owning module


class Assembly:
    """Numbering and global evaluation of a :class:`~flexmbs.model.Model`."""

    def __init__(self, model: Model, *, redundant_constraints: str = "error",
                 rank_tolerance: float = 1e-9) -> None:
        if redundant_constraints not in ("error", "drop"):
            raise ModelError("redundant_constraints must be 'error' or 'drop'")
        self.model = model
        self._number_coordinates()
        self._group_specs = self._beam_groups()
        self._build_constraints(redundant_constraints, rank_tolerance)
        self._build_loads()
        self._build_pattern()
        self._pack()
        self.length_scale = self._length_scale()
        self.stiffness_scale = 0.0
        self._idle_run = idle_run()
        self._kernel_ready = False
        self._plans: dict[bool, Any] = {}
        n, m = self.n_coords, self.n_mult
        self.evaluate(self.q_ref, np.zeros(n), None, np.zeros(m), 0.0, np.zeros(n), np.zeros(m),
                      matrix=(0.0, 0.0, 1.0), with_damping=False)

    # ================================================================== numbering
    def _number_coordinates(self) -> None:
        m = self.model
        off = 0
        self.beam_offset: dict[int, int] = {}
        labels: list[tuple[str, str]] = []
        for beam in m.beams:
            self.beam_offset[id(beam)] = off
            comp = beam.layout.node_coordinates
            for i in range(beam.n_nodes):
                labels.extend((f"beam '{beam.name}' node {i}", c) for c in comp)
            off += len(comp) * beam.n_nodes
        self.body_offset: dict[int, int] = {}
        for body in m.bodies:
            self.body_offset[id(body)] = off
            labels.extend((f"body '{body.name}'", c) for c in ("x", "y", "z", "e0", "e1", "e2", "e3"))
            off += 7
        self._extra_dofs: dict[int, np.ndarray] = {}
        for obj in m.interactions:
            names = obj.extra_labels()
            self._extra_dofs[id(obj)] = np.arange(off, off + len(names), dtype=np.int64)
            labels.extend((f"joint '{obj.name}'", c) for c in names)
            off += len(names)
        self.n_coords = off
        if off == 0:
            raise ModelError("the model is empty: add a beam (add_beam) or a rigid body "
                             "(add_rigid_body) before solving")
        self._coord_labels = labels
        q0 = np.zeros(off)
        v0 = np.zeros(off)
        for beam in m.beams:
            o = self.beam_offset[id(beam)]
            nodal = beam.element_type.reference_nodal_coordinates(beam.centerline.points,
                                                                  beam.centerline.tangents)
            q0[o:o + nodal.size] = nodal.ravel()
        for body in m.bodies:
            o = self.body_offset[id(body)]
            p = body.pose.quaternion
            q0[o:o + 3] = body.pose.position
            q0[o + 3:o + 7] = p
            v0[o:o + 3] = body.velocity
            v0[o + 3:o + 7] = rb.pdot_from_omega_global(p, body.angular_velocity)
        for obj in m.interactions:
            d = self._extra_dofs[id(obj)]
            obj.bind(self, d)
            q0[d] = obj.initial_extra(q0)
        self.q_ref = q0
        self.v_init = v0

    def node_dofs(self, node: Node) -> np.ndarray:
        k = node.beam.layout.node_size
        o = self.beam_offset[id(node.beam)] + k * node.index
        return np.arange(o, o + k)

    def body_dofs(self, body: RigidBody) -> np.ndarray:
        o = self.body_offset[id(body)]
        return np.arange(o, o + 7)

    def beam_dofs(self, beam: Beam) -> np.ndarray:
        o = self.beam_offset[id(beam)]
        return np.arange(o, o + beam.layout.node_size * beam.n_nodes)

    def element_dofs(self, beam: Beam) -> np.ndarray:
        o = self.beam_offset[id(beam)]
        conn = beam.connectivity
        lay = beam.layout
        k = lay.node_size
        return (o + k * conn[:, :, None] + np.arange(k)[None, None, :]).reshape(-1, lay.element_size)

    def centerline_dofs(self, beam: Beam) -> np.ndarray:
        """(n_elem, 12) coordinates of the Hermite centreline ``[r0, r0′, r1, r1′]`` of every
        element (what the centreline interpolation reads, whatever the element)."""
        return self.element_dofs(beam)[:, beam.layout.centerline]

    def beam_rest(self, beam: Beam, elements: np.ndarray | None = None) -> tuple[ElementType, Any, Any]:
        """(its element type, the rest data of the beam's ``elements`` (default all, in order)
        taken from its group's, the group's options): what the element's ``output_fields``
        reads."""
        gi, sl = self.beam_slices[id(beam)]
        grp = self.groups[gi]
        idx = np.arange(sl.start, sl.stop) if elements is None else sl.start + np.asarray(elements)
        n_grp = int(grp.dofs.shape[0])
        shared = grp.element_type.shared_rest_fields
        rest = grp.rest
        sliced = {f: (v[idx] if isinstance(v, np.ndarray) and v.ndim >= 1 and v.shape[0] == n_grp
                      and f not in shared else v)
                  for f, v in rest._asdict().items()}
        return grp.element_type, type(rest)(**sliced), grp.options

    def extra_dofs(self, owner: object) -> np.ndarray:
        return self._extra_dofs[id(owner)]

    def describe_coordinate(self, i: int) -> str:
        if i < self.n_coords:
            obj, c = self._coord_labels[i]
            return f"{obj}, coordinate {c}"
        j = i - self.n_coords
        return self.multiplier_labels[j] if j < len(self.multiplier_labels) else f"equation {i}"

    # ================================================================== beams
    def _beam_groups(self) -> list[tuple[ElementType, Any, list[Beam], np.ndarray, Any]]:
        """(element type, options, beams, element dofs, section properties per element) per
        group of beams sharing an element type and its options: one kernel call each."""
        groups: dict[tuple[str, Any], list[Beam]] = {}
        for beam in self.model.beams:
            groups.setdefault((beam.element, beam.options), []).append(beam)
        out = []
        self.beam_slices: dict[int, tuple[int, slice]] = {}
        for gi, ((_, opts), beams) in enumerate(groups.items()):
            etype = beams[0].element_type
            start = 0
            for beam in beams:
                self.beam_slices[id(beam)] = (gi, slice(start, start + beam.n_elem))
                start += beam.n_elem
            dofs = np.vstack([self.element_dofs(beam) for beam in beams])
            out.append((etype, opts, beams, np.ascontiguousarray(dofs, dtype=np.int64),
                        etype.section_properties(beams)))
        return out

    # ================================================================== constraints
    def _attachment(self, obj: object, point: np.ndarray | None, frame: np.ndarray | None) -> Attachment:
        if isinstance(obj, RigidBody):
            return Attachment.rigid_body(self.body_dofs(obj),
                                         np.zeros(3) if point is None else point, frame)
        if isinstance(obj, Node):
            d = self.node_dofs(obj)
            lay = obj.beam.layout
            cols = [*lay.position, *lay.slope] + ([] if lay.twist is None else [lay.twist])
            return Attachment.beam_node(d[cols], twist=lay.twist is not None)
        if isinstance(obj, Ground):
            return Attachment.ground(point if point is not None else np.zeros(3),
                                     frame if frame is not None else np.eye(3))
        raise ModelError(f"cannot attach a constraint to {obj!r}")

    def _check_prescribed_twists(self) -> None:
        """A rod node's twist is prescribed only with its slope held (clamped, or its three
        slope components prescribed without motion): the twist is the section's turn relative
        to the node's chart, which is re-based when the tangent turns far (FORMULATION §2.4),
        and a prescribed value cannot follow that."""
        held: set[tuple[int, int, int]] = set()
        turned: list[Any] = []
        for spec in self.model.constraints:
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

    def _build_constraints(self, policy: str, rank_tol: float) -> None:
        lin_rows: list[tuple[np.ndarray, np.ndarray]] = []   # (cols, vals) per row
        lin_rhs: list[float] = []
        lin_fun: list[TimeFunction | None] = []
        lin_labels: list[str] = []
        lin_owner: list[str] = []       # the constraint (spec name) of each linear row
        nonlinear: list[Constraint] = []
        q0 = self.q_ref
        self._check_prescribed_twists()
        for spec in self.model.constraints:
            k = spec.kind
            if k in ("clamp", "pin"):
                node: Node = spec.a  # type: ignore[assignment]
                d = self.node_dofs(node)
                for c in range(3):
                    lin_rows.append((d[c:c + 1], np.ones(1)))
                    lin_rhs.append(q0[d[c]])
                    lin_fun.append(None)
                    lin_labels.append(f"{k} '{spec.name}' ({node.name}) position {'xyz'[c]}")
                    lin_owner.append(spec.name)
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
                        lin_rows.append((slope[nz], normal[nz]))
                        lin_rhs.append(0.0)
                        lin_fun.append(None)
                        lin_labels.append(f"clamp '{spec.name}' ({node.name}) slope normal {j + 1}")
                        lin_owner.append(spec.name)
                    tw = node.beam.layout.twist
                    if tw is not None:      # the section's turn about the tangent (§2.3)
                        lin_rows.append((d[tw:tw + 1], np.ones(1)))
                        lin_rhs.append(q0[d[tw]])
                        lin_fun.append(None)
                        lin_labels.append(f"clamp '{spec.name}' ({node.name}) twist")
                        lin_owner.append(spec.name)
            elif k == "prescribed":
                tgt = spec.a
                d = self.node_dofs(tgt) if isinstance(tgt, Node) else self.body_dofs(tgt)  # type: ignore[arg-type]
                for c in spec.components:
                    lin_rows.append((d[c:c + 1], np.ones(1)))
                    lin_rhs.append(q0[d[c]])
                    lin_fun.append(spec.function)
                    lin_labels.append(f"prescribed '{spec.name}' component {c}")
                    lin_owner.append(spec.name)
            elif k == "rigid":
                node = spec.a  # type: ignore[assignment]
                body_att = self._attachment(spec.b, None, None)
                node_att = self._attachment(node, None, None)
                q_body = q0[self.body_dofs(spec.b)] if isinstance(spec.b, RigidBody) else None
                et = node.beam.element_type
                node_base = (None if et.node_base is None
                             else et.node_base(self.element_dofs(node.beam), q0, node.index))
                nonlinear.append(BeamNodeRigid.from_configuration(
                    spec.name, node_att, body_att, q0[node_att.dofs], q_body, base=node_base))
            elif k == "driver":
                a = self._attachment(spec.a, spec.point_a, spec.frame_a)
                b = self._attachment(spec.b, spec.point_b, spec.frame_b)
                assert spec.function is not None  # Model.add_driver sets it
                nonlinear.append(JointDriver(spec.name, a, b, spec.motion, spec.function, q0))
            else:  # generic joints and presets
                a = self._attachment(spec.a, spec.point_a, spec.frame_a)
                b = self._attachment(spec.b, spec.point_b, spec.frame_b)
                nonlinear.append(GenericJoint(spec.name, a, b, translation=spec.translation,
                                              rotation=spec.rotation))
        for body in self.model.bodies:
            nonlinear.append(EulerParameterNormalization(f"{body.name}.normalization",
                                                         self.body_dofs(body)))
        for obj in self.model.interactions:
            for con in obj.constraints():
                phi, _ = con.evaluate(q0[con.coordinates()], 0.0)
                if np.abs(phi).max(initial=0.0) > 1e-6 * max(self._length_scale(), 1e-3):
                    raise ModelError(
                        f"joint '{obj.name}' is violated by {np.abs(phi).max():.3g} in the initial "
                        "configuration: place the body on the beam (e.g. pose = beam.frame_at(s), "
                        "scenario pose = {on_beam, s}) with its hole axis along the tangent")
                nonlinear.append(con)

        # ---- redundancy check on the full Jacobian at the initial configuration
        n = self.n_coords
        m_lin = len(lin_rows)
        labels = list(lin_labels)
        J = np.zeros((m_lin + sum(con.n_equations for con in nonlinear), n))
        for i, (cols, vals) in enumerate(lin_rows):
            J[i, cols] = vals
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

                warnings.warn(f"dropping {len(dependent)} redundant constraint equation(s): {names}",
                              stacklevel=3)
                keep_rows = np.sort(perm[:rank])
        self.dropped_equations = [labels[i] for i in sorted(set(range(J.shape[0])) - set(keep_rows))]
        keep_set = {int(i) for i in keep_rows}

        # ---- linear rows kept
        lin_keep = [i for i in range(m_lin) if i in keep_set]
        rows_i, cols_i, vals_i = [], [], []
        for new, i in enumerate(lin_keep):
            cols, vals = lin_rows[i]
            rows_i.extend([new] * len(cols))
            cols_i.extend(cols.tolist())
            vals_i.extend(vals.tolist())
        self.m_lin = len(lin_keep)
        self.lin_matrix = sp.csr_matrix((vals_i, (rows_i, cols_i)), shape=(self.m_lin, n))
        self.lin_matrix_T = self.lin_matrix.T.tocsr()
        self.lin_rhs0 = np.array([lin_rhs[i] for i in lin_keep], float)
        self.lin_functions: list[tuple[int, TimeFunction]] = [
            (new, fn) for new, i in enumerate(lin_keep) if (fn := lin_fun[i]) is not None]
        self._lin_coo = (np.array(rows_i, np.int64), np.array(cols_i, np.int64), np.array(vals_i, float))
        multiplier_labels = [lin_labels[i] for i in lin_keep]
        owners = [lin_owner[i] for i in lin_keep]

        # ---- nonlinear rows kept
        self.nonlinear: list[_NonlinearRows] = []
        row = self.m_lin
        base = m_lin
        for con in nonlinear:
            keep = np.array([j for j in range(con.n_equations) if base + j in keep_set], np.int64)
            base += con.n_equations
            if keep.size == 0:
                continue
            rows = np.arange(row, row + keep.size)
            row += keep.size
            self.nonlinear.append(_NonlinearRows(con, np.asarray(con.coordinates(), np.int64), keep, rows))
            multiplier_labels.extend(f"{type(con).__name__} '{con.name}' equation {con.equation_labels[j]}"
                                     for j in keep)
            owners.extend([con.name] * keep.size)
        self.n_mult = row
        self.multiplier_labels = multiplier_labels
        #: the constraint or joint (by name) that owns each multiplier (reactions)
        self.multiplier_owner = owners
        self.n_total = self.n_coords + self.n_mult
        self._rows_of = {id(nl.constraint): nl for nl in self.nonlinear}
        self._interaction_constraints = {id(c) for obj in self.model.interactions
                                         for c in obj.constraints()}

    # ================================================================== loads
    def _build_loads(self) -> None:
        n = self.n_coords
        g = self.model.gravity
        f_const = np.zeros(n)
        self.gravity_vector = np.zeros(n)
        for etype, _, _, gdofs, gprops in self._group_specs:
            np.add.at(self.gravity_vector, gdofs, etype.gravity_force(gprops, g))
        for body in self.model.bodies:
            d = self.body_dofs(body)
            self.gravity_vector[d[:3]] += body.mass * g
        f_const += self.gravity_vector
        timed: list[tuple[np.ndarray, np.ndarray, TimeFunction]] = []
        body_loads: list[tuple[RigidBody, np.ndarray | None, np.ndarray, np.ndarray | None,
                               TimeFunction]] = []
        moments: list[tuple[np.ndarray, int, np.ndarray, np.ndarray, TimeFunction]] = []
        for load in self.model.loads:
            idx: np.ndarray
            vals: np.ndarray
            if load.kind == "distributed":
                beam: Beam = load.target  # type: ignore[assignment]
                gi, sl = self.beam_slices[id(beam)]
                etype, _, _, gdofs, gprops = self._group_specs[gi]
                props = type(gprops)(*[np.asarray(a)[sl] for a in gprops])
                Q = etype.distributed_force(props, load.force)
                idx, vals = gdofs[sl].ravel(), Q.ravel()
            elif isinstance(load.target, RigidBody):
                body_loads.append((load.target, load.point, load.force, load.moment,
                                   load.function))
                continue
            else:
                if isinstance(load.target, Node):
                    node = load.target
                    beam, s = node.beam, None
                else:
                    beam, s = load.target  # type: ignore[misc]
                if s is None:
                    d = self.node_dofs(node)
                    lay = node.beam.layout
                    idx, vals = d[list(lay.position)], load.force.copy()
                    if load.moment is not None:
                        # a moment on a node works through its current slope (and twist):
                        # loads.node_moment (FORMULATION §1.2, §2.3); the base tangent t̄ of
                        # the twist is the node's reference tangent
                        slope = d[list(lay.slope)]
                        t = self.q_ref[slope] / np.linalg.norm(self.q_ref[slope])
                        moments.append((slope, -1 if lay.twist is None else d[lay.twist],
                                        load.moment, t, load.function))
                else:
                    e, xi = beam.locate(float(s))
                    dofs = self.element_dofs(beam)[e]
                    L = np.array([beam.centerline.lengths[e]])
                    Q = beam.element_type.point_force(np.array([xi]), L, load.force[None, :])[0]
                    if load.moment is not None:
                        raise ModelError(f"load '{load.name}': moments are supported at nodes only")
                    idx, vals = dofs, Q
            fn = load.function
            if isinstance(fn, Constant) and fn.value == 1.0:
                np.add.at(f_const, idx, vals)
            else:
                timed.append((idx, vals, fn))
        self.f_const = f_const
        self.f_timed = timed
        self.body_loads = body_loads
        self.node_moments = moments

    # ================================================================== pattern and packing
    def _interactions_of(self, kind: str) -> list[Any]:
        return [obj for obj in self.model.interactions if obj.term_kind == kind]

    def _build_pattern(self) -> None:
        """CSC pattern: the union of the blocks every term kind reserves (built once)."""
        N = self.n_total
        n = self.n_coords
        blocks: list[tuple[np.ndarray, np.ndarray]] = []
        for *_, gdofs, _ in self._group_specs:
            blocks += [(d, d) for d in gdofs]        # the block of every element
        blocks += rb.bodies_pattern(self.model.bodies, self)
        blocks += linear_pattern(self.lin_matrix, n)
        for nl in self.nonlinear:
            if id(nl.constraint) in self._interaction_constraints:
                continue
            blocks += joint_pattern(nl.coords, self.multiplier_rows(nl.constraint), n, nl.constraint)
        for kind in driver.INTERACTION_KINDS:
            for obj in self._interactions_of(kind.name):
                blocks += kind.pattern(obj, self)
        blocks += springs_pattern(self.model.springs, self)
        blocks += moments_pattern(self.node_moments)
        keys = [np.arange(N, dtype=np.int64) * (N + 1)]   # the full diagonal
        for rows, cols in blocks:
            r = np.asarray(rows, np.int64)
            c = np.asarray(cols, np.int64)
            keys.append((c[None, :] * N + r[:, None]).ravel())
        ukeys = np.unique(np.concatenate(keys))
        self._ukeys = ukeys
        cols = ukeys // N
        rows = ukeys % N
        indptr = np.zeros(N + 1, np.int64)
        np.add.at(indptr, cols + 1, 1)
        indptr = np.cumsum(indptr)
        self.matrix = sp.csc_matrix((np.zeros(ukeys.size), rows.astype(np.int32),
                                     indptr.astype(np.int32)), shape=(N, N))
        self._data = self.matrix.data  # the array the matrix really holds
        self.nnz = ukeys.size

    def _pack(self) -> None:
        """Every term kind packs itself (:mod:`flexmbs.terms`) into the system the driver sums."""
        fns = FunctionTable()
        self.functions = fns
        self.groups: list[BeamGroup] = []
        for etype, opts, beams, gdofs, props in self._group_specs:
            pos = np.array([self.positions(d, d).reshape(-1) for d in gdofs], np.int64)
            self.groups.append(BeamGroup(etype, opts, beams,
                                         etype.pack(gdofs, props, opts, self.q_ref, pos)))
        # the parts in registration order: the default element (the first registered, the
        # cable) always has one (empty if the model has none of its elements), the others only
        # when used: a cable-only model compiles no rod code (measured: its first run 177 s ->
        # 116 s cold), and a model with rods compiles one signature, with or without cables
        parts = []
        for k, name in enumerate(ELEMENT_TYPES):
            et = ELEMENT_TYPES.get(name)
            mine = [g.part for g in self.groups if g.element_type is et]
            if not mine and k > 0:
                continue
            if not mine:
                size = et.layout.element_size
                mine = [et.pack(np.zeros((0, size), np.int64), et.section_properties([]),
                                et.default_options, self.q_ref, np.zeros((0, size * size), np.int64))]
            parts += mine
        if len(parts) > MAX_GROUPS:
            raise ModelError(f"{len(parts)} groups of beams (element type and options): at most "
                             f"{MAX_GROUPS}; give beams of one element type the same options")
        norms = [nl.constraint for nl in self.nonlinear
                 if isinstance(nl.constraint, EulerParameterNormalization)]
        terms = [nl.constraint for nl in self.nonlinear if hasattr(nl.constraint, "table")]
        drivers = [nl.constraint for nl in self.nonlinear if isinstance(nl.constraint, JointDriver)]
        self.joint_lists = {k.name: self._interactions_of(k.name) for k in driver.INTERACTION_KINDS}
        fn_rows = [row for row, _ in self.lin_functions]
        fn_idx = [fns(fn) for _, fn in self.lin_functions]
        bodies = rb.pack_bodies(self.model.bodies, self.body_loads, self, fns)
        loads = pack_loads(self.f_const, self.f_timed, self.node_moments, fns, self)
        linear = pack_linear(self.lin_matrix, self.lin_rhs0, fn_rows, fn_idx, self)
        norms_part, terms_part = pack_norms(norms, self), pack_terms(terms, self)
        kinds = {k.name: k.pack(self.joint_lists[k.name], self) for k in driver.INTERACTION_KINDS}
        self.system = driver.SystemPart(
            n=self.n_coords, m=self.n_mult, beams=tuple(parts), bodies=bodies, loads=loads,
            linear=linear, norms=norms_part, terms=terms_part, **kinds,
            springs=pack_springs(self.model.springs, self),
            drivers=pack_drivers(drivers, self, fns),
            error=np.zeros(3, np.int64),
            bases=np.zeros((sum(2 * g.dofs.shape[0] for g in self.groups
                                if g.element_type.rebase is not None), BASE_RECORD)))
        #: what the compiled kernel receives: the kinds this model lacks are None, so that
        #: their code is not compiled for it (driver.OPTIONAL_KINDS)
        self.kernel_system = self.system.without_absent(dict(
            bodies=bool(self.model.bodies), norms=bool(norms), terms=bool(terms),
            springs=bool(self.model.springs), drivers=bool(drivers),
            **{k: bool(objs) for k, objs in self.joint_lists.items()}))
        self._python_terms = [obj for obj in self.model.interactions if obj.term_kind == ""]
        self.body_dof_table = self.system.bodies.dofs
        self._r = np.zeros(self.n_total)

    def _length_scale(self) -> float:
        pts = [b.centerline.points for b in self.model.beams] + [
            b.pose.position[None, :] for b in self.model.bodies]
        if not pts:
            return 1.0
        P = np.vstack(pts)
        ext = float(np.linalg.norm(P.max(axis=0) - P.min(axis=0)))
        lengths = [b.length for b in self.model.beams]
        return max(ext, max(lengths, default=0.0), 1e-3 if ext == 0 else 0.0) or 1.0

    # ================================================================== evaluation
    def initial_state(self) -> tuple[np.ndarray, np.ndarray]:
        return self.q_ref.copy(), self.v_init.copy()

    def python_interactions(self) -> list[Any]:
        """Interactions evaluated by their Python path now: those of no compiled kind, and
        those of a switchable kind without a compiled form at the moment
        (:meth:`Interaction.compiled_form`). A query: :meth:`_switch_compiled_forms` acts on
        it."""
        out = list(self._python_terms)
        for kind in driver.INTERACTION_KINDS:
            if kind.enable is not None:
                out += [obj for obj in self.joint_lists[kind.name] if not obj.compiled_form()]
        return out

    def _switch_compiled_forms(self) -> list[Any]:
        """Switch every interaction of a switchable kind on or off in the packed system as it
        has a compiled form now (a test may freeze a joint's detection between two calls);
        returns :meth:`python_interactions`. Every evaluation starts with it."""
        for kind in driver.INTERACTION_KINDS:
            if kind.enable is not None:
                part = getattr(self.system, kind.name)
                for i, obj in enumerate(self.joint_lists[kind.name]):
                    kind.enable(part, i, obj.compiled_form())
        return self.python_interactions()

    def compiled_reason(self) -> str:
        """Why the compiled Newton loop cannot run this model now ("" if it can)."""
        for obj in self.python_interactions():
            return (f"joint '{obj.name}' has no compiled form now ({obj!r}: superellipse bore, "
                    "frozen detection or the consistent contact tangent); the Python Newton loop "
                    "evaluates it")
        return ""

    def error_exception(self, code: int, q: np.ndarray, t: float) -> FlexmbsError:
        """The exception of an error code of the driver (names the joint)."""
        err = self.system.error
        kind = driver.KIND_OF_ERROR.get(int(code))
        if kind is None:
            part = self.system.beams[int(err[1])]
            group = next((gi for gi, g in enumerate(self.groups) if g.part is part), None)
            message = (None if group is None
                       else self.groups[group].element_type.post_step_message)
            if group is None or message is None:
                return FlexmbsError(f"internal error code {code}")
            element, slot = divmod(int(err[2]), 2)
            for beam in self.groups[group].beams:
                gi, sl = self.beam_slices[id(beam)]
                if sl.start <= element < sl.stop:
                    node = int(beam.connectivity[element - sl.start, slot])
                    return FlexmbsError(message(beam, node, q))
            return FlexmbsError(f"internal error code {code}")
        return self.joint_lists[kind][int(err[1])].error(int(code), int(err[2]), q, t)

    def evaluate(self, q: np.ndarray, v: np.ndarray, qdd: np.ndarray | None, lam: np.ndarray,
                 t: float, r_q: np.ndarray, r_lam: np.ndarray, *,
                 matrix: tuple[float, float, float] | None = None, load_factor: float = 1.0,
                 with_damping: bool = True) -> float:
        """Fill ``r_q``, ``r_lam`` (and, with ``matrix=(cM, cC, cK)``, the iteration matrix in
        ``self.matrix``) through :mod:`flexmbs.driver`, then add the interactions that have no
        compiled form. ``qdd=None`` means statics (no inertia; ``cM`` is then the optional
        stabiliser). Returns the force scale used by the convergence test: the largest single
        force entering the residual."""
        n = self.n_coords
        if qdd is None:
            mode = static_mode(load_factor, damping=with_damping)
            acc = np.zeros(n)
        else:
            mode = dynamic_mode()
            mode[0] = load_factor
            mode[2] = 1.0 if with_damping else 0.0
            acc = qdd
        python = self._switch_compiled_forms()
        fv = self.functions.values(t)
        q = np.ascontiguousarray(q, dtype=float)
        v = np.ascontiguousarray(v, dtype=float)
        lam = np.ascontiguousarray(lam, dtype=float)
        scale, code = self._kernel(OP_RESIDUAL, q, v, acc, lam, fv, mode, self._r)
        if code:
            raise self.error_exception(code, q, t)
        r_q[:] = self._r[:n]
        r_lam[:] = self._r[n:]
        if matrix is not None:
            cM, cC, cK = matrix
            kscale, code = self._kernel(OP_JACOBIAN, q, v, acc, lam, fv, mode, self._data,
                                        (cM, cC, cK))
            if code:
                raise self.error_exception(code, q, t)
            if kscale > 0:
                self.stiffness_scale = kscale
        for obj in python:
            scale = max(scale, obj.evaluate(self, q, v, lam, t, r_q, matrix))
        return scale

    def _kernel(self, op: int, q: np.ndarray, v: np.ndarray, qdd: np.ndarray, lam: np.ndarray,
                fv: np.ndarray, mode: np.ndarray, out: np.ndarray,
                coef: tuple[float, float, float] = (0.0, 0.0, 0.0), *,
                run: Any = None) -> tuple[float, int]:
        """One evaluation through :func:`flexmbs.kernel.kernel` (``out``: the residual for
        ``OP_RESIDUAL``, the CSC data of the iteration matrix for ``OP_JACOBIAN``)."""
        r, data = (self._r, out) if op == OP_JACOBIAN else (out, self._data)
        args = (op, self.kernel_system, q, v, qdd, lam, fv.reshape(1, -1), mode,
                np.array(coef, dtype=float), r, data, self._idle_run if run is None else run)
        if not self._kernel_ready:      # compiled, loaded, or compiled now with one line
            prepare(args)
            self._kernel_ready = True
        value, code = kernel(*args)
        return float(value), int(code)

    def post_step(self, q: np.ndarray, v: np.ndarray, t: float, qdd: np.ndarray | None = None,
                  acc: np.ndarray | None = None, lam: np.ndarray | None = None) -> None:
        """Interaction state after a converged step (may raise :class:`SimulationStopped`),
        then the nodal frames re-based where needed (FORMULATION §2.4), which changes the
        twist entries of ``q, v`` and of ``qdd, acc`` (when given) in place. ``lam``: the
        step's multipliers (the sliding joint's friction cone needs its normal reaction;
        default zero)."""
        python = self._switch_compiled_forms()
        for name, arr in (("q", q), ("v", v), ("qdd", qdd), ("acc", acc)):
            if arr is not None and not (isinstance(arr, np.ndarray) and arr.dtype == float
                                        and arr.flags.c_contiguous and arr.shape == (self.n_coords,)):
                raise TypeError(f"post_step: {name} must be a contiguous float array of "
                                f"{self.n_coords} coordinates (it is changed in place)")
        lam = np.zeros(self.n_mult) if lam is None else np.ascontiguousarray(lam, dtype=float)
        fv, mode = self.functions.values(t), dynamic_mode()
        _, code = self._kernel(OP_RESIDUAL, q, v, np.zeros_like(q), lam, fv, mode, self._r)
        if code:
            raise self.error_exception(code, q, t)
        for obj in python:     # before the kernel's update moves the step's start on
            obj.post_step(q, v, t)
        run = self._idle_run._replace(a=acc if acc is not None else np.zeros(0))
        _, code = self._kernel(OP_POST_STEP, q, v, qdd if qdd is not None else np.zeros(0),
                               lam, fv, mode, self._r, run=run)
        if code:
            raise self.error_exception(code, q, t)

    def static_increment_done(self, q: np.ndarray, lam: np.ndarray, t: float = 0.0,
                              load_factor: float = 1.0) -> int:
        """After a converged static increment at ``(q, lam)`` (the multipliers: the sliding
        joint's friction cone needs its normal reaction): the joints' state as after a step
        (slide elements, contact tracking, friction anchors; ``q`` the next increment's start),
        then the nodal frames re-based where tangents turned far (FORMULATION §2.4; ``q``
        changed in place). Returns the number of re-based nodes; raises
        :class:`FlexmbsError` if a node turned past the frames' limit."""
        python = self._switch_compiled_forms()
        fv, mode = self.functions.values(t), static_mode(load_factor, damping=False)
        zeros = np.zeros_like(q)
        lam = np.ascontiguousarray(lam, dtype=float)
        _, code = self._kernel(OP_RESIDUAL, q, zeros, np.zeros(0), lam, fv, mode, self._r)
        if code:
            raise self.error_exception(code, q, t)
        for obj in python:     # before the kernel's update moves the increment's start on
            obj.post_step(q, zeros, t)
        count, code = self._kernel(OP_REBASE, q, zeros, np.zeros(0), lam, fv, mode, self._r)
        if code:
            raise self.error_exception(code, q, t)
        return int(count)

    def begin(self, q: np.ndarray) -> None:
        """``q`` is where the next step (or static increment) starts: the reference of the
        history-dependent terms (the clearance contacts' sticking friction). The integrators
        and :func:`~flexmbs.solvers.static.solve_static` call it at their start; each converged
        step moves it on. The interactions' compiled forms are switched as they are now (the
        compiled integrator then runs without asking again)."""
        for kind in driver.INTERACTION_KINDS:
            if kind.begin is not None:
                kind.begin(getattr(self.system, kind.name), q)
        self._switch_compiled_forms()

    def node_bases(self) -> np.ndarray:
        """Every twisting node's current base: records ``[twist coordinate, t̄ (3), D̄ (3)]``
        (FORMULATION §2.4; what a checkpoint carries)."""
        rows = [g.element_type.bases(g.part) for g in self.groups if g.element_type.bases]
        return np.vstack(rows) if rows else np.zeros((0, BASE_RECORD))

    def set_node_bases(self, records: np.ndarray) -> None:
        """Give the nodes of ``records`` (:meth:`node_bases`) their bases in every holder: the
        elements, joints and node moments (a resumed run)."""
        records = np.asarray(records, dtype=float).reshape(-1, BASE_RECORD)
        log = self.system.bases
        if records.shape[0] > log.shape[0]:
            raise ValueError(f"{records.shape[0]} nodal bases for a model with {log.shape[0]} "
                             "twisting node slots")
        log[:records.shape[0]] = records
        self._kernel(OP_SET_BASES, np.zeros(self.n_coords), np.zeros(self.n_coords), np.zeros(0),
                     np.zeros(self.n_mult), self.functions.values(0.0), static_mode(1.0), self._r,
                     (float(records.shape[0]), 0.0, 0.0))

    # ---------------------------------------------------------------- DofMap / MatrixSink
    def positions(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """CSC data positions of the (rows[i], cols[j]) block (must be in the pattern)."""
        N = self.n_total
        k = (np.asarray(cols, np.int64)[None, :] * N + np.asarray(rows, np.int64)[:, None]).ravel()
        pos = np.searchsorted(self._ukeys, k)
        if np.any(pos >= self._ukeys.size) or np.any(self._ukeys[np.minimum(pos, self._ukeys.size - 1)] != k):
            raise ModelError("internal: matrix entry outside the reserved sparsity pattern")
        return pos

    def border_indices(self) -> np.ndarray:
        """Unknowns of the bordered banded LU's dense border (:mod:`flexmbs.solvers._bordered`):
        rigid-body and interaction coordinates, nonlinear multipliers, and linear multipliers
        touching a border coordinate (the beams' coordinates form the band)."""
        n = self.n_coords
        coords = np.concatenate([self.body_dof_table.ravel()]
                                + [np.asarray(self.extra_dofs(obj), np.int64)
                                   for obj in self.model.interactions])
        in_border = np.zeros(n, bool)
        in_border[coords] = True
        parts = [coords] + [n + np.asarray(nl.rows, np.int64) for nl in self.nonlinear]
        if self.m_lin:
            L = sp.csr_matrix(self.lin_matrix)
            pattern = sp.csr_matrix((np.ones(L.nnz), L.indices, L.indptr), shape=L.shape)
            parts.append(n + np.flatnonzero(pattern @ in_border.astype(float) > 0))
        return np.unique(np.concatenate(parts).astype(np.int64))

    def coordinate_owners(self) -> np.ndarray:
        """A label per unknown (coordinates and multipliers): the body index for a rigid
        body's coordinates (the band order keeps them together), ``_ordering.MASSLESS`` for the
        interactions' coordinates (a slide coordinate has no mass: never in the band beside a
        border), −1 otherwise (:func:`flexmbs.solvers._ordering.close_border`)."""
        from .solvers._ordering import MASSLESS

        owner = np.full(self.n_total, -1, np.int64)
        table = self.body_dof_table
        owner[table.ravel()] = np.repeat(np.arange(table.shape[0]), table.shape[1])
        for obj in self.model.interactions:
            owner[np.asarray(self.extra_dofs(obj), np.int64)] = MASSLESS
        return owner

    def factor_plan(self, *, mass: bool = True) -> Any:
        """The factorisation plan of the iteration matrix
        (:func:`flexmbs.solvers._ordering.plan_factorization` of this pattern with
        :meth:`border_indices` and :meth:`coordinate_owners`), computed once. ``mass``: the
        matrix has c_M M on every coordinate that has mass (dynamics, velocity corrector,
        initial accelerations); without (statics, stiffness only) every coordinate is labelled
        massless, which closes every nonempty border over the whole matrix (docs/design-notes.md,
        "One factorisation for every solver")."""
        from .solvers._ordering import MASSLESS, plan_factorization

        if mass not in self._plans:
            owner = self.coordinate_owners()
            if not mass:
                owner[:self.n_coords] = MASSLESS
            self._plans[mass] = plan_factorization(self.matrix, self.border_indices(),
                                                   self.n_coords, owner)
        return self._plans[mass]

    def positions_present(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """As :meth:`positions`, with −1 for the entries outside the pattern."""
        N = self.n_total
        k = (np.asarray(cols, np.int64)[None, :] * N + np.asarray(rows, np.int64)[:, None]).ravel()
        pos = np.minimum(np.searchsorted(self._ukeys, k), self._ukeys.size - 1)
        return np.where(self._ukeys[pos] == k, pos, -1)

    def add_to_matrix(self, rows: np.ndarray, cols: np.ndarray, block: np.ndarray) -> None:
        """Add a dense block to the iteration matrix being assembled (rows/cols global)."""
        np.add.at(self._data, self.positions(rows, cols), np.asarray(block, float).ravel())

    def multiplier_rows(self, constraint: object) -> np.ndarray:
        """Multiplier indices (into lam) of the equations of ``constraint``, −1 if dropped."""
        nl = self._rows_of.get(id(constraint))
        if nl is None:
            return np.full(getattr(constraint, "n_equations", 0), -1, np.int64)
        out = np.full(nl.constraint.n_equations, -1, np.int64)
        out[nl.keep] = nl.rows
        return out

    def _matrix_at(self, q: np.ndarray, t: float, cM: float) -> sp.csc_matrix:
        """The iteration matrix with ``cM`` M and no stiffness (Φ_q in its borders)."""
        n = self.n_coords
        data = np.zeros_like(self._data)
        q = np.ascontiguousarray(q, dtype=float)
        zeros = np.zeros(n)
        self._switch_compiled_forms()
        self._kernel(OP_JACOBIAN, q, zeros, zeros, np.zeros(self.n_mult),
                     self.functions.values(t), dynamic_mode(), data, (cM, 0.0, 0.0))
        return sp.csc_matrix((data, self.matrix.indices, self.matrix.indptr), shape=self.matrix.shape)

    def constraint_jacobian(self, q: np.ndarray, t: float = 0.0) -> sp.csr_matrix:
        """Phi_q as a sparse (n_mult, n_coords) matrix (the driver's matrix border)."""
        n = self.n_coords
        return sp.csr_matrix(self._matrix_at(q, t, 0.0)[n:, :n])

    def constraint_values(self, q: np.ndarray, t: float) -> np.ndarray:
        """Phi(q, t) (the driver's constraint residual)."""
        n = self.n_coords
        q = np.ascontiguousarray(q, dtype=float)
        zeros = np.zeros(n)
        self._switch_compiled_forms()
        r = np.zeros(self.n_total)
        self._kernel(OP_RESIDUAL, q, zeros, zeros, np.zeros(self.n_mult),
                     self.functions.values(t), dynamic_mode(), r)
        return r[n:].copy()

    def constraint_velocity_terms(self, q: np.ndarray, t: float) -> np.ndarray:
        """Right-hand side ``−Phi_t`` of the velocity-level constraints ``Phi_q v = −Phi_t``
        (nonzero only for prescribed motion and drivers)."""
        out = np.zeros(self.n_mult)
        for row, fn in self.lin_functions:
            out[row] += fn.d1(t)
        for nl in self.nonlinear:
            if isinstance(nl.constraint, JointDriver):
                out[nl.rows] += nl.constraint.velocity_rhs(q[nl.coords], t)
        return out

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

    def has_nonlinear_constraints(self) -> bool:
        """Whether some kept equation is nonlinear in q (joints, Euler parameters, sliding)."""
        return bool(self.nonlinear)

    def matrix_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        """CSC ``(indptr, indices)`` of the iteration matrix as int64 (what compiled code that
        reads ``data`` by column needs, e.g. :func:`flexmbs.driver.constraint_velocity`)."""
        return (np.ascontiguousarray(self.matrix.indptr, dtype=np.int64),
                np.ascontiguousarray(self.matrix.indices, dtype=np.int64))

    def constraint_time_terms(self, q: np.ndarray, v: np.ndarray, t: float) -> np.ndarray:
        """Right-hand side of the acceleration-level constraints,
        ``-(Phi_q v)_q v - 2 Phi_qt v - Phi_tt`` (FORMULATION §6.1 INIT)."""
        eps = 1e-7 * self.length_scale / max(float(np.abs(v).max()), 1e-30)
        out = np.zeros(self.n_mult)
        if np.any(v):
            Jp = self.constraint_jacobian(q + eps * v, t)
            Jm = self.constraint_jacobian(q - eps * v, t)
            out -= ((Jp - Jm) @ v) / (2 * eps)
        if self.m_lin:
            for row, fn in self.lin_functions:
                out[row] += fn.d2(t)
        for nl in self.nonlinear:
            if isinstance(nl.constraint, JointDriver):
                out[nl.rows] += nl.constraint.acceleration_rhs(q[nl.coords], v[nl.coords], t)
        return out

    def mass_matrix(self, q: np.ndarray) -> sp.csr_matrix:
        """M(q) (the driver's matrix with cM = 1 and no stiffness)."""
        n = self.n_coords
        return sp.csr_matrix(self._matrix_at(q, 0.0, 1.0)[:n, :n])

    # ================================================================== energies
    def energies(self, q: np.ndarray, v: np.ndarray) -> dict[str, float]:
        """Kinetic, strain and gravitational potential energy (zero at the reference); the last
        state's values are kept (output, probes and results ask for the same state)."""
        key = (q.tobytes(), v.tobytes())
        cached = getattr(self, "_energy_cache", None)
        if cached is not None and cached[0] == key:
            return dict(cached[1])
        out = self._energies(q, v)
        self._energy_cache = (key, out)
        return dict(out)

    def _energies(self, q: np.ndarray, v: np.ndarray) -> dict[str, float]:
        kin = 0.0
        strain = 0.0
        for grp in self.groups:
            if grp.element_type.kinetic_energy is not None:
                kin += grp.element_type.kinetic_energy(grp.part, q, v)
            else:
                ve = v[grp.dofs]
                kin += 0.5 * float(np.einsum("ei,eij,ej->", ve, grp.mass, ve))
            strain += float(np.sum(grp.element_type.strain_energy(q[grp.dofs], grp.props, grp.rest,
                                                                  grp.options)))
        bp = self.system.bodies
        if bp.dofs.size:
            kin += float(np.sum(rb.kinetic_energy(bp.mass, bp.inertia, q[bp.dofs[:, 3:]], v[bp.dofs])))
        grav = -float(self.gravity_vector @ (q - self.q_ref))
        out = {"kinetic": kin, "strain": strain, "gravity": grav, "total": kin + strain + grav}
        if self.model.springs:
            out["spring"] = spring_energy(self.system.springs, np.ascontiguousarray(q, float))
            out["total"] += out["spring"]
        for kind in driver.INTERACTION_KINDS:
            if kind.energy is not None and self.joint_lists[kind.name]:
                label, energy = kind.energy
                out[label] = sum(energy(obj, q, v) for obj in self.joint_lists[kind.name])
                out["total"] += out[label]
        return out

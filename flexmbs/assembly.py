"""Global assembly: DOF map, residual, sparse iteration matrix (pattern built once), energies.

Unknowns: coordinates ``q`` (beams: per node [r, r'], 6 each; rigid bodies: [r, p], 7 each) and
Lagrange multipliers ``lam`` (one per constraint equation). The dynamic residual follows the
convention of FORMULATION §0::

    r_q   = M(q) q'' + Q_int(q, q') + Phi_q^T lam - Q_ext(q, t)
    r_lam = Phi(q, t)

The iteration matrix ``[[cM M + cC C + cK K, Phi_q^T], [Phi_q, 0]]`` (``K`` includes the
constraint Hessian contracted with ``lam``) is stored in CSC form with a fixed pattern; every
refill writes ``data`` in place through precomputed position maps.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.sparse as sp

from . import _scatter as sc
from .constraints.base import Attachment, Constraint
from .constraints.joints import BeamNodeRigid, EulerParameterNormalization, GenericJoint
from .elements import ancf_cable as cable
from .elements import rigid_body as rb
from .errors import ModelError, RedundantConstraintError
from .loads import TimeFunction
from .model import Beam, Ground, Model, Node, RigidBody

_DIAG = np.arange(12)


@dataclass
class _BeamGroup:
    """All elements (of possibly several beams) sharing one CableOptions: one kernel call."""

    options: cable.CableOptions
    beams: list[Beam]
    dofs: np.ndarray            # (ne, 12) global coordinate indices
    props: cable.CableProperties
    rest: object                # cable.CableRest
    mass: np.ndarray            # (ne, 12, 12)
    mass_flat: np.ndarray       # (ne, 144) view
    pos: np.ndarray | None = None   # (ne, 144) CSC data positions
    qe: np.ndarray | None = None
    ve: np.ndarray | None = None
    force: np.ndarray | None = None
    stiff: np.ndarray | None = None
    damp: np.ndarray | None = None


@dataclass
class _NonlinearRows:
    constraint: Constraint
    coords: np.ndarray          # (nc,) global coordinate indices
    keep: np.ndarray            # equation indices kept (redundant ones dropped)
    rows: np.ndarray            # multiplier indices of kept equations (len(keep),)
    pos_jac: np.ndarray | None = None
    pos_jacT: np.ndarray | None = None
    pos_hess: np.ndarray | None = None
    version: int = 0


class Assembly:
    """Numbering and global evaluation of a :class:`~flexmbs.model.Model`."""

    def __init__(self, model: Model, *, redundant_constraints: str = "error",
                 rank_tolerance: float = 1e-9) -> None:
        if redundant_constraints not in ("error", "drop"):
            raise ModelError("redundant_constraints must be 'error' or 'drop'")
        self.model = model
        self._number_coordinates()
        self._build_beams()
        self._build_bodies()
        self._build_constraints(redundant_constraints, rank_tolerance)
        self._build_loads()
        self._build_pattern()
        self.length_scale = self._length_scale()
        self.stiffness_scale = 0.0
        n, m = self.n_coords, self.n_mult
        self.evaluate(self.q_ref, np.zeros(n), None, np.zeros(m), 0.0, np.zeros(n), np.zeros(m),
                      matrix=(0.0, 0.0, 1.0), with_damping=False)

    # ================================================================== numbering
    def _number_coordinates(self) -> None:
        m = self.model
        off = 0
        self.beam_offset: dict[int, int] = {}
        labels: list[tuple[str, str]] = []
        comp = ("x", "y", "z", "x'", "y'", "z'")
        for beam in m.beams:
            self.beam_offset[id(beam)] = off
            for i in range(beam.n_nodes):
                labels.extend((f"beam '{beam.name}' node {i}", c) for c in comp)
            off += 6 * beam.n_nodes
        self.body_offset: dict[int, int] = {}
        for body in m.bodies:
            self.body_offset[id(body)] = off
            labels.extend((f"body '{body.name}'", c) for c in ("x", "y", "z", "e0", "e1", "e2", "e3"))
            off += 7
        self.extra_dofs: dict[int, np.ndarray] = {}
        for obj in m.interactions:
            names = obj.extra_labels()
            self.extra_dofs[id(obj)] = np.arange(off, off + len(names), dtype=np.int64)
            labels.extend((f"joint '{obj.name}'", c) for c in names)
            off += len(names)
        self.n_coords = off
        self._coord_labels = labels
        q0 = np.zeros(off)
        v0 = np.zeros(off)
        for beam in m.beams:
            o = self.beam_offset[id(beam)]
            nodal = np.hstack([beam.centerline.points, beam.centerline.tangents])
            q0[o:o + 6 * beam.n_nodes] = nodal.ravel()
        for body in m.bodies:
            o = self.body_offset[id(body)]
            p = body.pose.quaternion
            q0[o:o + 3] = body.pose.position
            q0[o + 3:o + 7] = p
            v0[o:o + 3] = body.velocity
            v0[o + 3:o + 7] = rb.pdot_from_omega_global(p, body.angular_velocity)
        for obj in m.interactions:
            d = self.extra_dofs[id(obj)]
            obj.bind(self, d)
            q0[d] = obj.initial_extra(q0)
        self.q_ref = q0
        self.v_init = v0

    def node_dofs(self, node: Node) -> np.ndarray:
        o = self.beam_offset[id(node.beam)] + 6 * node.index
        return np.arange(o, o + 6)

    def body_dofs(self, body: RigidBody) -> np.ndarray:
        o = self.body_offset[id(body)]
        return np.arange(o, o + 7)

    def beam_dofs(self, beam: Beam) -> np.ndarray:
        o = self.beam_offset[id(beam)]
        return np.arange(o, o + 6 * beam.n_nodes)

    def element_dofs(self, beam: Beam) -> np.ndarray:
        o = self.beam_offset[id(beam)]
        conn = beam.connectivity
        return (o + 6 * conn[:, :, None] + np.arange(6)[None, None, :]).reshape(-1, 12)

    def describe_coordinate(self, i: int) -> str:
        if i < self.n_coords:
            obj, c = self._coord_labels[i]
            return f"{obj}, coordinate {c}"
        j = i - self.n_coords
        return self.multiplier_labels[j] if j < len(self.multiplier_labels) else f"equation {i}"

    # ================================================================== beams
    def _build_beams(self) -> None:
        groups: dict[cable.CableOptions, list[Beam]] = {}
        for beam in self.model.beams:
            groups.setdefault(beam.options, []).append(beam)
        self.groups: list[_BeamGroup] = []
        self.beam_slices: dict[int, tuple[int, slice]] = {}
        for gi, (opts, beams) in enumerate(groups.items()):
            dofs, L, EA, EI, rA, dA, dB, e0 = [], [], [], [], [], [], [], []
            start = 0
            for beam in beams:
                d = self.element_dofs(beam)
                dofs.append(d)
                ne = beam.n_elem
                st = beam.stiffness
                L.append(np.asarray(beam.centerline.lengths, float))
                EA.append(np.full(ne, st.axial_stiffness))
                EI.append(np.full(ne, st.bending_stiffness))
                rA.append(np.full(ne, st.mass_per_length))
                dA.append(np.full(ne, beam.damping * st.axial_stiffness))
                dB.append(np.full(ne, beam.damping * st.bending_stiffness))
                e0.append(np.full(ne, beam.reference_axial_strain))
                self.beam_slices[id(beam)] = (gi, slice(start, start + ne))
                start += ne
            D = np.ascontiguousarray(np.vstack(dofs), dtype=np.int64)
            props = cable.CableProperties(
                length=np.concatenate(L), axial_stiffness=np.concatenate(EA),
                bending_stiffness=np.concatenate(EI), mass_per_length=np.concatenate(rA),
                axial_damping=np.concatenate(dA), bending_damping=np.concatenate(dB),
                reference_axial_strain=np.concatenate(e0))
            rest = cable.rest_state(np.ascontiguousarray(self.q_ref[D]), props, opts)
            mass = np.ascontiguousarray(cable.mass_matrix(props))
            ne = D.shape[0]
            self.groups.append(_BeamGroup(
                opts, beams, D, props, rest, mass, mass.reshape(ne, 144),
                qe=np.zeros((ne, 12)), ve=np.zeros((ne, 12)), force=np.zeros((ne, 12)),
                stiff=np.zeros((ne, 12, 12)), damp=np.zeros((ne, 12, 12))))

    # ================================================================== bodies
    def _build_bodies(self) -> None:
        bodies = self.model.bodies
        nb = len(bodies)
        self.body_dof_table = np.array([self.body_dofs(b) for b in bodies], dtype=np.int64).reshape(nb, 7)
        self.body_mass = np.array([b.mass for b in bodies], float)
        self.body_inertia = np.array([b.inertia for b in bodies], float).reshape(nb, 3, 3)
        self._br = np.zeros((nb, 7))
        self._bdq = np.zeros((nb, 7, 7))
        self._bdv = np.zeros((nb, 7, 7))
        self._bM = np.zeros((nb, 7, 7))

    # ================================================================== constraints
    def _attachment(self, obj: object, point: np.ndarray | None, frame: np.ndarray | None) -> Attachment:
        if isinstance(obj, RigidBody):
            return Attachment.rigid_body(self.body_dofs(obj),
                                         np.zeros(3) if point is None else point, frame)
        if isinstance(obj, Node):
            return Attachment.beam_node(self.node_dofs(obj))
        if isinstance(obj, Ground):
            return Attachment.ground(point if point is not None else np.zeros(3),
                                     frame if frame is not None else np.eye(3))
        raise ModelError(f"cannot attach a constraint to {obj!r}")

    def _build_constraints(self, policy: str, rank_tol: float) -> None:
        lin_rows: list[tuple[np.ndarray, np.ndarray]] = []   # (cols, vals) per row
        lin_rhs: list[float] = []
        lin_fun: list[TimeFunction | None] = []
        lin_labels: list[str] = []
        nonlinear: list[Constraint] = []
        q0 = self.q_ref
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
                if k == "clamp":
                    t = q0[d[3:6]] / np.linalg.norm(q0[d[3:6]])
                    # two unit normals to the reference tangent: axis-aligned when possible so that
                    # the rows stay coordinate constraints for beams along global axes
                    order = np.argsort(np.abs(t))
                    n1 = np.zeros(3)
                    n1[order[0]] = 1.0
                    n1 -= np.dot(n1, t) * t
                    n1 /= np.linalg.norm(n1)
                    n2 = np.cross(t, n1)
                    for j, n in enumerate((n1, n2)):
                        nz = np.abs(n) > 1e-14
                        lin_rows.append((d[3:6][nz], n[nz]))
                        lin_rhs.append(0.0)
                        lin_fun.append(None)
                        lin_labels.append(f"clamp '{spec.name}' ({node.name}) slope normal {j + 1}")
            elif k == "prescribed":
                tgt = spec.a
                d = self.node_dofs(tgt) if isinstance(tgt, Node) else self.body_dofs(tgt)  # type: ignore[arg-type]
                for c in spec.components:
                    lin_rows.append((d[c:c + 1], np.ones(1)))
                    lin_rhs.append(q0[d[c]])
                    lin_fun.append(spec.function)
                    lin_labels.append(f"prescribed '{spec.name}' component {c}")
            elif k == "rigid":
                node = spec.a  # type: ignore[assignment]
                body_att = self._attachment(spec.b, None, None)
                node_att = self._attachment(node, None, None)
                q_body = q0[self.body_dofs(spec.b)] if isinstance(spec.b, RigidBody) else None
                nonlinear.append(BeamNodeRigid.from_configuration(
                    spec.name, node_att, body_att, q0[self.node_dofs(node)], q_body))
            else:  # generic joints and presets
                a = self._attachment(spec.a, spec.point_a, spec.frame_a)
                b = self._attachment(spec.b, spec.point_b, spec.frame_b)
                nonlinear.append(GenericJoint(spec.name, a, b, translation=spec.translation,
                                              rotation=spec.rotation))
        for body in self.model.bodies:
            nonlinear.append(EulerParameterNormalization(f"{body.name}.normalization",
                                                         self.body_dofs(body)))
        for obj in self.model.interactions:
            for c in obj.constraints():
                phi, _ = c.evaluate(q0[c.coordinates()], 0.0)
                if np.abs(phi).max(initial=0.0) > 1e-6 * max(self._length_scale(), 1e-3):
                    raise ModelError(
                        f"joint '{obj.name}' is violated by {np.abs(phi).max():.3g} in the initial "
                        "configuration: place the body on the beam (e.g. pose = beam.frame_at(s), "
                        "scenario pose = {on_beam, s}) with its hole axis along the tangent")
                nonlinear.append(c)

        # ---- redundancy check on the full Jacobian at the initial configuration
        n = self.n_coords
        m_lin = len(lin_rows)
        blocks = []
        labels = list(lin_labels)
        owners: list[tuple[int, int]] = [(-1, i) for i in range(m_lin)]
        J = np.zeros((m_lin + sum(c.n_equations for c in nonlinear), n))
        for i, (cols, vals) in enumerate(lin_rows):
            J[i, cols] = vals
        r = m_lin
        for ci, c in enumerate(nonlinear):
            idx = c.coordinates()
            phi, jac = c.evaluate(q0[idx], 0.0)
            J[r:r + c.n_equations][:, idx] = jac
            labels.extend(f"{type(c).__name__} '{c.name}' equation {lab}" for lab in c.equation_labels)
            owners.extend((ci, j) for j in range(c.n_equations))
            r += c.n_equations
            blocks.append(phi)
        keep_rows = np.arange(J.shape[0])
        if J.shape[0] > 0:
            norms = np.linalg.norm(J, axis=1)
            zero = norms == 0
            if np.any(zero):
                raise ModelError("constraint equations with an all-zero Jacobian at the initial "
                                 f"configuration: {[labels[i] for i in np.flatnonzero(zero)]}")
            Jn = J / norms[:, None]
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
        keep_set = set(int(i) for i in keep_rows)

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
        self.lin_functions = [(new, lin_fun[i]) for new, i in enumerate(lin_keep) if lin_fun[i] is not None]
        self._lin_coo = (np.array(rows_i, np.int64), np.array(cols_i, np.int64), np.array(vals_i, float))
        multiplier_labels = [lin_labels[i] for i in lin_keep]

        # ---- nonlinear rows kept
        self.nonlinear: list[_NonlinearRows] = []
        row = self.m_lin
        base = m_lin
        for c in nonlinear:
            keep = np.array([j for j in range(c.n_equations) if base + j in keep_set], np.int64)
            base += c.n_equations
            if keep.size == 0:
                continue
            rows = np.arange(row, row + keep.size)
            row += keep.size
            self.nonlinear.append(_NonlinearRows(c, np.asarray(c.coordinates(), np.int64), keep, rows))
            multiplier_labels.extend(f"{type(c).__name__} '{c.name}' equation {c.equation_labels[j]}"
                                     for j in keep)
        self.n_mult = row
        self.multiplier_labels = multiplier_labels
        self.n_total = self.n_coords + self.n_mult

    # ================================================================== loads
    def _build_loads(self) -> None:
        n = self.n_coords
        g = self.model.gravity
        f_const = np.zeros(n)
        self.gravity_vector = np.zeros(n)
        for grp in self.groups:
            Qg = cable.gravity_force(grp.props, g)
            np.add.at(self.gravity_vector, grp.dofs, Qg)
        for body in self.model.bodies:
            d = self.body_dofs(body)
            self.gravity_vector[d[:3]] += body.mass * g
        f_const += self.gravity_vector
        timed: list[tuple[np.ndarray, np.ndarray, TimeFunction]] = []
        body_loads: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None, TimeFunction]] = []
        for load in self.model.loads:
            idx: np.ndarray
            vals: np.ndarray
            if load.kind == "distributed":
                beam: Beam = load.target  # type: ignore[assignment]
                gi, sl = self.beam_slices[id(beam)]
                grp = self.groups[gi]
                props = cable.CableProperties(*[np.asarray(a)[sl] for a in grp.props])
                Q = cable.distributed_force(props, load.force)
                idx, vals = grp.dofs[sl].ravel(), Q.ravel()
            elif isinstance(load.target, RigidBody):
                body_loads.append((self.body_dofs(load.target), load.point, load.force, load.moment,
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
                    idx, vals = d[:3], load.force.copy()
                    if load.moment is not None:
                        # moment on a cable node: only the part normal to the tangent does work,
                        # Q_slope = (T x t)/|r'| (FORMULATION §1.2)
                        t = self.q_ref[d[3:6]]
                        nt = np.linalg.norm(t)
                        idx = np.concatenate([idx, d[3:6]])
                        vals = np.concatenate([vals, np.cross(load.moment, t / nt) / nt])
                else:
                    e, xi = beam.locate(float(s))
                    dofs = self.element_dofs(beam)[e]
                    L = np.array([beam.centerline.lengths[e]])
                    Q = cable.point_force_vector(np.array([xi]), L, load.force[None, :])[0]
                    if load.moment is not None:
                        raise ModelError(f"load '{load.name}': moments are supported at nodes only")
                    idx, vals = dofs, Q
            fn = load.function
            if type(fn).__name__ == "Constant" and getattr(fn, "value", None) == 1.0:
                np.add.at(f_const, idx, vals)
            else:
                timed.append((idx, vals, fn))
        self.f_const = f_const
        self.f_timed = timed
        self.body_loads = body_loads

    def external_force(self, t: float, out: np.ndarray, load_factor: float = 1.0) -> None:
        """out = Q_ext(t) (state-independent part; body point loads are added in evaluate)."""
        np.multiply(self.f_const, load_factor, out=out)
        for idx, vals, fn in self.f_timed:
            np.add.at(out, idx, load_factor * fn(t) * vals)

    # ================================================================== pattern
    def _build_pattern(self) -> None:
        N = self.n_total
        n = self.n_coords
        keys_parts = [np.arange(N, dtype=np.int64) * (N + 1)]   # full diagonal
        contributions = []

        def key(r: np.ndarray, c: np.ndarray) -> np.ndarray:
            return (c.astype(np.int64) * N + r.astype(np.int64))

        for grp in self.groups:
            d = grp.dofs
            k = key(np.repeat(d, 12, axis=1), np.tile(d, (1, 12)))
            keys_parts.append(k.ravel())
            contributions.append(("group", grp, k))
        bd = self.body_dof_table
        if bd.size:
            kb = key(np.repeat(bd, 7, axis=1), np.tile(bd, (1, 7)))
            keys_parts.append(kb.ravel())
            contributions.append(("bodies", None, kb))
        lr, lc, _ = self._lin_coo
        klin = key(n + lr, lc)
        klinT = key(lc, n + lr)
        keys_parts += [klin, klinT]
        for nl in self.nonlinear:
            c = nl.coords
            rows = n + nl.rows
            kj = key(np.repeat(rows, c.size), np.tile(c, rows.size))
            kt = key(np.tile(c, rows.size), np.repeat(rows, c.size))
            kh = key(np.repeat(c, c.size), np.tile(c, c.size))
            keys_parts += [kj, kt, kh]
            contributions.append(("nl", nl, (kj, kt, kh)))
        for obj in self.model.interactions:
            for rows_i, cols_i in obj.pattern_blocks():
                rr, cc = np.meshgrid(np.asarray(rows_i, np.int64), np.asarray(cols_i, np.int64),
                                     indexing="ij")
                keys_parts += [key(rr.ravel(), cc.ravel()), key(cc.ravel(), rr.ravel())]
        for nl in self.nonlinear:   # interaction constraints: their multipliers x reserved coords
            c = nl.constraint
            if hasattr(c, "version"):
                for obj in self.model.interactions:
                    if c in obj.constraints():
                        for _, cols_i in obj.pattern_blocks():
                            cc = np.asarray(cols_i, np.int64)
                            rows = n + nl.rows
                            keys_parts += [key(np.repeat(rows, cc.size), np.tile(cc, rows.size)),
                                           key(np.tile(cc, rows.size), np.repeat(rows, cc.size))]
        ukeys = np.unique(np.concatenate(keys_parts))
        self._ukeys = ukeys
        cols = ukeys // N
        rows = ukeys % N
        indptr = np.zeros(N + 1, np.int64)
        np.add.at(indptr, cols + 1, 1)
        indptr = np.cumsum(indptr)
        self._data = np.zeros(ukeys.size)
        self.matrix = sp.csc_matrix((self._data, rows.astype(np.int32), indptr.astype(np.int32)),
                                    shape=(N, N))
        self._data = self.matrix.data  # the array the matrix really holds

        def pos(k: np.ndarray) -> np.ndarray:
            return np.ascontiguousarray(np.searchsorted(ukeys, k), dtype=np.int64)

        for kind, obj, k in contributions:
            if kind == "group":
                obj.pos = pos(k).reshape(-1, 144)
            elif kind == "bodies":
                self._body_pos = pos(k).reshape(-1, 49)
            else:
                kj, kt, kh = k
                obj.pos_jac = pos(kj)
                obj.pos_jacT = pos(kt)
                obj.pos_hess = pos(kh)
        # constant entries (linear constraint rows)
        self._const_data = np.zeros_like(self._data)
        np.add.at(self._const_data, pos(klin), self._lin_coo[2])
        np.add.at(self._const_data, pos(klinT), self._lin_coo[2])
        self.nnz = ukeys.size

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

    def evaluate(self, q: np.ndarray, v: np.ndarray, qdd: np.ndarray | None, lam: np.ndarray,
                 t: float, r_q: np.ndarray, r_lam: np.ndarray, *,
                 matrix: tuple[float, float, float] | None = None, load_factor: float = 1.0,
                 with_damping: bool = True) -> float:
        """Fill ``r_q``, ``r_lam`` (and, with ``matrix=(cM, cC, cK)``, the iteration matrix in
        ``self.matrix``). ``qdd=None`` means statics (no inertia). Returns the force scale used by
        the convergence test: the largest single force entering the residual."""
        want = matrix is not None
        self.external_force(t, r_q, load_factor)
        np.negative(r_q, out=r_q)
        scale = float(np.abs(r_q).max()) if r_q.size else 0.0
        if want:
            cM, cC, cK = matrix  # type: ignore[misc]
            data = self._data
            data[:] = self._const_data
            kscale = 0.0
        for grp in self.groups:
            sc.gather(q, grp.dofs, grp.qe)
            if with_damping:
                sc.gather(v, grp.dofs, grp.ve)
            else:
                grp.ve.fill(0.0)
            cable.internal_forces(grp.qe, grp.ve, grp.props, grp.rest, grp.options, grp.force,
                                  grp.stiff if want else None, grp.damp if want else None)
            scale = max(scale, sc.scatter_add(r_q, grp.dofs, grp.force, 1.0))
            if qdd is not None:
                scale = max(scale, sc.scatter_mass_times(r_q, grp.dofs, grp.mass, qdd))
            if want:
                ne = grp.dofs.shape[0]
                kscale = max(kscale, float(np.abs(grp.stiff[:, _DIAG, _DIAG]).max()))
                if qdd is not None or cM != 0.0:   # statics: cM is the optional stabiliser
                    sc.scatter_matrix(data, grp.pos, grp.stiff.reshape(ne, 144),
                                      grp.damp.reshape(ne, 144), grp.mass_flat, cK, cC, cM)
                else:
                    sc.scatter_matrix_kc(data, grp.pos, grp.stiff.reshape(ne, 144),
                                         grp.damp.reshape(ne, 144), cK, cC)
        nb = self.body_dof_table.shape[0]
        if nb:
            bd = self.body_dof_table
            p = q[bd[:, 3:]]
            if qdd is not None:
                rb.inertial_residual(self.body_mass, self.body_inertia, p, v[bd[:, 3:]], qdd[bd],
                                     self._br, self._bdq, self._bdv)
                r_q[bd] += self._br   # body coordinates are distinct: no accumulation needed
                scale = max(scale, float(np.abs(self._br).max()))
                if want:
                    self._bM[:] = rb.mass_matrix(self.body_mass, self.body_inertia, p)
                    blk = cM * self._bM + cC * self._bdv + cK * self._bdq
                    np.add.at(data, self._body_pos, blk.reshape(nb, 49))
            elif want and cM != 0.0:   # statics with the mass-proportional stabiliser
                blk = cM * rb.mass_matrix(self.body_mass, self.body_inertia, p)
                np.add.at(data, self._body_pos, blk.reshape(nb, 49))
            for dofs, point, force, moment, fn in self.body_loads:
                f = load_factor * fn(t)
                pb = q[dofs[3:]][None, :]
                Q, dQ = rb.applied_force(pb, point[None, :], (f * force)[None, :])
                if moment is not None:
                    Qm, dQm = rb.applied_torque_global(pb, (f * moment)[None, :])
                    Q, dQ = Q + Qm, dQ + dQm
                r_q[dofs] -= Q[0]
                scale = max(scale, float(np.abs(Q).max()))
                if want:
                    pos = self._body_pos[np.flatnonzero(bd[:, 0] == dofs[0])[0]]
                    data[pos] -= cK * dQ[0].ravel()
        # constraints
        if self.m_lin:
            r_q += self.lin_matrix_T @ lam[:self.m_lin]
            r_lam[:self.m_lin] = self.lin_matrix @ q - self.lin_rhs0
            for row, fn in self.lin_functions:
                # prescribed motion ramps with the load factor in statics, like the loads
                r_lam[row] -= load_factor * fn(t)
        for nl in self.nonlinear:
            c = nl.constraint
            if getattr(c, "version", 0) != nl.version:
                self._update_positions(nl)
            ql = q[nl.coords]
            phi, jac = c.evaluate(ql, t)
            lam_full = np.zeros(c.n_equations)
            lam_full[nl.keep] = lam[nl.rows]
            jk = jac[nl.keep]
            r_lam[nl.rows] = phi[nl.keep]
            r_q[nl.coords] += jk.T @ lam[nl.rows]
            if want:
                data[nl.pos_jac] += jk.ravel()
                data[nl.pos_jacT] += jk.ravel()
                data[nl.pos_hess] += cK * c.hessian_lambda(ql, lam_full, t).ravel()
        for obj in self.model.interactions:
            scale = max(scale, obj.evaluate(self, q, v, lam, t, r_q, matrix))
        if want and kscale > 0:
            self.stiffness_scale = kscale
        return scale

    # ---------------------------------------------------------------- helpers for interactions
    def positions(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """CSC data positions of the (rows[i], cols[j]) block (must be in the pattern)."""
        N = self.n_total
        k = (np.asarray(cols, np.int64)[None, :] * N + np.asarray(rows, np.int64)[:, None]).ravel()
        pos = np.searchsorted(self._ukeys, k)
        if np.any(pos >= self._ukeys.size) or np.any(self._ukeys[np.minimum(pos, self._ukeys.size - 1)] != k):
            raise ModelError("internal: matrix entry outside the reserved sparsity pattern")
        return pos

    def add_to_matrix(self, rows: np.ndarray, cols: np.ndarray, block: np.ndarray) -> None:
        """Add a dense block to the iteration matrix being assembled (rows/cols global)."""
        np.add.at(self._data, self.positions(rows, cols), np.asarray(block, float).ravel())

    def multiplier_rows(self, constraint: Constraint) -> np.ndarray:
        """Multiplier indices (into lam) of the kept equations of ``constraint``."""
        for nl in self.nonlinear:
            if nl.constraint is constraint:
                out = np.full(constraint.n_equations, -1, np.int64)
                out[nl.keep] = nl.rows
                return out
        raise ModelError(f"constraint '{constraint.name}' is not part of this assembly")

    def _update_positions(self, nl: _NonlinearRows) -> None:
        c = nl.constraint
        nl.coords = np.asarray(c.coordinates(), np.int64)
        rows = self.n_coords + nl.rows
        cc = nl.coords
        nl.pos_jac = self.positions(rows, cc)
        nl.pos_jacT = self.positions(cc, rows).reshape(cc.size, rows.size).T.ravel()
        nl.pos_hess = self.positions(cc, cc)
        nl.version = getattr(c, "version", 0)

    def constraint_jacobian(self, q: np.ndarray, t: float = 0.0) -> sp.csr_matrix:
        """Phi_q as a sparse (n_mult, n_coords) matrix."""
        lin = self.lin_matrix.tocoo()
        rows, cols, vals = [lin.row], [lin.col], [lin.data]
        for nl in self.nonlinear:
            _, jac = nl.constraint.evaluate(q[nl.coords], t)
            jk = jac[nl.keep]
            rows.append(np.repeat(nl.rows, nl.coords.size))
            cols.append(np.tile(nl.coords, nl.rows.size))
            vals.append(jk.ravel())
        return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                             shape=(self.n_mult, self.n_coords))

    def constraint_values(self, q: np.ndarray, t: float) -> np.ndarray:
        out = np.zeros(self.n_mult)
        if self.m_lin:
            out[:self.m_lin] = self.lin_matrix @ q - self.lin_rhs0
            for row, fn in self.lin_functions:
                out[row] -= fn(t)
        for nl in self.nonlinear:
            phi, _ = nl.constraint.evaluate(q[nl.coords], t)
            out[nl.rows] = phi[nl.keep]
        return out

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
            _, phi_tt = nl.constraint.time_derivatives(q[nl.coords], t)
            out[nl.rows] -= phi_tt[nl.keep]
        return out

    def mass_matrix(self, q: np.ndarray) -> sp.csr_matrix:
        rows, cols, vals = [], [], []
        for grp in self.groups:
            d = grp.dofs
            rows.append(np.repeat(d, 12, axis=1).ravel())
            cols.append(np.tile(d, (1, 12)).ravel())
            vals.append(grp.mass_flat.ravel())
        bd = self.body_dof_table
        if bd.size:
            M = rb.mass_matrix(self.body_mass, self.body_inertia, q[bd[:, 3:]])
            rows.append(np.repeat(bd, 7, axis=1).ravel())
            cols.append(np.tile(bd, (1, 7)).ravel())
            vals.append(M.ravel())
        if not rows:
            return sp.csr_matrix((self.n_coords, self.n_coords))
        return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                             shape=(self.n_coords, self.n_coords))

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
            ve = v[grp.dofs]
            kin += 0.5 * float(np.einsum("ei,eij,ej->", ve, grp.mass, ve))
            strain += float(np.sum(cable.strain_energy(q[grp.dofs], grp.props, grp.rest, grp.options)))
        bd = self.body_dof_table
        if bd.size:
            vv = v[bd]
            kin += float(np.sum(rb.kinetic_energy(self.body_mass, self.body_inertia, q[bd[:, 3:]], vv)))
        grav = -float(self.gravity_vector @ (q - self.q_ref))
        return {"kinetic": kin, "strain": strain, "gravity": grav, "total": kin + strain + grav}

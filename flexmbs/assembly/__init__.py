"""Global assembly: the unknowns and the evaluation of the equations of motion of a model.

Unknowns: coordinates ``q`` (beams: per node the coordinates of its element layout, for the
cable [r, r']; rigid bodies: [r, p], 7 each) and Lagrange multipliers ``lam`` (one per
constraint equation). The dynamic residual follows the convention of docs/theory.md §I.0::

    r_q   = M(q) q'' + Q_int(q, q') + Phi_q^T lam - Q_ext(q, t)
    r_lam = Phi(q, t)

The iteration matrix ``[[cM M + cC C + cK K, Phi_q^T], [Phi_q, 0]]`` (``K`` includes the
constraint Hessian contracted with ``lam``) is stored in CSC form with a fixed pattern; every
refill writes ``data`` in place through precomputed position maps.

:class:`Assembly` holds the parts, each with one job: :mod:`.numbering` (the coordinates and
the reference configuration), :mod:`.rows` (the constraint equations as multiplier rows, the
redundancy check), :mod:`.external_loads` (the loads sorted for their owners), :mod:`.pattern`
(the sparsity pattern and data positions) and :mod:`.packing` (every owner of terms listed
once with its blocks and its packer); it evaluates the packed system through the driver.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp

from .. import driver
from ..constraints.drivers import JointDriver
from ..constraints.interaction import InteractionKind
from ..elements import rigid_body as rb
from ..elements.layout import BASE_RECORD, ElementType
from ..errors import FlexmbsError, ModelError, OffPlanError
from ..kernel import (
    OP_HOLD,
    OP_JACOBIAN,
    OP_POST_STEP,
    OP_REBASE,
    OP_RESIDUAL,
    OP_SET_BASES,
    kernel,
    prepare,
)
from ..model import Beam, Model, Node, RigidBody
from ..springs import spring_energy
from ..steploop import idle_run
from ..terms import FunctionTable, dynamic_mode, static_mode
from .external_loads import collect_loads
from .numbering import Numbering, length_scale
from .packing import BeamGroup, pack_system, term_owners
from .pattern import SparsePattern
from .rows import ConstraintRows, NonlinearRows

__all__ = ["ENERGIES", "Assembly", "BeamGroup", "NonlinearRows"]


#: the energies of :meth:`Assembly.energies` by name: the model's own, then the stored energy
#: each interaction kind declares on its record (``InteractionKind.energy``)
ENERGIES = ("total", "kinetic", "strain", "gravity", "spring",
            *(kind.energy[0] for kind in driver.INTERACTION_KINDS if kind.energy is not None))


class Assembly:
    """Numbering and global evaluation of a :class:`~flexmbs.model.Model`: holds its parts
    (:attr:`numbering`, :attr:`rows`, :attr:`loads`, :attr:`pattern`, the packed system) and is
    the :class:`~flexmbs.terms.PackContext` its owners of terms read."""

    def __init__(self, model: Model, *, redundant_constraints: str = "error",
                 rank_tolerance: float = 1e-9) -> None:
        if redundant_constraints not in ("error", "drop"):
            raise ModelError("redundant_constraints must be 'error' or 'drop'")
        self.model = model
        self.numbering = numbering = Numbering(model)
        self.n_coords = numbering.n_coords
        self.q_ref, self.v_init = numbering.q_ref, numbering.v_init
        self.q_free = numbering.q_free
        self._rest_fraction = 1.0      # relax_towards_stress_free: as packed
        self.beam_slices = numbering.beam_slices
        numbering.bind_interactions(self)
        self.length_scale = length_scale(model)
        self.rows = rows = ConstraintRows(model, numbering, redundant_constraints=redundant_constraints,
                                          rank_tolerance=rank_tolerance, length_scale=self.length_scale)
        self.n_mult = rows.n_mult
        self.n_total = self.n_coords + self.n_mult
        # the rows under the names the solvers, io and tests read
        self.m_lin, self.lin_matrix, self.lin_matrix_T = rows.m_lin, rows.lin_matrix, rows.lin_matrix_T
        self.lin_rhs0, self.lin_functions, self.nonlinear = rows.lin_rhs0, rows.lin_functions, rows.nonlinear
        self.multiplier_labels, self.multiplier_owner = rows.multiplier_labels, rows.multiplier_owner
        self.dropped_equations = rows.dropped_equations
        self.loads = loads = collect_loads(model, numbering)
        self.gravity_vector, self.f_const = loads.gravity_vector, loads.f_const
        self.functions = FunctionTable()
        owners = term_owners(model, numbering, rows, loads, self)
        self.pattern = SparsePattern(self.n_total, (b for owner in owners for b in owner.blocks))
        following = {kind.name for kind in driver.INTERACTION_KINDS if kind.follow is not None}
        self._fixed_blocks = [b for owner in owners if owner.field not in following
                              for b in owner.blocks]
        self.matrix, self.nnz = self.pattern.matrix, self.pattern.nnz
        self._data = self.matrix.data  # the array the matrix really holds
        packed = pack_system(owners, model, self)
        self.groups, self.system = packed.groups, packed.system
        #: the systems the model's own kernel receives (the kinds it lacks are None) and the
        #: complete kernel (every part and feature: SystemPart.complete); the kernel's argument,
        #: :attr:`kernel_system`, is one of them, chosen at the first call
        #: (:func:`flexmbs.kernel.prepare`)
        self.lean_system = self.kernel_system = packed.kernel_system
        self.complete_system = packed.complete_system
        self.joint_lists = packed.joint_lists
        self._python_terms = [obj for obj in model.interactions if obj.term_kind == ""]
        self.body_dof_table = self.system.bodies.dofs
        self._r = np.zeros(self.n_total)
        self.stiffness_scale = 0.0
        self._idle_run = idle_run()
        self._kernel_ready = False
        self._plans: dict[tuple[bool, bytes | None], Any] = {}
        self._window_index: list[tuple[np.ndarray, np.ndarray, np.ndarray, list]] | None = None
        self._window_mask: tuple[bytes, np.ndarray] | None = None   # _window_entries' last
        self._rows: list[tuple[InteractionKind, list[tuple[Any, np.ndarray]]]] | None = None
        n, m = self.n_coords, self.n_mult
        self.evaluate(self.q_ref, np.zeros(n), None, np.zeros(m), 0.0, np.zeros(n), np.zeros(m),
                      matrix=(0.0, 0.0, 1.0), with_damping=False)

    def relax_towards_stress_free(self, fraction: float) -> None:
        """The elements of the beams given a ``stress_free`` shape rest ``fraction`` of the way
        from their starting shapes to it (:meth:`~flexmbs.assembly.numbering.Numbering.
        rest_coordinates`; 1, as packed: the stress-free shapes): statics ramps it with the
        load factor, so that a pre-curved tube inserted straight is a path, not a jump. The
        element types' own rest state, recomputed and written into the packed parts."""
        if not self.numbering.prestressed or fraction == self._rest_fraction:
            return
        q = self.numbering.rest_coordinates(fraction)
        for spec, group in zip(self.numbering.groups, self.groups, strict=True):
            if not any(beam.stress_free is not None for beam in spec.beams):
                continue
            size = spec.element_type.layout.element_size
            fresh = spec.element_type.pack(spec.dofs, spec.props, spec.options, q,
                                           np.zeros((spec.dofs.shape[0], size * size), np.int64))
            for old, new in zip(group.part.rest, fresh.rest, strict=True):
                if isinstance(old, np.ndarray):
                    old[...] = new
        self._rest_fraction = float(fraction)

    # ================================================================== numbering (DofMap)
    def node_dofs(self, node: Node) -> np.ndarray:
        return self.numbering.node_dofs(node)

    def body_dofs(self, body: RigidBody) -> np.ndarray:
        return self.numbering.body_dofs(body)

    def beam_dofs(self, beam: Beam) -> np.ndarray:
        return self.numbering.beam_dofs(beam)

    def element_dofs(self, beam: Beam) -> np.ndarray:
        return self.numbering.element_dofs(beam)

    def extra_dofs(self, owner: object) -> np.ndarray:
        return self.numbering.extra_dofs(owner)

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

    def describe_coordinate(self, i: int) -> str:
        if i < self.n_coords:
            return self.numbering.coordinate_label(i)
        j = i - self.n_coords
        return self.multiplier_labels[j] if j < len(self.multiplier_labels) else f"equation {i}"

    def multiplier_rows(self, constraint: object) -> np.ndarray:
        """Multiplier indices (into lam) of the equations of ``constraint``, −1 if dropped."""
        return self.rows.multiplier_rows(constraint)

    # ================================================================== pattern (MatrixSink)
    def positions(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """CSC data positions of the (rows[i], cols[j]) block (must be in the pattern)."""
        return self.pattern.positions(rows, cols)

    def positions_present(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """As :meth:`positions`, with −1 for the entries outside the pattern."""
        return self.pattern.positions_present(rows, cols)

    def add_to_matrix(self, rows: np.ndarray, cols: np.ndarray, block: np.ndarray) -> None:
        """Add a dense block to the iteration matrix being assembled (rows/cols global)."""
        np.add.at(self._data, self.positions(rows, cols), np.asarray(block, float).ravel())

    def matrix_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        """CSC ``(indptr, indices)`` of the iteration matrix as int64 (what compiled code that
        reads ``data`` by column needs, e.g. :func:`flexmbs.driver.constraint_velocity`)."""
        return self.pattern.matrix_pattern()

    # ================================================================== evaluation
    def initial_state(self) -> tuple[np.ndarray, np.ndarray]:
        return self.q_ref.copy(), self.v_init.copy()

    def python_interactions(self) -> list[Any]:
        """Interactions evaluated by their Python path now: those of no compiled kind, and
        those of a switchable kind without a compiled form at the moment
        (:meth:`Interaction.compiled_form`). A query: :meth:`_sync_compiled_forms` is the
        command that switches the packed system to match it."""
        out = list(self._python_terms)
        for kind in driver.INTERACTION_KINDS:
            if kind.enable is not None:
                out += [obj for obj in self.joint_lists[kind.name] if not obj.compiled_form()]
        return out

    def _sync_compiled_forms(self) -> None:
        """Switch every interaction of a switchable kind on or off in the packed system as it
        has a compiled form now (a test may freeze a joint's detection between two calls).
        Every evaluation through the driver starts with it."""
        for kind in driver.INTERACTION_KINDS:
            if kind.enable is not None:
                part = getattr(self.system, kind.name)
                for i, obj in enumerate(self.joint_lists[kind.name]):
                    kind.enable(part, i, obj.compiled_form())

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
        self._sync_compiled_forms()
        python = self.python_interactions()
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
            if code and self.off_plan(code):
                err = self.system.error
                raise OffPlanError(str(self.error_exception(code, q, t)),
                                   (int(code), int(err[3]), int(err[2])))
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
            self.kernel_system = prepare(args, self.complete_system)
            args = (op, self.kernel_system, *args[2:])
            self._kernel_ready = True
        value, code = kernel(*args)
        return float(value), int(code)

    def post_step(self, q: np.ndarray, v: np.ndarray, t: float, qdd: np.ndarray | None = None,
                  acc: np.ndarray | None = None, lam: np.ndarray | None = None) -> None:
        """Interaction state after a converged step (may raise :class:`SimulationStopped`),
        then the nodal frames re-based where needed (docs/theory.md §I.2.4), which changes the
        twist entries of ``q, v`` and of ``qdd, acc`` (when given) in place. ``lam``: the
        step's multipliers (the sliding joint's friction cone needs its normal reaction;
        default zero)."""
        self._sync_compiled_forms()
        python = self.python_interactions()
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
        then the nodal frames re-based where tangents turned far (docs/theory.md §I.2.4; ``q``
        changed in place). Returns the number of re-based nodes; raises
        :class:`FlexmbsError` if a node turned past the frames' limit."""
        self._sync_compiled_forms()
        python = self.python_interactions()
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

    def hold_contacts(self, action: int) -> int:
        """The clearance joints' held active set for a Newton solve (``action`` one of
        :mod:`flexmbs.contact.clearance_term`'s ``HOLD_*``; :mod:`flexmbs.steploop`'s
        docstring): the points of the last evaluation at odds with the set for ``HOLD_READ``,
        else 0. A model without clearance joints holds nothing (0)."""
        z = np.zeros(self.n_coords)
        value, _ = self._kernel(OP_HOLD, z, z, np.zeros(0), np.zeros(self.n_mult),
                                self.functions.values(0.0), static_mode(1.0), self._r,
                                (float(action), 0.0, 0.0))
        return int(value)

    def begin(self, q: np.ndarray) -> None:
        """``q`` is where the next step (or static increment) starts: the reference of the
        history-dependent terms (the clearance contacts' sticking friction). The integrators
        and :func:`~flexmbs.solvers.static.solve_static` call it at their start; each converged
        step moves it on. The interactions' compiled forms are switched as they are now (the
        compiled integrator then runs without asking again)."""
        for kind in driver.INTERACTION_KINDS:
            if kind.begin is not None:
                kind.begin(getattr(self.system, kind.name), q)
        self._sync_compiled_forms()

    def node_bases(self) -> np.ndarray:
        """Every twisting node's current base: records ``[twist coordinate, t̄ (3), D̄ (3)]``
        (docs/theory.md §I.2.4; what a checkpoint carries)."""
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

    # ================================================================== factorisation
    def border_indices(self) -> np.ndarray:
        """Unknowns of the bordered banded LU's dense border (:mod:`flexmbs.linalg.bordered`):
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
        body's coordinates (the band order keeps them together), ``linalg.ordering.MASSLESS`` for the
        interactions' coordinates (a slide coordinate has no mass: never in the band beside a
        border), −1 otherwise (:func:`flexmbs.linalg.ordering.close_border`)."""
        from ..linalg.ordering import MASSLESS

        owner = np.full(self.n_total, -1, np.int64)
        table = self.body_dof_table
        owner[table.ravel()] = np.repeat(np.arange(table.shape[0]), table.shape[1])
        for obj in self.model.interactions:
            owner[np.asarray(self.extra_dofs(obj), np.int64)] = MASSLESS
        return owner

    def factor_plan(self, *, mass: bool = True, windows: np.ndarray | None = None,
                    border: np.ndarray | None = None, sparse: bool | None = None) -> Any:
        """The factorisation plan of the iteration matrix
        (:func:`flexmbs.linalg.ordering.plan_factorization` of this pattern with
        :meth:`border_indices` and :meth:`coordinate_owners`), computed once. ``mass``: the
        matrix has c_M M on every coordinate that has mass (dynamics, velocity corrector,
        initial accelerations); without (statics, stiffness only) every coordinate is labelled
        massless, which closes every nonempty border over the whole matrix (docs/design-notes.md,
        "One factorisation for every solver"). ``windows`` (:meth:`contact_windows`): a plan
        that follows the sliding and clearance joints, holding their own unknowns' entries
        with their beam only on those elements (the last one is kept); ``border``:
        with ``windows``, plan only that border (a re-plan keeps the border it had), or with
        ``sparse`` only the sparse LU (a re-plan of a sparse plan)."""
        from ..linalg.ordering import MASSLESS, plan_factorization

        key = (mass, None if windows is None else
               np.asarray(windows, np.int64).tobytes()
               + (b"" if border is None else b"|" + np.asarray(border, np.int64).tobytes())
               + (b"" if sparse is None else b"|s%d" % sparse))
        if key not in self._plans:
            owner = self.coordinate_owners()
            if not mass:
                owner[:self.n_coords] = MASSLESS
            keep = None if windows is None else self._window_entries(windows)
            if windows is not None:      # one following plan at a time
                for old in [k for k in self._plans if k[1] is not None]:
                    del self._plans[old]
            suggested = self.border_indices() if windows is None or border is None else border
            self._plans[key] = plan_factorization(
                self.matrix, suggested, self.n_coords, owner, keep,
                search=windows is None or border is None,
                sparse=sparse if windows is not None else None)
        return self._plans[key]

    def _following(self) -> list[tuple[InteractionKind, list[Any]]]:
        """The kinds whose members the plan may follow along their beams, with their members
        (:class:`~flexmbs.constraints.interaction.Following`), in :data:`driver.
        INTERACTION_KINDS` order."""
        return [(kind, self.joint_lists[kind.name]) for kind in driver.INTERACTION_KINDS
                if kind.follow is not None and self.joint_lists[kind.name]]

    def _window_rows(self) -> list[tuple[InteractionKind, list[tuple[Any, np.ndarray]]]]:
        """Per following kind its windows' rows, each (member, its own unknowns of the row):
        the order of the rows of :meth:`contact_windows` (a member has one row, a flexible
        tube one per element); built once."""
        if self._rows is None:
            self._rows = []
            for kind, objs in self._following():
                assert kind.follow is not None
                self._rows.append((kind, [(obj, np.unique(np.asarray(own, np.int64)))
                                          for obj in objs for own in kind.follow.own(obj, self)]))
        return self._rows

    def contact_windows(self, reach: int, widen: tuple[int, int, int] | None = None,
                        keep: np.ndarray | None = None) -> np.ndarray | None:
        """Per window row of the members of a following kind (the sliding joints, then the
        clearance joints; :meth:`_window_rows`) the elements ``[lo, hi)`` of its beam the plan
        holds its entries on: ``reach`` elements either side of where it is at the step's start
        (its current element; its sections' crossings), as ``(n_rows, 2)``; None without such
        members. ``widen = (code, row, element)``: a driver error that found the row's member
        outside its window there (the element is added); ``keep``: earlier windows that the
        new ones contain (a re-plan that failed again: the windows only grow)."""
        rows = self._window_rows()
        if not rows:
            return None
        out = []
        for kind, members in rows:
            assert kind.follow is not None
            w = kind.follow.current(getattr(self.system, kind.name), reach)
            if widen is not None and widen[0] == kind.follow.off_plan:
                j, e = widen[1], widen[2]
                lo, hi = (w[j] if w[j, 1] > w[j, 0] else (e, e + 1))
                w[j] = min(lo, max(e - reach, 0)), max(hi, e + reach + 1)
                w[j, 1] = min(w[j, 1], len(kind.follow.elements(members[j][0])))
            out.append(w)
        windows = np.ascontiguousarray(np.concatenate(out), dtype=np.int64)
        if keep is not None:
            empty = windows[:, 1] <= windows[:, 0]
            windows[:, 0] = np.where(empty, keep[:, 0], np.minimum(windows[:, 0], keep[:, 0]))
            windows[:, 1] = np.where(empty, keep[:, 1], np.maximum(windows[:, 1], keep[:, 1]))
        return windows

    def follow(self, windows: np.ndarray | None) -> None:
        """The elements the factorisation's plan holds every following member's entries on
        (:meth:`contact_windows`; None: its whole beam): a member's Jacobian outside its window
        reports its kind's ``off_plan`` code instead of writing entries the plan left out."""
        at = 0
        for kind, members in self._window_rows():
            part = getattr(self.system, kind.name)
            if windows is None:
                part.window[:, 0] = 0
                part.window[:, 1] = [len(kind.follow.elements(obj)) for obj, _ in members]   # type: ignore[union-attr]
            else:
                part.window[:] = windows[at:at + len(members)]
            at += len(members)
        zero = self.system.zero
        if windows is None or zero.size == 1:
            zero[0] = -1
        else:
            # the Jacobian clears only what the plan reads, and the multipliers' rows and
            # columns (the velocity corrector reads Φ_q whole: driver.constraint_velocity)
            at_ = np.flatnonzero(self._window_entries(windows) | self._multiplier_entries())
            zero[1:1 + at_.size] = at_
            zero[0] = at_.size

    def _multiplier_entries(self) -> np.ndarray:
        """The stored positions in a multiplier's row or column (a mask)."""
        A, n = self.matrix, self.n_coords
        cols = np.repeat(np.arange(self.n_total), np.diff(A.indptr))
        return (A.indices >= n) | (cols >= n)

    def off_plan(self, code: int) -> bool:
        """Whether a driver error ``code`` says a member left the elements the plan follows it
        on (:meth:`follow`): the step is to be retried after a new plan."""
        return any(kind.follow is not None and code == kind.follow.off_plan
                   for kind, _ in self._following())

    def _window_entries(self, windows: np.ndarray) -> np.ndarray:
        """The stored positions a plan following the members on ``windows`` reads: all but a
        row's own unknowns against its beam's coordinates outside its window's elements (zero
        while it is inside: only the elements it is on are written), unless another row whose
        own unknowns hold the entry's (another member with the same own unknowns and beam; a
        tube's neighbouring element, which shares a node) has them in its window, or an owner
        that does not follow reserved them. One pass over the candidate positions (a
        re-plan's set-up)."""
        key = np.asarray(windows, np.int64).tobytes()
        if self._window_mask is not None and self._window_mask[0] == key:
            return self._window_mask[1]
        if self._window_index is None:
            self._window_index = self._following_index()
        candidate = np.zeros(self.matrix.nnz, bool)
        covered = np.zeros(self.matrix.nnz, bool)
        windows = np.asarray(windows, np.int64)
        for pos, dloc, fixed, members in self._window_index:
            cov = fixed.copy()
            for i, first, last in members:
                lo, hi = windows[i]
                cov |= (first[dloc] < hi) & (last[dloc] >= lo)
            candidate[pos] = True
            covered[pos[cov]] = True
        mask = ~candidate | covered
        self._window_mask = (key, mask)
        return mask

    def _following_index(self) -> list[tuple[np.ndarray, np.ndarray, np.ndarray, list]]:
        """What :meth:`_window_entries` reads, built once: per group of rows with the same own
        unknowns and beam, the stored positions of their (own, beam) entries both ways, the
        beam coordinate of each (its place in the group's list), whether an owner that does
        not follow reserved it, and per row (its row in the windows) the first and last of
        its member's elements holding each coordinate (none: outside every window)."""
        groups: dict[tuple[bytes, int], tuple[np.ndarray, np.ndarray, list]] = {}
        spans: dict[tuple[int, bytes], tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        i = 0
        for kind, members in self._window_rows():
            assert kind.follow is not None
            for obj, own in members:
                elems = np.asarray(kind.follow.elements(obj), np.int64)
                span_key = (id(obj.beam), elems.tobytes())      # members of one beam share it
                if span_key not in spans:
                    dofs = np.unique(np.asarray(self.beam_dofs(obj.beam), np.int64))
                    local = np.searchsorted(dofs, np.where(elems >= 0, elems, dofs[0]))
                    e = np.repeat(np.arange(elems.shape[0], dtype=np.int64), elems.shape[1])
                    ok = (elems >= 0).ravel()
                    first = np.full(dofs.size, np.iinfo(np.int64).max, np.int64)
                    last = np.full(dofs.size, -1, np.int64)
                    np.minimum.at(first, local.ravel()[ok], e[ok])
                    np.maximum.at(last, local.ravel()[ok], e[ok])
                    spans[span_key] = (dofs, first, last)
                dofs, first, last = spans[span_key]
                key = (own.tobytes(), id(obj.beam))
                if key not in groups:
                    groups[key] = (own, dofs, [])
                groups[key][2].append((i, first, last))
                i += 1
        N = self.n_total
        is_own = np.zeros(N, bool)
        for own, _, _ in groups.values():
            is_own[own] = True
        fixed_keys = self._fixed_keys(is_own)
        out = []
        for own, dofs, members in groups.values():
            pos, dloc, keys = [], [], []
            for rows, cols, d_axis in ((own, dofs, 1), (dofs, own, 0)):
                p = self.pattern.positions_present(rows, cols).reshape(rows.size, cols.size)
                d = np.broadcast_to((np.arange(dofs.size)[None, :] if d_axis else
                                     np.arange(dofs.size)[:, None]), p.shape)
                k = (cols[None, :] * N + rows[:, None])
                ok = p >= 0
                pos.append(p[ok])
                dloc.append(d[ok])
                keys.append(k[ok])
            kk = np.concatenate(keys)
            at = np.minimum(np.searchsorted(fixed_keys, kk), max(fixed_keys.size - 1, 0))
            fixed = (fixed_keys[at] == kk) if fixed_keys.size else np.zeros(kk.size, bool)
            out.append((np.concatenate(pos), np.concatenate(dloc).astype(np.int64), fixed, members))
        return out

    def _fixed_keys(self, own: np.ndarray) -> np.ndarray:
        """The sorted keys ``col N + row`` of the entries in a row or column of the ``own``
        unknowns (a bool mask) that owners which do not follow their beams reserved (they stay
        in every plan)."""
        N = self.n_total
        keys = [np.zeros(0, np.int64)]
        for rows, cols in self._fixed_blocks:
            r, c = np.asarray(rows, np.int64), np.asarray(cols, np.int64)
            r_own, c_own = own[r], own[c]
            if r_own.any():
                keys.append((c[None, :] * N + r[r_own][:, None]).ravel())
            if c_own.any():
                keys.append((c[c_own][None, :] * N + r[:, None]).ravel())
        return np.unique(np.concatenate(keys))

    def _matrix_at(self, q: np.ndarray, t: float, cM: float) -> sp.csc_matrix:
        """The iteration matrix with ``cM`` M and no stiffness (Φ_q in its borders)."""
        n = self.n_coords
        data = np.zeros_like(self._data)
        q = np.ascontiguousarray(q, dtype=float)
        zeros = np.zeros(n)
        self._sync_compiled_forms()
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
        self._sync_compiled_forms()
        r = np.zeros(self.n_total)
        self._kernel(OP_RESIDUAL, q, zeros, zeros, np.zeros(self.n_mult),
                     self.functions.values(t), dynamic_mode(), r)
        return r[n:].copy()

    def constraint_velocity_terms(self, q: np.ndarray, t: float) -> np.ndarray:
        """Right-hand side ``−Phi_t`` of the velocity-level constraints ``Phi_q v = −Phi_t``
        (nonzero only for prescribed motion and drivers)."""
        return self.rows.velocity_terms(q, t)

    def velocity_rows(self) -> np.ndarray:
        """(n_mult,) 1.0 for the equations whose velocity form is ``Phi_q v = 0`` (no time in
        Phi), 0.0 for prescribed coordinates with a time function and drivers (``Phi_t != 0``,
        which the velocity corrector leaves as they are)."""
        return self.rows.velocity_rows()

    def has_nonlinear_constraints(self) -> bool:
        """Whether some kept equation is nonlinear in q (joints, Euler parameters, sliding)."""
        return bool(self.nonlinear)

    def constraint_time_terms(self, q: np.ndarray, v: np.ndarray, t: float) -> np.ndarray:
        """Right-hand side of the acceleration-level constraints,
        ``-(Phi_q v)_q v - 2 Phi_qt v - Phi_tt`` (docs/theory.md §I.6.1 INIT)."""
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

    def observe(self, q: np.ndarray, v: np.ndarray, lam: np.ndarray, t: float, *,
                after_step: bool = False) -> None:
        """An output's state ``(q, v, lam, t)``: the by-products of the kernel's residual at it
        go to the interactions (:attr:`~flexmbs.constraints.interaction.InteractionKind.
        observe`), whose output records (contact rows, section counts, contact energy) are then
        read from them instead of evaluated again: with ``after_step``, those of the last
        residual of the converged step that just left this state (the forces its equations
        held), else of one residual evaluated here. The steps' state is left as it was; any
        other state is evaluated as before."""
        kinds = [kind for kind in driver.INTERACTION_KINDS
                 if kind.observe is not None and self.joint_lists[kind.name]]
        q = np.ascontiguousarray(q, dtype=float)
        v = np.ascontiguousarray(v, dtype=float)

        def residual() -> None:
            _, code = self._kernel(OP_RESIDUAL, q, v, np.zeros_like(q),
                                   np.ascontiguousarray(lam, dtype=float),
                                   self.functions.values(t), dynamic_mode(), np.empty_like(self._r))
            if code:
                raise self.error_exception(code, q, t)

        if kinds and not after_step:
            self._sync_compiled_forms()
        for kind in kinds:
            assert kind.observe is not None
            kind.observe(getattr(self.system, kind.name), self.joint_lists[kind.name], q, v,
                         None if after_step else residual)

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

"""Compiled global residual of an :class:`~flexmbs.assembly.Assembly` (numba).

:func:`compile_model` packs everything the dynamic residual needs into a :class:`CompiledModel`
(named tuples of arrays, one part per kind of term); :func:`residual` evaluates

    r_q   = M q'' + Q_int(q, q') + Phi_q^T lam - Q_ext(q, t)
    r_lam = Phi(q, t)

exactly as :meth:`Assembly.evaluate` does (same kernels: ANCF cable, rigid-body inertia, joint
term tables, sliding joint, clearance joint), and :func:`post_step` updates the interactions'
state after a converged step (sliding element, contact warm starts and approach velocities).
Both run inside the compiled generalized-alpha loop (:mod:`flexmbs.solvers._compiled`), so a
Newton iteration never returns to Python. Time functions (loads, prescribed motion, axial
forces) are evaluated in Python per step and passed as a table of values ``fv``.

Models with parts that have no compiled form (several beam groups, superellipse bores,
constraint types other than the joints of :mod:`flexmbs.constraints.joints`) keep the Python
path; :func:`compile_model` then returns the reason as a string.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from ._jit import FLAG, njit
from .constraints.joints import (
    BeamNodeRigid,
    BeamNodeSpherical,
    EulerParameterNormalization,
    GenericJoint,
    TermTable,
    concatenate_tables,
    term_hessian,
    term_values,
)
from .constraints.sliding import (
    SlidingJoint,
    sliding_axial_force,
    sliding_hessian,
    sliding_values,
)
from .contact._detect import N_COLS, clearance_forces, clearance_update
from .contact.joint import SlidingClearanceJoint
from .contact.sections import CircleSection
from .elements import ancf_cable as cable
from .elements.rigid_body import _g, _inertial_kernel, _mm, point_tensor

if TYPE_CHECKING:  # pragma: no cover
    from .assembly import Assembly
    from .loads import TimeFunction

__all__ = ["CompiledModel", "compile_model", "residual", "jacobian", "post_step",
           "ERR_LEFT_BORE", "ERR_END_OF_BEAM"]

#: error codes of :func:`residual` / :func:`post_step` (detail in ``model.error``)
ERR_LEFT_BORE = 1      # clearance joint ``error[1]``: beam axis left the bore at section ``error[2]``
ERR_END_OF_BEAM = 2    # sliding joint ``error[1]`` reached the end of its beam


class BeamPart(NamedTuple):
    dofs: np.ndarray                 # (ne, 12)
    qe: np.ndarray                   # (ne, 12) work
    ve: np.ndarray
    force: np.ndarray
    mass: np.ndarray                 # (ne, 12, 12)
    props: cable.CableProperties
    rest: cable.CableRest
    scalar: int                      # 1: scalar-curvature bending
    empty: np.ndarray                # (0, 12, 12): no tangent in the residual


class BodyPart(NamedTuple):
    dofs: np.ndarray                 # (nb, 7)
    mass: np.ndarray                 # (nb,)
    inertia: np.ndarray              # (nb, 3, 3)
    p: np.ndarray                    # (nb, 4) work
    pd: np.ndarray
    qdd: np.ndarray                  # (nb, 7) work
    res: np.ndarray                  # (nb, 7) work
    dq: np.ndarray                   # (nb, 7, 7) work
    dv: np.ndarray
    load_dofs: np.ndarray            # (nl, 7) body point loads
    load_T: np.ndarray               # (nl, 3, 4, 4) point tensor of the load point
    load_force: np.ndarray           # (nl, 3)
    load_moment: np.ndarray          # (nl, 3) (zeros: no moment)
    load_fn: np.ndarray              # (nl,) time-function index


class LinearPart(NamedTuple):
    indptr: np.ndarray               # CSR of the linear constraint rows
    indices: np.ndarray
    data: np.ndarray
    rhs0: np.ndarray
    fn_row: np.ndarray               # prescribed rows ...
    fn_idx: np.ndarray               # ... and their time functions


class LoadPart(NamedTuple):
    f_const: np.ndarray              # (n,) constant external forces (gravity, constant loads)
    idx: np.ndarray                  # timed loads, flattened: coordinate, value, time function
    val: np.ndarray
    fn: np.ndarray


class NormPart(NamedTuple):
    coords: np.ndarray               # (k, 4) Euler parameters of a body
    rows: np.ndarray                 # (k,) multiplier


class TermPart(NamedTuple):
    table: TermTable                 # all joint equations (constraints.joints)
    eq_ptr: np.ndarray               # (nc + 1,) equations of constraint c
    coord_ptr: np.ndarray            # (nc + 1,) coordinates of constraint c in ``coords``
    coords: np.ndarray
    rows: np.ndarray                 # (n_eq,) multiplier of each equation, -1 if dropped
    ql: np.ndarray                   # work
    phi: np.ndarray
    jac: np.ndarray


class SlidingPart(NamedTuple):
    body: np.ndarray                 # (nj, 7)
    elem_dofs: np.ndarray            # (nj, max_ne, 12)
    lengths: np.ndarray              # (nj, max_ne)
    starts: np.ndarray               # (nj, max_ne)
    n_elem: np.ndarray               # (nj,)
    total: np.ndarray                # (nj,) beam length
    s_dof: np.ndarray                # (nj,)
    T: np.ndarray                    # (nj, 3, 3, 4, 4) point tensors of u_C, y, z
    n_eq: np.ndarray                 # (nj,) 3 ring, 5 cylindrical
    rows: np.ndarray                 # (nj, 5) multipliers, -1 dropped
    mu: np.ndarray
    eps_v: np.ndarray
    fn: np.ndarray                   # (nj,) axial-force time function, -1 none
    element: np.ndarray              # (nj,) state: current element
    ql: np.ndarray                   # (20,) work
    phi: np.ndarray
    jac: np.ndarray


class ClearancePart(NamedTuple):
    body: np.ndarray                 # (nj, 7)
    elem_dofs: np.ndarray            # (nj, max_ne, 12)
    n_elem: np.ndarray
    lengths: np.ndarray              # (nj, max_ne)
    hole_point: np.ndarray           # (nj, 3)
    stations: np.ndarray             # (nj, max_ns)
    n_sec: np.ndarray
    r_b: np.ndarray
    R: np.ndarray
    law: np.ndarray                  # (nj, 5)
    mu: np.ndarray
    eps_v: np.ndarray
    elem_ws: np.ndarray              # (nj, max_ns) state: warm starts
    xi_ws: np.ndarray
    approach: np.ndarray             # (nj, max_ns, P) state: tracked contacts (approach
    active: np.ndarray               # (nj, max_ns, P)   velocity, in use, section angle)
    psi: np.ndarray                  # (nj, max_ns, P)
    qe: np.ndarray                   # (max_ne, 12) work
    rows: np.ndarray                 # (nj, 4 max_ns, N_COLS): candidates of the last residual
    count: np.ndarray                # (nj,) their number
    elem_out: np.ndarray             # (nj, max_ns): section crossings of the last residual
    xi_out: np.ndarray
    K: np.ndarray                    # (0, 19, 19): no tangent in the residual
    kelem: np.ndarray                # (0,)


class JacobianPart(NamedTuple):
    """CSC data positions of every term of the iteration matrix (pattern of ``asm.matrix``)."""

    const: np.ndarray                # (nnz,) constant entries (linear constraint rows)
    beam_pos: np.ndarray             # (ne, 144)
    beam_mass: np.ndarray            # (ne, 144)
    stiff: np.ndarray                # (ne, 12, 12) work
    damp: np.ndarray
    body_pos: np.ndarray             # (nb, 49)
    load_body: np.ndarray            # (nl,) body of each body load
    norm_jac: np.ndarray             # (k, 4) Phi_q, Phi_q^T and Hessian positions
    norm_jacT: np.ndarray
    norm_hess: np.ndarray            # (k, 16)
    term_jptr: np.ndarray            # (nc + 1,) into term_jac / term_jacT (kept rows x coords)
    term_jac: np.ndarray
    term_jacT: np.ndarray
    term_hptr: np.ndarray            # (nc + 1,) into term_hess (coords x coords)
    term_hess: np.ndarray
    term_H: np.ndarray               # work (max_nl, max_nl)
    term_lam: np.ndarray             # work (max_ne,)
    sl_jac: np.ndarray               # (nj, max_ne, 5, 20): per element; -1 for dropped rows
    sl_jacT: np.ndarray
    sl_hess: np.ndarray              # (nj, max_ne, 400)
    sl_s_elem: np.ndarray            # (nj, max_ne, 12): friction / axial force row of s
    sl_ss: np.ndarray                # (nj,)
    sl_s_lam: np.ndarray             # (nj, 3)
    sl_H: np.ndarray                 # work (20, 20)
    cl_pos: np.ndarray               # (nj, max_ne, 361): (body, element) blocks
    cl_K: np.ndarray                 # work (4 max_ns, 19, 19)
    cl_C: np.ndarray
    cl_elem: np.ndarray              # work (4 max_ns,)


class CompiledModel(NamedTuple):
    n: int                           # coordinates
    m: int                           # multipliers
    beam: BeamPart
    body: BodyPart
    lin: LinearPart
    load: LoadPart
    norm: NormPart
    term: TermPart
    sliding: SlidingPart
    clearance: ClearancePart
    jac: JacobianPart
    scratch: np.ndarray              # (n + m,) residual written while assembling the matrix
    error: np.ndarray                # (3,) [code, object, detail] of the last error


# ================================================================================ packing
class _Functions:
    """Time functions of the model, numbered in first-use order."""

    def __init__(self) -> None:
        self.items: list[TimeFunction] = []
        self._index: dict[int, int] = {}

    def __call__(self, fn: TimeFunction) -> int:
        key = id(fn)
        if key not in self._index:
            self._index[key] = len(self.items)
            self.items.append(fn)
        return self._index[key]


def _i64(a: object, shape: tuple[int, ...] | None = None) -> np.ndarray:
    out = np.ascontiguousarray(np.asarray(a, dtype=np.int64))
    return out.reshape(shape) if shape is not None else out


def _f64(a: object, shape: tuple[int, ...] | None = None) -> np.ndarray:
    out = np.ascontiguousarray(np.asarray(a, dtype=float))
    return out.reshape(shape) if shape is not None else out


def _pad(arrays: list[np.ndarray], tail: tuple[int, ...], fill: float | int,
         dtype: type) -> np.ndarray:
    """Stack arrays ``(n_i, *tail)`` into ``(len, max n_i, *tail)``, padded with ``fill``."""
    n = max((a.shape[0] for a in arrays), default=0)
    out = np.full((len(arrays), n) + tail, fill, dtype=dtype)
    for i, a in enumerate(arrays):
        out[i, :a.shape[0]] = np.asarray(a).reshape((a.shape[0],) + tail)
    return out


def _rows_of(asm: Assembly, constraint: object) -> np.ndarray:
    for nl in asm.nonlinear:
        if nl.constraint is constraint:
            out = np.full(nl.constraint.n_equations, -1, np.int64)
            out[nl.keep] = nl.rows
            return out
    return np.full(getattr(constraint, "n_equations", 0), -1, np.int64)


def compile_model(asm: Assembly) -> tuple[CompiledModel | None, list[TimeFunction], str]:
    """Pack ``asm`` for :func:`residual`: ``(model, time_functions, "")``, or
    ``(None, [], reason)`` when a part has no compiled form."""
    if len(asm.groups) != 1:
        return None, [], ("the compiled path needs exactly one beam group (all beams with the "
                          f"same CableOptions); this model has {len(asm.groups)}")
    fns = _Functions()
    n, mm = asm.n_coords, asm.n_mult

    g = asm.groups[0]
    beam = BeamPart(g.dofs, g.qe, g.ve, g.force, g.mass, g.props, g.rest,
                    1 if g.options.bending == "scalar" else 0, np.zeros((0, 12, 12)))

    nb = asm.body_dof_table.shape[0]
    loads = asm.body_loads
    body = BodyPart(
        _i64(asm.body_dof_table, (nb, 7)), _f64(asm.body_mass), _f64(asm.body_inertia, (nb, 3, 3)),
        np.zeros((nb, 4)), np.zeros((nb, 4)), np.zeros((nb, 7)), np.zeros((nb, 7)),
        np.zeros((nb, 7, 7)), np.zeros((nb, 7, 7)),
        _i64([d for d, *_ in loads], (len(loads), 7)),
        _f64([point_tensor(pt) for _, pt, *_ in loads], (len(loads), 3, 4, 4)),
        _f64([f for _, _, f, _, _ in loads], (len(loads), 3)),
        _f64([np.zeros(3) if mo is None else mo for _, _, _, mo, _ in loads], (len(loads), 3)),
        _i64([fns(fn) for *_, fn in loads]))

    L = asm.lin_matrix
    lin = LinearPart(_i64(L.indptr), _i64(L.indices), _f64(L.data), _f64(asm.lin_rhs0),
                     _i64([row for row, _ in asm.lin_functions]),
                     _i64([fns(fn) for _, fn in asm.lin_functions]))

    idx, val, fidx = [], [], []
    for i, v, fn in asm.f_timed:
        k = fns(fn)
        idx.append(np.asarray(i, np.int64).ravel())
        val.append(np.asarray(v, float).ravel())
        fidx.append(np.full(np.asarray(i).size, k, np.int64))
    load = LoadPart(_f64(asm.f_const), _i64(np.concatenate(idx) if idx else []),
                    _f64(np.concatenate(val) if val else []),
                    _i64(np.concatenate(fidx) if fidx else []))

    norm_c, norm_r = [], []
    tables, t_coords, t_rows = [], [], []
    sliding_constraints = {id(j._constraint): j for j in asm.model.interactions
                           if isinstance(j, SlidingJoint)}
    for nl in asm.nonlinear:
        c = nl.constraint
        if isinstance(c, EulerParameterNormalization):
            norm_c.append(nl.coords)
            norm_r.append(int(nl.rows[0]))
        elif isinstance(c, (GenericJoint, BeamNodeSpherical, BeamNodeRigid)):
            tables.append(c.table)
            t_coords.append(np.asarray(nl.coords, np.int64))
            t_rows.append(_rows_of(asm, c))
        elif id(c) not in sliding_constraints:
            return None, [], f"constraint '{c.name}' ({type(c).__name__}) has no compiled form"
    norm = NormPart(_i64(norm_c, (len(norm_c), 4)), _i64(norm_r))
    term = _pack_terms(tables, t_coords, t_rows)

    slides = [j for j in asm.model.interactions if isinstance(j, SlidingJoint)]
    clears = [j for j in asm.model.interactions if isinstance(j, SlidingClearanceJoint)]
    for j in asm.model.interactions:
        if not isinstance(j, (SlidingJoint, SlidingClearanceJoint)):
            return None, [], f"interaction '{j.name}' ({type(j).__name__}) has no compiled form"
    for j in clears:
        if not isinstance(j.hole.section, CircleSection):
            return None, [], (f"joint '{j.name}': only circular bores have a compiled detector "
                              f"(got {type(j.hole.section).__name__})")
    sliding = _pack_sliding(asm, slides, fns)
    clearance = _pack_clearance(clears)
    for j in clears:
        if j.consistent:
            return None, [], (f"joint '{j.name}': the consistent contact tangent has no compiled "
                              "form (use the default Gauss-Newton tangent, or compiled=False)")
    jac = _pack_jacobian(asm, slides, clears)
    model = CompiledModel(n, mm, beam, body, lin, load, norm, term, sliding, clearance, jac,
                          np.zeros(n + mm), np.zeros(3, np.int64))
    return model, fns.items, ""


def _pack_jacobian(asm: Assembly, slides: list[SlidingJoint],
                   clears: list[SlidingClearanceJoint]) -> JacobianPart:
    g = asm.groups[0]
    ne = g.dofs.shape[0]
    nb = asm.body_dof_table.shape[0]
    body_pos = asm._body_pos if nb else np.zeros((0, 49), np.int64)
    first = {int(d[0]): i for i, d in enumerate(asm.body_dof_table)}
    load_body = _i64([first[int(d[0])] for d, *_ in asm.body_loads])
    norm = [nl for nl in asm.nonlinear if isinstance(nl.constraint, EulerParameterNormalization)]
    terms = [nl for nl in asm.nonlinear
             if isinstance(nl.constraint, (GenericJoint, BeamNodeSpherical, BeamNodeRigid))]
    # term constraints: kept rows x coords (row-major), as Assembly.evaluate writes them
    jptr = np.zeros(len(terms) + 1, np.int64)
    hptr = np.zeros(len(terms) + 1, np.int64)
    tj, tjt, th = [], [], []
    for i, nl in enumerate(terms):
        tj.append(nl.pos_jac)
        tjt.append(nl.pos_jacT)
        th.append(nl.pos_hess)
        jptr[i + 1] = jptr[i] + nl.pos_jac.size
        hptr[i + 1] = hptr[i] + nl.pos_hess.size
    max_nl = max((nl.coords.size for nl in terms), default=0)
    max_ne = max((nl.constraint.n_equations for nl in terms), default=0)
    # sliding joints: positions for every element the slide point can be on
    nsj = len(slides)
    max_el = max((len(j._lengths) for j in slides), default=0)
    sl_jac = np.full((nsj, max_el, 5, 20), -1, np.int64)
    sl_jacT = np.full((nsj, max_el, 5, 20), -1, np.int64)
    sl_hess = np.zeros((nsj, max_el, 400), np.int64)
    sl_s_elem = np.zeros((nsj, max_el, 12), np.int64)
    sl_ss = np.zeros(nsj, np.int64)
    sl_s_lam = np.zeros((nsj, 3), np.int64)
    n = asm.n_coords
    for i, j in enumerate(slides):
        rows_full = _rows_of(asm, j._constraint)
        kept = np.flatnonzero(rows_full >= 0)
        sd = np.array([j._s_dof])
        for k in range(len(j._lengths)):
            cc = np.concatenate([j._body_dofs, j._elem_dofs[k], sd])
            if kept.size:
                rr = n + rows_full[kept]
                sl_jac[i, k, kept] = asm.positions(rr, cc).reshape(kept.size, 20)
                sl_jacT[i, k, kept] = asm.positions(cc, rr).reshape(20, kept.size).T
            sl_hess[i, k] = asm.positions(cc, cc)
            sl_s_elem[i, k] = asm.positions(sd, j._elem_dofs[k])
        sl_ss[i] = asm.positions(sd, sd)[0]
        if (j.friction > 0.0 or j.axial_force is not None) and np.all(rows_full[:3] >= 0):
            sl_s_lam[i] = asm.positions(sd, n + rows_full[:3])
    ncj = len(clears)
    max_ce = max((len(j._lengths) for j in clears), default=0)
    max_ns = max((len(j.stations) for j in clears), default=0)
    cl_pos = np.zeros((ncj, max_ce, 361), np.int64)
    for i, j in enumerate(clears):
        for k in range(len(j._lengths)):
            cl_pos[i, k] = j._block_positions(asm, k)
    return JacobianPart(
        np.ascontiguousarray(asm._const_data), _i64(g.pos), np.ascontiguousarray(g.mass_flat),
        np.zeros((ne, 12, 12)), np.zeros((ne, 12, 12)), _i64(body_pos, (nb, 49)), load_body,
        _i64([nl.pos_jac for nl in norm], (len(norm), 4)),
        _i64([nl.pos_jacT for nl in norm], (len(norm), 4)),
        _i64([nl.pos_hess for nl in norm], (len(norm), 16)),
        jptr, _i64(np.concatenate(tj) if tj else []), _i64(np.concatenate(tjt) if tjt else []),
        hptr, _i64(np.concatenate(th) if th else []), np.zeros((max_nl, max_nl)),
        np.zeros(max_ne), sl_jac, sl_jacT, sl_hess, sl_s_elem, sl_ss, sl_s_lam,
        np.zeros((20, 20)), cl_pos, np.zeros((4 * max_ns, 19, 19)),
        np.zeros((4 * max_ns, 19, 19)), np.zeros(4 * max_ns, np.int64))


def _pack_terms(tables: list[TermTable], coords: list[np.ndarray],
                rows: list[np.ndarray]) -> TermPart:
    if tables:
        table, eq_ptr = concatenate_tables(tables)
    else:
        table = TermTable(np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros((0, 3)),
                          np.zeros((0, 3, 4, 4)), np.zeros(0, np.int64), np.zeros((0, 4), np.int64),
                          np.zeros((0, 3)))
        eq_ptr = np.zeros(1, np.int64)
    cptr = np.zeros(len(coords) + 1, np.int64)
    cptr[1:] = np.cumsum([c.size for c in coords])
    max_nl = max((c.size for c in coords), default=0)
    max_ne = int(np.max(np.diff(eq_ptr), initial=0))
    return TermPart(table, _i64(eq_ptr), cptr, _i64(np.concatenate(coords) if coords else []),
                    _i64(np.concatenate(rows) if rows else []), np.zeros(max_nl),
                    np.zeros(max_ne), np.zeros((max_ne, max_nl)))


def _pack_sliding(asm: Assembly, joints: list[SlidingJoint], fns: _Functions) -> SlidingPart:
    nj = len(joints)
    rows = np.full((nj, 5), -1, np.int64)
    for i, j in enumerate(joints):
        r = _rows_of(asm, j._constraint)
        rows[i, :r.size] = r
    return SlidingPart(
        _i64([j._body_dofs for j in joints], (nj, 7)),
        _pad([j._elem_dofs for j in joints], (12,), 0, np.int64),
        _pad([j._lengths for j in joints], (), 1.0, float),
        _pad([j._starts for j in joints], (), 0.0, float),
        _i64([len(j._lengths) for j in joints]), _f64([j._total for j in joints]),
        _i64([j._s_dof for j in joints]), _f64([j._T_all for j in joints], (nj, 3, 3, 4, 4)),
        _i64([j._constraint.n_equations for j in joints]), rows,
        _f64([j.friction for j in joints]), _f64([j.friction_velocity for j in joints]),
        _i64([-1 if j.axial_force is None else fns(j.axial_force) for j in joints]),
        _i64([j.element for j in joints]), np.zeros(20), np.zeros(5), np.zeros((5, 20)))


def _pack_clearance(joints: list[SlidingClearanceJoint]) -> ClearancePart:
    nj = len(joints)
    max_ne = max((len(j._lengths) for j in joints), default=0)
    max_ns = max((len(j.stations) for j in joints), default=0)
    width = joints[0]._approach.shape[1] if joints else 1
    fr = [j._friction_parameters() for j in joints]
    return ClearancePart(
        _i64([j._body_dofs for j in joints], (nj, 7)),
        _pad([j._elem_dofs for j in joints], (12,), 0, np.int64),
        _i64([len(j._lengths) for j in joints]),
        _pad([j._lengths for j in joints], (), 1.0, float),
        _f64([j.hole_point for j in joints], (nj, 3)),
        _pad([j.stations for j in joints], (), 0.0, float),
        _i64([len(j.stations) for j in joints]), _f64([j.beam_radius for j in joints]),
        _f64([float(j.hole.section.radius) for j in joints]),
        _f64([j.contact.parameters() for j in joints], (nj, 5)),
        _f64([m for m, _ in fr]), _f64([e for _, e in fr]),
        _pad([j._elem for j in joints], (), 0, np.int64),
        _pad([j._xi for j in joints], (), 0.5, float),
        _pad([j._approach for j in joints], (width,), 0.0, float),
        _pad([j._active for j in joints], (width,), False, np.bool_),
        _pad([j._psi for j in joints], (width,), 0.0, float),
        np.zeros((max_ne, 12)), np.zeros((nj, 4 * max_ns, N_COLS)), np.zeros(nj, np.int64),
        np.zeros((nj, max_ns), np.int64), np.zeros((nj, max_ns)), np.zeros((0, 19, 19)),
        np.zeros(0, np.int64))


def push_state(model: CompiledModel, asm: Assembly) -> None:
    """Copy the interactions' state (Python objects) into the compiled arrays."""
    for i, j in enumerate(j for j in asm.model.interactions if isinstance(j, SlidingJoint)):
        model.sliding.element[i] = j.element
    c = model.clearance
    for i, j in enumerate(j for j in asm.model.interactions
                          if isinstance(j, SlidingClearanceJoint)):
        ns = len(j.stations)
        c.elem_ws[i, :ns] = j._elem
        c.xi_ws[i, :ns] = j._xi
        c.approach[i, :ns] = j._approach
        c.active[i, :ns] = j._active
        c.psi[i, :ns] = j._psi


def pull_state(model: CompiledModel, asm: Assembly) -> None:
    """Copy the compiled interaction state back into the Python objects."""
    for i, j in enumerate(j for j in asm.model.interactions if isinstance(j, SlidingJoint)):
        j.element = int(model.sliding.element[i])
    c = model.clearance
    for i, j in enumerate(j for j in asm.model.interactions
                          if isinstance(j, SlidingClearanceJoint)):
        ns = len(j.stations)
        j._elem[:] = c.elem_ws[i, :ns]
        j._xi[:] = c.xi_ws[i, :ns]
        j._approach[:] = c.approach[i, :ns]
        j._active[:] = c.active[i, :ns]
        j._psi[:] = c.psi[i, :ns]


def time_function_values(functions: list[TimeFunction], t0: float, h: float,
                         n_steps: int) -> np.ndarray:
    """``fv[k, i] = functions[i](t0 + (k + 1) h)``: the values at the end of every step."""
    out = np.empty((n_steps, len(functions)))
    for k in range(n_steps):
        t = t0 + (k + 1) * h
        for i, fn in enumerate(functions):
            out[k, i] = fn(t)
    return out


# ================================================================================ kernels
@njit
def _e_hat_times(y, p, out):  # noqa: ANN001, ANN202
    """out = Ê(y) p with Ê(y) = [[0, −yᵀ], [y, ỹ]] (FORMULATION I §5)."""
    out[0] = -(y[0] * p[1] + y[1] * p[2] + y[2] * p[3])
    out[1] = y[0] * p[0] + (-y[2] * p[2] + y[1] * p[3])
    out[2] = y[1] * p[0] + (y[2] * p[1] - y[0] * p[3])
    out[3] = y[2] * p[0] + (-y[1] * p[1] + y[0] * p[2])


@njit
def _bodies(b, q, v, qdd, fv, r):  # noqa: ANN001, ANN202
    scale = 0.0
    nb = b.dofs.shape[0]
    if nb == 0:
        return scale
    _body_inertia(b, q, v, qdd)
    for i in range(nb):
        for k in range(7):
            r[b.dofs[i, k]] += b.res[i, k]
            if abs(b.res[i, k]) > scale:
                scale = abs(b.res[i, k])
    Q = np.empty(7)
    Qm = np.empty(4)
    F = np.empty(3)
    for i in range(b.load_dofs.shape[0]):
        d = b.load_dofs[i]
        f = fv[b.load_fn[i]]
        p = np.empty(4)
        for k in range(4):
            p[k] = q[d[3 + k]]
        for c in range(3):
            F[c] = f * b.load_force[i, c]
            Q[c] = F[c]
        # Q_p = 2 C(s', F) p, C = sum_k F_k T_k(s')  (applied_force)
        for a in range(4):
            acc = 0.0
            for bb in range(4):
                cab = 0.0
                for c in range(3):
                    cab += F[c] * b.load_T[i, c, a, bb]
                acc += cab * p[bb]
            Q[3 + a] = 2.0 * acc
        mo = b.load_moment[i]
        if mo[0] != 0.0 or mo[1] != 0.0 or mo[2] != 0.0:
            _e_hat_times(f * mo, p, Qm)
            for a in range(4):
                Q[3 + a] += 2.0 * Qm[a]
        for k in range(7):
            r[d[k]] -= Q[k]
            if abs(Q[k]) > scale:
                scale = abs(Q[k])
    return scale


@njit(inline="always")
def _gather_beam(bm, q, v):  # noqa: ANN001, ANN202
    for e in range(bm.dofs.shape[0]):
        for k in range(12):
            bm.qe[e, k] = q[bm.dofs[e, k]]
            bm.ve[e, k] = v[bm.dofs[e, k]]


@njit(inline="always")
def _body_inertia(b, q, v, qdd):  # noqa: ANN001, ANN202
    """Gather [p, p', q''] of every body and evaluate the inertial residual and its derivatives."""
    for i in range(b.dofs.shape[0]):
        for k in range(4):
            b.p[i, k] = q[b.dofs[i, 3 + k]]
            b.pd[i, k] = v[b.dofs[i, 3 + k]]
        for k in range(7):
            b.qdd[i, k] = qdd[b.dofs[i, k]]
    _inertial_kernel(b.mass, b.inertia, b.p, b.pd, b.qdd, b.res, b.dq, b.dv)


@njit(inline="always")
def _term_constraint(tm, c, q):  # noqa: ANN001, ANN202
    """Φ, Φ_q of joint c into ``tm.phi``, ``tm.jac``; returns (first coordinate, coordinates,
    first equation, end of equations)."""
    c0 = tm.coord_ptr[c]
    nloc = tm.coord_ptr[c + 1] - c0
    for k in range(nloc):
        tm.ql[k] = q[tm.coords[c0 + k]]
    e0 = tm.eq_ptr[c]
    e1 = tm.eq_ptr[c + 1]
    term_values(tm.table, e0, e1, tm.ql[:nloc], tm.phi, tm.jac[:, :nloc])
    return c0, nloc, e0, e1


@njit(inline="always")
def _sliding_constraint(sl, j, q):  # noqa: ANN001, ANN202
    """Φ, Φ_q of sliding joint j on its current element; returns (element, its dofs, s dof,
    equations)."""
    k = sl.element[j]
    ed = sl.elem_dofs[j, k]
    for a in range(7):
        sl.ql[a] = q[sl.body[j, a]]
    for a in range(12):
        sl.ql[7 + a] = q[ed[a]]
    sd = sl.s_dof[j]
    sl.ql[19] = q[sd]
    ne_j = sl.n_eq[j]
    sliding_values(sl.ql, sl.lengths[j, k], sl.starts[j, k], sl.T[j], ne_j, sl.phi, sl.jac)
    return k, ed, sd, ne_j


@njit(inline="always")
def _sliding_force(sl, j, k, sd, q, v, lam, fv):  # noqa: ANN001, ANN202
    """Axial and friction force on s of sliding joint j (:func:`sliding_axial_force`)."""
    lp = np.zeros(3)
    for a in range(3):
        if sl.rows[j, a] >= 0:
            lp[a] = lam[sl.rows[j, a]]
    f_ax = fv[sl.fn[j]] if sl.fn[j] >= 0 else 0.0
    return sliding_axial_force(sl.ql[7:19], sl.lengths[j, k], sl.starts[j, k], q[sd], v[sd], lp,
                               sl.mu[j], sl.eps_v[j], f_ax)


@njit(inline="always")
def _clearance(model, j, q, v, want_tangent, r, K, C, elem):  # noqa: ANN001, ANN202
    """:func:`clearance_forces` of clearance joint j; records the candidates' count and, if the
    beam axis left the bore, the error. Returns (candidates, contacts, scale)."""
    cl = model.clearance
    ne_j = cl.n_elem[j]
    ns = cl.n_sec[j]
    m, cnt, sc = clearance_forces(
        q, v, cl.body[j], cl.elem_dofs[j, :ne_j], cl.lengths[j, :ne_j], cl.hole_point[j],
        cl.stations[j, :ns], cl.elem_ws[j, :ns], cl.xi_ws[j, :ns], cl.elem_out[j, :ns],
        cl.xi_out[j, :ns], cl.r_b[j], cl.R[j], cl.law[j], cl.mu[j], cl.eps_v[j],
        cl.approach[j, :ns], cl.active[j, :ns], cl.psi[j, :ns], cl.qe, cl.rows[j], want_tangent,
        r, K, C, elem)
    cl.count[j] = m
    if m < 0:
        model.error[0] = ERR_LEFT_BORE
        model.error[1] = j
        model.error[2] = -1 - m
    return m, cnt, sc


@njit
def residual(model, q, v, qdd, lam, fv, r):  # noqa: ANN001, ANN201, C901, PLR0912, PLR0915
    """``r = [r_q; r_lam]`` of the dynamic equations (see the module docstring); returns
    ``(scale, error)`` with the force scale of :meth:`Assembly.evaluate` (largest single force
    entering ``r_q``) and an error code (0: none; details in ``model.error``)."""
    n = model.n
    ld = model.load
    for i in range(n):
        r[i] = -ld.f_const[i]
    for k in range(ld.idx.size):
        r[ld.idx[k]] -= fv[ld.fn[k]] * ld.val[k]
    scale = 0.0
    for i in range(n):
        if abs(r[i]) > scale:
            scale = abs(r[i])
    # ---- beams
    bm = model.beam
    ne = bm.dofs.shape[0]
    _gather_beam(bm, q, v)
    cable._internal_kernel(bm.qe, bm.ve, bm.props, bm.rest, bm.scalar, FLAG[0], FLAG[0], bm.force,
                           bm.empty, bm.empty)
    for e in range(ne):
        for i in range(12):
            s = bm.force[e, i]
            if abs(s) > scale:
                scale = abs(s)
            acc = 0.0
            for j in range(12):
                acc += bm.mass[e, i, j] * qdd[bm.dofs[e, j]]
            if abs(acc) > scale:
                scale = abs(acc)
            r[bm.dofs[e, i]] += s + acc
    # ---- rigid bodies and their loads
    scale = max(scale, _bodies(model.body, q, v, qdd, fv, r))
    # ---- linear constraints
    li = model.lin
    for row in range(li.rhs0.size):
        acc = -li.rhs0[row]
        lr = lam[row]
        for k in range(li.indptr[row], li.indptr[row + 1]):
            c = li.indices[k]
            acc += li.data[k] * q[c]
            r[c] += li.data[k] * lr
        r[n + row] = acc
    for k in range(li.fn_row.size):
        r[n + li.fn_row[k]] -= fv[li.fn_idx[k]]
    # ---- Euler-parameter normalisation
    nm = model.norm
    for i in range(nm.rows.size):
        row = nm.rows[i]
        acc = -1.0
        for k in range(4):
            pk = q[nm.coords[i, k]]
            acc += pk * pk
            r[nm.coords[i, k]] += 2.0 * pk * lam[row]
        r[n + row] = acc
    # ---- joints (term tables)
    tm = model.term
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
    # ---- sliding joints (no clearance)
    sl = model.sliding
    for j in range(sl.s_dof.size):
        k, ed, sd, ne_j = _sliding_constraint(sl, j, q)
        for i in range(ne_j):
            row = sl.rows[j, i]
            if row < 0:
                continue
            r[n + row] = sl.phi[i]
            lr = lam[row]
            for a in range(7):
                r[sl.body[j, a]] += sl.jac[i, a] * lr
            for a in range(12):
                r[ed[a]] += sl.jac[i, 7 + a] * lr
            r[sd] += sl.jac[i, 19] * lr
        if sl.mu[j] > 0.0 or sl.fn[j] >= 0:
            Qs, _, _, _, _, _, _ = _sliding_force(sl, j, k, sd, q, v, lam, fv)
            r[sd] -= Qs
            if abs(Qs) > scale:
                scale = abs(Qs)
    # ---- clearance joints
    cl = model.clearance
    for j in range(cl.r_b.size):
        m, _, sc = _clearance(model, j, q, v, FLAG[0], r, cl.K, cl.K, cl.kelem)
        if m < 0:
            return scale, ERR_LEFT_BORE
        if sc > scale:
            scale = sc
    return scale, 0


@njit
def post_step(model, q, v):  # noqa: ANN001, ANN201
    """Interaction state after a converged step (as the joints' ``post_step``); must follow a
    :func:`residual` evaluation at this ``(q, v)`` (whose contact detection it reuses). Returns
    an error code (0: none)."""
    sl = model.sliding
    for j in range(sl.s_dof.size):
        s = q[sl.s_dof[j]]
        if s < 0.0 or s > sl.total[j] or math.isnan(s):
            model.error[0] = ERR_END_OF_BEAM
            model.error[1] = j
            return ERR_END_OF_BEAM
        ne_j = sl.n_elem[j]
        k = np.searchsorted(sl.starts[j, :ne_j], s, side="right") - 1
        sl.element[j] = min(max(k, 0), ne_j - 1)
    # contacts: from the last residual evaluation, which was at the converged state
    cl = model.clearance
    for j in range(cl.r_b.size):
        ns = cl.n_sec[j]
        for k in range(ns):
            cl.elem_ws[j, k] = cl.elem_out[j, k]
            cl.xi_ws[j, k] = cl.xi_out[j, k]
        clearance_update(cl.rows[j], cl.count[j], cl.approach[j, :ns], cl.active[j, :ns],
                         cl.psi[j, :ns])
    return 0


@njit
def _body_mass_pp(J, p, out):  # noqa: ANN001, ANN202
    """``4 GᵀJ′G`` (4, 4), the Euler-parameter block of the body mass matrix (FORMULATION I §5)."""
    G = _g(p)
    JG = _mm(J, G)
    for a in range(4):
        for b in range(4):
            acc = 0.0
            for k in range(3):
                acc += G[k, a] * JG[k, b]
            out[a, b] = 4.0 * acc


@njit
def jacobian(model, q, v, qdd, lam, fv, cM, cC, cK, data):  # noqa: ANN001, ANN201, C901, PLR0912, PLR0913, PLR0915
    """Iteration matrix ``[[cM M + cC C + cK K, Φ_qᵀ], [Φ_q, 0]]`` into the CSC ``data`` of
    ``asm.matrix``, term by term as :meth:`Assembly.evaluate` (dynamics: M includes the beams'
    and bodies' mass). Returns the largest diagonal beam stiffness (the rounding-floor scale)
    and an error code (0, or as :func:`residual`)."""
    jp = model.jac
    for i in range(data.size):
        data[i] = jp.const[i]
    # ---- beams
    bm = model.beam
    ne = bm.dofs.shape[0]
    _gather_beam(bm, q, v)
    cable._internal_kernel(bm.qe, bm.ve, bm.props, bm.rest, bm.scalar, FLAG[1], FLAG[1], bm.force,
                           jp.stiff, jp.damp)
    kscale = 0.0
    for e in range(ne):
        for i in range(12):
            if abs(jp.stiff[e, i, i]) > kscale:
                kscale = abs(jp.stiff[e, i, i])
            for j in range(12):
                k = 12 * i + j
                data[jp.beam_pos[e, k]] += (cK * jp.stiff[e, i, j] + cC * jp.damp[e, i, j]
                                            + cM * jp.beam_mass[e, k])
    # ---- bodies
    b = model.body
    nb = b.dofs.shape[0]
    if nb > 0:
        _body_inertia(b, q, v, qdd)
        Mpp = np.empty((4, 4))
        for i in range(nb):
            _body_mass_pp(b.inertia[i], b.p[i], Mpp)
            for r in range(7):
                for c in range(7):
                    val = cC * b.dv[i, r, c] + cK * b.dq[i, r, c]
                    if r < 3 and r == c:
                        val += cM * b.mass[i]
                    elif r >= 3 and c >= 3:
                        val += cM * Mpp[r - 3, c - 3]
                    data[jp.body_pos[i, 7 * r + c]] += val
        Eh = np.empty(4)
        ev = np.zeros(4)
        for i in range(b.load_dofs.shape[0]):
            f = fv[b.load_fn[i]]
            pos = jp.body_pos[jp.load_body[i]]
            mo = b.load_moment[i]
            for a in range(4):
                for c in range(4):
                    # dQ_p/dp = 2 C(s', F) + 2 Ê(n): minus in the residual
                    cab = 0.0
                    for k in range(3):
                        cab += f * b.load_force[i, k] * b.load_T[i, k, a, c]
                    for k in range(4):
                        ev[k] = 1.0 if k == c else 0.0
                    _e_hat_times(f * mo, ev, Eh)
                    data[pos[7 * (3 + a) + 3 + c]] -= cK * 2.0 * (cab + Eh[a])
    # ---- Euler-parameter normalisation
    nm = model.norm
    for i in range(nm.rows.size):
        lr = lam[nm.rows[i]]
        for k in range(4):
            pk = q[nm.coords[i, k]]
            data[jp.norm_jac[i, k]] += 2.0 * pk
            data[jp.norm_jacT[i, k]] += 2.0 * pk
            data[jp.norm_hess[i, 5 * k]] += cK * 2.0 * lr
    # ---- joints (term tables)
    tm = model.term
    for c in range(tm.coord_ptr.size - 1):
        c0, nloc, e0, e1 = _term_constraint(tm, c, q)
        w = jp.term_jptr[c]
        for i in range(e0, e1):
            row = tm.rows[i]
            jp.term_lam[i - e0] = lam[row] if row >= 0 else 0.0
            if row < 0:
                continue
            for k in range(nloc):
                data[jp.term_jac[w]] += tm.jac[i - e0, k]
                data[jp.term_jacT[w]] += tm.jac[i - e0, k]
                w += 1
        H = jp.term_H[:nloc, :nloc]
        term_hessian(tm.table, e0, e1, tm.ql[:nloc], jp.term_lam, H)
        h0 = jp.term_hptr[c]
        for a in range(nloc):
            for k in range(nloc):
                data[jp.term_hess[h0 + a * nloc + k]] += cK * H[a, k]
    # ---- sliding joints
    sl = model.sliding
    lfull = np.zeros(5)
    for j in range(sl.s_dof.size):
        k, ed, sd, ne_j = _sliding_constraint(sl, j, q)
        for i in range(ne_j):
            row = sl.rows[j, i]
            lfull[i] = lam[row] if row >= 0 else 0.0
            if row < 0:
                continue
            for a in range(20):
                data[jp.sl_jac[j, k, i, a]] += sl.jac[i, a]
                data[jp.sl_jacT[j, k, i, a]] += sl.jac[i, a]
        sliding_hessian(sl.ql, sl.lengths[j, k], sl.starts[j, k], sl.T[j], ne_j, lfull[:ne_j],
                        jp.sl_H)
        for a in range(20):
            for c in range(20):
                data[jp.sl_hess[j, k, 20 * a + c]] += cK * jp.sl_H[a, c]
        if sl.mu[j] > 0.0 or sl.fn[j] >= 0:
            Qs, dQ_dlam, dQ_dsd, nr, tvec, r2, dS = _sliding_force(sl, j, k, sd, q, v, lam, fv)
            Ft = Qs / nr
            for m in range(4):
                for c in range(3):
                    data[jp.sl_s_elem[j, k, 3 * m + c]] -= cK * Ft * dS[m] * tvec[c]
            data[jp.sl_ss[j]] += -cK * Ft * (tvec[0] * r2[0] + tvec[1] * r2[1]
                                             + tvec[2] * r2[2]) - cC * dQ_dsd
            if sl.rows[j, 0] >= 0 and sl.rows[j, 1] >= 0 and sl.rows[j, 2] >= 0:
                for a in range(3):
                    data[jp.sl_s_lam[j, a]] -= dQ_dlam[a]
    # ---- clearance joints (Gauss-Newton contact tangent)
    cl = model.clearance
    for j in range(cl.r_b.size):
        m, cnt, _ = _clearance(model, j, q, v, FLAG[1], model.scratch, jp.cl_K, jp.cl_C,
                               jp.cl_elem)
        if m < 0:
            return kscale, ERR_LEFT_BORE
        for i in range(cnt):
            pos = jp.cl_pos[j, jp.cl_elem[i]]
            for a in range(19):
                for c in range(19):
                    data[pos[19 * a + c]] += cK * jp.cl_K[i, a, c] + cC * jp.cl_C[i, a, c]
    return kscale, 0

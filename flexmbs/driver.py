"""The one assembler kernel: sums the terms of every kind through their owners' kernels.

    r_q   = M q'' + Q_int(q, q') + Phi_q^T lam - Q_ext(q, t)        (docs/theory.md §I.0)
    r_lam = Phi(q, t)

and the iteration matrix ``[[cM M + cC C + cK K, Phi_q^T], [Phi_q, 0]]`` into the CSC ``data``
of the assembler's fixed pattern. Every term is stated once, in the module that owns its
physics (:mod:`flexmbs.terms`); this module only calls them in order. The Python Newton loop
(through :meth:`flexmbs.assembly.Assembly.evaluate`) and the compiled one
(:mod:`flexmbs.steploop`) both call these functions, inlined into the one compiled
entry :func:`flexmbs.kernel.kernel` (called from Python directly, e.g. by a test, each is
compiled on its own).

``mode`` = ``[load factor, with inertia, with damping]`` (:mod:`flexmbs.terms`); ``fv`` holds
the values of the model's time functions at the current time; ``error`` (int64, 4) receives
``[code, index of the joint within its kind, detail, window row]`` of a failure (the row of
the plan's windows for an off-plan error, :class:`~flexmbs.constraints.interaction.Following`).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from ._jit import FLAG, njit
from .constraints.drivers import DriverPart, drivers_jacobian, drivers_residual
from .constraints.interaction import InteractionKind
from .constraints.joints import (
    JointPart,
    NormPart,
    joints_jacobian,
    joints_residual,
    joints_set_bases,
    norms_jacobian,
    norms_residual,
    with_directors,
)
from .constraints.linear import LinearPart, linear_jacobian, linear_residual
from .constraints.sliding import (
    ERR_END_OF_BEAM,
    SLIDING,
    SlidingPart,
    sliding_jacobian,
    sliding_post_step,
    sliding_residual,
)
from .contact.clearance_term import (
    ERR_LEFT_BORE,
    ClearancePart,
    clearance_hold,
    clearance_post_step_all,
    clearance_set_bases,
    clearance_terms,
)
from .contact.joint import CLEARANCE
from .elements.group import (
    groups_jacobian,
    groups_post_step,
    groups_rebase,
    groups_residual,
    groups_set_bases,
)
from .elements.rigid_body import BodiesPart, bodies_jacobian, bodies_residual
from .loads import LoadsPart, loads_jacobian, loads_residual, loads_set_bases
from .ropes import ROPE, RopePart, ropes_jacobian, ropes_post_step, ropes_residual
from .springs import SpringPart, springs_jacobian, springs_post_step, springs_residual

__all__ = ["SystemPart", "residual", "jacobian", "constraint_velocity", "post_step",
           "rebase_static", "set_bases", "ERR_LEFT_BORE", "ERR_END_OF_BEAM", "INTERACTION_KINDS",
           "KIND_OF_ERROR", "KINDS", "STOPS_RUN", "kind_of", "stops_run"]

#: the compiled interaction kinds, each a field of :class:`SystemPart` whose kernels the
#: functions below call (docs/extending.md: a new kind is its module, one entry here, a field
#: and its calls)
INTERACTION_KINDS = (SLIDING, CLEARANCE, ROPE)

#: the record of every compiled interaction kind by name (its interactions' ``term_kind``)
KINDS = {kind.name: kind for kind in INTERACTION_KINDS}


def kind_of(obj: Any) -> InteractionKind | None:
    """The record of an interaction's compiled kind (None for a Python-only interaction): its
    output hooks and energy are declared there, not looked for on the object."""
    return KINDS.get(getattr(obj, "term_kind", ""))


#: term kind whose joint list ``error[1]`` indexes, per error code
KIND_OF_ERROR = {code: kind.name for kind in INTERACTION_KINDS for code in kind.errors}

#: ``STOPS_RUN[code]``: after this post-step error the step stands and the run stops (the
#: kinds' ``stops``; a constant array, which numba freezes into the compiled loop)
STOPS_RUN = np.zeros(max(KIND_OF_ERROR, default=0) + 1, dtype=np.bool_)
for _kind in INTERACTION_KINDS:
    STOPS_RUN[list(_kind.stops)] = True


@njit(inline="always")
def stops_run(code):
    """Whether a post-step error ``code`` stops the run with the step standing (:data:`STOPS_RUN`)."""
    return 0 <= code < STOPS_RUN.size and STOPS_RUN[code]


class SystemPart(NamedTuple):
    """The packed system (the driver's functions unpack it whole, in this order). In the copy
    the kernel receives, the parts of the kinds of :data:`OPTIONAL_KINDS` a model has none of
    are ``None`` (:meth:`without_absent`): their kernels then start with ``if part is None:
    return ...``, which numba prunes by the argument's type, so that nothing else of them is
    compiled for such a model."""

    n: int                           # coordinates
    m: int                           # multipliers
    beams: tuple                     # one part per element group (any element types)
    bodies: BodiesPart
    loads: LoadsPart
    linear: LinearPart
    norms: NormPart
    joints: JointPart
    sliding: SlidingPart
    clearance: ClearancePart
    rope: RopePart
    springs: SpringPart
    drivers: DriverPart
    error: np.ndarray                # (4,) [code, joint, detail, window row] of the last error
    bases: np.ndarray                # (nodes with a twist, 7) re-based nodes' records (§2.4)
    zero: np.ndarray                 # (1 + k,) int64: the matrix positions a Jacobian zeroes
                                     # (clear_matrix; Assembly.follow)

    def without_absent(self, present: dict[str, bool]) -> SystemPart:
        """This system with ``None`` for every optional kind that ``present`` marks absent,
        and the present interaction kinds' parts as they declare them for the kernel (their
        ``compiled_view``: features no interaction uses are ``None`` too); the same arrays
        otherwise: in-place updates are seen by both."""
        present = dict(present)
        for group in COMPILED_TOGETHER:
            if any(present[k] for k in group):
                present.update(dict.fromkeys(group, True))
        absent: dict[str, Any] = {k: None for k in OPTIONAL_KINDS if not present[k]}
        for kind in INTERACTION_KINDS:
            if present[kind.name] and kind.compiled_view is not None:
                absent[kind.name] = kind.compiled_view(getattr(self, kind.name))
        return self._replace(**absent)

    def complete(self) -> SystemPart:
        """This system as the complete kernel of its element types receives it
        (flexmbs.kernel.prepare): every optional kind's part (this system has them all, empty
        where the model has none) and every compile-time feature in: the interactions' full
        parts (no ``compiled_view``) and term tables with node directors (empty where none).
        Models with the same element groups (types and count: one cable group; cables and one
        rod group, ...) then share one type of system, hence one kernel (tested). Not the other
        element types' parts: an empty rod group in the kernel of cable models cost Example 1
        10 µs per step (0.64 -> 0.78 s per simulated second)."""
        return self._replace(joints=with_directors(self.joints),
                             drivers=with_directors(self.drivers),
                             springs=with_directors(self.springs))


#: the kinds of terms compiled only for models that have them (docs/design-notes.md, "Compile
#: time"); beams, loads and linear rows are in nearly every model
OPTIONAL_KINDS = ("bodies", "norms", "joints", *(kind.name for kind in INTERACTION_KINDS), "springs",
                  "drivers")

#: optional kinds compiled together: a model that has any kind of a group compiles the group's
#: other kinds too (their parts empty, not None). Joints and spring-dampers: a model of bodies
#: with joints gains its first spring (or the reverse) without a kernel of its own (a new kind
#: of model is a compile of 15-40 s), and the test suite compiles 19 kernels instead of 27.
#: Bodies alone stay lean: compiling joints and springs into every model of bodies (Example 1
#: has neither) cost its first run 77 -> 105 s (docs/design-notes.md, "Compile time").
COMPILED_TOGETHER = (("joints", "springs"),)


# Each function below reads the packed system once, unpacked into its parts (numba stores every
# variable, the system too, in a stack slot that LLVM's SROA splits into its ~1500-4000
# scalars; reading ``sy.part`` loads the whole system again each time, and the inlined copies
# of these functions multiplied that: docs/design-notes.md, "Compile time: the entry's copies
# of the system").


@njit(inline="always")
def residual(sy, q, v, qdd, lam, fv, mode, r):
    """``r = [r_q; r_lam]``; returns ``(scale, error code)``: the largest single force entering
    ``r_q`` (the force scale of the convergence test) and 0 or an ``ERR_*`` code."""
    n, _m, beams, bodies, loads, linear, norms, joints, sliding, clearance, rope, springs, \
        drivers, error, _bases, _zero = sy
    for i in range(n, r.size):
        r[i] = 0.0
    scale = loads_residual(loads, q, fv, mode, r)
    scale = max(scale, groups_residual(beams, q, v, qdd, mode, r))
    scale = max(scale, bodies_residual(bodies, q, v, qdd, fv, mode, r))
    scale = max(scale, springs_residual(springs, q, v, mode, r))
    scale = max(scale, ropes_residual(rope, q, v, mode, r))
    linear_residual(linear, n, q, lam, fv, mode, r)
    norms_residual(norms, n, q, lam, r)
    joints_residual(joints, n, q, lam, r)
    drivers_residual(drivers, n, q, lam, fv, mode, r)
    scale = max(scale, sliding_residual(sliding, n, q, v, lam, fv, r))
    sc, code = clearance_terms(clearance, q, v, FLAG[0], 0.0, 0.0, r, r, error)
    return max(scale, sc), code


@njit(inline="always")
def clear_matrix(zero, data):
    """``data`` = 0 where a Jacobian may write: every stored position (``zero[0]`` < 0), or, while
    the factorisation's plan follows the sliding and clearance joints (:meth:`Assembly.follow
    <flexmbs.assembly.Assembly.follow>`), the ``zero[0]`` positions ``zero[1:]``: those it
    reads and the multipliers' rows and columns (:func:`constraint_velocity` reads Φ_q
    whole). A following member writes only inside its windows (else its off-plan error), and
    no factorisation reads a position outside its plan, so a stored pattern that reserves a
    joint's body against a whole beam is not swept at every evaluation."""
    count = zero[0]
    if count < 0:
        for i in range(data.size):
            data[i] = 0.0
        return
    for i in range(count):
        data[zero[1 + i]] = 0.0


@njit(inline="always")
def jacobian(sy, q, v, qdd, lam, fv, mode, cM, cC, cK, data):
    """Iteration matrix into ``data``; returns ``(largest diagonal beam or spring stiffness,
    error code)``."""
    _n, _m, beams, bodies, loads, linear, norms, joints, sliding, clearance, rope, springs, \
        drivers, error, _bases, zero = sy
    clear_matrix(zero, data)
    kscale = 0.0
    kscale = max(kscale, groups_jacobian(beams, q, v, qdd, mode, cM, cC, cK, data))
    bodies_jacobian(bodies, q, v, qdd, fv, mode, cM, cC, cK, data)
    loads_jacobian(loads, q, fv, mode, cK, data)
    kscale = max(kscale, springs_jacobian(springs, q, v, mode, cC, cK, data))
    kscale = max(kscale, ropes_jacobian(rope, q, v, mode, cC, cK, data))
    linear_jacobian(linear, data)
    norms_jacobian(norms, q, lam, cK, data)
    joints_jacobian(joints, q, lam, cK, data)
    drivers_jacobian(drivers, q, lam, fv, mode, cK, data)
    code = sliding_jacobian(sliding, q, v, lam, fv, cC, cK, data, error)
    if code != 0:
        return kscale, code
    _, code = clearance_terms(clearance, q, v, FLAG[1], cC, cK, data, data, error)
    return kscale, code


@njit(inline="always")
def post_step(sy, q, v, qdd, acc):
    """Interaction state after a converged step, then the nodal frames re-based where needed
    (:func:`after_step`); must follow a :func:`residual` at this state (whose contact detection
    it reuses). Returns 0 or an ``ERR_*`` code (then nothing is changed)."""
    _, code = after_step(sy, q, v, qdd, acc)
    return code


@njit(inline="always")
def after_step(sy, q, v, qdd, acc):
    """The one sequence after a converged step or static increment (following a residual at
    ``q``): the elements' checks, the joints' state (slide elements, contact tracking and
    friction anchors, ``q`` the next step's start), the springs' and ropes' state, then the
    nodal frames re-based where needed (:func:`_rebase`: ``q, v, qdd`` and the integrator's
    ``acc``; empty rates for statics). Returns ``(re-based nodes, 0)`` or ``(0, error code)``
    (then nothing is changed)."""
    _n, _m, beams, _bodies, loads, _linear, _norms, joints, sliding, clearance, rope, springs, \
        _drivers, error, bases, _zero = sy
    code = groups_post_step(beams, q, error)
    if code != 0:
        return 0, code
    code = sliding_post_step(sliding, q, error)
    if code != 0:
        return 0, code
    clearance_post_step_all(clearance, q)
    springs_post_step(springs, q)
    ropes_post_step(rope, q, v)
    return _rebase(beams, joints, loads, clearance, bases, q, v, qdd, acc), 0


@njit(inline="always")
def hold_contacts(sy, action):
    """The clearance joints' held active set (:func:`~flexmbs.contact.clearance_term.clearance_hold`:
    ``action`` one of its ``HOLD_*``); returns its count for ``HOLD_READ``, else 0."""
    _n, _m, _beams, _bodies, _loads, _linear, _norms, _joints, _sliding, clearance, _rope, \
        _springs, _drivers, _error, _bases, _zero = sy
    return clearance_hold(clearance, action)


@njit(inline="always")
def _rebase(beams, joints, loads, clearance, bases, q, v, qdd, acc):
    """Nodes whose tangent turned far from its base get a new chart (docs/theory.md §I.2.4): the
    element groups change their coordinates (``q, v, qdd`` and the integrator's ``acc``; an
    empty array is left out) and record the new bases, which the joints and node moments
    holding those nodes then read. Returns the number of re-based nodes."""
    count = groups_rebase(beams, q, v, qdd, acc, bases)
    if count > 0:   # q: the friction's step start, re-based
        _set_bases(beams, joints, loads, clearance, bases, count, False, q)
    return count


@njit(inline="always")
def rebase_static(sy, q):
    """After a converged static increment: :func:`after_step` without rates. Returns
    ``(re-based nodes, 0)`` or ``(0, error code)``."""
    empty = q[:0]
    return after_step(sy, q, empty, empty, empty)


@njit(inline="always")
def set_bases(sy, log, stop, elements, q):
    """Every holder of a node listed in ``log[:stop]`` (records ``[twist coordinate, t̄, D̄]``)
    takes its base: joints and node moments, and with ``elements`` the element groups too (a
    resumed run; after a re-basing they have them already). ``q``: the re-based start of the
    next step (empty for a resumed run, whose start :meth:`Assembly.begin` sets)."""
    _n, _m, beams, _bodies, loads, _linear, _norms, joints, _sliding, clearance, _rope, \
        _springs, _drivers, _error, _bases, _zero = sy
    _set_bases(beams, joints, loads, clearance, log, stop, elements, q)


@njit(inline="always")
def _set_bases(beams, joints, loads, clearance, log, stop, elements, q):
    if elements:
        groups_set_bases(beams, log, stop)
    joints_set_bases(joints, log, stop)
    loads_set_bases(loads, log, stop)
    clearance_set_bases(clearance, log, stop, q)


@njit
def constraint_velocity(indptr, indices, n, data, v, rows, scale, r):
    """``r[n + i] = scale rows[i] (Φ_q v)_i`` with ``Φ_q`` read from the constraint rows of the
    iteration matrix (CSC ``indptr``, ``indices``, ``data`` after :func:`jacobian`): the
    velocity-level constraints from what every owner already wrote, no second statement of
    any constraint. ``rows[i] = 0`` leaves row i at 0 (a row with ``Φ_t != 0``)."""
    m = rows.size
    for i in range(m):
        r[n + i] = 0.0
    for j in range(n):
        vj = v[j]
        for k in range(indptr[j], indptr[j + 1]):
            row = indices[k]
            if row >= n:
                r[row] += data[k] * vj
    for i in range(m):
        r[n + i] *= scale * rows[i]

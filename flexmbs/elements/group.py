"""An element group as the assembler sees it: the parts of every element type summed by one
loop, whatever their element.

Every element module packs a group of its elements into a named tuple (its *part*) holding at
least ``dofs (n_elem, n)``, ``pos (n_elem, n*n)`` (matrix positions), ``mass (n_elem, n, n)``
and the work arrays ``qe, ve, force (n_elem, n)``, ``stiff, damp (n_elem, n, n)``, and states
its internal forces in a kernel. What is common to all elements — gathering the element
states, adding ``Q_int + M q̈`` into the residual and ``cK K + cC C + cM M`` into the matrix —
is stated once here (:func:`gather_states`, :func:`add_residual`, :func:`add_matrix`).

The driver sums a tuple of parts of *different* types (several element types in one model) by
:func:`groups_residual` and :func:`groups_jacobian`, ``for part in literal_unroll(parts):
element_residual(part, ...)`` (a function of its own: numba's unrolling pass types its caller
partially, which the step loop it would be inlined into does not survive): :func:`element_residual`
and :func:`element_jacobian` are resolved at compile time to the kernels the part's element
type registered (:class:`~flexmbs.elements.layout.ElementType` ``part_type``, ``residual``,
``jacobian``), so an element is its module and its registration.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._jit import HAVE_NUMBA, literal_unroll, njit
from ..terms import WITH_DAMPING, WITH_INERTIA
from .layout import ELEMENT_TYPES, ElementType

__all__ = ["gather_states", "add_residual", "add_matrix", "element_residual", "element_jacobian",
           "element_post_step", "element_rebase", "element_set_bases", "groups_residual",
           "groups_jacobian", "groups_post_step", "groups_rebase", "groups_set_bases"]


@njit(inline="always")
def gather_states(part, q, v, mode):  # noqa: ANN001, ANN201
    """``qe, ve`` of the part's elements from the global ``q, v`` (``ve = 0`` without damping)."""
    damping = mode[WITH_DAMPING] != 0.0
    dofs = part.dofs
    for e in range(dofs.shape[0]):
        for k in range(dofs.shape[1]):
            part.qe[e, k] = q[dofs[e, k]]
            part.ve[e, k] = v[dofs[e, k]] if damping else 0.0


@njit(inline="always")
def add_residual(part, qdd, mode, r):  # noqa: ANN001, ANN201
    """``r += Q_int (+ M q̈ with inertia)`` from ``part.force``; returns the largest single force
    (an element force entry or a row of M q̈)."""
    inertia = mode[WITH_INERTIA] != 0.0
    dofs = part.dofs
    n = dofs.shape[1]
    scale = 0.0
    for e in range(dofs.shape[0]):
        for i in range(n):
            s = part.force[e, i]
            if abs(s) > scale:
                scale = abs(s)
            if inertia:
                acc = 0.0
                for j in range(n):
                    acc += part.mass[e, i, j] * qdd[dofs[e, j]]
                if abs(acc) > scale:
                    scale = abs(acc)
                s += acc
            r[dofs[e, i]] += s
    return scale


@njit(inline="always")
def add_matrix(part, cM, cC, cK, data):  # noqa: ANN001, ANN201
    """``cK ∂Q_int/∂q + cC ∂Q_int/∂q̇ + cM M`` from ``part.stiff, part.damp, part.mass`` into the
    CSC ``data``; returns the largest diagonal stiffness (the rounding floor's scale)."""
    dofs = part.dofs
    n = dofs.shape[1]
    kscale = 0.0
    for e in range(dofs.shape[0]):
        for i in range(n):
            if abs(part.stiff[e, i, i]) > kscale:
                kscale = abs(part.stiff[e, i, i])
            for j in range(n):
                data[part.pos[e, n * i + j]] += (cK * part.stiff[e, i, j] + cC * part.damp[e, i, j]
                                                 + cM * part.mass[e, i, j])
    return kscale


def _element_type_of(part_class: type) -> ElementType:
    for name in ELEMENT_TYPES:
        et = ELEMENT_TYPES.get(name)
        if et.part_type is part_class:
            return et
    raise TypeError(f"no registered element type packs {part_class.__name__}")


def element_residual(part: Any, q: Any, v: Any, qdd: Any, mode: Any, r: Any) -> float:
    """``r_q += Q_int + M q̈`` of one part by its element type's kernel; the force scale."""
    return float(_element_type_of(type(part)).residual(part, q, v, qdd, mode, r))


def element_post_step(part: Any, q: Any, error: Any) -> int:
    """The part's check after a converged step (0: none or passed; else its error code)."""
    check = _element_type_of(type(part)).post_step
    return 0 if check is None else int(check(part, q, error))


def element_rebase(part: Any, q: Any, v: Any, qdd: Any, acc: Any, log: Any, count: int) -> int:
    """Re-base the part's nodal frames that need it (elements with charts, FORMULATION §2.4);
    the new count of records in ``log``."""
    rebase = _element_type_of(type(part)).rebase
    return count if rebase is None else int(rebase(part, q, v, qdd, acc, log, count))


def element_set_bases(part: Any, log: Any, start: int, stop: int) -> int:
    """Give the part's nodes listed in ``log[start:stop]`` their bases; returns ``stop``."""
    set_bases = _element_type_of(type(part)).set_bases
    return stop if set_bases is None else int(set_bases(part, log, start, stop))


def element_jacobian(part: Any, q: Any, v: Any, qdd: Any, mode: Any, cM: float, cC: float,
                     cK: float, data: Any) -> float:
    """The part's matrix block by its element type's kernel; the stiffness scale."""
    return float(_element_type_of(type(part)).jacobian(part, q, v, qdd, mode, cM, cC, cK, data))


if HAVE_NUMBA:
    from numba import types
    from numba.extending import overload

    def _registered(part: Any) -> ElementType | None:
        if isinstance(part, types.BaseNamedTuple):
            return _element_type_of(part.instance_class)  # type: ignore[attr-defined]
        return None

    @overload(element_residual)
    def _residual_overload(part, q, v, qdd, mode, r):  # noqa: ANN001, ANN202
        et = _registered(part)
        if et is None:
            return None
        kernel = et.residual

        def impl(part, q, v, qdd, mode, r):  # noqa: ANN001, ANN202
            return kernel(part, q, v, qdd, mode, r)
        return impl

    @overload(element_post_step)
    def _post_step_overload(part, q, error):  # noqa: ANN001, ANN202
        et = _registered(part)
        if et is None:
            return None
        check = et.post_step
        if check is None:
            def none(part, q, error):  # noqa: ANN001, ANN202
                return np.int64(0)
            return none

        def impl(part, q, error):  # noqa: ANN001, ANN202
            return np.int64(check(part, q, error))
        return impl

    @overload(element_rebase)
    def _rebase_overload(part, q, v, qdd, acc, log, count):  # noqa: ANN001, ANN202
        et = _registered(part)
        if et is None:
            return None
        rebase = et.rebase
        if rebase is None:
            def none(part, q, v, qdd, acc, log, count):  # noqa: ANN001, ANN202
                return count
            return none

        def impl(part, q, v, qdd, acc, log, count):  # noqa: ANN001, ANN202
            return rebase(part, q, v, qdd, acc, log, count)
        return impl

    @overload(element_set_bases)
    def _set_bases_overload(part, log, start, stop):  # noqa: ANN001, ANN202
        et = _registered(part)
        if et is None:
            return None
        set_bases = et.set_bases
        if set_bases is None:
            def none(part, log, start, stop):  # noqa: ANN001, ANN202
                return stop
            return none

        def impl(part, log, start, stop):  # noqa: ANN001, ANN202
            return set_bases(part, log, start, stop)
        return impl

    @overload(element_jacobian)
    def _jacobian_overload(part, q, v, qdd, mode, cM, cC, cK, data):  # noqa: ANN001, ANN202
        et = _registered(part)
        if et is None:
            return None
        kernel = et.jacobian

        def impl(part, q, v, qdd, mode, cM, cC, cK, data):  # noqa: ANN001, ANN202
            return kernel(part, q, v, qdd, mode, cM, cC, cK, data)
        return impl


@njit
def groups_residual(parts, q, v, qdd, mode, r):  # noqa: ANN001, ANN201
    """``r_q += Q_int + M q̈`` of every element group; the largest single force."""
    scale = 0.0
    for part in literal_unroll(parts):
        scale = max(scale, element_residual(part, q, v, qdd, mode, r))
    return scale


@njit
def groups_jacobian(parts, q, v, qdd, mode, cM, cC, cK, data):  # noqa: ANN001, ANN201
    """The matrix blocks of every element group; the largest diagonal stiffness."""
    kscale = 0.0
    for part in literal_unroll(parts):
        kscale = max(kscale, element_jacobian(part, q, v, qdd, mode, cM, cC, cK, data))
    return kscale


@njit
def groups_post_step(parts, q, error):  # noqa: ANN001, ANN201
    """The element groups' checks after a converged step: the first error code (``error[1]`` =
    the part's position in ``parts``), or 0."""
    k = 0
    found = 0
    for part in literal_unroll(parts):
        if found == 0:
            code = element_post_step(part, q, error)
            if code != 0:
                found = code
                error[0] = code
                error[1] = k
        k += 1  # noqa: SIM113 - numba cannot enumerate a literal_unroll
    return found


@njit
def groups_rebase(parts, q, v, qdd, acc, log):  # noqa: ANN001, ANN201
    """Re-base the nodal frames of every element group that has charts (FORMULATION §2.4) after
    a converged step; returns the number of records written to ``log``."""
    count = 0
    for part in literal_unroll(parts):
        count = element_rebase(part, q, v, qdd, acc, log, count)
    return count


@njit
def groups_set_bases(parts, log, stop):  # noqa: ANN001, ANN201
    """Give every listed node (``log[:stop]``) its base, in whichever group holds it."""
    for part in literal_unroll(parts):
        element_set_bases(part, log, 0, stop)

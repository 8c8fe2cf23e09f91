"""An element group as the assembler sees it: the parts of every element type summed by one
loop, whatever their element.

Every element module packs a group of its elements into a named tuple (its *part*) holding at
least ``dofs (n_elem, n)``, ``pos (n_elem, n*n)`` (matrix positions), ``mass (n_elem, n, n)``
and the work arrays ``qe, ve, force (n_elem, n)``, ``stiff, damp (n_elem, n, n)``, and states
its internal forces in a kernel. What is common to all elements — gathering the element
states, adding ``Q_int + M q̈`` into the residual and ``cK K + cC C + cM M`` into the matrix —
is stated once here (:func:`gather_states`, :func:`add_residual`, :func:`add_matrix`).

The driver sums a tuple of parts of *different* types (several element types in one model) by
:func:`groups_residual` and :func:`groups_jacobian`, which take the parts at the fixed positions
``0 .. MAX_GROUPS - 1`` (``None`` past the last, compiled to nothing) and call the kernels the
part's element type registered (:class:`~flexmbs.elements.layout.ElementType` ``part_type``,
``residual``, ``jacobian``, ...), resolved when typed by numba intrinsics that call them in place,
so an element is its module and its registration. (A ``literal_unroll`` loop over the parts
calling ``@overload`` implementations did the same; numba compiled each of those into a library
of its own, with the element's whole tree optimised and turned into machine code again: about
30 s of a rod model's first run, benchmarks/README.md.) :func:`element_residual` and
:func:`element_jacobian` stay for other compiled callers (benchmarks/rod.py).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._jit import HAVE_NUMBA, njit
from ..terms import WITH_DAMPING, WITH_INERTIA
from .layout import ELEMENT_TYPES, ElementType

__all__ = ["gather_states", "add_residual", "add_matrix", "element_residual", "element_jacobian",
           "element_post_step", "element_rebase", "element_set_bases", "groups_residual",
           "groups_jacobian", "groups_post_step", "groups_rebase", "groups_set_bases"]


@njit(inline="always")
def gather_states(part, q, v, mode):
    """``qe, ve`` of the part's elements from the global ``q, v`` (``ve = 0`` without damping)."""
    damping = mode[WITH_DAMPING] != 0.0
    dofs = part.dofs
    for e in range(dofs.shape[0]):
        for k in range(dofs.shape[1]):
            part.qe[e, k] = q[dofs[e, k]]
            part.ve[e, k] = v[dofs[e, k]] if damping else 0.0


@njit(inline="always")
def add_residual(part, qdd, mode, r):
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
def add_matrix(part, cM, cC, cK, data):
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
    """Re-base the part's nodal frames that need it (elements with charts, docs/theory.md §I.2.4);
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
    def _residual_overload(part, q, v, qdd, mode, r):
        et = _registered(part)
        if et is None:
            return None
        kernel = et.residual

        def impl(part, q, v, qdd, mode, r):
            return kernel(part, q, v, qdd, mode, r)
        return impl

    @overload(element_post_step)
    def _post_step_overload(part, q, error):
        et = _registered(part)
        if et is None:
            return None
        check = et.post_step
        if check is None:
            def none(part, q, error):
                return np.int64(0)
            return none

        def impl(part, q, error):
            return np.int64(check(part, q, error))
        return impl

    @overload(element_rebase)
    def _rebase_overload(part, q, v, qdd, acc, log, count):
        et = _registered(part)
        if et is None:
            return None
        rebase = et.rebase
        if rebase is None:
            def none(part, q, v, qdd, acc, log, count):
                return count
            return none

        def impl(part, q, v, qdd, acc, log, count):
            return rebase(part, q, v, qdd, acc, log, count)
        return impl

    @overload(element_set_bases)
    def _set_bases_overload(part, log, start, stop):
        et = _registered(part)
        if et is None:
            return None
        set_bases = et.set_bases
        if set_bases is None:
            def none(part, log, start, stop):
                return stop
            return none

        def impl(part, log, start, stop):
            return set_bases(part, log, start, stop)
        return impl

    @overload(element_jacobian)
    def _jacobian_overload(part, q, v, qdd, mode, cM, cC, cK, data):
        et = _registered(part)
        if et is None:
            return None
        kernel = et.jacobian

        def impl(part, q, v, qdd, mode, cM, cC, cK, data):
            return kernel(part, q, v, qdd, mode, cM, cC, cK, data)
        return impl


#: the most element groups (an element type with its options) a model may have: the group
#: functions call the parts at fixed positions (below)
MAX_GROUPS = 8


def _nth_python(k: int) -> Any:
    return lambda parts: parts[k] if k < len(parts) else None


def _or_none(op: Any, absent: Any) -> Any:
    """``op`` of a part, ``absent(*args)`` for ``None`` (a group position past the last)."""
    return lambda part, *args: absent(*args) if part is None else op(part, *args)


if HAVE_NUMBA:
    from numba.core.imputils import impl_ret_borrowed
    from numba.extending import intrinsic

    def _nth_compiled(k: int) -> Any:
        """``parts[k]``, or ``None`` past the end of the tuple, decided when typed."""
        @intrinsic
        def nth(typingctx, parts):
            if k < len(parts):
                def codegen(context, builder, sig, args):
                    return impl_ret_borrowed(context, builder, sig.return_type,
                                             builder.extract_value(args[0], k))
                return parts.types[k](parts), codegen

            def codegen_none(context, builder, sig, args):
                return context.get_constant_null(sig.return_type)
            return types.none(parts), codegen_none
        return nth

    def _element_call(field: str, result: Any, passthrough: int | None) -> Any:
        """A call of the kernel the part's element type registered under ``field``, resolved
        when typed and lowered in place (no library of its own, unlike an overload's
        implementation, which numba compiles, optimises and turns into machine code again
        for every kernel it calls). For ``None`` or an unregistered kernel: ``0`` of type
        ``result``, or the argument at ``passthrough``."""
        @intrinsic
        def call(typingctx, part, *args):
            args = args[0] if len(args) == 1 and isinstance(args[0], types.StarArgTuple) else args
            kernel = None if isinstance(part, types.NoneType) else getattr(
                _registered(part), field, None)
            rtype = result if passthrough is None else args[passthrough]
            sig = rtype(part, types.StarArgTuple(args))
            if kernel is None:
                def codegen_absent(context, builder, signature, cargs):
                    if passthrough is None:
                        return context.get_constant(rtype, 0)
                    return builder.extract_value(cargs[1], passthrough)
                return sig, codegen_absent
            fnty = typingctx.resolve_value_type(kernel)
            ksig = typingctx.resolve_function_type(fnty, (part, *args), {})

            def codegen(context, builder, signature, cargs):
                flat = [cargs[0]] + [builder.extract_value(cargs[1], i) for i in range(len(args))]
                value = context.get_function(fnty, ksig)(builder, flat)
                return context.cast(builder, value, ksig.return_type, rtype)
            return sig, codegen
        return call

    _nth = [_nth_compiled(k) for k in range(MAX_GROUPS)]
    _residual = _element_call("residual", types.float64, None)
    _jacobian = _element_call("jacobian", types.float64, None)
    _post_step = _element_call("post_step", types.int64, None)
    _rebase = _element_call("rebase", types.int64, 5)
    _set_bases = _element_call("set_bases", types.int64, 2)
else:
    _nth = [_nth_python(k) for k in range(MAX_GROUPS)]
    _residual = _or_none(element_residual, lambda *a: 0.0)
    _jacobian = _or_none(element_jacobian, lambda *a: 0.0)
    _post_step = _or_none(element_post_step, lambda *a: 0)
    _rebase = _or_none(element_rebase, lambda *a: a[5])
    _set_bases = _or_none(element_set_bases, lambda *a: a[2])

_n0, _n1, _n2, _n3, _n4, _n5, _n6, _n7 = _nth


# The group functions below take the parts at the fixed positions 0..MAX_GROUPS-1 (an absent
# position is None and compiles to nothing) instead of a literal_unroll loop, and call the
# element kernels without a library of their own in between (docs/design-notes.md, "Compile
# time"). They stay functions of their own: inlined, every position's access to the tuple of
# parts would be one more copy of it for LLVM's SROA in the kernel (measured: the rod model's
# kernel 10.9 -> 18.2 s of function passes).


@njit(internal=True)
def groups_residual(parts, q, v, qdd, mode, r):
    """``r_q += Q_int + M q̈`` of every element group; the largest single force."""
    s = _residual(_n0(parts), q, v, qdd, mode, r)
    s = max(s, _residual(_n1(parts), q, v, qdd, mode, r))
    s = max(s, _residual(_n2(parts), q, v, qdd, mode, r))
    s = max(s, _residual(_n3(parts), q, v, qdd, mode, r))
    s = max(s, _residual(_n4(parts), q, v, qdd, mode, r))
    s = max(s, _residual(_n5(parts), q, v, qdd, mode, r))
    s = max(s, _residual(_n6(parts), q, v, qdd, mode, r))
    return max(s, _residual(_n7(parts), q, v, qdd, mode, r))


@njit(internal=True)
def groups_jacobian(parts, q, v, qdd, mode, cM, cC, cK, data):
    """The matrix blocks of every element group; the largest diagonal stiffness."""
    s = _jacobian(_n0(parts), q, v, qdd, mode, cM, cC, cK, data)
    s = max(s, _jacobian(_n1(parts), q, v, qdd, mode, cM, cC, cK, data))
    s = max(s, _jacobian(_n2(parts), q, v, qdd, mode, cM, cC, cK, data))
    s = max(s, _jacobian(_n3(parts), q, v, qdd, mode, cM, cC, cK, data))
    s = max(s, _jacobian(_n4(parts), q, v, qdd, mode, cM, cC, cK, data))
    s = max(s, _jacobian(_n5(parts), q, v, qdd, mode, cM, cC, cK, data))
    s = max(s, _jacobian(_n6(parts), q, v, qdd, mode, cM, cC, cK, data))
    return max(s, _jacobian(_n7(parts), q, v, qdd, mode, cM, cC, cK, data))


@njit(inline="always")
def _check(part, q, error, k, found):
    """The first error code of the groups' checks; ``error[1]`` = the part's position."""
    if found != 0:
        return found
    code = _post_step(part, q, error)
    if code != 0:
        error[0] = code
        error[1] = k
    return code


@njit(internal=True)
def groups_post_step(parts, q, error):
    """The element groups' checks after a converged step: the first error code (``error[1]`` =
    the part's position in ``parts``), or 0."""
    found = _check(_n0(parts), q, error, 0, 0)
    found = _check(_n1(parts), q, error, 1, found)
    found = _check(_n2(parts), q, error, 2, found)
    found = _check(_n3(parts), q, error, 3, found)
    found = _check(_n4(parts), q, error, 4, found)
    found = _check(_n5(parts), q, error, 5, found)
    found = _check(_n6(parts), q, error, 6, found)
    return _check(_n7(parts), q, error, 7, found)


@njit(internal=True)
def groups_rebase(parts, q, v, qdd, acc, log):
    """Re-base the nodal frames of every element group that has charts (docs/theory.md §I.2.4) after
    a converged step; returns the number of records written to ``log``."""
    count = _rebase(_n0(parts), q, v, qdd, acc, log, 0)
    count = _rebase(_n1(parts), q, v, qdd, acc, log, count)
    count = _rebase(_n2(parts), q, v, qdd, acc, log, count)
    count = _rebase(_n3(parts), q, v, qdd, acc, log, count)
    count = _rebase(_n4(parts), q, v, qdd, acc, log, count)
    count = _rebase(_n5(parts), q, v, qdd, acc, log, count)
    count = _rebase(_n6(parts), q, v, qdd, acc, log, count)
    return _rebase(_n7(parts), q, v, qdd, acc, log, count)


@njit(internal=True)
def groups_set_bases(parts, log, stop):
    """Give every listed node (``log[:stop]``) its base, in whichever group holds it."""
    _set_bases(_n0(parts), log, 0, stop)
    _set_bases(_n1(parts), log, 0, stop)
    _set_bases(_n2(parts), log, 0, stop)
    _set_bases(_n3(parts), log, 0, stop)
    _set_bases(_n4(parts), log, 0, stop)
    _set_bases(_n5(parts), log, 0, stop)
    _set_bases(_n6(parts), log, 0, stop)
    _set_bases(_n7(parts), log, 0, stop)

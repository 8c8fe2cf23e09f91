"""The one compiled entry point: every compiled evaluation of a system goes through :func:`kernel`.

numba compiles each function called from Python into one machine-code library holding its
whole call tree, linked in and optimised again. With the residual, the iteration matrix, the
post-step update (called from the Python Newton loop) and the generalized-α step loop as four
such entries, the code of every term was compiled twice, into the Python path's libraries and
into the step loop's. As one entry, with those four inlined at numba's IR level, it is compiled
once and loaded once (docs/design-notes.md, "Compile time"). The kernels themselves stay where
their physics is: :mod:`flexmbs.driver` sums the owners' terms, :mod:`flexmbs.steploop`
holds the step loop.

``op`` selects the work:

- ``OP_RESIDUAL``: ``r = [r_q; r_lam]`` at ``fv[0]``; returns ``(force scale, error code)``;
- ``OP_JACOBIAN``: the iteration matrix ``cM M + cC C + cK K`` (``coef = [cM, cC, cK]``) with
  its constraint borders into ``data``; returns ``(stiffness scale, error code)``;
- ``OP_POST_STEP``: interaction state after a converged step (after an ``OP_RESIDUAL`` at the
  same state) and re-basing of nodal frames, which changes ``q, v, qdd`` and ``run.a`` in place;
  returns ``(0, error code)``;
- ``OP_REBASE``: after a converged static increment (after an ``OP_RESIDUAL`` at ``q``): the
  joints' state as after a step, and the re-basing of ``q``; returns ``(number of re-based
  nodes, error code)``;
- ``OP_SET_BASES``: the nodal bases of the records ``system.bases[:coef[0]]`` into every
  holder (a resumed run); returns ``(0, 0)``;
- ``OP_HOLD``: the clearance joints' held active set
  (:func:`~flexmbs.contact.clearance_term.clearance_hold`, action ``coef[0]``) for the Python
  Newton loop; returns ``(its count for HOLD_READ, 0)``;
- ``OP_STEPS``: up to ``run.n_steps`` generalized-α steps (``fv[k]`` = time-function values at
  the end of step k); returns ``(status, 0)``.

The entry is compiled without numba's reference counting (``njit(refcount=False)``): it only
passes the system's arrays on, and the counting of every array of every part at each of its
calls made it the largest single compile cost (docs/design-notes.md, "Cost of compilation").

Callers that only evaluate pass :func:`~flexmbs.steploop.idle_run` as ``run`` and a
one-row ``fv``, so that every call for a model has the same argument types (one signature, one
library per kind of model: the optional kinds of terms a model lacks are ``None`` in the system
it receives, :data:`flexmbs.driver.OPTIONAL_KINDS`, and are not compiled for it).
:func:`prepare` announces a compile and records its duration (the next one's estimate).
"""

from __future__ import annotations

import contextlib
import json
import os
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ._jit import njit
from .driver import hold_contacts, jacobian, post_step, rebase_static, residual, set_bases
from .steploop import alpha_run

__all__ = ["OP_STEPS", "OP_RESIDUAL", "OP_JACOBIAN", "OP_POST_STEP", "OP_REBASE", "OP_SET_BASES",
           "OP_HOLD",
           "KERNEL_CHOICES", "kernel", "kernels_cached", "prepare", "model_kind", "kernel_choice",
           "announce_compile"]

OP_STEPS, OP_RESIDUAL, OP_JACOBIAN, OP_POST_STEP, OP_REBASE, OP_SET_BASES, OP_HOLD = range(7)


@njit(refcount=False, nogil=True)
def kernel(op, system, q, v, qdd, lam, fv, mode, coef, r, data, run):
    """See the module docstring."""
    if op == OP_RESIDUAL:
        return residual(system, q, v, qdd, lam, fv[0], mode, r)
    if op == OP_JACOBIAN:
        return jacobian(system, q, v, qdd, lam, fv[0], mode, coef[0], coef[1], coef[2], data)
    if op == OP_POST_STEP:
        return 0.0, post_step(system, q, v, qdd, run.a)
    if op == OP_REBASE:
        count, code = rebase_static(system, q)
        return float(count), code
    if op == OP_SET_BASES:
        set_bases(system, system.bases, int(coef[0]), True, q[:0])
        return 0.0, 0
    if op == OP_HOLD:
        return float(hold_contacts(system, int(coef[0]))), 0
    return float(alpha_run(system, q, v, qdd, lam, fv, mode, r, data, run)), 0


def kernels_cached() -> bool:
    """Whether numba's on-disk cache holds a compiled :func:`kernel` for some model (each kind
    of model, by its element types and optional kinds of terms, has its own, see
    :func:`prepare`)."""
    try:
        return bool(kernel._cache._cache_file._load_index())
    except Exception:   # no numba, caching disabled, or numba internals changed
        return True


#: called before :func:`kernel` compiles for a new kind of model, with the last compile's
#: seconds here (of this kind if recorded, else the longest of any kind; None if none is
#: recorded), the kind and whether the seconds are this kind's; the ``flexmbs`` command prints
#: one line
announce_compile: Callable[[float | None, str, bool], None] | None = None

#: which kernel serves a model (:func:`prepare`; environment variable ``FLEXMBS_KERNEL``):
#: ``"auto"`` its own kind's if compiled or cached, else the complete kernel of its element
#: groups if that is, else its own kind's, compiled now; ``"own"`` always its own kind's;
#: ``"complete"`` always the complete one (``flexmbs compile --complete``)
KERNEL_CHOICES = ("auto", "own", "complete")

#: kinds of model whose kernel this process has made ready (see :func:`prepare`)
_READY: set[Any] = set()

_TIMES_FILE = "flexmbs-compile-times.json"


def model_kind(system: Any, complete: bool = False) -> str:
    """A name of the kernel's specialisation for a packed system: its element types and the
    optional kinds of terms it holds, e.g. ``BeamPart+bodies+norms+clearance``; a system whose
    every part is present (the complete kernel of its element groups, :func:`prepare`): e.g.
    ``BeamPart+RodPart complete``."""
    from .driver import OPTIONAL_KINDS

    kinds = [type(p).__name__ for p in system.beams] or ["no beams"]
    if complete:
        return "+".join(kinds) + " complete"
    kinds += [k for k in OPTIONAL_KINDS if getattr(system, k) is not None]
    return "+".join(kinds)


def kernel_choice() -> str:
    """The selection of :data:`KERNEL_CHOICES` in force (``FLEXMBS_KERNEL``, default ``auto``)."""
    choice = os.environ.get("FLEXMBS_KERNEL", "auto").strip().lower() or "auto"
    if choice not in KERNEL_CHOICES:
        from .errors import FlexmbsError
        raise FlexmbsError(f"environment variable FLEXMBS_KERNEL={choice!r}: expected one of "
                           f"{', '.join(KERNEL_CHOICES)} (or unset it)")
    return choice


def prepare(args: tuple[Any, ...], complete: Any = None) -> Any:
    """Make :func:`kernel` ready for a call's arguments ``args`` and return the packed system
    to call it with: ``args[1]`` (the model's own kind, where the optional kinds it lacks are
    None), or ``complete`` (the same model with every part present, empty where it has none:
    the complete kernel of its element groups serves every model with them, somewhat slower,
    docs/design-notes.md "Compile time: the complete kernels"), as
    :func:`kernel_choice` says. Ready: compiled in this process, or in numba's cache (the call
    loads it); otherwise announced (:data:`announce_compile`), compiled here and its duration
    recorded beside the cache (the next compile's estimate). Never raises for numba's
    internals: the call compiles then."""
    own = args[1]
    choice = kernel_choice()
    if complete is None or complete is own:
        choice = "own"
    candidates = {"auto": (own, complete), "own": (own,), "complete": (complete,)}[choice]
    try:
        sigs = [_signature(args, system) for system in candidates]
    except Exception:   # no numba (FLEXMBS_DISABLE_JIT)
        return candidates[0]
    for system, sig in zip(candidates, sigs, strict=True):
        if _is_ready(sig):
            _READY.add(sig)
            return system
    system, sig = candidates[0], sigs[0]
    _READY.add(sig)
    try:
        folder = Path(kernel._cache._cache_path)
    except Exception:   # caching disabled or numba internals changed
        return system
    kind = model_kind(system, complete=system is complete)
    times = _read_times(folder)
    estimate = times.get(kind, max(times.values(), default=None))
    if announce_compile is not None:
        announce_compile(estimate, kind, kind in times)
    start = time.perf_counter()
    kernel.compile(sig)
    times = _read_times(folder)     # another process may have recorded a kind meanwhile
    times[kind] = round(time.perf_counter() - start, 1)
    _write_times(folder, times)
    return system


def _signature(args: tuple[Any, ...], system: Any) -> tuple[Any, ...]:
    """numba's argument types of a call of :func:`kernel` with ``args`` and ``system``."""
    return tuple(kernel.typeof_pyval(a) for a in (*args[:1], system, *args[2:]))


def _is_ready(sig: tuple[Any, ...]) -> bool:
    """Whether :func:`kernel` for ``sig`` is compiled in this process or in numba's cache."""
    if sig in _READY or sig in kernel.overloads:
        return True
    try:
        cache = kernel._cache
        return cache._index_key(sig, kernel.targetctx.codegen()) in cache._cache_file._load_index()
    except Exception:   # caching disabled or numba internals changed
        return False


def _read_times(folder: Path) -> dict[str, float]:
    try:
        data = json.loads((folder / _TIMES_FILE).read_text())
        return {str(k): float(v) for k, v in data.items()}
    except (OSError, ValueError, AttributeError, TypeError):
        return {}


def _write_times(folder: Path, times: dict[str, float]) -> None:
    path = folder / _TIMES_FILE
    tmp = path.with_name(f"{path.name}.{os.getpid()}.tmp")
    try:
        tmp.write_text(json.dumps(times, indent=1, sort_keys=True))
        os.replace(tmp, path)
    except OSError:   # a read-only installation: no estimate next time
        with contextlib.suppress(OSError):
            tmp.unlink()

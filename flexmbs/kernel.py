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
from .driver import jacobian, post_step, rebase_static, residual, set_bases
from .steploop import alpha_run

__all__ = ["OP_STEPS", "OP_RESIDUAL", "OP_JACOBIAN", "OP_POST_STEP", "OP_REBASE", "OP_SET_BASES",
           "kernel", "kernels_cached", "prepare", "model_kind", "announce_compile"]

OP_STEPS, OP_RESIDUAL, OP_JACOBIAN, OP_POST_STEP, OP_REBASE, OP_SET_BASES = range(6)


@njit(refcount=False, nogil=True)
def kernel(op, system, q, v, qdd, lam, fv, mode, coef, r, data, run):  # noqa: ANN001, ANN201
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
    return float(alpha_run(system, q, v, qdd, lam, fv, mode, r, data, run)), 0


def kernels_cached() -> bool:
    """Whether numba's on-disk cache holds a compiled :func:`kernel` for some model (each kind
    of model, by its element types and optional kinds of terms, has its own, see
    :func:`prepare`)."""
    try:
        return bool(kernel._cache._cache_file._load_index())
    except Exception:   # no numba, caching disabled, or numba internals changed  # noqa: BLE001
        return True


#: called before :func:`kernel` compiles for a new kind of model, with the last compile's
#: seconds here (of this kind if recorded, else the longest of any kind; None if none is
#: recorded), the kind and whether the seconds are this kind's; the ``flexmbs`` command prints
#: one line
announce_compile: Callable[[float | None, str, bool], None] | None = None

#: kinds of model whose kernel this process has made ready (see :func:`prepare`)
_READY: set[Any] = set()

_TIMES_FILE = "flexmbs-compile-times.json"


def model_kind(system: Any) -> str:
    """A name of the kernel's specialisation for a packed system: its element types and the
    optional kinds of terms it holds, e.g. ``BeamPart+bodies+clearance``."""
    from .driver import OPTIONAL_KINDS

    kinds = [type(p).__name__ for p in system.beams] or ["no beams"]
    kinds += [k for k in OPTIONAL_KINDS if getattr(system, k) is not None]
    return "+".join(kinds)


def prepare(args: tuple[Any, ...]) -> None:
    """Make :func:`kernel` ready for the types of ``args`` (a call's arguments): nothing if it
    is compiled in this process; loaded by the call if numba's cache holds it; else announced
    (:data:`announce_compile`), compiled here and its duration recorded beside the cache (the
    next compile's estimate). Never raises for numba's internals: the call compiles then."""
    try:
        sig = tuple(kernel.typeof_pyval(a) for a in args)
    except Exception:   # no numba (FLEXMBS_DISABLE_JIT)  # noqa: BLE001
        return
    if sig in _READY or sig in kernel.overloads:
        return
    _READY.add(sig)
    try:
        cache = kernel._cache
        key = cache._index_key(sig, kernel.targetctx.codegen())
        if key in cache._cache_file._load_index():
            return
        folder = Path(cache._cache_path)
    except Exception:   # caching disabled or numba internals changed  # noqa: BLE001
        return
    kind = model_kind(args[1])
    times = _read_times(folder)
    estimate = times.get(kind, max(times.values(), default=None))
    if announce_compile is not None:
        announce_compile(estimate, kind, kind in times)
    start = time.perf_counter()
    kernel.compile(sig)
    times[kind] = round(time.perf_counter() - start, 1)
    _write_times(folder, times)


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

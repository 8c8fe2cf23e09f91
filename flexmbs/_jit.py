"""Compilation shim: numba's ``njit`` when available, a transparent no-op otherwise.

numba is a core dependency (the hot loop must run compiled), but keeping the kernels importable
without it lets the pure-Python path serve as a slow, debuggable reference.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

try:  # pragma: no cover - exercised implicitly
    if os.environ.get("FLEXMBS_DISABLE_JIT", "") == "1":
        raise ImportError
    from numba import njit as _njit

    HAVE_NUMBA = True
except ImportError:  # pragma: no cover
    HAVE_NUMBA = False
    _njit = None  # type: ignore[assignment]


def njit(*args: Any, **kwargs: Any) -> Any:
    """``numba.njit(cache=True, ...)`` or identity when numba is absent or disabled."""
    if _njit is None:
        if len(args) == 1 and callable(args[0]) and not kwargs:
            return args[0]
        return lambda f: f
    kwargs.setdefault("cache", True)
    if len(args) == 1 and callable(args[0]):
        return _tolerate_stale_cache(_njit(**kwargs)(args[0]))
    decorate = _njit(*args, **kwargs)
    return lambda f: _tolerate_stale_cache(decorate(f))


def _tolerate_stale_cache(dispatcher: Any) -> Any:
    """An on-disk cache index written by an older flexmbs can name types of modules that no
    longer exist (numba unpickles it before it checks the source stamp, and then fails with
    ModuleNotFoundError): such an index is treated as empty, so the kernel is compiled again
    and the cache rewritten."""
    cache_file: Any = getattr(getattr(dispatcher, "_cache", None), "_cache_file", None)
    load = getattr(cache_file, "_load_index", None)
    if load is None:   # no cache, or numba internals changed: nothing to guard
        return dispatcher

    def load_index() -> Any:
        try:
            return load()
        except (ImportError, AttributeError, EOFError):
            return {}

    cache_file._load_index = load_index
    return dispatcher


#: Runtime booleans for compiled callers. A literal ``True``/``False`` (or int) argument of a call
#: from compiled code makes numba compile a separate specialisation of the callee
#: (``Literal[bool]``), one more copy of its machine code; ``FLAG[0]``/``FLAG[1]`` (and
#: ``np.int64(n)``) are typed like the values a Python caller passes.
FLAG = np.array([False, True])

__all__ = ["njit", "HAVE_NUMBA", "FLAG"]

"""Compilation shim: numba's ``njit`` when available, a transparent no-op otherwise.

numba is a core dependency (the hot loop must run compiled), but keeping the kernels importable
without it lets the pure-Python path serve as a slow, debuggable reference.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path
from typing import Any

import numpy as np

try:  # pragma: no cover - exercised implicitly
    if os.environ.get("FLEXMBS_DISABLE_JIT", "") == "1":
        raise ImportError
    from numba import literal_unroll
    from numba import njit as _njit

    HAVE_NUMBA = True
except ImportError:  # pragma: no cover
    HAVE_NUMBA = False
    _njit = None  # type: ignore[assignment]

    def literal_unroll(container: Any) -> Any:  # type: ignore[misc, no-redef]
        """Identity without numba (numba's unrolls a loop over a heterogeneous tuple)."""
        return container


def package_stamp(root: str | os.PathLike[str]) -> str:
    """Content hash of every module under ``root`` that holds compiled kernels (text contains
    ``njit``): the on-disk cache stamp of every flexmbs kernel.

    numba stamps a cached function with its own file only, but a kernel carries the machine
    code of every kernel it calls (the one entry :func:`flexmbs.kernel.kernel` all of them):
    after an edit of a callee's module (``git pull`` in a development checkout keeps the
    caller's file untouched) numba would load the stale code. With this stamp an edit of any
    kernel module recompiles them all."""
    h = hashlib.sha1()
    for path in sorted(Path(root).rglob("*.py")):
        text = path.read_bytes()
        if b"njit" in text:
            h.update(str(path.relative_to(root)).encode() + b"\0" + text + b"\0")
    return h.hexdigest()


def _install_package_stamp() -> None:
    """Put cache locators first that give this package's kernels :func:`package_stamp` as
    their source stamp (numba's own locators otherwise, e.g. for users' functions)."""
    try:
        from numba.core import caching
        impl = getattr(caching, "CacheImpl", None) or getattr(caching, "_CacheImpl")  # noqa: B009
        names = ("UserProvidedCacheLocator", "_UserProvidedCacheLocator", "InTreeCacheLocator",
                 "_InTreeCacheLocator")
        bases = [b for b in dict.fromkeys(getattr(caching, n, None) for n in names) if b is not None]
    except (ImportError, AttributeError):   # numba internals changed: keep numba's stamps
        return
    root = Path(__file__).resolve().parent
    stamp = package_stamp(root)

    def locator(base: Any) -> Any:
        class PackageLocator(base):  # type: ignore[misc, valid-type]
            def get_source_stamp(self) -> str:
                return stamp

            @classmethod
            def from_function(cls, py_func: Any, py_file: str) -> Any:
                if not Path(py_file).resolve().is_relative_to(root):
                    return None
                return super().from_function(py_func, py_file)

        PackageLocator.__name__ = "Flexmbs" + base.__name__.lstrip("_")
        return PackageLocator

    def caller_locator(base: Any) -> Any:
        class CallerLocator(base):  # type: ignore[misc, valid-type]
            """A function outside the package compiled by :func:`njit` (a benchmark's timing
            loop, a user's kernel): its cached code holds the package kernels it calls, so its
            stamp is its own file's and the package's."""

            def get_source_stamp(self) -> Any:
                return (super().get_source_stamp(), stamp)

            @classmethod
            def from_function(cls, py_func: Any, py_file: str) -> Any:
                if not getattr(py_func, _CALLER_MARK, False) \
                        or Path(py_file).resolve().is_relative_to(root):
                    return None
                return super().from_function(py_func, py_file)

        CallerLocator.__name__ = "FlexmbsCaller" + base.__name__.lstrip("_")
        return CallerLocator

    impl._locator_classes = ([locator(b) for b in bases] + [caller_locator(b) for b in bases]
                             + list(impl._locator_classes))


#: attribute :func:`njit` sets on the Python functions it compiles (their cache stamp then
#: includes the package's, :func:`_install_package_stamp`)
_CALLER_MARK = "__flexmbs_njit__"


if _njit is not None:
    _install_package_stamp()


def _nrt_option_known() -> bool:
    """Whether this numba accepts ``_nrt=False`` (a flag of its own test suite)."""
    try:
        from numba.core import cpu
        return "_nrt" in cpu.CPUTargetOptions.__dict__ or hasattr(cpu.CPUTargetOptions, "_nrt")
    except (ImportError, AttributeError):   # numba internals changed: keep the default
        return False


_NRT_OPTION = _njit is not None and _nrt_option_known()


def njit(*args: Any, refcount: bool = True, internal: bool = False, **kwargs: Any) -> Any:
    """``numba.njit(cache=True, ...)`` or identity when numba is absent or disabled.

    ``internal=True``: a kernel that only compiled code calls (the term kinds' functions the
    driver sums): numba builds no Python entry for it (``no_cpython_wrapper``), whose code
    unboxes every array of a packed part from Python objects and is compiled like any other
    (measured: 0.45 s of a function taking a part of 62 arrays). Calling it from Python then
    raises a TypeError (:func:`_compiled_callers_only`).

    ``refcount=False`` compiles without numba's reference counting of arrays (its NRT), for
    kernels that neither allocate nor keep an array beyond the call (they only read and write
    their callers' arrays): every view or field of a tuple of arrays otherwise costs an atomic
    increment and decrement, which made the rod's element kernel 4x slower (measured: 9.1 ->
    2.3 µs per element residual). The flag is always set explicitly: numba compiles a callee
    that leaves it unset with its first caller's setting (``nrt`` is inherited), so a kernel
    that allocates would otherwise fail to compile when first called from one without
    reference counting, or be cached without it. A ``refcount=False`` function must neither
    allocate nor return arrays (nor call a function that returns one). Falls back to the
    default if numba does not know the option."""
    if _njit is None:
        if len(args) == 1 and callable(args[0]) and not kwargs:
            return args[0]
        return lambda f: f
    for f in args[:1]:
        if callable(f):
            setattr(f, _CALLER_MARK, True)
    kwargs.setdefault("cache", True)
    if internal:
        kwargs["no_cpython_wrapper"] = True
    if _NRT_OPTION:
        kwargs["_nrt"] = refcount
    wrap = _compiled_callers_only if internal else (lambda d: d)
    if len(args) == 1 and callable(args[0]):
        return wrap(_tolerate_stale_cache(_njit(**kwargs)(args[0])))
    decorate = _njit(*args, **kwargs)

    def compile_marked(f: Any) -> Any:
        setattr(f, _CALLER_MARK, True)
        return wrap(_tolerate_stale_cache(decorate(f)))

    return compile_marked


_INTERNAL_CLASSES: dict[type, type] = {}


def _compiled_callers_only(dispatcher: Any) -> Any:
    """A call of an ``internal`` kernel from Python raises a TypeError naming it (numba would
    call its missing Python entry and crash the interpreter); compiled callers see the same
    dispatcher (its class is a subclass that only overrides the Python call)."""
    base = type(dispatcher)
    cls = _INTERNAL_CLASSES.get(base)
    if cls is None:
        def call(self: Any, *args: Any, **kwargs: Any) -> Any:
            raise TypeError(f"{self.py_func.__module__}.{self.py_func.__qualname__} is compiled "
                            "for compiled callers only (njit(internal=True)); call the compiled "
                            "entry (flexmbs.kernel) instead")
        cls = type(base.__name__, (base,), {"__call__": call})
        _INTERNAL_CLASSES[base] = cls
    dispatcher.__class__ = cls
    return dispatcher


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

__all__ = ["njit", "literal_unroll", "HAVE_NUMBA", "FLAG"]

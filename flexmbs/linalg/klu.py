"""SuiteSparse KLU (sparse direct LU, BTF + AMD/COLAMD) callable from numba nopython code.

The library is the ``libklu`` shipped inside the ``kvxopt`` wheel (``pip install kvxopt``; on
Linux ``kvxopt.libs/libklu-*.so.*``, on macOS ``kvxopt/.dylibs/libklu*.dylib``); the environment
variable ``FLEXMBS_KLU_LIBRARY`` names another one (a system ``libklu.so.2``, say), and a
library that the system's linker finds (``ctypes.util.find_library("klu")``) is the last resort.

Binding: the library is opened with ctypes (``RTLD_LOCAL``: its ``klu_*``/``amd_*`` symbols do
not enter the process's global namespace) and each function's address is registered with
LLVM under a private name (``flexmbs_klu_factor``, ...; ``llvmlite.binding.add_symbol``) at
import. Compiled code refers to that *name* only (``types.ExternalFunction``), which LLVM
resolves when it links the code, also code loaded from numba's on-disk cache: no address is
baked into cached machine code, and no other ``klu_factor`` in the process (another package's
bundled copy) can be picked up instead.

All functions are ``@njit`` and callable from Python and from compiled code. Matrices
are CSC with C-contiguous ``int32`` column pointers ``Ap`` (n+1) and row indices ``Ai`` and
``float64`` values ``Ax``. Handles (``klu_symbolic*``, ``klu_numeric*``) are ``int64``, 0 for
none; keep them in an ``int64`` array. ``common`` is an ``int64`` array from :func:`new_common`
(the C ``klu_common``, 160 bytes on 64-bit platforms, over-allocated to 1024). Failures return
0 (handle or flag) with KLU's status in :func:`klu_status` (``KLU_SINGULAR`` = 1,
``KLU_OUT_OF_MEMORY`` = -2, ``KLU_INVALID`` = -3, ``KLU_TOO_LARGE`` = -4). Not thread-safe per
object: ``klu_solve`` uses the numeric object's workspace, so threads need their own numeric
objects and commons.

Usage::

    import numpy as np, scipy.sparse as sp
    from flexmbs.linalg import klu

    A = (sp.random(200, 200, density=0.02, random_state=0) + 4 * sp.eye(200)).tocsc()
    Ap, Ai = A.indptr.astype(np.int32), A.indices.astype(np.int32)
    common = klu.new_common()                     # klu_defaults already applied
    h = np.zeros(2, np.int64)                     # [symbolic, numeric]
    h[0] = klu.klu_analyse(200, Ap, Ai, common)   # once per pattern
    h[1] = klu.klu_factorise(Ap, Ai, A.data, h[0], common)
    b = np.ones(200)
    assert klu.klu_solve_inplace(h[0], h[1], 200, 1, b, common)   # b := A^-1 b
    A.data *= 2.0                                 # new values, same pattern
    assert klu.klu_refactorise(Ap, Ai, A.data, h[0], h[1], common)
    klu.klu_free_numeric(h, 1, common)
    klu.klu_free_symbolic(h, 0, common)           # both slots now 0
"""

from __future__ import annotations

import ctypes
import ctypes.util
import glob
import importlib.util
import os
import struct
from collections.abc import Callable
from typing import Any

import llvmlite.binding as llvm
import numpy as np
from llvmlite import ir
from numba import types
from numba.core.errors import TypingError
from numba.extending import intrinsic

from .._jit import njit

__all__ = [
    "AVAILABLE", "KLU_OK", "KLU_SINGULAR", "KLU_OUT_OF_MEMORY", "KLU_INVALID", "KLU_TOO_LARGE",
    "LIBRARY", "flops", "singular_column", "symbolic_estimate",
    "new_common", "klu_setup", "klu_configure", "klu_status", "klu_rcond",
    "klu_analyse", "klu_factorise", "klu_refactorise", "klu_solve_inplace",
    "klu_free_numeric", "klu_free_symbolic",
]

KLU_OK = 0
KLU_SINGULAR = 1
KLU_OUT_OF_MEMORY = -2
KLU_INVALID = -3
KLU_TOO_LARGE = -4

#: ``klu_common`` (identical in KLU 1.3 and 2.x, LP64/LLP64): double tol@0 memgrow@8
#: initmem_amd@16 initmem@24 maxwork@32; int btf@40 ordering@44 scale@48; pointers user_order@56
#: user_data@64; int halt_if_singular@72 status@76 nrealloc@80 structural_rank@84
#: numerical_rank@88 singular_col@92 noffdiag@96; double flops@104 rcond@112 condest@120
#: rgrowth@128 work@136; size_t memusage@144 mempeak@152. Indices below are into int32 / float64
#: views of the common array.
_COMMON_WORDS = 128                 # 1024 bytes, of which KLU uses 160
_I_BTF, _I_ORDERING, _I_SCALE, _I_HALT, _I_STATUS, _I_SINGULAR_COL = 10, 11, 12, 18, 19, 23
_D_TOL, _D_FLOPS, _D_RCOND = 0, 13, 14
_SYMBOLIC_N_OFFSET = 40             # klu_symbolic: 4 doubles, double *Lnz, then int n

_FUNCTIONS = ("klu_defaults", "klu_analyze", "klu_factor", "klu_refactor", "klu_solve",
              "klu_free_symbolic", "klu_free_numeric", "klu_rcond")


def _candidates() -> list[str]:
    """Library paths to try, in order (see the module docstring)."""
    found = [os.environ["FLEXMBS_KLU_LIBRARY"]] if os.environ.get("FLEXMBS_KLU_LIBRARY") else []
    spec = importlib.util.find_spec("kvxopt")          # locates the wheel without importing it
    for pkg in (spec.submodule_search_locations or []) if spec is not None else []:
        site = os.path.dirname(pkg)
        found += sorted(glob.glob(os.path.join(site, "kvxopt.libs", "libklu*.so*")))    # Linux
        found += sorted(glob.glob(os.path.join(pkg, ".dylibs", "libklu*.dylib")))       # macOS
    system = ctypes.util.find_library("klu")
    return found + ([system] if system else [])


def _check(path: str) -> ctypes.CDLL | str:
    """The library at ``path`` if it exports every function and its ``klu_common`` has the
    layout above (``klu_defaults`` called on a poisoned buffer), else why not."""
    try:
        lib = ctypes.CDLL(path)
    except OSError as exc:
        return str(exc)
    missing = [f for f in _FUNCTIONS if not hasattr(lib, f)]
    if missing:
        return f"does not export {', '.join(missing)}"
    buf = (ctypes.c_byte * 1024)(*([-1] * 1024))
    ok = lib.klu_defaults(buf)
    fields = (ok, struct.unpack_from("=d", buf, 0)[0], *struct.unpack_from("=3i", buf, 40),
              *struct.unpack_from("=2i", buf, 72))      # tol; btf ordering scale; halt status
    if fields != (1, 0.001, 1, 0, 2, 1, 0) or bytes(buf)[160:] != b"\xff" * (1024 - 160):
        return "its klu_common has an unexpected layout"
    return lib


def _open() -> tuple[str, ctypes.CDLL]:
    """The first candidate that passes :func:`_check`."""
    if struct.calcsize("P") != 8:
        raise ImportError("flexmbs.linalg.klu needs a 64-bit Python")
    errors = []
    for path in _candidates():
        lib = _check(path)
        if not isinstance(lib, str):
            return path, lib
        errors.append(f"{path}: {lib}")
    raise ImportError("flexmbs.linalg.klu needs SuiteSparse KLU: pip install kvxopt "
                      "(or set FLEXMBS_KLU_LIBRARY to a libklu shared library)"
                      + ("; tried " + "; ".join(errors) if errors else ""))


def _stubs() -> dict[str, Any]:
    """Functions of KLU's signatures that do nothing and report failure (0, NULL): what the
    names are bound to where no library is found, so that compiled code that can call KLU
    still links; :data:`AVAILABLE` is then False and no plan uses it."""
    ret = {"klu_analyze": ctypes.c_void_p, "klu_factor": ctypes.c_void_p}
    out = {}
    for name in _FUNCTIONS:
        proto = ctypes.CFUNCTYPE(ret.get(name, ctypes.c_int), *([ctypes.c_void_p] * 6))
        out[name] = proto(lambda *args: 0)
    return out


try:
    LIBRARY, _LIB = _open()
    #: whether a KLU library was found (else the names are bound to failing stubs)
    AVAILABLE = True
    MISSING = ""
    _ADDRESSES = {name: ctypes.cast(getattr(_LIB, name), ctypes.c_void_p).value for name in _FUNCTIONS}
except ImportError as _exc:
    LIBRARY, AVAILABLE, MISSING = "", False, str(_exc)
    _STUBS = _stubs()          # kept alive: the compiled code calls them
    _ADDRESSES = {name: ctypes.cast(f, ctypes.c_void_p).value for name, f in _STUBS.items()}
for _name in _FUNCTIONS:
    llvm.add_symbol("flexmbs_" + _name, _ADDRESSES[_name])

_int, _ptr = types.int32, types.voidptr
_c_defaults: Any = types.ExternalFunction("flexmbs_klu_defaults", _int(_ptr))
_c_analyze: Any = types.ExternalFunction("flexmbs_klu_analyze", _ptr(_int, _ptr, _ptr, _ptr))
_c_factor: Any = types.ExternalFunction("flexmbs_klu_factor", _ptr(_ptr, _ptr, _ptr, _ptr, _ptr))
_c_refactor: Any = types.ExternalFunction("flexmbs_klu_refactor",
                                          _int(_ptr, _ptr, _ptr, _ptr, _ptr, _ptr))
_c_solve: Any = types.ExternalFunction("flexmbs_klu_solve", _int(_ptr, _ptr, _int, _int, _ptr, _ptr))
_c_free_symbolic: Any = types.ExternalFunction("flexmbs_klu_free_symbolic", _int(_ptr, _ptr))
_c_free_numeric: Any = types.ExternalFunction("flexmbs_klu_free_numeric", _int(_ptr, _ptr))
_c_rcond: Any = types.ExternalFunction("flexmbs_klu_rcond", _int(_ptr, _ptr, _ptr))


def _intrinsic(typer: Callable[..., Any]) -> Any:
    """numba's ``intrinsic`` (typed ``Any``: its callers pass no typing context)."""
    return intrinsic(typer)


def _array_pointer(dtype: Any, name: str) -> Any:
    """An intrinsic ``f(a)`` -> ``void*`` to the data of a C-contiguous array of ``dtype``
    (a TypingError naming ``name`` for any other argument)."""

    @_intrinsic
    def data(typingctx: Any, a: Any) -> Any:
        if not (isinstance(a, types.Array) and a.dtype == dtype and a.layout == "C"):
            raise TypingError(f"klu: {name} must be a C-contiguous {dtype} array, not {a}")

        def codegen(context: Any, builder: Any, sig: Any, args: Any) -> Any:
            array = context.make_array(sig.args[0])(context, builder, value=args[0])
            return builder.bitcast(array.data, ir.IntType(8).as_pointer())

        return types.voidptr(a), codegen

    return data


_i32_data = _array_pointer(types.int32, "Ap, Ai")
_f64_data = _array_pointer(types.float64, "Ax, b")
_i64_data = _array_pointer(types.int64, "common, handles")


@_intrinsic
def _handle_pointer(typingctx: Any, handle: Any) -> Any:
    """int64 handle -> ``void*``."""
    if not isinstance(handle, types.Integer):
        return None

    def codegen(context: Any, builder: Any, sig: Any, args: Any) -> Any:
        value = context.cast(builder, args[0], sig.args[0], types.int64)
        return builder.inttoptr(value, ir.IntType(8).as_pointer())

    return types.voidptr(handle), codegen


@_intrinsic
def _pointer_handle(typingctx: Any, pointer: Any) -> Any:
    """``void*`` -> int64 handle."""
    if pointer != types.voidptr:
        return None

    def codegen(context: Any, builder: Any, sig: Any, args: Any) -> Any:
        return builder.ptrtoint(args[0], ir.IntType(64))

    return types.int64(pointer), codegen


@_intrinsic
def _slot_pointer(typingctx: Any, handles: Any, index: Any) -> Any:
    """``&handles[index]`` as ``void*`` (KLU's free functions take ``klu_numeric **``)."""
    if not (isinstance(handles, types.Array) and handles.dtype == types.int64
            and handles.layout == "C" and isinstance(index, types.Integer)):
        raise TypingError(f"klu: handles must be a C-contiguous int64 array, not {handles}")

    def codegen(context: Any, builder: Any, sig: Any, args: Any) -> Any:
        array = context.make_array(sig.args[0])(context, builder, value=args[0])
        i = context.cast(builder, args[1], sig.args[1], types.intp)
        return builder.bitcast(builder.gep(array.data, [i]), ir.IntType(8).as_pointer())

    return types.voidptr(handles, index), codegen


@_intrinsic
def _symbolic_n(typingctx: Any, handle: Any) -> Any:
    """``Symbolic->n`` of a non-zero symbolic handle."""
    if not isinstance(handle, types.Integer):
        return None

    def codegen(context: Any, builder: Any, sig: Any, args: Any) -> Any:
        value = context.cast(builder, args[0], sig.args[0], types.int64)
        address = builder.add(value, ir.Constant(ir.IntType(64), _SYMBOLIC_N_OFFSET))
        return builder.load(builder.inttoptr(address, ir.IntType(32).as_pointer()))

    return types.int32(handle), codegen


def new_common() -> np.ndarray:
    """A zeroed 1024-byte ``klu_common`` (int64 array, 8-byte aligned) with KLU's defaults."""
    common = np.zeros(_COMMON_WORDS, np.int64)
    if not klu_setup(common):
        raise RuntimeError("klu_defaults failed")
    return common


@njit
def klu_setup(common: np.ndarray) -> int:
    """Zero ``common`` and apply ``klu_defaults`` (tol 1e-3, BTF on, AMD, max-row scaling,
    halt if singular); 1 if done."""
    if common.size < 20:
        return 0
    common[:] = 0
    return int(_c_defaults(_i64_data(common)))


@njit
def klu_configure(common: np.ndarray, tol: float, btf: int, ordering: int, scale: int,
                  halt_if_singular: int) -> None:
    """Set KLU's parameters: pivot tolerance ``tol`` (diagonal preference, 1 = partial
    pivoting), ``btf`` (1: block triangular pre-ordering), ``ordering`` (0 AMD, 1 COLAMD),
    ``scale`` (-1 none and no checks, 0 none, 1 sum, 2 max), ``halt_if_singular``."""
    common.view(np.float64)[_D_TOL] = tol
    ints = common.view(np.int32)
    ints[_I_BTF] = btf
    ints[_I_ORDERING] = ordering
    ints[_I_SCALE] = scale
    ints[_I_HALT] = halt_if_singular


@njit
def klu_status(common: np.ndarray) -> int:
    """KLU's status after the last call (``KLU_OK``, ``KLU_SINGULAR``, or < 0)."""
    return int(common.view(np.int32)[_I_STATUS])


@njit
def singular_column(common: np.ndarray) -> int:
    """The first singular column KLU met (``Common->singular_col``; n when none)."""
    return int(common.view(np.int32)[_I_SINGULAR_COL])


@njit
def _fail(common: np.ndarray, status: int) -> None:
    common.view(np.int32)[_I_STATUS] = status


@njit
def klu_analyse(n: int, Ap: np.ndarray, Ai: np.ndarray, common: np.ndarray) -> int:
    """Order the pattern (BTF, then AMD or COLAMD per block): a symbolic handle, 0 on failure."""
    if n < 0 or n > 2**31 - 2 or Ap.size != n + 1 or Ai.size < Ap[n]:
        _fail(common, KLU_INVALID)
        return 0
    return _pointer_handle(_c_analyze(np.int32(n), _i32_data(Ap), _i32_data(Ai),
                                      _i64_data(common)))


@njit
def klu_factorise(Ap: np.ndarray, Ai: np.ndarray, Ax: np.ndarray, symbolic: int,
                  common: np.ndarray) -> int:
    """Factorise with partial pivoting on ``symbolic``'s pattern: a numeric handle, 0 on
    failure (``klu_status``: ``KLU_SINGULAR`` for a singular matrix)."""
    if symbolic == 0 or Ap.size != _symbolic_n(symbolic) + 1 or Ai.size < Ap[Ap.size - 1] \
            or Ax.size < Ap[Ap.size - 1]:
        _fail(common, KLU_INVALID)
        return 0
    return _pointer_handle(_c_factor(_i32_data(Ap), _i32_data(Ai), _f64_data(Ax),
                                     _handle_pointer(symbolic), _i64_data(common)))


@njit
def klu_refactorise(Ap: np.ndarray, Ai: np.ndarray, Ax: np.ndarray, symbolic: int, numeric: int,
                    common: np.ndarray) -> int:
    """New values, same pattern, the pivot order of the last :func:`klu_factorise` (no
    pivoting: check :func:`klu_rcond` or factorise anew when values change much); 1 if done."""
    if symbolic == 0 or numeric == 0 or Ap.size != _symbolic_n(symbolic) + 1 \
            or Ai.size < Ap[Ap.size - 1] or Ax.size < Ap[Ap.size - 1]:
        _fail(common, KLU_INVALID)
        return 0
    return int(_c_refactor(_i32_data(Ap), _i32_data(Ai), _f64_data(Ax), _handle_pointer(symbolic),
                           _handle_pointer(numeric), _i64_data(common)))


@njit
def klu_solve_inplace(symbolic: int, numeric: int, n: int, nrhs: int, b: np.ndarray,
                      common: np.ndarray) -> int:
    """Overwrite ``b`` (``nrhs`` right-hand sides of length ``n`` one after another, 1-D) with
    ``A^-1 b``; 1 if done."""
    if symbolic == 0 or numeric == 0 or nrhs < 0 or n != _symbolic_n(symbolic) \
            or b.size < n * nrhs:
        _fail(common, KLU_INVALID)
        return 0
    return int(_c_solve(_handle_pointer(symbolic), _handle_pointer(numeric), np.int32(n),
                        np.int32(nrhs), _f64_data(b), _i64_data(common)))


@njit
def klu_rcond(symbolic: int, numeric: int, common: np.ndarray) -> float:
    """KLU's cheap reciprocal condition estimate min|U_ii| / max|U_ii| (-1 on failure)."""
    if symbolic == 0 or numeric == 0 or not _c_rcond(_handle_pointer(symbolic),
                                                     _handle_pointer(numeric), _i64_data(common)):
        return -1.0
    return common.view(np.float64)[_D_RCOND]


@njit
def klu_free_numeric(handles: np.ndarray, index: int, common: np.ndarray) -> None:
    """Free the numeric object in ``handles[index]`` (if any) and set the slot to 0."""
    if index < 0 or index >= handles.size:
        return
    if handles[index] != 0:
        _c_free_numeric(_slot_pointer(handles, index), _i64_data(common))
    handles[index] = 0


@njit
def klu_free_symbolic(handles: np.ndarray, index: int, common: np.ndarray) -> None:
    """Free the symbolic object in ``handles[index]`` (if any) and set the slot to 0."""
    if index < 0 or index >= handles.size:
        return
    if handles[index] != 0:
        _c_free_symbolic(_slot_pointer(handles, index), _i64_data(common))
    handles[index] = 0



def flops(symbolic: int, numeric: int, common: np.ndarray) -> tuple[float, int]:
    """The floating-point operations of the factorisation ``numeric`` (``klu_flops``) and
    its entries in L and U (``Numeric->lnz + unz``, the solves' work)."""
    if not AVAILABLE:
        raise ImportError(MISSING)
    if not symbolic or not numeric:
        raise ValueError("klu.flops: no factorisation")
    _LIB.klu_flops(ctypes.c_void_p(symbolic), ctypes.c_void_p(numeric),
                   ctypes.c_void_p(common.ctypes.data))
    lnz, unz = struct.unpack("=2i", ctypes.string_at(numeric + 8, 8))   # n, nblocks, lnz, unz
    return float(common.view(np.float64)[_D_FLOPS]), int(lnz) + int(unz)


def symbolic_estimate(symbolic: int) -> tuple[float, float, float]:
    """AMD's estimates in a symbolic analysis (``Symbolic->est_flops, lnz, unz``): the
    factorisation's operations and the entries of L and U when no pivot leaves the diagonal
    (no numeric factorisation needed)."""
    if not AVAILABLE:
        raise ImportError(MISSING)
    if not symbolic:
        raise ValueError("klu.symbolic_estimate: no analysis")
    _, est_flops, lnz, unz = struct.unpack("=4d", ctypes.string_at(symbolic, 32))
    return float(est_flops), float(lnz), float(unz)

"""The protocol between the assembler and the owners of the terms of the equations of motion.

Every kind of term (a beam element group, the rigid bodies and their loads, the linear and
prescribed constraint rows, the Euler-parameter normalisation, the joint term tables, the sliding
joints, the clearance joints, the external loads) is owned by one module, which

- reserves its couplings in the sparse pattern (``pattern(dofs)`` -> list of (rows, cols)),
- packs itself into a named tuple of arrays (``pack(dofs, functions)``), reading the global
  numbering through :class:`DofMap` (never the concrete assembler),
- states its residual and Jacobian once, as numba kernels ``residual(part, ...)`` and
  ``jacobian(part, ...)`` next to its physics,

and :mod:`flexmbs.driver` sums the kernels of all kinds. The compiled Newton loop and the Python
Newton loop both call that one driver, so no equation is written twice.
"""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np

__all__ = ["DofMap", "FunctionTable", "pad_stack", "LOAD_FACTOR", "WITH_INERTIA", "WITH_DAMPING", "MODE_SIZE",
           "dynamic_mode", "static_mode"]

#: entries of the ``mode`` vector every kernel receives (a float array, so that compiled callers
#: do not specialise on literal flags)
LOAD_FACTOR, WITH_INERTIA, WITH_DAMPING = 0, 1, 2
MODE_SIZE = 3


def dynamic_mode() -> np.ndarray:
    """Dynamics: full loads, inertia and damping."""
    return np.array([1.0, 1.0, 1.0])


def static_mode(load_factor: float = 1.0, *, damping: bool = False) -> np.ndarray:
    """Statics: loads and prescribed motion scaled by ``load_factor``, no inertia."""
    return np.array([float(load_factor), 0.0, 1.0 if damping else 0.0])


class TimeFunctionLike(Protocol):
    def __call__(self, t: float) -> float: ...


class DofMap(Protocol):
    """Global numbering as the owners of terms see it (implemented by the assembler; the
    arguments are the model's nodes, bodies and beams, which this layer does not import)."""

    n_coords: int

    def node_dofs(self, node: Any) -> np.ndarray:
        """The 6 (or the element's nodal count of) coordinates of a beam node."""

    def body_dofs(self, body: Any) -> np.ndarray:
        """The 7 coordinates ``[r, p]`` of a rigid body."""

    def element_dofs(self, beam: Any) -> np.ndarray:
        """(n_elem, element DOFs) coordinates of every element of a beam."""

    def beam_dofs(self, beam: Any) -> np.ndarray:
        """All coordinates of a beam."""

    def extra_dofs(self, owner: object) -> np.ndarray:
        """Extra coordinates numbered for an interaction (e.g. a slide coordinate)."""

    def multiplier_rows(self, constraint: object) -> np.ndarray:
        """Multiplier index (into ``lam``) of every equation of a constraint, −1 if dropped."""

    def positions(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """CSC data positions of the dense block ``rows × cols`` (global, multipliers at
        ``n_coords + row``), row-major (len(rows), len(cols)) flattened."""

    def positions_present(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """As :meth:`positions`, with −1 for the entries outside the pattern (no error)."""


class PackContext(DofMap, Protocol):
    """What a term kind's ``pack`` sees besides the numbering (implemented by the assembler):
    the model's time functions (a kernel reads their values from ``fv``), the size of the
    unknowns, the coordinates the model starts from and those of the elements' stress-free
    shapes (``q_free``: ``q_ref`` but for beams given a ``stress_free`` shape)."""

    functions: FunctionTable
    n_total: int
    q_ref: np.ndarray
    q_free: np.ndarray

    def matrix_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        """The iteration matrix's CSC ``(indptr, indices)`` (int64; fixed once packed)."""


class FunctionTable:
    """Time functions of a model numbered in first-use order; kernels read their values at the
    current time from a vector ``fv`` (``fv[k] = functions[k](t)``)."""

    def __init__(self) -> None:
        self.items: list[TimeFunctionLike] = []
        self._index: dict[int, int] = {}

    def __call__(self, fn: TimeFunctionLike) -> int:
        key = id(fn)
        if key not in self._index:
            self._index[key] = len(self.items)
            self.items.append(fn)
        return self._index[key]

    def values(self, t: float) -> np.ndarray:
        return np.array([fn(t) for fn in self.items], dtype=float)

    def table(self, t0: float, h: float, n_steps: int) -> np.ndarray:
        """``fv[k, i] = functions[i](t0 + (k + 1) h)``: the values at the end of every step."""
        out = np.empty((n_steps, len(self.items)))
        for k in range(n_steps):
            t = t0 + (k + 1) * h
            for i, fn in enumerate(self.items):
                out[k, i] = fn(t)
        return out


def pad_stack(arrays: list[np.ndarray], tail: tuple[int, ...], fill: float,
              dtype: type) -> np.ndarray:
    """Stack per-object arrays ``(n_i, *tail)`` into ``(len, max n_i, *tail)`` padded with
    ``fill``: how a term kind packs several joints of different sizes into one part."""
    n = max((a.shape[0] for a in arrays), default=0)
    out = np.full((len(arrays), n) + tail, fill, dtype=dtype)
    for i, a in enumerate(arrays):
        out[i, :a.shape[0]] = np.asarray(a).reshape((a.shape[0],) + tail)
    return out

"""Linear constraint rows ``Φ = A q − b − f(t) = 0``: clamps, pins and prescribed coordinates.

The rows are data (a CSR matrix built from the model's constraint specifications); the one
kernel :func:`linear_residual` evaluates them and their reactions ``Aᵀλ``, and
:func:`linear_jacobian` writes the constant entries of ``Φ_q`` and ``Φ_qᵀ``. Prescribed rows
subtract the (load-factor scaled, in statics) value of their time function.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np
import scipy.sparse as sp

from .._jit import njit
from ..terms import LOAD_FACTOR

if TYPE_CHECKING:  # pragma: no cover
    from ..terms import DofMap

__all__ = ["LinearPart", "pack_linear", "linear_residual", "linear_jacobian"]


class LinearPart(NamedTuple):
    indptr: np.ndarray               # CSR of the kept rows (m_lin, n)
    indices: np.ndarray
    data: np.ndarray
    rhs0: np.ndarray                 # (m_lin,) b
    fn_row: np.ndarray               # prescribed rows ...
    fn_idx: np.ndarray               # ... and their time functions
    pos: np.ndarray                  # (nnz,) matrix positions of Φ_q entries (row n + i, col j)
    posT: np.ndarray                 # (nnz,) of the transposed entries


def linear_pattern(matrix: sp.csr_matrix, n: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """Every entry of ``A`` (multiplier row n + i, column j) and its transpose."""
    coo = matrix.tocoo()
    out = []
    for r, c in zip(coo.row, coo.col, strict=True):
        out += [(np.array([n + r]), np.array([c])), (np.array([c]), np.array([n + r]))]
    return out


def pack_linear(matrix: sp.csr_matrix, rhs0: np.ndarray, fn_rows: list[int], fn_idx: list[int],
                dofs: DofMap) -> LinearPart:
    n = dofs.n_coords
    A = sp.csr_matrix(matrix)
    rows = np.repeat(np.arange(A.shape[0]), np.diff(A.indptr))
    pos = np.array([dofs.positions(np.array([n + r]), np.array([c]))[0]
                    for r, c in zip(rows, A.indices, strict=True)], dtype=np.int64)
    posT = np.array([dofs.positions(np.array([c]), np.array([n + r]))[0]
                     for r, c in zip(rows, A.indices, strict=True)], dtype=np.int64)
    i64 = np.int64
    return LinearPart(
        indptr=np.ascontiguousarray(A.indptr, dtype=i64),
        indices=np.ascontiguousarray(A.indices, dtype=i64),
        data=np.ascontiguousarray(A.data, dtype=float),
        rhs0=np.ascontiguousarray(rhs0, float),
        fn_row=np.array(fn_rows, dtype=i64),
        fn_idx=np.array(fn_idx, dtype=i64),
        pos=pos,
        posT=posT)


@njit(internal=True)
def linear_residual(li, n, q, lam, fv, mode, r):
    """``r_λ = A q − b − λ_load f(t)``, ``r_q += Aᵀλ``."""
    for row in range(li.rhs0.size):
        acc = -li.rhs0[row]
        lr = lam[row]
        for k in range(li.indptr[row], li.indptr[row + 1]):
            c = li.indices[k]
            acc += li.data[k] * q[c]
            r[c] += li.data[k] * lr
        r[n + row] = acc
    for k in range(li.fn_row.size):
        r[n + li.fn_row[k]] -= mode[LOAD_FACTOR] * fv[li.fn_idx[k]]


@njit(internal=True)
def linear_jacobian(li, data):
    """The constant entries ``A`` and ``Aᵀ`` of the iteration matrix."""
    for k in range(li.data.size):
        data[li.pos[k]] += li.data[k]
        data[li.posT[k]] += li.data[k]

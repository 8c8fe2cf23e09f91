"""The sparsity pattern of the iteration matrix ``[[cM M + cC C + cK K, Phi_q^T], [Phi_q, 0]]``:
the union of the dense blocks the owners of terms reserve and the full diagonal, in CSC form,
built once; an owner finds the data positions of its entries through :meth:`positions`."""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
import scipy.sparse as sp

from ..errors import ModelError


class SparsePattern:
    """CSC pattern of an ``n_total × n_total`` matrix and the matrix that holds its data
    (``matrix.data`` is refilled in place; the pattern never changes)."""

    def __init__(self, n_total: int, blocks: Iterable[tuple[np.ndarray, np.ndarray]]) -> None:
        N = n_total
        keys = [np.arange(N, dtype=np.int64) * (N + 1)]   # the full diagonal
        for rows, cols in blocks:
            r = np.asarray(rows, np.int64)
            c = np.asarray(cols, np.int64)
            keys.append((c[None, :] * N + r[:, None]).ravel())
        ukeys = np.unique(np.concatenate(keys))
        self._n = N
        self._keys = ukeys      # column-major keys col * N + row of the entries, sorted
        cols = ukeys // N
        rows = ukeys % N
        indptr = np.zeros(N + 1, np.int64)
        np.add.at(indptr, cols + 1, 1)
        indptr = np.cumsum(indptr)
        self.matrix = sp.csc_matrix((np.zeros(ukeys.size), rows.astype(np.int32),
                                     indptr.astype(np.int32)), shape=(N, N))
        self.nnz = ukeys.size

    def positions(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """CSC data positions of the (rows[i], cols[j]) block (must be in the pattern)."""
        N = self._n
        k = (np.asarray(cols, np.int64)[None, :] * N + np.asarray(rows, np.int64)[:, None]).ravel()
        pos = np.searchsorted(self._keys, k)
        if np.any(pos >= self._keys.size) or np.any(self._keys[np.minimum(pos, self._keys.size - 1)] != k):
            raise ModelError("internal: matrix entry outside the reserved sparsity pattern")
        return pos

    def positions_present(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """As :meth:`positions`, with −1 for the entries outside the pattern."""
        N = self._n
        k = (np.asarray(cols, np.int64)[None, :] * N + np.asarray(rows, np.int64)[:, None]).ravel()
        pos = np.minimum(np.searchsorted(self._keys, k), self._keys.size - 1)
        return np.where(self._keys[pos] == k, pos, -1)

    def matrix_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        """CSC ``(indptr, indices)`` as int64 (what compiled code that reads ``data`` by
        column needs, e.g. :func:`flexmbs.driver.constraint_velocity`)."""
        return (np.ascontiguousarray(self.matrix.indptr, dtype=np.int64),
                np.ascontiguousarray(self.matrix.indices, dtype=np.int64))

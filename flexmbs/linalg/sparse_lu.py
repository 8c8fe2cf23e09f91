"""The sparse part of the factorisation: SuiteSparse's KLU on the kept entries of the pattern.

For topologies the band, border and tree cannot serve (many bodies on several beams, holes on
flexible bodies: the tendon robot's disks couple with six tendons and the backbone, and a
dense border of every disk costs its cube), the plan factorises the whole matrix with KLU
(Davis and Palamadai Natarajan 2010: block triangular form, AMD on each block, left-looking
LU with partial pivoting; :mod:`flexmbs.linalg.klu` binds it for compiled code). The pattern's
kept entries are taken in its CSC order (their rows and columns are the matrix's own), the
symbolic analysis is done once per plan, and a refactorisation reuses the last full
factorisation's pivot order while the pivots stay sound: the ratio of U's smallest and
largest diagonal entries (``klu_rcond``) may fall at most :data:`REFACTOR_DROP` times below
its value at that factorisation, else the matrix is factorised anew with pivoting.

Everything the compiled loop needs is one :class:`SparseFactor` (a member of
:class:`~flexmbs.linalg.bordered.BorderedFactor`: every solver keeps one factorisation type);
its ``n`` is 0 in plans that do not use it. KLU's objects are C memory whose addresses live in
``handles``; :class:`SparseHandles` frees them with the Python object that planned them.
"""

from __future__ import annotations

import weakref
from typing import NamedTuple

import numpy as np
import scipy.sparse as sp

from .._jit import njit
from . import klu

#: a refactorisation is kept while klu_rcond stays above this fraction of its value at the last
#: full factorisation (KLU does not pivot when it refactorises)
REFACTOR_DROP = 1e-3
#: KLU's flops are worth this many of the band's in time (left-looking by columns, indirect
#: addressing, no blocking; measured on the tendon robot's following plan: KLU's refactorisation
#: and 8 solves 4.0 ms for an estimate of 5.9e6 flops, the band's 5.6 ms for 9.7e7)
SPARSE_FLOP_WEIGHT = 12.0
#: and a factorisation costs at least this many flops (the symbolic objects' overhead)
SPARSE_OVERHEAD = 2.0e4

#: ``state`` entries: a numeric factorisation held (0/1), refactorisations since the last full
#: one, full factorisations
ST_HAVE, ST_REFACTORS, ST_FULL = range(3)
#: ``values`` rows: klu_rcond at the last full factorisation
V_RCOND = 0


class SparseFactor(NamedTuple):
    """KLU's factorisation of the kept entries of a CSC pattern (module docstring)."""

    n: int                  # unknowns (0: not used)
    Ap: np.ndarray          # int32 (n + 1,): column pointers of the kept entries
    Ai: np.ndarray          # int32 (nnz,): their rows
    src: np.ndarray         # int64 (nnz,): their positions in the pattern's data
    Ax: np.ndarray          # float64 (nnz,): the values last factorised
    Ax_full: np.ndarray     # float64 (nnz,): the values of the last full factorisation
    handles: np.ndarray     # int64 (2,): klu_symbolic*, klu_numeric* (0: none)
    common: np.ndarray      # int64: klu_common
    state: np.ndarray       # int64 (3,): ST_*
    values: np.ndarray      # float64 (1,): V_*


def empty_sparse() -> SparseFactor:
    """A :class:`SparseFactor` of no unknowns, typed like a real one."""
    zi = np.zeros(0, np.int32)
    z = np.zeros(0)
    return SparseFactor(n=0, Ap=np.zeros(1, np.int32), Ai=zi, src=np.zeros(0, np.int64), Ax=z,
                        Ax_full=z, handles=np.zeros(2, np.int64), common=np.zeros(0, np.int64),
                        state=np.zeros(3, np.int64), values=np.zeros(1))


def _kept_csc(A: sp.csc_matrix, keep: np.ndarray | None) -> tuple[np.ndarray, np.ndarray,
                                                                  np.ndarray]:
    """(Ap, Ai, src) of the kept entries of ``A``'s pattern, in its CSC order."""
    N = A.shape[0]
    cols = np.repeat(np.arange(N, dtype=np.int64), np.diff(A.indptr))
    src = np.arange(cols.size, dtype=np.int64)
    if keep is not None:
        src = src[np.asarray(keep, bool)]
    Ap = np.zeros(N + 1, np.int64)
    np.add.at(Ap, cols[src] + 1, 1)
    return (np.ascontiguousarray(np.cumsum(Ap), dtype=np.int32),
            np.ascontiguousarray(A.indices[src], dtype=np.int32), src)


class SparseHandles:
    """Owner of the KLU objects of the :class:`SparseFactor` s it makes: they are freed when it
    is (a factor must not be used after its owner is gone)."""

    def __init__(self, A: sp.csc_matrix, keep: np.ndarray | None = None) -> None:
        if not klu.AVAILABLE:
            raise ImportError(klu.MISSING)
        A = sp.csc_matrix(A)
        if not A.has_sorted_indices:
            raise ValueError("SparseHandles: the pattern's rows must be sorted in each column")
        self.n = A.shape[0]
        self.Ap, self.Ai, self.src = _kept_csc(A, keep)

    def factor(self) -> SparseFactor:
        """A new factor of this pattern with its own symbolic analysis and numeric storage (a
        twin for the velocity corrector shares nothing that a factorisation writes)."""
        common = klu.new_common()
        handles = np.zeros(2, np.int64)
        handles[0] = klu.klu_analyse(self.n, self.Ap, self.Ai, common)
        if handles[0] == 0:
            raise RuntimeError(f"KLU's analysis failed (status {klu.klu_status(common)})")
        weakref.finalize(self, _free, handles, common)
        nnz = self.Ai.size
        return SparseFactor(n=self.n, Ap=self.Ap, Ai=self.Ai, src=self.src, Ax=np.zeros(nnz),
                            Ax_full=np.zeros(nnz), handles=handles, common=common,
                            state=np.zeros(3, np.int64), values=np.zeros(1))


def _free(handles: np.ndarray, common: np.ndarray) -> None:
    klu.klu_free_numeric(handles, 1, common)
    klu.klu_free_symbolic(handles, 0, common)


def sparse_cost(A: sp.csc_matrix, keep: np.ndarray | None, solves: float) -> float:
    """Estimated cost of one KLU factorisation plus ``solves`` solves, in the band's flops
    (:func:`flexmbs.linalg.ordering.factor_cost`): the operations and the entries of L and U
    that AMD's analysis of the kept pattern predicts when no pivot leaves the diagonal
    (``klu.symbolic_estimate``; no numeric factorisation: the analysis of the tendon robot's
    whole reserved pattern takes 88 ms, a factorisation more), ``2 nnz(L + U)`` per solve,
    weighted by :data:`SPARSE_FLOP_WEIGHT`."""
    A = sp.csc_matrix(A, copy=True)
    A.sort_indices()
    Ap, Ai, _ = _kept_csc(A, keep)
    common = klu.new_common()
    handles = np.zeros(2, np.int64)
    try:
        handles[0] = klu.klu_analyse(A.shape[0], Ap, Ai, common)
        if not handles[0]:
            return np.inf
        flops, lnz, unz = klu.symbolic_estimate(int(handles[0]))
    finally:
        _free(handles, common)
    return SPARSE_FLOP_WEIGHT * (max(flops, SPARSE_OVERHEAD) + solves * 2.0 * (lnz + unz))


@njit
def sparse_factorize(sf: SparseFactor, data: np.ndarray) -> int:
    """KLU's factorisation of the kept entries of ``data``: a refactorisation on the last
    pivot order while its pivots stay sound (module docstring), else a full one. Returns 0,
    ``n + 1`` (a non-finite entry) or ``1 + k`` (column k singular)."""
    probe = 0.0
    Ax, src = sf.Ax, sf.src
    for k in range(Ax.size):
        d = data[src[k]]
        probe += 0.0 * d
        Ax[k] = d
    if probe != 0.0:
        return sf.n + 1
    h, common, state = sf.handles, sf.common, sf.state
    if state[ST_HAVE] != 0 and h[1] != 0 and klu.klu_refactorise(sf.Ap, sf.Ai, Ax, h[0], h[1],
                                                                    common):
        rcond = klu.klu_rcond(h[0], h[1], common)
        if rcond >= REFACTOR_DROP * sf.values[V_RCOND] and np.isfinite(rcond):
            state[ST_REFACTORS] += 1
            return 0
    return _full_factorize(sf)


@njit
def _full_factorize(sf: SparseFactor) -> int:
    """A full factorisation (pivoting) of ``sf.Ax``, which becomes ``Ax_full``."""
    h, common, state = sf.handles, sf.common, sf.state
    state[ST_HAVE] = 0
    klu.klu_free_numeric(h, 1, common)
    h[1] = klu.klu_factorise(sf.Ap, sf.Ai, sf.Ax, h[0], common)
    if h[1] == 0:
        return 1 + max(klu.singular_column(common), 0)
    sf.Ax_full[:] = sf.Ax
    sf.values[V_RCOND] = klu.klu_rcond(h[0], h[1], common)
    state[ST_HAVE] = 1
    state[ST_FULL] += 1
    return 0


@njit
def sparse_restore(sf: SparseFactor) -> int:
    """The factorisation a resumed run continues with: the full one of ``Ax_full``, then the
    refactorisation of ``Ax`` on its pivots (the values a snapshot kept), bit for bit the
    factors the run had; 0 or :func:`sparse_factorize`'s codes."""
    last = sf.Ax.copy()
    sf.Ax[:] = sf.Ax_full
    info = _full_factorize(sf)
    sf.Ax[:] = last
    if info != 0:
        return info
    for k in range(last.size):
        if last[k] != sf.Ax_full[k]:
            h = sf.handles
            if not klu.klu_refactorise(sf.Ap, sf.Ai, sf.Ax, h[0], h[1], sf.common):
                sf.state[ST_HAVE] = 0
                return 1 + max(klu.singular_column(sf.common), 0)
            break
    return 0


@njit
def sparse_solve(sf: SparseFactor, b: np.ndarray, x: np.ndarray) -> None:
    """x = A^-1 b with the last factorisation (x must not alias b)."""
    for i in range(sf.n):
        x[i] = b[i]
    klu.klu_solve_inplace(sf.handles[0], sf.handles[1], sf.n, 1, x, sf.common)

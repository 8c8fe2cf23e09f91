"""The sparse part of the factorisation (flexmbs.linalg.sparse_lu): KLU on a plan's kept
entries solves as SuperLU does, refactorises on its pivots while they stay sound and factorises
anew when they do not, restores the same factors bit for bit, and the planner takes it where
no band, border or tree is cheaper (a ladder of chains tied at many levels) and not where one
is (a beam)."""

from __future__ import annotations

import sys

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from flexmbs.linalg.bordered import BorderedBandedLU, bordered_factorize, bordered_solve
from flexmbs.linalg.ordering import plan_factorization
from flexmbs.linalg.sparse_lu import ST_FULL, ST_REFACTORS, sparse_restore

# KLU is a dependency everywhere but on Windows (kvxopt's wheel there exports no KLU): a
# missing library elsewhere is a broken install, and these tests then fail
pytestmark = pytest.mark.skipif(sys.platform == "win32",
                                reason="no SuiteSparse KLU library on Windows")


def _ladder(chains: int, length: int, every: int, seed: int = 0) -> sp.csc_matrix:
    """``chains`` tridiagonal chains of ``length`` unknowns side by side, all tied to one
    extra unknown at every ``every``-th level (the rungs), nonsymmetric values, a zero
    diagonal on the rungs (saddle-like: the LU must pivot)."""
    rng = np.random.default_rng(seed)
    n = chains * length
    rungs = list(range(0, length, every))
    N = n + len(rungs)
    rows, cols = [], []
    for c in range(chains):
        for i in range(length):
            k = c * length + i
            rows += [k]
            cols += [k]
            if i + 1 < length:
                rows += [k, k + 1]
                cols += [k + 1, k]
    for r, level in enumerate(rungs):
        for c in range(chains):
            k = c * length + level
            rows += [n + r, k]
            cols += [k, n + r]
    vals = rng.uniform(0.5, 1.5, len(rows))
    A = sp.csc_matrix((vals, (rows, cols)), shape=(N, N))
    A = A + sp.diags(np.r_[np.full(n, 8.0), np.zeros(N - n)])
    A = sp.csc_matrix(A)
    A.sort_indices()
    return A


def test_sparse_plan_solves_as_superlu_and_refactorises_on_its_pivots():
    A = _ladder(6, 60, 3)
    lu = BorderedBandedLU(A, np.zeros(0, np.int64), sparse=True)
    f = lu.factor
    assert f.n_band == f.n_border == 0 and f.sparse.n == A.shape[0]
    b = np.random.default_rng(1).standard_normal(A.shape[0])
    assert lu.factorize(A.data)
    np.testing.assert_allclose(lu.solve(b), spla.splu(A).solve(b), rtol=1e-10, atol=1e-12)
    assert f.sparse.state[ST_FULL] == 1
    A2 = A.copy()
    A2.data *= 1.0 + 0.01 * np.sin(np.arange(A2.nnz))      # nearby values: same pivots
    assert lu.factorize(A2.data)
    assert f.sparse.state[ST_REFACTORS] == 1 and f.sparse.state[ST_FULL] == 1
    np.testing.assert_allclose(lu.solve(b), spla.splu(A2).solve(b), rtol=1e-10, atol=1e-12)


def test_a_collapsed_pivot_factorises_anew_with_pivoting():
    """Values whose last pivot order meets a (near) zero pivot: the refactorisation is
    refused by its pivot test and a full factorisation pivots again (the solution as
    SuperLU's), instead of a solve on rounding noise."""
    A = sp.csc_matrix(np.array([[4.0, 1.0, 0.0], [1.0, 3.0, 1.0], [0.0, 1.0, 2.0]]))
    A.sort_indices()
    lu = BorderedBandedLU(A, np.zeros(0, np.int64), sparse=True)
    assert lu.factorize(A.data)
    B = sp.csc_matrix(np.array([[1e-14, 1.0, 0.0], [1.0, 3.0, 1.0], [0.0, 1.0, 2.0]]))
    B.sort_indices()
    assert lu.factorize(B.data)
    assert lu.factor.sparse.state[ST_FULL] == 2
    b = np.array([1.0, 2.0, 3.0])
    np.testing.assert_allclose(lu.solve(b), np.linalg.solve(B.toarray(), b), rtol=1e-12)


def test_restored_factors_are_the_same_bits():
    """A resumed run rebuilds KLU's factors from the values kept (the last full
    factorisation's, then the refactorised ones): the same solution, bit for bit."""
    A = _ladder(5, 40, 4, seed=3)
    A2 = A.copy()
    A2.data *= 1.0 + 0.05 * np.cos(np.arange(A2.nnz))
    lu = BorderedBandedLU(A, np.zeros(0, np.int64), sparse=True)
    assert lu.factorize(A.data) and lu.factorize(A2.data)
    b = np.random.default_rng(2).standard_normal(A.shape[0])
    x = lu.solve(b)
    other = BorderedBandedLU(A, np.zeros(0, np.int64), sparse=True)
    s, t = lu.factor.sparse, other.factor.sparse
    t.Ax[:], t.Ax_full[:], t.state[:], t.values[:] = s.Ax, s.Ax_full, s.state, s.values
    assert sparse_restore(t) == 0
    y = np.empty_like(b)
    bordered_solve(other.factor, b, y)
    assert np.array_equal(x, y)


def test_singular_and_nonfinite_matrices_are_reported():
    A = _ladder(3, 10, 2)
    lu = BorderedBandedLU(A, np.zeros(0, np.int64), sparse=True)
    data = A.data.copy()
    data[3] = np.nan
    assert bordered_factorize(lu.factor, data) == A.shape[0] + 1
    cols = np.repeat(np.arange(A.shape[0]), np.diff(A.indptr))
    singular = A.data.copy()
    singular[cols == 4] = 0.0                     # a zero column
    assert bordered_factorize(lu.factor, singular) == 1 + 4


def _robot_like(chains: int, length: int, every: int, reach: int) -> sp.csc_matrix:
    """The tendon robot's pattern: ``chains`` banded chains (half bandwidth 6, a cable's
    node coupling) side by side, and every ``every`` levels a 7-unknown body coupled with
    ``reach`` consecutive unknowns of every chain there (a disk and the tendons' elements in
    its holes)."""
    rng = np.random.default_rng(7)
    n = chains * length
    levels = list(range(every // 2, length - reach, every))
    N = n + 7 * len(levels)
    rows, cols = [], []
    for c in range(chains):
        for i in range(length):
            for j in range(max(0, i - 6), min(length, i + 7)):
                rows.append(c * length + i)
                cols.append(c * length + j)
    for b, level in enumerate(levels):
        body = n + 7 * b + np.arange(7)
        rows += list(np.repeat(body, 7))
        cols += list(np.tile(body, 7))
        for c in range(chains):
            near = c * length + level + np.arange(reach)
            rows += list(np.repeat(body, reach)) + list(np.tile(near, 7))
            cols += list(np.tile(near, 7)) + list(np.repeat(body, reach))
    A = sp.csc_matrix((rng.uniform(0.5, 1.5, len(rows)), (rows, cols)), shape=(N, N))
    A = sp.csc_matrix(A + sp.diags(np.full(N, 50.0)))
    A.sum_duplicates()
    A.sort_indices()
    return A


def test_the_planner_takes_the_sparse_lu_where_it_is_cheaper():
    """Seven chains tied by a body every 15 levels to 24 unknowns of each (the tendon robot's
    pattern): any band holds seven windows of 24, a border of the bodies is dense; KLU's
    fill-reducing order is cheaper and is taken, and solves as SuperLU. A single chain (a
    beam) and the ladder of single couplings keep their bands."""
    A = _robot_like(7, 400, 15, 24)
    n = 7 * 400
    plan = plan_factorization(A, np.arange(n, A.shape[0]), n)
    assert plan.sparse
    band_only = plan_factorization(A, np.arange(n, A.shape[0]), n, sparse=False)
    assert plan.cost < band_only.cost
    lu = plan.factorization(A)
    assert lu.factorize(A.data)
    b = np.random.default_rng(4).standard_normal(A.shape[0])
    np.testing.assert_allclose(lu.solve(b), spla.splu(A).solve(b), rtol=1e-10, atol=1e-12)
    assert not plan_factorization(_ladder(1, 200, 1000), np.zeros(0, np.int64), 200).sparse
    ladder = _ladder(6, 200, 3)
    assert not plan_factorization(ladder, np.arange(1200, ladder.shape[0]), 1200).sparse

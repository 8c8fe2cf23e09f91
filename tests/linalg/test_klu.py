"""SuiteSparse KLU bound for compiled code (flexmbs.linalg.klu): solutions against SciPy's,
refactorisation on a fixed pattern, failures reported through KLU's status, and the on-disk
cache of a compiled caller reused by a fresh process."""

from __future__ import annotations

import importlib
import importlib.util
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

if sys.platform == "win32":   # kvxopt's Windows wheel links KLU into its module, exports none
    pytest.skip("no SuiteSparse KLU library on Windows", allow_module_level=True)

from numba import njit
from numba.core.errors import TypingError

from flexmbs.linalg import klu

ROOT = Path(__file__).resolve().parents[2]


def _matrix(n: int, seed: int, density: float = 0.01, shift: float = 4.0) -> sp.csc_matrix:
    """Random unsymmetric sparse matrix plus ``shift`` I (sorted CSC)."""
    A = sp.random(n, n, density=density, random_state=seed, format="csc") + shift * sp.eye(n)
    A = sp.csc_matrix(A)
    A.sort_indices()
    return A


def _csc(A: sp.csc_matrix) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return A.indptr.astype(np.int32), A.indices.astype(np.int32), A.data.copy()


@njit(cache=True)
def _factor_solve_refactor(n, Ap, Ai, Ax, Ax2, B, nrhs, common, handles):
    """The step loop's use: analyse and factorise once, refactorise with new values, solve."""
    handles[0] = klu.klu_analyse(n, Ap, Ai, common)
    handles[1] = klu.klu_factorise(Ap, Ai, Ax, handles[0], common)
    X1 = B.copy()
    ok = klu.klu_solve_inplace(handles[0], handles[1], n, nrhs, X1, common)
    ok += klu.klu_refactorise(Ap, Ai, Ax2, handles[0], handles[1], common)
    X2 = B.copy()
    ok += klu.klu_solve_inplace(handles[0], handles[1], n, nrhs, X2, common)
    klu.klu_free_numeric(handles, 1, common)
    klu.klu_free_symbolic(handles, 0, common)
    return X1, X2, ok


def test_solution_matches_scipy() -> None:
    n, seed = 2000, 0
    A = _matrix(n, seed, density=0.002)      # ~10k entries (at 1%, fill makes L+U nearly dense)
    Ap, Ai, Ax = _csc(A)
    rng = np.random.default_rng(seed)
    b = rng.standard_normal(n)
    common = klu.new_common()
    h = np.zeros(2, np.int64)
    h[0] = klu.klu_analyse(n, Ap, Ai, common)
    h[1] = klu.klu_factorise(Ap, Ai, Ax, h[0], common)
    assert h[0] != 0 and h[1] != 0 and klu.klu_status(common) == klu.KLU_OK
    x = b.copy()
    assert klu.klu_solve_inplace(h[0], h[1], n, 1, x, common) == 1
    reference = spla.spsolve(A, b)
    assert np.linalg.norm(A @ x - b) <= 1e-12 * np.linalg.norm(b)
    assert np.linalg.norm(x - reference) <= 1e-12 * np.linalg.norm(reference)
    assert 0.0 < klu.klu_rcond(h[0], h[1], common) <= 1.0
    klu.klu_free_numeric(h, 1, common)
    klu.klu_free_symbolic(h, 0, common)
    assert not h.any()
    klu.klu_free_numeric(h, 1, common)          # freeing an empty slot is a no-op


def test_compiled_caller_refactorises_and_solves_several_rhs() -> None:
    n, nrhs = 600, 3
    A = _matrix(n, 7, density=0.01)
    Ap, Ai, Ax = _csc(A)
    Ax2 = Ax * np.random.default_rng(3).uniform(0.5, 2.0, Ax.size)   # same pattern, new values
    A2 = sp.csc_matrix((Ax2, A.indices, A.indptr), shape=A.shape)
    B = np.random.default_rng(4).standard_normal((nrhs, n))           # one rhs per row
    X1, X2, ok = _factor_solve_refactor(n, Ap, Ai, Ax, Ax2, B.ravel(), nrhs, klu.new_common(),
                                        np.zeros(2, np.int64))
    assert ok == 3
    for A_, X in ((A, X1), (A2, X2)):
        reference = spla.spsolve(A_, B.T).T
        assert np.abs(X.reshape(nrhs, n) - reference).max() <= 1e-12 * np.abs(reference).max()


def test_options_are_applied() -> None:
    n = 400
    A = _matrix(n, 5, density=0.02)
    Ap, Ai, Ax = _csc(A)
    b = np.ones(n)
    reference = spla.spsolve(A, b)
    for ordering, btf, scale in ((1, 0, 0), (0, 1, 1), (1, 1, -1)):
        common = klu.new_common()
        klu.klu_configure(common, 1.0, btf, ordering, scale, 1)
        ints = common.view(np.int32)
        assert common.view(np.float64)[0] == 1.0 and tuple(ints[10:13]) == (btf, ordering, scale)
        h = np.zeros(2, np.int64)
        h[0] = klu.klu_analyse(n, Ap, Ai, common)
        h[1] = klu.klu_factorise(Ap, Ai, Ax, h[0], common)
        x = b.copy()
        assert klu.klu_solve_inplace(h[0], h[1], n, 1, x, common) == 1
        assert np.abs(x - reference).max() <= 1e-12 * np.abs(reference).max()
        klu.klu_free_numeric(h, 1, common)
        klu.klu_free_symbolic(h, 0, common)


def test_singular_matrix_reports_status() -> None:
    n = 50
    A = _matrix(n, 2, density=0.1).tolil()
    A[:, 7] = A[:, 3]                         # two equal columns: numerically singular
    A = sp.csc_matrix(A)
    A.sort_indices()
    Ap, Ai, Ax = _csc(A)
    common = klu.new_common()
    h = np.zeros(2, np.int64)
    h[0] = klu.klu_analyse(n, Ap, Ai, common)
    assert h[0] != 0
    assert klu.klu_factorise(Ap, Ai, Ax, h[0], common) == 0
    assert klu.klu_status(common) == klu.KLU_SINGULAR

    # a good factorisation, then singular values on its pattern: refactor fails, no crash
    good = Ax.copy()
    good[Ap[7]:Ap[8]] += np.random.default_rng(9).uniform(0.5, 1.0, Ap[8] - Ap[7])
    h[1] = klu.klu_factorise(Ap, Ai, good, h[0], common)
    assert h[1] != 0 and klu.klu_status(common) == klu.KLU_OK
    assert klu.klu_refactorise(Ap, Ai, Ax, h[0], h[1], common) == 0
    assert klu.klu_status(common) == klu.KLU_SINGULAR
    assert klu.klu_refactorise(Ap, Ai, good, h[0], h[1], common) == 1   # and it recovers
    x = np.ones(n)
    assert klu.klu_solve_inplace(h[0], h[1], n, 1, x, common) == 1
    Ag = sp.csc_matrix((good, A.indices, A.indptr), shape=A.shape)
    assert np.allclose(Ag @ x, 1.0, rtol=0, atol=1e-10)
    klu.klu_free_numeric(h, 1, common)
    klu.klu_free_symbolic(h, 0, common)

    empty_column = sp.csc_matrix((np.ones(n - 1), (np.arange(n - 1), np.arange(n - 1))), (n, n))
    Ap, Ai, Ax = _csc(empty_column)            # structurally singular
    h[0] = klu.klu_analyse(n, Ap, Ai, common)
    assert klu.klu_factorise(Ap, Ai, Ax, h[0], common) == 0
    assert klu.klu_status(common) == klu.KLU_SINGULAR
    klu.klu_free_symbolic(h, 0, common)


def test_invalid_input_is_refused() -> None:
    n = 30
    A = _matrix(n, 4, density=0.1)
    Ap, Ai, Ax = _csc(A)
    common = klu.new_common()
    assert klu.klu_analyse(n + 1, Ap, Ai, common) == 0                  # Ap too short
    assert klu.klu_status(common) == klu.KLU_INVALID
    bad = Ap.copy()
    bad[5], bad[6] = bad[6], bad[5]                                     # not monotonic
    assert klu.klu_analyse(n, bad, Ai, common) == 0
    assert klu.klu_status(common) == klu.KLU_INVALID
    h = np.zeros(2, np.int64)
    h[0] = klu.klu_analyse(n, Ap, Ai, common)
    assert klu.klu_factorise(Ap, Ai, Ax[:-1], h[0], common) == 0        # Ax too short
    assert klu.klu_status(common) == klu.KLU_INVALID
    h[1] = klu.klu_factorise(Ap, Ai, Ax, h[0], common)
    assert klu.klu_solve_inplace(h[0], h[1], n, 2, np.ones(n), common) == 0   # b too short
    assert klu.klu_solve_inplace(h[0], h[1], n - 1, 1, np.ones(n), common) == 0
    assert klu.klu_status(common) == klu.KLU_INVALID
    with pytest.raises(TypingError, match="int32"):
        klu.klu_analyse(n, A.indptr.astype(np.int64), Ai, common)
    klu.klu_free_numeric(h, 1, common)
    klu.klu_free_symbolic(h, 0, common)


def test_cached_caller_reloads_in_a_fresh_process(tmp_path: Path) -> None:
    """A cached caller's machine code names KLU's functions, not their addresses: a fresh
    process (the library mapped elsewhere) loads it from numba's cache and solves right."""
    (tmp_path / "klu_caller.py").write_text(textwrap.dedent("""
        import numpy as np
        from numba import njit
        from flexmbs.linalg import klu

        @njit(cache=True)
        def solve(n, Ap, Ai, Ax, b):
            common = np.zeros(128, np.int64)
            klu.klu_setup(common)
            h = np.zeros(2, np.int64)
            h[0] = klu.klu_analyse(n, Ap, Ai, common)
            h[1] = klu.klu_factorise(Ap, Ai, Ax, h[0], common)
            x = b.copy()
            klu.klu_solve_inplace(h[0], h[1], n, 1, x, common)
            klu.klu_free_numeric(h, 1, common)
            klu.klu_free_symbolic(h, 0, common)
            return x

        n = 40
        A = np.diag(np.arange(1.0, n + 1)) + np.diag(np.ones(n - 1), 1)
        Ap = np.concatenate(([0], np.cumsum((A != 0).sum(axis=0)))).astype(np.int32)
        Ai = np.concatenate([np.flatnonzero(A[:, j]) for j in range(n)]).astype(np.int32)
        Ax = np.concatenate([A[np.flatnonzero(A[:, j]), j] for j in range(n)])
        x = solve(n, Ap, Ai, Ax, np.ones(n))
        hits = sum(solve.stats.cache_hits.values())
        if __name__ == "__main__":
            print(hits, float(np.abs(A @ x - 1.0).max()))
    """))
    sys.path.insert(0, str(tmp_path))
    try:
        first = importlib.import_module("klu_caller")        # compiles, writes the cache
    finally:
        sys.path.remove(str(tmp_path))
        sys.modules.pop("klu_caller", None)
    assert sum(first.solve.stats.cache_misses.values()) == 1
    assert np.abs(first.A @ first.x - 1.0).max() < 1e-12
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), str(tmp_path)]))
    run = subprocess.run([sys.executable, str(tmp_path / "klu_caller.py")], env=env, cwd=tmp_path,
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    hits, err = run.stdout.split()
    assert int(hits) == 1 and float(err) < 1e-12

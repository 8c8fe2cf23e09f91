"""Bordered-banded LU (flexmbs.linalg.bordered) against scipy/LAPACK on saddle-point matrices."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.linalg.lapack import dgbtrf

import flexmbs as fm
from flexmbs.assembly import Assembly
from flexmbs.linalg.bordered import BorderedBandedLU, bordered_solve
from tests.conftest import straight_beam

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def _saddle(rng: np.random.Generator, n_elem: int, n_lin: int, n_border: int
            ) -> tuple[sp.csc_matrix, np.ndarray]:
    """Beam-like saddle-point matrix in a shuffled global numbering, and its border indices.

    Band: overlapping 12x12 element blocks sharing 6 dofs (SPD plus a small unsymmetric part)
    + 10 I, and ``n_lin`` constraint rows on single beam coordinates (zero diagonal). Border:
    ``n_border // 2`` body-like coordinates (SPD block, coupled to every beam coordinate) and the
    remaining multipliers (zero diagonal block) of dense rows on all beam and body coordinates.
    The pattern depends on the sizes only (all coupling values are nonzero with probability 1).
    """
    n = 6 * (n_elem + 1)
    K = 10.0 * np.eye(n)
    for e in range(n_elem):
        B = rng.standard_normal((12, 12))
        K[6 * e:6 * e + 12, 6 * e:6 * e + 12] += B @ B.T / 12 + 0.1 * rng.standard_normal((12, 12))
    Cl = np.zeros((n_lin, n))
    Cl[np.arange(n_lin), np.linspace(0, n - 1, n_lin).astype(int)] = rng.uniform(0.5, 1.5, n_lin)
    nbody = n_border // 2
    nmul = n_border - nbody
    G = rng.standard_normal((nbody, nbody))
    Mb = G @ G.T / max(nbody, 1) + 10.0 * np.eye(nbody)
    H = 0.1 * rng.standard_normal((nbody, n))
    J = rng.standard_normal((nmul, n + nbody))
    Kt = np.block([[K, H.T], [H, Mb]])
    C = np.block([[Cl, np.zeros((n_lin, nbody))], [J]])
    m = n_lin + nmul
    D = np.block([[Kt, C.T], [C, np.zeros((m, m))]])
    # global numbering: [beam, body, linear multipliers, border multipliers], then shuffled
    order = np.r_[0:n, n + nbody:n + nbody + n_lin, n:n + nbody, n + nbody + n_lin:n + nbody + m]
    D = D[np.ix_(order, order)]
    border_old = np.arange(n + n_lin, D.shape[0])
    p = np.random.default_rng(7).permutation(D.shape[0])      # new index k <- old p[k]
    ip = np.argsort(p)
    return sp.csc_matrix(D[np.ix_(p, p)]), ip[border_old]


def _rel_residual(A: sp.csc_matrix, x: np.ndarray, b: np.ndarray) -> float:
    """Relative residual ||A x - b|| / ||b|| (infinity norm)."""
    return float(np.abs(A @ x - b).max() / np.abs(b).max())


def _backward_error(A: sp.csc_matrix, x: np.ndarray, b: np.ndarray) -> float:
    """Normwise backward error ||A x - b|| / (||A|| ||x|| + ||b||) (infinity norms)."""
    r = np.abs(A @ x - b).max()
    return float(r / (spla.norm(A, np.inf) * np.abs(x).max() + np.abs(b).max()))


# The random matrices below are well scaled (cond ~ 1e3): a backward-stable solve leaves
# ||r|| / ||b|| ~ 1e-15 (SuperLU the same); 1e-12 keeps three orders of margin.
RESIDUAL_TOL = 1e-12
# LU with partial pivoting is backward stable: backward error ~ eps times a modest growth
# factor; measured 1e-19..7e-17 here (the largest for the dense 30x30; SuperLU alike), while a
# wrong factor or index map gives ~1e-3. 1e-14 (~45 eps) is independent of the scaling of the
# matrix (Example 1: cond ~ 1e6).
BACKWARD_TOL = 1e-14


def _check(A: sp.csc_matrix, x: np.ndarray, b: np.ndarray) -> None:
    assert _backward_error(A, x, b) < BACKWARD_TOL
    assert _rel_residual(A, x, b) < RESIDUAL_TOL


@pytest.mark.parametrize("n_border", [0, 1, 8, 40])
def test_random_saddle_matches_spsolve(rng, n_border):
    """Residual and backward error (RESIDUAL_TOL, BACKWARD_TOL); the solution agrees with
    SuperLU within cond(A) * 1e-14 (forward error <= cond x backward error; cond ~ 1e3)."""
    A, border = _saddle(rng, 60, 7, n_border)
    lu = BorderedBandedLU(A, border)
    assert (lu.n_band, lu.n_border) == (A.shape[0] - n_border, n_border)
    assert lu.kl <= 30 and lu.ku <= 30   # RCM finds a band a few element blocks wide (n_a ~ 370)
    assert lu.factorize(A.data)
    cond = np.linalg.cond(A.toarray())
    for _ in range(3):
        b = rng.standard_normal(A.shape[0])
        x = lu.solve(b)
        ref = spla.spsolve(A, b)
        _check(A, x, b)
        assert np.abs(x - ref).max() <= cond * 1e-14 * np.abs(ref).max()


def test_refactorize_same_pattern(rng):
    """New values in the same pattern (the Jacobian refresh): the factor built for the first
    values solves the second matrix (and the first again) to the same tolerances."""
    A1, border = _saddle(np.random.default_rng(1), 40, 5, 8)
    A2, border2 = _saddle(np.random.default_rng(2), 40, 5, 8)
    assert np.array_equal(A1.indptr, A2.indptr) and np.array_equal(A1.indices, A2.indices)
    assert np.array_equal(border, border2)
    lu = BorderedBandedLU(A1, border)
    b = rng.standard_normal(A1.shape[0])
    for A in (A1, A2, A1):
        assert lu.factorize(A.data)
        _check(A, lu.solve(b), b)


def test_solve_kernel_in_place_buffers(rng):
    """The numba kernel writes into a caller's x (global numbering) without touching b."""
    A, border = _saddle(rng, 20, 3, 8)
    lu = BorderedBandedLU(A, border)
    assert lu.factorize(A.data)
    b = rng.standard_normal(A.shape[0])
    b0 = b.copy()
    x = np.full_like(b, np.nan)
    bordered_solve(lu.factor, b, x)
    assert np.array_equal(b, b0)
    _check(A, x, b)


def test_pure_band_matches_lapack_dgbtrf(rng):
    """n_b = 0: same band storage, pivots and factors as LAPACK dgbtrf (unblocked dgbtf2 for
    these narrow bands; 1e-12 relative allows for a different summation order in BLAS), and
    the solve meets the tolerances above."""
    A, border = _saddle(rng, 50, 6, 0)
    lu = BorderedBandedLU(A, border)
    f = lu.factor
    Aaa = A.toarray()[np.ix_(f.perm, f.perm)]
    kl, ku = lu.kl, lu.ku
    ab = np.zeros((2 * kl + ku + 1, f.n_band), order="F")
    for j in range(f.n_band):
        for i in range(max(0, j - ku), min(f.n_band, j + kl + 1)):
            ab[kl + ku + i - j, j] = Aaa[i, j]
    assert np.count_nonzero(Aaa) == np.count_nonzero(ab)     # kl, ku cover all of A_aa
    ref, piv, info = dgbtrf(ab, kl, ku)
    assert info == 0 and lu.factorize(A.data)
    assert np.array_equal(f.piv, piv)
    assert np.allclose(f.ab, ref, rtol=1e-12, atol=1e-12 * np.abs(ref).max())
    b = rng.standard_normal(A.shape[0])
    _check(A, lu.solve(b), b)


def test_pure_dense_border(rng):
    """n_a = 0: plain dense LU with partial pivoting (a zero leading diagonal block needs it);
    same tolerances (cond of a random 30x30 is ~1e2)."""
    n = 30
    D = rng.standard_normal((n, n))
    D[:5, :5] = 0.0
    A = sp.csc_matrix(D)
    lu = BorderedBandedLU(A, np.arange(n))
    assert (lu.n_band, lu.n_border, lu.kl, lu.ku) == (0, n, 0, 0)
    assert lu.factorize(A.data)
    b = rng.standard_normal(n)
    _check(A, lu.solve(b), b)


@pytest.mark.parametrize("n_band", [0, 1, 4])
def test_band_storage_is_typed_like_the_idle_run(rng, n_band):
    """A band of at most one coordinate, or a diagonal one, still gives F-typed band storage
    (numba types an array that is C- and F-contiguous as C: a second compile of the entry)."""
    from numba import typeof

    from flexmbs.steploop import idle_run

    n = n_band + 3
    D = rng.standard_normal((n, n)) + 5 * np.eye(n)
    D[:n_band, :n_band] = np.diag(np.diag(D)[:n_band])        # diagonal band block
    A = sp.csc_matrix(D)
    lu = BorderedBandedLU(A, np.arange(n_band, n))
    assert lu.n_band == n_band and lu.kl == lu.ku == 0
    assert typeof(lu.factor.ab) == typeof(idle_run().factor.ab)
    assert lu.factorize(A.data)
    b = rng.standard_normal(n)
    _check(A, lu.solve(b), b)


def test_singular_returns_false(rng):
    """Singular A_aa, singular Schur complement, non-finite data, singular dense matrix: False
    with the documented info code, never an exception; solve refuses a failed factor."""
    A, border = _saddle(rng, 20, 3, 8)
    lu = BorderedBandedLU(A, border)
    na, N = lu.n_band, A.shape[0]
    # a band unknown with a zero column (pattern kept, values zero): A_aa singular
    k = int(lu.factor.perm[na // 2])
    data = A.data.copy()
    data[A.indptr[k]:A.indptr[k + 1]] = 0.0
    assert not lu.factorize(data)
    assert 1 <= lu.info <= na
    with pytest.raises(RuntimeError):
        lu.solve(np.ones(N))
    # two border unknowns with equal rows and columns: S singular, A_aa untouched
    D = A.toarray()
    m1, m2 = border[-1], border[-2]
    D[m1, :], D[:, m1] = D[m2, :], D[:, m2]
    S = sp.csc_matrix(D)
    lu2 = BorderedBandedLU(S, border)
    assert not lu2.factorize(S.data)
    assert na < lu2.info <= N
    # non-finite entry
    data = A.data.copy()
    data[3] = np.nan
    assert not lu.factorize(data)
    assert lu.info == N + 1
    assert lu.factorize(A.data)           # and it recovers
    # pure dense, rank-deficient
    D = rng.standard_normal((6, 6))
    D[5] = D[4]
    lu3 = BorderedBandedLU(sp.csc_matrix(D), np.arange(6))
    assert not lu3.factorize(sp.csc_matrix(D).data)


def test_border_indices_of_body_constraints():
    """Linear rows on body coordinates (prescribed motion) and nonlinear joint multipliers are
    border; clamp rows on the beam stay in the band."""
    model = fm.Model()
    beam = straight_beam(model, 4)
    model.clamp(beam.first_node)
    body = model.add_rigid_body(mass=1.0, inertia=(1.0, 1.0, 1.0), position=(1.0, 0.0, 0.0))
    model.rigid(beam.last_node, body)
    model.prescribe(body, [2])
    asm = Assembly(model)
    n = asm.n_coords
    border = asm.border_indices()
    lin_body = [n + r for r in range(asm.m_lin) if np.any(asm.lin_matrix[r].indices >= 30)]
    assert len(lin_body) == 1 and asm.m_lin == 6
    nonlin = np.concatenate([n + nl.rows for nl in asm.nonlinear])
    expected = np.unique(np.r_[asm.body_dof_table.ravel(), nonlin, lin_body])
    assert np.array_equal(border, expected)


def test_example1_matrix():
    """Example 1 (sleeve on a curved rail, clearance joint coupling the body to every rail
    coordinate) at gen-alpha's scaling for h = 1e-4. cond ~ 1e6 and ||x|| ~ 1e5 ||b||: the
    backward error stays below BACKWARD_TOL, ||r|| / ||b|| is ~3e-13 (SuperLU ~5e-13), below
    1e-11; the solution agrees with SuperLU within cond(A) * 1e-14."""
    sys.path.insert(0, str(EXAMPLES))
    try:
        from curved_beam_sleeve import build
    finally:
        sys.path.remove(str(EXAMPLES))
    model, rail, sleeve, joint, probes = build()
    asm = Assembly(model)
    n, m = asm.n_coords, asm.n_mult
    asm.evaluate(asm.q_ref, np.zeros(n), np.zeros(n), np.zeros(m), 0.0, np.zeros(n), np.zeros(m),
                 matrix=(1.0, 0.05, 1e-8))
    A = asm.matrix
    border = asm.border_indices()
    nl = np.concatenate([n + r.rows for r in asm.nonlinear])
    assert np.array_equal(border, np.unique(np.r_[asm.body_dof_table.ravel(), nl]))
    lu = BorderedBandedLU(A, border)
    print(f"Example 1: n_a={lu.n_band} n_b={lu.n_border} kl={lu.kl} ku={lu.ku}")
    assert lu.factorize(A.data)
    cond = np.linalg.cond(A.toarray())
    rng = np.random.default_rng(5)
    for _ in range(3):
        b = rng.standard_normal(A.shape[0])
        x = lu.solve(b)
        ref = spla.spsolve(A.tocsc(), b)
        assert _backward_error(A, x, b) < BACKWARD_TOL
        assert _rel_residual(A, x, b) < 1e-11
        assert np.abs(x - ref).max() <= cond * 1e-14 * np.abs(ref).max()

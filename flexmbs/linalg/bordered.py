"""Bordered-banded direct solver for the generalized-alpha iteration matrix (numba).

The unknowns are split into *band* unknowns ``a`` (beam coordinates and the multipliers of linear
constraints on them: a narrow band after reverse Cuthill-McKee) and a small *border* ``b`` (rigid
bodies, interaction coordinates, nonlinear multipliers) that may couple densely to the band::

    [A_aa A_ab] [x_a]   [b_a]      A_aa = P L U        (banded LU, partial pivoting, dgbtf2)
    [A_ba A_bb] [x_b] = [b_b]      X = A_aa^-1 A_ab    (n_b band solves)
                                   S = A_bb - A_ba X   (Schur complement, dense LU, dgetf2)

    y = A_aa^-1 b_a,  x_b = S^-1 (b_b - A_ba y),  x_a = y - X x_b

Factorisation and solve are numba functions taking a :class:`BorderedFactor` (a NamedTuple of
arrays), so that a compiled Newton loop can call them; the index maps from the CSC ``data`` of the
fixed pattern to the four blocks are precomputed in Python. Pivoting is within ``A_aa`` and within
``S`` only: ``A_aa`` itself must be nonsingular (true in dynamics, where the beam mass matrix
enters it; not for a beam held only through border unknowns in statics).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import scipy.sparse as sp

from .._jit import njit


class BorderedFactor(NamedTuple):
    """Everything the numba kernels need (index maps, factors, work arrays)."""

    n: int                  # N = n_band + n_border
    n_band: int             # n_a
    n_border: int           # n_b
    kl: int                 # sub-diagonals of A_aa in band order
    ku: int                 # super-diagonals of A_aa in band order
    perm: np.ndarray        # int64 (n_a,): global index of band unknown k (RCM order)
    border: np.ndarray      # int64 (n_b,): global index of border unknown k (sorted)
    fill_pos: np.ndarray    # int64 (nnz,): CSC data positions grouped by block aa, ab, ba, bb
    fill_row: np.ndarray    # int64 (nnz,): first index into the block's array
    fill_col: np.ndarray    # int64 (nnz,): second index into the block's array
    fill_ptr: np.ndarray    # int64 (5,): block k is fill_*[fill_ptr[k]:fill_ptr[k + 1]]
    ab: np.ndarray          # float64 (2 kl + ku + 1, n_a), Fortran order: dgbtrf layout of A_aa
    piv: np.ndarray         # int64 (n_a,): 0-based row interchanges of the band LU
    xt: np.ndarray          # float64 (n_b, n_a): X^T = (A_aa^-1 A_ab)^T (A_ab^T before solves)
    a_ba: np.ndarray        # float64 (n_b, n_a)
    s: np.ndarray           # float64 (n_b, n_b): A_bb, then the LU of the Schur complement
    piv_s: np.ndarray       # int64 (n_b,): 0-based row interchanges of the dense LU
    work_a: np.ndarray      # float64 (n_a,)
    work_b: np.ndarray      # float64 (n_b,)


class BorderedBandedLU:
    """Bordered-banded LU of a matrix with a fixed CSC pattern (band: RCM + dgbtf2, border:
    Schur complement + dgetf2), all in numba; see the module docstring."""

    def __init__(self, A: sp.csc_matrix, border: np.ndarray, order: np.ndarray | None = None,
                 keep: np.ndarray | None = None) -> None:
        """``border``: the unknowns of the dense Schur complement; ``order``: the others in
        band order (default: reverse Cuthill-McKee), e.g. from
        :func:`flexmbs.linalg.ordering.plan_factorization`; ``keep``: the entries of the
        pattern (a bool per CSC position) the factorisation reads, default all; the others
        must be zero in every matrix it factorises (a plan that follows the sliding joints,
        :meth:`flexmbs.assembly.Assembly.factor_plan`)."""
        from scipy.sparse.csgraph import reverse_cuthill_mckee

        A = sp.csc_matrix(A)
        N = A.shape[0]
        if A.shape != (N, N):
            raise ValueError("BorderedBandedLU: the matrix must be square")
        border = np.unique(np.asarray(border, np.int64))
        if border.size and (border[0] < 0 or border[-1] >= N):
            raise ValueError("BorderedBandedLU: border index out of range")
        in_border = np.zeros(N, bool)
        in_border[border] = True
        band = np.flatnonzero(~in_border).astype(np.int64)
        cols = np.repeat(np.arange(N, dtype=np.int64), np.diff(A.indptr))
        rows = A.indices[:cols.size].astype(np.int64)
        read = np.ones(cols.size, bool) if keep is None else np.asarray(keep, bool)
        if read.shape != cols.shape:
            raise ValueError("BorderedBandedLU: keep must have one entry per stored position")
        if order is not None:
            perm = np.asarray(order, np.int64)
            if perm.shape != band.shape or not np.array_equal(np.sort(perm), band):
                raise ValueError("BorderedBandedLU: order must list every non-border unknown once")
        elif band.size:
            P = sp.csr_matrix((np.ones(rows.size), (rows, cols)), shape=(N, N))[band][:, band]
            P = (P + P.T).tocsr()
            perm = band[reverse_cuthill_mckee(P, symmetric_mode=True)]
        else:
            perm = band
        perm = np.ascontiguousarray(perm, dtype=np.int64)
        na, nb = perm.size, border.size
        local = np.empty(N, np.int64)   # position inside the band order or inside the border
        local[perm] = np.arange(na)
        local[border] = np.arange(nb)
        ri, ci = local[rows], local[cols]
        rb, cb = in_border[rows], in_border[cols]
        aa = ~rb & ~cb & read
        kl = int(max(0, (ri[aa] - ci[aa]).max(initial=0)))
        ku = int(max(0, (ci[aa] - ri[aa]).max(initial=0)))
        kv = kl + ku
        # blocks aa, ab, ba, bb -> (mask, first index, second index) into ab, xt, a_ba, s
        blocks = [(aa, kv + ri - ci, ci), (~rb & cb & read, ci, ri), (rb & ~cb & read, ri, ci),
                  (rb & cb & read, ri, ci)]
        pos = [np.flatnonzero(m) for m, _, _ in blocks]
        fill_row = np.concatenate([r[m] for m, r, _ in blocks])
        fill_col = np.concatenate([c[m] for m, _, c in blocks])
        self.factor = BorderedFactor(
            n=N, n_band=na, n_border=nb, kl=kl, ku=ku, perm=perm, border=border,
            fill_pos=np.ascontiguousarray(np.concatenate(pos), dtype=np.int64),
            fill_row=np.ascontiguousarray(fill_row, dtype=np.int64),
            fill_col=np.ascontiguousarray(fill_col, dtype=np.int64),
            fill_ptr=np.concatenate([[0], np.cumsum([p.size for p in pos])]).astype(np.int64),
            ab=_band_storage(2 * kl + ku + 1, na), piv=np.zeros(na, np.int64),
            xt=np.zeros((nb, na)), a_ba=np.zeros((nb, na)), s=np.zeros((nb, nb)),
            piv_s=np.zeros(nb, np.int64), work_a=np.zeros(na), work_b=np.zeros(nb))
        self.nnz = rows.size
        self.kl, self.ku, self.n_band, self.n_border = kl, ku, na, nb
        self.info = -1

    def twin(self) -> BorderedFactor:
        """A second factorisation of this plan (e.g. the velocity corrector's): the index maps
        shared (never written), its own numeric storage."""
        f = self.factor
        return f._replace(ab=np.zeros_like(f.ab), piv=np.zeros_like(f.piv), xt=np.zeros_like(f.xt),
                          a_ba=np.zeros_like(f.a_ba), s=np.zeros_like(f.s),
                          piv_s=np.zeros_like(f.piv_s), work_a=np.zeros_like(f.work_a),
                          work_b=np.zeros_like(f.work_b))

    def factorize(self, data: np.ndarray) -> bool:
        """Factor the matrix with CSC ``data`` (pattern of construction). False if singular;
        ``self.info`` holds the code of :func:`bordered_factorize`."""
        if data.shape != (self.nnz,):
            raise ValueError(f"BorderedBandedLU.factorize: expected {self.nnz} values")
        self.info = int(bordered_factorize(self.factor, np.ascontiguousarray(data, dtype=np.float64)))
        return self.info == 0

    def solve(self, b: np.ndarray) -> np.ndarray:
        """x = A^-1 b with the last successful factorisation."""
        if self.info != 0:
            raise RuntimeError("BorderedBandedLU.solve: no valid factorisation")
        x = np.empty(self.factor.n)
        bordered_solve(self.factor, np.ascontiguousarray(b, dtype=np.float64), x)
        return x


def _band_storage(rows: int, cols: int) -> np.ndarray:
    """Zeroed Fortran-order band storage of at least 2 x 2 (the part past ``rows x cols`` is
    never read): a narrower array is C- as well as F-contiguous, which numba types as C, and
    the compiled entry would be compiled a second time for it (a model with at most one band
    coordinate or a diagonal band; ``idle_run``'s factor is typed F)."""
    return np.zeros((max(rows, 2), max(cols, 2)), order="F")


@njit
def _band_lu(ab: np.ndarray, kl: int, ku: int, piv: np.ndarray) -> int:
    """In-place banded LU with partial pivoting (LAPACK dgbtf2, 0-based pivots); ``ab`` holds
    A in rows kl..2kl+ku with kl zero rows on top for the fill-in (columns past ``piv.size``
    are padding). Returns 0 or 1 + the column of the first zero or non-finite pivot."""
    n = piv.size
    kv = kl + ku
    ju = 0
    for j in range(n):
        km = min(kl, n - 1 - j)
        jp = 0
        best = abs(ab[kv, j])
        for i in range(1, km + 1):
            a = abs(ab[kv + i, j])
            if a > best:
                best = a
                jp = i
        piv[j] = j + jp
        if not (best > 0.0 and best < np.inf):
            return j + 1
        ju = max(ju, min(j + ku + jp, n - 1))
        if jp != 0:
            for c in range(j, ju + 1):
                t = ab[kv + jp + j - c, c]
                ab[kv + jp + j - c, c] = ab[kv + j - c, c]
                ab[kv + j - c, c] = t
        r = 1.0 / ab[kv, j]
        for i in range(1, km + 1):
            ab[kv + i, j] *= r
        for c in range(j + 1, ju + 1):
            t = ab[kv + j - c, c]
            if t != 0.0:
                o = kv + j - c
                for i in range(1, km + 1):
                    ab[o + i, c] -= ab[kv + i, j] * t
    return 0


@njit
def _band_solve(ab: np.ndarray, kl: int, ku: int, piv: np.ndarray, b: np.ndarray) -> None:
    """In-place solve with the band LU (LAPACK dgbtrs, no transpose)."""
    n = b.size
    kv = kl + ku
    if kl > 0:
        for j in range(n - 1):
            p = piv[j]
            if p != j:
                t = b[j]
                b[j] = b[p]
                b[p] = t
            bj = b[j]
            if bj != 0.0:
                for i in range(1, min(kl, n - 1 - j) + 1):
                    b[j + i] -= ab[kv + i, j] * bj
    for j in range(n - 1, -1, -1):
        b[j] /= ab[kv, j]
        bj = b[j]
        if bj != 0.0:
            for i in range(max(0, j - kv), j):
                b[i] -= ab[kv + i - j, j] * bj


@njit
def _dense_lu(s: np.ndarray, piv: np.ndarray) -> int:
    """In-place LU with partial pivoting of a row-major square matrix (LAPACK dgetf2, 0-based
    pivots). Returns 0 or 1 + the column of the first zero or non-finite pivot."""
    n = s.shape[0]
    for k in range(n):
        p = k
        best = abs(s[k, k])
        for i in range(k + 1, n):
            a = abs(s[i, k])
            if a > best:
                best = a
                p = i
        piv[k] = p
        if not (best > 0.0 and best < np.inf):
            return k + 1
        if p != k:
            for c in range(n):
                t = s[k, c]
                s[k, c] = s[p, c]
                s[p, c] = t
        r = 1.0 / s[k, k]
        for i in range(k + 1, n):
            m = s[i, k] * r
            s[i, k] = m
            if m != 0.0:
                for c in range(k + 1, n):
                    s[i, c] -= m * s[k, c]
    return 0


@njit
def _dense_solve(s: np.ndarray, piv: np.ndarray, b: np.ndarray) -> None:
    """In-place solve with the dense LU (LAPACK dgetrs, no transpose)."""
    n = b.size
    for k in range(n):
        p = piv[k]
        if p != k:
            t = b[k]
            b[k] = b[p]
            b[p] = t
    for i in range(n):
        acc = b[i]
        for c in range(i):
            acc -= s[i, c] * b[c]
        b[i] = acc
    for i in range(n - 1, -1, -1):
        acc = b[i]
        for c in range(i + 1, n):
            acc -= s[i, c] * b[c]
        b[i] = acc / s[i, i]


@njit(inline="always")
def _fill(block, data, pos, fr, fc, lo, hi):  # noqa: ANN001, ANN202
    """Adds the CSC entries ``data[pos[lo:hi]]`` into ``block[fr, fc]``; returns 0.0, or nan
    if one of them is inf or nan (the probe of :func:`bordered_factorize`)."""
    probe = 0.0
    for k in range(lo, hi):
        d = data[pos[k]]
        probe += 0.0 * d
        block[fr[k], fc[k]] += d
    return probe


@njit
def bordered_factorize(factor: BorderedFactor, data: np.ndarray) -> int:
    """Fill the blocks from CSC ``data``, band LU of A_aa (dgbtf2), X = A_aa^-1 A_ab, Schur
    complement S = A_bb - A_ba X and its dense LU (dgetf2). Returns 0 (ok), 1 + k (zero or
    non-finite pivot in band column k of A_aa, 0 <= k < n_a), n_a + 1 + k (pivot k of the
    Schur complement) or N + 1 (non-finite matrix entry)."""
    ab, xt, a_ba, s = factor.ab, factor.xt, factor.a_ba, factor.s
    pos, fr, fc, ptr = factor.fill_pos, factor.fill_row, factor.fill_col, factor.fill_ptr
    ab[:, :] = 0.0
    xt[:, :] = 0.0
    a_ba[:, :] = 0.0
    s[:, :] = 0.0
    nan_probe = (_fill(ab, data, pos, fr, fc, ptr[0], ptr[1])      # 0 unless an entry is
                 + _fill(xt, data, pos, fr, fc, ptr[1], ptr[2])    # inf or nan
                 + _fill(a_ba, data, pos, fr, fc, ptr[2], ptr[3])
                 + _fill(s, data, pos, fr, fc, ptr[3], ptr[4]))
    if nan_probe != 0.0:
        return factor.n + 1
    info = _band_lu(ab, factor.kl, factor.ku, factor.piv)
    if info != 0:
        return info
    na, nb = factor.n_band, factor.n_border
    for k in range(nb):
        _band_solve(ab, factor.kl, factor.ku, factor.piv, xt[k])
    for i in range(nb):
        for j in range(nb):
            acc = 0.0
            for k in range(na):
                acc += a_ba[i, k] * xt[j, k]
            s[i, j] -= acc
    info = _dense_lu(s, factor.piv_s)
    if info != 0:
        return na + info
    return 0


@njit
def bordered_solve(factor: BorderedFactor, b: np.ndarray, x: np.ndarray) -> None:
    """x = A^-1 b (global numbering, x must not alias b): y = A_aa^-1 b_a,
    x_b = S^-1 (b_b - A_ba y), x_a = y - X x_b (Schur complement); allocation-free."""
    perm, border, wa, wb = factor.perm, factor.border, factor.work_a, factor.work_b
    xt, a_ba = factor.xt, factor.a_ba
    na, nb = factor.n_band, factor.n_border
    for k in range(na):
        wa[k] = b[perm[k]]
    _band_solve(factor.ab, factor.kl, factor.ku, factor.piv, wa)
    if nb > 0:
        for i in range(nb):
            acc = b[border[i]]
            for k in range(na):
                acc -= a_ba[i, k] * wa[k]
            wb[i] = acc
        _dense_solve(factor.s, factor.piv_s, wb)
        for j in range(nb):
            z = wb[j]
            for k in range(na):
                wa[k] -= xt[j, k] * z
            x[border[j]] = z
    for k in range(na):
        x[perm[k]] = wa[k]

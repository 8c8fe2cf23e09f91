"""Bordered-banded direct solver for the generalized-alpha iteration matrix (numba).

The unknowns are split into *band* unknowns ``a`` (beam coordinates and the multipliers of linear
constraints on them: a narrow band after reverse Cuthill-McKee) and a small *border* ``b`` (rigid
bodies, interaction coordinates, nonlinear multipliers) that may couple densely to the band::

    [A_aa A_ab] [x_a]   [b_a]      A_aa = P L U        (banded LU, partial pivoting, dgbtf2)
    [A_ba A_bb] [x_b] = [b_b]      X = A_aa^-1 A_ab    (n_b band solves)
                                   S = A_bb - A_ba X   (Schur complement, dense LU, dgetf2)

    y = A_aa^-1 b_a,  x_b = S^-1 (b_b - A_ba y),  x_a = y - X x_b

Before the band, an optional *tree part* (:class:`~flexmbs.linalg.ordering.TreePlan`: rigid
bodies with their joint rows, children before parents) is eliminated supernode by supernode:
each block D_k = P L U (dense, partial pivoting), X_k = D_k^-1 A_kp on the columns of its
parent set p, and A_pp -= A_pk X_k in the parent's block (a later supernode's, or the band's and
border's, where the plan reserved it): no other fill, O(N) on trees of bodies (Baraff 1996).

Factorisation and solve are numba functions taking a :class:`BorderedFactor` (a NamedTuple of
arrays), so that a compiled Newton loop can call them; the index maps from the CSC ``data`` of the
fixed pattern to the four blocks are precomputed in Python. Pivoting is within ``A_aa`` and within
``S`` only: ``A_aa`` itself must be nonsingular (true in dynamics, where the beam mass matrix
enters it; not for a beam held only through border unknowns in statics).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np
import scipy.sparse as sp

from .._jit import njit
from .sparse_lu import SparseFactor, SparseHandles, empty_sparse, sparse_factorize, sparse_solve

if TYPE_CHECKING:
    from .tree_plan import TreePlan


#: columns of :class:`TreeFactor`'s supernode table: where its unknowns and parent set start in
#: ``maps``, their numbers n and m, its storage in ``val``, its first update in ``maps``, its
#: first pivot in ``piv``
SN_UNKNOWNS, SN_N, SN_SET, SN_M, SN_VAL, SN_UPDATE, SN_PIV, SN_COLUMNS = range(8)


class TreeFactor(NamedTuple):
    """The tree part's maps and storage (:class:`BorderedFactor`'s ``tree``), its integer maps
    in one array (a factor is passed by value in every call: 5 arrays, not 15).

    ``maps``: the supernode table (``n_super`` rows of :data:`SN_COLUMNS`, row-major), then
    the supernodes' unknowns and parent sets (global), each supernode's updates of its parent's
    block as triples (kind, a, b): A_pk X_k's m x m entries row-major, kind 0 ``val[a]``,
    1 ``ab[a, b]``, 2 ``xt[a, b]``, 3 ``a_ba[a, b]``, 4 ``s[a, b]``; from ``o_fill`` the
    ``n_fill`` pairs (CSC data position, place in ``val``) of the tree's entries. ``val``
    holds per supernode D_k (n x n), then X_k^T (m x n: the columns of A_kp, then of
    D_k^-1 A_kp), then A_pk (m x n), all row-major."""

    n_super: int
    o_fill: int
    n_fill: int
    maps: np.ndarray        # int64, read only (shared by a twin)
    piv: np.ndarray         # int64: row interchanges of each D_k, local 0-based
    val: np.ndarray         # float64
    work: np.ndarray        # float64 (N,): the right-hand side as the elimination changes it
    work_k: np.ndarray      # float64 (max n,)

    def update_kinds(self) -> np.ndarray:
        """The kind of every update entry (Python side: which blocks the tree fills)."""
        if not self.n_super:
            return np.zeros(0, np.int64)
        first = int(self.maps[SN_UPDATE])
        return self.maps[first:self.o_fill:3]


def empty_tree() -> TreeFactor:
    """A :class:`TreeFactor` of no supernodes, typed like a real one."""
    return TreeFactor(n_super=0, o_fill=0, n_fill=0, maps=np.zeros(0, np.int64),
                      piv=np.zeros(0, np.int64), val=np.zeros(0), work=np.zeros(0),
                      work_k=np.zeros(0))


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
    u_top: np.ndarray       # int64 (n_a,): the first non-zero row of U's column j (the solve's)
    u_inv: np.ndarray       # float64 (n_a,): 1 / U_jj (the solve multiplies)
    xt: np.ndarray          # float64 (n_b, n_a): X^T = (A_aa^-1 A_ab)^T (A_ab^T before solves)
    a_ba: np.ndarray        # float64 (n_b, n_a)
    s: np.ndarray           # float64 (n_b, n_b): A_bb, then the LU of the Schur complement
    piv_s: np.ndarray       # int64 (n_b,): 0-based row interchanges of the dense LU
    work_a: np.ndarray      # float64 (n_a,): the solve's band unknowns; the band LU's multipliers
    work_b: np.ndarray      # float64 (n_b,)
    tree: TreeFactor        # the bodies eliminated before the band (none: empty_tree())
    sparse: SparseFactor    # KLU on the whole matrix instead (n = 0: not used)


class BorderedBandedLU:
    """Bordered-banded LU of a matrix with a fixed CSC pattern (band: RCM + dgbtf2, border:
    Schur complement + dgetf2), all in numba; see the module docstring."""

    def __init__(self, A: sp.csc_matrix, border: np.ndarray, order: np.ndarray | None = None,
                 keep: np.ndarray | None = None, tree: TreePlan | None = None,
                 sparse: bool = False) -> None:
        """``border``: the unknowns of the dense Schur complement; ``order``: the band's in
        band order (default: reverse Cuthill-McKee of all unknowns in neither the border nor
        the tree), e.g. from :func:`flexmbs.linalg.ordering.plan_factorization`; ``keep``: the
        entries of the pattern (a bool per CSC position) the factorisation reads, default
        all; the others must be zero in every matrix it factorises (a plan that follows the
        sliding joints, :meth:`flexmbs.assembly.Assembly.factor_plan`); ``tree``: the
        unknowns eliminated in tree order first (their entries must lie within a supernode
        or between it and its parent set); ``sparse``: the whole matrix's kept entries by
        KLU instead (:mod:`flexmbs.linalg.sparse_lu`; no border, band or tree)."""
        from scipy.sparse.csgraph import reverse_cuthill_mckee

        A = sp.csc_matrix(A)
        N = A.shape[0]
        if A.shape != (N, N):
            raise ValueError("BorderedBandedLU: the matrix must be square")
        self._sparse: SparseHandles | None = None
        if sparse:
            self._sparse = SparseHandles(A, keep)
            border = np.zeros(0, np.int64)
            order = np.zeros(0, np.int64)
            keep = np.zeros(A.nnz, bool)      # nothing in the (empty) band and border
            tree = None
        border = np.unique(np.asarray(border, np.int64))
        if border.size and (border[0] < 0 or border[-1] >= N):
            raise ValueError("BorderedBandedLU: border index out of range")
        in_border = np.zeros(N, bool)
        in_border[border] = True
        in_tree = np.zeros(N, bool)
        if tree is not None:
            in_tree[tree.unknowns] = True
            if (in_tree & in_border).any() or np.bincount(tree.unknowns, minlength=N).max() > 1:
                raise ValueError("BorderedBandedLU: the tree's unknowns must be distinct and "
                                 "outside the border")
        band = np.flatnonzero(~in_border & ~in_tree).astype(np.int64)
        if sparse:
            band = np.zeros(0, np.int64)
        cols = np.repeat(np.arange(N, dtype=np.int64), np.diff(A.indptr))
        rows = A.indices[:cols.size].astype(np.int64)
        read = np.ones(cols.size, bool) if keep is None else np.asarray(keep, bool)
        if read.shape != cols.shape:
            raise ValueError("BorderedBandedLU: keep must have one entry per stored position")
        if order is not None:
            perm = np.asarray(order, np.int64)
            if perm.shape != band.shape or not np.array_equal(np.sort(perm), band):
                raise ValueError("BorderedBandedLU: order must list every band unknown once")
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
        on_tree = in_tree[rows] | in_tree[cols]
        rest = read & ~on_tree
        if tree is not None:     # the parent blocks the tree's elimination adds to
            cr, cc = tree.cliques(~in_tree)
        else:
            cr = cc = np.zeros(0, np.int64)
        ri, ci = local[rows], local[cols]
        rb, cb = in_border[rows], in_border[cols]
        aa = ~rb & ~cb & rest
        extra = ~in_border[cr] & ~in_border[cc]
        dif = np.concatenate([ri[aa] - ci[aa], local[cr[extra]] - local[cc[extra]]])
        kl = int(max(0, dif.max(initial=0)))
        ku = int(max(0, (-dif).max(initial=0)))
        kv = kl + ku
        # blocks aa, ab, ba, bb -> (mask, first index, second index) into ab, xt, a_ba, s
        blocks = [(aa, kv + ri - ci, ci), (~rb & cb & rest, ci, ri), (rb & ~cb & rest, ri, ci),
                  (rb & cb & rest, ri, ci)]
        pos = [np.flatnonzero(m) for m, _, _ in blocks]
        fill_row = np.concatenate([r[m] for m, r, _ in blocks])
        fill_col = np.concatenate([c[m] for m, _, c in blocks])
        tree_factor = (empty_tree() if tree is None else
                       _tree_factor(tree, N, rows[read & on_tree], cols[read & on_tree],
                                    np.flatnonzero(read & on_tree), local, in_border, kv))
        self.factor = BorderedFactor(
            n=N, n_band=na, n_border=nb, kl=kl, ku=ku, perm=perm, border=border,
            fill_pos=np.ascontiguousarray(np.concatenate(pos), dtype=np.int64),
            fill_row=np.ascontiguousarray(fill_row, dtype=np.int64),
            fill_col=np.ascontiguousarray(fill_col, dtype=np.int64),
            fill_ptr=np.concatenate([[0], np.cumsum([p.size for p in pos])]).astype(np.int64),
            ab=_band_storage(2 * kl + ku + 1, na), piv=np.zeros(na, np.int64),
            u_top=np.zeros(na, np.int64), u_inv=np.zeros(na),
            xt=np.zeros((nb, na)), a_ba=np.zeros((nb, na)), s=np.zeros((nb, nb)),
            piv_s=np.zeros(nb, np.int64), work_a=np.zeros(na), work_b=np.zeros(nb),
            tree=tree_factor,
            sparse=empty_sparse() if self._sparse is None else self._sparse.factor())
        self.nnz = rows.size
        self.kl, self.ku, self.n_band, self.n_border = kl, ku, na, nb
        self.n_tree = 0 if tree is None else tree.size
        self.sparse = sparse
        self.info = -1

    def twin(self) -> BorderedFactor:
        """A second factorisation of this plan (e.g. the velocity corrector's): the index maps
        shared (never written), its own numeric storage."""
        f = self.factor
        t = f.tree
        return f._replace(ab=np.zeros_like(f.ab), piv=np.zeros_like(f.piv),
                          u_top=np.zeros_like(f.u_top), u_inv=np.zeros_like(f.u_inv),
                          xt=np.zeros_like(f.xt),
                          a_ba=np.zeros_like(f.a_ba), s=np.zeros_like(f.s),
                          piv_s=np.zeros_like(f.piv_s), work_a=np.zeros_like(f.work_a),
                          work_b=np.zeros_like(f.work_b),
                          tree=t._replace(piv=np.zeros_like(t.piv), val=np.zeros_like(t.val),
                                          work=np.zeros_like(t.work),
                                          work_k=np.zeros_like(t.work_k)),
                          sparse=f.sparse if self._sparse is None else self._sparse.factor())

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


def _tree_factor(tree: TreePlan, N: int, rows: np.ndarray, cols: np.ndarray, pos: np.ndarray,
                 local: np.ndarray, in_border: np.ndarray, kv: int) -> TreeFactor:
    """The maps of the tree part: the stored entries (``rows``, ``cols`` at CSC ``pos``) that
    touch it into its blocks, and each supernode's update A_pk X_k into its parent's block
    (a later supernode's, or the band's and border's: ``local``, ``in_border``, ``kv`` as in
    :class:`BorderedBandedLU`)."""
    S = tree.ptr.size - 1
    n = np.diff(tree.ptr)
    m = np.diff(tree.set_ptr)
    base = np.concatenate([[0], np.cumsum(n * n + 2 * m * n)]).astype(np.int64)
    sup = np.full(N, S, np.int64)               # S: the rest, eliminated after the tree
    sup[tree.unknowns] = np.repeat(np.arange(S), n)
    lpos = np.zeros(N, np.int64)
    lpos[tree.unknowns] = np.arange(tree.unknowns.size) - np.repeat(tree.ptr[:-1], n)
    owner = np.repeat(np.arange(S, dtype=np.int64), m)
    keys = owner * N + tree.parent_set
    by_key = np.argsort(keys, kind="stable")
    sorted_keys = keys[by_key]

    def place_in_set(k: np.ndarray, u: np.ndarray) -> np.ndarray:
        """The position of unknown u in supernode k's parent set."""
        if not u.size:
            return u
        at = np.minimum(np.searchsorted(sorted_keys, k * N + u), max(sorted_keys.size - 1, 0))
        if not sorted_keys.size or (sorted_keys[at] != k * N + u).any():
            raise ValueError("BorderedBandedLU: an entry couples a tree supernode outside its "
                             "parent set")
        return by_key[at] - tree.set_ptr[k]

    sr, sc = sup[rows], sup[cols]
    at = np.empty(rows.size, np.int64)
    same = sr == sc
    k = sr[same]
    at[same] = base[k] + lpos[rows[same]] * n[k] + lpos[cols[same]]
    down = sr < sc            # row in supernode k, column in its parent set: X_k^T
    k = sr[down]
    at[down] = base[k] + n[k] * n[k] + place_in_set(k, cols[down]) * n[k] + lpos[rows[down]]
    up = sc < sr              # row in the parent set, column in supernode k: A_pk
    k = sc[up]
    at[up] = (base[k] + n[k] * n[k] + m[k] * n[k] + place_in_set(k, rows[up]) * n[k]
              + lpos[cols[up]])
    # A_pk X_k (m x m, row-major) into the parent's block
    ks = np.repeat(np.arange(S, dtype=np.int64), m * m)
    first = np.repeat(tree.set_ptr[:-1], m * m)
    within = np.arange(ks.size) - np.repeat(np.concatenate([[0], np.cumsum(m * m)[:-1]]), m * m)
    mk = m[ks]
    u = tree.parent_set[first + within // np.maximum(mk, 1)]
    v = tree.parent_set[first + within % np.maximum(mk, 1)]
    q = sup[u]
    if (q != sup[v]).any() or (q <= ks).any():
        raise ValueError("BorderedBandedLU: a tree supernode's parent set must lie in one later "
                         "supernode or in the rest")
    kind = np.zeros(ks.size, np.int64)
    ua = np.zeros(ks.size, np.int64)
    ub = np.zeros(ks.size, np.int64)
    t = q < S
    ua[t] = base[q[t]] + lpos[u[t]] * n[q[t]] + lpos[v[t]]
    rb, cb = in_border[u], in_border[v]
    ri, ci = local[u], local[v]
    for code, mask, fa, fb in ((1, ~rb & ~cb, kv + ri - ci, ci), (2, ~rb & cb, ci, ri),
                               (3, rb & ~cb, ri, ci), (4, rb & cb, ri, ci)):
        mask = mask & ~t
        kind[mask], ua[mask], ub[mask] = code, fa[mask], fb[mask]
    o_unknowns = SN_COLUMNS * S
    o_sets = o_unknowns + tree.unknowns.size
    o_updates = o_sets + tree.parent_set.size
    table = np.stack([o_unknowns + tree.ptr[:-1], n, o_sets + tree.set_ptr[:-1], m, base[:-1],
                      o_updates + 3 * np.concatenate([[0], np.cumsum(m * m)[:-1]]),
                      tree.ptr[:-1]], axis=1) if S else np.zeros((0, SN_COLUMNS), np.int64)
    maps = np.concatenate([table.ravel(), tree.unknowns, tree.parent_set,
                           np.stack([kind, ua, ub], axis=1).ravel(),
                           np.stack([pos, at], axis=1).ravel()]).astype(np.int64)
    return TreeFactor(n_super=S, o_fill=o_updates + 3 * ks.size, n_fill=pos.size,
                      maps=np.ascontiguousarray(maps), piv=np.zeros(tree.unknowns.size, np.int64),
                      val=np.zeros(max(int(base[-1]), 1)), work=np.zeros(N),
                      work_k=np.zeros(int(n.max(initial=1))))


def _band_storage(rows: int, cols: int) -> np.ndarray:
    """Zeroed Fortran-order band storage of at least 2 x 2 (the part past ``rows x cols`` is
    never read): a narrower array is C- as well as F-contiguous, which numba types as C, and
    the compiled entry would be compiled a second time for it (a model with at most one band
    coordinate or a diagonal band; ``idle_run``'s factor is typed F)."""
    return np.zeros((max(rows, 2), max(cols, 2)), order="F")


@njit
def _band_lu(ab: np.ndarray, kl: int, ku: int, piv: np.ndarray, mult: np.ndarray,
             u_top: np.ndarray, u_inv: np.ndarray) -> int:
    """In-place banded LU with partial pivoting (LAPACK dgbtf2, 0-based pivots); ``ab`` holds
    A in rows kl..2kl+ku with kl zero rows on top for the fill-in (columns past ``piv.size``
    are padding); ``mult`` (at least kl + 1) is scratch for a column's multipliers. Writes
    ``u_top[j]``, the first non-zero row of U's column j: the row swaps fill U's band only in
    part (Example 1: 12.9 of its kl + ku = 22 rows on average, the 8-element cantilever 10.3),
    and :func:`_band_solve` runs over the rows filled; and ``u_inv[j]`` = 1 / U_jj, which the
    solve multiplies by (a division on the back substitution's chain of dependent columns
    cost about 15 % of the 8-element cantilever's solve). Returns 0 or 1 + the column of the
    first zero or non-finite pivot. (Threshold pivoting, the diagonal
    kept while at least 0.1 of its column's largest entry, made the 8-element cantilever's LU
    4.5 → 3.8 µs but changed a fed wire's path in a curved bore (tests/contact); not kept.)"""
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
        u_inv[j] = r
        for i in range(1, km + 1):
            x = ab[kv + i, j] * r
            ab[kv + i, j] = x
            mult[i] = x
        # the multipliers from ``mult``, each column a contiguous slice (the 8-element
        # cantilever's LU 6.2 → 4.5 µs, the same factors: the compiler reloaded the pivot
        # column of ``ab``, which it cannot prove unchanged by the update)
        for c in range(j + 1, ju + 1):
            t = ab[kv + j - c, c]
            if t != 0.0:
                col = ab[kv + j - c:kv + j - c + km + 1, c]
                for i in range(1, km + 1):
                    col[i] -= mult[i] * t
    for j in range(n):
        top = max(0, j - kv)
        while top < j and ab[kv + top - j, j] == 0.0:
            top += 1
        u_top[j] = top
    return 0


@njit
def _band_solve(ab: np.ndarray, kl: int, ku: int, piv: np.ndarray, u_top: np.ndarray,
                u_inv: np.ndarray, b: np.ndarray) -> None:
    """In-place solve with the band LU (LAPACK dgbtrs, no transpose), U's columns from their
    first non-zero row ``u_top``, its diagonal as the reciprocals ``u_inv`` (:func:`_band_lu`;
    the terms skipped are zeros)."""
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
            if bj != 0.0:      # contiguous slices: 1.56 → 1.28 µs, the 8-element cantilever
                m = min(kl, n - 1 - j)
                col = ab[kv + 1:kv + 1 + m, j]
                rhs = b[j + 1:j + 1 + m]
                for i in range(m):
                    rhs[i] -= col[i] * bj
    for j in range(n - 1, -1, -1):
        bj = b[j] * u_inv[j]
        b[j] = bj
        if bj != 0.0:
            lo = u_top[j]
            col = ab[kv + lo - j:kv, j]
            rhs = b[lo:j]
            for i in range(j - lo):
                rhs[i] -= col[i] * bj


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


@njit
def _tree_factorize(t: TreeFactor, data: np.ndarray, ab: np.ndarray, xt: np.ndarray,
                    a_ba: np.ndarray, s: np.ndarray) -> int:
    """The tree part's elimination, children first: D_k = P L U, X_k = D_k^-1 A_kp,
    A_pp -= A_pk X_k into the parent's block (``ab``, ``xt``, ``a_ba``, ``s`` already filled).
    Returns 0, -1 (non-finite entry) or 1 + the tree position of a zero pivot."""
    mp, val = t.maps, t.val
    val[:] = 0.0
    probe = 0.0
    for e in range(t.o_fill, t.o_fill + 2 * t.n_fill, 2):
        d = data[mp[e]]
        probe += 0.0 * d
        val[mp[e + 1]] += d
    if probe != 0.0:
        return -1
    for k in range(t.n_super):
        h = SN_COLUMNS * k
        n, m, b, u, lo = mp[h + SN_N], mp[h + SN_M], mp[h + SN_VAL], mp[h + SN_UPDATE], mp[h + SN_PIV]
        d_k = val[b:b + n * n].reshape((n, n))
        piv = t.piv[lo:lo + n]
        info = _dense_lu(d_k, piv)
        if info != 0:
            return lo + info
        x_k = val[b + n * n:b + n * n + m * n].reshape((m, n))
        l_k = val[b + n * n + m * n:b + n * n + 2 * m * n].reshape((m, n))
        for j in range(m):
            _dense_solve(d_k, piv, x_k[j])
        for i in range(m):
            for j in range(m):
                c = 0.0
                for r in range(n):
                    c += l_k[i, r] * x_k[j, r]
                kind, ua, ub = mp[u], mp[u + 1], mp[u + 2]
                if kind == 0:
                    val[ua] -= c
                elif kind == 1:
                    ab[ua, ub] -= c
                elif kind == 2:
                    xt[ua, ub] -= c
                elif kind == 3:
                    a_ba[ua, ub] -= c
                else:
                    s[ua, ub] -= c
                u += 3
    return 0


@njit
def _tree_forward(t: TreeFactor) -> None:
    """y_k = D_k^-1 w_k and w_p -= A_pk y_k, children first, in ``t.work``."""
    mp, w, val = t.maps, t.work, t.val
    for k in range(t.n_super):
        h = SN_COLUMNS * k
        iu, n, ip, m, b, lo = (mp[h + SN_UNKNOWNS], mp[h + SN_N], mp[h + SN_SET], mp[h + SN_M],
                               mp[h + SN_VAL], mp[h + SN_PIV])
        y = t.work_k[:n]
        for r in range(n):
            y[r] = w[mp[iu + r]]
        _dense_solve(val[b:b + n * n].reshape((n, n)), t.piv[lo:lo + n], y)
        for r in range(n):
            w[mp[iu + r]] = y[r]
        o = b + n * n + m * n
        for i in range(m):
            acc = 0.0
            for r in range(n):
                acc += val[o + i * n + r] * y[r]
            w[mp[ip + i]] -= acc


@njit
def _tree_backward(t: TreeFactor, x: np.ndarray) -> None:
    """x_k = y_k - X_k x_p, parents first (x_p already solved)."""
    mp, w, val = t.maps, t.work, t.val
    for k in range(t.n_super - 1, -1, -1):
        h = SN_COLUMNS * k
        iu, n, ip, m = mp[h + SN_UNKNOWNS], mp[h + SN_N], mp[h + SN_SET], mp[h + SN_M]
        o = mp[h + SN_VAL] + n * n
        for r in range(n):
            acc = w[mp[iu + r]]
            for j in range(m):
                acc -= val[o + j * n + r] * x[mp[ip + j]]
            x[mp[iu + r]] = acc


@njit(inline="always")
def _fill(block, data, pos, fr, fc, lo, hi):
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
    Schur complement), N + 1 (non-finite matrix entry) or N + 2 + k (pivot of the tree
    part's unknown k, :class:`TreeFactor`); a sparse factor (``factor.sparse.n``):
    :func:`~flexmbs.linalg.sparse_lu.sparse_factorize`'s codes."""
    if factor.sparse.n:
        return sparse_factorize(factor.sparse, data)
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
    if factor.tree.n_super:
        info = _tree_factorize(factor.tree, data, ab, xt, a_ba, s)
        if info != 0:
            return factor.n + 1 if info < 0 else factor.n + 1 + info
    info = _band_lu(ab, factor.kl, factor.ku, factor.piv, factor.work_a, factor.u_top,
                    factor.u_inv)
    if info != 0:
        return info
    na, nb = factor.n_band, factor.n_border
    for k in range(nb):
        _band_solve(ab, factor.kl, factor.ku, factor.piv, factor.u_top, factor.u_inv, xt[k])
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
    """x = A^-1 b (global numbering, x must not alias b): the tree part's forward pass, the
    bordered band's solve (:func:`_solve_rest`), the tree part's backward pass;
    allocation-free."""
    if factor.sparse.n:
        sparse_solve(factor.sparse, b, x)
        return
    tree = factor.tree
    if tree.n_super:
        tree.work[:] = b
        _tree_forward(tree)
        _solve_rest(factor, tree.work, x)
        _tree_backward(tree, x)
    else:
        _solve_rest(factor, b, x)


@njit(inline="always")
def _solve_rest(factor: BorderedFactor, b: np.ndarray, x: np.ndarray) -> None:
    """The bordered band's part of x = A^-1 b: y = A_aa^-1 b_a, x_b = S^-1 (b_b - A_ba y),
    x_a = y - X x_b (Schur complement); writes x's band and border unknowns only."""
    perm, border, wa, wb = factor.perm, factor.border, factor.work_a, factor.work_b
    xt, a_ba = factor.xt, factor.a_ba
    na, nb = factor.n_band, factor.n_border
    for k in range(na):
        wa[k] = b[perm[k]]
    _band_solve(factor.ab, factor.kl, factor.ku, factor.piv, factor.u_top, factor.u_inv, wa)
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

"""Choice of the bordered LU's border (:mod:`flexmbs.solvers._bordered`) from a cost estimate.

Pure Python and scipy (no compiled code here, so that this file does not enter the compiled
kernels' cache stamp). See ``docs/design-notes.md`` ("The border, chosen by cost").
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import scipy.sparse as sp

#: borders larger than this are not considered (the dense Schur complement's memory)
MAX_BORDER = 4000


#: solves per factorisation assumed by the cost estimate of :func:`choose_border` (modified
#: Newton reuses a factorisation for several iterations and steps)
SOLVES_PER_FACTOR = 8.0


def _graph(A: sp.csc_matrix) -> tuple[sp.csr_matrix, np.ndarray]:
    """Symmetric adjacency (pattern of A + A^T without the diagonal) and the structural
    diagonal (True where the pattern stores A_ii)."""
    A = sp.csc_matrix(A)
    N = A.shape[0]
    cols = np.repeat(np.arange(N, dtype=np.int64), np.diff(A.indptr))
    rows = A.indices[:cols.size].astype(np.int64)
    diag = np.zeros(N, bool)
    diag[rows[rows == cols]] = True
    off = rows != cols
    G = sp.csr_matrix((np.ones(int(off.sum())), (rows[off], cols[off])), shape=(N, N))
    G = (G + G.T).tocsr()
    G.data[:] = 1.0
    return G, diag


def _band_order(G: sp.csr_matrix, band: np.ndarray) -> tuple[np.ndarray, int]:
    """Reverse Cuthill-McKee order of the ``band`` unknowns and its half bandwidth."""
    from scipy.sparse.csgraph import reverse_cuthill_mckee

    if not band.size:
        return band, 0
    P = G[band][:, band].tocsr()
    perm = band[reverse_cuthill_mckee(P, symmetric_mode=True)]
    local = np.empty(G.shape[0], np.int64)
    local[perm] = np.arange(perm.size)
    C = P.tocoo()
    inv = local[band]
    w = int(np.abs(inv[C.row] - inv[C.col]).max(initial=0))
    return perm, w


def factor_cost(n_band: int, n_border: int, bandwidth: int) -> float:
    """Estimated flops of one bordered factorisation plus :data:`SOLVES_PER_FACTOR` solves
    (kl = ku = ``bandwidth``; partial pivoting widens the upper band to kl + ku): band LU
    n_a kl (kl + ku), the n_b band solves of X, the Schur product n_b^2 n_a, its dense LU."""
    na, nb, k = float(n_band), float(n_border), float(bandwidth)
    factor = na * k * 2 * k + nb * na * 3 * k * 2 + nb * nb * na * 2 + 2 * nb**3 / 3
    solve = na * 3 * k * 2 + 4 * nb * na + 2 * nb * nb
    return factor + SOLVES_PER_FACTOR * solve


class FactorPlan(NamedTuple):
    """Border and band order of a :class:`~flexmbs.solvers._bordered.BorderedBandedLU`."""

    border: np.ndarray      # int64: unknowns of the dense Schur complement
    order: np.ndarray       # int64: the other unknowns in band order
    bandwidth: int          # half bandwidth of the band in that order (before pivoting)
    cost: float             # factor_cost estimate


def plan_factorization(A: sp.csc_matrix, suggested: np.ndarray, n_coords: int,
                       owner: np.ndarray | None = None) -> FactorPlan:
    """The border (unknowns of the dense Schur complement) and band order with the least
    :func:`factor_cost` among these borders: ``suggested`` (e.g.
    :meth:`flexmbs.assembly.Assembly.border_indices`), none (the whole saddle-point system in
    one band: chains of bodies and joints, whose bandwidth does not grow with their number),
    and the *hubs*: unknowns coupled to at least d others, for a few thresholds d (a slide
    coordinate or a sliding joint's multipliers reserved along a whole beam, the hub of a star
    of bodies); each band in the narrower of two orders: reverse Cuthill-McKee of all its
    unknowns, or :func:`saddle_order` (unknowns from ``n_coords`` on are multipliers, with a
    zero diagonal block; ``owner``: a label per unknown, >= 0 for the coordinates of one rigid
    body, kept together). A multiplier whose neighbours are all in the border joins it (a band
    block with an empty row would be singular). Computed once per pattern."""
    G, _ = _graph(A)
    N = G.shape[0]
    is_coord = np.arange(N) < n_coords
    degree = np.diff(G.indptr)
    suggested = np.unique(np.asarray(suggested, np.int64))
    candidates = [suggested, np.zeros(0, np.int64)]
    levels = np.unique(degree)
    levels = levels[levels > 2 * max(float(np.median(degree)), 1.0)]
    if levels.size:
        for d in levels[::-1][::max(1, levels.size // 6)]:
            candidates.append(np.flatnonzero(degree >= d).astype(np.int64))
    best: FactorPlan | None = None
    seen: set[bytes] = set()
    for border in candidates:
        if border.tobytes() in seen:
            continue
        seen.add(border.tobytes())
        in_border = np.zeros(N, bool)
        in_border[border] = True
        if border.size:   # closure: multipliers left without band neighbours
            band_nb = G @ (~in_border).astype(float)
            in_border |= ~is_coord & (band_nb == 0) & (degree > 0)
        border = np.flatnonzero(in_border).astype(np.int64)
        if border.size > MAX_BORDER:
            continue
        band = np.flatnonzero(~in_border).astype(np.int64)
        order, w = _band_order(G, band)
        # the second order only where it can matter (bodies in the band, or a border whose
        # rows leave multipliers in it): a plain beam model keeps its plan at RCM's cost
        if border.size or (owner is not None and (owner[band] >= 0).any()):
            alt = saddle_order(G, is_coord, band, owner)
            w_alt = _bandwidth(G, alt)
            if w_alt < w:
                order, w = alt, w_alt
        cost = factor_cost(band.size, border.size, w)
        if best is None or cost < best.cost:
            best = FactorPlan(border, np.ascontiguousarray(order, np.int64), w, cost)
    assert best is not None
    return best


def _bandwidth(G: sp.csr_matrix, order: np.ndarray) -> int:
    """Half bandwidth of the unknowns ``order`` (all others excluded) in that order."""
    if not order.size:
        return 0
    pos = np.full(G.shape[0], -1, np.int64)
    pos[order] = np.arange(order.size)
    C = G[order][:, order].tocoo()
    return int(np.abs(pos[order][C.row] - pos[order][C.col]).max(initial=0))


def saddle_order(G: sp.csr_matrix, diag: np.ndarray, band: np.ndarray,
                 owner: np.ndarray | None = None) -> np.ndarray:
    """Band order of a saddle-point system: reverse Cuthill-McKee on the unknowns with a
    structural diagonal (coordinates), coupled also through every zero-diagonal unknown
    (multiplier) they share, the coordinates with one ``owner`` label (>= 0: a rigid body)
    kept together, then each multiplier placed at the mean position of the coordinates it
    constrains (next to them, whatever the joint graph looks like)."""
    from scipy.sparse.csgraph import reverse_cuthill_mckee

    prim = band[diag[band]]
    sec = band[~diag[band]]
    if not prim.size or not sec.size:
        return _band_order(G, band)[0]
    Gpp = G[prim][:, prim]
    Gps = G[prim][:, sec]
    P = (Gpp + Gps @ Gps.T + sp.identity(prim.size)).tocsr()
    P.data[:] = 1.0
    # the coordinates of one owner (a rigid body's 7) form one supernode, ordered together;
    # RCM runs on the quotient graph
    if owner is None:
        group = np.arange(prim.size)
    else:
        lab = owner[prim]
        lab = np.where(lab >= 0, lab, lab.max(initial=0) + 1 + np.arange(prim.size))
        _, group = np.unique(lab, return_inverse=True)
        group = group.ravel()
    E = sp.csr_matrix((np.ones(prim.size), (np.arange(prim.size), group)))
    Q = (E.T @ P @ E).tocsr()
    g_order = reverse_cuthill_mckee(Q, symmetric_mode=True)
    g_rank = np.empty(g_order.size, np.int64)
    g_rank[g_order] = np.arange(g_order.size)
    order_p = prim[np.argsort(g_rank[group], kind="stable")]
    key = np.empty(G.shape[0])
    key[order_p] = np.arange(order_p.size, dtype=float)
    S = G[sec][:, order_p].tocsr()
    cnt = np.diff(S.indptr)
    sums = S @ np.arange(order_p.size, dtype=float)
    lonely = cnt == 0
    key[sec] = np.where(lonely, order_p.size, sums / np.maximum(cnt, 1))
    if lonely.any():   # multipliers of multipliers only: after everything, in RCM order
        key[sec[lonely]] += np.arange(int(lonely.sum())) * 1e-6
    order = np.concatenate([order_p, sec])
    return order[np.argsort(key[order], kind="stable")]

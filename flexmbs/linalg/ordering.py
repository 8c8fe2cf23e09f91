"""Choice of the bordered LU's border (:mod:`flexmbs.linalg.bordered`) from a cost estimate.

Pure Python and scipy (no compiled code here, so that this file does not enter the compiled
kernels' cache stamp). See ``docs/design-notes.md`` ("The border, chosen by cost").
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np
import scipy.sparse as sp

from . import klu
from .sparse_lu import sparse_cost
from .tree_plan import TreePlan

if TYPE_CHECKING:
    from .bordered import BorderedBandedLU

#: borders larger than this are not considered (the dense Schur complement's memory)
MAX_BORDER = 4000


#: solves per factorisation assumed by the cost estimate of :func:`choose_border` (modified
#: Newton reuses a factorisation for several iterations and steps)
SOLVES_PER_FACTOR = 8.0


def _graph(A: sp.csc_matrix, keep: np.ndarray | None = None) -> tuple[sp.csr_matrix, np.ndarray]:
    """Symmetric adjacency (pattern of A + A^T without the diagonal; ``keep``: the stored
    positions that count, default all) and the structural diagonal (True where the pattern
    stores A_ii)."""
    A = sp.csc_matrix(A)
    N = A.shape[0]
    cols = np.repeat(np.arange(N, dtype=np.int64), np.diff(A.indptr))
    rows = A.indices[:cols.size].astype(np.int64)
    if keep is not None:
        cols, rows = cols[keep], rows[keep]
    diag = np.zeros(N, bool)
    diag[rows[rows == cols]] = True
    off = rows != cols
    G = sp.csr_matrix((np.ones(int(off.sum())), (rows[off], cols[off])), shape=(N, N))
    G = (G + G.T).tocsr()
    G.data[:] = 1.0
    return G, diag


def _least_degree(mask: np.ndarray, label: np.ndarray, degree: np.ndarray,
                  n_comp: int) -> np.ndarray:
    """Per connected component the vertex of least degree among ``mask`` (the lowest index
    among equals; −1 where the component has none)."""
    at = np.flatnonzero(mask)
    pick = at[np.lexsort((at, degree[at], label[at]))]
    first = np.full(n_comp, -1, np.int64)
    lab = label[pick]
    head = np.r_[True, lab[1:] != lab[:-1]] if pick.size else np.zeros(0, bool)
    first[lab[head]] = pick[head]
    return first


def _peripheral_nodes(P: sp.csr_matrix, label: np.ndarray, n_comp: int) -> np.ndarray:
    """A pseudo-peripheral vertex of every connected component of the graph ``P`` (George
    and Liu 1979): from a vertex of least degree, a breadth-first search at a time moves to
    the least-degree vertex of the last level while the eccentricity grows. All components
    at once: one multi-source search per round (the components are disjoint, so each
    vertex's distance is from its own component's start)."""
    from scipy.sparse.csgraph import dijkstra

    degree = np.diff(P.indptr)
    start = _least_degree(np.ones(label.size, bool), label, degree, n_comp)
    eccentricity = np.full(n_comp, -1, np.int64)
    while True:
        dist = dijkstra(P, directed=False, unweighted=True, indices=start, min_only=True)
        level = np.where(np.isfinite(dist), dist, -1).astype(np.int64)
        e = np.full(n_comp, -1, np.int64)
        np.maximum.at(e, label, level)
        grew = e > eccentricity
        eccentricity = np.maximum(e, eccentricity)
        nxt = _least_degree(level == e[label], label, degree, n_comp)
        moved = grew & (nxt != start)
        if not moved.any():
            return start
        start = np.where(moved, nxt, start)


def _peripheral_rcm(P: sp.csr_matrix) -> np.ndarray:
    """Reverse Cuthill-McKee order of the symmetric graph ``P`` (no diagonal) started in each
    connected component at a pseudo-peripheral vertex (:func:`_peripheral_nodes`). scipy's
    ``reverse_cuthill_mckee`` starts at a vertex of least degree, which on a chain of bodies
    may lie anywhere along it (its half bandwidth then 17 instead of 10 from an end). Its
    start is steered, not reimplemented: each start gets a new neighbour of degree 1, every
    other vertex a diagonal entry (+1 to every degree, which keeps their order), so scipy
    seeds at the new vertex, whose only neighbour is the chosen start; the new vertices are
    then dropped."""
    from scipy.sparse.csgraph import connected_components, reverse_cuthill_mckee

    n = P.shape[0]
    if n == 0:
        return np.zeros(0, np.int64)
    n_comp, label = connected_components(P, directed=False)
    starts = _peripheral_nodes(P, label, n_comp)[np.bincount(label, minlength=n_comp) > 2]
    k = starts.size
    seeds = n + np.arange(k, dtype=np.int64)
    rows = np.concatenate([np.arange(n, dtype=np.int64), seeds, starts])
    cols = np.concatenate([np.arange(n, dtype=np.int64), starts, seeds])
    S = sp.csr_matrix((np.ones(rows.size), (rows, cols)), shape=(n + k, n + k))
    S = (S + sp.block_diag([P, sp.csr_matrix((k, k))], format="csr")).tocsr()
    perm = reverse_cuthill_mckee(S, symmetric_mode=True)
    return perm[perm < n].astype(np.int64)


def _band_order(G: sp.csr_matrix, band: np.ndarray) -> tuple[np.ndarray, int]:
    """Reverse Cuthill-McKee order of the ``band`` unknowns (scipy's, started at a vertex of
    least degree) and its half bandwidth."""
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


def supernode_order(G: sp.csr_matrix, band: np.ndarray, n_coords: int) -> np.ndarray:
    """Band order by nodes: reverse Cuthill-McKee on the quotient graph whose vertices are the
    sets of coordinates with one closed neighbourhood among the coordinates (a beam node's
    coordinates, a rigid body's), each multiplier joined to the set of the coordinates it
    constrains when they lie in one set (a clamp's rows with its node), on the side of the set
    away from its neighbours in the order. Scalar RCM splits a node between two of its
    levels (a clamped cable: half bandwidth 15 where node by node gives 11, the coordinates of
    a node coupling 2 x 6 - 1 positions ahead); this keeps nodes whole."""
    from scipy.sparse.csgraph import reverse_cuthill_mckee

    P = G[band][:, band].tocsr()
    nb = band.size
    is_coord = band < n_coords
    C = (P + sp.identity(nb, format="csr")).tocsr()
    C.sort_indices()
    coords = np.flatnonzero(is_coord)
    Cpp = C[coords][:, coords].tocsr()
    Cpp.sort_indices()
    group = np.full(nb, -1, np.int64)
    # coordinates with one closed neighbourhood: one set, numbered in order of appearance; rows
    # compared by their length and two sums of random 64-bit words of their columns (exact and
    # order-free in wrapping integer arithmetic; fixed seed: a plan is reproducible)
    words = np.random.default_rng(0x5E7).integers(0, 2**63, size=(2, coords.size),
                                                  dtype=np.uint64)
    sums = np.add.reduceat(words[:, Cpp.indices], Cpp.indptr[:-1], axis=1)   # rows: >= 1 entry
    keys = np.column_stack([np.diff(Cpp.indptr).astype(np.uint64), sums.T])
    _, first_seen, which = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    appearance = np.empty(first_seen.size, np.int64)
    appearance[np.argsort(first_seen, kind="stable")] = np.arange(first_seen.size)
    group[coords] = appearance[which.ravel()]
    # a multiplier whose coordinates lie in one set joins it; the others: sets of their own
    mult = np.flatnonzero(~is_coord)
    M = C[mult][:, coords].tocsr()
    count = np.diff(M.indptr)
    lowest = np.full(mult.size, -1, np.int64)
    highest = np.full(mult.size, -2, np.int64)
    some = count > 0
    if M.nnz:
        g = group[coords][M.indices]
        lowest[some] = np.minimum.reduceat(g, M.indptr[:-1][some])
        highest[some] = np.maximum.reduceat(g, M.indptr[:-1][some])
    joined = np.zeros(nb, bool)       # a multiplier in its coordinates' set
    joined[mult] = lowest == highest
    alone = mult[lowest != highest]
    group[mult[lowest == highest]] = lowest[lowest == highest]
    group[alone] = first_seen.size + np.arange(alone.size)
    ng = first_seen.size + alone.size
    E = sp.csr_matrix((np.ones(nb), (np.arange(nb), group)), shape=(nb, ng))
    Q = (E.T @ C @ E).tocsr()
    rank = np.empty(ng, np.int64)
    rank[reverse_cuthill_mckee(Q, symmetric_mode=True)] = np.arange(ng)
    # within a set: its coordinates, its multipliers first if its neighbours come after it
    Q = Q.tocoo()
    off = Q.row != Q.col
    later = np.bincount(Q.row[off], weights=(rank[Q.col[off]] > rank[Q.row[off]]).astype(float),
                        minlength=ng)
    earlier = np.bincount(Q.row[off], weights=(rank[Q.col[off]] < rank[Q.row[off]]).astype(float),
                          minlength=ng)
    first = later > earlier
    inner = np.where(joined, np.where(first[group], -1, 1), 0)
    key = rank[group] * 4 + inner + 1
    return band[np.lexsort((np.arange(nb), key))]


def factor_cost(n_band: int, n_border: int, bandwidth: int) -> float:
    """Estimated flops of one bordered factorisation plus :data:`SOLVES_PER_FACTOR` solves
    (kl = ku = ``bandwidth``; partial pivoting widens the upper band to kl + ku): band LU
    n_a kl (kl + ku), the n_b band solves of X, the Schur product n_b^2 n_a, its dense LU."""
    na, nb, k = float(n_band), float(n_border), float(bandwidth)
    factor = na * k * 2 * k + nb * na * 3 * k * 2 + nb * nb * na * 2 + 2 * nb**3 / 3
    solve = na * 3 * k * 2 + 4 * nb * na + 2 * nb * nb
    return factor + SOLVES_PER_FACTOR * solve


class FactorPlan(NamedTuple):
    """Border, band order and tree part of a
    :class:`~flexmbs.linalg.bordered.BorderedBandedLU`."""

    border: np.ndarray      # int64: unknowns of the dense Schur complement
    order: np.ndarray       # int64: the band's unknowns in band order
    bandwidth: int          # half bandwidth of the band in that order (before pivoting)
    cost: float             # factor_cost estimate (+ the tree part's)
    keep: np.ndarray | None = None   # the stored positions planned for (None: all)
    tree: TreePlan | None = None     # the bodies eliminated in tree order first
    sparse: bool = False             # KLU on the whole matrix instead (flexmbs.linalg.sparse_lu)

    def factorization(self, A: sp.csc_matrix) -> BorderedBandedLU:
        """The bordered banded LU of ``A``'s pattern with this plan."""
        from .bordered import BorderedBandedLU

        return BorderedBandedLU(A, self.border, self.order, self.keep, self.tree, self.sparse)


def plan_factorization(A: sp.csc_matrix, suggested: np.ndarray, n_coords: int,
                       owner: np.ndarray | None = None, keep: np.ndarray | None = None,
                       search: bool = True, sparse: bool | None = None) -> FactorPlan:
    """The border (unknowns of the dense Schur complement) and band order with the least
    :func:`factor_cost` among these borders: ``suggested`` (e.g.
    :meth:`flexmbs.assembly.Assembly.border_indices`), none (the whole saddle-point system in
    one band: chains of bodies and joints, whose bandwidth does not grow with their number),
    and the *hubs*: unknowns coupled to at least d others, for a few thresholds d (a slide
    coordinate or a sliding joint's multipliers reserved along a whole beam, the hub of a star
    of bodies); each band in the narrower of two orders: reverse Cuthill-McKee of all its
    unknowns, or :func:`saddle_order` (unknowns from ``n_coords`` on are multipliers, with a
    zero diagonal block; ``owner``: a label per unknown, >= 0 for the coordinates of one rigid
    body, kept together; :data:`MASSLESS` for a coordinate without mass). Each border is
    closed by :func:`close_border` (the band block must stay nonsingular). The same search
    once more for the rest after the bodies that :func:`peel_tree` eliminates in tree order
    (trees of bodies: no band holds a branching tree), taken where its cost with the tree's
    is lower. Computed once per pattern. ``keep``: the stored positions to plan for (the
    others are zero whenever the plan is used: a plan that follows the sliding joints),
    default all; ``search=False``: only the ``suggested`` border (closed), e.g. a plan's
    border planned again for shifted ``keep`` (a re-plan that follows the joints, in a few
    ms instead of tens). Last, the sparse LU of the whole matrix
    (:func:`~flexmbs.linalg.sparse_lu.sparse_cost`, where KLU is installed) is taken where it
    costs less than all of those (many bodies on several beams: no band holds them, and a
    border of all of them is dense); ``sparse``: True plans it without the search, False
    never."""
    if sparse:
        return _sparse_plan(A, keep)
    G, _ = _graph(A, keep)
    N = G.shape[0]
    suggested = np.unique(np.asarray(suggested, np.int64))
    best = _plan_band(G, suggested, n_coords, owner, np.ones(N, bool), search)
    tree = peel_tree(G, n_coords, owner)
    if tree is not None:
        rest = np.ones(N, bool)
        rest[tree.unknowns] = False
        cr, cc = tree.cliques(rest)         # the parent blocks in the rest the tree fills
        off = cr != cc
        on_rest = sp.diags(rest.astype(float))
        Gr = (on_rest @ G @ on_rest
              + sp.csr_matrix((np.ones(int(off.sum())), (cr[off], cc[off])), shape=G.shape)).tocsr()
        Gr.eliminate_zeros()
        Gr.data[:] = 1.0
        with_tree = _plan_band(Gr, suggested[rest[suggested]], n_coords, owner, rest, search)
        cost = with_tree.cost + tree_cost(tree)
        if cost < best.cost:
            best = with_tree._replace(cost=cost, tree=tree)
    if sparse is None and klu.AVAILABLE and N > 1:
        alternative = _sparse_plan(A, keep)
        if alternative.cost < best.cost:
            return alternative
    return best._replace(keep=keep)


def _sparse_plan(A: sp.csc_matrix, keep: np.ndarray | None) -> FactorPlan:
    """The plan of KLU on the kept entries (its cost in the band's flops)."""
    empty = np.zeros(0, np.int64)
    return FactorPlan(empty, empty, 0, sparse_cost(A, keep, SOLVES_PER_FACTOR), keep=keep,
                      sparse=True)


def _plan_band(G: sp.csr_matrix, suggested: np.ndarray, n_coords: int,
               owner: np.ndarray | None, among: np.ndarray, search: bool) -> FactorPlan:
    """:func:`plan_factorization`'s search for the border and band order of the unknowns
    ``among`` (a bool mask; the others are not in ``G``'s edges)."""
    N = G.shape[0]
    is_coord = np.arange(N) < n_coords
    degree = np.diff(G.indptr)
    candidates = [suggested, np.zeros(0, np.int64)] if search else [suggested]
    levels = np.unique(degree[among])
    if levels.size:
        levels = levels[levels > 2 * max(float(np.median(degree[among])), 1.0)]
    if levels.size and search:
        for d in levels[::-1][::max(1, levels.size // 6)]:
            candidates.append(np.flatnonzero((degree >= d) & among).astype(np.int64))
    best: FactorPlan | None = None
    seen: set[bytes] = set()
    for border in candidates:
        if border.tobytes() in seen:
            continue
        seen.add(border.tobytes())
        in_border = np.zeros(N, bool)
        in_border[border] = True
        if border.size:
            in_border = close_border(G, in_border, n_coords, owner) & among
        border = np.flatnonzero(in_border).astype(np.int64)
        if border.size > MAX_BORDER:
            continue
        band = np.flatnonzero(~in_border & among).astype(np.int64)
        order, w = _band_order(G, band)
        if band.size:
            alt = supernode_order(G, band, n_coords)
            w_alt = _bandwidth(G, alt)
            if w_alt < w:
                order, w = alt, w_alt
        # the second order only where it can matter (bodies in the band, or a border whose
        # rows leave multipliers in it): a plain beam model keeps its plan at RCM's cost
        if border.size or (owner is not None and (owner[band] >= 0).any()):
            alt = saddle_order(G, is_coord, band, owner)
            w_alt = _bandwidth(G, alt)
            if w_alt < w:
                order, w = alt, w_alt
        if band.size:       # started at a chain's end (taken only where strictly narrower)
            alt = band[_peripheral_rcm(G[band][:, band].tocsr())]
            w_alt = _bandwidth(G, alt)
            if w_alt < w:
                order, w = alt, w_alt
        cost = factor_cost(band.size, border.size, w)
        if best is None or cost < best.cost:
            best = FactorPlan(border, np.ascontiguousarray(order, np.int64), w, cost)
    assert best is not None
    return best

def tree_cost(tree: TreePlan) -> float:
    """Estimated flops of one elimination of the tree part plus :data:`SOLVES_PER_FACTOR`
    solves (dense LU of each supernode, its solves with the parent set's columns, the update of
    the parent's block), comparable with :func:`factor_cost`."""
    n = np.diff(tree.ptr).astype(float)
    m = np.diff(tree.set_ptr).astype(float)
    factor = 2 * n**3 / 3 + 2 * m * n * n + 2 * m * m * n
    solve = 2 * n * n + 4 * m * n
    return float((factor + SOLVES_PER_FACTOR * solve).sum())


def peel_tree(G: sp.csr_matrix, n_coords: int, owner: np.ndarray | None) -> TreePlan | None:
    """The rigid bodies that can be eliminated leaf by leaf, children before parents (Baraff
    1996, "Linear-time dynamics using Lagrange multipliers"): a body whose remaining
    neighbours are, through the rows of the joints to it and directly, the coordinates of one
    other body (its parent) is a leaf; with those joint rows and its own rows it forms a
    supernode whose block [[H, J^T], [J, 0]] is nonsingular when the body has mass and the rows
    are independent: the joint rows are functions of its pose with the parent held and at most
    one own row (the normalisation, orthogonal to them) is allowed beside them, as for the
    border's leaves (:func:`close_border`). A body left with no neighbours is a root (any own
    rows: its joints to the ground). Eliminating a leaf fills only its parent's block, so a
    chain or tree of bodies costs O(N) and no band or border holds it. ``G``: the symmetric
    pattern graph; ``owner``: >= 0 labels the coordinates of one rigid body (with mass: a
    statics plan, all :data:`MASSLESS`, peels nothing). None when no body is peeled."""
    N = G.shape[0]
    if owner is None or N == 0:
        return None
    lab = np.asarray(owner[:n_coords], np.int64)
    bodies, atom_c = np.unique(lab[lab >= 0], return_inverse=True)
    if not bodies.size:
        return None
    atom = np.full(N, -1, np.int64)       # the body an unknown belongs to (coordinates, own rows)
    coords = np.flatnonzero(lab >= 0)
    atom[coords] = atom_c.ravel()
    # a row is a body's own when all its neighbours are that body's coordinates (multipliers
    # are labelled -1 here, so a neighbouring multiplier disqualifies it)
    indptr, indices = G.indptr, G.indices
    start_r, end_r = indptr[n_coords:N], indptr[n_coords + 1:N + 1]
    filled = end_r > start_r
    if indices.size and filled.any():
        label = atom[indices]
        lo = np.minimum.reduceat(label, start_r[filled])
        hi = np.maximum.reduceat(label, start_r[filled])
        rows = n_coords + np.flatnonzero(filled)
        own = (lo >= 0) & (lo == hi)
        atom[rows[own]] = lo[own]
    order = np.argsort(atom, kind="stable")
    start = np.searchsorted(atom[order], np.arange(bodies.size + 1))
    members = [order[start[a]:start[a + 1]] for a in range(bodies.size)]
    # only a body with at most one own row (a leaf) or with nothing outside it (a root) can be
    # taken now; the others are looked at again when a child of theirs is taken
    cols = np.repeat(np.arange(N, dtype=np.int64), np.diff(indptr))
    outside = (atom[cols] >= 0) & (atom[indices] != atom[cols])
    has_outside = np.bincount(atom[cols[outside]], minlength=bodies.size) > 0
    n_own = np.bincount(atom[n_coords:][atom[n_coords:] >= 0], minlength=bodies.size)
    alive = np.ones(N, bool)
    peeled = np.zeros(bodies.size, bool)
    supernodes: list[np.ndarray] = []
    sets: list[np.ndarray] = []
    queue = np.flatnonzero((n_own <= 1) | ~has_outside).tolist()
    while queue:
        a = queue.pop()
        if peeled[a]:
            continue
        mine = members[a]
        own_rows = int(n_own[a])
        ext = np.unique(np.concatenate([indices[indptr[u]:indptr[u + 1]] for u in mine]))
        ext = ext[alive[ext] & (atom[ext] != a)]
        link = ext[(ext >= n_coords) & (atom[ext] < 0)]
        node = np.concatenate([mine, link]) if link.size else mine
        if link.size:       # the joint rows' other coordinates join the neighbours
            around = np.unique(np.concatenate([indices[indptr[u]:indptr[u + 1]] for u in link]))
            ext = np.union1d(np.setdiff1d(ext, link), around[alive[around]])
        parent_set = np.setdiff1d(ext, node)
        if parent_set.size:
            p = atom[parent_set[0]]
            if (own_rows > 1 or p < 0 or (parent_set >= n_coords).any()
                    or (atom[parent_set] != p).any()):
                continue
        alive[node] = False
        peeled[a] = True
        supernodes.append(node.astype(np.int64))
        sets.append(parent_set.astype(np.int64))
        if parent_set.size:
            queue.append(int(atom[parent_set[0]]))
    if not supernodes:
        return None
    return TreePlan(ptr=np.concatenate([[0], np.cumsum([s.size for s in supernodes])]).astype(np.int64),
                    unknowns=np.concatenate(supernodes).astype(np.int64),
                    set_ptr=np.concatenate([[0], np.cumsum([s.size for s in sets])]).astype(np.int64),
                    parent_set=np.concatenate(sets).astype(np.int64))


#: :func:`plan_factorization`'s ``owner`` label of a coordinate without mass (a sliding
#: joint's slide coordinate): in the border whenever there is one
MASSLESS = -2


def close_border(G: sp.csr_matrix, in_border: np.ndarray, n_coords: int,
                 owner: np.ndarray | None = None) -> np.ndarray:
    """The smallest border containing ``in_border`` whose band block A_aa is nonsingular
    whenever the iteration matrix is (in dynamics: mass on every band coordinate, Φ_q of
    full row rank); the Schur complement needs A_aa^-1 (:mod:`flexmbs.linalg.bordered`).

    A_aa = [[H_aa, B_a^T], [B_a, 0]] is nonsingular if B_a (the band multipliers' rows of
    Φ_q on the band coordinates) has full row rank and H_aa = c_M M_aa + ... is definite on
    its null space. A multiplier that constrains a border coordinate loses those columns in
    B_a, and its row may then depend on the others: Example 2's hinge CD, with panel 2 in the
    border, puts 5 rows on panel 1's 7 coordinates beside panel 1's own 6 (hinge AB,
    normalisation), 11 rows on 7 columns. Hence:

    * a rigid body (``owner`` >= 0) is in the border whole or not at all (at the identity
      orientation e0 has no mass, which only its normalisation row in the band makes up
      for), and a coordinate without mass (``owner`` == :data:`MASSLESS`) is in the border;
    * a multiplier that constrains a border coordinate joins the border (its rows in B_a
      are then rows of Φ_q, independent), except the rows of a *leaf*: a band rigid body o
      whose band multipliers touch no other band coordinate, all but at most one of them
      (its normalisation) constrain border coordinates of one single border body b. These
      are joints between o and b: independent functions of the relative pose, hence of o's
      pose with b held, and orthogonal to o's normalisation gradient 2p (Φ(p) homogeneous
      in p); they occupy o's columns alone, so B_a stays block-diagonal and of full rank.
      The leaves keep a star's hub a border of its own 7 coordinates and their rows;
    * a multiplier without band neighbours joins the border (an empty row of A_aa).
    """
    N = G.shape[0]
    in_border = in_border.copy()
    if owner is not None:
        in_border[:n_coords] |= owner[:n_coords] == MASSLESS
        body = np.where(owner[:n_coords] >= 0, owner[:n_coords], -1)
        split = np.unique(body[in_border[:n_coords] & (body >= 0)])
        in_border[:n_coords] |= np.isin(body, split) & (body >= 0)
    else:
        body = np.full(n_coords, -1, np.int64)
    coupling = G[n_coords:, :n_coords].tocsr()   # multiplier rows x coordinates
    m = N - n_coords
    move = np.zeros(m, bool)
    touches_border = np.zeros(m, bool)
    leaf_of = np.full(m, -1, np.int64)    # the band body a border-touching row may stay on
    for r in np.flatnonzero(~in_border[n_coords:]):
        cols = coupling.indices[coupling.indptr[r]:coupling.indptr[r + 1]]
        inside = in_border[cols]
        touches_border[r] = inside.any()
        if not touches_border[r]:
            move[r] = not cols.size and G.indptr[n_coords + r + 1] > G.indptr[n_coords + r]
            continue
        mine = np.unique(body[cols[~inside]])
        theirs = np.unique(body[cols[inside]])
        if mine.size == 1 and mine[0] >= 0 and theirs.size == 1 and theirs[0] >= 0:
            leaf_of[r] = mine[0]
        else:       # no band neighbour, several bodies, beam or massless coordinates
            move[r] = True
    for o in np.unique(leaf_of[leaf_of >= 0]):
        cols_o = np.flatnonzero(body == o)
        rows_o = np.unique(coupling[:, cols_o].tocsc().indices)
        rows_o = rows_o[~in_border[n_coords + rows_o] & ~move[rows_o]]
        anchors: set[int] = set()
        local = True
        for r in rows_o:
            cols = coupling.indices[coupling.indptr[r]:coupling.indptr[r + 1]]
            local = local and bool((body[cols[~in_border[cols]]] == o).all())
            anchors.update(np.unique(body[cols[in_border[cols]]]).tolist())
        if not (local and len(anchors) == 1 and int((~touches_border[rows_o]).sum()) <= 1):
            move[rows_o[touches_border[rows_o]]] = True
    in_border[n_coords:] |= move
    return in_border


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

"""The bordered LU's plan (flexmbs.linalg.ordering): border and band order chosen by cost,
checked against SuperLU on saddle-point systems of multibody shapes (issue 37)."""

from __future__ import annotations

import sys

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from flexmbs.linalg.bordered import BorderedBandedLU
from flexmbs.linalg.ordering import close_border, plan_factorization

#: relative agreement with SuperLU (the systems below have cond ~ 1e2..1e4)
SUPERLU_TOL = 1e-12


def _saddle(rng: np.random.Generator, n_bodies: int, joints: list[tuple[int, int]],
            beam_elements: int = 0, on_beam: tuple[int, ...] = (), regularise: float = 0.0,
            ) -> tuple[sp.csc_matrix, int, np.ndarray, np.ndarray]:
    """Saddle-point matrix of rigid bodies (7 coordinates, an SPD block each, a normalisation
    row on the last 4), spherical-like joints (3 rows on both bodies' 7 coordinates; body −1 is
    the ground), an optional beam (6 coordinates per node, 12 x 12 element blocks) whose node
    ``k`` in ``on_beam`` is joined to body ``k % n_bodies``. Multipliers after coordinates;
    ``regularise`` > 0 puts −regularise I in the multiplier block (no zero diagonal block).
    Returns A, the number of coordinates, the suggested border (all bodies and their rows) and
    the owner labels (body index of a body's coordinates, −1 otherwise)."""
    nb7 = 7 * n_bodies
    n_beam = 6 * (beam_elements + 1) if beam_elements else 0
    n = nb7 + n_beam
    K = sp.lil_matrix((n, n))
    for b in range(n_bodies):
        B = rng.standard_normal((7, 7))
        K[7 * b:7 * b + 7, 7 * b:7 * b + 7] = B @ B.T / 7 + 2 * np.eye(7)
    for e in range(beam_elements):
        B = rng.standard_normal((12, 12))
        s = slice(nb7 + 6 * e, nb7 + 6 * e + 12)
        K[s, s] = K[s, s].toarray() + B @ B.T / 12 + np.eye(12)
    rows = []
    for b in range(n_bodies):        # normalisation
        r = np.zeros(n)
        r[7 * b + 3:7 * b + 7] = rng.uniform(0.5, 1.5, 4)
        rows.append(r)
    pairs = [(a, ("body", b)) for a, b in joints] + [(k % n_bodies, ("node", k)) for k in on_beam]
    for a, (kind, b) in pairs:
        for _ in range(3):
            r = np.zeros(n)
            r[7 * a:7 * a + 7] = rng.standard_normal(7)
            if kind == "body" and b >= 0:
                r[7 * b:7 * b + 7] = rng.standard_normal(7)
            elif kind == "node":
                r[nb7 + 6 * b:nb7 + 6 * b + 6] = rng.standard_normal(6)
            rows.append(r)
    C = sp.csr_matrix(np.array(rows))
    m = C.shape[0]
    # a joint's rotational coupling (Φ_qq^T λ) between the two bodies
    for a, (kind, b) in pairs:
        if kind == "body" and b >= 0:
            X = 0.1 * rng.standard_normal((7, 7))
            K[7 * a:7 * a + 7, 7 * b:7 * b + 7] = X
            K[7 * b:7 * b + 7, 7 * a:7 * a + 7] = X.T
    D = -regularise * sp.identity(m) if regularise else sp.csr_matrix((m, m))
    A = sp.bmat([[sp.csr_matrix(K), C.T], [C, D]], format="csc")
    A.sort_indices()
    border = np.r_[np.arange(nb7), n + np.arange(m)] if n_bodies else np.zeros(0, np.int64)
    owner = np.full(A.shape[0], -1, np.int64)
    owner[:nb7] = np.repeat(np.arange(n_bodies), 7)
    return A, n, border, owner


def _chain(n):
    return [(k, k - 1) for k in range(n)]


def _star(n):
    return [(0, -1)] + [(k, 0) for k in range(1, n)]


def _binary_tree(n):
    return [(0, -1)] + [(k, (k - 1) // 2) for k in range(1, n)]


def _loop(n):   # a closed chain: both ends on the ground (four-bar: n = 3)
    return _chain(n) + [(n - 1, -1)]


SHAPES = {
    "chain": lambda rng, reg: _saddle(rng, 60, _chain(60), regularise=reg),
    "star": lambda rng, reg: _saddle(rng, 40, _star(40), regularise=reg),
    "binary_tree": lambda rng, reg: _saddle(rng, 63, _binary_tree(63), regularise=reg),
    "four_bar": lambda rng, reg: _saddle(rng, 3, _loop(3), regularise=reg),
    "loop": lambda rng, reg: _saddle(rng, 30, _loop(30), regularise=reg),
    "beam_with_bodies": lambda rng, reg: _saddle(rng, 4, _chain(4), beam_elements=40,
                                                 on_beam=(10, 20, 30, 40), regularise=reg),
}


@pytest.mark.parametrize("regularise", [0.0, 1e-2], ids=["zero_block", "regularised"])
@pytest.mark.parametrize("shape", sorted(SHAPES))
def test_planned_lu_matches_superlu(shape, regularise):
    rng = np.random.default_rng(abs(hash(shape)) % 2**32)
    A, n, border, owner = SHAPES[shape](rng, regularise)
    plan = plan_factorization(A, border, n, owner)
    lu = plan.factorization(A)
    assert lu.factorize(A.data), f"pivot failure {lu.info}"
    b = rng.standard_normal(A.shape[0])
    x = lu.solve(b)
    ref = spla.splu(A, permc_spec="COLAMD").solve(b)
    assert np.abs(x - ref).max() <= SUPERLU_TOL * np.abs(ref).max()
    assert plan.cost <= plan_factorization(A, border, n, owner).cost   # deterministic


def test_chain_is_one_band_of_constant_width():
    """A chain needs no border and its bandwidth does not grow with its length (O(N))."""
    widths = []
    for nb in (20, 80, 320):
        A, n, border, owner = _saddle(np.random.default_rng(nb), nb, _chain(nb))
        plan = plan_factorization(A, border, n, owner)
        assert plan.border.size == 0
        widths.append(plan.bandwidth)
    assert widths[0] == widths[1] == widths[2] <= 21


def test_reverse_cuthill_mckee_starts_at_a_chain_end():
    """scipy's reverse Cuthill-McKee starts at a vertex of least degree, on a chain of bodies
    anywhere along it: its band is then about twice as wide as from an end. Started at a
    pseudo-peripheral vertex the band does not depend on the chain's length; the planned LU
    solves as SuperLU does."""
    from scipy.sparse.csgraph import reverse_cuthill_mckee

    from flexmbs.linalg.ordering import _bandwidth, _graph, _peripheral_rcm

    scipy_widths, widths = [], []
    for nb in (10, 40, 160, 320):
        rng = np.random.default_rng(3)
        A, n, border, owner = _saddle(rng, nb, _chain(nb))
        G, _ = _graph(A)
        scipy_widths.append(_bandwidth(G, reverse_cuthill_mckee(G, symmetric_mode=True)))
        widths.append(_bandwidth(G, _peripheral_rcm(G)))
        plan = plan_factorization(A, border, n, owner)
        assert plan.border.size == 0 and plan.bandwidth <= widths[-1]
        lu = plan.factorization(A)
        assert lu.factorize(A.data)
        b = rng.standard_normal(A.shape[0])
        ref = spla.splu(A, permc_spec="COLAMD").solve(b)
        assert np.abs(lu.solve(b) - ref).max() <= SUPERLU_TOL * np.abs(ref).max()
    assert len(set(widths)) == 1 and max(scipy_widths) > widths[0]


def test_a_chain_of_spherical_joints_plans_to_the_width_of_one_link():
    """The hanging chain of ``benchmarks/chain.py`` (spherical joints in global components):
    one link's 7 coordinates, its normalisation row and the 3 rows of the next joint, so a
    half bandwidth of 10 at any length (13 or 17 where the order started mid-chain)."""
    import flexmbs as fm
    from flexmbs.assembly import Assembly

    for nb in (10, 320):
        model = fm.Model(gravity=(0.0, 0.0, -9.81))
        prev = fm.GROUND
        for k in range(nb):
            body = model.add_rigid_body(mass=0.1, inertia=(1e-6, 1e-4, 1e-4),
                                        pose=fm.Pose(((k + 0.5) * 0.1, 0.0, 0.0), np.eye(3)))
            model.spherical(body, prev, point=(k * 0.1, 0.0, 0.0))
            prev = body
        plan = Assembly(model).factor_plan()
        assert plan.border.size == 0 and plan.bandwidth == 10


def test_star_keeps_its_hub_in_the_border():
    """A star's hub couples to every joint: a band would be as wide as the star; the hub's
    coordinates (with the rows on the hub alone: normalisation, joint to the ground) form the
    border, the leaves a narrow band (the band search alone: with the tree part the star is
    a tree, below)."""
    from flexmbs.linalg.ordering import _graph, _plan_band

    A, n, border, owner = _saddle(np.random.default_rng(3), 80, _star(80))
    G, _ = _graph(A)
    plan = _plan_band(G, border, n, owner, np.ones(A.shape[0], bool), True)
    assert 0 < plan.border.size <= 7 + 1 + 3
    assert plan.bandwidth <= 12


def _tree_plan(A: sp.csc_matrix, n: int, owner: np.ndarray):
    from flexmbs.linalg.ordering import _graph, peel_tree

    return peel_tree(_graph(A)[0], n, owner)


def _peeled_bodies(tree, owner: np.ndarray) -> list[int]:
    """The bodies of the tree's supernodes, in elimination order."""
    return [int(np.unique(owner[tree.unknowns[tree.ptr[k]:tree.ptr[k + 1]]][
        owner[tree.unknowns[tree.ptr[k]:tree.ptr[k + 1]]] >= 0])[0]) for k in range(tree.ptr.size - 1)]


def test_trees_of_bodies_are_eliminated_children_first():
    """peel_tree (Baraff 1996): every body of a binary tree or a star, each after all of its
    children, the root last with its ground joint; each supernode is a body's 7 coordinates,
    its normalisation and the 3 rows of the joint to its parent, and couples only to its
    parent's 7 coordinates."""
    for joints in (_binary_tree(31), _star(12), _chain(9)):
        nb = len(joints)
        A, n, _, owner = _saddle(np.random.default_rng(nb), nb, joints)
        tree = _tree_plan(A, n, owner)
        assert tree is not None and tree.size == A.shape[0]
        order = _peeled_bodies(tree, owner)
        assert sorted(order) == list(range(nb))
        rank = {b: k for k, b in enumerate(order)}
        for child, parent in joints:
            if parent >= 0:
                assert rank[child] < rank[parent]
        sizes, sets = np.diff(tree.ptr), np.diff(tree.set_ptr)
        assert (sizes[:-1] == 7 + 1 + 3).all() and sizes[-1] == 7 + 1 + 3
        assert (sets[:-1] == 7).all() and sets[-1] == 0


def test_loops_and_doubly_held_bodies_stay_in_the_rest():
    """A closed loop has no leaf (four-bar, a loop of 30); a body with a joint to the ground
    besides the joint to its parent is not a leaf (its rows need not be independent on its
    coordinates alone), so the chain it ends stays too; a tree hanging from a loop is
    peeled up to the loop."""
    for joints in (_loop(3), _loop(30)):
        A, n, _, owner = _saddle(np.random.default_rng(1), len(joints) - 1, joints)
        assert _tree_plan(A, n, owner) is None
    A, n, _, owner = _saddle(np.random.default_rng(2), 5, _chain(5) + [(4, -1)])
    assert _tree_plan(A, n, owner) is None
    # a four-bar (bodies 0-2) with a binary tree of 7 bodies (3-9) hanging from body 1
    joints = _loop(3) + [(3, 1)] + [(3 + k, 3 + (k - 1) // 2) for k in range(1, 7)]
    A, n, _, owner = _saddle(np.random.default_rng(3), 10, joints)
    tree = _tree_plan(A, n, owner)
    assert sorted(_peeled_bodies(tree, owner)) == list(range(3, 10))
    last = tree.parent_set[tree.set_ptr[-2]:tree.set_ptr[-1]]
    assert set(owner[last]) == {1}          # the tree's root fills body 1's block only


def _check_tree_lu(A: sp.csc_matrix, border: np.ndarray, tree, rng: np.random.Generator) -> None:
    """The bordered LU with ``tree`` and ``border`` (band: the rest) against SuperLU, twice
    (a refactorisation reuses the maps), and its twin."""
    lu = BorderedBandedLU(A, border, tree=tree)
    for _ in range(2):
        assert lu.factorize(A.data), f"pivot failure {lu.info}"
        b = rng.standard_normal(A.shape[0])
        ref = spla.splu(A, permc_spec="COLAMD").solve(b)
        assert np.abs(lu.solve(b) - ref).max() <= SUPERLU_TOL * np.abs(ref).max()
        A = A.copy()
        A.data = A.data * rng.uniform(0.9, 1.1, A.data.size)


@pytest.mark.parametrize("regularise", [0.0, 1e-2], ids=["zero_block", "regularised"])
def test_tree_part_matches_superlu(regularise):
    """The tree part eliminated first, its roots' updates landing in every kind of block of
    the rest: a tree whose root is a loop body in the band, in the border (band-border,
    border-border entries), a body on a beam with a tree below it, and a whole binary tree."""
    rng = np.random.default_rng(11)
    joints = _loop(3) + [(3, 1)] + [(3 + k, 3 + (k - 1) // 2) for k in range(1, 7)]
    A, n, _, owner = _saddle(rng, 10, joints, regularise=regularise)
    tree = _tree_plan(A, n, owner)
    rest = np.setdiff1d(np.arange(A.shape[0]), tree.unknowns)
    from flexmbs.linalg.ordering import _graph

    G = _graph(A)[0]
    for pick in (np.zeros(0, np.int64), np.flatnonzero(owner == 1), rest[::2], rest):
        in_border = np.zeros(A.shape[0], bool)
        in_border[pick] = True
        border = np.flatnonzero(close_border(G, in_border, n, owner) & ~np.isin(
            np.arange(A.shape[0]), tree.unknowns))
        _check_tree_lu(A, border, tree, rng)
    # a border that splits body 1 (not a planned one): updates into all four blocks
    border = np.flatnonzero(owner == 1)[:3]
    kinds = np.bincount(BorderedBandedLU(A, border, tree=tree).factor.tree.update_kinds(),
                        minlength=5)
    assert (kinds > 0).all()
    _check_tree_lu(A, border, tree, rng)
    # bodies 0-3 in a chain, body 0 on a beam node; a binary tree of 7 below body 3
    joints = [(1, 0), (2, 1), (3, 2)] + [(4, 3)] + [(4 + k, 4 + (k - 1) // 2) for k in range(1, 7)]
    A, n, border, owner = _saddle(rng, 11, joints, beam_elements=20, on_beam=(11,),
                                  regularise=regularise)
    tree = _tree_plan(A, n, owner)
    assert sorted(_peeled_bodies(tree, owner)) == list(range(1, 11))
    _check_tree_lu(A, np.zeros(0, np.int64), tree, rng)
    A, n, border, owner = _saddle(rng, 63, _binary_tree(63), regularise=regularise)
    _check_tree_lu(A, np.zeros(0, np.int64), _tree_plan(A, n, owner), rng)


def test_a_singular_tree_block_is_reported():
    """A first leaf without mass or rows (its block zero): the factorisation fails with the
    pivot code of a tree unknown of that leaf (N + 2 + k, k < its size)."""
    A, n, _, owner = _saddle(np.random.default_rng(4), 7, _binary_tree(7))
    tree = _tree_plan(A, n, owner)
    first = tree.unknowns[:tree.ptr[1]]
    cols = np.repeat(np.arange(A.shape[0]), np.diff(A.indptr))
    A.data[np.isin(A.indices, first) & np.isin(cols, first)] = 0.0
    lu = BorderedBandedLU(A, np.zeros(0, np.int64), tree=tree)
    assert not lu.factorize(A.data)
    assert A.shape[0] + 2 <= lu.info < A.shape[0] + 2 + first.size


def test_a_binary_tree_costs_o_n():
    """The plan of a binary tree of bodies: all of it in tree order, an estimated cost per
    body that does not grow with the tree (the band's grew with its width: O(N^2) and
    worse)."""
    per_body = []
    for nb in (15, 63, 255, 1023):
        A, n, border, owner = _saddle(np.random.default_rng(nb), nb, _binary_tree(nb))
        plan = plan_factorization(A, border, n, owner)
        assert plan.tree is not None and plan.tree.size == A.shape[0]
        per_body.append(plan.cost / nb)
    assert max(per_body) <= 1.1 * min(per_body)


def test_cost_estimate_prefers_the_given_border_for_a_sleeve_on_a_long_beam():
    """A few bodies coupled along a whole beam (Example 1's sleeve): among the bands, the
    bordered form. Where KLU is installed its sparse LU is cheaper still and taken (measured
    on this matrix: a refactorisation 169 µs against the bordered form's 8.9 ms)."""
    rng = np.random.default_rng(5)
    A, n, border, owner = _saddle(rng, 1, [(0, -1)], beam_elements=60, on_beam=tuple(range(61)))
    plan = plan_factorization(A, border, n, owner, sparse=False)
    assert plan.border.size > 0 and plan.bandwidth <= 20
    if sys.platform != "win32":   # KLU: a dependency but on Windows
        chosen = plan_factorization(A, border, n, owner)
        assert chosen.sparse and chosen.cost < plan.cost


def _hinged(rng: np.random.Generator, joints: list[tuple[int, int, int]], n_bodies: int,
            beam_nodes: int, hubs: tuple[int, ...], copy_rows: dict[int, int] | None = None,
            ) -> tuple[sp.csc_matrix, int, np.ndarray, np.ndarray]:
    """Saddle-point matrix of rigid bodies (7 coordinates, SPD block, a normalisation row on
    the last 4) joined by ``joints`` (a, b, rows: ``rows`` rows on both bodies' 7
    coordinates, b = −1 the ground), and a beam of ``beam_nodes`` nodes (6 coordinates,
    12 x 12 element blocks) held at both ends (6 rows each); every body in ``hubs`` couples
    through stiffness to every beam coordinate (a contact along the wire), which makes it a
    hub of the graph. ``copy_rows`` {j: k}: joint j's rows on its body a are those of joint
    k (the full rows stay independent through the other bodies' columns)."""
    nb7 = 7 * n_bodies
    n = nb7 + 6 * beam_nodes
    K = np.zeros((n, n))
    for b in range(n_bodies):
        B = rng.standard_normal((7, 7))
        K[7 * b:7 * b + 7, 7 * b:7 * b + 7] = B @ B.T / 7 + 2 * np.eye(7)
    for e in range(beam_nodes - 1):
        B = rng.standard_normal((12, 12))
        s = slice(nb7 + 6 * e, nb7 + 6 * e + 12)
        K[s, s] += B @ B.T / 12 + np.eye(12)
    for h in hubs:
        X = 0.05 * rng.standard_normal((7, 6 * beam_nodes))
        K[7 * h:7 * h + 7, nb7:] = X
        K[nb7:, 7 * h:7 * h + 7] = X.T
    rows = []
    for b in range(n_bodies):
        r = np.zeros(n)
        r[7 * b + 3:7 * b + 7] = rng.uniform(0.5, 1.5, 4)
        rows.append(r)
    on_a: list[np.ndarray] = []
    for j, (a, b, k) in enumerate(joints):
        block = rng.standard_normal((k, 7))
        if copy_rows and j in copy_rows:
            block = on_a[copy_rows[j]]
        on_a.append(block)
        for i in range(k):
            r = np.zeros(n)
            r[7 * a:7 * a + 7] = block[i]
            if b >= 0:
                r[7 * b:7 * b + 7] = rng.standard_normal(7)
            rows.append(r)
    for node in (0, beam_nodes - 1):
        for i in range(6):
            r = np.zeros(n)
            r[nb7 + 6 * node + i] = 1.0
            rows.append(r)
    C = np.array(rows)
    m = C.shape[0]
    A = sp.csc_matrix(np.block([[K, C.T], [C, np.zeros((m, m))]]))
    A.sort_indices()
    border = np.r_[np.arange(nb7), n + np.arange(m - 12)]
    owner = np.full(n + m, -1, np.int64)
    owner[:nb7] = np.repeat(np.arange(n_bodies), 7)
    return A, n, border, owner


def _wing(rng: np.random.Generator) -> tuple[sp.csc_matrix, int, np.ndarray, np.ndarray]:
    """Example 2's structure: panel 1 hinged to the ground (5 rows), panel 2 hinged to
    panel 1 (5), a bar on a slider (5) tied to panel 2 (2); the guide wire (13 nodes) in
    contact with panel 2 all along, which makes panel 2 a hub."""
    return _hinged(rng, [(0, -1, 5), (0, 1, 5), (2, -1, 5), (2, 1, 2)], 3, 13, hubs=(1,))


def _two_anchors(rng: np.random.Generator) -> tuple[sp.csc_matrix, int, np.ndarray, np.ndarray]:
    """A body (0) joined to two hubs (1, 2) by 3 rows each whose parts on body 0 coincide
    (two spherical joints on one axis: the body may spin about it when both hubs are held):
    7 rows on 7 coordinates, square yet singular once the hubs are in the border."""
    return _hinged(rng, [(0, 1, 3), (0, 2, 3), (1, -1, 3), (2, -1, 3)], 3, 13, hubs=(1, 2),
                   copy_rows={1: 0})


def test_example2_shape_band_block_is_nonsingular():
    """Regression (Example 2 failed at its first step, "zero pivot 9"): panel 2 is a hub of
    the border, and the hinge CD and tie EF multipliers it leaves in the band put 11 rows on
    panel 1's 7 coordinates (8 on the bar's): A_aa singular. Closed border: they join it."""
    rng = np.random.default_rng(37)
    A, n, border, owner = _wing(rng)
    assert np.linalg.matrix_rank(A.toarray()) == A.shape[0]
    plan = plan_factorization(A, border, n, owner)
    assert 0 < plan.border.size < border.size          # the hub's border, not the assembly's
    assert set(range(7, 14)) <= set(plan.border.tolist())
    lu = plan.factorization(A)
    assert lu.factorize(A.data), f"pivot failure {lu.info}"
    b = rng.standard_normal(A.shape[0])
    ref = spla.splu(A, permc_spec="COLAMD").solve(b)
    assert np.abs(lu.solve(b) - ref).max() <= SUPERLU_TOL * np.abs(ref).max()


def _band_rank(A: sp.csc_matrix, in_border: np.ndarray) -> tuple[int, int]:
    band = np.flatnonzero(~in_border)
    return np.linalg.matrix_rank(A[band][:, band].toarray()), band.size


@pytest.mark.parametrize("shape", ["wing", "two_anchors", "star", "chain", "binary_tree",
                                   "loop"])
def test_closed_border_leaves_a_nonsingular_band(shape):
    """Every border of whole bodies (random subsets), closed by close_border, leaves a band
    block of full rank; the rows it keeps beside a border body are a leaf's."""
    builders = {
        "wing": _wing, "two_anchors": _two_anchors,
        "star": lambda rng: _saddle(rng, 12, _star(12)),
        "chain": lambda rng: _saddle(rng, 12, _chain(12)),
        "binary_tree": lambda rng: _saddle(rng, 15, _binary_tree(15)),
        "loop": lambda rng: _saddle(rng, 10, _loop(10)),
    }
    rng = np.random.default_rng(abs(hash(shape)) % 2**32)
    A, n, _, owner = builders[shape](rng)
    assert np.linalg.matrix_rank(A.toarray()) == A.shape[0]
    G = (abs(A) + abs(A).T).tocsr()
    G.setdiag(0)
    G.eliminate_zeros()
    n_bodies = int(owner.max()) + 1
    for _ in range(12):
        chosen = rng.random(n_bodies) < 0.4
        in_border = np.zeros(A.shape[0], bool)
        in_border[:n] = np.isin(owner[:n], np.flatnonzero(chosen))
        closed = close_border(G, in_border, n, owner)
        assert (closed >= in_border).all()
        rank, size = _band_rank(A, closed)
        assert rank == size, f"band block rank {rank} < {size} (border of bodies {chosen})"


def test_two_anchors_rows_join_the_border():
    """The rows of a body held by two border bodies are not a leaf's: with both hubs in the
    border, the body's 6 joint rows join it (left in the band, its block has rank 6 of 7
    rows)."""
    A, n, _, owner = _two_anchors(np.random.default_rng(1))
    G = (abs(A) + abs(A).T).tocsr()
    G.setdiag(0)
    G.eliminate_zeros()
    in_border = np.zeros(A.shape[0], bool)
    in_border[7:21] = True
    rank, size = _band_rank(A, in_border)
    assert rank < size                       # the singular band the closure must prevent
    closed = close_border(G, in_border, n, owner)
    assert closed[n + 1:n + 7].all() and not closed[n]   # joint rows in, body 0's norm. out
    rank, size = _band_rank(A, closed)
    assert rank == size


def _clamped_beam(rng: np.random.Generator, elements: int) -> tuple[sp.csc_matrix, int]:
    """A cable's pattern: 6 coordinates per node, 12 x 12 element blocks, the first node's
    position and two slope components held by 5 single-coordinate rows (a clamp)."""
    n = 6 * (elements + 1)
    K = sp.lil_matrix((n, n))
    for e in range(elements):
        B = rng.standard_normal((12, 12))
        s = slice(6 * e, 6 * e + 12)
        K[s, s] = K[s, s].toarray() + B @ B.T / 12 + np.eye(12)
    clamp = [0, 1, 2, 4, 5]
    C = sp.csr_matrix((np.ones(len(clamp)), (np.arange(len(clamp)), clamp)), shape=(len(clamp), n))
    A = sp.bmat([[sp.csr_matrix(K), C.T], [C, None]], format="csc")
    A.sort_indices()
    return A, n


def test_a_clamped_beam_is_ordered_node_by_node():
    """Scalar reverse Cuthill-McKee splits a node's coordinates between two of its levels and
    puts the clamp's rows between nodes (half bandwidth 15); node by node, the clamp's rows at
    the beam's end, the band is as narrow as the element coupling: 2 x 6 - 1 = 11 (measured on
    the dynamic cantilever: factorisation and solve about 17 % cheaper)."""
    from scipy.sparse.csgraph import reverse_cuthill_mckee

    from flexmbs.linalg.ordering import _bandwidth, _graph

    rng = np.random.default_rng(7)
    for elements in (8, 40):
        A, n = _clamped_beam(rng, elements)
        G, _ = _graph(A)
        assert _bandwidth(G, reverse_cuthill_mckee(G, symmetric_mode=True)) > 11   # scalar
        plan = plan_factorization(A, np.zeros(0, np.int64), n)
        assert plan.border.size == 0 and plan.bandwidth == 11
        lu = plan.factorization(A)
        assert lu.factorize(A.data) and lu.kl == lu.ku == 11
        b = rng.standard_normal(A.shape[0])
        ref = spla.splu(A, permc_spec="COLAMD").solve(b)
        assert np.abs(lu.solve(b) - ref).max() <= SUPERLU_TOL * np.abs(ref).max()


def test_a_plan_of_the_entries_in_use_puts_a_ring_beside_its_element():
    """A slide coordinate and its three multipliers reserve entries against the whole beam
    (the ring may slide anywhere) but use those of one element: planned on the whole pattern
    they are hubs in the dense border; planned on the entries in use (``keep``, the rest zero)
    they sit in the band beside their element, and the factorisation (which reads only the
    kept entries) solves as SuperLU does."""
    rng = np.random.default_rng(11)
    A, n = _clamped_beam(rng, 40)
    N0 = A.shape[0]
    ring = np.arange(N0, N0 + 4)                        # s, then three multipliers
    near = np.arange(6 * 20, 6 * 22)                    # element 20's coordinates
    B = sp.lil_matrix((N0 + 4, N0 + 4))
    B[:N0, :N0] = A
    B[ring[0], ring[0]] = 1.0
    for r in ring:                                      # the reserved pattern: whole beam
        B[r, :n] = 1e-300
        B[:n, r] = 1e-300
    B = sp.csc_matrix(B)
    B.sort_indices()
    cols = np.repeat(np.arange(B.shape[0]), np.diff(B.indptr))
    rows = B.indices
    reserved = (np.isin(rows, ring) & (cols < n)) | (np.isin(cols, ring) & (rows < n))
    in_use = reserved & (np.isin(rows, near) | np.isin(cols, near))
    values = B.copy()                                   # the same pattern, values in use:
    values.data[reserved] = 0.0                         # ring x beam at element 20 only
    w = rng.standard_normal((4, near.size))
    for k in np.flatnonzero(in_use):
        r, c = (rows[k], cols[k]) if rows[k] >= N0 else (cols[k], rows[k])
        values.data[k] = w[r - N0, np.searchsorted(near, c)]
    coords = n                                          # the ring's unknowns: massless + rows
    owner = np.full(B.shape[0], -1, np.int64)
    whole = plan_factorization(B, ring, coords, owner)
    assert whole.border.size > 0
    keep = ~reserved | in_use
    used = plan_factorization(B, ring, coords, owner, keep)
    assert used.border.size == 0 and used.bandwidth < 30
    lu = used.factorization(B)
    assert lu.factorize(values.data)
    b = rng.standard_normal(B.shape[0])
    ref = spla.splu(values, permc_spec="COLAMD").solve(b)
    assert np.abs(lu.solve(b) - ref).max() <= SUPERLU_TOL * np.abs(ref).max()


def test_a_lone_body_on_the_ground_beside_a_beam():
    """A root without a parent set beside the rest (a pendulum on the ground and a cantilever):
    the body is a tree of one supernode, the beam the band."""
    A, n, border, owner = _saddle(np.random.default_rng(8), 1, [(0, -1)], beam_elements=6)
    plan = plan_factorization(A, border, n, owner)
    assert plan.tree is not None and np.diff(plan.tree.set_ptr).tolist() == [0]
    _check_tree_lu(A, plan.border, plan.tree, np.random.default_rng(9))

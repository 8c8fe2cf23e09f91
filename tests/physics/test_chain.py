"""A hanging chain of rigid bodies on spherical joints (issue 37): the whole saddle-point system
in one band, O(N) per step; the scaled iteration matrix solved as SuperLU does."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import flexmbs as fm
from flexmbs.assembly import Assembly
from flexmbs.linalg.ordering import plan_factorization
from flexmbs.simulation import Result

LINK, MASS = 0.1, 0.1
INERTIA = (1e-6, MASS * LINK**2 / 12, MASS * LINK**2 / 12)
SUPERLU_TOL = 1e-12


def hanging_chain(n: int) -> fm.Model:
    """``n`` links of 0.1 m, 0.1 kg, starting horizontal, the first hinged to the ground."""
    model = fm.Model(gravity=(0.0, 0.0, -9.81))
    prev = fm.GROUND
    for k in range(n):
        b = model.add_rigid_body(mass=MASS, inertia=INERTIA,
                                 pose=fm.Pose(((k + 0.5) * LINK, 0.0, 0.0), np.eye(3)))
        model.spherical(b, prev, point=(k * LINK, 0.0, 0.0))
        prev = b
    return model


def test_scaled_iteration_matrix_matches_superlu():
    """The generalized-alpha iteration matrix (Bottasso scaling: coordinate rows times
    beta h^2) of a chain in swing, factorised in one band with partial pivoting."""
    asm = Assembly(hanging_chain(30))
    n, m = asm.n_coords, asm.n_mult
    h = 1e-3
    am, af, gamma, beta = fm.GeneralizedAlpha(rho_inf=0.8).parameters()
    bp = (1 - am) / (h * h * beta * (1 - af))
    s = beta * h * h
    q, v = asm.initial_state()
    rng = np.random.default_rng(2)
    v = v + 0.1 * rng.standard_normal(v.size)
    lam = rng.standard_normal(m)
    asm.evaluate(q, v, np.zeros(n), lam, 0.0, np.zeros(n), np.zeros(m),
                 matrix=(s * bp, s * gamma / (h * beta), s))
    A = sp.csc_matrix((asm.matrix.data.copy(), asm.matrix.indices, asm.matrix.indptr),
                      shape=asm.matrix.shape)
    plan = plan_factorization(A, asm.border_indices(), n, asm.coordinate_owners())
    assert plan.border.size == 0
    lu = plan.factorization(A)
    assert lu.factorize(A.data)
    b = rng.standard_normal(n + m)
    ref = spla.splu(A, permc_spec="COLAMD").solve(b)
    assert np.abs(lu.solve(b) - ref).max() <= SUPERLU_TOL * np.abs(ref).max()


def test_640_body_chain_runs_without_rejected_steps():
    model = hanging_chain(640)
    res = fm.simulate(model, t_end=0.2, dt=1e-3, output_interval=0.2, record_energy=False,
                      integrator=fm.GeneralizedAlpha(rho_inf=0.8))
    assert res.stats.steps == 200 and res.stats.rejected_steps == 0
    # far from the pivot the chain (a string) falls freely: z = -g t^2 / 2
    z = res.body_position(model.bodies[-1])[-1][2]
    assert z == pytest.approx(-0.5 * 9.81 * 0.2**2, rel=1e-6)


def _hanging_tree(depth: int, *, lumped: bool = False) -> tuple[fm.Model, list]:
    """A binary tree of ``2^depth - 1`` links hanging from the ground, each link's two
    children on its end (coinciding: they move alike); ``lumped``: instead the chain of its
    ``depth`` levels, level k one link of 2^k times the mass and inertia."""
    model = fm.Model(gravity=(0.0, 0.0, -9.81))
    bodies: list = []
    levels = [[fm.GROUND]]
    for k in range(depth):
        scale = 2.0**k if lumped else 1.0
        count = 1 if lumped else 2**k
        level = []
        for j in range(count):
            parent = levels[-1][0 if lumped else j // 2]
            b = model.add_rigid_body(mass=scale * MASS, inertia=tuple(scale * i for i in INERTIA),
                                     pose=fm.Pose(((k + 0.5) * LINK, 0.0, 0.0), np.eye(3)))
            model.spherical(b, parent, point=(k * LINK, 0.0, 0.0))
            level.append(b)
            bodies.append(b)
        levels.append(level)
    return model, bodies


def _swing(model: fm.Model) -> Result:
    return fm.simulate(model, t_end=0.1, dt=1e-3, output_interval=0.01, record_energy=False,
                       integrator=fm.GeneralizedAlpha(rho_inf=0.8, adaptive=False))


def test_a_binary_tree_swings_as_its_lumped_chain(monkeypatch):
    """A binary tree of 31 links (Baraff's tree-order elimination, the whole system in tree
    order) swings as the chain of its 5 levels with 2^k times the mass and inertia (siblings
    coincide, so each level moves as one body): the leaves' path agrees with the chain's end
    to the Newton tolerance; and the same tree factorised in one band (the tree part
    switched off) gives the same path to round-off."""
    from flexmbs.linalg import ordering

    tree_model, tree_bodies = _hanging_tree(5)
    plan = Assembly(tree_model).factor_plan()
    assert plan.tree is not None and plan.tree.size == Assembly(tree_model).n_total
    tree = _swing(tree_model)
    chain_model, chain_bodies = _hanging_tree(5, lumped=True)
    chain = _swing(chain_model)
    leaf = tree.body_position(tree_bodies[-1])
    end = chain.body_position(chain_bodies[-1])
    assert abs(leaf[-1][2]) > 0.04                      # it has swung
    assert np.abs(leaf - end).max() <= 1e-7
    monkeypatch.setattr(ordering, "peel_tree", lambda *args: None)
    band_model, band_bodies = _hanging_tree(5)
    assert Assembly(band_model).factor_plan().tree is None
    band = _swing(band_model)
    assert np.abs(band.body_position(band_bodies[-1]) - leaf).max() <= 1e-10

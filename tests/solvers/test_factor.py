"""One factorisation for every solver (issue 37, item 2): the planned bordered LU on the
matrices each path sees, against SuperLU; the static rule (docs/design-notes.md, "One
factorisation for every solver")."""

from __future__ import annotations

import sys

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import flexmbs as fm
from flexmbs.assembly import Assembly
from flexmbs.errors import ConvergenceError
from flexmbs.io.scenario import load_scenario
from flexmbs.linalg import ordering
from flexmbs.linalg.bordered import BorderedBandedLU
from flexmbs.solvers.factor import PlannedLU, static_factorization
from flexmbs.solvers.newton import SuperLUFactor
from tests.conftest import straight_beam
from tests.physics.test_chain import hanging_chain

#: relative agreement with SuperLU (the matrices with mass here: cond <= 1e8, measured <= 1.4e-13)
SUPERLU_TOL = 1e-12
EXAMPLES = "examples"


def _model(name: str) -> fm.Model:
    if name == "chain":
        return hanging_chain(30)
    if name == "tip_body_beam":
        model = fm.Model(gravity=(0.0, 0.0, -9.81))
        beam = straight_beam(model, 12)
        model.clamp(beam.first_node)
        tip = model.add_rigid_body(mass=0.5, inertia=(1e-3, 1e-3, 1e-3),
                                   pose=fm.Pose((1.0, 0.0, 0.0), np.eye(3)))
        model.rigid(beam.last_node, tip)     # welded: statics has no free motion
        return model
    return load_scenario(f"{EXAMPLES}/{name}.toml").model


def _matrix(asm: Assembly, kind: str, rng: np.random.Generator) -> sp.csc_matrix:
    """The matrix of one path at a perturbed state: Newton's iteration matrix (Bottasso
    scaling), the velocity corrector's (no stiffness), the initial accelerations' (M and
    Phi_q), statics' (stiffness only)."""
    n, m = asm.n_coords, asm.n_mult
    h = 1e-3
    am, af, gamma, beta = fm.GeneralizedAlpha(rho_inf=0.8).parameters()
    bp, gp, s = (1 - am) / (h * h * beta * (1 - af)), gamma / (h * beta), beta * h * h
    coef = {"newton": (s * bp, s * gp, s), "corrector": (s * bp, s * gp, 0.0),
            "initial": (1.0, 0.0, 0.0), "static": (0.0, 0.0, 1.0)}[kind]
    q, v = asm.initial_state()
    v = v + 0.01 * rng.standard_normal(n)
    lam = 1e-2 * rng.standard_normal(m)
    static = kind == "static"
    asm.evaluate(q, v, None if static else np.zeros(n), lam, 0.0, np.zeros(n), np.zeros(m),
                 matrix=coef, with_damping=not static)
    return asm.matrix.copy()


def _massless(asm: Assembly) -> np.ndarray:
    """The coordinate owners of a stiffness-only plan (every coordinate without mass)."""
    owner = asm.coordinate_owners()
    owner[:asm.n_coords] = ordering.MASSLESS
    return owner


def _agrees(factor, A: sp.csc_matrix, rng: np.random.Generator,
            tol: float = SUPERLU_TOL) -> bool:
    """Same solution as SuperLU to ``tol`` relative."""
    factor.factorize(A)
    b = rng.standard_normal(A.shape[0])
    ref = spla.splu(A, permc_spec="COLAMD").solve(b)
    return bool(np.abs(factor.solve(b) - ref).max() <= tol * np.abs(ref).max())


def _conditioned(A: sp.csc_matrix) -> float:
    """SUPERLU_TOL, or the accuracy the condition allows both solvers (100 eps cond: the
    static matrix of a stiff beam has cond ~ 1e10)."""
    return max(SUPERLU_TOL, 100 * np.finfo(float).eps * float(np.linalg.cond(A.toarray())))


@pytest.mark.parametrize("kind", ["newton", "corrector", "initial"])
@pytest.mark.parametrize("name", ["chain", "tip_body_beam", "solar_array_wing_flat",
                                  "solar_array_wing", "curved_beam_sleeve"])
def test_planned_lu_matches_superlu_on_the_matrices_with_mass(name, kind):
    """The compiled and Python Newton loops, the corrector and the initial accelerations
    share one plan (a border in three of these models, none in the chain)."""
    rng = np.random.default_rng(3)
    asm = Assembly(_model(name))
    assert _agrees(PlannedLU(asm), _matrix(asm, kind, rng), rng)


@pytest.mark.parametrize("name", ["chain", "tip_body_beam"])
def test_static_matrix_planned_where_it_stays_one_band(name):
    """A chain and a clamped beam with a body: the stiffness-only plan is the dynamic one's
    band (no border), so statics uses the planned LU, and it solves as SuperLU does."""
    rng = np.random.default_rng(4)
    asm = Assembly(_model(name))
    f = static_factorization(asm)
    assert isinstance(f, PlannedLU)
    assert asm.factor_plan(mass=False).border.size == 0
    A = _matrix(asm, "static", rng)
    assert _agrees(f, A, rng, _conditioned(A))


def test_dynamic_plan_is_unsafe_for_the_static_matrix():
    """The flat Example 2: the dynamic plan's border (panel 2, hinge CD, tie EF) leaves panel
    1 and the bar held in the band only by their stiffness, none without mass: the static
    matrix (nonsingular: SuperLU solves it) has a singular band block. The stiffness-only
    plan closes the border over the whole matrix; being dense, statics takes KLU's sparse LU
    (which pivots across the whole matrix) where installed, else SuperLU; either solves it."""
    rng = np.random.default_rng(5)
    asm = Assembly(_model("solar_array_wing_flat"))
    A = _matrix(asm, "static", rng)
    dyn = asm.factor_plan()
    assert dyn.border.size > 0
    lu = BorderedBandedLU(A, dyn.border, dyn.order)
    assert not lu.factorize(A.data)
    assert lu.info - 1 < lu.n_band          # a zero pivot of the band block
    static = asm.factor_plan(mass=False)
    banded = ordering.plan_factorization(asm.matrix, asm.border_indices(), asm.n_coords,
                                         _massless(asm), sparse=False)
    assert banded.border.size == A.shape[0]
    factorization = static_factorization(asm)
    if sys.platform != "win32":   # KLU: a dependency but on Windows
        assert static.sparse and isinstance(factorization, PlannedLU)
        assert _agrees(factorization, A, rng, _conditioned(A))
    else:
        assert isinstance(factorization, SuperLUFactor)
    assert _agrees(SuperLUFactor(), A, rng, 0.0)


def test_singular_matrix_is_a_convergence_error():
    """A chain in statics without multipliers: nothing holds its links' rotations (a zero
    column of the stiffness-only matrix)."""
    asm = Assembly(hanging_chain(3))
    n, m = asm.n_coords, asm.n_mult
    asm.evaluate(asm.q_ref, np.zeros(n), None, np.zeros(m), 0.0, np.zeros(n), np.zeros(m),
                 matrix=(0.0, 0.0, 1.0), with_damping=False)
    f = static_factorization(asm)
    assert isinstance(f, PlannedLU)
    with pytest.raises(ConvergenceError, match="singular"):
        f.factorize(asm.matrix)


def test_python_and_compiled_paths_agree_on_the_chain_with_corrector():
    """Both Newton loops and both correctors on one plan: same trajectory (the Python path
    used SuperLU before)."""
    out = []
    for compiled in (True, False):
        model = hanging_chain(8)
        res = fm.simulate(model, t_end=0.02, dt=1e-3, output_interval=0.02, record_energy=False,
                          integrator=fm.GeneralizedAlpha(
                              rho_inf=0.9, adaptive=False, compiled=compiled,
                              constraint_level="position_velocity"))
        out.append(res.body_position(model.bodies[-1])[-1])
    assert np.abs(out[0] - out[1]).max() <= 1e-10

"""Assembly: the sparse iteration matrix equals finite differences of the assembled residual;
DOF map; redundancy detection."""

from __future__ import annotations

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.assembly import Assembly
from tests.conftest import quarter_arc_beam, straight_beam


def _mixed_model() -> fm.Model:
    """Curved beam clamped at one end, rigidly attached to a body at the other; the body hangs
    on a spherical joint from a second body on a revolute joint; loads on all kinds of objects."""
    model = fm.Model(gravity=(0.3, -1.0, -9.81))
    beam = quarter_arc_beam(model, 3, EA=1e3, EI=2.0, rhoA=0.7)
    model.clamp(beam.first_node)
    b1 = model.add_rigid_body(mass=1.5, inertia=(0.1, 0.2, 0.15), position=(1.0, 1.2, 0.0),
                              quaternion=(0.9, 0.1, 0.3, -0.2), angular_velocity=(0.3, -0.2, 0.5))
    model.rigid(beam.last_node, b1)
    b2 = model.add_rigid_body(mass=0.8, inertia=(0.05, 0.06, 0.07), position=(1.5, 1.0, 0.3),
                              quaternion=(1.0, 0.2, -0.1, 0.1))
    model.spherical(b2, b1, point=(1.2, 1.1, 0.1))
    b3 = model.add_rigid_body(mass=0.5, inertia=(0.01, 0.02, 0.02), position=(2.0, 0.0, 0.0))
    model.revolute(b3, fm.GROUND, point=(2.0, 0.0, -0.2), axis=(0.3, 0.2, 1.0))
    model.prismatic(b2, b3, point=(1.8, 0.5, 0.1), axis=(1.0, 0.5, 0.2))
    model.add_point_load(b2, (1.0, 2.0, -3.0), point=(0.1, 0.0, 0.05), moment=(0.1, 0.2, 0.3))
    model.add_point_load((beam, 0.7), (0.5, -0.2, 0.1), function=fm.Sine(frequency=0.3))
    model.add_distributed_load(beam, (0.0, 0.0, -0.4))
    return model


def test_iteration_matrix_matches_finite_differences(rng):
    """cM M + cC C + cK K vs central differences of r_q in qdd, v, q (and of Phi in q) at a
    random state with nonzero multipliers: the analytic tangent is exact, so the relative
    error is at the FD truncation/rounding level (~1e-6)."""
    model = _mixed_model()
    model.beams[0].damping = 0.01
    asm = Assembly(model, redundant_constraints="drop")
    n, m = asm.n_coords, asm.n_mult
    q = asm.q_ref + 1e-2 * rng.standard_normal(n)
    v = rng.standard_normal(n)
    qdd = rng.standard_normal(n)
    lam = rng.standard_normal(m)
    t = 0.37

    def res(q_, v_, a_):
        rq, rl = np.zeros(n), np.zeros(m)
        asm.evaluate(q_, v_, a_, lam, t, rq, rl)
        return np.concatenate([rq, rl])

    cM, cC, cK = 3.0, 0.7, 1.3
    rq, rl = np.zeros(n), np.zeros(m)
    asm.evaluate(q, v, qdd, lam, t, rq, rl, matrix=(cM, cC, cK))
    A = asm.matrix.toarray()
    fd = np.zeros((n + m, n))
    h = 1e-6
    for j in range(n):
        e = np.zeros(n)
        e[j] = h
        fd[:, j] = (cK * (res(q + e, v, qdd) - res(q - e, v, qdd))
                    + cC * (res(q, v + e, qdd) - res(q, v - e, qdd))
                    + cM * (res(q, v, qdd + e) - res(q, v, qdd - e))) / (2 * h)
    # constraint rows: d Phi/dq only (unscaled)
    fd[n:, :] /= cK
    top = A[:, :n]
    err = np.abs(top - fd).max() / np.abs(fd).max()
    assert err < 1e-6
    # multiplier columns are Phi_q^T
    assert np.allclose(A[:n, n:], A[n:, :n].T)


def test_dof_map_and_labels():
    model = fm.Model()
    beam = straight_beam(model, 3)
    body = model.add_rigid_body(mass=1.0, inertia=(1, 1, 1))
    asm = Assembly(model)
    assert asm.n_coords == 6 * 4 + 7
    assert list(asm.node_dofs(beam.node(2))) == list(range(12, 18))
    assert list(asm.body_dofs(body)) == list(range(24, 31))
    assert "node 2" in asm.describe_coordinate(14) and "z" in asm.describe_coordinate(14)
    assert asm.n_mult == 1  # Euler-parameter normalisation only


def test_redundant_constraints_are_reported_by_name_or_dropped():
    """A body fixed twice (fix_body + a spherical joint to ground) is over-constrained by 3
    equations; the error names the dependent equations; 'drop' keeps a solvable model."""
    model = fm.Model(gravity=(0, 0, -9.81))
    body = model.add_rigid_body(mass=1.0, inertia=(1, 1, 1), name="plate")
    model.fix_body(body, name="weld")
    model.spherical(body, fm.GROUND, name="ball")
    with pytest.raises(fm.RedundantConstraintError, match="redundant") as exc:
        Assembly(model)
    assert "ball" in str(exc.value) or "weld" in str(exc.value)
    with pytest.warns(UserWarning, match="dropping 3"):
        asm = Assembly(model, redundant_constraints="drop")
    assert len(asm.dropped_equations) == 3
    st = fm.solve_static(asm)
    assert np.allclose(st.q, asm.q_ref, atol=1e-12)


def test_pattern_built_once_and_refilled_in_place():
    model = fm.Model(gravity=(0, 0, -9.81))
    beam = straight_beam(model, 5)
    model.clamp(beam.first_node)
    asm = Assembly(model)
    data = asm.matrix.data
    n, m = asm.n_coords, asm.n_mult
    rq, rl = np.zeros(n), np.zeros(m)
    asm.evaluate(asm.q_ref, np.zeros(n), np.zeros(n), np.zeros(m), 0.0, rq, rl,
                 matrix=(1.0, 0.0, 1.0))
    assert asm.matrix.data is data
    # banded: 6 nodes -> 6 diagonal + 10 off-diagonal 6x6 node blocks; the clamp gives 5
    # axis-aligned rows (+ their transposes) and the multiplier block keeps its diagonal
    assert asm.matrix.nnz == 16 * 36 + 2 * 5 + 5

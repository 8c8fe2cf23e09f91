"""Joint constraints: exact Jacobians/Hessians, consistency, and the freedoms they leave."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from flexmbs.constraints.base import Attachment, Constraint
from flexmbs.constraints.joints import (
    BeamNodeRigid,
    BeamNodeSpherical,
    EulerParameterNormalization,
    GenericJoint,
    fixed,
    perpendicular_pair,
    prismatic,
    revolute,
    spherical,
)
from flexmbs.elements import rigid_body as rb
from flexmbs.errors import ModelError

# Tolerances (one place).
FD_H = 1e-6          # central differences: truncation O(h²) ~ 1e-12 on O(1) polynomials
JAC_REL = 1e-7       # jac vs FD of Φ (degree-≤4 polynomials; round-off ε/h ~ 1e-10)
HESS_REL = 1e-6      # hessian_lambda vs FD of Φ_qᵀλ
ZERO = 1e-12         # Φ at a constructed consistent configuration (O(1) coordinates)
RANK_TOL = 1e-9      # singular values below this (relative) count as zero
SEEDS = [0, 1, 2]

# Global coordinate layout of the test system: two rigid bodies and one beam node.
BODY_A = np.arange(0, 7)
BODY_B = np.arange(7, 14)
NODE = np.arange(14, 20)
N_GLOBAL = 20


def _rot(rng: np.random.Generator) -> np.ndarray:
    return rb.rotation_matrix(rb.normalize(rng.normal(size=4)))


def _rot_about(axis: np.ndarray, angle: float) -> np.ndarray:
    return rb.rotation_matrix(rb.quaternion_from_axis_angle(axis, angle))


def _random_q(rng: np.random.Generator) -> np.ndarray:
    q = rng.normal(size=N_GLOBAL)
    for dofs in (BODY_A, BODY_B):
        q[dofs[3:]] = rb.normalize(q[dofs[3:]])
    return q


def _A(q: np.ndarray, dofs: np.ndarray) -> np.ndarray:
    return rb.rotation_matrix(q[dofs[3:]])


# ------------------------------------------------------------------------ generic derivative checks
def _check_derivatives(c: Constraint, q_local: np.ndarray, lam: np.ndarray) -> None:
    n = q_local.size
    phi, jac = c.evaluate(q_local, 0.0)
    assert phi.shape == (c.n_equations,) and jac.shape == (c.n_equations, n)
    assert len(c.equation_labels) == c.n_equations
    fd = np.empty_like(jac)
    fdh = np.empty((n, n))
    for j in range(n):
        e = np.zeros(n)
        e[j] = FD_H
        pp, jp = c.evaluate(q_local + e, 0.0)
        pm, jm = c.evaluate(q_local - e, 0.0)
        fd[:, j] = (pp - pm) / (2 * FD_H)
        fdh[:, j] = (jp.T @ lam - jm.T @ lam) / (2 * FD_H)
    scale = max(np.abs(jac).max(), 1.0)
    assert np.abs(jac - fd).max() < JAC_REL * scale
    H = c.hessian_lambda(q_local, lam, 0.0)
    assert H.shape == (n, n)
    assert np.array_equal(H, H.T) or np.abs(H - H.T).max() < 1e-14 * max(np.abs(H).max(), 1.0)
    assert np.abs(H - fdh).max() < HESS_REL * max(np.abs(fdh).max(), 1.0)
    assert np.all(c.time_derivatives(q_local, 0.0)[0] == 0.0)


def _body(dofs: np.ndarray, rng: np.random.Generator) -> Attachment:
    return Attachment.rigid_body(dofs, rng.normal(size=3), _rot(rng))


def _ground(rng: np.random.Generator) -> Attachment:
    return Attachment.ground(rng.normal(size=3), _rot(rng))


# Factories: rng -> constraint (random, generally inconsistent attachments).
FACTORIES: dict[str, Callable[[np.random.Generator], Constraint]] = {
    "normalization": lambda r: EulerParameterNormalization("n", BODY_A),
    "spherical_bb": lambda r: spherical("s", _body(BODY_A, r), _body(BODY_B, r)),
    "spherical_bg": lambda r: spherical("s", _body(BODY_A, r), _ground(r)),
    "spherical_gb": lambda r: spherical("s", _ground(r), _body(BODY_B, r)),
    "revolute_bb": lambda r: revolute("r", _body(BODY_A, r), _body(BODY_B, r)),
    "revolute_bg": lambda r: revolute("r", _body(BODY_A, r), _ground(r)),
    "revolute_gb": lambda r: revolute("r", _ground(r), _body(BODY_B, r)),
    "prismatic_bb": lambda r: prismatic("p", _body(BODY_A, r), _body(BODY_B, r)),
    "prismatic_bg": lambda r: prismatic("p", _body(BODY_A, r), _ground(r)),
    "fixed_bb": lambda r: fixed("f", _body(BODY_A, r), _body(BODY_B, r)),
    "generic_partial_bg": lambda r: GenericJoint("g", _body(BODY_A, r), _ground(r),
                                                 translation=(1, 0, 1), rotation=(1, 0, 0)),
    "generic_partial_gb": lambda r: GenericJoint("g", _ground(r), _body(BODY_B, r),
                                                 translation=(0, 1, 0), rotation=(0, 0, 1)),
    "node_body_joint": lambda r: spherical("nb", Attachment.beam_node(NODE), _body(BODY_B, r)),
    "node_body_partial": lambda r: GenericJoint("nb", Attachment.beam_node(NODE),
                                                _body(BODY_B, r), translation=(0, 1, 1)),
    "node_ground_joint": lambda r: GenericJoint("ng", Attachment.beam_node(NODE), _ground(r),
                                                translation=(1, 1, 0)),
    "node_spherical_body": lambda r: BeamNodeSpherical("ns", Attachment.beam_node(NODE),
                                                       _body(BODY_A, r)),
    "node_spherical_ground": lambda r: BeamNodeSpherical("ns", Attachment.beam_node(NODE),
                                                         _ground(r)),
    "node_rigid_body": lambda r: BeamNodeRigid("nr", Attachment.beam_node(NODE),
                                               _body(BODY_A, r), r.normal(size=(3, 2))),
    "node_rigid_ground": lambda r: BeamNodeRigid("nr", Attachment.beam_node(NODE), _ground(r),
                                                 r.normal(size=(3, 2))),
}


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("kind", list(FACTORIES))
def test_jacobian_and_hessian_fd(kind, seed):
    """Exact derivatives, also at non-unit p (the formulas are polynomial identities)."""
    rng = np.random.default_rng(seed)
    c = FACTORIES[kind](rng)
    q = rng.normal(size=N_GLOBAL)  # p deliberately not normalised
    lam = rng.normal(size=c.n_equations)
    _check_derivatives(c, q[c.coordinates()], lam)
    _check_derivatives(c, _random_q(rng)[c.coordinates()], lam)


# ------------------------------------------------------------------------ consistent configurations
def _assembled(rng: np.random.Generator, make, b_ground: bool = False, theta: float = 0.0,
               slide: float = 0.0):
    """Two bodies meeting at a random global point x with a common joint frame J.

    b's frame is J rotated by θ about J_x and b's point sits at x + slide·J_x.
    Returns (constraint, q).
    """
    q = _random_q(rng)
    x = rng.normal(size=3)
    J = _rot(rng)
    Ja = J
    Jb = J @ _rot_about(np.array([1.0, 0.0, 0.0]), theta)
    xb = x + slide * J[:, 0]
    Aa = _A(q, BODY_A)
    a = Attachment.rigid_body(BODY_A, Aa.T @ (x - q[BODY_A[:3]]), Aa.T @ Ja)
    if b_ground:
        b = Attachment.ground(xb, Jb)
    else:
        Ab = _A(q, BODY_B)
        b = Attachment.rigid_body(BODY_B, Ab.T @ (xb - q[BODY_B[:3]]), Ab.T @ Jb)
    return make("j", a, b), q, J, x


def _perturbed_rotation(q: np.ndarray, dofs: np.ndarray, axis: np.ndarray,
                        angle: float) -> np.ndarray:
    """Rotate body `dofs` by `angle` about global `axis` through its centre of mass."""
    q = q.copy()
    A = _rot_about(axis, angle) @ _A(q, dofs)
    p = rb.quaternion_from_matrix(A)
    q[dofs[3:]] = p if p @ q[dofs[3:]] >= 0 else -p
    return q


def _phi(c: Constraint, q: np.ndarray) -> np.ndarray:
    return c.evaluate(q[c.coordinates()], 0.0)[0]


CASES = {  # name: (factory, theta, slide) – motions the joint allows
    "spherical": (spherical, 0.7, 0.0),
    "revolute": (revolute, 0.7, 0.0),
    "prismatic": (prismatic, 0.0, 0.4),
    "fixed": (fixed, 0.0, 0.0),
}


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("b_ground", [False, True])
@pytest.mark.parametrize("case", list(CASES))
def test_zero_when_assembled_nonzero_when_violated(case, b_ground, seed):
    make, theta, slide = CASES[case]
    rng = np.random.default_rng(seed)
    c, q, J, _ = _assembled(rng, make, b_ground, theta, slide)
    assert np.abs(_phi(c, q)).max() < ZERO
    # translate a perpendicular to the joint x axis: violates every joint's translation eqs
    q1 = q.copy()
    q1[BODY_A[:3]] += 1e-3 * J[:, 1]
    assert np.abs(_phi(c, q1)).max() > 1e-4
    # rotate a about the joint y axis: violates the rotation eqs (and moves the point)
    q2 = _perturbed_rotation(q, BODY_A, J[:, 1], 1e-2)
    phi2 = _phi(c, q2)
    assert np.abs(phi2).max() > 1e-4
    if case != "spherical":
        rot_rows = [i for i, lab in enumerate(c.equation_labels) if lab.startswith("rot")]
        assert np.abs(phi2[rot_rows]).max() > 1e-3


def _full_jacobian(constraints: list[Constraint], q: np.ndarray) -> np.ndarray:
    rows = []
    for c in constraints:
        _, jl = c.evaluate(q[c.coordinates()], 0.0)
        jg = np.zeros((c.n_equations, N_GLOBAL))
        jg[:, c.coordinates()] = jl
        rows.append(jg)
    return np.vstack(rows)[:, :14]


def _rigid_rotation(q: np.ndarray, dofs: np.ndarray, w: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Velocity δq of body `dofs` rotating with ω = w about an axis through point x."""
    dq = np.zeros(N_GLOBAL)
    dq[dofs[:3]] = np.cross(w, q[dofs[:3]] - x)
    dq[dofs[3:]] = rb.pdot_from_omega_global(q[dofs[3:]], w)
    return dq[:14]


@pytest.mark.parametrize("seed", SEEDS)
def test_revolute_leaves_one_relative_rotation(seed):
    """rank [Φ_q; Φ^p_q] = 5 + 2 on 14 coordinates; null space holds the rotation about J_x."""
    rng = np.random.default_rng(seed)
    c, q, J, x = _assembled(rng, revolute, theta=0.7)
    cons = [c, EulerParameterNormalization("na", BODY_A), EulerParameterNormalization("nb", BODY_B)]
    D = _full_jacobian(cons, q)
    sv = np.linalg.svd(D, compute_uv=False)
    assert int(np.sum(sv > RANK_TOL * sv[0])) == 7
    about_axis = _rigid_rotation(q, BODY_A, J[:, 0], x)
    assert np.abs(D @ about_axis).max() < 1e-12
    for k in (1, 2):  # rotations about the locked axes are not free
        assert np.abs(D @ _rigid_rotation(q, BODY_A, J[:, k], x)).max() > 1e-2
    # the joint moves with the pair: rotating both bodies together about any axis is free
    w = rng.normal(size=3)
    both = _rigid_rotation(q, BODY_A, w, x) + _rigid_rotation(q, BODY_B, w, x)
    assert np.abs(D @ both).max() < 1e-12


@pytest.mark.parametrize("seed", SEEDS)
def test_prismatic_and_spherical_freedoms(seed):
    rng = np.random.default_rng(seed)
    c, q, J, x = _assembled(rng, prismatic, slide=0.3)
    norm = [EulerParameterNormalization("na", BODY_A), EulerParameterNormalization("nb", BODY_B)]
    D = _full_jacobian([c, *norm], q)
    sv = np.linalg.svd(D, compute_uv=False)
    assert int(np.sum(sv > RANK_TOL * sv[0])) == 7
    slide = np.zeros(14)
    slide[BODY_A[:3]] = J[:, 0]
    assert np.abs(D @ slide).max() < 1e-12
    c, q, J, x = _assembled(rng, spherical, theta=0.3)
    D = _full_jacobian([c, *norm], q)
    sv = np.linalg.svd(D, compute_uv=False)
    assert int(np.sum(sv > RANK_TOL * sv[0])) == 5
    w = rng.normal(size=3)
    assert np.abs(D @ _rigid_rotation(q, BODY_A, w, x)).max() < 1e-12


def test_spherical_to_ground_uses_global_components():
    rng = np.random.default_rng(5)
    c, q, _, _ = _assembled(rng, spherical, b_ground=True)
    assert c.global_translation
    q1 = q.copy()
    q1[BODY_A[:3]] += np.array([1e-3, 2e-3, -3e-3])
    assert np.allclose(_phi(c, q1), [1e-3, 2e-3, -3e-3], atol=1e-12)


def test_spherical_between_bodies_uses_global_components():
    """All translations locked between two bodies: Φ = x_a − x_b in global components, so the
    Hessian of Φ_qᵀλ has no block between a's and b's coordinates (the chain's narrow band,
    issue 37); a revolute's translations likewise."""
    rng = np.random.default_rng(6)
    for make in (spherical, revolute):
        c, q, _, _ = _assembled(rng, make, theta=0.3 if make is spherical else 0.0)
        assert c.global_translation
        q1 = q.copy()
        q1[BODY_A[:3]] += np.array([1e-3, 2e-3, -3e-3])
        assert np.allclose(_phi(c, q1)[:3], [1e-3, 2e-3, -3e-3], atol=1e-12)
    c, q, _, _ = _assembled(rng, spherical)
    ql = q[c.coordinates()]
    H = c.hessian_lambda(ql, rng.normal(size=3), 0.0)
    na = 7
    assert np.abs(H[:na, na:]).max() == 0.0 and np.abs(H[na:, :na]).max() == 0.0
    assert np.abs(H).max() > 0.0                     # each body's own rotation block remains
    partial = GenericJoint("g", c.a, c.b, translation=(1, 1, 0))
    assert not partial.global_translation


# ------------------------------------------------------------------------ beam node connections
@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("to_ground", [False, True])
def test_beam_node_rigid_from_configuration(seed, to_ground):
    rng = np.random.default_rng(seed)
    q = _random_q(rng)
    body = (Attachment.ground() if to_ground
            else Attachment.rigid_body(BODY_A, rng.normal(size=3)))
    c = BeamNodeRigid.from_configuration("nr", Attachment.beam_node(NODE), body, q[NODE],
                                         None if to_ground else q[BODY_A])
    assert c.coordinates().size == (6 if to_ground else 13)
    assert np.abs(_phi(c, q)).max() < ZERO
    t = q[NODE[3:]] / np.linalg.norm(q[NODE[3:]])
    q1 = q.copy()
    q1[NODE[3:]] *= 1.3  # axial stretch of the slope is free
    assert np.abs(_phi(c, q1)).max() < ZERO
    q2 = q.copy()
    q2[NODE[3:]] += 1e-3 * perpendicular_pair(t)[:, 0]  # bending the slope is not
    assert np.abs(_phi(c, q2)[3:]).max() > 1e-4
    q3 = q.copy()
    q3[NODE[:3]] += 1e-3 * t
    assert np.allclose(_phi(c, q3)[:3], 1e-3 * t, atol=1e-12)
    if not to_ground:  # rigid motion of node + body together keeps Φ = 0
        w = rng.normal(size=3)
        dq = np.zeros(N_GLOBAL)
        dq[:14] = _rigid_rotation(q, BODY_A, w, q[NODE[:3]])
        dq[NODE[3:]] = np.cross(w, q[NODE[3:]])
        _, jl = c.evaluate(q[c.coordinates()], 0.0)
        assert np.abs(jl @ dq[c.coordinates()]).max() < 1e-12


def test_beam_node_spherical_consistent():
    rng = np.random.default_rng(3)
    q = _random_q(rng)
    A = _A(q, BODY_A)
    s = A.T @ (q[NODE[:3]] - q[BODY_A[:3]])
    c = BeamNodeSpherical("ns", Attachment.beam_node(NODE), Attachment.rigid_body(BODY_A, s))
    assert np.abs(_phi(c, q)).max() < ZERO
    assert c.coordinates().tolist() == NODE[:3].tolist() + BODY_A.tolist()


# ------------------------------------------------------------------------ validation
def test_invalid_definitions_raise():
    g = Attachment.ground()
    node = Attachment.beam_node(NODE)
    body = Attachment.rigid_body(BODY_A, (0, 0, 0))
    with pytest.raises(ModelError, match="ground"):
        spherical("x", g, g)
    with pytest.raises(ModelError, match="rotation frame"):
        revolute("x", node, body)
    with pytest.raises(ModelError, match="attachment a"):
        spherical("x", body, node)
    with pytest.raises(ModelError, match="rotation matrix"):
        Attachment.rigid_body(BODY_A, (0, 0, 0), frame=2.0 * np.eye(3))
    with pytest.raises(ModelError, match="7 dofs"):
        Attachment.rigid_body(np.arange(6), (0, 0, 0))
    with pytest.raises(ModelError, match="at least one"):
        GenericJoint("x", body, g, translation=(0, 0, 0))
    assert revolute("hinge", body, g).equation_name(3) == "hinge.rot_y"

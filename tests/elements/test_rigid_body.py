"""Rigid body with Euler parameters (docs/theory.md §I.5): identities, inertia, loads."""

from __future__ import annotations

import numpy as np
import pytest

from flexmbs.elements import rigid_body as rb

# Tolerances (one place).
EXACT = 1e-12      # algebraic identities evaluated in float64 on O(1) numbers
FD_H = 1e-6        # central-difference step; truncation O(h²)·|f'''| ~ 1e-12 on O(1) data
FD_REL = 1e-6      # FD of derivatives: round-off ε/h ~ 1e-10, kept generous vs cancellation
NB = 4             # bodies per batch
SEEDS = [0, 1, 2]


def _unit_p(rng: np.random.Generator, n: int) -> np.ndarray:
    p = rng.normal(size=(n, 4))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    p *= np.sign(p[:, :1])
    return p


def _inertia(rng: np.random.Generator, n: int) -> np.ndarray:
    """Random SPD centroidal inertia tensors (not diagonal: tests the full J′)."""
    R = rb.rotation_matrix(_unit_p(rng, n))
    d = rng.uniform(0.5, 2.0, size=(n, 3))
    return np.einsum("bij,bj,bkj->bik", R, d, R)


def _state(seed: int):
    """Random consistent state: unit p, pᵀṗ = 0, pᵀp̈ = −ṗᵀṗ."""
    rng = np.random.default_rng(seed)
    mass = rng.uniform(0.5, 3.0, NB)
    J = _inertia(rng, NB)
    p = _unit_p(rng, NB)
    pd = rb.pdot_from_omega_global(p, rng.normal(size=(NB, 3)))
    pdd = rb.pdot_from_omega_global(p, rng.normal(size=(NB, 3)))
    pdd -= np.einsum("bi,bi->b", pd, pd)[:, None] * p
    qdd = np.concatenate([rng.normal(size=(NB, 3)), pdd], axis=1)
    return rng, mass, J, p, pd, qdd


def _rel_err(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1.0))


# ---------------------------------------------------------------------------------- kinematics
@pytest.mark.parametrize("seed", SEEDS)
def test_rotation_matrix_is_a_rotation(seed):
    p = _unit_p(np.random.default_rng(seed), NB)
    A = rb.rotation_matrix(p)
    assert np.allclose(np.einsum("bki,bkj->bij", A, A), np.eye(3), atol=EXACT)
    assert np.allclose(np.linalg.det(A), 1.0, atol=EXACT)


@pytest.mark.parametrize("seed", SEEDS)
def test_point_tensor_is_a_polynomial_identity(seed):
    """(A(p)s)_k = pᵀT_k(s)p for any p, including non-unit (A is homogeneous quadratic)."""
    rng = np.random.default_rng(seed)
    p = 2.0 * rng.normal(size=(NB, 4))
    s = rng.normal(size=(NB, 3))
    T = rb.point_tensor(s)
    assert np.allclose(T, np.swapaxes(T, -1, -2), atol=0.0)
    As = np.einsum("bij,bj->bi", rb.rotation_matrix(p), s)
    assert np.allclose(np.einsum("bi,bkij,bj->bk", p, T, p), As, atol=EXACT * 10)
    w = rng.normal(size=(NB, 3))
    C = rb.point_tensor_contract(s, w)
    assert np.allclose(np.einsum("bi,bij,bj->b", p, C, p), np.einsum("bi,bi->b", w, As),
                       atol=EXACT * 10)


@pytest.mark.parametrize("seed", SEEDS)
def test_e_g_identities(seed):
    rng = np.random.default_rng(seed)
    p = _unit_p(rng, NB)
    E, G = rb.e_matrix(p), rb.g_matrix(p)
    assert np.allclose(np.einsum("bij,bj->bi", E, p), 0.0, atol=EXACT)
    assert np.allclose(np.einsum("bij,bj->bi", G, p), 0.0, atol=EXACT)
    assert np.allclose(E @ np.swapaxes(G, 1, 2), rb.rotation_matrix(p), atol=EXACT)
    assert np.allclose(E @ np.swapaxes(E, 1, 2), np.eye(3), atol=EXACT)
    assert np.allclose(np.swapaxes(G, 1, 2) @ G,
                       np.eye(4) - np.einsum("bi,bj->bij", p, p), atol=EXACT)
    # A = E Gᵀ is a polynomial identity (also for non-unit p)
    pn = 3.0 * rng.normal(size=(NB, 4))
    assert np.allclose(rb.e_matrix(pn) @ np.swapaxes(rb.g_matrix(pn), 1, 2),
                       rb.rotation_matrix(pn), atol=1e-11)
    # Ĝ, Ê: Gᵀy = Ĝ(y)p, Eᵀy = Ê(y)p
    y = rng.normal(size=(NB, 3))
    assert np.allclose(np.einsum("bji,bj->bi", G, y), np.einsum("bij,bj->bi", rb.g_hat(y), p))
    assert np.allclose(np.einsum("bji,bj->bi", E, y), np.einsum("bij,bj->bi", rb.e_hat(y), p))
    # Haug's B = −2A s̃ G + 2(As)pᵀ
    s = rng.normal(size=(NB, 3))
    A = rb.rotation_matrix(p)
    B = -2.0 * A @ rb.skew(s) @ G + 2.0 * np.einsum("bi,bj->bij", np.einsum("bij,bj->bi", A, s), p)
    assert np.allclose(rb.point_jacobian(p, s), B, atol=EXACT)


@pytest.mark.parametrize("seed", SEEDS)
def test_quaternion_from_matrix_round_trip(seed):
    rng = np.random.default_rng(seed)
    # one near-identity and rotations by ~π about each axis exercise all Shepperd branches
    axes = np.vstack([rng.normal(size=(NB, 3)), np.eye(3) + 0.05 * rng.normal(size=(3, 3))])
    angles = np.concatenate([rng.uniform(0.0, np.pi, NB), np.full(3, 3.1)])
    p = rb.quaternion_from_axis_angle(axes, angles)
    assert np.allclose(rb.quaternion_from_matrix(rb.rotation_matrix(p)), p, atol=EXACT)


@pytest.mark.parametrize("seed", SEEDS)
def test_angular_velocity(seed):
    """ω̃ = ȦAᵀ (FD of A along ṗ), ω′ = Aᵀω, and ṗ = ½Eᵀω = ½Gᵀω′ inverts them."""
    rng = np.random.default_rng(seed)
    p = _unit_p(rng, NB)
    w = rng.normal(size=(NB, 3))
    pd = rb.pdot_from_omega_global(p, w)
    assert np.allclose(np.einsum("bi,bi->b", p, pd), 0.0, atol=EXACT)
    Ad = (rb.rotation_matrix(p + FD_H * pd) - rb.rotation_matrix(p - FD_H * pd)) / (2 * FD_H)
    W = Ad @ np.swapaxes(rb.rotation_matrix(p), 1, 2)
    assert np.allclose(W, rb.skew(w), atol=1e-8)
    assert np.allclose(rb.angular_velocity_global(p, pd), w, atol=EXACT)
    wb = rb.angular_velocity_body(p, pd)
    assert np.allclose(wb, np.einsum("bji,bj->bi", rb.rotation_matrix(p), w), atol=EXACT)
    assert np.allclose(rb.pdot_from_omega_body(p, wb), pd, atol=EXACT)


# ---------------------------------------------------------------------------------- inertia
@pytest.mark.parametrize("seed", SEEDS)
def test_mass_matrix_matches_kinetic_energy(seed):
    rng, mass, J, p, pd, _ = _state(seed)
    v = np.concatenate([rng.normal(size=(NB, 3)), pd], axis=1)
    M = rb.mass_matrix(mass, J, p)
    T = rb.kinetic_energy(mass, J, p, v)
    assert np.allclose(0.5 * np.einsum("bi,bij,bj->b", v, M, v), T, rtol=EXACT)
    # and T = ½m|ṙ|² + ½ω′ᵀJ′ω′
    wb = rb.angular_velocity_body(p, pd)
    T2 = 0.5 * mass * np.sum(v[:, :3] ** 2, 1) + 0.5 * np.einsum("bi,bij,bj->b", wb, J, wb)
    assert np.allclose(T, T2, rtol=EXACT)


def _residual(mass, J, p, pd, qdd):
    r = np.empty((p.shape[0], 7))
    dq = np.empty((p.shape[0], 7, 7))
    dv = np.empty((p.shape[0], 7, 7))
    rb.inertial_residual(mass, J, p, pd, qdd, r, dq, dv)
    return r, dq, dv


@pytest.mark.parametrize("seed", SEEDS)
def test_inertial_residual_is_euler_equations(seed):
    """Independent reference: G·r_p = 2(J′ω̇′ + ω′×J′ω′) (Newton–Euler), r_r = m r̈."""
    _, mass, J, p, pd, qdd = _state(seed)
    r, _, _ = _residual(mass, J, p, pd, qdd)
    wb = rb.angular_velocity_body(p, pd)
    wbd = rb.angular_velocity_body(p, qdd[:, 3:])          # ω̇′ = 2Gp̈ since Ġṗ = 0
    Jw = np.einsum("bij,bj->bi", J, wb)
    ref = 2.0 * (np.einsum("bij,bj->bi", J, wbd) + np.cross(wb, Jw))
    assert np.allclose(np.einsum("bij,bj->bi", rb.g_matrix(p), r[:, 3:]), ref, atol=1e-11)
    assert np.allclose(r[:, :3], mass[:, None] * qdd[:, :3], atol=EXACT)
    # and the residual equals M q̈ − Q_v
    M = rb.mass_matrix(mass, J, p)
    Gd = rb.g_matrix(pd)
    Qv = 8.0 * np.einsum("bji,bjk,bkl,bl->bi", Gd, J, Gd, p)
    assert np.allclose(r[:, 3:], np.einsum("bij,bj->bi", M, qdd)[:, 3:] - Qv, atol=1e-11)


@pytest.mark.parametrize("seed", SEEDS)
def test_inertial_residual_derivatives_fd(seed):
    """∂r/∂q and ∂r/∂q̇ vs central FD over all 7 coordinates (also off the unit sphere)."""
    _, mass, J, p, pd, qdd = _state(seed)
    _, dq, dv = _residual(mass, J, p, pd, qdd)
    fd_q = np.zeros_like(dq)
    fd_v = np.zeros_like(dv)
    for j in range(3, 7):  # r does not enter: the r columns must be exactly zero
        e = np.zeros(4)
        e[j - 3] = FD_H
        fd_q[:, :, j] = (_residual(mass, J, p + e, pd, qdd)[0]
                         - _residual(mass, J, p - e, pd, qdd)[0]) / (2 * FD_H)
        fd_v[:, :, j] = (_residual(mass, J, p, pd + e, qdd)[0]
                         - _residual(mass, J, p, pd - e, qdd)[0]) / (2 * FD_H)
    assert _rel_err(dq, fd_q) < FD_REL
    assert _rel_err(dv, fd_v) < FD_REL
    assert np.all(dq[:, :, :3] == 0.0) and np.all(dv[:, :, :3] == 0.0)
    # ∂r/∂q̈ = M
    M = rb.mass_matrix(mass, J, p)
    fd_a = np.zeros_like(M)
    for j in range(7):
        e = np.zeros(7)
        e[j] = FD_H
        fd_a[:, :, j] = (_residual(mass, J, p, pd, qdd + e)[0]
                         - _residual(mass, J, p, pd, qdd - e)[0]) / (2 * FD_H)
    assert _rel_err(M, fd_a) < FD_REL


# ---------------------------------------------------------------------------------- loads
def _tangent(rng: np.random.Generator, p: np.ndarray) -> np.ndarray:
    d = rng.normal(size=p.shape)
    return d - np.einsum("bi,bi->b", d, p)[:, None] * p


@pytest.mark.parametrize("seed", SEEDS)
def test_applied_force_virtual_work(seed):
    """Q·δq = F·δx_P, x_P = r + A(p/|p|)s′ (FD along δp tangent to |p| = 1); dQ/dq vs FD."""
    rng = np.random.default_rng(seed)
    p = _unit_p(rng, NB)
    s = rng.normal(size=(NB, 3))
    F = rng.normal(size=(NB, 3))
    Q, dQ = rb.applied_force(p, s, F)
    dr = rng.normal(size=(NB, 3))
    dp = _tangent(rng, p)

    def x_P(h):
        pp = rb.normalize(p + h * dp)
        return h * dr + np.einsum("bij,bj->bi", rb.rotation_matrix(pp), s)

    dx = (x_P(FD_H) - x_P(-FD_H)) / (2 * FD_H)
    vw_ref = np.einsum("bi,bi->b", F, dx)
    vw = np.einsum("bi,bi->b", Q, np.concatenate([dr, dp], axis=1))
    assert np.allclose(vw, vw_ref, rtol=FD_REL, atol=FD_REL)
    # E·Q_p = 2 (A s′) × F: the moment of F about the centre of mass
    m = np.cross(np.einsum("bij,bj->bi", rb.rotation_matrix(p), s), F)
    assert np.allclose(np.einsum("bij,bj->bi", rb.e_matrix(p), Q[:, 3:]), 2.0 * m, atol=1e-12)
    fd = np.zeros_like(dQ)
    for j in range(3, 7):
        e = np.zeros(4)
        e[j - 3] = FD_H
        fd[:, :, j] = (rb.applied_force(p + e, s, F)[0]
                       - rb.applied_force(p - e, s, F)[0]) / (2 * FD_H)
    assert _rel_err(dQ, fd) < FD_REL


@pytest.mark.parametrize("seed", SEEDS)
def test_applied_torque_virtual_work(seed):
    """Global torque n: Q_p·ṗ = n·ω for a rotation p(h) = quat(Rot(u, h)A(p)); dQ/dq vs FD."""
    rng = np.random.default_rng(seed)
    p = _unit_p(rng, NB)
    p[:, 0] += 1.0  # keep e0 away from 0 so quaternion_from_matrix stays on one branch
    p = rb.normalize(p)
    n = rng.normal(size=(NB, 3))
    u = rng.normal(size=(NB, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    Q, dQ = rb.applied_torque_global(p, n)

    def p_of(h):
        R = rb.rotation_matrix(rb.quaternion_from_axis_angle(u, np.full(NB, h)))
        return rb.quaternion_from_matrix(R @ rb.rotation_matrix(p))

    pd = (p_of(FD_H) - p_of(-FD_H)) / (2 * FD_H)
    assert np.allclose(np.einsum("bi,bi->b", Q[:, 3:], pd), np.einsum("bi,bi->b", n, u),
                       rtol=FD_REL, atol=FD_REL)
    assert np.all(Q[:, :3] == 0.0)
    fd = np.zeros_like(dQ)
    for j in range(3, 7):
        e = np.zeros(4)
        e[j - 3] = FD_H
        fd[:, :, j] = (rb.applied_torque_global(p + e, n)[0]
                       - rb.applied_torque_global(p - e, n)[0]) / (2 * FD_H)
    assert _rel_err(dQ, fd) < FD_REL
    # body torque n′ = Aᵀn gives the same generalized force on |p| = 1
    nb_ = np.einsum("bji,bj->bi", rb.rotation_matrix(p), n)
    Qb, _ = rb.applied_torque_body(p, nb_)
    assert np.allclose(Qb, Q, atol=1e-12)


@pytest.mark.parametrize("seed", SEEDS)
def test_force_couple_equals_torque(seed):
    """F at s1 and −F at s2 act like the torque A(s1 − s2) × F (up to a multiple of p)."""
    rng = np.random.default_rng(seed)
    p = _unit_p(rng, NB)
    s1, s2, F = (rng.normal(size=(NB, 3)) for _ in range(3))
    Qc = rb.applied_force(p, s1, F)[0] + rb.applied_force(p, s2, -F)[0]
    n = np.cross(np.einsum("bij,bj->bi", rb.rotation_matrix(p), s1 - s2), F)
    Qt = rb.applied_torque_global(p, n)[0]
    assert np.allclose(Qc[:, :3], 0.0, atol=EXACT)
    dQ = Qc[:, 3:] - Qt[:, 3:]
    # remove the component along p; the rest must vanish
    dQ -= np.einsum("bi,bi->b", dQ, p)[:, None] * p
    assert np.allclose(dQ, 0.0, atol=1e-11)

"""One contact point: gap, generalized forces and tangents vs finite differences
(docs/theory.md §II.4–§II.5)."""

from __future__ import annotations

import numpy as np
import pytest

from flexmbs.contact.geometry import beam_point
from flexmbs.contact.laws import ForceLaw, LinearPenalty, RegularizedCoulomb
from flexmbs.contact.pair import N_LOCAL, contact_geometry, contact_point
from flexmbs.elements.rigid_body import (
    point_jacobian,
    quaternion_from_axis_angle,
    rotation_matrix,
)

L_E = 0.1
R_B = 2e-3
#: central-difference step on the 19 local coordinates (metres / unit Euler parameters)
H_FD = 1e-7
#: FD vs analytic: exact derivatives agree to truncation/round-off ~1e-8 relative
FD_RTOL = 1e-7
#: Gauss–Newton neglects −f_N ∂²g_N, O(δ/ℓ) relative; δ/r_b = 5e-3 here -> < 2 %
GN_RTOL = 2e-2


def _setup(delta: float = 1e-5, seed: int = 0) -> dict:
    rng = np.random.default_rng(seed)
    q_elem = np.array([0, 0, 0, 1, 0.05, 0, L_E, 0.002, 0.001, 1, -0.02, 0.03], dtype=float)
    P0, rx, _ = beam_point(q_elem[None], np.array([L_E]), 0, 0.5)
    d = np.cross(rx, [0.3, 0.4, 0.7])
    d /= np.linalg.norm(d)
    Qg = P0 + d * (R_B - delta)
    p = quaternion_from_axis_angle(np.array([0.3, 1.0, 0.2]), 0.4)
    rH = np.array([0.05, 0.01, 0.0])
    uQ = rotation_matrix(p).T @ (Qg - rH)
    return dict(q_body=np.concatenate([rH, p]), v_body=rng.normal(size=7) * 0.1, u_Q=uQ,
                q_elem=q_elem, v_elem=rng.normal(size=12) * 0.1, length=L_E, xi=0.4, r_b=R_B)


def _Q(s: dict, q_c: np.ndarray, v_c: np.ndarray, law: ForceLaw, **kw: object) -> np.ndarray:
    r = contact_point(q_c[:7], v_c[:7], s["u_Q"], q_c[7:], v_c[7:], s["length"], s["xi"], s["r_b"],
                      law, **kw)
    return np.concatenate([r.Q_body, r.Q_elem])


def _fd(fun, x: np.ndarray) -> np.ndarray:
    cols = []
    for j in range(x.size):
        e = np.zeros(x.size)
        e[j] = H_FD
        cols.append((fun(x + e) - fun(x - e)) / (2 * H_FD))
    return np.column_stack(cols)


def _rel(a: np.ndarray, b: np.ndarray) -> float:
    den = np.abs(b).max()
    return float(np.abs(a - b).max() / den) if den > 0 else float(np.abs(a).max())


def test_hole_point_is_the_body_point(rng: np.random.Generator) -> None:
    s = _setup()
    xi, g, gd, n, P, Q, B, W, H = contact_geometry(s["q_body"], s["v_body"], s["u_Q"], s["q_elem"],
                                                   s["v_elem"], L_E, 0.4, R_B, False)
    A = rotation_matrix(s["q_body"][3:])
    np.testing.assert_allclose(Q, s["q_body"][:3] + A @ s["u_Q"], atol=1e-15)
    np.testing.assert_allclose(W[:, 3:7], point_jacobian(s["q_body"][3:], s["u_Q"]), atol=1e-15)


def test_gap_projection_and_B() -> None:
    s = _setup()
    qc = np.concatenate([s["q_body"], s["q_elem"]])
    vc = np.concatenate([s["v_body"], s["v_elem"]])

    def geo(q: np.ndarray, v: np.ndarray = vc) -> tuple:
        return contact_geometry(q[:7], v[:7], s["u_Q"], q[7:], v[7:], L_E, 0.4, R_B, True)

    xi, g, gd, n, P, Q, B, W, H = geo(qc)
    m = qc.size        # the gap does not depend on the twists: their entries are zero
    assert not B[m:].any() and not W[:, m:].any() and not H[m:].any() and not H[:, m:].any()
    B, H = B[:m], H[:m, :m]
    assert xi == pytest.approx(0.5, abs=1e-12) and g == pytest.approx(-1e-5, abs=1e-15)
    np.testing.assert_allclose(n, (Q - P) / np.linalg.norm(Q - P))
    Bfd = _fd(lambda q: np.array([geo(q)[1]]), qc)[0]
    assert _rel(B, Bfd) < FD_RTOL
    Hfd = _fd(lambda q: geo(q)[6][:m], qc)
    assert _rel(H, Hfd) < 1e-6
    np.testing.assert_allclose(H, H.T, atol=1e-12 * np.abs(H).max())
    assert gd == pytest.approx(B @ vc, rel=1e-14)  # ξ̇_P drops out (n ⟂ r_ξ)
    # the hole point Q is frozen in the body: a rigid motion of the body alone moves Q rigidly
    assert np.linalg.norm(Q - P) == pytest.approx(R_B - 1e-5, rel=1e-12)


def test_forces_are_minus_gradient_of_penalty_energy() -> None:
    """Linear law, no damping: E = ½k⟨−g⟩², Q_ext = −∂E/∂q_c (virtual work δW = f_N δg_N)."""
    s = _setup()
    k = 1e6
    law = LinearPenalty(stiffness=k)
    qc = np.concatenate([s["q_body"], s["q_elem"]])
    vc = np.concatenate([s["v_body"], s["v_elem"]])

    def energy(q: np.ndarray) -> np.ndarray:
        g = contact_geometry(q[:7], vc[:7], s["u_Q"], q[7:], vc[7:], L_E, 0.4, R_B, False)[1]
        return np.array([0.5 * k * max(-g, 0.0) ** 2])

    Qfd = -_fd(energy, qc)[0]
    res = contact_point(s["q_body"], s["v_body"], s["u_Q"], s["q_elem"], s["v_elem"], L_E, 0.4, R_B, law)
    assert res.f_n == pytest.approx(k * 1e-5, rel=1e-9)
    np.testing.assert_allclose(np.concatenate([res.Q_body, res.Q_elem]), Qfd, rtol=1e-6, atol=1e-9)
    # action = reaction: force on the hole f n at Q, opposite on the beam at P (translation part)
    np.testing.assert_allclose(res.Q_body[:3], res.f_n * res.normal)
    S1, S3 = res.Q_elem[0:3], res.Q_elem[6:9]
    np.testing.assert_allclose(S1 + S3, -res.force_on_hole, rtol=1e-12)  # S1 + S3 = 1


def test_open_gap_gives_nothing() -> None:
    s = _setup(delta=-1e-4)
    res = contact_point(s["q_body"], s["v_body"], s["u_Q"], s["q_elem"], s["v_elem"], L_E, 0.4, R_B,
                        LinearPenalty(stiffness=1e6, damping=10.0), consistent=True)
    assert res.gap == pytest.approx(1e-4) and res.f_n == 0.0
    assert not res.Q_body.any() and not res.Q_elem.any() and not res.K.any() and not res.C.any()


@pytest.mark.parametrize("friction", [None, RegularizedCoulomb(mu=0.3, eps_v=1e-3)],
                         ids=["frictionless", "friction"])
@pytest.mark.parametrize("damping", [0.0, 50.0])
def test_tangents_vs_fd(friction: RegularizedCoulomb | None, damping: float) -> None:
    s = _setup()
    law = LinearPenalty(stiffness=1e6, damping=damping)
    qc = np.concatenate([s["q_body"], s["q_elem"]])
    vc = np.concatenate([s["v_body"], s["v_elem"]])
    kw = dict(friction=friction, approach_velocity=0.1)
    Kfd = -_fd(lambda q: _Q(s, q, vc, law, **kw), qc)
    Cfd = -_fd(lambda v: _Q(s, qc, v, law, **kw), vc)
    for consistent in (False, True):
        r = contact_point(s["q_body"], s["v_body"], s["u_Q"], s["q_elem"], s["v_elem"], L_E, 0.4, R_B,
                          law, consistent=consistent, **kw)
        n = qc.size        # a cable: the twists' rows and columns are zero
        assert not r.K[n:].any() and not r.K[:, n:].any() and not r.C[n:].any()
        assert _rel(r.C[:n, :n], Cfd) < FD_RTOL  # C is exact in both modes
        assert _rel(r.K[:n, :n], Kfd) < (FD_RTOL * 10 if consistent else GN_RTOL)
    if friction is None and damping == 0.0:
        B = contact_geometry(s["q_body"], s["v_body"], s["u_Q"], s["q_elem"], s["v_elem"], L_E, 0.4, R_B,
                             False)[6]
        np.testing.assert_allclose(r.C, 0.0)
        assert r.K.shape == (N_LOCAL, N_LOCAL)
        assert np.abs(r.K - r.K.T).max() < 1e-6 * np.abs(r.K).max()
        assert B.shape == (N_LOCAL,)


def test_reprojection_follows_element_motion() -> None:
    """ξ is re-projected for the current q_elem from the given warm start."""
    s = _setup()
    q2 = s["q_elem"].copy()
    q2[0::3][[0, 2]] -= 0.01  # translate both nodes by −1 cm along x
    r = contact_point(s["q_body"], s["v_body"], s["u_Q"], q2, s["v_elem"], L_E, 0.45, R_B,
                      LinearPenalty(stiffness=1e6))
    P, rx, _ = beam_point(q2[None], np.array([L_E]), 0, r.xi)
    assert abs((r.Q - P) @ rx) < 1e-15 and r.xi > 0.55

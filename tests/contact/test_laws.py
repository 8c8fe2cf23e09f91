"""Normal force laws and regularised Coulomb friction (docs/theory.md §II.5)."""

from __future__ import annotations

import numpy as np
import pytest

from flexmbs.contact.laws import (
    DAMPING_ONSET,
    LAWS,
    ForceLaw,
    Hertz,
    HuntCrossley,
    LankaraniNikravesh,
    LinearPenalty,
    RegularizedCoulomb,
    get_law,
)
from flexmbs.errors import ModelError

#: central differences with h = 1e-7·scale on smooth laws: truncation + round-off ~1e-7 relative
FD_RTOL = 1e-6

LAW_CASES = [
    LinearPenalty(stiffness=1e6, damping=30.0),
    LinearPenalty(stiffness=1e6, damping=30.0, onset=2e-4),     # δ = 1e-4, 3e-5 in the onset
    LinearPenalty(stiffness=1e6, damping=30.0, damping_onset=3e-4),   # in the viscous ramp
    Hertz(stiffness=1e9, exponent=1.5),
    Hertz(stiffness=1e7, exponent=1.1),
    HuntCrossley(stiffness=1e9, exponent=1.5, restitution=0.7),
    LankaraniNikravesh(stiffness=1e9, exponent=1.5, restitution=0.5),
]


@pytest.mark.parametrize("law", LAW_CASES, ids=lambda x: type(x).__name__)
@pytest.mark.parametrize("delta, ddot", [(1e-4, 0.05), (3e-5, -0.01), (2e-4, 0.0)])
def test_derivatives_fd(law: ForceLaw, delta: float, ddot: float) -> None:
    assert isinstance(law, ForceLaw)
    v0 = 0.2
    f, kd, kv = law.force(delta, ddot, v0)
    assert f > 0
    h = 1e-7 * delta
    fd = (law.force(delta + h, ddot, v0)[0] - law.force(delta - h, ddot, v0)[0]) / (2 * h)
    assert kd == pytest.approx(fd, rel=FD_RTOL)
    hv = 1e-7
    fv = (law.force(delta, ddot + hv, v0)[0] - law.force(delta, ddot - hv, v0)[0]) / (2 * hv)
    assert kv == pytest.approx(fv, rel=FD_RTOL, abs=1e-9 * f)


def test_values() -> None:
    assert LinearPenalty(stiffness=1e6, damping=20.0).force(1e-4, 0.5, 0.0) == (110.0, 1e6, 20.0)
    f, k, c = Hertz(stiffness=1e9, exponent=1.5).force(1e-4, 3.0, 0.0)
    assert f == pytest.approx(1e9 * 1e-6) and k == pytest.approx(1.5e9 * 1e-2) and c == 0.0
    e, v0, d, dd = 0.6, 0.4, 1e-4, 0.1
    f, _, _ = HuntCrossley(stiffness=1e9, restitution=e).force(d, dd, v0)
    assert f == pytest.approx(1e9 * d**1.5 * (1 + 1.5 * (1 - e) * dd / v0))
    f, _, _ = LankaraniNikravesh(stiffness=1e9, restitution=e).force(d, dd, v0)
    assert f == pytest.approx(1e9 * d**1.5 * (1 + 0.75 * (1 - e**2) * dd / v0))
    # e = 1: purely elastic
    f1 = LankaraniNikravesh(stiffness=1e9, restitution=1.0).force(d, dd, v0)[0]
    assert f1 == pytest.approx(1e9 * d**1.5)


def test_the_linear_penalty_s_smooth_onset() -> None:
    """Reference: f = kδ²/(2δ₀) below the onset δ₀, k(δ − δ₀/2) above; f and ∂f/∂δ continuous
    at δ₀ (and ∂f/∂δ = 0 at first touch: C¹); the potential (law_energy) is its integral
    (Simpson's rule is exact on the piecewise cubic); onset 0 is the plain law."""
    from scipy.integrate import quad

    from flexmbs.contact.laws import law_energy

    k, d0 = 1e6, 2e-7
    law = LinearPenalty(stiffness=k, onset=d0)
    assert law.force(0.5 * d0, 0.0, 0.0) == pytest.approx((k * d0 / 8, 0.5 * k, 0.0))
    assert law.force(3 * d0, 0.0, 0.0) == pytest.approx((2.5 * k * d0, k, 0.0))
    below, above = law.force(d0 * (1 - 1e-12), 0.0, 0.0), law.force(d0 * (1 + 1e-12), 0.0, 0.0)
    assert below[0] == pytest.approx(above[0], rel=1e-9) and below[1] == pytest.approx(above[1])
    assert law.force(1e-15, 0.0, 0.0)[1] == pytest.approx(k * 1e-15 / d0)
    p = law.parameters()
    for delta in (0.3 * d0, d0, 4 * d0):
        exact = quad(lambda x: law.force(x, 0.0, 0.0)[0], 0.0, delta, points=[d0], epsabs=0)[0]
        assert law_energy(p, delta) == pytest.approx(exact, rel=1e-10)
    assert LinearPenalty(stiffness=k).force(1e-6, 0.0, 0.0) == (1.0, k, 0.0)
    with pytest.raises(ModelError, match="onset must be a finite number >= 0"):
        LinearPenalty(stiffness=k, onset=-1e-9)


def test_the_damped_linear_penalty_s_viscous_force_starts_from_zero() -> None:
    """Issue 53 item 2. Reference: f = kδ + c s(δ) δ̇, s = x²(3 − 2x), x = δ/δ_c below the
    damping onset δ_c, 1 above: at first touch the force is 0 whatever δ̇ (the plain law jumps
    to c δ̇ there), f and ∂f/∂δ are continuous at δ_c; a given ``onset`` is the damping's too;
    a clearance joint gives a damped law without either DAMPING_ONSET of its clearance."""
    k, c, dc, ddot = 2e5, 2.0, 1e-7, 0.065
    law = LinearPenalty(stiffness=k, damping=c, damping_onset=dc)
    assert law.force(1e-15, ddot, 0.0)[0] == pytest.approx(k * 1e-15 + 3 * c * ddot * 1e-16, rel=1e-6)
    assert law.force(0.5 * dc, ddot, 0.0) == pytest.approx(
        (k * 0.5 * dc + 0.5 * c * ddot, k + 1.5 * c * ddot / dc, 0.5 * c))
    below, above = law.force(dc * (1 - 1e-12), ddot, 0.0), law.force(dc * (1 + 1e-12), ddot, 0.0)
    assert below[0] == pytest.approx(above[0], rel=1e-9)
    assert below[1] == pytest.approx(above[1], rel=1e-6) and below[2] == pytest.approx(above[2])
    assert law.force(2 * dc, ddot, 0.0) == pytest.approx((2 * k * dc + c * ddot, k, c))
    plain = LinearPenalty(stiffness=k, damping=c, damping_onset=0.0)
    assert plain.force(1e-15, ddot, 0.0)[0] == pytest.approx(c * ddot)      # the jump
    assert LinearPenalty(stiffness=k, damping=c, onset=dc).parameters()[6] == dc
    assert LinearPenalty(stiffness=k, damping=c).for_clearance(1e-4).damping_onset == \
        pytest.approx(DAMPING_ONSET * 1e-4)
    for kept in (LinearPenalty(stiffness=k), LinearPenalty(stiffness=k, damping=c, onset=dc),
                 plain):
        assert kept.for_clearance(1e-4) is kept
    assert get_law("linear", stiffness=k, damping=c, damping_onset=dc) == law
    with pytest.raises(ModelError, match="damping_onset must be a finite number >= 0"):
        LinearPenalty(stiffness=k, damping=c, damping_onset=-1e-9)


def _step_residual(law: ForceLaw, delta: float, pred: float, v_pred: float, m: float,
                   h: float) -> tuple[float, float]:
    """One generalized-α step (ρ∞ = 0.8, the integrator's form) of a point of mass m moving
    onto a wall, unknown its penetration δ at the step's end: R = m b (δ − δ*) + f(δ, δ̇),
    δ̇ = v* + g (δ − δ*) (b, g: the step's ∂q̈/∂q, ∂q̇/∂q); returns (R, ∂R/∂δ)."""
    from flexmbs.solvers.generalized_alpha import GeneralizedAlpha

    am, af, gamma, beta = GeneralizedAlpha(rho_inf=0.8).parameters()
    b, g = (1 - am) / (h * h * beta * (1 - af)), gamma / (h * beta)
    f, kd, kv = law.force(delta, v_pred + g * (delta - pred), 0.0)
    return m * b * (delta - pred) + f, m * b + kd + g * kv


def test_an_implicit_step_onto_the_damped_wall_has_a_solution() -> None:
    """Issue 53 item 2, the mechanism: a wire's section (3.06e-6 kg) reaches the wall at
    0.065 m/s, c = 2 N s/m, k = 2e5 N/m, h = 2e-6 s. When the free motion would end the step
    less than c v*/(m b + c g) inside the wall (here 22 % of the step's travel h v*), the plain
    law's step equation has no root: R < 0 for every δ ≤ 0 (the free motion goes further in)
    and R > 0 for every δ > 0 (the viscous force c δ̇ there already throws it back out);
    Newton cycles between open and closed (as in the bore at t = 3.85 ms). With the viscous
    force ramped in, the residual is continuous and increasing: Newton finds the root."""
    m, c, k, h, v = 3.06e-6, 2.0, 2e5, 2e-6, 0.065
    plain = LinearPenalty(stiffness=k, damping=c, damping_onset=0.0)
    ramped = LinearPenalty(stiffness=k, damping=c).for_clearance(1e-4)
    pred = 0.5 * _band(m, c, h, v)
    assert pred > 0.1 * h * v
    grid = np.concatenate([-np.geomspace(1e-6, 1e-14, 60), np.geomspace(1e-14, 1e-6, 60)])
    R = np.array([_step_residual(plain, d, pred, v, m, h)[0] for d in grid])
    assert np.all(R[grid <= 0] < 0) and np.all(R[grid > 0] > 0)          # no root
    for law in (plain, ramped):
        d, cycle = pred, []
        for _ in range(30):
            r, dr = _step_residual(law, d, pred, v, m, h)
            d -= r / dr
            cycle.append(d)
        converged = abs(_step_residual(law, d, pred, v, m, h)[0]) < 1e-12 * m * v / h
        assert converged == (law is ramped), (law, cycle[-4:])


def _band(m: float, c: float, h: float, v: float) -> float:
    """The predictor penetrations (0, c v/(m b + c g)) without a solution (plain law)."""
    from flexmbs.solvers.generalized_alpha import GeneralizedAlpha

    am, af, gamma, beta = GeneralizedAlpha(rho_inf=0.8).parameters()
    b, g = (1 - am) / (h * h * beta * (1 - af)), gamma / (h * beta)
    return c * v / (m * b + c * g)


@pytest.mark.parametrize("law", LAW_CASES, ids=lambda x: type(x).__name__)
def test_nonnegative_and_clamped(law: ForceLaw) -> None:
    assert law.force(0.0, 1.0, 0.1) == (0.0, 0.0, 0.0)
    assert law.force(-1e-3, 1.0, 0.1) == (0.0, 0.0, 0.0)
    for ddot in np.linspace(-1e3, 1e3, 41):
        f, kd, kv = law.force(1e-5, ddot, 0.1)
        assert f >= 0.0
        if f == 0.0:
            assert kd == 0.0 and kv == 0.0  # damping would pull: clamped


def test_approach_velocity_guard() -> None:
    law = HuntCrossley(stiffness=1e9, restitution=0.5, min_approach_velocity=1e-3)
    f0 = law.force(1e-4, 1e-2, 0.0)
    assert np.isfinite(f0[0]) and f0 == law.force(1e-4, 1e-2, 1e-3)
    assert law.force(1e-4, 1e-2, -0.2) == law.force(1e-4, 1e-2, 0.2)


def test_registry_errors() -> None:
    assert set(LAWS) == {"linear", "hertz", "hunt_crossley", "lankarani_nikravesh"}
    assert get_law("linear", stiffness=1e5) == LinearPenalty(stiffness=1e5)
    assert isinstance(get_law("lankarani_nikravesh", stiffness=1.0, restitution=0.8), LankaraniNikravesh)
    with pytest.raises(ModelError, match=r"unknown contact law 'spring' \(known: hertz, hunt_crossley, "
                                         r"lankarani_nikravesh, linear\)"):
        get_law("spring", stiffness=1.0)
    with pytest.raises(ModelError, match="missing required parameter.*restitution"):
        get_law("hunt_crossley", stiffness=1e6)
    with pytest.raises(ModelError, match="unknown parameter.*stifness"):
        get_law("linear", stifness=1e6)
    with pytest.raises(ModelError, match="stiffness must be"):
        get_law("linear", stiffness=-1.0)
    with pytest.raises(ModelError, match="restitution must be in"):
        get_law("hunt_crossley", stiffness=1.0, restitution=1.5)
    with pytest.raises(ModelError, match="exponent must be >= 1"):
        get_law("hertz", stiffness=1.0, exponent=0.5)
    with pytest.raises(ModelError, match="damping"):
        LinearPenalty(stiffness=1.0, damping=-2.0)


def test_regularized_coulomb(rng: np.random.Generator) -> None:
    fr = RegularizedCoulomb(mu=0.3, eps_v=1e-3)
    v = np.array([0.2, -0.1, 0.05])
    F, dFv, dFf = fr.force(v, 10.0)
    assert F @ v < 0 and np.linalg.norm(F) < 0.3 * 10.0
    np.testing.assert_allclose(np.linalg.norm(fr.force(100 * v, 10.0)[0]), 3.0, rtol=1e-9)
    assert np.all(fr.force(np.zeros(3), 10.0)[0] == 0.0)
    h = 1e-8
    fd = np.column_stack([(fr.force(v + h * e, 10.0)[0] - fr.force(v - h * e, 10.0)[0]) / (2 * h)
                          for e in np.eye(3)])
    np.testing.assert_allclose(dFv, fd, rtol=1e-6, atol=1e-8)
    np.testing.assert_allclose(dFf, (fr.force(v, 10.0 + 1e-4)[0] - fr.force(v, 10.0 - 1e-4)[0]) / 2e-4,
                               rtol=1e-8)
    with pytest.raises(ModelError, match="eps_v"):
        RegularizedCoulomb(mu=0.3, eps_v=0.0)


@pytest.mark.parametrize("law", [LinearPenalty(stiffness=1e6, damping=20.0),
                                 Hertz(stiffness=1e9, exponent=1.5),
                                 HuntCrossley(stiffness=1e9, restitution=0.6)],
                         ids=["linear", "hertz", "hunt_crossley"])
def test_the_weighted_law_at_a_mouth(law: ForceLaw) -> None:
    """At an open bore's end section (``mouth`` = r_b) the law is ``w(δ) f`` with
    ``w = x²(3 − 2x)``, ``x = (r_b − δ)/(r_b/2)``: unchanged below r_b/2, 0 at δ = r_b (the
    axis at the wall); its δ- and δ̇-derivatives match central differences; the potential's
    derivative is the weighted elastic force (central differences of ``law_energy``), and the
    potential is continuous at r_b/2."""
    from flexmbs.contact.laws import MOUTH_FADE, held_law_force, law_energy

    p, r_b, v0, ddot = law.parameters(), 0.5e-3, 0.2, 0.01
    for delta in (0.1 * r_b, 0.3 * r_b):
        assert held_law_force(p, delta, ddot, v0, False, r_b) == law.force(delta, ddot, v0)
    assert held_law_force(p, r_b, ddot, v0, False, r_b) == (0.0, 0.0, 0.0)
    start = (1.0 - MOUTH_FADE) * r_b
    assert law_energy(p, start * (1 + 1e-12), r_b) == pytest.approx(law_energy(p, start), rel=1e-9)
    for delta in (0.55 * r_b, 0.75 * r_b, 0.95 * r_b):
        x = (r_b - delta) / (MOUTH_FADE * r_b)
        f, kd, kv = held_law_force(p, delta, ddot, v0, False, r_b)
        assert f == pytest.approx(x * x * (3 - 2 * x) * law.force(delta, ddot, v0)[0], rel=1e-12)
        h = 1e-7 * delta

        def force(d: float, dd: float = ddot) -> float:
            return held_law_force(p, d, dd, v0, False, r_b)[0]

        assert kd == pytest.approx((force(delta + h) - force(delta - h)) / (2 * h), rel=FD_RTOL)
        assert kv == pytest.approx((force(delta, ddot + 1e-7) - force(delta, ddot - 1e-7)) / 2e-7,
                                   rel=FD_RTOL, abs=1e-9 * f)
        dE = (law_energy(p, delta + h, r_b) - law_energy(p, delta - h, r_b)) / (2 * h)
        assert dE == pytest.approx(force(delta, 0.0), rel=1e-6)

"""Normal force laws and regularised Coulomb friction (docs/theory.md §II.5)."""

from __future__ import annotations

import numpy as np
import pytest

from flexmbs.contact.laws import (
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

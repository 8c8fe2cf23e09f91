"""Beam dynamics: natural frequencies (eigen solver and free vibration), energy conservation."""

from __future__ import annotations

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.assembly import Assembly
from tests.conftest import straight_beam

BETA_L = np.array([1.8751040687, 4.6940911330, 7.8547574382, 10.9955407349])


def _unit_cantilever(n_elem: int, gravity=(0, 0, 0)) -> tuple[fm.Model, fm.Beam]:
    model = fm.Model(gravity=gravity)
    beam = straight_beam(model, n_elem, EA=1e4, EI=1.0, rhoA=1.0)
    model.clamp(beam.first_node)
    return model, beam


def test_cantilever_eigenfrequencies():
    """L = rhoA = EI = 1, EA = 1e4 (docs/theory.md §I.7.3): bending (beta_n L)^2, each twice (y, z),
    and the first axial mode pi/2 sqrt(EA/rhoA) = 157.0796. With 16 cubic elements the 4th
    bending mode is within ~2e-4 (it converges as h^4; Exudyn's 8-element value is 2.2e-3 off);
    tolerances grow with the mode number accordingly."""
    model, _ = _unit_cantilever(16)
    m = fm.modes(model, n_modes=9)
    w = m.omega
    exact = BETA_L**2
    for k, tol in enumerate([1e-6, 1e-5, 1e-4, 5e-4]):
        assert w[2 * k] == pytest.approx(exact[k], rel=tol)
        assert w[2 * k + 1] == pytest.approx(exact[k], rel=tol)
    assert w[8] == pytest.approx(np.pi / 2 * 100.0, rel=1e-5)


def test_eigenfrequency_convergence_rate():
    """Fourth bending mode error decreases at the rate of cubic Hermite elements (~h^4) once
    the mode is resolved (8+ elements; measured 3.9-4.0). The 8-element value also equals
    Exudyn's 121.173 (docs/theory.md §I.7.3 table) to the printed digits."""
    model, _ = _unit_cantilever(8)
    assert fm.modes(model, n_modes=8).omega[6] == pytest.approx(121.173, abs=1e-3)
    ns = [8, 16, 32]
    errs = []
    for n in ns:
        model, _ = _unit_cantilever(n)
        errs.append(abs(fm.modes(model, n_modes=8).omega[6] - BETA_L[3] ** 2))
    rate = np.polyfit(np.log(1.0 / np.array(ns)), np.log(errs), 1)[0]
    assert rate == pytest.approx(4.0, abs=0.3)


def test_free_vibration_period_matches_first_mode():
    """Release a statically tip-loaded cantilever: the mean period between upward zero
    crossings of the tip deflection equals 2 pi / omega_1. Gen-alpha (rho_inf = 0.9) has a
    period error O((omega h)^2) ~ 1e-4 at h = T/200; the tip-load shape is ~97 % mode 1 and the
    rest is damped by rho_inf, so 2e-3 relative."""
    model, beam = _unit_cantilever(8)
    model.add_point_load(beam.last_node, (0, 0, -1e-3), function=lambda t: 1.0 if t <= 0 else 0.0)
    w1 = BETA_L[0] ** 2
    T = 2 * np.pi / w1
    res = fm.simulate(model, t_end=4.2 * T, dt=T / 200, initial_static=True,
                      integrator=fm.GeneralizedAlpha(rho_inf=0.9), record_energy=False)
    z = res.node_displacement(beam.last_node)[:, 2]
    t = res.t
    up = np.flatnonzero((z[:-1] < 0) & (z[1:] >= 0))
    tc = t[up] - z[up] * (t[up + 1] - t[up]) / (z[up + 1] - z[up])
    assert len(tc) >= 3
    assert np.mean(np.diff(tc)) == pytest.approx(T, rel=2e-3)


def test_undamped_beam_conserves_energy_with_rho_inf_one():
    """rho_inf = 1 is the trapezoidal rule: for a beam in free vibration (moderate amplitude,
    geometrically nonlinear) the total energy drifts only through the nonlinearity; we allow
    1e-4 of the energy over 400 steps (measured ~1e-5). The reference is the energy after the
    first step: the load is released between t = 0 and t = h, and the discrete scheme lets it
    do work during that one step (an artefact of the step load, not of the free vibration)."""
    model, beam = _unit_cantilever(6)
    model.add_point_load(beam.last_node, (0, 0, -0.3), function=lambda t: 1.0 if t <= 0 else 0.0)
    res = fm.simulate(model, t_end=4.0, dt=0.01, initial_static=True,
                      integrator=fm.GeneralizedAlpha(rho_inf=1.0))
    E = res.energy["kinetic"] + res.energy["strain"]
    assert E[1] > 0
    assert np.abs(E[1:] - E[1]).max() <= 1e-4 * E[1]
    # and numerical damping really dissipates with rho_inf = 0.5 (the test can fail both ways)
    res2 = fm.simulate(model, t_end=4.0, dt=0.01, initial_static=True,
                       integrator=fm.GeneralizedAlpha(rho_inf=0.5))
    E2 = res2.energy["kinetic"] + res2.energy["strain"]
    assert E2[-1] < E2[0] * (1 - 1e-3)


def test_dynamic_cantilever_under_gravity_settles_to_static():
    """Damped cantilever dropped under gravity converges to the static solution."""
    model = fm.Model(gravity=(0, 0, -9.81))
    beam = straight_beam(model, 4, EA=1e6, EI=10.0, rhoA=0.5, damping=0.02)
    model.clamp(beam.first_node)
    asm = Assembly(model)
    st = fm.solve_static(asm)
    res = fm.simulate(asm, t_end=3.0, dt=2e-3, output_interval=0.5, record_energy=False)
    tip = asm.node_dofs(beam.last_node)[2]
    assert res.q[-1, tip] == pytest.approx(st.q[tip], rel=2e-3)

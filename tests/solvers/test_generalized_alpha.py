"""Generalized-alpha paths and step control: the compiled fast path and the general Python path
agree, HHT, prescribed motion, step cut-back, divergence diagnostics (the bordered banded LU has
its own tests in tests/linalg/test_bordered.py)."""

from __future__ import annotations

import numpy as np
import pytest

import flexmbs as fm
from tests.conftest import straight_beam


def _forced_beam(load_function=None) -> tuple[fm.Model, fm.Beam]:
    model = fm.Model(gravity=(0, 0, -9.81))
    beam = straight_beam(model, 6, EA=1e6, EI=5.0, rhoA=0.4, damping=1e-3)
    model.clamp(beam.first_node)
    model.add_point_load(beam.last_node, (0.0, 0.3, 0.5),
                         function=load_function or fm.HalfSine(duration=0.05, amplitude=2.0))
    model.prescribe(beam.node(2), [1], fm.Sine(amplitude=1e-3, frequency=5.0))
    return model, beam


@pytest.mark.parametrize("scheme", ["generalized_alpha", "hht"])
def test_compiled_and_python_paths_agree(scheme):
    """Same equations, same convergence test: the two implementations give the same trajectory
    up to the Newton tolerance (rtol 1e-10 here), i.e. ~1e-9 relative on displacements."""
    runs = []
    for compiled in (True, False):
        model, beam = _forced_beam()
        integ = fm.GeneralizedAlpha(rho_inf=0.8, scheme=scheme, compiled=compiled,
                                    newton=fm.NewtonOptions(relative_tolerance=1e-10))
        res = fm.simulate(model, t_end=0.2, dt=1e-3, output_interval=0.01, integrator=integ,
                          record_energy=False)
        runs.append(res.node_displacement(beam.last_node))
    a, b = runs
    assert np.abs(a).max() > 1e-4  # it moves
    assert np.abs(a - b).max() < 1e-7 * np.abs(a).max()


def test_prescribed_motion_is_followed_exactly():
    model, beam = _forced_beam()
    res = fm.simulate(model, t_end=0.3, dt=1e-3, output_interval=0.01, record_energy=False)
    y = res.node_displacement(beam.node(2))[:, 1]
    expected = 1e-3 * np.sin(2 * np.pi * 5.0 * res.t)
    assert np.abs(y - expected).max() < 1e-12


def test_hht_energy_behaviour():
    """HHT with rho_inf = 1 is the trapezoidal rule (no dissipation); rho_inf = 0.6 dissipates."""
    def energy_loss(rho):
        model = fm.Model()
        beam = straight_beam(model, 4, EA=1e4, EI=1.0, rhoA=1.0)
        model.clamp(beam.first_node)
        model.add_point_load(beam.last_node, (0, 0, -0.05), function=lambda t: 1.0 if t <= 0 else 0.0)
        res = fm.simulate(model, t_end=3.0, dt=0.02, initial_static=True,
                          integrator=fm.GeneralizedAlpha(rho_inf=rho, scheme="hht"))
        E = res.energy["kinetic"] + res.energy["strain"]
        return (E[1] - E[-1]) / E[1]
    assert abs(energy_loss(1.0)) < 1e-5
    assert energy_loss(0.6) > 1e-3


def test_step_cut_back_recovers_and_matches_small_steps():
    """A Newton budget of 3 full-Newton iterations is too small for h = 0.02 on this problem, so
    steps are rejected and halved; the result must still match a run at h = 0.0025 (the cut-back
    steps are that small) to the accuracy of the scheme (1e-3 relative)."""
    def run(dt, its):
        model, beam = _forced_beam(fm.Constant(1.0))
        integ = fm.GeneralizedAlpha(rho_inf=0.8, newton=fm.NewtonOptions(
            max_iterations=its, modified=False), grow_after=1000)
        res = fm.simulate(model, t_end=0.1, dt=dt, output_interval=0.02, integrator=integ,
                          record_energy=False)
        return res, res.node_displacement(beam.last_node)[-1]
    res, tip = run(0.02, 3)
    assert res.stats.rejected_steps > 0
    _, ref = run(0.0025, 25)
    assert np.linalg.norm(tip - ref) < 1e-3 * np.linalg.norm(ref)


def test_divergence_names_the_worst_equation():
    model, beam = _forced_beam(fm.Constant(1.0))
    integ = fm.GeneralizedAlpha(adaptive=False, newton=fm.NewtonOptions(max_iterations=1))
    pattern = r"worst equation: (beam 'beam' node \d+, coordinate|clamp|prescribed)"
    with pytest.raises(fm.ConvergenceError, match=pattern) as exc:
        fm.simulate(model, t_end=0.1, dt=0.05, integrator=integ)
    # the partial history (initial state) travels with the exception
    assert exc.value.partial_result.t[0] == 0.0

"""Step-error control of generalized-alpha (``step_tolerance``, issue 32): the estimator
against the true local error of an oscillator, the global error's rate in the tolerance, both
Newton loops taking the same steps, and the scenario key."""

from __future__ import annotations

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.assembly import Assembly
from flexmbs.errors import ModelError, ScenarioError
from flexmbs.solvers.generalized_alpha import GeneralizedAlpha, integrate
from flexmbs.steploop import step_error

K, M, REST, OFFSET = 400.0, 2.0, 0.5, 0.01
W = np.sqrt(K / M)
T = 2 * np.pi / W


def _oscillator(damping: float = 0.0) -> tuple[fm.Model, fm.RigidBody]:
    """A body on a vertical spring from (0, 0, 1) (rest length 0.5), started ``OFFSET`` below
    its rest position: z'' = -w^2 (z - 0.5) - (c/m) z'."""
    model = fm.Model()
    body = model.add_rigid_body(mass=M, inertia=(1e-3, 1e-3, 1e-3),
                                position=(0, 0, REST - OFFSET))
    model.add_spring_damper(fm.GROUND, body, point_a=(0, 0, 1.0), stiffness=K, damping=damping,
                            rest_length=REST)
    return model, body


def _estimate_against_true_error(steps_per_period: int) -> float:
    """Largest |estimate / true local error - 1| over the steps of a fixed-step run (rho_inf =
    0.8) where the error is at least 0.3 of its largest (away from the zeros of the jerk), the
    true error being z_{n+1} minus the exact solution through (z_n, v_n)."""
    model, body = _oscillator()
    asm = Assembly(model)
    iz = int(asm.body_dofs(body)[2])
    opts = GeneralizedAlpha(rho_inf=0.8, adaptive=False)
    h = T / steps_per_period
    states: list = []
    integrate(asm, opts, t_end=T, dt=h, output_interval=h,
              observer=lambda s: states.append(s.copy()))
    _, _, gamma, beta = opts.parameters()
    true, est = [], []
    skip = steps_per_period // 10              # past the start transient of a_n
    for s0, s1 in zip(states[skip:-1], states[skip + 1:], strict=True):
        z0, v0 = s0.q[iz] - REST, s0.v[iz]
        exact = REST + z0 * np.cos(W * h) + v0 / W * np.sin(W * h)
        true.append(abs(s1.q[iz] - exact))
        est.append(step_error(s1.a, s0.a, h, beta, gamma, 1.0))
    true_a, est_a = np.array(true), np.array(est)
    big = true_a > 0.3 * true_a.max()
    return float(np.abs(est_a[big] / true_a[big] - 1.0).max())


def test_the_estimate_is_the_local_error_of_a_step():
    """The estimate has the true local error's leading term: their ratio tends to 1 like
    w h (measured: within 6 % at 200 steps per period, 3 % at 400). The Newmark constant
    (beta - 1/6), which ignores that a_n lags q'' by (alpha_m - alpha_f) h, would be 1.6x too
    large at rho_inf = 0.8."""
    coarse, fine = _estimate_against_true_error(200), _estimate_against_true_error(400)
    assert coarse < 0.08 and fine < 0.04, (coarse, fine)
    assert 1.6 < coarse / fine < 2.5                          # first order in w h
    _, _, gamma, beta = GeneralizedAlpha(rho_inf=0.8).parameters()
    assert abs(beta - 1 / 6) / abs(beta - gamma / 2 + 1 / 12) > 1.5


def _run(tolerance: float, *, compiled: bool = True, damping: float = 4.0,
         t_end: float = 3 * T) -> tuple[fm.Result, float]:
    model, body = _oscillator(damping)
    res = fm.simulate(model, t_end=t_end, dt=T / 8, output_interval=T / 8,
                      integrator=GeneralizedAlpha(rho_inf=0.8, step_tolerance=tolerance,
                                                  compiled=compiled))
    z = res.body_position(body)[:, 2]
    zeta = damping / (2 * np.sqrt(K * M))
    wd = W * np.sqrt(1 - zeta**2)
    exact = REST - OFFSET * np.exp(-zeta * W * res.t) * (
        np.cos(wd * res.t) + zeta * W / wd * np.sin(wd * res.t))
    return res, float(np.abs(z - exact).max())


def test_the_global_error_follows_the_tolerance():
    """Steps chosen by the estimate: h ~ tol^(1/3), so the global error of a second-order
    method falls like tol^(2/3) (100x tighter: 21.5x smaller), the number of steps grows like
    tol^(-1/3) (4.6x); measured 17x and 4.6x."""
    res_a, err_a = _run(1e-7)
    res_b, err_b = _run(1e-9)
    assert 10.0 < err_a / err_b < 40.0, (err_a, err_b)
    ratio = res_b.stats.steps / res_a.stats.steps
    assert 3.0 < ratio < 7.0, ratio
    assert res_a.stats.error_rejections > 0                  # dt = T/8 is refused at first
    assert res_a.stats.rejected_steps >= res_a.stats.error_rejections
    assert err_a < 2e-3 * OFFSET                             # and the steps kept are accurate
    # without control the largest step T/8 is taken throughout: far less accurate
    _, err_fixed = _run(0.0)
    assert err_fixed > 10 * err_a


def test_both_newton_loops_take_the_same_steps():
    res_c, err_c = _run(1e-7, compiled=True, t_end=T)
    res_p, err_p = _run(1e-7, compiled=False, t_end=T)
    assert res_c.stats.steps == res_p.stats.steps
    assert res_c.stats.error_rejections == res_p.stats.error_rejections
    np.testing.assert_allclose(res_c.q, res_p.q, rtol=0, atol=1e-11)


def test_tolerance_options_and_scenario_key(tmp_path):
    with pytest.raises(ModelError, match="step_tolerance"):
        GeneralizedAlpha(step_tolerance=-1.0)
    with pytest.raises(ModelError, match="adaptive"):
        GeneralizedAlpha(step_tolerance=1e-6, adaptive=False)
    from flexmbs.io.scenario import load_scenario

    src = (tmp_path / "s.toml")
    base = """
[simulation]
t_end = 0.01
dt = 1e-3
{extra}
[[beams]]
name = "rod"
geometry = {{ line = {{ start = [0, 0, 0], end = [1, 0, 0] }} }}
elements = 2
radius = 0.01
youngs_modulus = 2e11
density = 7800.0
"""
    src.write_text(base.format(extra="step_tolerance = 1e-6"))
    assert load_scenario(src).integrator_options().step_tolerance == 1e-6
    src.write_text(base.format(extra="step_tolerance = 1e-6\nadaptive = false"))
    with pytest.raises(ScenarioError, match=r"simulation\.step_tolerance"):
        load_scenario(src)
    src.write_text(base.format(extra="step_tolerance = -1.0"))
    with pytest.raises(ScenarioError, match=r"simulation\.step_tolerance"):
        load_scenario(src)

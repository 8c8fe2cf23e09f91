"""Torque and drag: a rod turned and pulled inside a tube with friction (issue "a rod or wire
inside a curved tube", item 3: the rod's proximal end turned by a driver, its torque the
reaction; the drill string's "torque and drag").

A steel rod (r_b = 1 mm, 0.5 m, the torsion-capable ``ancf_rod14``) lies on the bottom of a
straight horizontal tube (bore 1.5 mm, a section every 10 mm) under gravity. Its proximal end
is pulled along the tube at v and turned about its axis at ω (both prescribed, smooth start),
its slope held. Each contact slips at the surface velocity ``v x̂ + ω r_b (x̂ × n)``, so
Coulomb friction gives every contact the same split between drag and torque: over the whole
rod, in steady sliding,

    T / (r_b F_ax) = ω r_b / v     and     √(F_ax² + (T/r_b)²) = μ Σ f_N

(F_ax the pull's reaction along the tube, T the turn's torque reaction, Σ f_N the wall's normal
forces, averaged over the last 20 ms). Turning makes the drag fall: at ω r_b = v it is
μ Σ f_N / √2. Without the spin in the contact (before), the torque was zero and the drag
μ Σ f_N whatever ω.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import flexmbs as fm

R_B, BORE, LENGTH = 1e-3, 1.5e-3, 0.5
MU, V, RAMP = 0.3, 0.01, 0.02
T_END = 0.05


def _run(omega: float, law: str) -> dict[str, float]:
    model = fm.Model(name="torque_drag", gravity=(0.0, 0.0, -9.81))
    low = BORE - R_B                      # on the bottom of the bore from the start
    rod = model.add_beam(fm.line((0.0, 0.0, -low), (LENGTH, 0.0, -low), elements=20),
                         section=fm.CircularSection(R_B),
                         material=fm.Material(E=2e11, rho=7800.0, nu=0.3),
                         element="ancf_rod14", damping=1e-4, name="rod")
    tube = model.add_rigid_body(mass=1.0, inertia=(1e-3, 1e-3, 1e-3), name="tube")
    model.fix_body(tube)
    bore = fm.CurvedBore(fm.line((-0.02, 0.0, 0.0), (LENGTH + 0.02, 0.0, 0.0), elements=1),
                         radius=BORE, spacing=1e-2)
    friction = (fm.Friction(mu=MU) if law == "stick"
                else fm.RegularizedCoulomb(mu=MU, eps_v=1e-5))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model.add_joint(fm.SlidingClearanceJoint(
            rod, tube, hole=bore, contact=fm.LinearPenalty(stiffness=1e6, damping=5.0),
            friction=friction, name="tube"))
    model.prescribe(rod.first_node, [0], fm.Function(lambda t: V * _ramped_time(t)),
                    name="pull")
    model.prescribe(rod.first_node, [1, 2, 3, 4, 5], name="hold")
    model.prescribe(rod.first_node, [6], fm.Function(lambda t: omega * _ramped_time(t)),
                    name="turn")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = fm.simulate(model, t_end=T_END, dt=5e-5, output_interval=5e-4,
                          integrator=fm.GeneralizedAlpha(rho_inf=0.8))
    late = res.t > T_END - 0.02
    F, _ = res.reaction("pull", rod)
    _, M = res.reaction("turn", rod)
    joint = next(j for j in model.interactions if isinstance(j, fm.SlidingClearanceJoint))
    normal = []
    for q, v, lam, t in zip(res.q[late], res.v[late], res.lam[late], res.t[late], strict=True):
        rows = joint.output(res.assembly, q, v, lam, float(t))
        normal.append(sum(r["normal_force"] for r in rows))
    return {"drag": float(F[late, 0].mean()), "torque": float(M[late, 0].mean()),
            "normal": float(np.mean(normal))}


def _ramped_time(t: float) -> float:
    """Time with a smooth start: the motion ramps to full speed over RAMP."""
    if t <= 0.0:
        return 0.0
    if t >= RAMP:
        return t - 0.5 * RAMP
    return t * t / (2.0 * RAMP)


@pytest.mark.parametrize("law", ["stick", "regularised"])
def test_turning_a_rod_splits_its_friction_into_drag_and_torque(law: str) -> None:
    """Measured (20 ms of steady sliding after a 20 ms start): turned at ω r_b = v, T/(r_b F_ax)
    = 1.011 and √(F_ax² + (T/r_b)²) = 0.9995 μ Σ f_N, the drag 0.703 μ Σ f_N (1/√2 = 0.707);
    not turned, the drag μ Σ f_N to 1e-5 and no torque; the two laws agree to 2e-4."""
    turned = _run(V / R_B, law)          # ω r_b = v: the slip at 45°
    ratio = turned["torque"] / (R_B * turned["drag"])
    assert ratio == pytest.approx(1.0, rel=2e-2), turned
    total = math.hypot(turned["drag"], turned["torque"] / R_B)
    assert total == pytest.approx(MU * turned["normal"], rel=5e-3), turned
    assert turned["drag"] / (MU * turned["normal"]) == pytest.approx(1 / math.sqrt(2), rel=1e-2)
    pulled = _run(0.0, law)              # not turned: all drag, no torque
    assert pulled["drag"] == pytest.approx(MU * pulled["normal"], rel=1e-3), pulled
    assert abs(pulled["torque"]) < 1e-6 * R_B * pulled["drag"], pulled

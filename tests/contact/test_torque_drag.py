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


# ---------------------------------------------------------------------------------------------
# A rod whose nodes are re-based while they slide in frictional contact: pulled 0.25 m around
# a 180° tube (centre-line radius 0.1 m), each node inside the bend turns past 120° from its
# chart's base and takes a new chart (docs/theory.md §I.2.4) with its contacts' friction history
# on it; the cable (no charts) is the reference.
BEND_R, BEND_BORE, BEND_WIRE = 0.1, 0.8e-3, 0.5e-3


def _u_tube_path(ds: float = 2e-2, entry: float = 0.3, exit_: float = 0.06):
    """Straight along +y into a half circle (centre at the origin, from (−ρ, 0, 0) over the
    top), straight out along −y: nodes and unit tangents."""
    pts, tans = [], []
    for k in range(round(entry / ds)):
        pts.append((-BEND_R, -entry + k * ds, 0.0))
        tans.append((0.0, 1.0, 0.0))
    n_arc = round(BEND_R * math.pi / ds)
    for k in range(n_arc + 1):
        phi = math.pi - math.pi * k / n_arc
        pts.append((BEND_R * math.cos(phi), BEND_R * math.sin(phi), 0.0))
        tans.append((math.sin(phi), -math.cos(phi), 0.0))
    for k in range(1, round(exit_ / ds) + 1):
        pts.append((BEND_R, -k * ds, 0.0))
        tans.append((0.0, -1.0, 0.0))
    return np.array(pts), np.array(tans)


def _pulled_around(element: str, speed: float = 2.0, t_end: float = 0.15,
                   ) -> tuple[np.ndarray, int]:
    """Pull force along the exit line over the capstan value e^{μπ}·100 N at the output
    times, and the number of nodes re-based during the run."""
    from flexmbs.assembly import Assembly

    model = fm.Model(name="u_tube", gravity=(0.0, 0.0, 0.0))
    pts, tans = _u_tube_path()
    wire = model.add_beam(fm.polyline(pts, tans), section=fm.CircularSection(BEND_WIRE),
                          material=fm.Material(E=2e11, rho=7800.0), damping=1e-4, name="wire",
                          element=element)
    tube = model.add_rigid_body(mass=1.0, inertia=(1e-3, 1e-3, 1e-3), name="tube")
    model.fix_body(tube)
    arc = fm.arc((0.0, 0.0, 0.0), BEND_R, (-BEND_R, 0.0, 0.0), -math.pi,
                 normal=(0.0, 0.0, 1.0), elements=64)
    model.add_joint(fm.SlidingClearanceJoint(
        wire, tube, hole=fm.CurvedBore(arc, radius=BEND_BORE, spacing=4e-3),
        contact=fm.LinearPenalty(stiffness=2e6), friction=fm.Friction(mu=0.2), name="tube"))
    model.add_point_load(wire.first_node, (0.0, -100.0, 0.0),
                         function=fm.Ramp(start=0.0, end=0.02, value=1.0, smooth=True))

    def pulled(t: float) -> float:     # at `speed` from t = 0.03 (C¹ start)
        if t < 0.02:
            return 0.0
        return -(speed * (t - 0.02) ** 2 / 0.02 if t < 0.03 else speed * (t - 0.025))

    model.prescribe(wire.last_node, [1], fm.Function(pulled), name="pull")
    model.prescribe(wire.last_node, [0, 2], name="pull_line")
    asm = Assembly(model)
    bases0 = asm.node_bases().copy()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = fm.simulate(asm, t_end=t_end, dt=2e-4, output_interval=5e-3,
                          integrator=fm.GeneralizedAlpha(rho_inf=0.8))
    bases = asm.node_bases()
    rebased = 0 if bases0.size == 0 else int(
        np.any(np.abs(bases[:, 1:4] - bases0[:, 1:4]) > 1e-9, axis=1).sum())
    F, _ = res.reaction("pull", wire)
    return -F[:, 1] / (100.0 * math.exp(0.2 * math.pi)), rebased


def test_a_rod_rebased_in_frictional_contact_pulls_like_the_cable():
    """Pulled 0.25 m around the U-tube at 2 m/s, 7 of the rod's nodes take a new chart while
    they slide on the wall; the pull force over the capstan value e^{μπ}·100 N is the cable's
    (which has no charts) at every output time to 2e-4 (measured 4.5e-5) and 1 to 1 % (measured
    1.0031–1.0068 while sliding): the friction history crosses the re-basing."""
    cable, none = _pulled_around("ancf_cable")
    rod, rebased = _pulled_around("ancf_rod14")
    assert none == 0 and rebased >= 5, rebased
    sliding = slice(8, None)                       # from t = 0.04 s
    assert np.abs(rod[sliding] - cable[sliding]).max() < 2e-4, np.abs(rod - cable).max()
    assert np.abs(rod[sliding] - 1.0).max() < 0.01, rod

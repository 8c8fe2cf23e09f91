"""Reaction forces from the multipliers (issue "multibody basics": reactions)."""

from __future__ import annotations

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.assembly import Assembly
from flexmbs.constraints.reactions import reactions


def _cantilever(gravity=(0.0, 0.0, 0.0), load=(0.0, 3.0, -2.0), moment=None):
    model = fm.Model(gravity=gravity)
    beam = model.add_beam(fm.line((0, 0, 0), (1, 0, 0), elements=8),
                          section=fm.CircularSection(5e-3),
                          material=fm.Material(E=2.1e11, rho=7800))
    model.clamp(beam.first_node, name="root")
    model.add_point_load(beam.last_node, load, moment=moment, name="tip")
    return model, beam


def test_clamp_reaction_balances_a_tip_load_on_the_deformed_cantilever():
    """Statics: reaction force = -F; moment about the root = -(x_tip x F) with the deformed
    tip position (large enough that the deformed arm matters: 3 N sideways on 1 m)."""
    model, beam = _cantilever()
    asm = Assembly(model)
    st = fm.solve_static(asm)
    (r,) = reactions(asm, st.q, st.lam, "root")
    assert r.part == beam.name
    F = np.array([0.0, 3.0, -2.0])
    x_tip = st.q[asm.node_dofs(beam.last_node)[:3]]
    assert np.allclose(r.force, -F, rtol=0, atol=1e-9)
    assert np.allclose(r.moment, -np.cross(x_tip, F), rtol=0, atol=1e-9)
    assert np.linalg.norm(x_tip - (1, 0, 0)) > 1e-3          # the tip really moved


def test_clamp_reaction_equals_the_weight_and_its_moment():
    """Gravity only, small deflection: force = total weight up, moment = weight x L/2
    (deformed arm: relative difference of order the deflection/length)."""
    model, beam = _cantilever(gravity=(0, 0, -9.81), load=(0, 0, 0))
    asm = Assembly(model)
    st = fm.solve_static(asm)
    (r,) = reactions(asm, st.q, st.lam, "root")
    W = 7800 * np.pi * 25e-6 * 1.0 * 9.81
    assert np.allclose(r.force, (0, 0, W), rtol=1e-12, atol=1e-12)
    assert r.moment[1] == pytest.approx(-W * 0.5, rel=1e-3)


def test_spherical_joint_of_the_heavy_top_carries_weight_and_centripetal_force():
    """Dynamics: m a_com = F_joint + m g, a_com from central differences of the body's
    velocity (output every step); the joint moment about the centre of mass is r x F with r
    from the centre of mass to the fixed point (a spherical joint transmits no moment)."""
    arm, tilt, spin = 0.1, 0.3, 40.0
    c, s = np.cos(tilt), np.sin(tilt)
    R = np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    model = fm.Model(gravity=(0, 0, -9.81))
    top = model.add_rigid_body(mass=1.0, inertia=(4e-3, 4e-3, 1e-3), pose=fm.Pose(arm * R[:, 2], R),
                               angular_velocity=spin * R[:, 2])
    model.spherical(top, fm.GROUND, point=(0, 0, 0), name="pivot")
    dt = 2e-4
    res = fm.simulate(model, t_end=0.1, dt=dt, output_interval=dt,
                      integrator=fm.GeneralizedAlpha(rho_inf=0.9, adaptive=False))
    F, M = res.reaction("pivot", top)
    v = res.v[:, res.assembly.body_dofs(top)[:3]]
    a = (v[2:] - v[:-2]) / (2 * dt)
    g = np.array([0, 0, -9.81])
    err = a - (F[1:-1] + g)
    assert np.abs(err[50:]).max() < 2e-3 * 9.81
    r_cm = res.body_position(top)
    assert np.allclose(M, np.cross(-r_cm, F), atol=1e-9)
    assert np.abs(F[:, :2]).max() > 0.05          # centripetal/precession part is present


def test_sliding_joint_reaction_probe_is_unchanged():
    """The existing joint_reaction of the sliding joint and the new reaction agree (force on
    the body)."""
    from pathlib import Path

    from flexmbs.io.scenario import load_scenario

    sc = load_scenario(Path(__file__).resolve().parents[2] / "examples" /
                       "curved_beam_sleeve_ideal.toml", ["simulation.t_end=0.05"])
    joint = next(j for j in sc.model.interactions)
    res = fm.simulate(sc.model, t_end=0.05, dt=1e-3, output_interval=1e-2)
    F, _ = res.reaction(joint.name, joint.body)
    old = np.array([joint.reaction_force(res.assembly, lam) for lam in res.lam])
    assert np.allclose(F, old, atol=1e-9 * max(1.0, np.abs(old).max()))
    assert np.abs(old).max() > 0.1


def test_reaction_probe_in_a_scenario_and_errors(tmp_path, capsys):
    from flexmbs.cli import main

    root = tmp_path / "c.toml"
    root.write_text(
        'name = "c"\n[simulation]\nintegrator = "static"\n[[beams]]\nname = "rod"\n'
        'geometry = { line = { start = [0, 0, 0], end = [1, 0, 0] } }\nelements = 4\n'
        'radius = 5e-3\nyoungs_modulus = 2.1e11\ndensity = 7800.0\n'
        '[[constraints]]\nname = "root"\ntype = "clamp"\nbeam = "rod"\nnode = "first"\n'
        '[[loads]]\nname = "tip"\ntype = "point"\nbeam = "rod"\nnode = "last"\n'
        'force = [0.0, 0.0, -5.0]\n'
        '[[probes]]\nname = "R"\ntype = "reaction"\nconstraint = "root"\n')
    assert main(["run", str(root), "--out", str(tmp_path / "o"), "-q"]) == 0
    header, row = (tmp_path / "o" / "probes.csv").read_text().strip().splitlines()[:2]
    assert header.startswith("t,R_fx,R_fy,R_fz,R_mx,R_my,R_mz")
    vals = [float(x) for x in row.split(",")]
    assert vals[3] == pytest.approx(5.0, rel=1e-12)
    bad = root.read_text().replace('constraint = "root"', 'constraint = "rooot"')
    root.write_text(bad)
    assert main(["info", str(root)]) == 2
    assert "probes[R].constraint: no constraint or joint named 'rooot'" in capsys.readouterr().err


# ----------------------------------------------------------------- a rod node's twist
STEEL = fm.Material(E=2e11, rho=7800.0, nu=0.3)


def _rod(length: float = 0.5, elements: int = 10, radius: float = 5e-3):
    model = fm.Model()
    rod = model.add_beam(fm.line((0, 0, 0), (length, 0, 0), elements=elements),
                         section=fm.CircularSection(radius), material=STEEL,
                         element="ancf_rod14", name="rod")
    return model, rod


def test_turning_a_rods_end_takes_the_torsional_torque():
    """A straight rod turned by Φ at one end (its twist prescribed, position and slope held)
    and clamped at the other: the torque is GJ Φ / L, about the axis, at both ends."""
    model, rod = _rod()
    phi = 0.3
    model.prescribe(rod.first_node, [0, 1, 2, 3, 4, 5], name="hold")
    model.prescribe(rod.first_node, [6], fm.Constant(phi), name="turn")
    model.clamp(rod.last_node, name="end")
    asm = Assembly(model)
    st = fm.solve_static(asm)
    G = STEEL.E / (2 * (1 + STEEL.nu))
    torque = G * np.pi * 5e-3**4 / 2 * phi / 0.5
    (turn,) = reactions(asm, st.q, st.lam, "turn")
    (end,) = reactions(asm, st.q, st.lam, "end")
    assert turn.moment == pytest.approx([torque, 0.0, 0.0], rel=1e-9, abs=1e-9 * torque)
    assert end.moment == pytest.approx([-torque, 0.0, 0.0], rel=1e-9, abs=1e-9 * torque)
    assert np.allclose(turn.force, 0.0, atol=1e-9) and np.allclose(end.force, 0.0, atol=1e-9)


def test_rigid_node_reaction_on_a_turned_rod_node_balances_the_body():
    """A rod cantilever carrying a rigid body at its tip (``rigid``: position, slope and the
    section's turn), the body loaded by a force and a moment that turn the tip 37° from
    its chart's base: the reaction on the beam (through the node's rotation map, twist and
    chart included) is equal and opposite to the reaction on the body, and that one balances
    the load."""
    model, rod = _rod(length=1.0, elements=8, radius=4e-3)
    model.clamp(rod.first_node, name="root")
    tip = model.add_rigid_body(mass=1.0, inertia=(1e-3, 1e-3, 1e-3),
                               pose=fm.Pose(position=(1.0, 0.0, 0.0)), name="tip")
    model.rigid(rod.last_node, tip, name="weld")
    F, M = np.array([0.0, 60.0, -40.0]), np.array([25.0, 10.0, -15.0])
    model.add_point_load(tip, F, moment=M, name="load")
    asm = Assembly(model)
    st = fm.solve_static(asm, fm.StaticOptions(load_steps=8))
    g = st.q[asm.node_dofs(rod.last_node)[3:6]]
    assert np.degrees(np.arccos(g[0] / np.linalg.norm(g))) > 30.0       # the tip turned far
    on = {r.part: r for r in reactions(asm, st.q, st.lam, "weld")}
    assert np.allclose(on["tip"].force, -F, atol=1e-8)
    assert np.allclose(on["tip"].moment, -M, atol=1e-8)
    assert np.allclose(on["rod"].point, on["tip"].point, atol=1e-12)
    assert np.allclose(on["rod"].force, F, atol=1e-8)
    assert np.allclose(on["rod"].moment, M, atol=1e-7)


def test_a_prescribed_twist_needs_a_held_slope_and_a_rod():
    model, rod = _rod()
    model.prescribe(rod.first_node, [0, 1, 2], name="hold")
    model.prescribe(rod.first_node, [6], fm.Constant(0.1), name="turn")
    with pytest.raises(fm.ModelError, match=r"prescribed 'turn': the twist of node 0 of beam "
                                            r"'rod' is prescribed but its slope is free"):
        Assembly(model)
    cable = fm.Model()
    wire = cable.add_beam(fm.line((0, 0, 0), (1, 0, 0), elements=2),
                          section=fm.CircularSection(1e-3), material=STEEL)
    with pytest.raises(fm.ModelError, match="a cable's node has no twist"):
        cable.prescribe(wire.first_node, [6])

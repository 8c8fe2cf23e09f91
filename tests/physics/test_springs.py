"""Translational spring-dampers (issue "multibody basics", springs): closed forms, energy,
exact tangent."""

from __future__ import annotations

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.assembly import Assembly
from flexmbs.springs import spring_forces
from flexmbs.terms import dynamic_mode


def _mass_on_spring(k=400.0, c=0.0, m=2.0, gravity=0.0, preload=0.0, offset=0.01):
    """A body hanging from the ground point (0, 0, 1) on a vertical spring of rest length 0.5,
    started ``offset`` below the rest position; its rotation is free (the spring acts at its
    centre of mass)."""
    model = fm.Model(gravity=(0, 0, -gravity))
    body = model.add_rigid_body(mass=m, inertia=(1e-3, 1e-3, 1e-3),
                                position=(0, 0, 0.5 - offset))
    spring = model.add_spring_damper(fm.GROUND, body, point_a=(0, 0, 1.0), stiffness=k,
                                     damping=c, rest_length=0.5, preload=preload, name="s")
    return model, body, spring


def test_period_of_a_mass_on_a_spring():
    k, m = 400.0, 2.0
    model, body, _ = _mass_on_spring(k=k, m=m)
    w = np.sqrt(k / m)
    T = 2 * np.pi / w
    res = fm.simulate(model, t_end=2 * T, dt=T / 400, output_interval=T / 400,
                      integrator=fm.GeneralizedAlpha(rho_inf=1.0, adaptive=False))
    z = res.body_position(body)[:, 2]
    exact = 0.5 - 0.01 * np.cos(w * res.t)
    assert np.abs(z - exact).max() < 2e-3 * 0.01          # second order: (w h)^2 / 12 ~ 2e-5
    E = res.energy["total"]
    assert np.abs(E - E[0]).max() < 1e-8 + 1e-6 * 0.5 * k * 0.01**2
    assert "spring" in res.energy


def test_damped_decay_against_the_closed_form():
    k, m, zeta = 400.0, 2.0, 0.05
    c = 2 * zeta * np.sqrt(k * m)
    model, body, _ = _mass_on_spring(k=k, c=c, m=m)
    w = np.sqrt(k / m)
    wd = w * np.sqrt(1 - zeta**2)
    T = 2 * np.pi / wd
    res = fm.simulate(model, t_end=3 * T, dt=T / 800, output_interval=T / 800,
                      integrator=fm.GeneralizedAlpha(rho_inf=1.0, adaptive=False))
    t = res.t
    exact = -0.01 * np.exp(-zeta * w * t) * (np.cos(wd * t) + zeta / np.sqrt(1 - zeta**2)
                                              * np.sin(wd * t))
    z = res.body_position(body)[:, 2] - 0.5
    assert np.abs(z - exact).max() < 1e-3 * 0.01


def test_preloaded_spring_in_statics():
    """Static equilibrium under gravity: k (l - l0) + f0 = m g (the body on a vertical
    prismatic joint, which the reaction confirms carries nothing along z)."""
    k, m, g, f0 = 400.0, 2.0, 9.81, 5.0
    model, body, _ = _mass_on_spring(k=k, m=m, gravity=g, preload=f0, offset=0.0)
    model.prismatic(body, point=(0, 0, 0.5), axis=(0, 0, 1), name="guide")
    st = fm.solve_static(model)
    asm = Assembly(model)
    z = st.q[asm.body_dofs(body)[2]]
    stretch = (m * g - f0) / k
    assert z == pytest.approx(0.5 - stretch, rel=1e-10)


def test_table_spring_and_its_energy():
    """A stiffening table spring: the force follows the table; energy is conserved with
    rho_inf = 1 (the potential is the table's integral)."""
    model = fm.Model()
    body = model.add_rigid_body(mass=1.0, inertia=(1e-3, 1e-3, 1e-3), position=(0.52, 0, 0))
    model.add_spring_damper(fm.GROUND, body, table=[[-0.1, -100.0], [0.0, 0.0], [0.01, 2.0],
                                                    [0.1, 80.0]], rest_length=0.5)
    res = fm.simulate(model, t_end=0.5, dt=2e-4, output_interval=2e-3,
                      integrator=fm.GeneralizedAlpha(rho_inf=1.0, adaptive=False))
    E = res.energy["total"]
    assert res.energy["spring"][0] == pytest.approx(0.5 * 2.0 * 0.01 + 0.5 * (2.0 + 10.667) * 0.01,
                                                     rel=1e-3)
    assert np.abs(E - E[0]).max() < 1e-4 * E[0]


def test_spring_tangent_equals_finite_differences():
    """Body-to-body, body-to-node and node-to-ground springs with damping, off-centre points
    and a rotating body: dr/dq and dr/dq' of the assembled residual against central
    differences."""
    model = fm.Model(gravity=(0, 0, 0))
    beam = model.add_beam(fm.line((0, 0, 0), (1, 0, 0), elements=2),
                          section=fm.CircularSection(1e-2), material=fm.Material(E=1e7, rho=1e3))
    b1 = model.add_rigid_body(mass=1.0, inertia=(1e-2, 2e-2, 3e-2), position=(0.3, 0.4, 0.2),
                              angular_velocity=(1.0, -2.0, 0.5), velocity=(0.1, 0.2, -0.3))
    b2 = model.add_rigid_body(mass=2.0, inertia=(2e-2, 2e-2, 1e-2), position=(-0.2, 0.5, 0.6))
    model.add_spring_damper(b1, b2, point_a=(0.05, -0.02, 0.1), point_b=(0.0, 0.1, -0.05),
                            stiffness=300.0, damping=4.0, rest_length=0.3, preload=2.0)
    model.add_spring_damper(b1, beam.last_node, point_a=(-0.1, 0.0, 0.03), stiffness=150.0,
                            damping=1.5, table=[[-1, -200], [0, 0], [1, 300]])
    model.add_spring_damper(beam.node(1), fm.GROUND, point_b=(0.5, -0.3, 0.2), stiffness=80.0)
    asm = Assembly(model)
    rng = np.random.default_rng(3)
    q, v = asm.initial_state()
    q = q + 1e-2 * rng.standard_normal(q.size)
    v = v + 0.3 * rng.standard_normal(v.size)
    n, m = asm.n_coords, asm.n_mult
    lam = np.zeros(m)

    def res(qq, vv):
        r_q, r_l = np.zeros(n), np.zeros(m)
        asm.evaluate(qq, vv, None, lam, 0.0, r_q, r_l)      # statics with damping: no
        return r_q                                        # inertia terms in the comparison

    def mat(cK, cC):
        r_q, r_l = np.zeros(n), np.zeros(m)
        asm.evaluate(q, v, None, lam, 0.0, r_q, r_l, matrix=(0.0, cC, cK))
        return asm.matrix.toarray()[:n, :n]

    Kfd = np.zeros((n, n))
    Cfd = np.zeros((n, n))
    h = 1e-6
    for j in range(n):
        e = np.zeros(n)
        e[j] = h
        Kfd[:, j] = (res(q + e, v) - res(q - e, v)) / (2 * h)
        Cfd[:, j] = (res(q, v + e) - res(q, v - e)) / (2 * h)
    K = mat(1.0, 0.0)
    C = mat(0.0, 1.0)
    springs = np.unique(np.concatenate([asm.body_dofs(b1), asm.body_dofs(b2)]))
    scale = np.abs(Kfd).max()
    assert np.abs(K - Kfd).max() < 1e-6 * scale
    assert np.abs(C - Cfd).max() < 1e-6 * np.abs(Cfd).max()
    assert np.abs(Kfd[np.ix_(springs, springs)]).max() > 1.0   # the springs are in there


SCENARIO = """
name = "mass_spring"
[simulation]
t_end = 0.2
dt = 1e-3
gravity = [0.0, 0.0, -9.81]
rho_inf = 0.9
[[rigid_bodies]]
name = "mass"
mass = 2.0
inertia = [1e-3, 1e-3, 1e-3]
pose = { position = [0.0, 0.0, 0.45] }
[[constraints]]
name = "guide"
type = "prismatic"
body = "mass"
axis = [0.0, 0.0, 1.0]
point = [0.0, 0.0, 0.45]
[[springs]]
name = "spring"
type = "translational"
body = "mass"
point2 = [0.0, 0.0, 1.0]
stiffness = 400.0
damping = 2.0
rest_length = 0.5
[[probes]]
name = "z"
type = "body_position"
body = "mass"
"""


def test_springs_in_a_scenario_and_their_errors(tmp_path, capsys):
    from flexmbs.cli import main
    from flexmbs.io.scenario import load_scenario

    path = tmp_path / "s.toml"
    path.write_text(SCENARIO)
    sc = load_scenario(path, ["simulation.integrator=\"static\""])
    st = fm.solve_static(sc.model)
    z = st.q[Assembly(sc.model).body_dofs(sc.model.bodies[0])[2]]
    assert z == pytest.approx(0.5 - 2.0 * 9.81 / 400.0, rel=1e-10)
    assert main(["run", str(path), "--out", str(tmp_path / "o"), "-q",
                 "--set", "springs.spring.stiffness=800.0"]) == 0
    for setting, text in [("springs.spring.stiffness=-1.0", "springs[spring].stiffness"),
                          ("springs.spring.table=[[0, 0]]", "springs[spring].table"),
                          ("springs.spring.body=\"nope\"", "no rigid body named 'nope'")]:
        assert main(["info", str(path), "--set", setting]) == 2
        assert text in capsys.readouterr().err
    no_end = SCENARIO.replace("point2 = [0.0, 0.0, 1.0]\n", "")
    path.write_text(no_end)
    assert main(["info", str(path)]) == 2
    assert "springs[spring].point2: missing required key" in capsys.readouterr().err


# ---------------------------------------------------------------------------------------------
# rotational spring-dampers
def _hinged_arm(k, c=0.0, L=0.4, m=1.5, gravity=9.81, theta0=0.0, rest_angle=0.0, preload=0.0):
    """A body of mass m, centre of mass L below a hinge at the origin (axis z, gravity -y),
    rotated by theta0 about the hinge, with a torsional spring-damper at the hinge."""
    I_c = 0.02
    model = fm.Model(gravity=(0, -gravity, 0))
    R = np.array([[np.cos(theta0), -np.sin(theta0), 0], [np.sin(theta0), np.cos(theta0), 0],
                  [0, 0, 1]])
    body = model.add_rigid_body(mass=m, inertia=(0.01, 0.01, I_c),
                                pose=fm.Pose(R @ np.array([0.0, -L, 0.0]), R), name="arm")
    hinge = model.revolute(body, fm.GROUND, point=(0, 0, 0), axis=(0, 0, 1), name="hinge")
    if k is not None:
        model.add_rotational_spring(hinge, stiffness=k, damping=c, rest_angle=rest_angle,
                                    preload=preload, name="torsion")
    return model, body, I_c + m * L * L


def _angle_history(res, body):
    """Rotation of the arm about z from its position history (centre of mass below the hinge
    at angle 0)."""
    x = res.body_position(body)
    return np.arctan2(x[:, 0], -x[:, 1])


def _zero_crossings(t, y):
    s = np.flatnonzero(np.sign(y[:-1]) * np.sign(y[1:]) < 0)
    return t[s] - y[s] * (t[s + 1] - t[s]) / (y[s + 1] - y[s])


def test_pendulum_with_a_torsional_spring_oscillates_at_the_closed_form_frequency():
    """Small oscillations: I_O theta'' + (k + m g L) theta = 0."""
    k, m, L = 6.0, 1.5, 0.4
    # assembled 0.02 rad off the vertical; the spring's rest angle (measured from the assembled
    # configuration) is the vertical
    model, body, I_O = _hinged_arm(k, L=L, m=m, theta0=0.02, rest_angle=-0.02)
    w = np.sqrt((k + m * 9.81 * L) / I_O)
    T = 2 * np.pi / w
    res = fm.simulate(model, t_end=3 * T, dt=T / 400, output_interval=T / 400,
                      integrator=fm.GeneralizedAlpha(rho_inf=0.95))
    theta = _angle_history(res, body)
    assert theta[0] == pytest.approx(0.02, rel=1e-9)
    zc = _zero_crossings(res.t, theta)
    assert len(zc) >= 5
    period = 2 * np.mean(np.diff(zc))
    assert period == pytest.approx(T, rel=2e-4)   # amplitude 0.02: (1 + theta^2/16) ~ 3e-5
    assert np.abs(theta).max() == pytest.approx(0.02, rel=1e-3)


def test_torsional_spring_preload_and_rest_angle_in_statics():
    """Without gravity the arm turns to where k (theta - rest) + preload = 0; with gravity to
    k (theta - rest) + preload + m g L sin(theta) = 0."""
    k = 5.0
    model, body, _ = _hinged_arm(k, gravity=0.0, rest_angle=0.6, preload=1.0)
    st = fm.solve_static(model)
    x = st.q[Assembly(model).body_dofs(body)[:3]]
    assert np.arctan2(x[0], -x[1]) == pytest.approx(0.6 - 1.0 / k, abs=1e-10)
    m, L = 1.5, 0.4
    model, body, _ = _hinged_arm(k, rest_angle=1.2, m=m, L=L)
    st = fm.solve_static(model)
    x = st.q[Assembly(model).body_dofs(body)[:3]]
    th = np.arctan2(x[0], -x[1])
    assert k * (th - 1.2) + m * 9.81 * L * np.sin(th) == pytest.approx(0.0, abs=1e-9)
    assert 0.3 < th < 1.2


def test_energy_balance_with_springs_for_rho_inf_near_one():
    """A double pendulum-like chain with a torsional table spring, a damper-free translational
    spring and gravity, large motion: total energy (kinetic + gravity + springs) is conserved to
    the accuracy of the integrator's (small) numerical dissipation at rho_inf = 0.98."""
    model, body, _ = _hinged_arm(None, theta0=1.2)
    hinge = model.constraints[0]
    model.add_rotational_spring(hinge, table=[[-2.0, -12.0], [0.0, 0.0], [0.5, 1.0], [2.0, 9.0]],
                                rest_angle=0.1, name="torsion")
    model.add_spring_damper(body, fm.GROUND, point_a=(0.0, -0.1, 0.0), point_b=(0.3, -0.6, 0.0),
                            stiffness=30.0, name="pull")
    res = fm.simulate(model, t_end=2.0, dt=5e-4, output_interval=1e-2,
                      integrator=fm.GeneralizedAlpha(rho_inf=0.98))
    e = res.energy
    swing = np.ptp(e["spring"]) + np.ptp(e["kinetic"])
    assert swing > 0.5                               # energy really moves between the stores
    assert np.abs(e["total"] - e["total"][0]).max() < 1e-3 * swing


def test_rotational_spring_tangent_equals_finite_differences():
    """Body-to-body (frames tilted on both bodies, off-centre joint point) and body-to-ground
    rotational springs with damping and a table, at a perturbed, rotating state: dr/dq and
    dr/dq' against central differences."""
    model = fm.Model(gravity=(0, 0, 0))
    R = np.linalg.qr(np.array([[1.0, 0.3, -0.2], [0.1, 1.0, 0.4], [-0.3, 0.2, 1.0]]))[0]
    R *= np.sign(np.linalg.det(R))
    b1 = model.add_rigid_body(mass=1.0, inertia=(1e-2, 2e-2, 3e-2), pose=fm.Pose((0.3, 0.4, 0.2), R),
                              angular_velocity=(1.0, -2.0, 0.5))
    b2 = model.add_rigid_body(mass=2.0, inertia=(2e-2, 2e-2, 1e-2), position=(-0.2, 0.5, 0.6),
                              angular_velocity=(0.3, 0.2, -1.0))
    j1 = model.revolute(b1, b2, point=(0.0, 0.4, 0.4), axis=(1.0, 2.0, -0.5))
    j2 = model.revolute(b2, fm.GROUND, point=(-0.2, 0.5, 0.8), axis=(0.2, -0.3, 1.0))
    model.add_rotational_spring(j1, stiffness=3.0, damping=0.4, rest_angle=0.3, preload=0.2)
    model.add_rotational_spring(j2, table=[[-1, -5], [0, 0], [1, 8]], damping=0.1)
    model.constraints.clear()   # the springs alone (their frames are kept)
    asm = Assembly(model)
    rng = np.random.default_rng(5)
    q, v = asm.initial_state()
    q = q + 3e-2 * rng.standard_normal(q.size)
    v = v + 0.3 * rng.standard_normal(v.size)
    n = asm.n_coords
    lam = np.zeros(asm.n_mult)

    def res(qq, vv):
        r_q, r_l = np.zeros(n), np.zeros(asm.n_mult)
        asm.evaluate(qq, vv, None, lam, 0.0, r_q, r_l)
        return r_q

    def mat(cK, cC):
        r_q, r_l = np.zeros(n), np.zeros(asm.n_mult)
        asm.evaluate(q, v, None, lam, 0.0, r_q, r_l, matrix=(0.0, cC, cK))
        return asm.matrix.toarray()[:n, :n]

    h = 1e-6
    E = np.eye(n) * h
    Kfd = np.column_stack([(res(q + E[j], v) - res(q - E[j], v)) / (2 * h) for j in range(n)])
    Cfd = np.column_stack([(res(q, v + E[j]) - res(q, v - E[j])) / (2 * h) for j in range(n)])
    assert np.abs(Kfd).max() > 1.0
    assert np.abs(mat(1.0, 0.0) - Kfd).max() < 1e-6 * np.abs(Kfd).max()
    assert np.abs(mat(0.0, 1.0) - Cfd).max() < 1e-6 * np.abs(Cfd).max()


def test_rotational_spring_errors():
    model = fm.Model()
    b = model.add_rigid_body(mass=1.0, inertia=(1, 1, 1), position=(0, 0, 0))
    sph = model.spherical(b, fm.GROUND)
    with pytest.raises(fm.ModelError, match="rotation mask"):
        model.add_rotational_spring(sph, stiffness=1.0)
    rev = model.revolute(b, fm.GROUND, point=(0, 0, 0), axis=(0, 0, 1))
    with pytest.raises(fm.ModelError, match="stiffness must be a finite number >= 0"):
        model.add_rotational_spring(rev, stiffness=-1.0)
    with pytest.raises(fm.ModelError, match="rest_angle must be finite"):
        model.add_rotational_spring(rev, stiffness=1.0, rest_angle=float("nan"))
    with pytest.raises(fm.ModelError, match="joint must be a revolute"):
        model.add_rotational_spring("hinge", stiffness=1.0)   # type: ignore[arg-type]


def test_springs_in_the_vtu_output(tmp_path):
    """Translational springs are line cells between their ends with their force; rotational
    ones a vertex at the joint point with their torque (block_id 3, spring_id names in the
    summary)."""
    import json

    import meshio

    from flexmbs.cli import main

    path = tmp_path / "s.toml"
    path.write_text(SCENARIO.replace("rho_inf = 0.9", "rho_inf = 0.9\nintegrator = \"static\""))
    out = tmp_path / "o"
    # the merged frame (meshio); the multiblock's springs block: tests/io/test_multiblock.py
    assert main(["run", str(path), "--out", str(out), "-q", "--output-frames", "merged"]) == 0
    vtus = sorted((out / "vtu").glob("*.vtu"))
    mesh = meshio.read(vtus[-1])
    cd = {k: np.concatenate(v) for k, v in mesh.cell_data.items()}
    found = [(j, k) for j, blk in enumerate(mesh.cells)
             for k in np.flatnonzero(mesh.cell_data["block_id"][j] == 3)]
    assert len(found) == 1 and mesh.cells[found[0][0]].type == "line"
    j, k = found[0]
    a, b = mesh.points[mesh.cells[j].data[k]]
    i = sum(len(c.data) for c in mesh.cells[:j]) + k
    length = np.linalg.norm(b - a)
    assert length == pytest.approx(0.5 + 2.0 * 9.81 / 400.0, rel=1e-9)
    assert cd["spring_force"][i] == pytest.approx(400.0 * (length - 0.5), rel=1e-9)
    assert cd["spring_extension"][i] == pytest.approx(length - 0.5, rel=1e-9)
    assert np.all(cd["spring_id"][cd["block_id"] != 3] == -1)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["vtu_blocks"]["spring_id"] == ["spring"]
    assert summary["vtu_blocks"]["block_id"]["3"] == "spring"


def test_rotational_spring_wound_three_turns_keeps_its_torque():
    """The arm driven three and a half turns about its hinge winds the torsional spring: its
    torque is k θ with θ counted through the turns (not within ±π of the rest angle), the
    motor's torque I_O θ'' + m g L cos θ + k θ; a run resumed after two turns continues the
    count (the turns are checkpointed)."""
    w, k = 2 * np.pi, 0.7
    m, L, I_c = 2.0, 0.5, 0.05

    def build():
        model = fm.Model(gravity=(0, -9.81, 0))
        body = model.add_rigid_body(mass=m, inertia=(0.001, I_c, I_c), position=(L, 0, 0),
                                    name="arm")
        hinge = model.revolute(body, fm.GROUND, point=(0, 0, 0), axis=(0, 0, 1), name="hinge")
        model.add_rotational_spring(hinge, stiffness=k, name="torsion")
        model.add_driver(hinge, fm.Function(lambda t: w * t * t / 2.0), name="motor")
        return model

    res = fm.simulate(build(), t_end=2.65, dt=5e-4, output_interval=1e-2)   # 3.5 turns
    theta = w * res.t**2 / 2.0
    assert theta[-1] > 6 * np.pi
    angle, torque, _ = spring_forces(res.assembly.system.springs, res.q[-1], res.v[-1],
                                     dynamic_mode())[0]
    assert angle == pytest.approx(theta[-1], rel=1e-9)          # three and a half turns
    assert torque == pytest.approx(k * theta[-1], rel=1e-9)
    _, Mo = res.reaction("motor")
    expected = (I_c + m * L * L) * w + m * 9.81 * L * np.cos(theta) + k * theta
    late = res.t > 0.05
    assert np.abs(Mo[late, 2] - expected[late]).max() < 1e-4 * np.abs(expected).max()


def test_a_resumed_run_keeps_the_turns_of_its_rotational_springs(tmp_path):
    """Stopped after two turns and resumed: the same final state bit for bit as the run
    without a stop (the spring's branch is checkpointed; from the rest angle it would read
    the angle two turns short)."""
    w, k = 2 * np.pi, 0.7

    def run(t_end, out, resume=False):
        model = fm.Model(gravity=(0, -9.81, 0))
        body = model.add_rigid_body(mass=2.0, inertia=(0.001, 0.05, 0.05), position=(0.5, 0, 0),
                                    name="arm")
        hinge = model.revolute(body, fm.GROUND, point=(0, 0, 0), axis=(0, 0, 1), name="hinge")
        model.add_rotational_spring(hinge, stiffness=k, name="torsion")
        model.add_driver(hinge, fm.Function(lambda t: w * t * t / 2.0), name="motor")
        return fm.simulate(model, t_end=t_end, dt=1e-3, output_interval=0.05, out=out,
                           resume=resume, write_vtu=False)

    full = run(2.5, tmp_path / "full")
    run(1.5, tmp_path / "part")
    resumed = run(2.5, tmp_path / "part", resume=True)
    np.testing.assert_array_equal(resumed.q[-1], full.q[-1])
    np.testing.assert_array_equal(resumed.lam[-1], full.lam[-1])

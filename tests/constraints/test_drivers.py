"""Joint drivers (issue "multibody basics": motors): the driven coordinate follows its function,
the driving torque/force is the reaction, exact Jacobian, statics, scenario keys and errors."""

from __future__ import annotations

import math

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.assembly import Assembly

M, L, G = 2.0, 0.5, 9.81
I_C = 0.05                       # about the hinge axis, at the centre of mass


def _arm(function, gravity=G):
    """A body with its centre of mass at (L, 0, 0), hinged at the origin about z, gravity -y,
    its rotation driven by ``function`` (rad, from the assembled configuration)."""
    model = fm.Model(gravity=(0, -gravity, 0))
    body = model.add_rigid_body(mass=M, inertia=(0.001, I_C, I_C), position=(L, 0, 0), name="arm")
    hinge = model.revolute(body, fm.GROUND, point=(0, 0, 0), axis=(0, 0, 1), name="hinge")
    model.add_driver(hinge, function, name="motor")
    return model, body


def test_rotation_driver_follows_its_function_and_its_torque_is_the_closed_form():
    """theta(t) = (1 - cos w t)/2 -> motor torque I_O theta'' + m g L cos theta (about +z)."""
    w = 2.0
    model, body = _arm(fm.Function(lambda t: 0.5 * (1 - math.cos(w * t))))
    res = fm.simulate(model, t_end=2.0, dt=1e-3, output_interval=1e-2)
    t = res.t
    th = 0.5 * (1 - np.cos(w * t))
    x = res.body_position(body)
    assert np.abs(np.arctan2(x[:, 1], x[:, 0]) - th).max() < 1e-9
    F, Mo = res.reaction("motor")
    tau = (I_C + M * L * L) * 0.5 * w * w * np.cos(w * t) + M * G * L * np.cos(th)
    assert np.abs(F).max() < 1e-9                  # a pure torque ...
    assert np.abs(Mo[:, :2]).max() < 1e-9          # ... about the axis
    assert np.abs(Mo[:, 2] - tau).max() < 1e-5 * np.abs(tau).max()


def test_rotation_driver_turns_many_times_without_a_branch_cut():
    """theta = w (t - tau (1 - exp(-t/tau))): starts at rest with a finite acceleration (the
    consistent initial acceleration includes the driver's Phi_tt), then turns more than three
    times: no jump at +-pi; the torque is I_O theta'' + m g L cos(theta) throughout."""
    w, tau = 4 * np.pi, 0.1

    def theta(t):
        return w * (t - tau * (1 - math.exp(-t / tau)))

    model, body = _arm(fm.Function(theta))
    res = fm.simulate(model, t_end=1.75, dt=5e-4, output_interval=5e-3)
    p = res.body_quaternion(body)
    turned = np.unwrap(2 * np.arctan2(p[:, 3], p[:, 0]))
    target = np.array([theta(t) for t in res.t])
    assert target[-1] > 6 * np.pi
    assert np.abs(turned - target).max() < 1e-8
    _, Mo = res.reaction("motor")
    expected = (I_C + M * L * L) * (w / tau) * np.exp(-res.t / tau) + M * G * L * np.cos(target)
    # t = 0: the consistent initial acceleration; then the multipliers' start-up transient of
    # generalized-alpha (O(h) while theta'' changes fast) decays within ~20 steps
    assert Mo[0, 2] == pytest.approx(expected[0], rel=1e-6)
    late = res.t > 0.05
    assert np.abs(Mo[late, 2] - expected[late]).max() < 1e-4 * np.abs(expected).max()


def test_slide_driver_force_against_a_spring_and_inertia():
    """A body on a prismatic guide along x tied to the ground by a spring k; the slide follows
    A sin(w t): the driving force is m x'' + k x (on the body, along +x)."""
    k, A, w = 200.0, 0.05, 6.0
    model = fm.Model()
    body = model.add_rigid_body(mass=M, inertia=(0.01, 0.01, 0.01), position=(0, 0, 0))
    guide = model.prismatic(body, fm.GROUND, point=(0, 0, 0), axis=(1, 0, 0), name="guide")
    model.add_spring_damper(body, fm.GROUND, point_b=(-0.4, 0, 0), stiffness=k, rest_length=0.4)
    model.add_driver(guide, fm.Sine(amplitude=A, frequency=w / (2 * np.pi)), name="actuator")
    res = fm.simulate(model, t_end=1.5, dt=1e-3, output_interval=1e-2)
    x = res.body_position(body)[:, 0]
    assert np.abs(x - A * np.sin(w * res.t)).max() < 1e-10
    F, _ = res.reaction("actuator")
    expected = -M * A * w * w * np.sin(w * res.t) + k * x
    late = res.t > 0.1                # after generalized-alpha's multiplier start-up transient
    assert np.abs(F[late, 0] - expected[late]).max() < 1e-4 * np.abs(expected).max()
    # the body starts at rest, the slide at A w: the initial velocity is made consistent
    assert res.v[0, asm_dof(model, body)] == pytest.approx(A * w, rel=1e-12)
    assert np.abs(F[:, 1:]).max() < 1e-9


def asm_dof(model, body):
    return Assembly(model).body_dofs(body)[0]


def test_rotation_driver_in_statics_holds_the_arm_at_the_target_angle():
    """Statics at time t: the driver holds the arm at theta(t) (scaled by the load factor) with
    the torque m g L cos theta."""
    model, body = _arm(fm.Ramp(start=0.0, end=1.0, value=1.0))
    asm = Assembly(model)
    st = fm.solve_static(asm, t=0.7)
    x = st.q[asm.body_dofs(body)[:3]]
    assert math.atan2(x[1], x[0]) == pytest.approx(0.7, abs=1e-10)
    from flexmbs.constraints.reactions import reactions

    (r,) = reactions(asm, st.q, st.lam, "motor", t=0.7)
    assert r.moment[2] == pytest.approx(M * G * L * math.cos(0.7), rel=1e-9)


def test_driver_jacobian_equals_finite_differences():
    """Rotation and slide drivers between two tilted bodies and to ground, at a perturbed state
    with arbitrary multipliers: the assembled Phi_q, Phi_q^T lam tangent against central
    differences of the residual."""
    model = fm.Model()
    R = np.linalg.qr(np.array([[1.0, 0.3, -0.2], [0.1, 1.0, 0.4], [-0.3, 0.2, 1.0]]))[0]
    R *= np.sign(np.linalg.det(R))
    b1 = model.add_rigid_body(mass=1.0, inertia=(1e-2, 2e-2, 3e-2), pose=fm.Pose((0.3, 0.4, 0.2), R))
    b2 = model.add_rigid_body(mass=2.0, inertia=(2e-2, 2e-2, 1e-2), position=(-0.2, 0.5, 0.6))
    j1 = model.revolute(b1, b2, point=(0.0, 0.4, 0.4), axis=(1.0, 2.0, -0.5))
    j2 = model.prismatic(b2, fm.GROUND, point=(-0.2, 0.5, 0.8), axis=(0.2, -0.3, 1.0))
    model.add_driver(j1, fm.Sine(amplitude=0.8, frequency=0.3))
    model.add_driver(j2, fm.Sine(amplitude=0.1, frequency=0.5))
    asm = Assembly(model)
    rng = np.random.default_rng(11)
    q, v = asm.initial_state()
    q = q + 3e-2 * rng.standard_normal(q.size)
    n, m = asm.n_coords, asm.n_mult
    lam = rng.standard_normal(m)
    t = 0.4

    def res(qq):
        r_q, r_l = np.zeros(n), np.zeros(m)
        asm.evaluate(qq, v, None, lam, t, r_q, r_l, with_damping=False)
        return np.concatenate([r_q, r_l])

    r_q, r_l = np.zeros(n), np.zeros(m)
    asm.evaluate(q, v, None, lam, t, r_q, r_l, matrix=(0.0, 0.0, 1.0), with_damping=False)
    A = asm.matrix.toarray()
    h = 1e-6
    E = np.eye(n) * h
    Jfd = np.column_stack([(res(q + E[j]) - res(q - E[j])) / (2 * h) for j in range(n)])
    assert np.abs(A[:, :n] - Jfd).max() < 1e-6 * np.abs(Jfd).max()
    drivers = [i for i, o in enumerate(asm.multiplier_owner) if o.startswith("driver")]
    assert len(drivers) == 2 and np.abs(Jfd[n + np.array(drivers)]).max() > 0.1


def test_driver_errors():
    model = fm.Model()
    b = model.add_rigid_body(mass=1.0, inertia=(1, 1, 1), position=(0, 0, 0))
    sph = model.spherical(b, fm.GROUND)
    with pytest.raises(fm.ModelError, match="needs motion"):
        model.add_driver(sph, 0.1)
    with pytest.raises(fm.ModelError, match="a rotation driver needs"):
        model.add_driver(sph, 0.1, motion="rotation")
    fixed = model.fix_body(b)
    with pytest.raises(fm.ModelError, match="a slide driver needs"):
        model.add_driver(fixed, 0.1, motion="slide")
    with pytest.raises(fm.ModelError, match="joint must be"):
        model.add_driver("hinge", 0.1)   # type: ignore[arg-type]


SCENARIO = """
name = "motor_arm"
[simulation]
t_end = 0.3
dt = 1e-3
gravity = [0.0, -9.81, 0.0]
rho_inf = 0.9
[[rigid_bodies]]
name = "arm"
mass = 2.0
inertia = [0.001, 0.05, 0.05]
pose = { position = [0.5, 0.0, 0.0] }
[[constraints]]
name = "hinge"
type = "revolute"
body = "arm"
point = [0.0, 0.0, 0.0]
axis = [0.0, 0.0, 1.0]
[[constraints]]
name = "motor"
type = "driver"
joint = "hinge"
function = { type = "ramp", start = 0.0, end = 1.0, value = 1.0, smooth = true }
[[springs]]
name = "torsion"
type = "rotational"
joint = "hinge"
stiffness = 3.0
damping = 0.1
[[probes]]
name = "torque"
type = "reaction"
constraint = "motor"
"""


def test_driver_and_rotational_spring_in_a_scenario(tmp_path, capsys):
    """The motor's torque probe equals I_O theta'' + m g L cos(theta) + k theta + c theta' for
    theta = (1 - cos(pi t))/2; bad keys are one-line errors naming the key."""
    import csv

    from flexmbs.cli import main

    path = tmp_path / "m.toml"
    path.write_text(SCENARIO)
    out = tmp_path / "o"
    assert main(["run", str(path), "--out", str(out), "-q"]) == 0
    with open(out / "probes.csv") as fh:
        rows = list(csv.DictReader(fh))
    t = np.array([float(r["t"]) for r in rows])
    mz = np.array([float(r["torque_mz"]) for r in rows])
    th = 0.5 * (1 - np.cos(np.pi * t))
    thd = 0.5 * np.pi * np.sin(np.pi * t)
    thdd = 0.5 * np.pi ** 2 * np.cos(np.pi * t)
    expected = (I_C + M * L * L) * thdd + M * G * L * np.cos(th) + 3.0 * th + 0.1 * thd
    assert np.abs(mz - expected).max() < 1e-3 * np.abs(expected).max()
    for setting, text in [
            ("constraints.motor.joint=\"nope\"", "constraints[motor].joint: no joint named 'nope'"),
            ("constraints.motor.motion=\"twist\"", "constraints[motor].motion"),
            ("springs.torsion.stiffness=-2.0", "springs[torsion].stiffness"),
            ("springs.torsion.joint=\"motor\"", "springs[torsion].joint: no joint named 'motor'"),
            ("constraints.motor.motion=\"slide\"", "constraints[motor]: add_driver: a slide driver")]:
        assert main(["info", str(path), "--set", setting]) == 2
        err = capsys.readouterr().err
        assert text in err and err.count("\n") == 1, err


def test_time_function_derivatives_are_right_sided():
    """The initial acceleration needs the motion after t: at the start of a ramp the right
    derivatives (not the central average of the two sides)."""
    smooth = fm.Ramp(start=0.0, end=2.0, value=3.0, smooth=True)
    assert smooth.d1(0.0) == 0.0
    assert smooth.d2(0.0) == pytest.approx(3.0 * 0.5 * (np.pi / 2.0) ** 2, rel=1e-12)
    assert smooth.d2(2.0) == 0.0                 # constant after the end
    linear = fm.Ramp(start=1.0, end=3.0, value=4.0)
    assert linear.d1(1.0) == 2.0 and linear.d1(0.5) == 0.0 and linear.d1(3.0) == 0.0
    half = fm.HalfSine(duration=0.5, amplitude=2.0)   # generic forward differences
    assert half.d1(0.0) == pytest.approx(2.0 * np.pi / 0.5, rel=1e-6)
    assert half.d2(0.1) == pytest.approx(-2.0 * (np.pi / 0.5) ** 2 * np.sin(np.pi * 0.2), rel=1e-4)


def test_compiled_and_python_loops_agree_with_springs_and_drivers():
    """A driven hinge carrying a second arm on a torsional table spring, a translational
    spring-damper to the ground: the compiled Newton loop and the Python one give the same
    trajectory and multipliers."""
    def build():
        model, body = _arm(fm.Ramp(start=0.0, end=0.5, value=1.0, smooth=True))
        arm2 = model.add_rigid_body(mass=0.5, inertia=(1e-3, 4e-3, 4e-3), position=(1.25, 0, 0),
                                    name="arm2")
        elbow = model.revolute(arm2, body, point=(1.0, 0, 0), axis=(0, 0, 1), name="elbow")
        model.add_rotational_spring(elbow, table=[[-1.0, -3.0], [0.0, 0.0], [1.0, 5.0]],
                                    damping=0.02)
        model.add_spring_damper(arm2, fm.GROUND, point_a=(0.25, 0, 0), point_b=(1.5, -0.5, 0),
                                stiffness=40.0, damping=0.5)
        return model

    runs = [fm.simulate(build(), t_end=0.6, dt=1e-3, output_interval=0.05,
                        integrator=fm.GeneralizedAlpha(compiled=c)) for c in (True, False)]
    assert np.abs(runs[0].q - runs[1].q).max() < 1e-10
    assert np.abs(runs[0].lam - runs[1].lam).max() < 1e-7 * np.abs(runs[1].lam).max()
    assert np.ptp(runs[0].q[:, 7]) > 0.1                      # the second arm really moved


def test_moves_are_smooth_pushes_that_start_and_stop_at_rest():
    """fm.Moves (scenario type "moves"): the positions of two pushes and a pull-back, each a
    cosine ramp; the rate and the acceleration against central differences of the value, the
    rate zero at every start and end (no impulse where a table's corners would have one)."""
    moves = fm.Moves([(0.0, 0.4, 0.025), (0.8, 1.2, 0.02), (1.3, 1.5, -0.005)])
    assert moves(0.0) == 0.0 and moves(0.6) == pytest.approx(0.025, abs=1e-15)
    assert moves(1.25) == pytest.approx(0.045) and moves(2.0) == pytest.approx(0.04)
    assert moves(0.2) == pytest.approx(0.0125)       # half way: half the push
    for t in (0.0, 0.4, 0.8, 1.2, 1.3, 1.5):
        assert moves.d1(t) == pytest.approx(0.0, abs=1e-15), t
    h = 1e-6
    for t in (0.05, 0.33, 0.9, 1.41):
        assert moves.d1(t) == pytest.approx((moves(t + h) - moves(t - h)) / (2 * h), rel=1e-6)
        assert moves.d2(t) == pytest.approx((moves.d1(t + h) - moves.d1(t - h)) / (2 * h),
                                            rel=1e-5)
    with pytest.raises(fm.ModelError, match="move 1 must end after it starts"):
        fm.Moves([(0.0, 0.4, 1.0), (0.5, 0.5, 1.0)])
    with pytest.raises(fm.ModelError, match="at least one move"):
        fm.Moves([])

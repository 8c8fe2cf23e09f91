"""Friction that sticks on the sliding joint (docs/design-notes.md "Friction that sticks: the
sliding joint"): a body held on a slope below the friction angle, sliding above it with
g (sin α − μ cos α), the stick–slip oscillator against its closed form, the exact tangent
against central differences, dissipation per step, bit-identical resume and the scenario key.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.optimize import curve_fit

import flexmbs as fm
from flexmbs.assembly import Assembly
from flexmbs.contact.laws import FRICTION_STICK
from tests.conftest import FULL

G = 9.81
#: stick–slip oscillator: mass, spring, belt speed, coefficients (ω = 10 rad/s)
M, K, V_BELT, MU_S, MU_K = 1.0, 100.0, 0.1, 0.4, 0.3
#: statics of a body hanging from the beam: its spin is held only by the constraint forces,
#: which the first iterate lacks (a mass-proportional stabiliser in the first increment)
STATIC = fm.StaticOptions(load_steps=2, stabilizer=1.0)
#: relative agreement of the oscillator's phases with the closed form
OSC_RTOL = 1e-2
#: agreement of the s row of the iteration matrix with central differences (relative to the row)
FD_RTOL = 1e-6


def rigid_track(model: fm.Model, start, end, n_elem: int, *, EA: float = 1e9) -> fm.Beam:
    """A straight beam with every nodal coordinate prescribed: a rigid track (|r′| = 1), so the
    closed forms of a body on a rigid guide hold exactly. EA only sets the default k_t."""
    beam = model.add_beam(fm.line(start, end, elements=n_elem),
                          section=fm.BeamStiffness(axial_stiffness=EA, bending_stiffness=1e6,
                                                   mass_per_length=1.0))
    for i in range(beam.n_nodes):
        model.prescribe(beam.node(i), range(6))
    return beam


def slope(alpha: float, friction, *, s0: float = 0.2, clamped: bool = True, hang: float = 0.0):
    """Body (0.5 kg) on a 2 m beam inclined by alpha (downhill = +s), gravity −z: a stiff beam
    clamped at both ends (EA 1e9, EI 1e6) or a rigid track. ``hang``: the centre of mass that
    far below the hole (a pendulum about the beam: statics then has no free spin)."""
    d = np.array([math.cos(alpha), 0.0, -math.sin(alpha)])
    model = fm.Model(gravity=(0, 0, -G))
    if clamped:
        beam = model.add_beam(fm.line((0, 0, 0), tuple(2.0 * d), elements=8),
                              section=fm.BeamStiffness(axial_stiffness=1e9, bending_stiffness=1e6,
                                                       mass_per_length=1.0))
        model.clamp(beam.first_node)
        model.clamp(beam.last_node)
    else:
        beam = rigid_track(model, (0, 0, 0), tuple(2.0 * d), 8)
    pose = beam.frame_at(s0).shifted((0.0, 0.0, -hang), local=True)
    body = model.add_rigid_body(mass=0.5, inertia=(1e-3, 2e-3, 2e-3), pose=pose)
    joint = model.add_joint(fm.SlidingJoint(beam, body, friction=friction,
                                            hole_point=(0.0, 0.0, hang)))
    return model, joint


def slide(res, joint) -> np.ndarray:
    return res.q[:, res.assembly.extra_dofs(joint)[0]]


# ------------------------------------------------------------------------------ the slope
def test_body_sticks_below_the_friction_angle_and_the_regularised_law_creeps():
    """tan α = 0.203 < μ = 0.3 on the stiff clamped beam, 11 s at dt = 10 ms: after the first
    second the stick law holds s within 1e-9 m. The regularised law (ε_v = 1e-3 m/s) on the same
    model creeps at its steady speed ε_v artanh(tan α/μ) = 0.8212 mm/s (closed form, 1e-3;
    measured: drift 2e-16 m stuck, creep 4e-6 off the closed form)."""
    alpha, mu = 0.2, 0.3
    for friction in (fm.Friction(mu=mu), fm.Friction(mu=mu, law="regularised", velocity=1e-3)):
        model, joint = slope(alpha, friction)
        res = fm.simulate(model, t_end=11.0, dt=1e-2, output_interval=0.1, record_energy=False)
        s = slide(res, joint)
        late = res.t >= 1.0
        drift = np.ptp(s[late])
        if friction.law == "stick":
            assert drift < 1e-9
            assert joint.stuck
        else:
            creep = np.polyfit(res.t[late], s[late], 1)[0]
            assert creep == pytest.approx(1e-3 * math.atanh(math.tan(alpha) / mu), rel=1e-3)
            assert drift > 5e-3


def test_static_coefficient_holds_between_the_kinetic_and_static_angles():
    """tan α = 0.309: μ = 0.2 alone lets it go (s grows by > 1 cm in 0.5 s), with μ_s = 0.4 the
    body started at rest in its static equilibrium stays (its cone is μ_s N while it sticks).
    (Released with the tangential spring unstretched, it would slip: the elastic overshoot
    reaches 2 m g sin α > μ_s N.)"""
    alpha = 0.3
    moved = []
    for friction in (fm.Friction(mu=0.2), fm.Friction(mu=0.2, mu_static=0.4)):
        model, joint = slope(alpha, friction, clamped=False, hang=0.05)
        res = fm.simulate(model, t_end=0.5, dt=1e-2, output_interval=0.1, record_energy=False,
                          initial_static=friction.mu_static is not None, static_options=STATIC)
        moved.append(np.ptp(slide(res, joint)))
    assert moved[0] > 1e-2
    assert moved[1] < 1e-8


def test_body_slides_above_the_friction_angle_with_the_coulomb_acceleration():
    """tan α = 0.42 > μ = 0.2: s'' = g (sin α − μ cos α) (quadratic fit over 0.2–0.6 s, stiff
    clamped beam, dt = 1 ms), 2e-3 relative."""
    alpha, mu = 0.4, 0.2
    model, joint = slope(alpha, fm.Friction(mu=mu))
    res = fm.simulate(model, t_end=0.6, dt=1e-3, output_interval=0.01, record_energy=False)
    s = slide(res, joint)
    sel = res.t >= 0.2
    acc = 2 * np.polyfit(res.t[sel], s[sel], 2)[0]
    exact = G * (math.sin(alpha) - mu * math.cos(alpha))
    assert acc == pytest.approx(exact, rel=2e-3)
    assert not joint.stuck


def test_static_solution_holds_the_body_on_the_slope():
    """solve_static with the anchor at s0 (rigid track, k_t = 1e4 N/m): the tangential spring
    carries the downhill weight, s − s0 = m g sin α / k_t (1e-9 relative)."""
    alpha, k_t = 0.2, 1e4
    model, joint = slope(alpha, fm.Friction(mu=0.3, stiffness=k_t), clamped=False, hang=0.05)
    asm = Assembly(model)
    st = fm.solve_static(asm, STATIC)
    s = st.q[asm.extra_dofs(joint)[0]]
    assert s - 0.2 == pytest.approx(0.5 * G * math.sin(alpha) / k_t, rel=1e-9)


# ------------------------------------------------------------------ the stick–slip oscillator
def oscillator(mu_s: float = MU_S, mu_k: float = MU_K, **friction):
    """Mass M on a belt moving at V_BELT, held by a spring K from the ground, seen in the belt's
    frame: a rigid horizontal track (the belt), the body sliding on it (s = its position on the
    belt, ṡ its speed relative to the belt) and the spring's far end on a second body moving
    at −V_BELT. Normal force M g. The spring starts unstretched, the body at rest on the belt."""
    model = fm.Model(gravity=(0, 0, -G))
    belt = rigid_track(model, (-3.0, 0, 0), (1.0, 0, 0), 8)
    body = model.add_rigid_body(mass=M, inertia=(1e-3, 1e-3, 1e-3), pose=belt.frame_at(3.5),
                                name="block")
    end = model.add_rigid_body(mass=1.0, inertia=(1.0, 1.0, 1.0), position=(0.0, 0.0, 0.0),
                               velocity=(-V_BELT, 0.0, 0.0), name="spring_end")
    model.prescribe(end, [0], fm.Ramp(start=0.0, end=1e3, value=-V_BELT * 1e3))
    model.prescribe(end, [1, 2])
    model.add_spring_damper(body, end, stiffness=K)
    joint = model.add_joint(fm.SlidingJoint(
        belt, body, friction=fm.Friction(mu=mu_k, mu_static=mu_s, **friction), name="block"))
    return model, joint


def run_oscillator(t_end: float, dt: float, **kw):
    """History of (t, u = spring elongation, ṡ, anchor, stuck) at every step."""
    model, joint = oscillator(**kw)
    rows: list[tuple[float, float, float]] = []
    res = fm.simulate(model, t_end=t_end, dt=dt, output_interval=dt, record_energy=False,
                      observer=lambda st: rows.append((joint.anchor, float(joint.stuck), st.t)))
    sd = res.assembly.extra_dofs(joint)[0]
    s, sdot = res.q[:, sd], res.v[:, sd]
    hist = np.array(rows)
    assert np.array_equal(hist[:, 2], res.t)
    u = (s - 3.5) + V_BELT * res.t         # body on the belt minus spring end: elongation
    return res.t, u, sdot, hist[:, 0], hist[:, 1], s, joint


def phases(t: np.ndarray, sdot: np.ndarray, tol: float = 1e-4) -> list[tuple[float, float, bool]]:
    """Intervals (start, end, stuck) where |ṡ| < tol (stuck) or not."""
    stuck = np.abs(sdot) < tol
    edges = np.flatnonzero(stuck[1:] != stuck[:-1]) + 1
    bounds = np.concatenate([[0], edges, [t.size - 1]])
    return [(t[a], t[b], bool(stuck[a])) for a, b in zip(bounds[:-1], bounds[1:], strict=True)]


@pytest.fixture(scope="module")
def stick_slip():
    """μ_s = 0.4 > μ_k = 0.3, k_t default (EA/L_e = 2e9 N/m), 2.6 s at dt = 2e-4 (3–4 cycles)."""
    return run_oscillator(2.6 if not FULL else 6.0, 2e-4)


def test_stick_phase_lasts_the_closed_form(stick_slip):
    """Stick phases after the first: 2 (μ_s − μ_k) m g / (k v_b) = 0.1962 s (1 %); the first
    one, from the unstretched spring, μ_s m g/(k v_b) = 0.3924 s."""
    t, u, sdot, *_ = stick_slip
    ph = phases(t, sdot)
    sticks = [b - a for a, b, stuck in ph if stuck and b < t[-1]]
    assert len(sticks) >= 3
    assert sticks[0] == pytest.approx(MU_S * M * G / (K * V_BELT), rel=OSC_RTOL)
    for d in sticks[1:]:
        assert d == pytest.approx(2 * (MU_S - MU_K) * M * G / (K * V_BELT), rel=OSC_RTOL)


def test_slip_phase_is_the_harmonic_arc_about_the_kinetic_equilibrium(stick_slip):
    """Each slip: u = x_e + A cos(ω t + φ) with x_e = μ_k m g/k, ω = √(k/m) (least-squares fit,
    1 %), lasting (π + 2 atan(v_b/(ω d)))/ω, d = (μ_s − μ_k) m g/k, and A = √(d² + (v_b/ω)²)."""
    t, u, sdot, *_ = stick_slip
    w = math.sqrt(K / M)
    xe, d = MU_K * M * G / K, (MU_S - MU_K) * M * G / K
    slips = [(a, b) for a, b, stuck in phases(t, sdot) if not stuck and b < t[-1] and a > 0]
    assert len(slips) >= 3
    for a, b in slips:
        assert b - a == pytest.approx((math.pi + 2 * math.atan(V_BELT / (w * d))) / w, rel=OSC_RTOL)
        sel = (t > a) & (t < b)
        p, _ = curve_fit(lambda tt, x0, amp, om, ph: x0 + amp * np.cos(om * tt + ph), t[sel] - a,
                         u[sel], p0=(xe, math.hypot(d, V_BELT / w), w, 0.0))
        assert p[0] == pytest.approx(xe, rel=OSC_RTOL)
        assert p[2] == pytest.approx(w, rel=OSC_RTOL)
        assert abs(p[1]) == pytest.approx(math.hypot(d, V_BELT / w), rel=OSC_RTOL)


def test_equal_coefficients_give_the_harmonic_limit_cycle():
    """μ_s = μ_k: after the first stick the motion is the harmonic of amplitude v_b √(m/k)
    about μ_k m g/k (extremes of u, 1 %); it never sticks for long again."""
    t, u, sdot, *_ = run_oscillator(1.5, 2e-4, mu_s=MU_K, mu_k=MU_K)
    xe, amp = MU_K * M * G / K, V_BELT * math.sqrt(M / K)
    after = t > MU_K * M * G / (K * V_BELT) + 0.05
    assert u[after].max() - xe == pytest.approx(amp, rel=OSC_RTOL)
    assert xe - u[after].min() == pytest.approx(amp, rel=OSC_RTOL)


def test_friction_dissipation_per_step_is_never_negative(stick_slip):
    """On the rigid track (|r′| = 1, c_t = 0) the friction force after step n is the spring's,
    F_n = −k_t (s_n − s_A,n). Per step, the work the body does on the contact minus the change
    of the tangential spring energy, D_n = −F_{n+1} Δs − (F²_{n+1} − F²_n)/(2 k_t), is the
    dissipation: ≥ 0 up to round-off at every step; over the run it is, within 1e-4, μ_k m g
    times the distance slipped (the spring energy is negligible; measured 1e-7)."""
    t, u, sdot, anchor, stuck, s, joint = stick_slip
    k_t = joint.friction_parameters()[3]
    assert k_t == pytest.approx(1e9 / 0.5)
    F = -k_t * (s - anchor)
    D = -F[1:] * np.diff(s) - (F[1:] ** 2 - F[:-1] ** 2) / (2 * k_t)
    work_scale = np.abs(F[1:] * np.diff(s)).max()
    assert D.min() >= -1e-12 * work_scale
    slipped = np.abs(np.diff(s))[stuck[1:] == 0.0].sum()
    assert D.sum() == pytest.approx(MU_K * M * G * slipped, rel=1e-4)
    assert np.any(stuck == 0.0) and np.any(stuck == 1.0)


# ------------------------------------------------------------------------ the exact tangent
def _fd_setup(law: str, variant: str, rng):
    """Stiff clamped slope, perturbed state, random multipliers with a clear normal part (N ≈ 5
    N), soft friction (k_t = 1e3 N/m, c_t = 2 N s/m) so that a difference step does not cross
    the cone."""
    friction = (fm.Friction(mu=0.3, mu_static=0.4, stiffness=1e3, damping=2.0) if law == "stick"
                else fm.Friction(mu=0.3, law="regularised", velocity=1e-2))
    d = np.array([math.cos(0.4), 0.0, -math.sin(0.4)])
    model = fm.Model(gravity=(0, 0, -G))
    beam = model.add_beam(fm.line((0, 0, 0), tuple(2.0 * d), elements=8),
                          section=fm.BeamStiffness(axial_stiffness=1e3, bending_stiffness=10.0,
                                                   mass_per_length=1.0))
    model.clamp(beam.first_node)
    model.clamp(beam.last_node)
    body = model.add_rigid_body(mass=0.5, inertia=(1e-3, 2e-3, 2e-3), pose=beam.frame_at(0.6))
    joint = model.add_joint(fm.SlidingJoint(beam, body, variant=variant, friction=friction,
                                            axial_force=fm.Sine(amplitude=3.0)))
    asm = Assembly(model)
    n, m = asm.n_coords, asm.n_mult
    q = asm.q_ref + 1e-3 * rng.standard_normal(n)
    v = 0.1 * rng.standard_normal(n)
    sd = asm.extra_dofs(joint)[0]
    v[sd] = 3e-3
    lam = rng.standard_normal(m)
    rows = asm.multiplier_rows(joint.constraints()[0])[:3]
    lam[rows] += np.array([1.0, -2.0, 4.0])
    return asm, joint, q, v, lam, sd


def _set_regime(asm, joint, q, v, lam, regime: str) -> None:
    """Anchor such that the trial force sticks, slips, or lies a hair (2e-3 ρ) inside or
    outside the cone: bisection on the anchor for the flip of the return map."""
    def sticks(sa: float) -> bool:
        joint.anchor = sa
        return joint.friction_force(asm, q, v, lam).sticking

    s = float(q[asm.extra_dofs(joint)[0]])
    lo, hi = s - 10.0, s + 10.0
    while not sticks(lo):            # bring lo into the cone: T(s_A) rises with s_A
        lo = 0.5 * (lo + hi)
    assert not sticks(hi)
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if sticks(mid) else (lo, mid)
    joint.anchor = hi
    rho = abs(joint.friction_force(asm, q, v, lam).force)
    k_t = joint.friction_parameters()[3]
    edge = 0.5 * (lo + hi)
    offset = {"stick": -0.5 * rho / k_t, "slip": 0.5 * rho / k_t,
              "inside": -2e-3 * rho / k_t, "outside": 2e-3 * rho / k_t}[regime]
    joint.anchor = edge + offset
    assert joint.friction_force(asm, q, v, lam).sticking == (regime in ("stick", "inside"))


@pytest.mark.parametrize("variant", ["cylindrical", "ring"])
@pytest.mark.parametrize(("law", "regime", "stuck"), [
    ("stick", "stick", True), ("stick", "slip", True), ("stick", "slip", False),
    ("stick", "inside", True), ("stick", "outside", True), ("stick", "outside", False),
    ("regularised", "", False)])
def test_friction_tangent_matches_central_differences(law, regime, stuck, variant, rng):
    """The row of s of the iteration matrix (K in q, C in v, the multiplier columns) equals
    central differences (h = 1e-7) of the compiled residual, in stick, in slip and a hair on
    either side of the cone; the whole matrix to the existing tolerance of the sliding tests."""
    asm, joint, q, v, lam, sd = _fd_setup(law, variant, rng)
    joint.stuck = stuck
    if law == "stick":
        _set_regime(asm, joint, q, v, lam, regime)
    n, m = asm.n_coords, asm.n_mult
    a = rng.standard_normal(n)
    t = 0.3

    def res(q_, v_, l_):
        rq, rl = np.zeros(n), np.zeros(m)
        asm.evaluate(q_, v_, a, l_, t, rq, rl)
        return np.concatenate([rq, rl])

    rq, rl = np.zeros(n), np.zeros(m)
    asm.evaluate(q, v, a, lam, t, rq, rl, matrix=(0.0, 0.0, 1.0))
    A = asm.matrix.toarray()
    asm.evaluate(q, v, a, lam, t, rq, rl, matrix=(0.0, 1.0, 0.0))
    C = asm.matrix.toarray()[:n, :n]
    h = 1e-7
    K_fd, C_fd, L_fd = np.zeros((n + m, n)), np.zeros((n, n)), np.zeros((n, m))
    for j in range(n):
        e = np.zeros(n)
        e[j] = h
        K_fd[:, j] = (res(q + e, v, lam) - res(q - e, v, lam)) / (2 * h)
        C_fd[:, j] = (res(q, v + e, lam)[:n] - res(q, v - e, lam)[:n]) / (2 * h)
    for j in range(m):
        e = np.zeros(m)
        e[j] = h
        L_fd[:, j] = (res(q, v, lam + e)[:n] - res(q, v, lam - e)[:n]) / (2 * h)
    row = np.concatenate([K_fd[sd], C_fd[sd], L_fd[sd]])
    got = np.concatenate([A[sd, :n], C[sd], A[sd, n:]])
    assert np.abs(got - row).max() < FD_RTOL * np.abs(row).max()
    assert np.abs(A[:, :n] - K_fd).max() < 1e-6 * np.abs(K_fd).max()
    assert np.abs(A[:n, n:] - L_fd).max() < 1e-6 * np.abs(L_fd).max()


# ------------------------------------------------------------------------ state and resume
def test_resume_with_the_anchor_in_flight_is_bit_identical(tmp_path):
    """The oscillator run 0.8 s straight, and stopped at 0.5 s (slipping: the anchor moves every
    step) then resumed: final q, v, λ and the anchor bit for bit. A resumed run with another
    friction law is refused."""
    kw = dict(dt=1e-3, output_interval=0.05, record_energy=False, write_vtu=False)
    model, joint = oscillator()
    full = fm.simulate(model, t_end=0.8, out=tmp_path / "full", **kw)
    anchor_full = joint.anchor
    model, joint = oscillator()
    fm.simulate(model, t_end=0.5, out=tmp_path / "part", **kw)
    assert not joint.stuck and joint.anchor != 3.5
    model, joint = oscillator()
    part = fm.simulate(model, t_end=0.8, out=tmp_path / "part", resume=True, **kw)
    for k in ("q", "v", "lam"):
        np.testing.assert_array_equal(getattr(part, k)[-1], getattr(full, k)[-1])
    assert joint.anchor == anchor_full
    state = joint.get_state()
    assert state["friction"][0] == FRICTION_STICK
    model, joint = oscillator(mu_k=0.25)
    with pytest.raises(fm.ScenarioError, match=r"cannot resume: joint 'block': the checkpoint was "
                       r"written with friction \{law = \"stick\", mu = 0.3.*now has \{law = \"stick\", "
                       r"mu = 0.25.*run without --resume"):
        fm.simulate(model, t_end=0.8, out=tmp_path / "part", resume=True, **kw)


def test_state_round_trips_and_older_checkpoints_are_accepted():
    model, joint = oscillator()
    Assembly(model)
    joint.anchor, joint.stuck = 3.4999999999999996, False
    state = joint.get_state()
    joint.anchor, joint.stuck = 0.0, True
    joint.set_state(json.loads(json.dumps(state)))
    assert joint.anchor == 3.4999999999999996 and not joint.stuck
    joint.set_state({"element": 3})           # written before friction had state
    assert joint.element == 3 and joint.anchor == 3.4999999999999996


# ------------------------------------------------------------------------------ scenario
SCENARIO = """
name = "belt"
[simulation]
t_end = 0.01
dt = 1e-3
gravity = [0.0, 0.0, -9.81]

[[beams]]
name = "rail"
geometry = { line = { start = [0.0, 0.0, 0.0], end = [2.0, 0.0, 0.0] } }
elements = 4
axial_stiffness = 1e8
bending_stiffness = 1e6
mass_per_length = 1.0

[[rigid_bodies]]
name = "sleeve"
mass = 0.5
inertia = [1e-3, 2e-3, 2e-3]
pose = { on_beam = "rail", s = 0.5 }

[[constraints]]
type = "clamp"
beam = "rail"
node = "first"

[[joints]]
name = "slider"
type = "sliding"
beam = "rail"
body = "sleeve"
FRICTION
"""


@pytest.mark.parametrize(("text", "expected", "params"), [
    ("friction = { mu = 0.3, mu_static = 0.4, stiffness = 1e6, damping = 2.0 }",
     fm.Friction(mu=0.3, mu_static=0.4, stiffness=1e6, damping=2.0),
     [FRICTION_STICK, 0.3, 0.4, 1e6, 2.0, 1e-3]),
    ("friction = 0.3", fm.Friction(mu=0.3), [FRICTION_STICK, 0.3, 0.3, 1e8 / 0.5, 0.0, 1e-3]),
    ("friction = 0.3\nfriction_velocity = 2e-3",
     fm.Friction(mu=0.3, law="regularised", velocity=2e-3), [1.0, 0.3, 0.3, 2e8, 0.0, 2e-3]),
])
def test_scenario_friction_reaches_the_joint(tmp_path, text, expected, params):
    """``friction`` of a sliding joint: a table, a number (stick law, k_t = EA/L_e = 1e8/0.5) or
    a number with friction_velocity (regularised); the packed kernel parameters follow."""
    from flexmbs.io.scenario import load_scenario

    f = tmp_path / "belt.toml"
    f.write_text(SCENARIO.replace("FRICTION", text))
    sc = load_scenario(f)
    joint = next(j for j in sc.model.interactions if isinstance(j, fm.SlidingJoint))
    assert joint.friction == expected
    asm = Assembly(sc.model)
    np.testing.assert_array_equal(asm.system.sliding.friction[0], params)

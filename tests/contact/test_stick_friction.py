"""Friction that sticks on the clearance joint (issue 36): the return mapping's own properties,
a sleeve held on an incline below the friction angle (dynamics and statics), the sliding
acceleration above it, history as state (resume bit for bit, a changed law refused)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.assembly import Assembly
from flexmbs.contact.laws import FRICTION_STICK, tangential_force

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
G = 9.81
M_SLEEVE = 0.1
R_BEAM = 5e-3


# ---------------------------------------------------------------------------------------------
# the law
def test_return_mapping_never_creates_energy_and_stays_in_the_cone():
    """Random relative increments and normal forces through the stick law (kernel): the force
    never leaves the cone μ f_N, it is on the cone exactly when slipping, and in every step the
    work done against the contact, −F_{n+1}·Δx, is at least the increase of the tangential
    spring's energy ½|F|²/k_t (the dissipation is never negative)."""
    rng = np.random.default_rng(7)
    k_t, mu, mu_s = 2e5, 0.3, 0.45
    fric = np.array([FRICTION_STICK, mu, mu_s, k_t, 0.0, 1e-3])
    d = np.zeros(3)
    stuck = 1.0
    F, dF_dd, dF_dv, dF_dfn, d_new = (np.empty(3), np.empty((3, 3)), np.empty((3, 3)),
                                      np.empty(3), np.empty(3))
    slips = sticks = 0
    for _ in range(4000):
        f_n = float(rng.uniform(0.0, 20.0))
        step = rng.normal(scale=float(rng.choice([1e-6, 1e-5, 1e-4])), size=3)
        step[2] = 0.0                        # in the tangent plane (normal = z)
        trial = d + step
        stuck_now = tangential_force(fric, stuck, f_n, trial, np.zeros(3), F, dF_dd, dF_dv,
                                     dF_dfn, d_new)
        radius = (mu_s if stuck > 0.5 else mu) * f_n
        assert np.linalg.norm(F) <= radius * (1 + 1e-12) + 1e-300
        if stuck_now:
            sticks += 1
            np.testing.assert_allclose(F, -k_t * trial, rtol=1e-14)
        else:
            slips += 1
            assert np.linalg.norm(F) == pytest.approx(radius, rel=1e-12)
            np.testing.assert_allclose(np.cross(F, trial), 0.0, atol=1e-12 * radius * 1e-4)
            assert F @ trial < 0.0
        work = -F @ step
        stored = 0.5 * k_t * (d_new @ d_new - d @ d)
        assert work - stored >= -1e-12 * max(abs(work), 1e-30)
        d, stuck = d_new.copy(), stuck_now
    assert slips > 500 and sticks > 500


# ---------------------------------------------------------------------------------------------
# a sleeve on an incline
def _incline(alpha_deg: float, friction: fm.Friction | None, *, sections: int = 3,
             damping: float = 20.0) -> tuple[fm.Model, fm.SlidingClearanceJoint]:
    """A straight beam clamped at both ends, inclined by alpha in the x-z plane, so stiff and
    light that it neither sags nor rings (a ringing support makes a sleeve walk: its normal
    force drops to zero every cycle), and a 0.1 kg sleeve with 0.5 mm radial clearance resting
    on it at mid-length under gravity."""
    a = math.radians(alpha_deg)
    t = np.array([math.cos(a), 0.0, math.sin(a)])
    model = fm.Model(gravity=(0.0, 0.0, -G))
    beam = model.add_beam(fm.line(tuple(-0.5 * t), tuple(0.5 * t), elements=4), name="rail",
                          section=fm.CircularSection(R_BEAM),
                          material=fm.Material(E=2.1e11, rho=7800.0))
    beam.stiffness = fm.BeamStiffness(axial_stiffness=1e9, bending_stiffness=1e5,
                                      mass_per_length=0.01, radius=R_BEAM)
    model.clamp(beam.first_node)
    model.clamp(beam.last_node)
    sleeve = model.add_rigid_body(mass=M_SLEEVE, inertia=(1e-5, 2e-5, 2e-5),
                                  pose=beam.frame_at(0.5), name="sleeve")
    joint = fm.SlidingClearanceJoint(
        beam, sleeve, hole=fm.CircleHole(R_BEAM + 5e-4, 0.04, sections),
        contact=fm.LinearPenalty(stiffness=1e6, damping=damping), friction=friction)
    joint.rest_on_beam((0.0, 0.0, -1.0))
    model.add_joint(joint)
    return model, joint


#: the sleeve starts touching the beam without force: the first increments need the stabiliser
STATIC = fm.StaticOptions(load_steps=4, stabilizer=100.0)


def _slide(res: fm.Result, joint: fm.SlidingClearanceJoint) -> np.ndarray:
    return np.array([joint.slide_coordinate(q) for q in res.q])


@pytest.mark.parametrize("law", ["stick", "regularised"])
def test_sleeve_below_the_friction_angle_stays_put(law):
    """tan α = 0.2 < μ = 0.3: with the stick law the sleeve settles and then moves less than
    1e-9 m over 10 s; the regularised law (ε_v = 1 mm/s) lets it creep, which is the contrast
    the issue measured on Example 1 (here: more than 1e-4 m over the same 10 s). The stick
    run starts from the static solution (which only the stick law has), the regularised one
    from the sleeve touching the beam."""
    alpha = math.degrees(math.atan(0.2))
    model, joint = _incline(alpha, fm.Friction(mu=0.3, law=law))
    res = fm.simulate(model, t_end=10.5, dt=2e-3, output_interval=0.1, record_energy=False,
                      initial_static=law == "stick", static_options=STATIC)
    s = _slide(res, joint)
    after = s[res.t >= 0.5 - 1e-9]
    drift = np.abs(after - after[0]).max()
    if law == "stick":
        assert drift < 1e-9, drift
    else:
        assert drift > 1e-4, drift


def test_sleeve_above_the_friction_angle_slides_with_the_coulomb_acceleration():
    """tan α = 0.577 > μ = 0.3: the sleeve slides down with a = g(sin α − μ cos α) (to 2e-3;
    fit of s(t) = s₀ + v₀t + ½at² after the first contact transient)."""
    mu = 0.3
    model, joint = _incline(30.0, fm.Friction(mu=mu))
    res = fm.simulate(model, t_end=0.35, dt=5e-4, output_interval=0.01, record_energy=False)
    s = _slide(res, joint)
    keep = res.t >= 0.05 - 1e-9
    coef = np.polyfit(res.t[keep], s[keep], 2)
    a_num = 2.0 * coef[0]
    a_ref = -G * (math.sin(math.radians(30.0)) - mu * math.cos(math.radians(30.0)))
    assert a_num == pytest.approx(a_ref, rel=2e-3)


def test_static_solution_holds_below_the_friction_angle_and_none_exists_above():
    """solve_static holds the sleeve on the slope by stick: it moves down the slope by the
    elastic stick displacement m g sin α / (n k_t) of its n contacts (within 15 %: the beam's
    axial compliance and the sleeve's pitch take a little); above the friction angle there is
    no static solution and the solve says so."""
    alpha = math.degrees(math.atan(0.2))
    model, joint = _incline(alpha, fm.Friction(mu=0.3))
    asm = Assembly(model)
    s0 = joint.slide_coordinate(asm.q_ref)
    st = fm.solve_static(asm, STATIC)
    moved = joint.slide_coordinate(st.q) - s0
    contacts = joint.output(asm, st.q, np.zeros(asm.n_coords), st.lam, 0.0)
    k_total = len(contacts) * joint.friction_stiffness()
    expected = -M_SLEEVE * G * math.sin(math.radians(alpha)) / k_total
    assert len(contacts) >= 2
    assert moved == pytest.approx(expected, rel=0.15)
    # the contacts stick and their friction forces carry the weight's pull along the slope
    slope = np.array([math.cos(math.radians(alpha)), 0.0, math.sin(math.radians(alpha))])
    assert all(c["stick"] == 1.0 for c in contacts)
    pull = sum(float(c["tangential_force"] @ slope) for c in contacts)
    assert pull == pytest.approx(M_SLEEVE * G * math.sin(math.radians(alpha)), rel=1e-6)
    model, joint = _incline(35.0, fm.Friction(mu=0.3))
    with pytest.raises(fm.ConvergenceError):
        fm.solve_static(Assembly(model), fm.StaticOptions(load_steps=4, stabilizer=100.0,
                                                          min_increment=0.05))


def test_a_run_resumed_with_anchors_in_flight_is_bit_identical(tmp_path):
    """The anchors and stick states are state: a run stopped while the sleeve slides and its
    contacts' anchors move resumes bit for bit; a changed friction law is refused."""
    def run(t_end: float, out, resume: bool = False, mu: float = 0.3) -> fm.Result:
        model, _ = _incline(18.0, fm.Friction(mu=mu, mu_static=0.35))
        return fm.simulate(model, t_end=t_end, dt=1e-3, output_interval=0.02, out=out,
                           resume=resume, record_energy=False, write_vtu=False)

    full = run(0.2, tmp_path / "full")
    run(0.1, tmp_path / "part")
    resumed = run(0.2, tmp_path / "part", resume=True)
    np.testing.assert_array_equal(resumed.q[-1], full.q[-1])
    np.testing.assert_array_equal(resumed.v[-1], full.v[-1])
    with pytest.raises(fm.ScenarioError, match=r"cannot resume: joint .* friction \{law = \"stick\", "
                                               r"mu = 0.3, mu_static = 0.35.*mu = 0.25"):
        run(0.3, tmp_path / "part", resume=True, mu=0.25)


def test_compiled_and_python_contact_paths_agree_with_friction_that_sticks():
    """The per-contact Python path (frozen-point tangent) carries the same history as the
    compiled one: the same run through both agrees to Newton's tolerance."""
    out = []
    for tangent in ("exact", "frozen_point"):
        model, joint = _incline(18.0, fm.Friction(mu=0.3, mu_static=0.35))
        joint.tangent = tangent
        res = fm.simulate(model, t_end=0.1, dt=1e-3, output_interval=0.05, record_energy=False)
        out.append(_slide(res, joint))
    np.testing.assert_allclose(out[0], out[1], atol=1e-9)


@pytest.mark.parametrize("law", ["stick", "regularised"])
def test_example1_sleeve_stops_and_stays_with_friction_that_sticks(law):
    """Example 1 with μ = 0.3 (the rail given a little structural damping, 1e-3 s: about 4 %
    of critical on its first mode with the sleeve). With the stick law the sleeve stops near
    −4.5° by 1.5 s and then moves less than 1e-6 m over 2 s (measured: 2.6e-7 m while the
    rail's ringing decays, then below 1e-9 m); the regularised law (ε_v = 1 mm/s) creeps at
    about 0.27 mm/s (the issue measured 0.28 mm/s on the undamped rail). On the undamped rail
    the ringing rail itself walks a stuck sleeve: its normal force swings between 0.45 and 1.5
    m g about every 75 ms (see docs/design-notes.md)."""
    from flexmbs.io.scenario import load_scenario

    over = ["joints.sleeve.contact.friction=0.3", "beams.rail.damping=1e-3"]
    if law == "regularised":
        over.append("joints.sleeve.contact.friction_velocity=1e-3")
    sc = load_scenario(EXAMPLES / "curved_beam_sleeve.toml", overrides=over)
    (joint,) = sc.model.interactions
    res = fm.simulate(sc.model, t_end=3.5, dt=sc.simulation.dt,
                      integrator=sc.integrator_options(), output_interval=0.1,
                      record_energy=False)
    s = _slide(res, joint)
    late = s[res.t >= 1.5 - 1e-9]
    lowest = math.pi / 4
    assert math.degrees((late[0] - lowest) / 1.0) == pytest.approx(-4.5, abs=0.2)
    if law == "stick":
        assert np.abs(late - late[0]).max() < 1e-6
    else:
        speed = (late[-1] - late[0]) / 2.0
        assert 1e-4 < speed < 1e-3


def test_friction_keys_reach_the_joint_and_bad_ones_are_named():
    """``contact.friction`` as a coefficient (stick law), as a table, and the old form with
    ``friction_velocity`` (regularised); wrong keys and values are one-line errors naming
    the key."""
    from flexmbs.io.scenario import load_scenario

    def joint(*over: str) -> fm.SlidingClearanceJoint:
        sc = load_scenario(EXAMPLES / "curved_beam_sleeve.toml",
                           overrides=[f"joints.sleeve.contact.{o}" for o in over])
        return sc.model.interactions[0]

    assert joint("friction=0.3").friction == fm.Friction(mu=0.3)
    assert joint("friction=0.3").friction_stiffness() == 1e6      # the linear law's stiffness
    j = joint("friction={ mu = 0.3, mu_static = 0.4, stiffness = 2e5, damping = 3.0 }")
    assert j.friction == fm.Friction(mu=0.3, mu_static=0.4, stiffness=2e5, damping=3.0)
    np.testing.assert_array_equal(j.friction_parameters(),
                                  [FRICTION_STICK, 0.3, 0.4, 2e5, 3.0, 1e-3])
    assert joint("friction=0.3", "friction_velocity=2e-3").friction == fm.Friction(
        mu=0.3, law="regularised", velocity=2e-3)
    assert joint("friction=0.0").friction is None
    for bad, message in [
            ("friction={ mu = 0.3, velocity = 1e-3 }", r"friction\.velocity: belongs to law"),
            ("friction={ mu = 0.3, mu_static = 0.2 }", r"friction\.mu_static: expected a static"),
            ("friction={ mu = 0.3, law = \"sticky\" }", r"friction\.law: unknown friction law"),
            ("friction={ mu = 0.3, law = \"regularised\", stiffness = 1e5 }",
             r"friction\.stiffness: belongs to law = \"stick\""),
            ("friction={ mu = 0.3, stifness = 1e5 }", r"did you mean 'stiffness'"),
            ("friction={ mu = -0.3 }", r"friction\.mu: expected a number >= 0")]:
        with pytest.raises(fm.ScenarioError, match=message):
            joint(bad)
    with pytest.raises(fm.ScenarioError, match=r"friction_velocity: with a friction table"):
        joint("friction={ mu = 0.3 }", "friction_velocity=1e-3")


def test_hertz_contact_gets_its_tangent_stiffness_at_one_percent_of_the_clearance():
    """The default tangential stiffness of a power law: ∂f_N/∂δ = nKδ^(n−1) at δ = 1 % of the
    radial clearance."""
    model, joint = _incline(10.0, fm.Friction(mu=0.3))
    joint.contact = fm.Hertz(stiffness=1e9, exponent=1.5)
    delta = 0.01 * 5e-4
    assert joint.friction_stiffness() == pytest.approx(1.5 * 1e9 * delta ** 0.5, rel=1e-12)

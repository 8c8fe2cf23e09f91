"""Sliding joint without clearance (Sugiyama, Escalona & Shabana 2003): Jacobians, element
crossing, analytic motions on rigid-like tracks."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.special import ellipk

import flexmbs as fm
from flexmbs.assembly import Assembly


def _inclined(alpha: float, *, friction: float = 0.0, friction_velocity: float | None = None,
              variant: str = "cylindrical", axial_force=None, n_elem: int = 8):
    L = 2.0
    d = np.array([np.cos(alpha), 0.0, -np.sin(alpha)])
    model = fm.Model(gravity=(0, 0, -9.81))
    beam = model.add_beam(fm.line((0, 0, 0), tuple(L * d), elements=n_elem),
                          section=fm.BeamStiffness(axial_stiffness=1e9, bending_stiffness=1e6,
                                                   mass_per_length=1.0))
    model.clamp(beam.first_node)
    model.clamp(beam.last_node)
    body = model.add_rigid_body(mass=0.5, inertia=(1e-3, 2e-3, 2e-3), pose=beam.frame_at(0.2))
    joint = model.add_joint(fm.SlidingJoint(beam, body, variant=variant, friction=friction,
                                            friction_velocity=friction_velocity,
                                            axial_force=axial_force))
    return model, beam, body, joint


@pytest.mark.parametrize("variant", ["cylindrical", "ring"])
def test_sliding_jacobian_matches_finite_differences(variant, rng):
    """Assembled residual derivative in q (including s and the multipliers' geometric terms)
    and in v, at a perturbed state with random multipliers and a prescribed axial force:
    exact tangent, so FD error level (1e-6 relative)."""
    model, beam, body, joint = _inclined(0.4, variant=variant, axial_force=fm.Sine(amplitude=3.0))
    asm = Assembly(model)
    n, m = asm.n_coords, asm.n_mult
    q = asm.q_ref + 1e-3 * rng.standard_normal(n)
    v = rng.standard_normal(n)
    a = rng.standard_normal(n)
    lam = rng.standard_normal(m)
    t = 0.3

    def res(q_, v_):
        rq, rl = np.zeros(n), np.zeros(m)
        asm.evaluate(q_, v_, a, lam, t, rq, rl)
        return np.concatenate([rq, rl])

    rq, rl = np.zeros(n), np.zeros(m)
    asm.evaluate(q, v, a, lam, t, rq, rl, matrix=(0.0, 1.0, 0.0))
    C = asm.matrix.toarray()[:n, :n]
    asm.evaluate(q, v, a, lam, t, rq, rl, matrix=(0.0, 0.0, 1.0))
    A = asm.matrix.toarray()
    h = 1e-6
    K_fd = np.zeros((n + m, n))
    C_fd = np.zeros((n, n))
    for j in range(n):
        e = np.zeros(n)
        e[j] = h
        K_fd[:, j] = (res(q + e, v) - res(q - e, v)) / (2 * h)
        C_fd[:, j] = (res(q, v + e)[:n] - res(q, v - e)[:n]) / (2 * h)
    assert np.abs(A[:, :n] - K_fd).max() < 1e-6 * np.abs(K_fd).max()
    assert np.abs(C - C_fd).max() < 1e-6 * max(np.abs(C_fd).max(), 1.0)
    # multiplier columns are the transposed constraint Jacobian (no friction here)
    assert np.allclose(A[:n, n:], A[n:, :n].T)


@pytest.mark.parametrize("friction", [0.0, 0.3])
def test_a_rings_body_has_no_matrix_entries_with_the_beam(friction):
    """The ring's Hessian couples the body only with itself: the reserved pattern has no
    body-beam or body-s entries (so a fixed eyelet's body stays out of the border of the
    factorisation, issue 37), while the cylindrical joint's alignment rows need them. The
    values stay exact: test_sliding_jacobian_matches_finite_differences (ring) and the
    friction tangent tests run on this pattern."""
    for variant, coupled in (("ring", False), ("cylindrical", True)):
        model, beam, body, joint = _inclined(0.4, variant=variant, friction=friction)
        asm = Assembly(model)
        bd = asm.body_dofs(body)
        others = np.setdiff1d(np.arange(asm.n_coords), bd)
        present = asm.positions_present(bd, others) >= 0
        assert present.any() == coupled, variant
        s_dof = asm.extra_dofs(joint)[0]
        assert (asm.positions_present(np.array([s_dof]), others) >= 0).sum() > 12   # s: beam


def test_frictionless_slide_accelerates_with_g_sin_alpha_across_elements():
    """Stiff straight beam inclined by alpha: s(t) = s0 + g sin(alpha) t^2 / 2 while crossing
    elements (L_e = 0.25 m, s from 0.2 to ~0.99). Beam compliance and the time
    discretisation (O(h^2)) keep the error below 1e-5 relative."""
    alpha = 0.3
    model, beam, body, joint = _inclined(alpha)
    res = fm.simulate(model, t_end=0.7, dt=1e-3, output_interval=0.05, record_energy=False)
    s = res.q[:, res.assembly.extra_dofs(joint)[0]]
    expected = 0.2 + 0.5 * 9.81 * np.sin(alpha) * res.t**2
    assert joint.element >= 3
    assert np.abs(s - expected).max() < 1e-5 * expected.max()


def test_friction_follows_regularised_coulomb():
    """With Coulomb friction mu = 0.2 (regularisation 1e-3 m/s) the sleeve slides with
    g (sin alpha - mu cos alpha) once it moves; the regularisation adds a velocity lag of order
    eps_v, so compare the acceleration from a quadratic fit over 0.2-0.6 s (1e-3 relative)."""
    alpha, mu = 0.4, 0.2
    model, beam, body, joint = _inclined(alpha, friction=mu, friction_velocity=1e-3)
    res = fm.simulate(model, t_end=0.6, dt=1e-3, output_interval=0.01, record_energy=False)
    s = res.q[:, res.assembly.extra_dofs(joint)[0]]
    sel = res.t >= 0.2
    acc = 2 * np.polyfit(res.t[sel], s[sel], 2)[0]
    assert acc == pytest.approx(9.81 * (np.sin(alpha) - mu * np.cos(alpha)), rel=1e-3)


def test_axial_force_on_the_ring():
    """Horizontal beam, no gravity: a constant axial force F on the body gives s'' = F/m."""
    model, beam, body, joint = _inclined(0.0, variant="ring", axial_force=2.0)
    model.gravity[:] = 0.0
    res = fm.simulate(model, t_end=0.3, dt=1e-3, output_interval=0.05, record_energy=False)
    s = res.q[:, res.assembly.extra_dofs(joint)[0]]
    assert np.abs(s - (0.2 + 0.5 * (2.0 / 0.5) * res.t**2)).max() < 1e-6


def _ring_pushed_along(tmp_path, follow: bool, t_end: float, *, resume: bool = False):
    """The ring of test_axial_force_on_the_ring on a beam of 32 elements (6.25 cm): it slides
    over about three elements in 0.3 s; ``follow``: the compiled loop's plan follows it
    (forced: alone on its beam the fixed plan is the cheaper one), else the fixed plan; full
    Newton (a fresh matrix at every iteration: the joint's elements are checked at each)."""
    import flexmbs.solvers.generalized_alpha as ga

    model, beam, body, joint = _inclined(0.0, variant="ring", axial_force=2.0, n_elem=32)
    model.gravity[:] = 0.0
    ratio = ga.FOLLOW_COST_RATIO
    ga.FOLLOW_COST_RATIO = np.inf if follow else 0.0
    try:
        res = fm.simulate(model, t_end=t_end, dt=1e-3, output_interval=0.05,
                          record_energy=False, out=tmp_path / "run", resume=resume,
                          integrator=fm.GeneralizedAlpha(
                              newton=fm.NewtonOptions(modified=False)))
    finally:
        ga.FOLLOW_COST_RATIO = ratio
    return res, joint


def test_a_plan_that_follows_the_ring_gives_the_same_motion(tmp_path):
    """The compiled loop's factorisation planned on the ring's current elements only
    (issue 37: many rings on a beam stay out of the dense border): the slide coordinate
    keeps s'' = F/m, the run equals the fixed plan's to round-off, the plan was made again as
    the ring moved on (ERR_OFF_PLAN from the Jacobian), and afterwards every plan holds the
    whole beam again."""
    follow, joint = _ring_pushed_along(tmp_path / "follow", True, 0.3)
    fixed, _ = _ring_pushed_along(tmp_path / "fixed", False, 0.3)
    s = follow.q[:, follow.assembly.extra_dofs(joint)[0]]
    assert np.abs(s - (0.2 + 0.5 * (2.0 / 0.5) * follow.t**2)).max() < 1e-6
    assert s[-1] > 0.2 + 2.5 * 2.0 / 32                   # across three element ends
    assert follow.stats.replans >= 1 and fixed.stats.replans == 0
    assert follow.stats.rejected_steps == fixed.stats.rejected_steps == 0
    np.testing.assert_allclose(follow.q, fixed.q, rtol=0, atol=1e-12)
    part = follow.assembly.system.sliding
    assert part.window[0, 0] == 0 and part.window[0, 1] == 32


def test_a_resumed_run_follows_the_ring_with_the_same_plan(tmp_path):
    """The plan's windows travel in the checkpoint: stopped at 0.15 s and resumed to 0.3 s,
    the run that follows the ring equals the uninterrupted one bit for bit."""
    full, _ = _ring_pushed_along(tmp_path / "full", True, 0.3)
    _ring_pushed_along(tmp_path / "part", True, 0.15)
    part, _ = _ring_pushed_along(tmp_path / "part", True, 0.3, resume=True)
    np.testing.assert_array_equal(part.q[-1], full.q[-1])
    np.testing.assert_array_equal(part.lam[-1], full.lam[-1])


@pytest.mark.parametrize("element", ["ancf_cable", "ancf_rod14"])
def test_a_following_plan_drops_exactly_the_entries_outside_the_windows(element, rng):
    """The stored positions a plan following the sliding joints reads (one vectorised pass):
    all but each joint's slide coordinate and multipliers against its beam's coordinates
    outside the elements of its window, by their definition (the beam's coordinates minus
    those of the window's elements; a rod's twists are in no window), for three rings and a
    sleeve on one beam and a ring on a second, at random windows."""
    model = fm.Model(gravity=(0, 0, -9.81))
    stiffness = fm.BeamStiffness(axial_stiffness=1e9, bending_stiffness=1e6, mass_per_length=1.0,
                                 torsional_stiffness=1e6)
    beams = [model.add_beam(fm.line((0, y, 0), (2.0, y, 0), elements=n), section=stiffness,
                            element=element) for y, n in ((0.0, 20), (0.5, 12))]
    for beam in beams:
        model.clamp(beam.first_node)
    for k, (beam, s, variant) in enumerate([(beams[0], 0.3, "ring"), (beams[0], 0.9, "ring"),
                                            (beams[0], 1.5, "cylindrical"), (beams[0], 1.7, "ring"),
                                            (beams[1], 1.0, "ring")]):
        body = model.add_rigid_body(mass=0.5, inertia=(1e-3, 2e-3, 2e-3), pose=beam.frame_at(s),
                                    name=f"b{k}")
        model.add_joint(fm.SlidingJoint(beam, body, variant=variant, name=f"j{k}"))
    asm = Assembly(model)
    A = asm.matrix
    cols = np.repeat(np.arange(asm.n_total), np.diff(A.indptr))
    rows = A.indices
    for _ in range(5):
        windows = []
        expected = np.ones(A.nnz, bool)
        for joint in asm.joint_lists["sliding"]:
            g = joint.geometry
            lo = int(rng.integers(0, g.elem_dofs.shape[0]))
            hi = int(rng.integers(lo + 1, g.elem_dofs.shape[0] + 1))
            windows.append((lo, hi))
            lam = asm.multiplier_rows(joint.constraints()[0])
            own = np.concatenate([[g.s_dof], asm.n_coords + lam[lam >= 0]])
            outside = np.setdiff1d(g.beam_dofs, g.elem_dofs[lo:hi])
            expected &= ~((np.isin(rows, own) & np.isin(cols, outside))
                          | (np.isin(cols, own) & np.isin(rows, outside)))
        keep = asm._window_entries(np.array(windows, np.int64))
        assert (~expected).sum() > 0
        np.testing.assert_array_equal(keep, expected)


def test_sleeve_on_stiff_arc_swings_with_rigid_track_period():
    """docs/theory.md §III.9, rigid-track limit: sleeve (m = 0.21441 kg, J = 4.098e-5)
    released at phi0 = -30 deg on a 90-deg arc of radius 1 m (E x 1000, 16 elements):
    (m rho^2 + J) phi'' + m g rho sin(phi) = 0, T(30 deg) = T0 (2/pi) K(sin 15 deg) = 2.04118 s.
    We measure the time between the first two passages through the lowest point (T/2); the
    discretisation (h = 1e-3, period error O((omega h)^2) ~ 1e-5) and the beam's residual
    compliance allow 5e-4 relative."""
    m, J, rho, g = 0.21441, 4.098e-5, 1.0, 9.81
    model = fm.Model(gravity=(0, 0, -g))
    c45 = np.sqrt(0.5)
    arc = fm.arc((0, 0, rho), rho, (-c45 * rho, 0, rho - c45 * rho), np.pi / 2, normal=(0, -1, 0),
                 elements=16)
    rail = model.add_beam(arc, section=fm.CircularSection(2e-3),
                          material=fm.Material(E=2.1e14, rho=7800), name="rail")
    model.clamp(rail.first_node)
    model.clamp(rail.last_node)
    s0 = np.pi / 4 - np.pi / 6
    sleeve = model.add_rigid_body(mass=m, inertia=(2.479e-5, J, J), pose=rail.frame_at(s0),
                                  name="sleeve")
    joint = model.add_joint(fm.SlidingJoint(rail, sleeve))
    res = fm.simulate(model, t_end=1.7, dt=1e-3, output_interval=1e-3, record_energy=False)
    phi = res.q[:, res.assembly.extra_dofs(joint)[0]] - np.pi / 4
    i = np.flatnonzero(np.sign(phi[:-1]) != np.sign(phi[1:]))
    tc = res.t[i] - phi[i] * (res.t[i + 1] - res.t[i]) / (phi[i + 1] - phi[i])
    T0 = 2 * np.pi * np.sqrt((m * rho**2 + J) / (m * g * rho))
    T = T0 * 2 / np.pi * ellipk(np.sin(np.pi / 12) ** 2)
    assert pytest.approx(2.04118, abs=1e-5) == T
    assert tc[0] == pytest.approx(T / 4, rel=5e-4)
    assert tc[1] - tc[0] == pytest.approx(T / 2, rel=5e-4)


def test_leaving_the_beam_stops_with_a_clear_message():
    model, beam, body, joint = _inclined(0.5)
    with pytest.raises(fm.SimulationStopped, match="reached the end of beam"):
        fm.simulate(model, t_end=2.0, dt=2e-3, output_interval=0.1, record_energy=False)


def test_misplaced_body_is_rejected():
    model, beam, body, joint = _inclined(0.3)
    body.pose = body.pose.shifted((0, 0, 0.01))
    with pytest.raises(fm.ModelError, match="violated by"):
        Assembly(model)


SCENARIO = """
name = "incline"
[simulation]
t_end = 0.2
dt = 1e-3
gravity = [0.0, 0.0, -9.81]
output_interval = 0.05

[[beams]]
name = "rail"
geometry = { line = { start = [0.0, 0.0, 0.0], end = [1.9106, 0.0, -0.5910] } }
elements = 8
axial_stiffness = 1e9
bending_stiffness = 1e6
mass_per_length = 1.0

[[rigid_bodies]]
name = "sleeve"
mass = 0.5
inertia = [1e-3, 2e-3, 2e-3]
pose = { on_beam = "rail", s = 0.2 }

[[constraints]]
type = "clamp"
beam = "rail"
node = "first"

[[constraints]]
type = "clamp"
beam = "rail"
node = "last"

[[joints]]
name = "slider"
type = "sliding"
beam = "rail"
body = "sleeve"

[[probes]]
name = "s"
type = "slide_coordinate"
joint = "slider"
"""


def test_sliding_joint_from_scenario(tmp_path):
    from flexmbs.io.scenario import load_scenario

    f = tmp_path / "incline.toml"
    f.write_text(SCENARIO)
    sc = load_scenario(f)
    res = fm.simulate(sc.model, t_end=0.2, dt=1e-3, output_interval=0.05, record_energy=False)
    probe = sc.probes[0]
    s_end = probe.evaluate(res.assembly, res.final_state)[0]
    alpha = np.arctan2(0.5910, 1.9106)
    assert s_end == pytest.approx(0.2 + 0.5 * 9.81 * np.sin(alpha) * 0.2**2, rel=1e-5)
    bad = SCENARIO.replace('joint = "slider"', 'joint = "slide"')
    f.write_text(bad)
    with pytest.raises(fm.ScenarioError, match=r"probes\[s\]\.joint: no sliding joint named 'slide'"):
        load_scenario(f)


def test_joint_reaction_is_the_force_on_the_body():
    """Sleeve on a horizontal stiff beam: the reaction probe equals m (r'' - g) of the body
    (its equation of motion, to the Newton tolerance) and, with the beam nearly rigid, carries
    the weight m g within 5 % (the beam vibrates under the suddenly applied load)."""
    from flexmbs.io.probes import JointReactionProbe

    model, beam, body, joint = _inclined(0.0)
    probe = JointReactionProbe("reaction", joint)
    res = fm.simulate(model, t_end=0.05, dt=1e-3, output_interval=0.05, record_energy=False)
    st = res.final_state
    F = probe.evaluate(res.assembly, st)
    acc = st.qdd[res.assembly.body_dofs(body)[:3]]
    expected = 0.5 * (acc - model.gravity)
    assert np.abs(F - expected).max() < 1e-6 * 0.5 * 9.81
    assert F[2] == pytest.approx(0.5 * 9.81, rel=5e-2)

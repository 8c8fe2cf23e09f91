"""Sliding joint with clearance in the assembled model: statics (docs/theory.md §III.9, V3),
tangent vs finite differences, sliding on an incline, input validation."""

from __future__ import annotations

import math

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.assembly import Assembly

M_SLEEVE, G = 0.21441, 9.81
J_SLEEVE = (2.479e-5, 4.098e-5, 4.098e-5)


def _beam_with_sleeve(*, direction=(1.0, 0.0, 0.0), offset=-5.01e-4, stiffness=1e6, damping=0.0,
                      lock_axial=True, friction=None, s=0.5, tangent="exact", hole=None):
    d = np.asarray(direction, float) / np.linalg.norm(direction)
    model = fm.Model(gravity=(0, 0, -G))
    beam = model.add_beam(fm.line((0, 0, 0), tuple(d), elements=16), name="rail",
                          section=fm.CircularSection(2e-3), material=fm.Material(E=2.1e11, rho=7800))
    model.clamp(beam.first_node)
    model.clamp(beam.last_node)
    pose = beam.frame_at(s).shifted((0, 0, offset))
    sleeve = model.add_rigid_body(mass=M_SLEEVE, inertia=J_SLEEVE, pose=pose, name="sleeve")
    if lock_axial:   # statics: fix the free slide and roll of the sleeve (frictionless)
        model.joint(sleeve, fm.GROUND, point=pose.position, axis=tuple(d), translation=(1, 0, 0),
                    rotation=(1, 0, 0))
    joint = model.add_joint(fm.SlidingClearanceJoint(
        beam, sleeve, hole=hole or fm.CircleHole(2.5e-3, 0.04, 9), friction=friction,
        tangent=tangent,
        contact=fm.LinearPenalty(stiffness=stiffness, damping=damping)))
    return model, beam, sleeve, joint


def test_sleeve_at_rest_loads_only_the_end_sections():
    """V3: horizontal clamped-clamped steel rod (L = 1 m, r = 2 mm), sleeve (bore 2.5 mm,
    40 mm, 9 sections) at midspan: the beam's sag over the sleeve lifts it off the middle
    sections, so only sections 0 and 8 carry mg/2 each (to the equilibrium's rounding); the
    midspan deflection equals that of the beam under two point loads mg/2 at the end-section
    stations (penalty penetration 1e-6 m shifts the load points negligibly: 1e-5 relative)."""
    # with the default (exact) tangent; the Gauss-Newton tangent has no lateral stiffness for
    # the hanging sleeve (singular matrix)
    model, beam, sleeve, joint = _beam_with_sleeve()
    asm = Assembly(model)
    st = fm.solve_static(asm, fm.StaticOptions(load_steps=4))
    rows = joint.output(asm, st.q, np.zeros_like(st.q), st.lam, 0.0)
    assert sorted(r["section"] for r in rows) == [0, 8]
    for r in rows:
        assert r["normal_force"] == pytest.approx(M_SLEEVE * G / 2, rel=1e-5)
        assert r["gap"] == pytest.approx(-M_SLEEVE * G / 2 / 1e6, rel=1e-5)
    mid = asm.node_dofs(beam.node(8))[2]
    ref = fm.Model(gravity=(0, 0, -G))
    b2 = ref.add_beam(fm.line((0, 0, 0), (1, 0, 0), elements=16),
                      section=fm.CircularSection(2e-3), material=fm.Material(E=2.1e11, rho=7800))
    ref.clamp(b2.first_node)
    ref.clamp(b2.last_node)
    for s in (0.48, 0.52):
        ref.add_point_load((b2, s), (0, 0, -M_SLEEVE * G / 2))
    st2 = fm.solve_static(ref)
    assert st.q[mid] == pytest.approx(st2.q[mid], rel=1e-5)


def test_contact_tangent_matches_finite_differences(rng):
    """Assembled iteration matrix with active contacts (consistent tangent, damped penalty)
    vs central differences of the residual in q and v with the detected hole points frozen as
    material points of the hole (the function the tangent differentiates): 1e-6 relative."""
    model, beam, sleeve, joint = _beam_with_sleeve(offset=-5.3e-4, damping=20.0, lock_axial=False,
                                                   tangent="frozen_point")
    asm = Assembly(model)
    n, m = asm.n_coords, asm.n_mult
    q = asm.q_ref.copy()
    q[asm.body_dofs(sleeve)[:3]] += 1e-5 * rng.standard_normal(3)
    v = 1e-2 * rng.standard_normal(n)
    a = np.zeros(n)
    lam = rng.standard_normal(m)

    def res(q_, v_):
        rq, rl = np.zeros(n), np.zeros(m)
        asm.evaluate(q_, v_, a, lam, 0.0, rq, rl)
        return rq

    rq, rl = np.zeros(n), np.zeros(m)
    assert joint.output(asm, q, v, lam, 0.0), "the configuration must have active contacts"
    joint.freeze_detection(q, v)
    asm.evaluate(q, v, a, lam, 0.0, rq, rl, matrix=(0.0, 0.0, 1.0))
    K = asm.matrix.toarray()[:n, :n]
    asm.evaluate(q, v, a, lam, 0.0, rq, rl, matrix=(0.0, 1.0, 0.0))
    C = asm.matrix.toarray()[:n, :n]
    idx = np.concatenate([asm.body_dofs(sleeve), asm.beam_dofs(beam)[40:60]])
    h = 1e-8
    for j in idx:
        e = np.zeros(n)
        e[j] = h
        col = (res(q + e, v) - res(q - e, v)) / (2 * h)
        assert np.abs(K[:, j] - col).max() <= 1e-6 * np.abs(K).max() + 1e-6 * np.abs(col).max()
        e[j] = 1e-6
        colv = (res(q, v + e) - res(q, v - e)) / 2e-6
        assert np.abs(C[:, j] - colv).max() <= 1e-6 * max(np.abs(C).max(), 1.0)


def test_frictionless_sleeve_slides_down_an_incline_with_g_sin_alpha():
    """Stiff inclined rod, sleeve resting in contact: after the contact settles (0.05 s) the
    slide acceleration is g sin(alpha) (frictionless, penalty normal forces do no axial work);
    fitted over 0.05-0.25 s, 2e-3 relative (the rod's own vibration under the moving load)."""
    alpha = 0.2
    acc, *_ = _slide_on_incline(alpha)
    assert acc == pytest.approx(G * np.sin(alpha), rel=2e-3)


def _slide_on_incline(alpha: float, hole=None):
    """Stiff rod inclined by alpha, sleeve resting on it, 0.25 s: (slide acceleration fitted
    over 0.05-0.25 s, result, sleeve, joint)."""
    d = (np.cos(alpha), 0.0, -np.sin(alpha))
    model, beam, sleeve, joint = _beam_with_sleeve(direction=d, offset=-5.05e-4 / np.cos(alpha),
                                                   lock_axial=False, damping=20.0, s=0.3,
                                                   hole=hole)
    for b in model.beams:
        b.stiffness = fm.BeamStiffness(axial_stiffness=2.6e8, bending_stiffness=2.6e2,
                                       mass_per_length=0.098, radius=2e-3)
    res = fm.simulate(model, t_end=0.25, dt=2e-4, output_interval=5e-3, record_energy=False,
                      integrator=fm.GeneralizedAlpha(rho_inf=0.8))
    x = res.body_position(sleeve) @ np.asarray(d)
    sel = res.t >= 0.05
    return 2 * np.polyfit(res.t[sel], x[sel], 2)[0], res, sleeve, joint


def test_input_errors_are_clear():
    """Caught when the joint is added to the model (the reference configuration), not when the
    run starts."""
    with pytest.raises(fm.ModelError, match="does not pass through the hole"):
        _beam_with_sleeve(offset=-0.01)
    model = fm.Model()
    beam = model.add_beam(fm.line((0, 0, 0), (1, 0, 0), elements=4),
                          section=fm.CircularSection(2e-3), material=fm.Material(E=2e11, rho=7800))
    body = model.add_rigid_body(mass=1.0, inertia=(1, 1, 1), pose=beam.frame_at(0.5))
    with pytest.raises(fm.ModelError, match="not larger than the beam"):
        fm.SlidingClearanceJoint(beam, body, hole=fm.CircleHole(1.9e-3, 0.04, 5))
    half = np.radians(20.0)   # 40 deg tilt: a = r_b / cos(40 deg) = 2.61 mm > R = 2.5 mm
    tilted = model.add_rigid_body(mass=1.0, inertia=(1, 1, 1), position=(0.5, 0, 0),
                                  quaternion=(np.cos(half), 0, 0, np.sin(half)))
    with pytest.raises(fm.ModelError, match="jamming"):
        model.add_joint(fm.SlidingClearanceJoint(beam, tilted, hole=fm.CircleHole(2.5e-3, 1e-4, 3)))
    with pytest.raises(fm.ModelError, match="unknown hole section 'hexagon'"):
        from flexmbs.contact.sections import get_section
        get_section("hexagon")



def test_beam_leaving_the_bore_is_an_error_not_an_open_contact():
    """Example 2 with 0.3 mm clearance, 0.5 mm anchor steps and the Gauss-Newton tangent:
    plain Newton from the reference state to half the load pushes the wire axis through the
    bore wall. The unsigned gap |Q - P| - r_b would read "open" again and the solve would
    converge with the wire outside the grommet; instead the iterate is rejected with a message
    naming the joint and the section. The static solver (load steps, then its slope search
    where plain Newton fails) finds the equilibrium with the wire inside the bore, touching
    its wall at every section. (The exact tangent converges here:
    test_example2_preload_converges...; so does the Gauss-Newton tangent with the consistent
    detection, hence the paper's here; retreats = 0: Newton would halve such a step.)"""
    from pathlib import Path

    from flexmbs.io.scenario import load_scenario
    from flexmbs.solvers.factor import static_factorization
    from flexmbs.solvers.newton import Newton
    from flexmbs.solvers.static import _StaticStep

    sc = load_scenario(Path(__file__).resolve().parents[2] / "examples" / "solar_array_wing_flat.toml",
                       ["joints.grommet.hole.radius=1.1e-3", "simulation.load_steps=10",
                        "joints.grommet.tangent=gauss_newton", "joints.grommet.detection=paper",
                        "simulation.newton.retreats=0"])
    options = sc.static_options()
    asm = Assembly(sc.model)
    q = asm.q_ref.copy()
    asm.begin(q)
    half = _StaticStep(asm, q, np.zeros(asm.n_mult), 0.0)
    half.load, half.stabilizer = 0.5, options.stabilizer
    newton = Newton(options.newton, asm.length_scale, static_factorization(asm))
    with pytest.raises(fm.ConvergenceError, match="joint 'grommet': the beam axis left the bore"):
        newton.solve(half, full=True)

    asm = Assembly(sc.model)
    st = fm.solve_static(asm, options)
    assert st.slope_search_from is not None
    grommet = next(j for j in sc.model.interactions if j.name == "grommet")
    rows = grommet.section_records(st.q, np.zeros_like(st.q), 0.0)
    clearance = 1.1e-3 - grommet.beam_radius
    assert len(rows) == len(grommet.stations)
    for row in rows:
        assert row["contacts"] >= 1
        assert math.hypot(row["cy"], row["cz"]) == pytest.approx(clearance, abs=2e-5)


def test_full_newton_converges_quadratically_with_the_exact_tangent():
    """The hanging sleeve (statics, full Newton from the equilibrium at 80 % of the load to the
    full load): with the exact contact tangent the scaled errors fall quadratically once in
    the basin (measured 3.0e6, 1.9e4, 1.6: e_{k+1}/e_k² = 2.1e-9, 4.5e-9, about constant; a
    linear rate would grow that ratio by 1/e_k per iteration). The Gauss-Newton tangent has
    no lateral stiffness here and fails."""
    from flexmbs.solvers.newton import Newton, NewtonOptions
    from flexmbs.solvers.static import _StaticStep

    model, beam, sleeve, joint = _beam_with_sleeve()
    asm = Assembly(model)
    st = fm.solve_static(asm, fm.StaticOptions(load_steps=4))
    prob = _StaticStep(asm, st.q.copy(), st.lam.copy(), 0.0)
    newton = Newton(NewtonOptions(relative_tolerance=1e-12), asm.length_scale)
    prob.load = 0.8
    newton.solve(prob, full=True)
    prob.load = 1.0
    e = newton.solve(prob, full=True).history
    assert e[-1] <= 1.0
    big = [k for k in range(1, len(e) - 1) if e[k + 1] > 1.0]   # above the tolerance
    assert len(big) >= 2
    c = [e[k + 1] / e[k] ** 2 for k in big]
    assert max(c[i + 1] / c[i] for i in range(len(c) - 1)) < 5.0
    with pytest.raises(fm.ConvergenceError):
        joint.tangent = "gauss_newton"
        asm_gn = Assembly(model)
        gn = _StaticStep(asm_gn, st.q.copy(), st.lam.copy(), 0.0)
        gn.load = 0.8
        Newton(NewtonOptions(relative_tolerance=1e-12), asm_gn.length_scale).solve(gn, full=True)


def _contact_directions(asm, sleeve, joint, q):
    """(angle of Q, angle of the contact normal) about the hole axis, in the sleeve's (y, z)."""
    from flexmbs.elements.rigid_body import rotation_matrix

    qb = q[asm.body_dofs(sleeve)]
    A = rotation_matrix(qb[3:7])
    out = []
    for r in joint.output(asm, q, np.zeros_like(q), np.zeros(asm.n_mult), 0.0):
        u = A.T @ (np.asarray(r["position"]) - qb[:3])
        nrm = A.T @ np.asarray(r["normal"])
        out.append((math.atan2(u[2], u[1]), math.atan2(nrm[2], nrm[1])))
    return out


ROUNDED_SQUARE = fm.SuperellipseHole(2.5e-3, 2.5e-3, 6.0, 0.04, 9)


def test_rounded_square_sleeve_slides_on_its_flat_side_like_the_circular_one():
    """The incline of the test above with a rounded-square bore (superellipse n = 6, compiled):
    the beam bears on the bore's flat top, and the sleeve slides with g sin(alpha) like the
    circular one (2e-3)."""
    alpha = 0.2
    acc, res, sleeve, joint = _slide_on_incline(alpha, hole=ROUNDED_SQUARE)
    assert joint.compiled_form()
    assert acc == pytest.approx(G * np.sin(alpha), rel=2e-3)
    dirs = _contact_directions(res.assembly, sleeve, joint, res.q[-1])
    assert dirs
    for q_angle, n_angle in dirs:     # on the flat top, normal straight up
        assert abs(q_angle - math.pi / 2) < 0.45 and abs(n_angle - math.pi / 2) < 1e-3


def test_pushed_diagonally_the_contact_moves_to_the_rounded_corner():
    """Statics: the hanging sleeve pushed sideways by m g as well: the beam must bear along the
    resultant, 45 degrees from the vertical (y, z of the sleeve). A thin stiff rod (r = 0.5 mm)
    in a rounded-square bore (n = 4, corner radius of curvature 0.99 mm > r) sits in the corner
    with one contact whose wall normal points along the resultant, like the circular bore's;
    the flat sides alone cannot carry the sideways force. (The sleeve starts with the rod near
    that corner: along a flat there is no stiffness to load-step on.)"""
    r_b = 5e-4
    for hole, corner in ((fm.CircleHole(2.5e-3, 0.04, 9), 2.5e-3),
                         (fm.SuperellipseHole(2.5e-3, 2.5e-3, 4.0, 0.04, 9),
                          2.5e-3 * 0.5 ** (-1 / 4))):
        reach = (corner - r_b + 1e-6) / math.sqrt(2.0)     # rod axis off the hole centre
        model = fm.Model(gravity=(0, 0, -G))
        beam = model.add_beam(fm.line((0, 0, 0), (1, 0, 0), elements=16), name="rail",
                              section=fm.CircularSection(r_b),
                              material=fm.Material(E=2.1e11, rho=7800))
        beam.stiffness = fm.BeamStiffness(axial_stiffness=2.6e8, bending_stiffness=2.6e2,
                                          mass_per_length=0.098, radius=r_b)
        model.clamp(beam.first_node)
        model.clamp(beam.last_node)
        pose = beam.frame_at(0.5).shifted((0, -reach, -reach))
        sleeve = model.add_rigid_body(mass=M_SLEEVE, inertia=J_SLEEVE, pose=pose, name="sleeve")
        model.joint(sleeve, fm.GROUND, point=pose.position, axis=(1, 0, 0), translation=(1, 0, 0),
                    rotation=(1, 0, 0))
        joint = model.add_joint(fm.SlidingClearanceJoint(beam, sleeve, hole=hole,
                                                         contact=fm.LinearPenalty(stiffness=1e6)))
        model.add_point_load(sleeve, (0.0, -M_SLEEVE * G, 0.0))
        asm = Assembly(model)
        st = fm.solve_static(asm, fm.StaticOptions(load_steps=4))
        dirs = _contact_directions(asm, sleeve, joint, st.q)
        assert dirs
        for q_angle, n_angle in dirs:
            assert n_angle == pytest.approx(math.pi / 4, abs=2e-3)
            assert q_angle == pytest.approx(math.pi / 4, abs=0.02)


@pytest.mark.parametrize("law", ["regularised", "stick"])
def test_contact_migrates_from_the_flat_side_to_the_rounded_corner(law):
    """Dynamics: the thin rod of the test above rests on the flat top of the rounded square
    (contact normal straight up, 90 degrees); a sideways push ramped to m g over 0.3 s moves
    the contact round to the corner. With regularised friction 0.3 (which cannot hold) it
    settles with the normal along the resultant, 45 degrees (measured 45.0 / 45.1 degrees at
    1 s); friction that sticks holds it anywhere inside the friction cone, within atan(0.3) =
    16.7 degrees of the resultant (measured: 52.05-52.06 degrees from 0.35 s to 2 s)."""
    r_b = 5e-4
    model = fm.Model(gravity=(0, 0, -G))
    beam = model.add_beam(fm.line((0, 0, 0), (1, 0, 0), elements=16), name="rail",
                          section=fm.CircularSection(r_b), material=fm.Material(E=2.1e11, rho=7800))
    beam.stiffness = fm.BeamStiffness(axial_stiffness=2.6e8, bending_stiffness=2.6e2,
                                      mass_per_length=0.098, radius=r_b)
    model.clamp(beam.first_node)
    model.clamp(beam.last_node)
    pose = beam.frame_at(0.5).shifted((0, 0, -(2.5e-3 - r_b + 1e-6)))
    sleeve = model.add_rigid_body(mass=M_SLEEVE, inertia=J_SLEEVE, pose=pose, name="sleeve")
    model.joint(sleeve, fm.GROUND, point=pose.position, axis=(1, 0, 0), translation=(1, 0, 0),
                rotation=(1, 0, 0))
    joint = model.add_joint(fm.SlidingClearanceJoint(
        beam, sleeve, hole=fm.SuperellipseHole(2.5e-3, 2.5e-3, 4.0, 0.04, 9),
        contact=fm.LinearPenalty(stiffness=1e6, damping=30.0),
        friction=fm.Friction(mu=0.3, law=law)))
    model.add_point_load(sleeve, (0.0, -M_SLEEVE * G, 0.0), function=fm.Ramp(end=0.3))
    res = fm.simulate(model, t_end=1.0, dt=2e-4, output_interval=0.05, record_energy=False)
    first = _contact_directions(res.assembly, sleeve, joint, res.q[0])
    last = _contact_directions(res.assembly, sleeve, joint, res.q[-1])
    assert first and all(n == pytest.approx(math.pi / 2, abs=1e-3) for _, n in first)
    assert last
    if law == "stick":      # held: the contact does not move along the wall any more (the
        # rail's bending mode with the sleeve keeps ringing: nothing in this model damps it)
        held = [n for i in range(len(res.t)) if res.t[i] >= 0.5
                for _, n in _contact_directions(res.assembly, sleeve, joint, res.q[i])]
        assert math.degrees(max(held) - min(held)) < 0.05
    for q_angle, n_angle in last:
        if law == "regularised":
            assert math.degrees(n_angle) == pytest.approx(45.0, abs=1.0)
            assert math.degrees(q_angle) == pytest.approx(45.0, abs=1.0)
        else:    # held on the wall, not at the bottom of the cone, inside it
            assert 46.0 < math.degrees(n_angle) < 45.0 + math.degrees(math.atan(0.3))

"""The tendon-driven continuum robot against independent references (issue 52, item 6).

A NiTi backbone (``ancf_rod14``, r = 0.7 mm, E = 54 GPa, 200 mm, clamped with its twist) carries
``n`` disks at equal spacing; one steel tendon (r = 0.08 mm) runs through a hole 10 mm from the
backbone in the base plate and every disk but the last, where it is anchored, and is pulled at
its start by T (:meth:`flexmbs.Model.add_tendon`; 20 µm clearance, linear penalty 1e6 N/m).
Statics from the straight, unloaded state by :func:`flexmbs.solve_static`.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.assembly import Assembly
from flexmbs.constraints.reactions import reactions

LENGTH, ROD_R, OFFSET = 0.2, 0.7e-3, 10e-3
NITI = fm.Material(E=54e9, rho=6450.0, nu=0.3)
STEEL = fm.Material(E=200e9, rho=7850.0, nu=0.3)
WIRE_R = 0.08e-3
EI = NITI.E * math.pi * ROD_R**4 / 4
#: body x along global z: the disks' cylinders (and the hole check) run along the backbone
AXIS_Z = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])


def robot(n: int, tension: float = 1.0, *, wire: fm.BeamStiffness | None = None,
          element_length: float | None = None, mu: float = 0.0, damping: float = 0.0,
          wire_damping: float = 0.0):
    """The robot with ``n`` disks and one tendon at +x pulled by ``tension`` (a constant or a
    time function); returns (model, tendon parts, disks)."""
    model = fm.Model(gravity=(0.0, 0.0, 0.0))
    backbone = model.add_beam(fm.line((0, 0, 0), (0, 0, LENGTH), elements=2 * n),
                              section=fm.CircularSection(ROD_R), material=NITI,
                              element="ancf_rod14", damping=damping, name="backbone")

    def disk(z: float, name: str) -> fm.RigidBody:
        return model.add_rigid_body(mass=3.8e-3, inertia=(4.3e-7, 2.2e-7, 2.2e-7),
                                    pose=fm.Pose((0.0, 0.0, z), AXIS_Z), name=name,
                                    shape={"type": "cylinder", "radius": 15e-3, "length": 2e-3})

    plate = disk(0.0, "plate")
    model.fix_body(plate, name="plate_fixed")
    model.rigid(backbone.first_node, plate, name="clamp")
    disks = []
    for k in range(1, n + 1):
        d = disk(k * LENGTH / n, f"disk{k}")
        model.rigid(backbone.node(2 * k), d, name=f"mount{k}")
        disks.append(d)
    hole = AXIS_Z.T @ np.array([OFFSET, 0.0, 0.0])
    wire_kw = {"material": STEEL} if wire is None else {"section": wire}
    parts = model.add_tendon(fm.Tendon(damping=wire_damping,
        name="t1", route=[(plate, hole)] + [(d, hole) for d in disks[:-1]],
        anchor=(disks[-1], hole), lead=0.02, radius=WIRE_R, clearance=0.02e-3,
        element_length=element_length, tension=tension, contact=fm.LinearPenalty(stiffness=1e6),
        friction=mu or None, **wire_kw))
    return model, parts, disks


def static(n: int, **kw):
    model, parts, disks = robot(n, **kw)
    asm = Assembly(model)
    st = fm.solve_static(asm, fm.StaticOptions(load_steps=10))
    return asm, st, parts, disks


def circle_error(asm: Assembly, q: np.ndarray, disks, kappa: float) -> float:
    """Largest distance [m] of a disk centre from the arc of curvature ``kappa`` (clamped along
    z at the origin, bending towards +x) at the disk's arc length."""
    err = 0.0
    for k, d in enumerate(disks):
        s = (k + 1) * LENGTH / len(disks)
        exact = np.array([(1 - math.cos(kappa * s)) / kappa, 0.0, math.sin(kappa * s) / kappa])
        err = max(err, float(np.linalg.norm(q[asm.body_dofs(d)[:3]] - exact)))
    return err


def test_one_tendon_bends_the_backbone_to_constant_curvature():
    """Reference: a tendon at a fixed offset d from the backbone, pulled by T and anchored at
    its end, loads the backbone with the constant moment T d, so it bends to the arc of
    curvature κ = T d / (E I) (Camarillo et al. 2008, Rucker & Webster 2011); here κ L = 0.2 rad.
    Between disks the tendon runs on a chord, whose distance from the backbone exceeds d by
    h² κ / 8 (h the spacing): the disk-to-arc error falls like h² until the 20 µm clearance
    (2e-3 of d) sets a floor. Measured (error / L): 1.5e-3, 3.9e-4, 1.6e-4 at 4, 8, 16 disks."""
    kappa = 1.0 * OFFSET / EI
    errors = []
    for n in (4, 8, 16):
        asm, st, _, disks = static(n)
        errors.append(circle_error(asm, st.q, disks, kappa) / LENGTH)
    assert errors[0] > errors[1] > errors[2]
    assert errors[1] / errors[0] < 0.3            # h²: 0.25, with the floor beginning
    assert errors[0] < 3e-3 and errors[2] < 2.5e-4


def test_a_frictionless_tendon_keeps_its_tension_along_the_route():
    """Reference: a frictionless wire pulled by T has the tension T in every span (only normal
    forces at the holes). The wire in 4 mm elements (the holes press single points of it: a
    cubic element follows the bend there only as well as its length allows); tolerance 1e-4 T
    (measured 4e-5 T; the penalty's penetration, ~1e-6 m, changes nothing)."""
    T = 1.0
    asm, st, parts, _ = static(4, tension=T, element_length=4e-3)
    N = parts.axial_forces(asm, st.q)
    assert N.size == 5
    np.testing.assert_allclose(N, T, rtol=0, atol=1e-4 * T)


def test_the_shape_does_not_depend_on_a_soft_tendon_bending_stiffness():
    """Reference: a tendon acts by its tension alone once its bending stiffness is negligible:
    the wire's share of the bending moment is of the order of its stiffness ratio, so the disks
    converge linearly in that ratio. Wire E I of 1e-3, 1e-4 and 1e-5 of the backbone's
    (measured: the disks move by 2.1e-3 and 3.5e-4 of their displacement between them; the
    second step is not a tenth of the first: the wire also bends within the clearance, a share
    that does not scale with its stiffness)."""
    ea = STEEL.E * math.pi * WIRE_R**2
    rho_a = STEEL.rho * math.pi * WIRE_R**2
    out = []
    for ratio in (1e-3, 1e-4, 1e-5):
        wire = fm.BeamStiffness(axial_stiffness=ea, bending_stiffness=ratio * EI,
                                mass_per_length=rho_a, radius=WIRE_R)
        asm, st, _, disks = static(8, wire=wire)
        out.append(np.array([st.q[asm.body_dofs(d)[:3]] - asm.q_ref[asm.body_dofs(d)[:3]]
                             for d in disks]))
    scale = np.abs(out[2]).max()
    first, second = np.abs(out[0] - out[1]).max(), np.abs(out[1] - out[2]).max()
    assert first < 4e-3 * scale and second < 4e-4 * scale
    assert second < 0.25 * first


def test_the_base_reactions_balance_the_tendon_tension():
    """Reference: the robot's free-body balance. The plate's fixation, the hold of the tendon's
    start and the pull T are the only external forces: their sum and their moment about the
    origin vanish (to the solver's tolerance), and the plate holds the moment T d about y."""
    T = 1.0
    asm, st, parts, _ = static(4, tension=T)
    plate = reactions(asm, st.q, st.lam, "plate_fixed")
    hold = reactions(asm, st.q, st.lam, "t1_hold")
    assert [r.part for r in plate] == ["plate"] and [r.part for r in hold] == ["t1"]
    start = st.q[asm.node_dofs(parts.beam.first_node)[:3]]
    pull = T * parts.pull
    force = plate[0].force + hold[0].force + pull
    moment = (plate[0].moment + np.cross(plate[0].point, plate[0].force)
              + hold[0].moment + np.cross(hold[0].point, hold[0].force) + np.cross(start, pull))
    assert np.abs(force).max() < 1e-8 * T
    assert np.abs(moment).max() < 1e-8 * T * LENGTH
    # the pull at the start (x = d) and the plate: the plate takes the moment -T d about y
    assert plate[0].moment[1] + np.cross(plate[0].point, plate[0].force)[1] == pytest.approx(
        -np.cross(start, pull)[1] - (hold[0].moment + np.cross(hold[0].point, hold[0].force))[1],
        rel=1e-8)


def _wire_points(asm: Assembly, q: np.ndarray, parts) -> np.ndarray:
    """The wire's centreline at its start, where every hole is on it, and at its anchor."""
    from flexmbs.elements.hermite import element_point

    beam = parts.beam
    stations = ([0.0] + [j.slide_coordinate(q) for j in parts.holes]
                + [float(beam.centerline.lengths.sum())])
    dofs = asm.element_dofs(beam)
    points = []
    for s in stations:
        e, xi = beam.locate(s)
        r, _, _ = element_point(q[dofs[e]], float(beam.centerline.lengths[e]), xi)
        points.append(r)
    return np.array(points)


def test_friction_drops_the_tension_across_each_hole_by_the_capstan_factor():
    """Reference: the capstan (Euler–Eytelwein) law. While the wire slides (the pull draws it
    through the holes as the backbone bends), Coulomb friction μ = 0.1 at a hole where it turns
    by φ_k leaves N_k = N_(k-1) e^(−μ φ_k), falling from the actuator towards the anchor. φ_k
    from the wire's own points at the holes; the drops 1 − N_k/N_(k-1) (2.4e-3 to 5e-3) agree
    with 1 − e^(−μφ_k) within 5 % (measured 0.3-3 %; without friction the spans agree within
    4e-5)."""
    asm, st, parts, _ = static(4, tension=1.0, element_length=4e-3, mu=0.1)
    N = parts.axial_forces(asm, st.q)
    d = np.diff(_wire_points(asm, st.q, parts), axis=0)
    d /= np.linalg.norm(d, axis=1)[:, None]
    phi = np.arccos(np.clip(np.sum(d[:-1] * d[1:], axis=1), -1.0, 1.0))
    assert np.all(phi > 0.02)
    drop = 1.0 - N[1:] / N[:-1]
    np.testing.assert_allclose(drop, 1.0 - np.exp(-0.1 * phi), rtol=0.05)


def test_statics_and_a_long_damped_dynamic_run_agree():
    """Reference: the static equilibrium is where a damped motion under the same loads comes to
    rest. The tension ramped in over 50 ms, backbone and wire damped (0.05 s and 1 ms,
    stiffness-proportional), 1 s of generalized-α: the last disk ends within 5e-4 of its
    displacement from the static solution, the span tensions within 1e-3 T."""
    asm, st, parts, disks = static(4, tension=1.0)
    model, parts2, disks2 = robot(4, tension=fm.Ramp(end=0.05, value=1.0, smooth=True),
                                  damping=0.05, wire_damping=1e-3)
    asm2 = Assembly(model)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = fm.simulate(asm2, t_end=1.0, dt=2e-3, output_interval=0.5,
                          integrator=fm.GeneralizedAlpha(rho_inf=0.5), record_energy=False)
    tip = asm.body_dofs(disks[-1])[:3]
    moved = np.linalg.norm(st.q[tip] - asm.q_ref[tip])
    q_end = res.final_state.q
    assert np.linalg.norm(q_end[asm2.body_dofs(disks2[-1])[:3]] - st.q[tip]) < 5e-4 * moved
    np.testing.assert_allclose(parts2.axial_forces(asm2, q_end), parts.axial_forces(asm, st.q),
                               rtol=0, atol=1e-3)


def test_a_slack_tendon_beside_a_pulled_one_adds_only_its_bending_stiffness():
    """Reference: a tendon that nothing pulls carries no moment but its bending, so beside a
    tendon pulled by T it stiffens the bend by its share of the bending stiffness: the disks
    move by ``EI_w / (EI_b + EI_w)`` (6.3e-4 here) less than with the pulled tendon alone
    (measured 5.3e-4 to 6.0e-4: the wire also bends within its clearance). Plain Newton
    cycles between the slack wire's contact sets from the first increment; the static solver
    goes on with the slope search (``StaticResult.slope_search_from``). The free body
    balances: the plate's fixation, the holds of both starts and the pull."""
    T = 2.0
    ref, st_ref, _, disks_ref = static(4, tension=T)
    model, parts, disks = robot(4, tension=T)
    hole = AXIS_Z.T @ np.array([-OFFSET, 0.0, 0.0])
    plate = model.body("plate")
    model.add_tendon(fm.Tendon(
        name="t2", route=[(plate, hole)] + [(d, hole) for d in disks[:-1]],
        anchor=(disks[-1], hole), lead=0.02, radius=WIRE_R, clearance=0.02e-3,
        material=STEEL, tension=0.0))
    asm = Assembly(model)
    st = fm.solve_static(asm, fm.StaticOptions(load_steps=10))
    assert st.slope_search_from is not None
    share = STEEL.E * WIRE_R**4 / (NITI.E * ROD_R**4)
    share /= 1.0 + share
    for d_ref, d in zip(disks_ref, disks, strict=True):
        u_ref = st_ref.q[ref.body_dofs(d_ref)[:3]] - ref.q_ref[ref.body_dofs(d_ref)[:3]]
        u = st.q[asm.body_dofs(d)[:3]] - asm.q_ref[asm.body_dofs(d)[:3]]
        assert np.linalg.norm(u - u_ref) / np.linalg.norm(u_ref) == pytest.approx(share, rel=0.3)
    fixed = reactions(asm, st.q, st.lam, "plate_fixed")[0]
    holds = [reactions(asm, st.q, st.lam, name)[0] for name in ("t1_hold", "t2_hold")]
    start = st.q[asm.node_dofs(parts.beam.first_node)[:3]]
    pull = T * parts.pull
    force = fixed.force + sum(h.force for h in holds) + pull
    moment = (fixed.moment + np.cross(fixed.point, fixed.force) + np.cross(start, pull)
              + sum(h.moment + np.cross(h.point, h.force) for h in holds))
    assert np.abs(force).max() < 1e-8 * T
    assert np.abs(moment).max() < 1e-8 * T * LENGTH


def _pull_release(mu: float):
    """Quasi-static equilibria as the pull rises to 1 N at t = 1 and falls to 0.5 N at t = 2."""
    pull = fm.Table(times=[0.0, 1.0, 2.0], values=[0.0, 1.0, 0.5])
    model, parts, disks = robot(4, tension=pull, element_length=4e-3, mu=mu)
    asm = Assembly(model)
    res = fm.solve_quasi_static(asm, np.linspace(0.0, 2.0, 9))
    tip = [float(q[asm.body_dofs(disks[-1])[0]]) for q in res.q]
    return asm, res, parts, tip


def _turns(asm: Assembly, q: np.ndarray, parts) -> np.ndarray:
    d = np.diff(_wire_points(asm, q, parts), axis=0)
    d /= np.linalg.norm(d, axis=1)[:, None]
    return np.arccos(np.clip(np.sum(d[:-1] * d[1:], axis=1), -1.0, 1.0))


def test_a_slow_pull_and_release_through_holes_with_friction_traces_a_hysteresis_loop():
    """Reference: the capstan law in both directions. Quasi-static equilibria (time as the
    path parameter, the friction anchors carried from increment to increment), μ = 0.1: while
    the pull rises the wire slides in and the span tensions fall towards the anchor by
    e^(−μ φ_k) per hole; once it falls the wire slides out and they rise by e^(+μ φ_k)
    (1 − e^(∓μφ) within 5 % and 8 %; measured 0.3–3.0 % and 0.2–5.9 %). So at the same pull
    the backbone bends further on the way back (measured 1.0 % and 0.7 % at 0.75 N and 0.5 N).
    Controls: without friction the two branches agree to 1e-8 (measured 2e-11), and the rising
    branch at 1 N is the equilibrium that :func:`flexmbs.solve_static` finds by load stepping
    (the same path; measured 7e-12 of the tip's displacement)."""
    asm, res, parts, tip = _pull_release(0.1)
    assert res.t[4] == 1.0 and res.t[8] == 2.0
    up = parts.axial_forces(asm, res.q[4])
    np.testing.assert_allclose(1.0 - up[1:] / up[:-1],
                               1.0 - np.exp(-0.1 * _turns(asm, res.q[4], parts)), rtol=0.05)
    down = parts.axial_forces(asm, res.q[8])
    np.testing.assert_allclose(down[1:] / down[:-1] - 1.0,
                               np.exp(0.1 * _turns(asm, res.q[8], parts)) - 1.0, rtol=0.08)
    for k_up, k_down in ((3, 6), (2, 8)):     # 0.75 N and 0.5 N
        assert tip[k_down] > tip[k_up] * 1.005
    tip0 = _pull_release(0.0)[3]
    for k_up, k_down in ((3, 6), (2, 8)):
        assert tip0[k_down] == pytest.approx(tip0[k_up], rel=1e-8)
    ref, st, _, disks = static(4, tension=1.0, element_length=4e-3, mu=0.1)
    d = ref.body_dofs(disks[-1])[:3]
    np.testing.assert_allclose(res.q[4][d], st.q[d], rtol=0, atol=1e-8 * abs(tip[4]))

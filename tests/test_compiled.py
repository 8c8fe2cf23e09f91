"""The one assembler (flexmbs.driver) serves both Newton loops: its iteration matrix is the
derivative of its residual (central differences, for every kind of term that has an exact
tangent), models with a term that has no compiled form say why, and the compiled and the Python
integrators, which call the same driver, produce the same trajectories.
"""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.assembly import Assembly

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "examples"))
import curved_beam_sleeve as ex1
import solar_array_wing_flat as ex2

#: agreement of the matrix with central differences of the residual (relative to the largest
#: entry of the block)
FD_RTOL = 2e-6


def kitchen_sink(redundant: bool = False, sleeve_offset: float = -2e-4) -> fm.Model:
    """A beam with both ends on bodies, a sliding and a clearance joint on it, every joint
    preset and body load kind (with time functions), prescribed body coordinates."""
    model = fm.Model(gravity=(0.0, -3.0, -9.81))
    beam = model.add_beam(fm.line((0, 0, 0), (1.0, 0, 0), elements=8),
                          section=fm.CircularSection(2e-3), name="rod",
                          material=fm.Material(E=2.1e10, rho=7800), damping=1e-4)
    base = model.add_rigid_body(mass=0.5, inertia=(1e-3, 2e-3, 2e-3), position=(0, 0, 0),
                                name="base")
    tip = model.add_rigid_body(mass=0.3, inertia=(1e-3, 1e-3, 2e-3), position=(1.0, 0, 0),
                               name="tip")
    arm = model.add_rigid_body(mass=0.2, inertia=(5e-4, 5e-4, 5e-4), position=(1.0, 0.2, 0),
                               name="arm")
    slider = model.add_rigid_body(mass=0.1, inertia=(1e-5, 2e-5, 2e-5), pose=beam.frame_at(0.3),
                                  name="slider")
    frame = beam.frame_at(0.7)
    sleeve = model.add_rigid_body(mass=0.2, inertia=(2e-5, 4e-5, 4e-5),
                                  pose=frame.shifted((0.0, 0.0, sleeve_offset)), name="sleeve")
    model.rigid(beam.first_node, base)
    model.spherical(beam.last_node, tip)
    model.revolute(base, point=(0, 0, 0), axis=(0, 0, 1))
    model.prismatic(tip, point=(1.0, 0, 0), axis=(1, 0, 0))
    model.joint(arm, tip, point=(1.0, 0.1, 0), axis=(0, 1, 0), translation=(0, 1, 1),
                rotation=(1, 0, 1))
    model.prescribe(arm, [1], fm.Sine(amplitude=1e-3, frequency=3.0))
    if redundant:   # the arm-tip joint's rotation about x once more: one equation is dropped
        model.joint(arm, tip, point=(1.0, 0.1, 0), axis=(0, 1, 0), translation=(0, 0, 0),
                    rotation=(1, 0, 0))
    model.add_point_load(tip, (0.0, 0.5, 0.2), moment=(0.01, 0.0, 0.02), point=(0.0, 0.01, 0.0),
                         function=fm.HalfSine(duration=0.02, amplitude=2.0))
    model.add_point_load(arm, (0.0, 0.0, 1.0), point=(0.02, 0.0, 0.0))
    model.add_point_load(beam.node(4), (0.0, 0.0, 0.3), function=fm.Ramp(end=0.01))
    model.add_joint(fm.SlidingJoint(beam, slider, name="slide", friction=0.2,
                                    axial_force=fm.Sine(amplitude=0.1, frequency=5.0)))
    model.add_joint(fm.SlidingClearanceJoint(
        beam, sleeve, name="sleeve", hole=fm.CircleHole(2.4e-3, 0.02, 5),
        contact=fm.HuntCrossley(stiffness=1e6, exponent=1.0, restitution=0.6),
        friction=fm.RegularizedCoulomb(mu=0.2, eps_v=1e-3)))
    return model


def _models():
    yield "example1", ex1.build()[0]
    yield "example1_ideal", ex1.build(ideal=True)[0]
    yield "example2", ex2.build()[0]
    yield "example2_ideal", ex2.build(ideal=True)[0]
    yield "kitchen_sink", kitchen_sink()


def two_groups() -> fm.Model:
    """Two beams with different CableOptions (two element groups in one model)."""
    model = fm.Model(gravity=(0, 0, -9.81))
    b1 = model.add_beam(fm.line((0, 0, 0), (1, 0, 0), elements=3), section=fm.CircularSection(1e-3),
                        material=fm.Material(E=1e9, rho=1000), damping=1e-3)
    b2 = model.add_beam(fm.line((0, 1, 0), (1, 1, 0), elements=4), section=fm.CircularSection(1e-3),
                        material=fm.Material(E=1e9, rho=1000),
                        options=fm.CableOptions(bending="scalar"))
    model.clamp(b1.first_node)
    model.pin(b2.first_node)
    model.add_point_load(b2.last_node, (0, 0.1, 0.2))
    return model


def steep_wire_in_a_ring() -> fm.Model:
    """A wire crossing a thin ring (one hole section) at 54° to its axis, 0.8 mm off the
    centre across the plane of the tilt: the section ellipse (a = 3.4 mm, b = 2 mm, a²/b > R =
    3.5 mm) touches the bore at two points (docs/theory.md §II.3), damped contact with friction."""
    import math

    model = fm.Model(gravity=(0, 0, 0))
    d = np.array([math.cos(0.942), 0.0, math.sin(0.942)])
    off = np.array([0.0, -8e-4, 0.0])
    beam = model.add_beam(fm.line(tuple(off - 0.1 * d), tuple(off + 0.1 * d), elements=4),
                          section=fm.CircularSection(2e-3), material=fm.Material(E=2.1e11, rho=7800))
    model.clamp(beam.first_node)
    ring = model.add_rigid_body(mass=0.1, inertia=(1e-5, 1e-5, 1e-5), position=(0, 0, 0),
                                name="ring")
    model.add_joint(fm.SlidingClearanceJoint(
        beam, ring, hole=fm.CircleHole(3.5e-3, 1e-3, 1), name="ring",
        contact=fm.LinearPenalty(stiffness=1e6, damping=5.0),
        friction=fm.RegularizedCoulomb(mu=0.2, eps_v=1e-3)))
    return model


def _exact_tangent_models():
    """Every term kind (its tangent is exact), the sliding joint's stick-law friction (slipping)
    included; the clearance contacts with their default, exact tangent (damped, with friction
    in the kitchen sink)."""
    yield "example1", ex1.build()[0]
    yield "example1_ideal", ex1.build(ideal=True)[0]
    yield "example2_ideal", ex2.build(ideal=True)[0]
    yield "two_groups", two_groups()
    yield "two_contacts_one_section", steep_wire_in_a_ring()
    yield "kitchen_sink_exact", kitchen_sink(sleeve_offset=-4.6e-4)    # bore resting on the beam
    yield "rods_and_node_moments", rods_and_node_moments()


def rods_and_node_moments() -> fm.Model:
    """A damped rod arc and a cable, soft, with timed moments on nodes (whose generalized
    forces depend on the slope): the moments' derivatives are not hidden by the stiffness."""
    model = fm.Model()
    section = fm.BeamStiffness(axial_stiffness=10.0, bending_stiffness=1e-2, mass_per_length=1.0,
                               torsional_stiffness=7e-3)
    rod = model.add_beam(fm.arc((1, 0, 0), 1.0, (0, 0, 0), -1.2, (0, 0, 1), elements=3),
                         section=section, element="ancf_rod14", damping=0.05)
    cable = model.add_beam(fm.line((0, 1, 0), (1, 1.3, 0.2), elements=2), section=section)
    for beam in (rod, cable):
        model.clamp(beam.first_node)
        model.add_point_load(beam.last_node, moment=(0.7, -0.4, 0.9),
                             function=lambda t: 1.0 + t)
        model.add_point_load(beam.node(1), moment=(-0.3, 0.5, 0.2))
    # a body held by the rod's tip (position, slope and section turn) and one by its middle node
    tip = model.add_rigid_body(mass=0.1, inertia=(1e-3, 2e-3, 3e-3),
                               position=tuple(rod.last_node.position + (0.05, 0.0, 0.02)))
    model.rigid(rod.last_node, tip)
    mid = model.add_rigid_body(mass=0.1, inertia=(1e-3, 1e-3, 1e-3),
                               position=tuple(rod.node(2).position))
    model.spherical(rod.node(2), mid)
    return model


@pytest.mark.parametrize("name, model", list(_exact_tangent_models()),
                         ids=[n for n, _ in _exact_tangent_models()])
def test_matrix_is_the_derivative_of_the_residual(name, model):
    rng = np.random.default_rng(3)
    asm = Assembly(model)
    n, m = asm.n_coords, asm.n_mult
    q = asm.q_ref + 1e-5 * rng.standard_normal(n)
    v = 0.05 * rng.standard_normal(n)
    qdd = rng.standard_normal(n)
    lam = rng.standard_normal(m)
    t = 0.013
    cM, cC, cK = 1.7, 0.3, 2e-2

    def res(q_, v_, a_, l_):
        rq, rl = np.zeros(n), np.zeros(m)
        asm.evaluate(q_, v_, a_, l_, t, rq, rl)
        return np.concatenate([rq, rl])

    asm.evaluate(q, v, qdd, lam, t, np.zeros(n), np.zeros(m), matrix=(cM, cC, cK))
    A = asm.matrix.toarray()
    for joint in model.interactions:   # the clearance contacts are active (else nothing tested)
        if isinstance(joint, fm.SlidingClearanceJoint):
            rows = joint.output(asm, q, v, lam, t)
            assert rows, f"{name}: no active contact"
            if name == "two_contacts_one_section":
                assert [r["section"] for r in rows] == [0, 0]
    h = 1e-7
    fd = np.zeros((n + m, n + m))
    for j in range(n):   # d r / d x with q' = cK dx, v' = cC dx, q'' = cM dx (the Newton update)
        e = np.zeros(n)
        e[j] = h
        fd[:, j] = (res(q + cK * e, v + cC * e, qdd + cM * e, lam)
                    - res(q - cK * e, v - cC * e, qdd - cM * e, lam)) / (2 * h)
        fd[n:, j] /= cK   # constraint rows are not scaled: Phi_q
    for j in range(m):
        e = np.zeros(m)
        e[j] = h
        fd[:, n + j] = (res(q, v, qdd, lam + e) - res(q, v, qdd, lam - e)) / (2 * h)
    for rows, cols in ((slice(0, n), slice(0, n)), (slice(0, n), slice(n, None)),
                       (slice(n, None), slice(0, n))):
        ref = fd[rows, cols]
        if ref.size:
            assert np.abs(A[rows, cols] - ref).max() <= FD_RTOL * max(np.abs(ref).max(), 1e-12)


def test_several_element_groups_run_compiled():
    asm = Assembly(two_groups())
    # two cable groups, and no part of an element type the model does not use
    assert len(asm.system.beams) == 2 and asm.compiled_reason() == ""
    res = fm.simulate(two_groups(), t_end=0.01, dt=1e-3, record_energy=False)
    ref = fm.simulate(two_groups(), t_end=0.01, dt=1e-3, record_energy=False,
                      integrator=fm.GeneralizedAlpha(compiled=False))
    assert np.abs(res.q[-1] - res.q[0]).max() > 1e-7
    assert np.abs(res.q - ref.q).max() < 1e-9 * np.abs(res.q).max()


def test_dropped_redundant_equations_have_no_multiplier():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        asm = Assembly(kitchen_sink(redundant=True), redundant_constraints="drop")
    assert asm.dropped_equations
    full = Assembly(kitchen_sink())
    assert asm.n_mult == full.n_mult


def test_models_without_a_compiled_form_say_why():
    m2, *_ = ex1.build()
    m2.interactions[0].tangent = "frozen_point"
    reason = Assembly(m2).compiled_reason()
    assert "sleeve" in reason and "no compiled form" in reason
    assert Assembly(ex1.build()[0]).compiled_reason() == ""


@pytest.mark.parametrize("name, t_end", [("kitchen_sink", 0.03), ("example2", 0.02)])
def test_compiled_and_python_integrators_agree(name, t_end):
    """Same equations, same convergence test (rtol 1e-10 here): trajectories agree to ~1e-8 of
    the largest displacement (the two loops take different iteration and refresh decisions
    only below the tolerance)."""
    runs = []
    for compiled in (True, False):
        model = kitchen_sink() if name == "kitchen_sink" else ex2.build()[0]
        integ = fm.GeneralizedAlpha(compiled=compiled,
                                    newton=fm.NewtonOptions(relative_tolerance=1e-10))
        res = fm.simulate(model, t_end=t_end, dt=1e-4, output_interval=t_end / 10,
                          integrator=integ, record_energy=False)
        runs.append(res)
    a, b = (r.q - r.q[0] for r in runs)
    assert np.abs(a).max() > 1e-6                        # it moves
    assert np.abs(a - b).max() < 1e-6 * np.abs(a).max()

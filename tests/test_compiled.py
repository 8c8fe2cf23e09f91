"""The compiled model (flexmbs.compiled) against the assembly it packs: the same residual, the
same iteration matrix and, through the compiled integrator, the same trajectories as the Python
path, for every kind of term (beam, bodies, body loads with moments and time functions, linear
and prescribed constraints, every joint of the term tables, sliding joints with friction and
axial force, clearance joints with friction and a dissipative law, dropped redundant equations).

The Python assembly is itself checked against finite differences (tests/test_assembly.py,
tests/constraints, tests/contact), so equality here (rounding level, 1e-12 of the largest
entry) carries those checks over to the compiled path.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

import flexmbs as fm
from flexmbs import compiled as cm
from flexmbs.assembly import Assembly

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "examples"))
import curved_beam_sleeve as ex1  # noqa: E402
import solar_array_wing as ex2  # noqa: E402

#: rounding level relative to the largest entry (the two paths sum the same terms in a
#: different order)
RTOL = 1e-12


def kitchen_sink(redundant: bool = False) -> fm.Model:
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
                                  pose=frame.shifted((0.0, 0.0, -2e-4)), name="sleeve")
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


def _state(asm: Assembly, rng: np.random.Generator, t: float):
    """A state near the reference with motion, accelerations and multipliers of realistic size
    (the clearance joints keep their beams inside the bores)."""
    q = asm.q_ref.copy()
    q += 1e-5 * rng.standard_normal(q.size)
    v = 0.05 * rng.standard_normal(q.size)
    qdd = rng.standard_normal(q.size)
    lam = rng.standard_normal(asm.n_mult)
    return q, v, qdd, lam


@pytest.mark.parametrize("name, model", list(_models()), ids=[n for n, _ in _models()])
def test_residual_and_matrix_equal_the_assembly(name, model, rng):
    asm = Assembly(model)
    packed, functions, reason = cm.compile_model(asm)
    assert packed is not None, reason
    cm.push_state(packed, asm)
    for t in (0.0, 0.013):
        q, v, qdd, lam = _state(asm, rng, t)
        fv = np.array([fn(t) for fn in functions])
        rq, rl = np.zeros(asm.n_coords), np.zeros(asm.n_mult)
        coef = (1.7, 0.3, 2e-8)
        scale_py = asm.evaluate(q, v, qdd, lam, t, rq, rl, matrix=coef)
        ref = np.concatenate([rq, rl])
        r = np.zeros(asm.n_total)
        scale, code = cm.residual(packed, q, v, qdd, lam, fv, r)
        assert code == 0
        assert np.abs(r - ref).max() <= RTOL * np.abs(ref).max()
        assert scale == pytest.approx(scale_py, rel=1e-14)
        data = np.zeros_like(asm.matrix.data)
        kscale, code = cm.jacobian(packed, q, v, qdd, lam, fv, *coef, data)
        assert code == 0 and kscale == pytest.approx(asm.stiffness_scale, rel=1e-14)
        assert np.abs(data - asm.matrix.data).max() <= RTOL * np.abs(asm.matrix.data).max()


def test_dropped_redundant_equations_are_skipped(rng):
    with pytest.warns(UserWarning, match="dropping 1 redundant"):
        asm = Assembly(kitchen_sink(redundant=True), redundant_constraints="drop")
    assert asm.dropped_equations
    packed, functions, reason = cm.compile_model(asm)
    assert packed is not None, reason
    q, v, qdd, lam = _state(asm, rng, 0.0)
    fv = np.array([fn(0.0) for fn in functions])
    rq, rl = np.zeros(asm.n_coords), np.zeros(asm.n_mult)
    asm.evaluate(q, v, qdd, lam, 0.0, rq, rl, matrix=(1.0, 0.1, 1e-8))
    r = np.zeros(asm.n_total)
    cm.residual(packed, q, v, qdd, lam, fv, r)
    ref = np.concatenate([rq, rl])
    assert np.abs(r - ref).max() <= RTOL * np.abs(ref).max()
    data = np.zeros_like(asm.matrix.data)
    cm.jacobian(packed, q, v, qdd, lam, fv, 1.0, 0.1, 1e-8, data)
    assert np.abs(data - asm.matrix.data).max() <= RTOL * np.abs(asm.matrix.data).max()


def test_models_without_a_compiled_form_say_why():
    model = fm.Model()
    b1 = model.add_beam(fm.line((0, 0, 0), (1, 0, 0), elements=2), section=fm.CircularSection(1e-3),
                        material=fm.Material(E=1e9, rho=1000))
    model.add_beam(fm.line((0, 1, 0), (1, 1, 0), elements=2), section=fm.CircularSection(1e-3),
                   material=fm.Material(E=1e9, rho=1000), options=fm.CableOptions(bending="scalar"))
    model.clamp(b1.first_node)
    packed, _, reason = cm.compile_model(Assembly(model))
    assert packed is None and "one beam group" in reason
    m2, *_ = ex1.build()
    m2.interactions[0].consistent = True
    packed, _, reason = cm.compile_model(Assembly(m2))
    assert packed is None and "consistent contact tangent" in reason


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

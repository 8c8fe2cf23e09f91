"""The rope length limiter (flexmbs/ropes.py), added as docs/extending.md says a joint kind is
added (issue 54, item 8).

Independent references: central differences of the assembled residual (the exact tangent);
the closed forms of a mass hanging on a rope (tension m g, stretch m g / k) and of the rigid
pendulum's period from the horizontal (4 √(L/g) K(1/√2)); a spring-damper with the one-sided
table ``[[-1, 0], [0, 0], [1, k]]`` (the undamped linear rope written another way); energy
conservation of a rope that goes slack and snaps taut again with an elastic law.

Every model here has bodies and a rotation lock (a generic joint, which compiles the springs
with it) besides its ropes: one kernel type for the whole file (each new combination of kinds
is a compile).
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.special import ellipk

import flexmbs as fm
from flexmbs.assembly import Assembly
from flexmbs.errors import ModelError
from flexmbs.io.probes import EnergyProbe, RopeProbe
from tests.contact.test_superellipse_compiled import assert_tangent_is_the_differences

G = 9.81
L = 1.0
MASS = 1.0
K = 2e4


def _pendulum(model: fm.Model, *, start: tuple, velocity: tuple, name: str) -> fm.RigidBody:
    """A point-like body at ``start`` whose rotation is locked (a point mass)."""
    body = model.add_rigid_body(mass=MASS, inertia=(1e-3, 1e-3, 1e-3), position=start,
                                velocity=velocity, name=name)
    model.joint(body, fm.GROUND, point=start, translation=(0, 0, 0), rotation=(1, 1, 1),
                name=f"{name}_lock")
    return body


def _model(law: object, *, start=(L, 0.0, 0.0), velocity=(0.0, 0.0, 0.0), spring: bool = True,
           length: float = L) -> tuple[fm.Model, fm.Rope, fm.RigidBody, fm.RigidBody | None]:
    """A rope pendulum from the origin and, with ``spring``, 10 m away the same pendulum on a
    spring-damper with the one-sided table."""
    model = fm.Model(gravity=(0, 0, -G))
    body = _pendulum(model, start=start, velocity=velocity, name="bob")
    rope = model.add_joint(fm.Rope(fm.GROUND, body, length=length, contact=law, name="rope"))
    twin = None
    if spring:
        twin_start = (start[0], 10.0 + start[1], start[2])
        twin = _pendulum(model, start=twin_start, velocity=velocity, name="twin")
        model.add_spring_damper(fm.GROUND, twin, point_a=(0, 10.0, 0), rest_length=length,
                                table=[[-1.0, 0.0], [0.0, 0.0], [1.0, K]], name="twin_rope")
    return model, rope, body, twin


def test_the_tangent_is_the_differences_of_the_residual():
    """Taut ropes between a beam node and a body point (Euler parameters in the Jacobian), and
    between the ground and a body, with damping (linear law with its ramp) and with the
    Hunt-Crossley χ damping at a stored approach velocity: the assembled ``cK K + cC C`` equals
    central differences of the residual."""
    model = fm.Model(gravity=(0, 0, -G))
    beam = model.add_beam(fm.line((0, 0, 0), (0.5, 0, 0), elements=3), name="boom",
                          section=fm.CircularSection(5e-3), material=fm.Material(E=2.1e11, rho=7800))
    model.clamp(beam.first_node)
    c, s = math.cos(0.3), math.sin(0.3)
    pose = fm.Pose(np.array([0.6, 0.1, -0.4]), np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]]))
    body = model.add_rigid_body(mass=2.0, inertia=(0.01, 0.02, 0.03), pose=pose, name="load")
    model.add_spring_damper(fm.GROUND, body, point_a=(0.6, 0.1, 0.5), stiffness=10.0, name="soft")
    model.joint(body, fm.GROUND, point=(0.6, 0.1, -0.4), translation=(0, 0, 1), name="guide")
    hang = model.add_joint(fm.Rope(beam.last_node, body, point_b=(0.05, 0.02, 0.03), length=0.40,
                                   contact=fm.LinearPenalty(stiffness=3e4, damping=40.0)))
    guy = model.add_joint(fm.Rope(fm.GROUND, body, point_a=(1.2, 0.1, -0.4), point_b=(0.05, 0, 0),
                                  length=0.5, contact=fm.HuntCrossley(stiffness=1e6, restitution=0.6,
                                                                      exponent=1.5)))
    asm = Assembly(model)
    rng = np.random.default_rng(5)
    q = asm.q_ref + 1e-5 * rng.standard_normal(asm.n_coords)
    v = 0.05 * rng.standard_normal(asm.n_coords)
    guy.approach[0] = 0.2
    for rope in (hang, guy):
        length, _rate, tension = rope.state_of(q, v)
        assert length > rope.length and tension > 0.0, (rope.name, length, tension)
    assert_tangent_is_the_differences(asm, q, v)


def test_a_hanging_mass_pulls_its_weight_and_stretches_the_rope_by_mg_over_k():
    """Statics: the mass below its pivot hangs on the rope (taut from the start: a slack rope
    holds nothing across); tension m g (probe), stretch m g / k, and the rope's stored energy
    is the law's potential ½ k δ²."""
    model, rope, body, _twin = _model(fm.LinearPenalty(stiffness=K), start=(0.0, 0.0, -L - 1e-4),
                                      spring=False)
    asm = Assembly(model)
    st = fm.solve_static(asm)
    z = st.q[asm.body_dofs(body)[2]]
    assert z == pytest.approx(-(L + MASS * G / K), rel=1e-9)
    probe = RopeProbe("hang", rope)
    st.v = np.zeros_like(st.q)  # type: ignore[attr-defined]   # the state a probe reads
    length, tension = probe.evaluate(asm, st)
    assert tension == pytest.approx(MASS * G, rel=1e-9)
    assert length == pytest.approx(L + MASS * G / K, rel=1e-9)
    assert asm.energies(st.q, np.zeros_like(st.q))["rope"] == pytest.approx(
        0.5 * K * (MASS * G / K) ** 2, rel=1e-9)
    assert "rope" in EnergyProbe.quantities()


def test_released_from_the_horizontal_it_swings_with_the_rigid_pendulums_period_and_equals_the_spring():
    """Released at rest with the rope straight and horizontal: the rope stays taut and the
    swing's period is the rigid pendulum's 4 √(L/g) K(sin 45°) to the rope's stretch (~5e-3
    with k = 2e4 N/m); the spring with the one-sided table follows the same path to solver
    rounding (an undamped linear rope is that spring)."""
    model, rope, body, twin = _model(fm.LinearPenalty(stiffness=K))
    period = 4 * math.sqrt(L / G) * ellipk(0.5)
    res = fm.simulate(model, t_end=1.1 * period, dt=2e-3, probes=[RopeProbe("rope", rope)])
    asm = res.assembly
    x = res.q[:, asm.body_dofs(body)[0]]
    # the bob passes under the pivot (x = 0) at a quarter period and comes back to rest at the
    # far side at half a period: x crosses 0 going down twice per period
    crossings = []
    for i in range(1, len(x)):
        if x[i - 1] > 0 >= x[i]:
            crossings.append(res.t[i - 1] + (res.t[i] - res.t[i - 1]) * x[i - 1] / (x[i - 1] - x[i]))
    assert len(crossings) >= 1
    assert crossings[0] == pytest.approx(period / 4, rel=5e-3)
    twin_q = res.q[:, asm.body_dofs(twin)[:3]] - np.array([0.0, 10.0, 0.0])
    assert np.abs(twin_q - res.q[:, asm.body_dofs(body)[:3]]).max() < 1e-7
    tension = res.extra["probes"]["rope_tension"]
    swing = (res.t > 0.02 * period) & (res.t < 0.48 * period)
    assert np.min(tension[swing]) > 0.0     # taut between the turning points (there T = 0)
    # at the bottom the rigid pendulum's tension is 3 m g
    assert np.max(tension) == pytest.approx(3 * MASS * G, rel=2e-2)


@pytest.mark.filterwarnings("ignore:rho_inf = 1 with the nonlinear constraint")  # the lock's
def test_a_rope_that_goes_slack_and_snaps_taut_keeps_its_energy():
    """Thrown sideways from below the pivot at 6 m/s (√(2gL) < v < √(5gL)): the rope goes slack
    above the horizontal (free flight) and snaps taut again: the undamped linear law stores
    and gives back the snap's energy (total energy constant to 1 %, the run's energy check
    passes); the tension is 0 while slack. With Hunt-Crossley damping the snap dissipates:
    the energy falls, the run's check finds no gain, and the approach velocity is kept."""
    model, rope, body, _twin = _model(fm.LinearPenalty(stiffness=K), start=(0.0, 0.0, -L),
                                      velocity=(6.0, 0.0, 0.0), spring=False)
    res = fm.simulate(model, t_end=1.5, dt=1e-3, probes=[RopeProbe("rope", rope)],
                      integrator=fm.GeneralizedAlpha(rho_inf=1.0))
    tension = res.extra["probes"]["rope_tension"]
    length = res.extra["probes"]["rope_length"]
    slack = length < L
    assert slack.sum() > 50 and (~slack).sum() > 50     # both phases, several times
    assert np.all(tension[slack] == 0.0)
    snaps = np.flatnonzero(slack[:-1] & ~slack[1:])
    assert len(snaps) >= 1
    total = res.energy["total"]
    exchanged = np.ptp(res.energy["kinetic"])
    assert np.ptp(total) < 1e-2 * exchanged
    check = res.extra["checks"]["energy"]
    assert check["checked"] and check["passed"], check
    assert rope.energy_flow() == "conserves"

    damped, rope_d, _b, _t = _model(fm.HuntCrossley(stiffness=K, restitution=0.3, exponent=1.0),
                                    start=(0.0, 0.0, -L), velocity=(6.0, 0.0, 0.0), spring=False)
    assert rope_d.energy_flow() == "dissipates"
    approach = []
    res_d = fm.simulate(damped, t_end=1.5, dt=1e-3, integrator=fm.GeneralizedAlpha(rho_inf=1.0),
                        observer=lambda state: approach.append(rope_d.get_state()["approach"]))
    e = res_d.energy["total"]
    assert e[-1] < 0.5 * e[0]
    check = res_d.extra["checks"]["energy"]
    assert check["checked"] and check["passed"] and check["quantity"] == "energy gained", check
    assert check["dissipated_by"] == ["joint 'rope'"]
    # the stretch rate at which it snapped taut is kept while taut (the χ damping's v₀)
    assert 0.5 < max(approach) < 6.0


def test_bad_ropes_are_one_line_errors():
    model = fm.Model()
    body = model.add_rigid_body(mass=1.0, inertia=(1, 1, 1), position=(1, 0, 0), name="b")
    law = fm.LinearPenalty(stiffness=1e3)
    with pytest.raises(ModelError, match=r"^rope 'r': length must be a finite number > 0 \[m\] "):
        fm.Rope(fm.GROUND, body, length=-1.0, contact=law, name="r")
    with pytest.raises(ModelError, match=r"^rope 'r': contact must be a force law"):
        fm.Rope(fm.GROUND, body, length=1.0, contact=3.0, name="r")  # type: ignore[arg-type]
    with pytest.raises(ModelError, match=r"^rope 'r': both ends on the ground"):
        fm.Rope(fm.GROUND, fm.GROUND, length=1.0, contact=law, name="r")
    with pytest.raises(ModelError, match=r"^rope 'r': its ends coincide"):
        model.add_joint(fm.Rope(fm.GROUND, body, point_a=(1, 0, 0), length=1.0, contact=law, name="r"))
    other = fm.Model().add_rigid_body(mass=1.0, inertia=(1, 1, 1), name="elsewhere")
    with pytest.raises(ModelError, match=r"^rope 'r': expected a rigid body of this model"):
        model.add_joint(fm.Rope(fm.GROUND, other, length=1.0, contact=law, name="r"))


def test_the_writers_ask_the_kinds_record_not_the_object():
    """Issue 54, item 5: the output hooks and the energy of a kind are declared on its record
    (``InteractionKind``): the clearance joint's contacts, sections, outlines and hole record
    are its record's; a rope declares none, so its model's frames have no contact or outline
    block, and a method of the same name on an object is not an output hook. The energy names
    of the probe are the records' (no list by name)."""
    from flexmbs import driver
    from flexmbs.contact.joint import CLEARANCE, SlidingClearanceJoint
    from flexmbs.io.frames import FrameBuilder
    from flexmbs.ropes import ROPE

    # the clearance record's hooks call the joint's methods, so a subclass answers its own
    # (a tube joint's hole record names its tube)
    joint = SimpleNamespace(output=lambda *a: ["contacts", a],
                            section_records=lambda *a: ["sections", a],
                            section_outlines=lambda *a: ("outlines", a),
                            hole_record=lambda: {"hole": "record"})
    assert CLEARANCE.contacts is not None and CLEARANCE.contacts(joint, 1, 2) == ["contacts", (1, 2)]
    assert CLEARANCE.sections is not None and CLEARANCE.sections(joint, 3) == ["sections", (3,)]
    assert CLEARANCE.outlines is not None and CLEARANCE.outlines(joint, 4) == ("outlines", (4,))
    assert CLEARANCE.hole_record is not None and CLEARANCE.hole_record(joint) == {"hole": "record"}
    assert hasattr(SlidingClearanceJoint, "section_outlines")
    model, rope, _body, _twin = _model(fm.LinearPenalty(stiffness=K), start=(0.0, 0.0, -L))
    rope.output = lambda *args: [{"x": 1.0}]                # type: ignore[attr-defined]
    rope.section_outlines = lambda *args: np.zeros((1, 4, 3))  # type: ignore[attr-defined]
    assert driver.kind_of(rope) is ROPE
    assert ROPE.contacts is ROPE.sections is ROPE.outlines is ROPE.hole_record is None
    frames = FrameBuilder(Assembly(model))
    assert [b["kind"] for b in frames.block_tree()] == ["body", "body", "springs"]
    labels = [kind.energy[0] for kind in driver.INTERACTION_KINDS if kind.energy is not None]
    assert labels == ["contact", "rope"]
    assert EnergyProbe.quantities() == ("total", "kinetic", "strain", "gravity", "spring", *labels)

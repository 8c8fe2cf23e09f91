"""Bores along a curve (issue "a rod or wire inside a curved tube", item 1): sections normal to
the curve, their axes carried along it without twist, fed to the same detection and exact
tangent as the straight bore.

Independent references: the helix's rotation-minimising frame in closed form (its normal turns
against the Frenet normal at minus the torsion); the straight bore (a straight path must give
the same residual, matrix and motion); central differences of the contact potential and of the
assembled residual; the energy of undamped, frictionless motion."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.assembly import Assembly
from flexmbs.contact.bores import transported_frames
from flexmbs.errors import ModelError, ScenarioError
from tests.contact.test_potential import (
    GRADIENT_TOL,
    STIFFNESS,
    WIRE_R,
    _bent,
    _checked_tangent,
    eyelet_on_wire,
    gradient_error,
)

BORE_R = 2e-3
#: the curved test bore: 8 mm long, bent with a 30 mm radius towards body +y (sagitta 0.27 mm)
BEND_RADIUS = 0.03
BORE_LENGTH = 8e-3


def bent_bore(sections: int = 9, radius: float = BEND_RADIUS, **kw) -> fm.CurvedBore:
    """An arc through the body origin with tangent body x there, bending towards body +y."""
    angle = BORE_LENGTH / radius
    start = (-radius * math.sin(angle / 2), radius - radius * math.cos(angle / 2), 0.0)
    path = fm.arc((0.0, radius, 0.0), radius, start, angle, normal=(0, 0, 1), elements=8)
    return fm.CurvedBore(path, radius=BORE_R, sections=sections, **kw)


def _helix_twist_error(n: int) -> float:
    """Largest error of the transported frame's turn against the Frenet frame on a helix
    (radius 1, pitch 2π·0.5, one turn): the exact turn is −τ s."""
    a, b = 1.0, 0.5
    c = math.hypot(a, b)
    s = np.linspace(0.0, 2 * math.pi * c, n)
    u = s / c
    pts = np.stack([a * np.cos(u), a * np.sin(u), b * u], axis=1)
    tan = np.stack([-a * np.sin(u), a * np.cos(u), np.full_like(u, b)], axis=1) / c
    normal = np.stack([-np.cos(u), -np.sin(u), np.zeros_like(u)], axis=1)   # Frenet N
    binormal = np.cross(tan, normal)
    F = transported_frames(pts, tan, normal[0])
    ey = F[:, :, 1]
    turn = np.unwrap(np.arctan2(np.einsum("ij,ij->i", ey, binormal),
                                np.einsum("ij,ij->i", ey, normal)))
    assert np.allclose(np.einsum("ij,ij->i", F[:, :, 0], ey), 0.0, atol=1e-14)
    assert np.allclose(np.linalg.det(F), 1.0, atol=1e-13)
    return float(np.abs(turn - (-b / c**2) * s).max())


def test_transported_frame_turns_against_the_helix_torsion_with_fourth_order():
    """Rotation-minimising frame (double reflection) on a helix: turn against the Frenet
    normal = −τ s; the error falls with the fourth power of the spacing."""
    coarse, fine = _helix_twist_error(41), _helix_twist_error(81)
    assert fine < 1e-6
    assert coarse / fine > 12.0          # ≈ 16 for fourth order


def test_a_straight_path_is_the_straight_bore():
    """A CurvedBore along a straight line on body x gives the sleeve's residual, matrix and
    motion to rounding."""
    runs = []
    for hole in (fm.CircleHole(BORE_R, BORE_LENGTH, 9),
                 fm.CurvedBore(fm.line((-BORE_LENGTH / 2, 0, 0), (BORE_LENGTH / 2, 0, 0),
                                       elements=3), radius=BORE_R, sections=9)):
        model, joint, body, _ = eyelet_on_wire(math.radians(8.0), 1.1e-3, hole=hole,
                                               free=True)
        asm = Assembly(model)
        q = _bent(asm, joint)
        n, m = asm.n_coords, asm.n_mult
        r1, r2 = np.zeros(n), np.zeros(m)
        asm.evaluate(q, np.zeros(n), np.zeros(n), np.zeros(m), 0.0, r1, r2,
                     matrix=(0.0, 0.0, 1.0))
        body.velocity = np.array([0.05, 0.0, 0.0])
        res = fm.simulate(model, t_end=1e-3, dt=2e-5, output_interval=1e-3,
                          integrator=fm.GeneralizedAlpha(rho_inf=0.9, adaptive=False))
        runs.append((r1, asm.matrix.toarray(), res.q[-1]))
    (ra, Ka, qa), (rb, Kb, qb) = runs
    assert np.abs(ra).max() > 1.0                          # in contact
    assert np.abs(ra - rb).max() <= 1e-12 * np.abs(ra).max()
    assert np.abs(Ka - Kb).max() <= 1e-12 * np.abs(Ka).max()
    assert np.abs(qa - qb).max() <= 1e-12


@pytest.mark.parametrize(("deg", "push", "axis"), [(0.0, 1.1e-3, "y"), (8.0, 0.9e-3, "y"),
                                                   (8.0, 0.8e-3, "z")])
def test_curved_bore_force_is_the_gradient_of_its_potential(deg, push, axis):
    """Force = −∂V/∂q by central differences (1e-7 relative) with sections turned along the
    curve; the bend puts the contacts at the bore's ends (pushed along y) or along it (z)."""
    model, joint, body, _ = eyelet_on_wire(math.radians(deg), push, axis, hole=bent_bore())
    asm = Assembly(model)
    q = _bent(asm, joint)
    err, kinds = gradient_error(joint, body, asm, q)
    assert kinds, "the configuration must be in contact"
    assert err < GRADIENT_TOL
    if deg == 0.0:      # the bend lifts the ends of the bore onto the wire, not its middle
        assert 0 in kinds and 8 in kinds and 4 not in kinds


@pytest.mark.parametrize(("friction", "ramp"), [(None, None), (0.3, None), (None, 0.5)])
def test_curved_bore_tangent_equals_central_differences(friction, ramp):
    """The assembled iteration matrix (exact contact tangent with turned sections; the stick
    law when friction is on; with ``ramp``, every contact inside the damped law's viscous
    ramp, its δ-derivative c s′(δ) δ̇ in the stiffness, issue 53 item 2) against central
    differences of the assembled residual."""
    law = None
    if ramp is not None:        # the ramp's length: `ramp` times the clearance (1.5 mm here)
        law = fm.LinearPenalty(stiffness=STIFFNESS, damping=5.0,
                               damping_onset=ramp * (BORE_R - WIRE_R))
    model, joint, body, _ = eyelet_on_wire(math.radians(8.0), 0.9e-3, hole=bent_bore(),
                                           free=True, damping=5.0, friction=friction, law=law)
    asm = Assembly(model)
    asm.begin(asm.q_ref)
    q = _bent(asm, joint)
    v = 1e-2 * np.random.default_rng(5).standard_normal(asm.n_coords)
    if ramp is not None:
        depths = [-res.gap for _k, _j, _kind, _eP, res, *_ in joint._observed(q, v)]
        assert depths and max(depths) < joint.contact.damping_onset, depths
    _checked_tangent(asm, joint, body, q, v)


def _sliding_energy_error(dt: float) -> float:
    """The curved eyelet thrown along and across a clamped straight wire: undamped,
    frictionless, Hertz-type contact, generalized-α with ρ∞ = 1; 20 ms. Largest relative
    energy error."""
    model, joint, body, _ = eyelet_on_wire(0.0, 0.6e-3, hole=bent_bore(), free=True,
                                           half=0.02, elements=4, at=0.0,
                                           law=fm.Hertz(stiffness=2e7, exponent=2.0))
    body.velocity = np.array([0.3, 0.2, 0.05])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = fm.simulate(model, t_end=0.02, dt=dt, output_interval=1e-4,
                          integrator=fm.GeneralizedAlpha(rho_inf=1.0, adaptive=False))
    E = res.energy["total"]
    assert np.ptp(res.energy["contact"]) > 0.05 * E[0]     # the contact stores energy
    return float(np.abs(E - E[0]).max() / E[0])


def test_curved_bore_keeps_the_energy_of_frictionless_motion():
    """No work from the curved bore's contact: the energy error falls like h² (order > 1.8)."""
    steps = np.array([2e-5, 1e-5])
    errors = [_sliding_energy_error(float(h)) for h in steps]
    assert errors[1] < 1e-3
    assert math.log(errors[0] / errors[1]) / math.log(2.0) > 1.8, errors


def test_curved_bore_input_errors():
    path = fm.arc((0.0, 0.03, 0.0), 0.03, (0.0, 0.0, 0.0), 0.3, normal=(0, 0, 1), elements=4)
    with pytest.raises(ModelError, match="either radius= .* or section="):
        fm.CurvedBore(path, sections=5)
    with pytest.raises(ModelError, match="either sections= .* or spacing="):
        fm.CurvedBore(path, radius=BORE_R)
    with pytest.raises(ModelError, match="spacing must be a number > 0"):
        fm.CurvedBore(path, radius=BORE_R, spacing=0.0)
    with pytest.raises(ModelError, match="tighter than the bore's radius"):
        fm.CurvedBore(path, radius=0.05, sections=20)
    with pytest.raises(ModelError, match="'up' is along the path"):
        fm.CurvedBore(path, radius=BORE_R, sections=5, up=(1.0, 0.0, 0.0))
    bore = fm.CurvedBore(path, radius=BORE_R, spacing=1e-3)
    assert bore.sections == math.ceil(0.3 * 0.03 / 1e-3) + 1
    origins, axes = bore.frames()
    assert np.allclose(origins[0], 0.0, atol=1e-15)
    assert np.allclose(axes[0], np.eye(3), atol=1e-12)     # tangent x, e_y = body y at the start
    assert np.allclose(axes[:, :, 2], [0.0, 0.0, 1.0], atol=1e-12)   # a planar bend: e_z fixed


SCENARIO = """
[[beams]]
name = "wire"
elements = 8
radius = 0.8e-3
youngs_modulus = 7e10
density = 2700
geometry = {{ line = {{ start = [-0.1, 0, 0], end = [0.1, 0, 0] }} }}
[[rigid_bodies]]
name = "tube"
mass = 2e-3
inertia = [2e-8, 1e-6, 1e-6]
pose = {{ position = [0.0, -1.0e-3, 0] }}
[[joints]]
name = "bore"
type = "sliding_clearance"
beam = "wire"
body = "tube"
hole = {{ shape = "circle", radius = 2e-3, {hole} }}
contact = {{ stiffness = 2e5 }}
[simulation]
t_end = 1e-3
dt = 1e-4
gravity = [0, 0, 0]
"""

ARC = "path = { arc = { center = [0, 0.03, 0], radius = 0.03, start = [0, 0, 0], angle = 0.3 } }"


def _load(tmp_path, hole: str):
    from flexmbs.io.scenario import load_scenario

    f = tmp_path / "s.toml"
    f.write_text(SCENARIO.format(hole=hole))
    return load_scenario(f)


def test_scenario_bore_along_a_path(tmp_path):
    sc = _load(tmp_path, ARC + ", spacing = 1e-3")
    joint = next(j for j in sc.model.interactions if isinstance(j, fm.SlidingClearanceJoint))
    assert isinstance(joint.hole, fm.CurvedBore)
    assert joint.hole.sections == 10 and joint.hole.length == pytest.approx(9e-3, rel=1e-6)
    for hole, match in [(ARC + ", length = 0.01, sections = 5", r"hole\.length: a bore along"),
                        (ARC, "needs sections = <count> or spacing"),
                        ("length = 0.01, spacing = 1e-3", r"hole\.spacing: only for a bore"),
                        (ARC + ", sections = 5, spacing = 1e-3", "give only one of"),
                        ("path = { circle = 1 }, sections = 5", "unknown key 'circle'")]:
        with pytest.raises(ScenarioError, match=match):
            _load(tmp_path, hole)


# ---------------------------------------------------------------------------------------------
# open ends and crossings found by the section tree (issue 30, item 2)
def _wire_into_bore(open_ends: bool, tip: float = 0.0, push: float = 1.3e-3,
                    feed: float = 0.0):
    """A clamped wire along x ending at ``tip``, a 40 mm bore (21 sections) centred at the
    origin, pushed along y so the wire touches its wall; with ``feed`` the clamp moves the
    wire that far along x in 0.01 s."""
    model = fm.Model(gravity=(0, 0, 0))
    wire = model.add_beam(fm.line((-0.1, 0, 0), (tip, 0, 0), elements=10), name="wire",
                          section=fm.CircularSection(0.8e-3), material=fm.Material(E=7e10, rho=2700))
    if feed:
        model.prescribe(wire.first_node, [0], fm.Ramp(start=0.0, end=0.01, value=feed,
                                                      smooth=True), name="feed")
        model.prescribe(wire.first_node, [1, 2, 3, 4, 5], name="feed_line")
    else:
        model.clamp(wire.first_node)
    body = model.add_rigid_body(mass=2e-3, inertia=(2e-8, 1e-6, 1e-6),
                                pose=fm.Pose(np.array([0.0, push, 0.0]), np.eye(3)), name="tube")
    model.fix_body(body)
    hole = fm.Hole(fm.CircleHole(BORE_R, 0.04).section, 0.04, 21, open_ends=open_ends)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        joint = model.add_joint(fm.SlidingClearanceJoint(
            wire, body, hole=hole, contact=fm.LinearPenalty(stiffness=2e5)))
    return model, joint


def test_open_ends_the_beam_may_end_inside_the_bore():
    """A wire ending in the middle of an open bore: the sections past its tip are idle, the
    others carry its contacts, and so does the tip section of its last end (slot n + 1; the
    first end, outside the mouth, has none); a closed bore refuses the same start."""
    model, joint = _wire_into_bore(True)
    asm = Assembly(model)
    q = asm.q_ref
    sections = {k for k, *_ in joint._contacts(q, np.zeros_like(q), False, False)}
    n = len(joint.stations)
    regular = {k for k in sections if k < n}
    assert regular and max(regular) <= 10 and min(regular) == 0
    assert sections - regular == {n + 1} and list(joint.state.tip_on) == [False, True]
    r = np.zeros(asm.n_coords)
    joint.evaluate(None, q, np.zeros_like(q), None, 0.0, r, None)
    assert np.abs(r).max() > 0.0
    with pytest.raises(ModelError, match="does not pass through the hole"):
        _wire_into_bore(False)


def test_the_sections_crossed_are_listed_as_the_wire_advances():
    """A wire fed 12 mm into an open bore (its tip from the middle towards the far mouth): the
    compiled steps keep the list of sections crossed at each step's start equal to the
    sections whose warm start is set (far sections are never visited), and the wire gains
    the sections it enters."""
    model, joint = _wire_into_bore(True, feed=0.012)
    before = int(np.count_nonzero(np.asarray(joint.state.elem) >= 0))
    res = fm.simulate(model, t_end=0.012, dt=2e-4, output_interval=0.004,
                      integrator=fm.GeneralizedAlpha(rho_inf=0.8))
    listed = joint.state.ws_list
    assert listed[0] >= 0, "the compiled post-step lists the crossed sections"
    crossed = np.flatnonzero(np.asarray(joint.state.elem) >= 0)
    np.testing.assert_array_equal(listed[1:1 + listed[0]], crossed)
    assert crossed.size >= before + 5 and res.t[-1] == pytest.approx(0.012)


HAIRPIN = dict(R=10e-3, r_b=1e-3, y=9.5e-3, k=2e5)


def _hairpin_model() -> fm.Model:
    """A hairpin wire whose two strands pass through a wide bore (R = 10 mm, 9 sections)
    touching its wall on opposite sides (joint 'hairpin')."""
    R, r_b, y, k = HAIRPIN["R"], HAIRPIN["r_b"], HAIRPIN["y"], HAIRPIN["k"]
    pts, tans = [], []
    for x in np.linspace(-0.05, 0.05, 11):
        pts.append((x, -y, 0.0))
        tans.append((1.0, 0.0, 0.0))
    for a in np.linspace(-math.pi / 2, math.pi / 2, 9)[1:-1]:
        pts.append((0.05 + y * math.cos(a), y * math.sin(a), 0.0))
        tans.append((-math.sin(a), math.cos(a), 0.0))
    for x in np.linspace(0.05, -0.05, 11):
        pts.append((x, y, 0.0))
        tans.append((-1.0, 0.0, 0.0))
    model = fm.Model(gravity=(0, 0, 0))
    wire = model.add_beam(fm.polyline(pts, tans), name="wire", section=fm.CircularSection(r_b),
                          material=fm.Material(E=7e10, rho=2700))
    model.clamp(wire.first_node)
    model.clamp(wire.last_node)
    body = model.add_rigid_body(mass=1.0, inertia=(1, 1, 1), name="tube")
    model.fix_body(body)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model.add_joint(fm.SlidingClearanceJoint(wire, body, hole=fm.CircleHole(R, 0.04, 9),
                                                 contact=fm.LinearPenalty(stiffness=k),
                                                 name="hairpin"))
    return model


def test_a_beam_looping_back_crosses_each_section_twice():
    """A hairpin wire whose two strands pass through a wide bore (R = 10 mm) touching its wall
    on opposite sides: every section finds both crossings and a contact on each strand; the
    forces on the body cancel and each equals the penalty law's k δ."""
    R, r_b, y, k = HAIRPIN["R"], HAIRPIN["r_b"], HAIRPIN["y"], HAIRPIN["k"]
    model = _hairpin_model()
    joint = next(j for j in model.interactions if isinstance(j, fm.SlidingClearanceJoint))
    asm = Assembly(model)
    q = asm.q_ref
    contacts = joint._contacts(q, np.zeros_like(q), False, False)
    per: dict[int, list[float]] = {}
    for kk, _j, kind, _e, res, *_ in contacts:
        assert kind == 1
        per.setdefault(kk, []).append(res.Q[1])
    assert sorted(per) == list(range(9))
    assert all(len(v) == 2 and min(v) < 0 < max(v) for v in per.values())
    F = joint.contact_force(q, np.zeros_like(q))
    assert np.abs(F).max() < 1e-9
    delta = y + r_b - R
    for _k, _j, _kind, _e, res, *_ in contacts:
        assert res.f_n == pytest.approx(k * delta, rel=1e-9)


def test_more_contacts_than_the_tangent_holds_is_a_clear_error(monkeypatch):
    """The tangent's work arrays hold CONTACTS_PER_SECTION contacts per section (plus a margin):
    a joint with more at once rejects the iterate with a message that names the joint (here the
    hairpin's 18 contacts against a capacity cut to 4)."""
    import flexmbs.contact.joint as joint_module
    from flexmbs.errors import ConvergenceError

    monkeypatch.setattr(joint_module, "contact_capacity", lambda ns: 4)
    model = _hairpin_model()
    with pytest.raises(ConvergenceError, match=r"joint 'hairpin': more than 4 contact points at "
                                                r"once, the most its tangent holds"):
        asm = Assembly(model)          # (its set-up evaluates the matrix once)
        n, m = asm.n_coords, asm.n_mult
        asm.evaluate(asm.q_ref, np.zeros(n), np.zeros(n), np.zeros(m), 0.0, np.zeros(n),
                     np.zeros(m), matrix=(0.0, 0.0, 1.0))

"""A rod as the tube: its sections turn with the rod's twist (flexmbs.contact.tube; docs/theory.md
§II.9).

Independent references: the rod's director at the station written out here in numpy from its
definition (§I.2.2), which the section's y axis must follow; central differences of the turn,
of the pose map and of the assembled residual (the exact tangent over both beams' coordinates,
a rounded-rectangle lumen, friction and damping); the friction angle of a wire in a spinning
tube, tan α = μ (the wall's velocity comes from the rod's twist rate alone)."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.assembly import Assembly
from flexmbs.contact.shapes.rounded_rectangle import RoundedRectangleSection
from flexmbs.contact.tube import (
    POSE_SIZE,
    POSE_WORK,
    ROD_ORDER,
    SECTION_COORDS,
    TURN_SIZE,
    pose_curvature,
    rebase,
    section_turn,
    tube_pose,
)
from flexmbs.elements.ancf_rod import new_turn_work
from flexmbs.elements.hermite import shape_xi
from flexmbs.elements.rigid_body import rotation
from flexmbs.errors import ModelError
from tests.contact.test_potential import assert_tangent_over

L_E = 0.1


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


def _sr(a: np.ndarray, b: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The smallest rotation taking unit a to unit b, applied to v (Rodrigues)."""
    k = np.cross(a, b)
    c = float(a @ b)
    return c * v + np.cross(k, v) + (k @ v) / (1.0 + c) * k


def _rot(t: np.ndarray, angle: float, v: np.ndarray) -> np.ndarray:
    """v ⟂ t turned by ``angle`` about t."""
    return math.cos(angle) * v + math.sin(angle) * np.cross(t, v)


def _element(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A curved, twisted rod element (layout [r0, g0, φ0, r1, g1, φ1]) and its nodal bases."""
    q = np.array([0, 0, 0, 1, 0.2, 0.1, 0.3, 0.1, 0.01, 0, 0.9, 0.1, 0.3, -0.5], float)
    q += rng.normal(scale=0.05, size=q.size)
    t_bar = np.array([_unit(np.array([1.0, 0.1, 0.0])), _unit(np.array([1.0, 0.0, 0.2]))])
    d_bar = np.array([_unit(np.cross(t, [0.0, 0.3, 1.0])) for t in t_bar])
    return q, t_bar, d_bar


def _director(q: np.ndarray, t_bar: np.ndarray, d_bar: np.ndarray, xi: float) -> np.ndarray:
    """d2(ξ) = Rot(t, ξΔθ) SR(t0 → t) d2_0 (docs/theory.md §I.2.2), from the nodal triads
    d2_a = Rot(t_a, φ_a) SR(t̄_a → t_a) D̄_a."""
    t_n = [_unit(q[3:6]), _unit(q[10:13])]
    d_n = [_rot(t_n[a], q[6 + 7 * a], _sr(t_bar[a], t_n[a], d_bar[a])) for a in range(2)]
    d_hat = _sr(t_n[0], t_n[1], d_n[0])
    dth = math.atan2(np.cross(d_hat, d_n[1]) @ t_n[1], d_hat @ d_n[1])
    x = shape_xi(xi, L_E)[1] @ q[ROD_ORDER[:12]].reshape(4, 3)
    t = _unit(x)
    return _rot(t, xi * dth, _sr(t_n[0], t, d_n[0]))


def _frame(t: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Euler parameters of the frame with axes (t, y, t × y)."""
    A = np.column_stack([t, y, np.cross(t, y)])
    w = math.sqrt(max(1.0 + np.trace(A), 0.0)) / 2.0
    return np.array([w, (A[2, 1] - A[1, 2]) / (4 * w), (A[0, 2] - A[2, 0]) / (4 * w),
                     (A[1, 0] - A[0, 1]) / (4 * w)])


class _Section:
    """A section at ξ of the rod element with base (t̄_s, p̄_s)."""

    def __init__(self, rng: np.random.Generator) -> None:
        self.q, self.t_bar, self.d_bar = _element(rng)
        self.xi = float(rng.uniform(0.1, 0.9))
        ts = _unit(np.array([1.0, 0.25, -0.1]))
        self.ts, self.p0 = ts, _frame(ts, _unit(np.cross(ts, [0.2, 0.1, 1.0])))
        self.tw = new_turn_work()

    def turn(self, e: np.ndarray, second: bool) -> np.ndarray:
        turn = np.zeros(TURN_SIZE)
        section_turn(e, SECTION_COORDS, L_E, self.xi, self.ts, self.p0, self.t_bar, self.d_bar,
                     self.tw, turn, second)
        return turn

    def pose(self, e: np.ndarray, ve: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        pose, vel, J = np.zeros(POSE_SIZE), np.zeros(POSE_SIZE), np.zeros((POSE_SIZE, SECTION_COORDS))
        tube_pose(e, SECTION_COORDS, L_E, self.xi, self.ts, self.p0, self.t_bar, self.d_bar,
                  self.tw, np.zeros(TURN_SIZE), ve, pose, vel, J, np.zeros(POSE_WORK))
        return pose, vel, J


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_rod_section_turns_with_the_director(seed: int) -> None:
    """The section's y axis is the rod's director d2 at the station (written out independently)
    and its x axis the tangent; the turn's gradient and Hessian, and the pose's J, λ-weighted
    Hessian H and rate derivative G (twists included) equal central differences (1e-6)."""
    rng = np.random.default_rng(seed)
    s = _Section(rng)
    e = s.q[ROD_ORDER]
    ve = rng.normal(size=SECTION_COORDS)
    pose, vel, J = s.pose(e, ve)
    A = rotation(pose[3:])
    x = shape_xi(s.xi, L_E)[1] @ e[:12].reshape(4, 3)
    assert np.allclose(A[:, 0], _unit(x), atol=1e-13)
    assert np.allclose(A[:, 1], _director(s.q, s.t_bar, s.d_bar, s.xi), atol=1e-12)
    assert abs(np.linalg.norm(pose[3:]) - 1.0) < 1e-13
    assert np.allclose(vel, J @ ve, atol=1e-12)
    turn = s.turn(e, True)
    g = turn[1:1 + SECTION_COORDS]
    Hpsi = turn[1 + SECTION_COORDS:].reshape(SECTION_COORDS, SECTION_COORDS)
    assert abs(g[12]) > 0.1 and abs(g[13]) > 0.1         # both twists turn it
    lam = rng.normal(size=POSE_SIZE)
    H, G = np.zeros((SECTION_COORDS, SECTION_COORDS)), np.zeros((POSE_SIZE, SECTION_COORDS))
    pose_curvature(e, SECTION_COORDS, L_E, s.xi, s.ts, s.p0, turn, ve, lam, H, G,
                   np.zeros(POSE_WORK))
    h = 1e-6
    steps = [[e + sign * h * d for sign in (1, -1)] for d in np.eye(SECTION_COORDS)]
    gfd = np.array([(s.turn(p, False)[0] - s.turn(m, False)[0]) / (2 * h) for p, m in steps])
    Hpfd = np.array([(s.turn(p, False)[1:1 + SECTION_COORDS]
                      - s.turn(m, False)[1:1 + SECTION_COORDS]) / (2 * h) for p, m in steps]).T
    poses = [[s.pose(p, ve), s.pose(m, ve)] for p, m in steps]
    Jfd = np.array([(p[0] - m[0]) / (2 * h) for p, m in poses]).T
    Hfd = np.array([lam @ (p[2] - m[2]) / (2 * h) for p, m in poses]).T
    Gfd = np.array([(p[1] - m[1]) / (2 * h) for p, m in poses]).T
    assert np.abs(g - gfd).max() <= 1e-6 * np.abs(g).max()
    assert np.abs(Hpsi - Hpfd).max() <= 1e-6 * np.abs(Hpsi).max()
    assert np.abs(Hpsi - Hpsi.T).max() <= 1e-12 * np.abs(Hpsi).max()
    assert np.abs(J - Jfd).max() <= 1e-6 * np.abs(J).max()
    assert np.abs(H - Hfd).max() <= 1e-6 * np.abs(H).max()
    assert np.abs(H - H.T).max() <= 1e-12 * np.abs(H).max()
    assert np.abs(G - Gfd).max() <= 1e-6 * np.abs(G).max()


def test_a_rod_section_turned_far_takes_a_new_base_without_moving() -> None:
    """Past a turn of 90° about its tangent the section re-bases; its pose is the same and its
    turn 0 on the new base."""
    s = _Section(np.random.default_rng(7))
    e = s.q[ROD_ORDER]
    e[12:] += 2.0                                      # both twists: ψ past π/2
    psi = s.turn(e, False)[0]
    assert abs(psi) > 0.5 * math.pi
    before = s.pose(e, np.zeros(SECTION_COORDS))[0]
    assert not rebase(e, SECTION_COORDS, L_E, s.xi, s.ts, s.p0, 0.4, np.zeros(POSE_WORK))
    assert rebase(e, SECTION_COORDS, L_E, s.xi, s.ts, s.p0, psi, np.zeros(POSE_WORK))
    assert abs(s.turn(e, False)[0]) < 1e-12
    after = s.pose(e, np.zeros(SECTION_COORDS))[0]
    assert np.abs(after - before).max() < 1e-13 or np.abs(after[3:] + before[3:]).max() < 1e-13


LUMEN = (1.6e-3, 1.4e-3)      # the rounded rectangle's half widths along d2 and d3
WIRE_R = 1e-3


def _rod_tube(*, friction: float | None = None, damping: float = 0.0,
              offset: tuple[float, float] = (0.53e-3, 0.53e-3)
              ) -> tuple[fm.Model, fm.TubeJoint, fm.Beam, fm.Beam]:
    """A rod tube along x (0 to 0.2 m) with a rounded-rectangle lumen, a wire inside it
    shifted by ``offset`` along y and z (the default, 0.75 mm off the axis, presses it onto
    the wall whichever way the lumen is turned)."""
    model = fm.Model(gravity=(0, 0, 0))
    tube = model.add_beam(fm.line((0, 0, 0), (0.2, 0, 0), elements=4), name="tube",
                          section=fm.CircularSection(3e-3), material=fm.Material(E=2e9, rho=1200),
                          element="ancf_rod14")
    wire = model.add_beam(fm.line((-0.01, *offset), (0.21, *offset), elements=6),
                          name="wire", section=fm.CircularSection(WIRE_R),
                          material=fm.Material(E=2e11, rho=7800))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        joint = model.add_joint(fm.TubeJoint(
            wire, tube, lumen=RoundedRectangleSection(w=LUMEN[0], h=LUMEN[1], r=1e-3),
            sections=9, friction=friction,
            contact=fm.LinearPenalty(stiffness=2e5, damping=damping)))
    return model, joint, tube, wire


@pytest.mark.parametrize(("friction", "damping"), [(None, 0.0), (0.3, 5.0)])
def test_rod_tube_tangent_equals_central_differences(friction: float | None,
                                                     damping: float) -> None:
    """A rod tube with a rounded-rectangle lumen, twisted: the assembled stiffness and damping
    matrices over both beams' coordinates (the tube's twists too) against central differences
    of the assembled residual (1e-6 relative); frictionless and undamped, K is symmetric."""
    model, joint, tube, wire = _rod_tube(friction=friction, damping=damping)
    asm = Assembly(model)
    asm.begin(asm.q_ref)
    n, m = asm.n_coords, asm.n_mult
    rng = np.random.default_rng(3)
    q = asm.q_ref.copy()
    q[:n] += 2e-5 * rng.standard_normal(n)
    twists = asm.beam_dofs(tube).reshape(-1, 7)[:, 6]
    q[twists] += np.linspace(0.0, 0.3, twists.size)      # the lumen turns along the tube
    # at rest when frictionless and undamped: the rod's own spin inertia has velocity terms
    v = 1e-2 * rng.standard_normal(n) if friction or damping else np.zeros(n)
    asm.evaluate(q, v, np.zeros(n), np.zeros(m), 0.0, np.zeros(n), np.zeros(m))
    assert len(joint._contacts(q, v, False, False)) >= 5
    idx = np.r_[asm.beam_dofs(tube), asm.beam_dofs(wire)]
    K, _ = assert_tangent_over(asm, q, v, idx)
    Ka = K[np.ix_(idx, idx)]
    # the tube's twists move the wall under the wire: about k × the lumen's lever (~1e2 N/rad)
    assert np.abs(K[np.ix_(asm.beam_dofs(wire), twists)]).max() > 10.0
    if friction is None and damping == 0.0:
        assert np.abs(Ka - Ka.T).max() <= 1e-8 * np.abs(Ka).max()


def test_a_twisted_rod_turns_its_lumen() -> None:
    """The tube's twist growing from 0 to 90° along it (a straight rod: its director at s turned
    by θ(s) about x) turns each section's lumen with it: the section's y axis is at θ(s), and a
    wire 0.5 mm off the axis towards the rectangle's short half width (1.4 mm; radius 1 mm)
    penetrates by 0.1 mm at the first section and clears the last (turned: the long half width,
    1.6 mm, faces it)."""
    model, joint, tube, wire = _rod_tube(offset=(0.0, 0.5e-3))
    asm = Assembly(model)
    asm.begin(asm.q_ref)
    n, m = asm.n_coords, asm.n_mult
    q = asm.q_ref.copy()
    A0 = rotation(joint.section_poses(q)[0][0, 3:])
    start = math.atan2(A0[2, 1], A0[1, 1])           # the reference director's angle about x
    twists = asm.beam_dofs(tube).reshape(-1, 7)[:, 6]
    theta = np.linspace(0.0, 0.5 * math.pi, twists.size)
    q[twists] = theta - start
    poses, _ = joint.section_poses(q)
    for k, s in enumerate(joint.stations):
        angle = 0.5 * math.pi * s / 0.2
        A = rotation(poses[k, 3:])
        assert np.allclose(A[:, 1], [0.0, math.cos(angle), math.sin(angle)], atol=1e-12)
        assert np.allclose(A[:, 0], [1.0, 0.0, 0.0], atol=1e-14)
    rq, rl = np.zeros(n), np.zeros(m)
    asm.evaluate(q, np.zeros(n), np.zeros(n), np.zeros(m), 0.0, rq, rl)
    gaps = {int(r["section"]): r["gap"] for r in joint.output(asm, q, np.zeros(n), np.zeros(m), 0.0)}
    assert gaps[0] == pytest.approx(-1e-4, rel=1e-6)
    assert gaps.get(len(joint.stations) - 1, 1.0) > 0.0


def test_a_lumen_that_is_not_round_needs_a_rod() -> None:
    model = fm.Model()
    tube = model.add_beam(fm.line((0, 0, 0), (0.2, 0, 0), elements=4), name="tube",
                          section=fm.CircularSection(3e-3), material=fm.Material(E=2e9, rho=1200))
    wire = model.add_beam(fm.line((0, 0, 0), (0.2, 0, 0), elements=4), name="wire",
                          section=fm.CircularSection(WIRE_R), material=fm.Material(E=2e11, rho=7800))
    with pytest.raises(ModelError, match="lumen: a RoundedRectangleSection lumen must turn") as err:
        fm.TubeJoint(wire, tube, lumen=RoundedRectangleSection(w=2e-3, h=1.4e-3,
                                                               r=1.2e-3), sections=5)
    assert "\n" not in str(err.value) and "ancf_rod14" in str(err.value)


# ---------------------------------------------------------------------------------------------
# A wire in a spinning tube rides up the wall to the friction angle: the rod tube's nodes held
# in place and turned at ω (their twists prescribed), the wire (a cable, held along x at one end,
# damped towards rest in y and z) on the bottom of the lumen under gravity. The wall slides under
# the wire at ω R; Coulomb's μ N along it balances the weight's component along the wall when
# tan α = μ (α from the bottom, on the side the wall moves to).
MU, OMEGA, SPIN_RAMP = 0.3, 5.0, 0.05


def _spin(t: float) -> float:
    if t <= 0.0:
        return 0.0
    if t >= SPIN_RAMP:
        return OMEGA * (t - 0.5 * SPIN_RAMP)
    return OMEGA * t * t / (2.0 * SPIN_RAMP)


def _spinning_tube(t_end: float, friction: float) -> float:
    lumen, radius = 2e-3, WIRE_R
    model = fm.Model(gravity=(0.0, 0.0, -9.81))
    tube = model.add_beam(fm.line((0, 0, 0), (0.1, 0, 0), elements=4), name="tube",
                          section=fm.CircularSection(3e-3), material=fm.Material(E=2e9, rho=1200),
                          element="ancf_rod14")
    low = lumen - radius
    wire = model.add_beam(fm.line((-0.01, 0, -low), (0.11, 0, -low), elements=8), name="wire",
                          section=fm.CircularSection(radius), material=fm.Material(E=2e11, rho=7800))
    for k in range(tube.n_nodes):
        model.prescribe(tube.node(k), [0, 1, 2, 3, 4, 5], name=f"hold{k}")
        model.prescribe(tube.node(k), [6], fm.Function(_spin), name=f"spin{k}")
    model.prescribe(wire.first_node, [0], name="axial")
    # dampers towards rest in y and z (1 m long: their lines stay along y and z)
    c = 0.3 / wire.n_nodes
    for k in range(wire.n_nodes):
        p = np.array([-0.01 + 0.12 * k / (wire.n_nodes - 1), 0.0, -low])
        for axis in (1, 2):
            model.add_spring_damper(wire.node(k), point_b=p + np.eye(3)[axis], damping=c)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        joint = model.add_joint(fm.TubeJoint(
            wire, tube, inner_radius=lumen, spacing=1e-2,
            contact=fm.LinearPenalty(stiffness=1e4, damping=1.0),
            friction=fm.Friction(mu=friction) if friction else None))
        res = fm.simulate(model, t_end=t_end, dt=5e-4, output_interval=5e-3,
                          integrator=fm.GeneralizedAlpha(rho_inf=0.8))
    late = res.t > t_end - 0.05
    centre = res.q[late][:, res.assembly.beam_dofs(wire).reshape(-1, 6)[:, :3]]
    inside = (centre[..., 0] > 0.01) & (centre[..., 0] < 0.09)
    y, z = centre[..., 1][inside], centre[..., 2][inside]
    assert joint is not None
    return float(np.mean(np.arctan2(y, -z)))


@pytest.mark.slow
def test_a_wire_in_a_spinning_rod_tube_rides_up_to_the_friction_angle() -> None:
    """Measured: α = 16.6996° (tan α = 0.300008 against μ = 0.3, 2.6e-5); frictionless the wire
    stays at the bottom (4e-14 rad)."""
    alpha = _spinning_tube(0.4, MU)
    assert math.tan(alpha) == pytest.approx(MU, rel=1e-3)
    assert abs(_spinning_tube(0.15, 0.0)) < 1e-6


_SCENARIO = """
name = "rod_tube"
[simulation]
t_end = 0.001
dt = 0.001
[[beams]]
name = "hose"
geometry = {{ line = {{ start = [0.0, 0.0, 0.0], end = [0.2, 0.0, 0.0] }} }}
elements = 4
radius = 3e-3
youngs_modulus = 2e9
density = 1200.0
{element}
[[beams]]
name = "core"
geometry = {{ line = {{ start = [-0.01, 0.0, 0.0], end = [0.21, 0.0, 0.0] }} }}
elements = 6
radius = 1e-3
youngs_modulus = 2e11
density = 7800.0
[[joints]]
name = "lumen"
type = "tube"
beam = "core"
tube = "hose"
lumen = {{ shape = "rounded_rectangle", w = 1.6e-3, h = 1.4e-3, r = 1e-3 }}
sections = 5
contact = {{ stiffness = 1e5 }}
"""


def test_a_scenario_s_rod_tube_takes_a_lumen_that_is_not_round(tmp_path) -> None:
    """``lumen = { shape = "rounded_rectangle", ... }`` on a rod tube builds a tube joint whose
    sections' y axes are the rod's directors; on a cable tube it is refused in one line naming
    the joint's ``lumen``."""
    from flexmbs.errors import ScenarioError
    from flexmbs.io.scenario import load_scenario

    rod = tmp_path / "rod.toml"
    rod.write_text(_SCENARIO.format(element='element = "ancf_rod14"'))
    scenario = load_scenario(rod)
    joint = next(j for j in scenario.model.interactions if isinstance(j, fm.TubeJoint))
    assert isinstance(joint.hole.section, RoundedRectangleSection)
    cable = tmp_path / "cable.toml"
    cable.write_text(_SCENARIO.format(element=""))
    with pytest.raises(ScenarioError, match=r"joints\[lumen\].*lumen: a RoundedRectangleSection "
                                            r"lumen must turn with the tube") as err:
        load_scenario(cable)
    assert "\n" not in str(err.value)

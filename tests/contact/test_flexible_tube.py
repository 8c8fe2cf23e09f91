"""A beam inside a flexible tube (flexmbs.contact.tube, tube_joint; docs/theory.md §II.9).

Independent references: central differences of the sections' pose map and of the assembled
residual (the exact tangent over both beams' coordinates); Newton's third law (the contact
forces on the two beams sum to zero force and moment); the rigid limit (a tube whose nodes are
held gives the forces of a rigid bore with the same sections); the closed form of a cantilever
tube pressed onto an inner cantilever wire."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.assembly import Assembly
from flexmbs.contact.laws import ForceLaw
from flexmbs.contact.shapes.circle import CircleSection
from flexmbs.contact.shapes.superellipse import SuperellipseSection
from flexmbs.contact.tube import (
    POSE_SIZE,
    POSE_WORK,
    SECTION_COORDS,
    TURN_SIZE,
    pose_curvature,
    rebase,
    section_pose,
)
from flexmbs.elements.hermite import CENTERLINE_SIZE, shape_xi
from flexmbs.elements.rigid_body import rotation
from flexmbs.errors import ModelError
from tests.contact.test_potential import assert_tangent_over

LUMEN_R = 2e-3
WIRE_R = 1e-3
STIFFNESS = 2e5


def _element(rng: np.random.Generator) -> np.ndarray:
    """A curved cubic element about the x axis."""
    return (np.concatenate([[0, 0, 0], [1, 0.2, 0.1], [0.1, 0.01, 0], [0.9, 0.1, 0.3]])
            + rng.normal(scale=0.05, size=CENTERLINE_SIZE))


def _base(t: np.ndarray) -> np.ndarray:
    """Euler parameters of a frame whose x axis is the unit vector ``t``."""
    axis = np.cross([1.0, 0.0, 0.0], t)
    s = np.linalg.norm(axis)
    angle = math.atan2(s, t[0])
    return np.array([math.cos(angle / 2), *(math.sin(angle / 2) * axis / s)])


def _pose(qe: np.ndarray, xi: float, tb: np.ndarray, p0: np.ndarray, ve: np.ndarray
          ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    pose, vel, J = np.zeros(POSE_SIZE), np.zeros(POSE_SIZE), np.zeros((POSE_SIZE, SECTION_COORDS))
    section_pose(qe, CENTERLINE_SIZE, 0.1, xi, tb, p0, np.zeros(TURN_SIZE), ve, pose, vel, J,
                 np.zeros(POSE_WORK))
    assert not J[:, CENTERLINE_SIZE:].any()          # a cable's section does not turn
    return pose, vel, J[:, :CENTERLINE_SIZE]


@pytest.mark.parametrize("slope", [0.0, -1.0], ids=["folded", "turned_back"])
def test_a_section_without_a_smallest_rotation_is_nan_not_a_crash(slope: float) -> None:
    """An iterate whose tube element has no tangent at the section (folded) or one turned back
    onto −t̄ has no section frame: NaN (the Newton loops reject the iterate and cut the step),
    not a division by zero inside compiled code (seen: a catheter and its wire fed at
    different speeds from rest, the first iterate folding the catheter's first element)."""
    qe = np.zeros(CENTERLINE_SIZE)
    qe[6] = 0.1 * max(slope, 0.0) + 0.1 * slope      # x of the second node
    qe[3], qe[9] = slope, slope                       # both slopes along ±x (0: a point)
    pose, _, J = _pose(qe, 0.5, np.array([1.0, 0.0, 0.0]), np.array([1.0, 0.0, 0.0, 0.0]),
                       np.zeros(CENTERLINE_SIZE))
    assert np.isnan(pose[3:]).all() and np.isnan(J[3:]).all()
    assert np.isfinite(pose[:3]).all()                # where it is stays defined


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_section_pose_and_its_derivatives(seed: int) -> None:
    """The section's frame has its normal along the tube's tangent and a unit quaternion; J, the
    λ-weighted Hessian H and the rate's derivative G equal central differences (1e-6
    relative)."""
    rng = np.random.default_rng(seed)
    qe, ve = _element(rng), rng.normal(size=CENTERLINE_SIZE)
    tb = np.array([1.0, 0.3, -0.2])
    tb /= np.linalg.norm(tb)
    p0 = _base(tb)
    xi = float(rng.uniform(0.1, 0.9))
    pose, vel, J = _pose(qe, xi, tb, p0, ve)
    x = shape_xi(xi, 0.1)[1] @ qe.reshape(4, 3)
    assert abs(np.linalg.norm(pose[3:]) - 1.0) < 1e-14
    assert np.allclose(rotation(pose[3:]) @ [1.0, 0.0, 0.0], x / np.linalg.norm(x), atol=1e-14)
    assert np.allclose(vel, J @ ve, atol=1e-13)
    lam = rng.normal(size=POSE_SIZE)
    H, G = np.zeros((SECTION_COORDS, SECTION_COORDS)), np.zeros((POSE_SIZE, SECTION_COORDS))
    pose_curvature(qe, CENTERLINE_SIZE, 0.1, xi, tb, p0, np.zeros(TURN_SIZE), ve, lam, H, G,
                   np.zeros(POSE_WORK))
    H, G = H[:CENTERLINE_SIZE, :CENTERLINE_SIZE], G[:, :CENTERLINE_SIZE]
    h = 1e-6
    cols = [[_pose(qe + s * h * e, xi, tb, p0, ve) for s in (1, -1)] for e in np.eye(CENTERLINE_SIZE)]
    Jfd = np.array([(p[0] - m[0]) / (2 * h) for p, m in cols]).T
    Hfd = np.array([lam @ (p[2] - m[2]) / (2 * h) for p, m in cols]).T
    Gfd = np.array([(p[1] - m[1]) / (2 * h) for p, m in cols]).T
    assert np.abs(J - Jfd).max() <= 1e-6 * np.abs(J).max()
    assert np.abs(H - Hfd).max() <= 1e-6 * np.abs(H).max()
    assert np.abs(H - H.T).max() <= 1e-12 * np.abs(H).max()
    assert np.abs(G - Gfd).max() <= 1e-6 * np.abs(G).max()


def test_a_section_that_turned_far_takes_a_new_base_without_moving() -> None:
    """After a turn of 90° the section re-bases; its pose is the same before and after."""
    rng = np.random.default_rng(4)
    qe = _element(rng)
    qe[0:3] = [0.0, 0.0, 0.0]
    qe[3:6] = [0.0, 1.0, 0.0]
    qe[6:9] = [0.01, 0.1, 0.0]
    qe[9:12] = [0.0, 1.0, 0.2]
    tb = np.array([1.0, 0.0, 0.0])
    p0 = np.array([1.0, 0.0, 0.0, 0.0])
    before = _pose(qe, 0.5, tb, p0, np.zeros(CENTERLINE_SIZE))[0]
    assert rebase(qe, CENTERLINE_SIZE, 0.1, 0.5, tb, p0, 0.0, np.zeros(POSE_WORK))
    after = _pose(qe, 0.5, tb, p0, np.zeros(CENTERLINE_SIZE))[0]
    assert np.abs(after - before).max() < 1e-14 or np.abs(after + before).max() < 1e-14
    assert not rebase(qe, CENTERLINE_SIZE, 0.1, 0.5, tb, p0, 0.0, np.zeros(POSE_WORK))


def wire_in_tube(push: float = 1.1e-3, *, friction: float | None = None, damping: float = 0.0,
                 clamp_tube: bool = False, clamp_wire: bool = False, sections: int = 9,
                 tube_elements: int = 4, wire_elements: int = 6, law: ForceLaw | None = None,
                 vessel: bool = False, span: tuple[float, float] = (-0.01, 0.21)
                 ) -> tuple[fm.Model, fm.TubeJoint, fm.Beam, fm.Beam]:
    """A tube along x (0 to 0.2 m) and a wire inside it shifted by ``push`` along y (past the
    1 mm clearance: every section in contact). ``vessel``: the tube also runs through a fixed
    rigid bore 50 mm long in its middle, shifted by 1 mm along −y (0.5 mm clearance): it
    presses the tube onto the wire. ``span``: the wire's ends along x (inside the tube: its
    tip sections hold them)."""
    model = fm.Model(gravity=(0, 0, 0))
    tube = model.add_beam(fm.line((0, 0, 0), (0.2, 0, 0), elements=tube_elements), name="tube",
                          section=fm.CircularSection(3e-3), material=fm.Material(E=2e9, rho=1200))
    wire = model.add_beam(fm.line((span[0], push, 0), (span[1], push, 0), elements=wire_elements),
                          name="wire", section=fm.CircularSection(WIRE_R),
                          material=fm.Material(E=2e11, rho=7800))
    if clamp_tube:
        for node in range(tube.n_nodes):
            model.clamp(tube.node(node))
    if clamp_wire:
        model.clamp(wire.first_node)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        joint = model.add_joint(fm.TubeJoint(
            wire, tube, inner_radius=LUMEN_R, sections=sections, friction=friction,
            contact=law or fm.LinearPenalty(stiffness=STIFFNESS, damping=damping)))
    if vessel:
        body = model.add_rigid_body(mass=1.0, inertia=(1, 1, 1), pose=fm.Pose((0.1, -1e-3, 0.0)),
                                    name="vessel")
        model.fix_body(body)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model.add_joint(fm.SlidingClearanceJoint(
                tube, body, hole=fm.Hole(CircleSection(3.5e-3), 0.05, 5, True),
                contact=fm.LinearPenalty(stiffness=STIFFNESS)))
    return model, joint, tube, wire


def _bent(asm: Assembly, seed: int) -> np.ndarray:
    q = asm.q_ref.copy()
    q[:asm.n_coords] += 2e-5 * np.random.default_rng(seed).standard_normal(asm.n_coords)
    return q


@pytest.mark.parametrize(("friction", "damping", "vessel", "span"),
                         [(None, 0.0, False, (-0.01, 0.21)), (None, 5.0, False, (-0.01, 0.21)),
                          (0.3, 0.0, False, (-0.01, 0.21)), (0.3, 5.0, True, (-0.01, 0.21)),
                          (0.3, 0.0, False, (0.06, 0.16))])
def test_tube_tangent_equals_central_differences(friction: float | None, damping: float,
                                                 vessel: bool, span: tuple[float, float]) -> None:
    """The assembled stiffness and damping matrices over both beams' coordinates against central
    differences of the assembled residual (detection redone at every perturbed state): 1e-6
    relative; frictionless and undamped, K is symmetric. ``vessel``: nested, the tube in a rigid
    bore too (a tube joint and a rigid-bore joint in one packed part); a short ``span``: both
    wire ends inside the tube, on tip sections."""
    model, joint, tube, wire = wire_in_tube(friction=friction, damping=damping, vessel=vessel,
                                            span=span)
    asm = Assembly(model)
    asm.begin(asm.q_ref)
    n, m = asm.n_coords, asm.n_mult
    q = _bent(asm, 3)
    v = 1e-2 * np.random.default_rng(5).standard_normal(n)
    asm.evaluate(q, v, np.zeros(n), np.zeros(m), 0.0, np.zeros(n), np.zeros(m))  # places tips
    assert len(joint._contacts(q, v, False, False)) >= 5
    if span[0] > 0.0:
        assert joint.state.tip_on.all()
        assert {k for k, *_ in joint._contacts(q, v, False, False)} >= {9, 10}
    if vessel:
        outer = next(j for j in model.interactions if isinstance(j, fm.SlidingClearanceJoint)
                     and j is not joint)
        assert len(outer._contacts(q, v, False, False)) >= 3
    idx = np.r_[asm.beam_dofs(tube), asm.beam_dofs(wire)]
    K, _ = assert_tangent_over(asm, q, v, idx)
    Ka = K[np.ix_(idx, idx)]
    if friction is None and damping == 0.0:
        assert np.abs(Ka - Ka.T).max() <= 1e-8 * np.abs(Ka).max()


def test_forces_on_both_beams_balance() -> None:
    """The contact forces on the tube and on the wire: zero resultant force and moment about
    the origin (the beams' own forces vanish in the stress-free shape)."""
    model, joint, tube, wire = wire_in_tube()
    asm = Assembly(model)
    n = asm.n_coords
    q = asm.q_ref.copy()
    rq, rl = np.zeros(n), np.zeros(asm.n_mult)
    asm.evaluate(q, np.zeros(n), np.zeros(n), np.zeros(asm.n_mult), 0.0, rq, rl)
    total_force = np.zeros(3)
    total_moment = np.zeros(3)
    for beam in (tube, wire):
        d = asm.beam_dofs(beam).reshape(-1, 6)     # per node: position, tangent
        for node in d:
            f = -rq[node[:3]]
            total_force += f
            total_moment += np.cross(q[node[:3]], f) + np.cross(q[node[3:]], -rq[node[3:]])
    scale = np.abs(rq).max()
    assert scale > 1.0
    assert np.abs(total_force).max() <= 1e-10 * scale
    assert np.abs(total_moment).max() <= 1e-10 * scale


def test_bad_tubes_are_refused_in_one_line() -> None:
    model = fm.Model()
    tube = model.add_beam(fm.line((0, 0, 0), (0.2, 0, 0), elements=4), name="tube",
                          section=fm.CircularSection(3e-3), material=fm.Material(E=2e9, rho=1200))
    wire = model.add_beam(fm.line((0, 0, 0), (0.2, 0, 0), elements=4), name="wire",
                          section=fm.CircularSection(WIRE_R), material=fm.Material(E=2e11, rho=7800))
    with pytest.raises(ModelError, match="cannot run inside itself"):
        fm.TubeJoint(tube, tube, inner_radius=LUMEN_R, sections=5)
    with pytest.raises(ModelError, match="not larger than the beam"):
        fm.TubeJoint(wire, tube, inner_radius=0.9 * WIRE_R, sections=5)
    with pytest.raises(ModelError, match="finer than the inner beam's radius"):
        fm.TubeJoint(wire, tube, inner_radius=LUMEN_R, spacing=0.5 * WIRE_R)
    with pytest.raises(ModelError, match="lumen: a SuperellipseSection lumen must turn with the "
                                         "tube, but tube 'tube' is a ancf_cable"):
        fm.TubeJoint(wire, tube, lumen=SuperellipseSection(a=2e-3, b=1.5e-3, exponent=4.0),
                     sections=5)
    with pytest.raises(ModelError, match="spacing = <distance> or sections"):
        fm.TubeJoint(wire, tube, inner_radius=LUMEN_R)


def test_a_tube_held_at_every_node_is_a_rigid_bore() -> None:
    """The rigid limit: a straight tube clamped at every node and a fixed rigid bore with the
    same sections put the same contact forces on a bent wire (1e-10 relative)."""
    model, joint, tube, wire = wire_in_tube(clamp_tube=True)
    asm = Assembly(model)
    n = asm.n_coords
    q = _bent(asm, 7)
    q[asm.beam_dofs(tube)] = asm.q_ref[asm.beam_dofs(tube)]
    rq, rl = np.zeros(n), np.zeros(asm.n_mult)
    asm.evaluate(q, np.zeros(n), np.zeros(n), np.zeros(asm.n_mult), 0.0, rq, rl)

    rigid = fm.Model(gravity=(0, 0, 0))
    wire2 = rigid.add_beam(fm.line((-0.01, 1.1e-3, 0), (0.21, 1.1e-3, 0), elements=6), name="wire",
                           section=fm.CircularSection(WIRE_R), material=fm.Material(E=2e11, rho=7800))
    body = rigid.add_rigid_body(mass=1.0, inertia=(1, 1, 1), pose=fm.Pose((0.1, 0.0, 0.0)),
                                name="bore")
    rigid.fix_body(body)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rigid.add_joint(fm.SlidingClearanceJoint(
            wire2, body, hole=fm.Hole(CircleSection(LUMEN_R), 0.2, 9, True),
            contact=fm.LinearPenalty(stiffness=STIFFNESS)))
    asm2 = Assembly(rigid)
    q2 = asm2.q_ref.copy()
    q2[asm2.beam_dofs(wire2)] = q[asm.beam_dofs(wire)]
    n2 = asm2.n_coords
    r2, rl2 = np.zeros(n2), np.zeros(asm2.n_mult)
    asm2.evaluate(q2, np.zeros(n2), np.zeros(n2), np.zeros(asm2.n_mult), 0.0, r2, rl2)
    a, b = rq[asm.beam_dofs(wire)], r2[asm2.beam_dofs(wire2)]
    assert np.abs(a).max() > 1.0
    assert np.abs(a - b).max() <= 1e-10 * np.abs(a).max()


def cantilever_tube(P: float, c: float = 0.5e-3, L: float = 0.5) -> tuple[float, float]:
    """A tube (E I_t) and a wire (E I_w) inside it, both clamped at the root, the tube's tip
    pushed by P across: (contact force on the wire, tube's tip deflection)."""
    model = fm.Model(gravity=(0, 0, 0))
    tube = model.add_beam(fm.line((0, 0, 0), (L, 0, 0), elements=8), name="tube",
                          section=fm.CircularSection(3e-3), material=fm.Material(E=2e9, rho=1200))
    wire = model.add_beam(fm.line((0, 0, 0), (L + 0.005, 0, 0), elements=9), name="wire",
                          section=fm.CircularSection(WIRE_R), material=fm.Material(E=2e11, rho=7800))
    model.clamp(tube.first_node)
    model.clamp(wire.first_node)
    model.add_point_load(tube.last_node, (0.0, -P, 0.0))
    joint = model.add_joint(fm.TubeJoint(wire, tube, inner_radius=WIRE_R + c, sections=21,
                                         contact=fm.LinearPenalty(stiffness=1e8)))
    asm = Assembly(model)
    res = fm.solve_static(asm, fm.StaticOptions(load_steps=4))
    tip = res.q[asm.node_dofs(tube.last_node)[:3]]
    force = joint.contact_force(res.q, np.zeros_like(res.q))
    return float(np.linalg.norm(force)), float(-tip[1])


def test_cantilever_tube_meets_its_wire_at_the_closed_form_load() -> None:
    """Contact starts at P0 = 3 E I_t c / L³ at the tip; beyond it the wire takes
    F = (P − P0) E I_w / (E I_t + E I_w) and the tip's compliance drops from L³/(3 E I_t) to
    L³/(3 (E I_t + E I_w)): each within 1 %."""
    L, c = 0.5, 0.5e-3
    EI_t = 2e9 * math.pi * (3e-3) ** 4 / 4
    EI_w = 2e11 * math.pi * WIRE_R ** 4 / 4
    P0 = 3 * EI_t * c / L ** 3
    F, d = cantilever_tube(0.8 * P0, c, L)
    assert F == 0.0
    assert d == pytest.approx(0.8 * P0 * L ** 3 / (3 * EI_t), rel=1e-2)
    forces, tips = [], []
    for ratio in (2.0, 3.0):
        F, d = cantilever_tube(ratio * P0, c, L)
        assert pytest.approx((ratio - 1) * P0 * EI_w / (EI_t + EI_w), rel=1e-2) == F
        forces.append(F)
        tips.append(d)
    compliance = (tips[1] - tips[0]) / P0
    assert compliance == pytest.approx(L ** 3 / (3 * (EI_t + EI_w)), rel=1e-2)


def _momenta(asm: Assembly, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Linear and angular momentum (about the origin) of the beams. With the scalar mass
    matrix M̄ of the nodal vectors (the assembled M = M̄ ⊗ I₃) and r = Σ S_m e_m,
    L = ∫ρA r × ṙ = Σ M̄_mn e_m × ė_n; P = ∫ρA ṙ = Σ_n (∫ρA S_n) ė_n, and since the position
    shape functions of a cubic element sum to one, ∫ρA S_n is the sum of M̄'s rows of the
    nodes' positions (every other vector of a cable's coordinates)."""
    n = asm.n_coords
    rq, rl = np.zeros(n), np.zeros(asm.n_mult)
    asm.evaluate(q, v, np.zeros(n), np.zeros(asm.n_mult), 0.0, rq, rl, matrix=(1.0, 0.0, 0.0))
    M = asm.matrix.toarray()[:n, :n]
    Mbar = M[0::3, 0::3]
    E, Ed = q[:n].reshape(-1, 3), v[:n].reshape(-1, 3)
    P = Mbar[0::2].sum(axis=0) @ Ed
    L = np.einsum("mn,mi,nj,kij->k", Mbar, E, Ed, _LEVI)
    return P, L


_LEVI = np.zeros((3, 3, 3))
for _i, _j, _k in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
    _LEVI[_k, _i, _j], _LEVI[_k, _j, _i] = 1.0, -1.0


def _free_pair(dt: float) -> tuple[float, float, float, int]:
    """A wire thrown across inside a free tube (0.3 m/s along y, 0.1 m/s along z), bouncing off
    its wall for 20 ms: no gravity, damping or friction, Hertz-type contact f = Kδ² (a C¹
    force, so the integrator keeps its order), generalized-α with ρ∞ = 1 at the fixed step
    ``dt``. Returns the largest momentum errors (linear, angular, relative to the initial
    ones), the largest energy error and the contact energy's swing (relative to the initial
    energy), and the contacts seen at the outputs."""
    model, joint, tube, wire = wire_in_tube(push=0.0, law=fm.Hertz(stiffness=2e9, exponent=2.0))
    asm = Assembly(model)
    d = asm.beam_dofs(wire).reshape(-1, 6)     # per node: position, tangent
    asm.v_init[d[:, :3].ravel()] = np.tile([0.0, 0.3, 0.1], d.shape[0])
    res = fm.simulate(asm, t_end=0.02, dt=dt, output_interval=5e-5,
                      integrator=fm.GeneralizedAlpha(rho_inf=1.0, adaptive=False))
    P0, L0 = _momenta(asm, res.q[0], res.v[0])
    dP = dL = 0.0
    contacts = 0
    for q, v in zip(res.q[1:], res.v[1:], strict=True):
        P, L = _momenta(asm, q, v)
        dP = max(dP, float(np.abs(P - P0).max() / np.abs(P0).max()))
        dL = max(dL, float(np.abs(L - L0).max() / np.abs(L0).max()))
        contacts += len(joint._observed(q, v))
    E = res.energy["total"]
    return (max(dP, dL), float(np.abs(E - E[0]).max() / E[0]),
            float(np.ptp(res.energy["contact"]) / E[0]), contacts)


def test_a_free_pair_keeps_its_momenta_and_its_energy() -> None:
    """Both beams free: the contact forces are internal, so linear and angular momentum stay
    (1e-10 relative: Newton's tolerance), and the forces are the gradient of the section
    potential through the moving sections, so with ρ∞ = 1 the energy error falls like h²
    (measured 9.3e-3, 2.5e-3, 6.2e-4, 1.5e-4 at h = 20, 10, 5, 2.5 µs; fitted order ≥ 1.8
    asserted) while the contact stores half of the energy at its deepest."""
    steps = np.array([2e-5, 1e-5, 5e-6, 2.5e-6])
    errors = []
    for h in steps:
        momenta, energy, stored, contacts = _free_pair(float(h))
        assert momenta <= 1e-10
        assert stored > 0.4
        assert contacts > 0, "the wire must reach the wall"
        errors.append(energy)
    order = np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert order > 1.8, errors
    assert errors[-1] < 2.5e-4



def test_a_curved_tube_held_at_every_node_is_the_curved_bore() -> None:
    """The rigid limit along a curve: a quarter-circle tube (radius 0.2 m) held at every node
    and a fixed curved bore along the same centreline with the same sections put the same
    contact forces on a wire pressed outwards against their walls (1e-6 relative; the
    sections' roll about the axis differs, which a circular lumen does not see)."""
    R, elements, n_sections = 0.2, 16, 33
    arc = fm.arc((0, R, 0), R, (0, 0, 0), math.pi / 2, elements=elements)
    # the wire from before the tube's start to past its end: no wire end inside (a rigid
    # bore's tip sections would hold it there; a tube has none yet)
    wire_arc = fm.arc((0, R, 0), R + 1.1e-3,
                      (-(R + 1.1e-3) * math.sin(0.02), R - (R + 1.1e-3) * math.cos(0.02), 0),
                      math.pi / 2 + 0.04, elements=24)
    wire_material = fm.Material(E=2e11, rho=7800)
    model = fm.Model(gravity=(0, 0, 0))
    tube = model.add_beam(arc, name="tube", section=fm.CircularSection(3e-3),
                          material=fm.Material(E=2e9, rho=1200))
    wire = model.add_beam(wire_arc, name="wire", section=fm.CircularSection(WIRE_R),
                          material=wire_material)
    for node in range(tube.n_nodes):
        model.clamp(tube.node(node))
    model.add_joint(fm.TubeJoint(wire, tube, inner_radius=LUMEN_R, sections=n_sections,
                                 contact=fm.LinearPenalty(stiffness=STIFFNESS)))
    asm = Assembly(model)
    q = asm.q_ref.copy()
    dw = asm.beam_dofs(wire)
    q[dw] += 2e-5 * np.random.default_rng(11).standard_normal(dw.size)
    n = asm.n_coords
    rq, rl = np.zeros(n), np.zeros(asm.n_mult)
    asm.evaluate(q, np.zeros(n), np.zeros(n), np.zeros(asm.n_mult), 0.0, rq, rl)

    rigid = fm.Model(gravity=(0, 0, 0))
    wire2 = rigid.add_beam(wire_arc, name="wire", section=fm.CircularSection(WIRE_R),
                           material=wire_material)
    body = rigid.add_rigid_body(mass=1.0, inertia=(1, 1, 1), name="bore")
    rigid.fix_body(body)
    rigid.add_joint(fm.SlidingClearanceJoint(
        wire2, body, hole=fm.CurvedBore(arc, radius=LUMEN_R, sections=n_sections),
        contact=fm.LinearPenalty(stiffness=STIFFNESS)))
    asm2 = Assembly(rigid)
    q2 = asm2.q_ref.copy()
    q2[asm2.beam_dofs(wire2)] = q[dw]
    n2 = asm2.n_coords
    r2, rl2 = np.zeros(n2), np.zeros(asm2.n_mult)
    asm2.evaluate(q2, np.zeros(n2), np.zeros(n2), np.zeros(asm2.n_mult), 0.0, r2, rl2)
    a, b = rq[dw], r2[asm2.beam_dofs(wire2)]
    assert np.abs(a).max() > 1.0
    assert np.abs(a - b).max() <= 1e-6 * np.abs(a).max()


def test_a_tube_held_at_every_node_holds_the_wire_ends_as_a_rigid_bore() -> None:
    """Tip sections: a wire whose both ends lie inside the tube (between sections), pressed
    onto the wall. Held at every node, the tube puts on it the forces of a fixed rigid bore
    with the same sections (1e-10 relative), tip sections included (both placed, both in
    contact)."""
    span = (0.06, 0.16)
    model, joint, tube, wire = wire_in_tube(clamp_tube=True, span=span)
    asm = Assembly(model)
    n = asm.n_coords
    q = _bent(asm, 7)
    q[asm.beam_dofs(tube)] = asm.q_ref[asm.beam_dofs(tube)]
    asm.begin(q)
    rq, rl = np.zeros(n), np.zeros(asm.n_mult)
    asm.evaluate(q, np.zeros(n), np.zeros(n), np.zeros(asm.n_mult), 0.0, rq, rl)
    assert joint.state.tip_on.all()

    rigid = fm.Model(gravity=(0, 0, 0))
    wire2 = rigid.add_beam(fm.line((span[0], 1.1e-3, 0), (span[1], 1.1e-3, 0), elements=6),
                           name="wire", section=fm.CircularSection(WIRE_R),
                           material=fm.Material(E=2e11, rho=7800))
    body = rigid.add_rigid_body(mass=1.0, inertia=(1, 1, 1), pose=fm.Pose((0.1, 0.0, 0.0)),
                                name="bore")
    rigid.fix_body(body)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        bore = rigid.add_joint(fm.SlidingClearanceJoint(
            wire2, body, hole=fm.Hole(CircleSection(LUMEN_R), 0.2, 9, True),
            contact=fm.LinearPenalty(stiffness=STIFFNESS)))
    asm2 = Assembly(rigid)
    q2 = asm2.q_ref.copy()
    q2[asm2.beam_dofs(wire2)] = q[asm.beam_dofs(wire)]
    asm2.begin(q2)
    n2 = asm2.n_coords
    r2, rl2 = np.zeros(n2), np.zeros(asm2.n_mult)
    asm2.evaluate(q2, np.zeros(n2), np.zeros(n2), np.zeros(asm2.n_mult), 0.0, r2, rl2)
    assert bore.state.tip_on.all()
    assert np.ptp(joint.state.tip_station - bore.state.tip_station) < 1e-12   # one offset
    a, b = rq[asm.beam_dofs(wire)], r2[asm2.beam_dofs(wire2)]
    assert np.abs(a).max() > 1.0
    assert np.abs(a - b).max() <= 1e-10 * np.abs(a).max()

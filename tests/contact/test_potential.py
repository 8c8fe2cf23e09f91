"""The clearance contact as the exact gradient of a potential (docs/theory.md §II.4b; issue "the
clearance contact as the exact gradient of a potential, at every crossing angle").

A straight or slightly bent wire (r_b = 0.8 mm unless said) held through a thin eyelet (0.2 mm
long, 3 sections, linear penalty k = 2e5 N/m), the eyelet turned by θ from the wire and pushed
across it. The contact's generalized force is read from the joint's residual and compared with
central differences of the section potential ``Σ_max Φ(δ) − Σ_min Φ(δ)``
(:meth:`SlidingClearanceJoint.contact_energy`): the independent reference is the potential
itself, evaluated by the detection at perturbed coordinates. The paper's detection fails these
tests (it is not a gradient once the crossing is oblique), which each test shows too."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.assembly import Assembly
from flexmbs.contact.laws import ForceLaw

WIRE_R = 0.8e-3
STIFFNESS = 2e5
FD_STEP = 1e-8
GRADIENT_TOL = 1e-7
#: the wire under the eyelet against the wire under the same force as a point load
TOL_BEAM = 1e-3


def eyelet_on_wire(theta: float, push: float, axis: str = "y", *, r_b: float = WIRE_R,
                   hole: fm.Hole | None = None, detection: str = "consistent",
                   stiffness: float = STIFFNESS, damping: float = 0.0, free: bool = False,
                   law: ForceLaw | None = None, friction: float | None = None,
                   elements: int = 8, at: float = 0.003, half: float = 0.1):
    """Wire along x from −half to half (0.1 m; clamped at both ends), eyelet at x = ``at`` turned by θ
    about y (its axis towards z), pushed by ``push`` along its y (the section ellipse's minor
    axis: two points past a²/b = R) or z (major axis). Returns (model, joint, body, wire)."""
    model = fm.Model(gravity=(0, 0, 0))
    wire = model.add_beam(fm.line((-half, 0, 0), (half, 0, 0), elements=elements), name="wire",
                          section=fm.CircularSection(r_b),
                          material=fm.Material(E=7e10, rho=2700))
    model.clamp(wire.first_node)
    model.clamp(wire.last_node)
    c, s = math.cos(theta), math.sin(theta)
    A = np.array([[c, 0.0, -s], [0.0, 1.0, 0.0], [s, 0.0, c]])
    pose = fm.Pose(np.array([at, 0.0, 0.0]) + push * A[:, 1 if axis == "y" else 2], A)
    body = model.add_rigid_body(mass=2e-3, inertia=(2e-8, 1e-6, 1e-6), pose=pose, name="eyelet")
    if not free:
        model.fix_body(body)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")   # starting in the wall is the point here
        joint = model.add_joint(fm.SlidingClearanceJoint(
            wire, body, hole=hole or fm.CircleHole(2e-3, 0.2e-3, 3), detection=detection,
            friction=friction,
            contact=law or fm.LinearPenalty(stiffness=stiffness, damping=damping)))
    return model, joint, body, wire


def _tangent_directions(p: np.ndarray) -> np.ndarray:
    """Three unit directions tangent to the unit sphere of Euler parameters at p."""
    return np.linalg.svd(np.eye(4) - np.outer(p, p))[0][:, :3].T


def gradient_error(joint, body, asm: Assembly, q: np.ndarray) -> tuple[float, dict]:
    """max |r − ∂V/∂q| / max |r| over the body's translations and rotations (tangent to the
    Euler-parameter constraint: the radial part is the normalisation's) and the wire elements
    at the eyelet; and the kinds of the points per section."""
    v = np.zeros_like(q)
    r = np.zeros(asm.n_coords)
    joint.evaluate(None, q, v, None, 0.0, r, None)
    bd = asm.body_dofs(body)
    ed = joint.geometry.elem_dofs[3:5].ravel()
    pairs = []
    for i in np.r_[bd[:3], ed]:
        e = np.zeros_like(q)
        e[i] = FD_STEP
        pairs.append(((joint.contact_energy(q + e) - joint.contact_energy(q - e)) / (2 * FD_STEP),
                      r[i]))
    for d in _tangent_directions(q[bd[3:]]):
        e = np.zeros_like(q)
        e[bd[3:]] = FD_STEP * d
        pairs.append(((joint.contact_energy(q + e) - joint.contact_energy(q - e)) / (2 * FD_STEP),
                      r[bd[3:]] @ d))
    fd, res = np.array(pairs).T
    kinds: dict[int, list[int]] = {}
    for k, _j, kind, *_ in joint._contacts(q, v, False, False):
        kinds.setdefault(k, []).append(kind)
    return float(np.max(np.abs(res - fd)) / np.max(np.abs(res))), kinds


def _bent(asm: Assembly, joint, seed: int = 1) -> np.ndarray:
    """Reference coordinates with the wire's two elements at the eyelet bent a little."""
    q = asm.q_ref.copy()
    ed = joint.geometry.elem_dofs[3:5].ravel()
    q[ed] += 2e-5 * np.random.default_rng(seed).standard_normal(ed.size)
    return q


SUPER_ROUND = dict(a=2.4e-3, b=2.0e-3, exponent=2.0)
SUPER_SQUARE = dict(a=2.4e-3, b=2.0e-3, exponent=4.0)
GRADIENT_CASES = [  # θ [deg], push, axis, wire radius, hole (None: circle R = 2 mm), points
    (5, 1.21e-3, "z", WIRE_R, None, 1),
    (20, 1.22e-3, "z", WIRE_R, None, 1),
    (35, 1.23e-3, "y", WIRE_R, None, 1),
    (50, 1.22e-3, "y", WIRE_R, None, 1),
    (55, 1.23e-3, "y", WIRE_R, None, 2),
    (60, 1.22e-3, "y", WIRE_R, None, 2),
    (75, 1.52e-3, "y", 0.5e-3, None, 2),
    (75, 0.3e-3, "z", 0.5e-3, None, 1),
    (40, 1.63e-3, "y", WIRE_R, SUPER_SQUARE, 1),
    (60, 1.40e-3, "z", WIRE_R, SUPER_SQUARE, 1),
    (55, 1.62e-3, "y", WIRE_R, SUPER_ROUND, 2),
    (60, 1.62e-3, "y", WIRE_R, dict(SUPER_ROUND, exponent=2.3), 2),
]


@pytest.mark.parametrize(("deg", "push", "axis", "r_b", "hole", "points"), GRADIENT_CASES)
def test_contact_force_is_the_gradient_of_the_section_potential(deg, push, axis, r_b, hole,
                                                                points):
    """Force = −∂V/∂q by central differences, 5°–75°, one and two points per section, circle
    and superellipse bores: 1e-7 relative (measured ≤ 6e-9)."""
    bore = fm.SuperellipseHole(**hole, length=0.2e-3, sections=3) if hole else None
    model, joint, body, _ = eyelet_on_wire(math.radians(deg), push, axis, r_b=r_b, hole=bore)
    asm = Assembly(model)
    err, kinds = gradient_error(joint, body, asm, _bent(asm, joint))
    most = max(kinds[k].count(1) for k in kinds)
    assert most == 1 if points == 1 else most >= 2
    assert err < GRADIENT_TOL


@pytest.mark.parametrize(("deg", "push", "floor"), [(55, 1.23e-3, 0.05), (60, 1.22e-3, 0.2)])
def test_the_papers_detection_is_not_a_gradient_at_steep_crossings(deg, push, floor):
    """The same check with ``detection = "paper"``: off by 10 % at 55°, 40 % at 60° (why the
    consistent detection is the default)."""
    model, joint, body, _ = eyelet_on_wire(math.radians(deg), push, detection="paper")
    asm = Assembly(model)
    err, _ = gradient_error(joint, body, asm, _bent(asm, joint))
    assert err > floor


def _loop_work(detection: str, n: int, deg: tuple[float, float], push: tuple[float, float]
               ) -> tuple[float, float]:
    """Work of the contact force on the eyelet around a closed loop of poses (turned from
    deg[0] to deg[1] and pushed from push[0] to push[1] across the wire, an ellipse in that
    plane) by the trapezoidal rule over n poses, and the absolute work along it."""
    model, joint, body, _ = eyelet_on_wire(math.radians(deg[0]), push[0], detection=detection)
    asm = Assembly(model)
    bd = asm.body_dofs(body)
    q = asm.q_ref.copy()
    v = np.zeros_like(q)
    t_mid, t_amp = 0.5 * (deg[0] + deg[1]), 0.5 * (deg[1] - deg[0])
    p_mid, p_amp = 0.5 * (push[0] + push[1]), 0.5 * (push[1] - push[0])
    forces, poses = [], []
    for s in np.linspace(0.0, 2 * np.pi, n + 1):
        th = math.radians(t_mid + t_amp * math.cos(s))
        c, si = math.cos(th), math.sin(th)
        A = np.array([[c, 0.0, -si], [0.0, 1.0, 0.0], [si, 0.0, c]])
        pose = fm.Pose(np.array([0.003, 0.0, 0.0]) + (p_mid + p_amp * math.sin(s)) * A[:, 1], A)
        q[bd[:3]] = pose.position
        q[bd[3:]] = pose.quaternion
        r = np.zeros(asm.n_coords)
        joint.evaluate(None, q, v, None, 0.0, r, None)
        forces.append(-r[bd])
        poses.append(q[bd].copy())
    F, X = np.array(forces), np.array(poses)
    dW = 0.5 * np.einsum("ij,ij->i", F[1:] + F[:-1], np.diff(X, axis=0))
    return float(np.sum(dW)), float(np.sum(np.abs(dW)))


@pytest.mark.parametrize(("deg", "push"), [((10.0, 20.0), (1.205e-3, 1.215e-3)),
                                           ((44.0, 54.0), (1.21e-3, 1.25e-3)),
                                           ((46.0, 56.0), (1.21e-3, 1.25e-3))])
def test_closed_loop_work_vanishes_with_the_loops_refinement(deg, push):
    """The contact does no work around a closed loop of poses: the trapezoidal loop work falls
    like n⁻² (n = 40 → 160: at least 10×) to below 1e-4 of the work along the loop; the
    paper's detection keeps a loop work of several % at 44°–56° whatever the refinement."""
    ratios = []
    for n in (40, 80, 160):
        w, along = _loop_work("consistent", n, deg, push)
        ratios.append(abs(w) / along)
    assert ratios[-1] < 1e-4
    assert ratios[-1] < 0.1 * ratios[0] or ratios[-1] < 1e-9
    if deg[0] > 40:
        w, along = _loop_work("paper", 160, deg, push)
        assert abs(w) / along > 1e-2


def assert_tangent_over(asm: Assembly, q: np.ndarray, v: np.ndarray, idx: np.ndarray
                        ) -> tuple[np.ndarray, np.ndarray]:
    """The assembled iteration matrix's stiffness K and damping C parts, over the coordinates
    ``idx``, against central differences of the assembled residual in q and q̇ (detection
    redone at every perturbed state, nothing frozen): 1e-6 of the block's largest entry.
    Returns the whole K and C."""
    n, m = asm.n_coords, asm.n_mult
    a, lam = np.zeros(n), np.zeros(m)
    rq, rl = np.zeros(n), np.zeros(m)
    asm.evaluate(q, v, a, lam, 0.0, rq, rl, matrix=(0.0, 0.0, 1.0))
    K = asm.matrix.toarray()[:n, :n]
    asm.evaluate(q, v, a, lam, 0.0, rq, rl, matrix=(0.0, 1.0, 0.0))
    C = asm.matrix.toarray()[:n, :n]

    def res(q_: np.ndarray, v_: np.ndarray) -> np.ndarray:
        r1, r2 = np.zeros(n), np.zeros(m)
        asm.evaluate(q_, v_, a, lam, 0.0, r1, r2)
        return r1

    k_scale = np.abs(K[np.ix_(idx, idx)]).max()
    c_scale = max(np.abs(C[np.ix_(idx, idx)]).max(), 1e-12)
    for j in idx:
        e = np.zeros(n)
        e[j] = FD_STEP
        col = (res(q + e, v) - res(q - e, v)) / (2 * FD_STEP)
        assert np.abs(K[idx, j] - col[idx]).max() <= 1e-6 * k_scale
        e[j] = 1e-7
        colv = (res(q, v + e) - res(q, v - e)) / 2e-7
        assert np.abs(C[idx, j] - colv[idx]).max() <= 1e-6 * c_scale
    return K, C


def _checked_tangent(asm: Assembly, joint, body, q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """:func:`assert_tangent_over` the eyelet's and the wire's coordinates at the eyelet.
    Returns K."""
    assert joint._contacts(q, v, False, False), "the configuration must have active contacts"
    idx = np.r_[asm.body_dofs(body), joint.geometry.elem_dofs[3:5].ravel()]
    return assert_tangent_over(asm, q, v, idx)[0]


@pytest.mark.parametrize(("deg", "push"), [(30.0, 1.22e-3), (55.0, 1.23e-3), (60.0, 1.22e-3)])
def test_exact_tangent_equals_central_differences_and_is_symmetric(deg, push):
    """The exact tangent of the consistent contact equals central differences of the
    assembled residual; without damping and friction it is the Hessian of the potential plus
    the wire's stiffness, symmetric to 1e-9 (on the directions tangent to the Euler parameters'
    unit sphere)."""
    model, joint, body, wire = eyelet_on_wire(math.radians(deg), push, free=True)
    asm = Assembly(model)
    n = asm.n_coords
    q = _bent(asm, joint)
    K = _checked_tangent(asm, joint, body, q, np.zeros(n))
    # symmetric on the coordinates' admissible directions (the Euler parameters' radial
    # direction is the normalisation constraint's)
    bd = asm.body_dofs(body)
    basis = np.eye(n)[:, [i for i in range(n) if i not in set(bd[3:])]]
    rot = np.zeros((n, 3))
    rot[bd[3:]] = _tangent_directions(q[bd[3:]]).T
    T = np.hstack([basis, rot])
    Kt = T.T @ K @ T
    assert np.abs(Kt - Kt.T).max() <= 1e-9 * np.abs(Kt).max()


@pytest.mark.parametrize("deg", [30.0, 55.0])
def test_damping_and_friction_act_at_the_pair_with_an_exact_tangent(deg):
    """Damping and friction at the same points (item 5): with a damped penalty (20 N s/m)
    and regularised Coulomb friction (μ = 0.3) at a sliding, rocking state the iteration
    matrix's stiffness and damping parts equal central differences of the assembled residual
    in q and in q̇ (1e-6 relative)."""
    model, joint, body, wire = eyelet_on_wire(math.radians(deg), 1.23e-3, free=True,
                                              damping=20.0, friction=0.3)
    asm = Assembly(model)
    q = _bent(asm, joint)
    v = 1e-2 * np.random.default_rng(3).standard_normal(asm.n_coords)
    _checked_tangent(asm, joint, body, q, v)


STATIC_GRID = [(deg, push) for deg in (50.0, 52.0, 53.5, 54.0, 56.0, 58.0, 60.0)
               for push in (1.21e-3, 1.23e-3, 1.25e-3, 1.28e-3)]


def test_static_solves_starting_in_penetration_converge_near_the_two_point_threshold():
    """Item 6: the eyelet fixed, the wire clamped at both ends 0.2 m apart, the eyelet turned
    50°–60° and pushed 1.21–1.28 mm across (starting 10–80 µm in the wall, two points per
    section past 50.8°): every one of the 28 static solves converges in one load step (a full
    Newton step that pushes the axis through the far wall is halved, not the load; the paper's
    detection failed 3 of them here before that). Reference: the same wire under a point
    load equal to the converged contact force at its middle node (no contact), whose static
    deflection there must match the wire's under the eyelet to TOL_BEAM (the load spread over
    the eyelet's 0.2 mm and its points' offsets from the node)."""
    for deg, push in STATIC_GRID:
        model, joint, body, wire = eyelet_on_wire(math.radians(deg), push, at=0.0)
        asm = Assembly(model)
        st = fm.solve_static(asm, fm.StaticOptions(load_steps=1))
        assert st.load_increments == 1
        force = -joint.contact_force(st.q, np.zeros_like(st.q))     # on the wire
        w = st.q[asm.node_dofs(wire.node(4))[:3]]
        ref = fm.Model(gravity=(0, 0, 0))
        free = ref.add_beam(fm.line((-0.1, 0, 0), (0.1, 0, 0), elements=8),
                            section=fm.CircularSection(WIRE_R),
                            material=fm.Material(E=7e10, rho=2700))
        ref.clamp(free.first_node)
        ref.clamp(free.last_node)
        ref.add_point_load((free, 0.1), tuple(force))
        asm_ref = Assembly(ref)
        st_ref = fm.solve_static(asm_ref, fm.StaticOptions(load_steps=2))
        w_ref = st_ref.q[asm_ref.node_dofs(free.node(4))[:3]]
        assert np.linalg.norm(w[1:] - w_ref[1:]) <= TOL_BEAM * np.linalg.norm(w_ref[1:]), \
            (deg, push)


def _free_eyelet_energy_error(detection: str, dt: float) -> tuple[float, float, int]:
    """An eyelet (turned 55° from the wire) flying freely across a short stiff clamped wire
    (20 mm, 4 elements) and bouncing off it at its steep crossing (the section ellipse's
    a²/b > R: two points in the middle section), sliding along: no gravity, no damping, no
    friction, Hertz-type contact f = Kδ² (a C¹ force, so the integrator keeps its order),
    generalized-α with ρ∞ = 1 at a fixed step, 30 ms. Returns the largest energy error and the
    contact energy's swing (both relative to the initial energy) and the most deepest points
    seen in one section."""
    model, joint, body, _ = eyelet_on_wire(math.radians(55.0), 0.0, free=True, half=0.01,
                                           elements=4, at=0.001, detection=detection,
                                           law=fm.Hertz(stiffness=2e7, exponent=2.0))
    body.velocity = np.array([0.05, 0.0, 0.0]) + 0.1 * body.pose.rotation[:, 1]
    most = [0]

    def watch(state) -> None:
        per: dict[int, int] = {}
        for k, _j, kind, *_ in joint._contacts(state.q, state.v, False, False):
            per[k] = per.get(k, 0) + (kind > 0)
        most[0] = max([most[0], *per.values()])

    res = fm.simulate(model, t_end=0.03, dt=dt, output_interval=4e-5, observer=watch,
                      integrator=fm.GeneralizedAlpha(rho_inf=1.0, adaptive=False))
    E = res.energy["total"]
    return (float(np.abs(E - E[0]).max() / E[0]), float(np.ptp(res.energy["contact"]) / E[0]),
            most[0])


def test_free_eyelet_keeps_its_energy_with_second_order_in_the_step():
    """Dynamics through steep crossings: the energy error falls like h² (measured 2.7e-4,
    8.0e-5, 2.0e-5, 5.0e-6 at h = 40, 20, 10, 5 µs; fitted order ≥ 1.8 asserted) while the
    contact stores 79 % of the energy at its deepest; with the paper's detection it levels off
    at 6.3 % whatever the step (the contact force does work over the bounce)."""
    steps = np.array([4e-5, 2e-5, 1e-5, 5e-6])
    errors = []
    for h in steps:
        err, stored, most = _free_eyelet_energy_error("consistent", float(h))
        errors.append(err)
        assert stored > 0.5
        assert most >= 2
    order = np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert order > 1.8, errors
    assert errors[-1] < 2e-5
    paper = [_free_eyelet_energy_error("paper", float(h))[0] for h in steps[-2:]]
    assert min(paper) > 1e-2
    assert paper[1] > 0.8 * paper[0]                     # no convergence with the step


def test_the_contact_potential_is_reported_with_the_energies():
    """``Assembly.energies`` holds the contact potential (part of the total) and the energy
    probe reads it: Σ k δ²/2 over the points of the 55° eyelet, maxima +, the penetrating
    minimum − (computed here from the joint's own output rows)."""
    from types import SimpleNamespace

    from flexmbs.io.probes import EnergyProbe

    model, joint, body, _ = eyelet_on_wire(math.radians(55.0), 1.23e-3)
    asm = Assembly(model)
    q = asm.q_ref.copy()
    v = np.zeros_like(q)
    rows = joint.output(asm, q, v, np.zeros(asm.n_mult), 0.0)
    assert sorted(r["normal_force"] > 0 for r in rows).count(False) == 1   # one minimum
    expected = sum(math.copysign(0.5 * STIFFNESS * r["gap"] ** 2, r["normal_force"])
                   for r in rows)
    energies = asm.energies(q, v)
    assert energies["contact"] == pytest.approx(expected, rel=1e-12)
    assert energies["total"] == pytest.approx(energies["kinetic"] + energies["strain"]
                                              + energies["gravity"] + expected, rel=1e-12)
    state = SimpleNamespace(q=q, v=v, t=0.0)
    assert EnergyProbe("e", "contact").evaluate(asm, state)[0] == pytest.approx(expected)
    assert EnergyProbe("e", "spring").evaluate(asm, state)[0] == 0.0


@pytest.mark.parametrize("onset", [1e-7, 1e-3])
def test_the_smooth_onset_keeps_the_potential_s_gradient_and_the_exact_tangent(onset):
    """The linear law with a smooth onset (LinearPenalty(onset=...): C¹, quadratic below the
    onset): the forces stay the gradient of the section potential and the exact tangent equals
    central differences, with the penetrations beyond the onset (1e-7 m) and within it (1e-3
    m), two points per section at 55°."""
    law = fm.LinearPenalty(stiffness=STIFFNESS, onset=onset)
    model, joint, body, _ = eyelet_on_wire(math.radians(55.0), 1.23e-3, law=law)
    asm = Assembly(model)
    q = _bent(asm, joint)
    err, _ = gradient_error(joint, body, asm, q)
    assert err < GRADIENT_TOL
    depths = [-res.gap for _k, _j, _kind, _e, res, *_ in joint._observed(q, np.zeros_like(q))]
    assert depths and all(d > 0 for d in depths)
    assert all(d > onset for d in depths) if onset < 1e-6 else all(d < onset for d in depths)
    model, joint, body, _ = eyelet_on_wire(math.radians(55.0), 1.23e-3, free=True, law=law)
    asm = Assembly(model)
    _checked_tangent(asm, joint, body, _bent(asm, joint), np.zeros(asm.n_coords))

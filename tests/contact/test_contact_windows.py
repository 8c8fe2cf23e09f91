"""Plans that follow the contacts (issue 52, item 1): a clearance joint's hole body is held
against its beam only on the elements its sections cross, a few either side; a contact found
outside them re-plans the step. The same motion as the plan of the whole reserved pattern, on
the band and on the sparse LU, and a resumed run bit for bit."""

from __future__ import annotations

import sys

import numpy as np
import pytest

import flexmbs as fm
import flexmbs.solvers.generalized_alpha as ga
from flexmbs.assembly import Assembly
from flexmbs.linalg import ordering


def _eyelets(n_elem: int = 30, pull: float = 0.03, shared: bool = False) -> tuple[fm.Model, fm.Beam]:
    """A steel wire (r = 0.3 mm) through three fixed eyelets (bore 1.2 mm, 2 mm long, 3
    sections), sagging under gravity, pulled 3 cm along its axis in 0.2 s by its first node
    (its slope held): every contact slides over several elements. ``shared``: a second wire
    through the same eyelets, its end tied to the last eyelet by a spring."""
    model = fm.Model(gravity=(0.0, 0.0, -9.81))
    wires = []
    for y in ((0.0, 0.5e-3) if shared else (0.0,)):
        wire = model.add_beam(fm.line((-0.05, y, 0.0), (0.25, y, 0.0), elements=n_elem),
                              section=fm.CircularSection(0.3e-3),
                              material=fm.Material(E=2e11, rho=7850.0), damping=1e-4,
                              name=f"wire{len(wires)}")
        wires.append(wire)
    bodies = []
    for k, x in enumerate((0.05, 0.1, 0.15)):
        body = model.add_rigid_body(mass=0.01, inertia=(1e-6, 1e-6, 1e-6),
                                    pose=fm.Pose((x, 0.0, 0.0)), name=f"eyelet{k}")
        model.fix_body(body)
        bodies.append(body)
        for w, wire in enumerate(wires):
            y = 0.5e-3 * w
            model.add_joint(fm.SlidingClearanceJoint(
                wire, body, hole=fm.CircleHole(radius=1.2e-3 if not shared else 1.6e-3,
                                               length=2e-3, sections=3),
                hole_point=(0.0, y, 0.0), contact=fm.LinearPenalty(stiffness=1e5),
                name=f"bore{k}_{w}"))
    wire = wires[0]
    model.prescribe(wire.first_node, [0], fm.Ramp(start=0.0, end=0.2, value=pull, smooth=True))
    model.prescribe(wire.first_node, [1, 2, 4, 5])
    if shared:
        model.add_spring_damper(wires[1].last_node, bodies[-1], stiffness=10.0, name="anchor")
        model.prescribe(wires[1].first_node, [1, 2, 4, 5])
    return model, wire


def _tube(n_elem: int = 30, pull: float = 0.03) -> tuple[fm.Model, fm.Beam]:
    """The same wire through a flexible tube instead of the eyelets: a polymer tube (bore
    0.5 mm, a damped contact, outer radius 2 mm, 10 elements over x = 0..0.2 m, a section every 5 mm) held at
    its ends only, so that both sag and the contacts move along both beams
    (``fm.TubeJoint``: a window per tube element); the wire's far end is held in y and z (a
    free end whipping through the tube's exit makes the motion chaotic: two runs that
    differ by round-off part by 1e-3 within 0.2 s)."""
    model = fm.Model(gravity=(0.0, 0.0, -9.81))
    wire = model.add_beam(fm.line((-0.05, 0.0, 0.0), (0.25, 0.0, 0.0), elements=n_elem),
                          section=fm.CircularSection(0.3e-3),
                          material=fm.Material(E=2e11, rho=7850.0), damping=1e-4, name="wire")
    tube = model.add_beam(fm.line((0.0, 0.0, 0.0), (0.2, 0.0, 0.0), elements=10),
                          section=fm.CircularSection(2e-3),
                          material=fm.Material(E=2e9, rho=1200.0), damping=1e-3, name="tube")
    model.clamp(tube.first_node)
    model.clamp(tube.last_node)
    model.add_joint(fm.TubeJoint(wire, tube, inner_radius=0.5e-3, spacing=5e-3,
                                 contact=fm.LinearPenalty(stiffness=1e5, damping=1.0),
                                 name="lumen"))
    model.prescribe(wire.first_node, [0], fm.Ramp(start=0.0, end=0.2, value=pull, smooth=True))
    model.prescribe(wire.first_node, [1, 2, 4, 5])
    model.prescribe(wire.last_node, [1, 2])
    return model, wire


def _run(tmp_path, follow: bool, t_end: float = 0.2, *, resume: bool = False,
         sparse: bool = False, tube: bool = False):
    ratio, cost = ga.FOLLOW_COST_RATIO, ordering.factor_cost
    ga.FOLLOW_COST_RATIO = np.inf if follow else 0.0
    if sparse:            # every band and border dearer than the sparse LU
        ordering.factor_cost = lambda *a: np.inf  # type: ignore[assignment]
    try:
        model, wire = _tube() if tube else _eyelets()
        res = fm.simulate(model, t_end=t_end, dt=1e-3, output_interval=0.02,
                          record_energy=False, out=tmp_path / "run", resume=resume,
                          integrator=fm.GeneralizedAlpha(
                              rho_inf=0.8, newton=fm.NewtonOptions(modified=False)))
        asm = res.assembly
        res.extra["sparse"] = asm.factor_plan(windows=asm.contact_windows(1)).sparse
    finally:
        ga.FOLLOW_COST_RATIO, ordering.factor_cost = ratio, cost
    return res, wire


@pytest.mark.parametrize("tube", [False, True], ids=["eyelets", "flexible_tube"])
def test_a_plan_that_follows_the_contacts_gives_the_same_motion(tmp_path, tube):
    """Full Newton (a fresh matrix at every iteration): the run on plans that hold each
    eyelet (each element of a flexible tube) against the wire's elements near its sections
    equals the run on the whole reserved pattern's plan to round-off; the contacts moved on
    (re-plans), and afterwards every joint holds its whole beam again."""
    follow, wire = _run(tmp_path / "follow", True, tube=tube)
    fixed, _ = _run(tmp_path / "fixed", False, tube=tube)
    assert follow.stats.replans >= 1 and fixed.stats.replans == 0
    x0 = follow.assembly.node_dofs(wire.first_node)[0]
    assert follow.q[-1, x0] - follow.q[0, x0] == pytest.approx(0.03, rel=1e-9)
    assert np.abs(follow.q - fixed.q).max() < 1e-10
    part = follow.assembly.system.clearance
    assert (part.window[:, 0] == 0).all() and (part.window[:, 1] == wire.n_elem).all()


@pytest.mark.skipif(sys.platform == "win32", reason="no SuiteSparse KLU library on Windows")
def test_the_sparse_plan_follows_the_contacts_and_resumes_bit_for_bit(tmp_path):
    """The same on KLU's sparse LU (forced: this model's band is cheaper): the motion of the
    band's run to round-off, and a run stopped at 0.1 s and resumed equals the uninterrupted
    one bit for bit (the factors rebuilt from the values a checkpoint keeps)."""
    band, _ = _run(tmp_path / "band", True)
    full, _ = _run(tmp_path / "full", True, sparse=True)
    assert full.extra["sparse"] and not band.extra["sparse"]
    assert full.stats.replans >= 1
    assert np.abs(full.q - band.q).max() < 1e-10
    _run(tmp_path / "part", True, 0.1, sparse=True)
    part, _ = _run(tmp_path / "part", True, 0.2, resume=True, sparse=True)
    np.testing.assert_array_equal(part.q[-1], full.q[-1])
    np.testing.assert_array_equal(part.lam[-1], full.lam[-1])


def test_a_following_plan_drops_exactly_the_hole_bodies_entries_outside_the_windows(rng):
    """The stored positions a following plan reads, by their definition: all but each hole
    body's coordinates against its wire's coordinates outside the window's elements, unless
    another joint of the same body and wire holds them, and never those another term
    reserves (a spring from the second wire's end to the last eyelet)."""
    model, _ = _eyelets(shared=True)
    asm = Assembly(model)
    A = asm.matrix
    cols = np.repeat(np.arange(asm.n_total), np.diff(A.indptr))
    rows = A.indices
    joints = asm.joint_lists["clearance"]
    anchored = asm.body_dofs(model.body("eyelet2"))
    anchor_node = asm.node_dofs(model.beam("wire1").last_node)[:3]   # the spring's ends
    for _ in range(5):
        windows = []
        expected = np.ones(A.nnz, bool)
        for joint in joints:
            g = joint.geometry
            lo = int(rng.integers(0, g.elem_dofs.shape[0]))
            hi = int(rng.integers(lo + 1, g.elem_dofs.shape[0] + 1))
            windows.append((lo, hi))
        for joint, (lo, hi) in zip(joints, windows, strict=True):
            g = joint.geometry
            inside = np.unique(g.elem_dofs[lo:hi])
            outside = np.setdiff1d(g.beam_dofs, inside)
            drop = ((np.isin(rows, g.body_dofs) & np.isin(cols, outside))
                    | (np.isin(cols, g.body_dofs) & np.isin(rows, outside)))
            if np.array_equal(g.body_dofs, anchored):    # the spring's entries
                drop &= ~((np.isin(rows, anchored) & np.isin(cols, anchor_node))
                          | (np.isin(cols, anchored) & np.isin(rows, anchor_node)))
            expected &= ~drop
        keep = asm._window_entries(np.array(windows, np.int64))
        assert (~expected).sum() > 0
        np.testing.assert_array_equal(keep, expected)


def test_a_tube_element_is_held_against_the_wire_near_its_own_sections_only(rng):
    """A flexible tube's stored pattern holds each of its elements against itself and the
    wire, never against the tube's far elements; a following plan reads, by definition, all
    but a tube element's coordinates against the wire's coordinates outside its own window,
    unless the neighbouring element that shares the node holds them in its window."""
    model, _ = _tube()
    asm = Assembly(model)
    A = asm.matrix
    cols = np.repeat(np.arange(asm.n_total), np.diff(A.indptr))
    rows = A.indices
    joint = asm.joint_lists["clearance"][0]
    owns, g = joint.window_owns(), joint.geometry
    assert len(owns) == model.beam("tube").n_elem          # every element carries sections
    assert (asm.pattern.positions_present(owns[0], owns[3]) < 0).all()   # no shared element
    n_wire = g.elem_dofs.shape[0]
    for _ in range(5):
        windows = []
        for _own in owns:
            lo = int(rng.integers(0, n_wire))
            windows.append((lo, int(rng.integers(lo + 1, min(lo + 6, n_wire) + 1))))
        candidate = np.zeros(A.nnz, bool)
        covered = np.zeros(A.nnz, bool)
        for own, (lo, hi) in zip(owns, windows, strict=True):
            inside = np.unique(g.elem_dofs[lo:hi])
            candidate |= ((np.isin(rows, own) & np.isin(cols, g.beam_dofs))
                          | (np.isin(cols, own) & np.isin(rows, g.beam_dofs)))
            covered |= ((np.isin(rows, own) & np.isin(cols, inside))
                        | (np.isin(cols, own) & np.isin(rows, inside)))
        expected = ~candidate | covered
        keep = asm._window_entries(np.array(windows, np.int64))
        assert (~expected).sum() > 0
        np.testing.assert_array_equal(keep, expected)


def test_statics_on_a_plan_that_follows_the_contacts(monkeypatch):
    """solve_static on the following plan (solvers.factor.FollowingStaticLU): the wire pulled 3
    cm through the sagging eyelets leaves its windows (OffPlanError: the increment is solved
    again on a wider plan, not halved) and ends at the equilibrium of the whole reserved
    pattern's plan to round-off; afterwards every joint holds its whole beam again."""
    import flexmbs.solvers.factor as factor

    solutions, replans = [], []
    original = factor.FollowingStaticLU.replan

    def counted(self, widen, again):
        replans.append(widen)
        original(self, widen, again)

    monkeypatch.setattr(factor.FollowingStaticLU, "replan", counted)
    for follow in (True, False):
        monkeypatch.setattr(factor, "FOLLOW_COST_RATIO", np.inf if follow else 0.0)
        model, wire = _eyelets()
        asm = Assembly(model)
        st = fm.solve_static(asm, fm.StaticOptions(load_steps=4), t=0.2)
        solutions.append(st.q)
        assert [tuple(w) for w in asm.system.clearance.window] == [(0, wire.n_elem)] * 3
        if follow:
            assert len(replans) >= 1
    assert len(replans) >= 1
    np.testing.assert_allclose(solutions[0], solutions[1], rtol=0, atol=1e-12)


def test_a_jacobian_on_a_following_plan_sweeps_only_the_plan():
    """While a plan follows the contacts (``Assembly.follow``), Newton's matrix is cleared only
    at the positions that plan reads and in the multipliers' rows and columns
    (``SystemPart.zero``): with the stored values made NaN
    first, the planned entries equal those of the whole pattern's evaluation at the same state,
    and every other entry is left as it was (NaN: not swept); with the whole beams held again
    (``follow(None)``) every entry is cleared."""
    model, _ = _tube()
    res = fm.simulate(model, t_end=0.05, dt=1e-3, output_interval=0.05, record_energy=False)
    asm = res.assembly
    q, v = res.q[-1], res.v[-1]
    n, m = asm.n_coords, asm.n_mult

    def matrix() -> np.ndarray:
        rq, rl = np.zeros(n), np.zeros(m)
        asm.evaluate(q, v, np.zeros(n), np.zeros(m), 0.05, rq, rl, matrix=(1.0, 0.5, 0.25))
        return asm.matrix.data.copy()

    whole = matrix()
    windows = asm.contact_windows(1)
    assert windows is not None
    keep = asm._window_entries(windows) | asm._multiplier_entries()
    assert 0 < keep.sum() < keep.size
    asm.follow(windows)
    assert asm.system.zero[0] == keep.sum()
    asm.matrix.data[:] = np.nan
    planned = matrix()
    np.testing.assert_array_equal(planned[keep], whole[keep])
    assert np.isnan(planned[~keep]).all()
    asm.follow(None)
    assert asm.system.zero[0] == -1
    asm.matrix.data[:] = np.nan
    np.testing.assert_array_equal(matrix(), whole)

"""The beam's element tree (issue 52, "many holes on one beam"): a hole's detection descends it
to the elements near the bore instead of visiting every element of the beam.

Independent references: points sampled on the centreline (every one inside its element's
sphere, every child sphere inside its parent's), and the scan of every element (a tree whose
inner spheres hold everything): the candidates found are the same, row for row."""

from __future__ import annotations

import math

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.assembly import Assembly
from flexmbs.contact import joint as joint_module
from flexmbs.elements.centerline import element_tree, element_tree_size
from flexmbs.elements.hermite import element_point
from tests.contact.test_curved_bore import _hairpin_model


def _random_chain(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    """A chain of n cubic elements with random nodes and slopes (C¹ across nodes)."""
    nodes = np.cumsum(rng.normal(scale=0.01, size=(n + 1, 3)), axis=0)
    slopes = rng.normal(size=(n + 1, 3))
    qe = np.zeros((n, 12))
    for e in range(n):
        qe[e] = np.concatenate([nodes[e], slopes[e], nodes[e + 1], slopes[e + 1]])
    return qe, rng.uniform(0.005, 0.02, n)


@pytest.mark.parametrize("n", [1, 2, 5, 17, 64])
def test_the_element_tree_holds_the_centreline_and_each_child(n: int) -> None:
    rng = np.random.default_rng(n)
    qe, lengths = _random_chain(rng, n)
    tree = np.zeros((element_tree_size(n), 4))
    element_tree(qe, lengths, tree)
    P = tree.shape[0] // 2
    assert n <= P and tree[1, 3] > 0.0
    for e in range(n):
        for xi in np.linspace(0.0, 1.0, 41):
            r = element_point(qe[e], lengths[e], xi)[0]
            assert np.linalg.norm(r - tree[P + e, :3]) <= tree[P + e, 3] * (1 + 1e-12)
    assert np.all(tree[P + n:, 3] == -1.0)
    for i in range(1, P):
        for child in (2 * i, 2 * i + 1):
            if tree[child, 3] < 0.0:
                continue
            gap = np.linalg.norm(tree[child, :3] - tree[i, :3]) + tree[child, 3] - tree[i, 3]
            assert gap <= 1e-15 * max(1.0, tree[i, 3])


def _scan_every_element(qe: np.ndarray, lengths: np.ndarray, tree: np.ndarray) -> None:
    """The tree of a scan of every element: the leaves as built, inner spheres that hold all."""
    element_tree(qe, lengths, tree)
    P = tree.shape[0] // 2
    for i in range(1, P):
        if tree[i, 3] >= 0.0:
            tree[i, 3] = 1e30


def _rows(joint: fm.SlidingClearanceJoint, q: np.ndarray) -> tuple[int, np.ndarray]:
    m = joint.detect_rows(q)
    return m, joint._rows[:max(m, 0)].copy()


def test_detection_through_the_tree_equals_a_scan_of_every_element(monkeypatch) -> None:
    """The hairpin's two strands in one bore (each section crossed twice), its wire moved at
    random: the rows (sections, candidates, crossings, contact points) are the scan's, bit for
    bit, and some configurations have contacts."""
    model = _hairpin_model()
    joint = next(j for j in model.interactions if isinstance(j, fm.SlidingClearanceJoint))
    asm = Assembly(model)
    q0 = asm.q_ref
    wire = joint.geometry.beam_dofs
    rng = np.random.default_rng(3)
    with_contacts = 0
    for trial in range(12):
        q = q0.copy()
        q[wire] += rng.normal(scale=4e-5 * trial, size=wire.size)
        m_tree, rows_tree = _rows(joint, q)
        monkeypatch.setattr(joint_module, "element_tree", _scan_every_element)
        m_scan, rows_scan = _rows(joint, q)
        monkeypatch.undo()
        assert m_tree == m_scan
        np.testing.assert_array_equal(rows_tree, rows_scan)
        with_contacts += m_tree > 0
    assert with_contacts >= 6


def test_holes_on_one_beam_share_its_tree() -> None:
    """Joints on the same beam share one copy of its coordinates and one tree per evaluation;
    joints on another beam have their own."""
    model = fm.Model(gravity=(0, 0, 0))
    beams = [model.add_beam(fm.line((0, y, 0), (0.1, y, 0), elements=8), name=f"w{i}",
                            section=fm.CircularSection(1e-4), material=fm.Material(E=2e11, rho=7800))
             for i, y in enumerate((0.0, 0.01))]
    for b, y in zip(beams, (0.0, 0.01), strict=True):
        model.clamp(b.first_node)
        for x in (0.02, 0.05, 0.08):
            body = model.add_rigid_body(mass=1e-3, inertia=(1e-8,) * 3,
                                        pose=fm.Pose(np.array([x, y, 0.0]), np.eye(3)))
            model.fix_body(body)
            model.add_joint(fm.SlidingClearanceJoint(b, body, hole=fm.CircleHole(2e-4, 1e-3, 3),
                                                     contact=fm.LinearPenalty(stiffness=1e5)))
    part = Assembly(model).system.clearance
    assert list(part.beam_of) == [0, 0, 0, 1, 1, 1] and list(part.beam_joint) == [0, 3]
    assert part.beam_tree.shape == (2, element_tree_size(8), 4)
    assert math.isfinite(part.beam_qe.sum())

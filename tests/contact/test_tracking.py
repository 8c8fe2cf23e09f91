"""Contact identity of the clearance joint (docs/theory.md §II.3): a contact point of a hole section
is the same contact from one step to the next when the section angle of its hole point moves
less than MATCH_ANGLE; it then keeps the approach velocity stored at its onset (used by the
dissipative laws), whatever its index among the stationary points of the section."""

from __future__ import annotations

import math

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.contact._detect import N_COLS
from flexmbs.contact.clearance_term import MATCH_ANGLE, clearance_update, tracked_approach
from tests.contact.test_clearance_joint import _beam_with_sleeve

P = 8   # tracked points per section (the joint's MAX_POINTS)


def _rows(*contacts: tuple[int, float, float, float]) -> np.ndarray:
    """Candidate rows (section, psi, gap, gap_rate) in the column layout of the detector."""
    rows = np.zeros((len(contacts), N_COLS))
    for i, (k, psi, gap, rate) in enumerate(contacts):
        rows[i, [0, 11, 12, 13]] = k, psi, gap, rate
    return rows


#: the sections crossed at the step's start not listed: every section is visited
ALL = np.full(1, -1, np.int64)


def _anchors(sections: int) -> tuple[np.ndarray, np.ndarray]:
    """Friction anchors and stick flags of ``sections`` sections (unused by these tests)."""
    return np.zeros((sections, P, 3)), np.zeros((sections, P))


def test_update_keeps_identity_by_angle_not_by_order():
    approach = np.zeros((2, P))
    active = np.zeros((2, P), dtype=bool)
    psi = np.zeros((2, P))
    # onset: section 0 at psi 1.0 (approaching at 0.3 m/s), section 1 at psi -2.0
    rows = _rows((0, 1.0, -1e-6, -0.3), (1, -2.0, -1e-6, -0.1))
    clearance_update(rows, 2, ALL, approach, active, psi, *_anchors(2))
    assert tracked_approach(approach, active, psi, 0, 1.0) == pytest.approx(0.3)
    assert tracked_approach(approach, active, psi, 1, -2.0) == pytest.approx(0.1)
    # next step: a second point appears in section 0 and is listed first; the old one moved
    # by 0.05 rad and now separates (gap rate > 0): it keeps its onset value
    rows = _rows((0, -1.5, -2e-7, -0.7), (0, 1.05, -5e-7, 0.2), (1, -2.0, 3e-7, 0.1))
    clearance_update(rows, 3, ALL, approach, active, psi, *_anchors(2))
    assert tracked_approach(approach, active, psi, 0, 1.05) == pytest.approx(0.3)
    assert tracked_approach(approach, active, psi, 0, -1.5) == pytest.approx(0.7)
    # section 1 opened (gap > 0): released; a later contact there is a new one
    assert not active[1].any()
    assert tracked_approach(approach, active, psi, 1, -2.0) == 0.0
    # a point farther than MATCH_ANGLE from every tracked one is new
    assert tracked_approach(approach, active, psi, 0, 1.05 + 1.5 * MATCH_ANGLE) == 0.0
    # across the angle wrap-around (pi -> -pi) the identity holds
    approach[:] = 0.0
    active[:] = False
    clearance_update(_rows((0, math.pi - 0.01, -1e-6, -0.4)), 1, ALL, approach, active, psi, *_anchors(2))
    clearance_update(_rows((0, -math.pi + 0.01, -1e-6, 0.5)), 1, ALL, approach, active, psi, *_anchors(2))
    assert tracked_approach(approach, active, psi, 0, -math.pi + 0.01) == pytest.approx(0.4)


def test_listing_the_crossed_sections_changes_nothing():
    """The post-step update visits only the sections with rows or crossed at the step's start
    (where every tracked contact lies): over 40 random steps on 60 sections it tracks exactly
    what visiting every section does."""
    rng = np.random.default_rng(3)
    ns = 60
    state = {name: (np.zeros((ns, P)), np.zeros((ns, P), dtype=bool), np.zeros((ns, P)),
                    *_anchors(ns)) for name in ("all", "listed")}
    crossed = np.full(ns + 1, -1, np.int64)
    crossed[0] = 0
    tracked = 0
    for _ in range(40):
        sections = np.sort(rng.choice(ns, size=rng.integers(0, 12), replace=False))
        contacts = [(int(k), float(rng.uniform(-np.pi, np.pi)), float(rng.uniform(-1e-6, 5e-7)),
                     float(rng.uniform(-1.0, 1.0))) for k in sections for _ in range(rng.integers(1, 3))]
        rows = _rows(*contacts) if contacts else np.zeros((0, N_COLS))
        clearance_update(rows, len(contacts), ALL, *state["all"])
        clearance_update(rows, len(contacts), crossed, *state["listed"])
        for a, b in zip(state["all"], state["listed"], strict=True):
            np.testing.assert_array_equal(a, b)
        tracked += int(state["all"][1].sum())
        crossed[0] = sections.size           # the next step starts where these were crossed
        crossed[1:1 + sections.size] = sections
    assert tracked > 40                      # contacts were tracked along the way


@pytest.mark.parametrize("compiled", [True, False], ids=["compiled", "python"])
def test_ongoing_contacts_keep_their_approach_velocity(compiled):
    """Sleeve sliding down a damped stiff rod with the Hunt-Crossley law: every section in
    contact keeps the approach velocity of its onset as long as it stays in contact (before the
    fix, the index of a contact among the stationary points flipped and the value was
    overwritten 80 times in 1000 steps). Checked after every step over 0.05 s."""
    alpha = 0.3
    d = (math.cos(alpha), 0.0, -math.sin(alpha))
    model, beam, sleeve, joint = _beam_with_sleeve(direction=d, offset=-5.05e-4 / math.cos(alpha),
                                                   lock_axial=False, s=0.2)
    joint.contact = fm.HuntCrossley(stiffness=1e6, exponent=1.0, restitution=0.5)
    for b in model.beams:
        b.stiffness = fm.BeamStiffness(axial_stiffness=2.6e8, bending_stiffness=2.6e2,
                                       mass_per_length=0.098, radius=2e-3)
        b.damping = 1e-3
    history = []

    def watch(state, stats):
        history.append((joint.state.active.copy(), joint.state.approach.copy(), joint.state.psi.copy()))

    fm.simulate(model, t_end=0.05, dt=2e-4, output_interval=2e-4, record_energy=False,
                progress=watch, integrator=fm.GeneralizedAlpha(compiled=compiled))
    kept = 0
    for (a0, v0, p0), (a1, v1, p1) in zip(history, history[1:], strict=False):
        for k in range(a0.shape[0]):
            if a0[k].sum() == 1 and a1[k].sum() == 1:      # one ongoing contact
                s0, s1 = np.flatnonzero(a0[k])[0], np.flatnonzero(a1[k])[0]
                if abs(p1[k, s1] - p0[k, s0]) < MATCH_ANGLE:
                    assert v1[k, s1] == v0[k, s0]
                    kept += 1
    assert kept > 200   # the check ran on many contact/step pairs

"""The damped linear penalty in a curved bore (issue 53 item 2; docs/design-notes.md "The
damped penalty in a curved bore (issue 53 item 2)").

A steel wire (r = 0.25 mm, 64 elements) runs straight for 50 mm, round a quarter circle of
radius 0.2 m and straight for 50 mm, stress-free along that path, through a fixed bore along
the arc (radius 0.35 mm, sections every 2 mm, open ends); 10 N pull it back at the inlet
(ramped in over 0.1 s) while the outlet is held, then pulled out at 20 mm/s.
``LinearPenalty(stiffness=2e5, damping=2.0)``: before the fix the run stopped at the first
contacts (t = 3.85 ms, at any step down to 2e-7 s): the viscous force jumped from 0 to c δ̇
at first touch, and a step whose contact closed within that jump had no solution (Newton
cycled with one section open and closed; the tube's row, which sums every section's force,
was the worst equation). Independent references: the capstan law e^{μθ} for the pull, and
the generalized-α step equation of one point on the wall (tests/contact/test_laws.py)."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import flexmbs as fm
from tests.conftest import FULL

RHO, BORE, WIRE_R, STRAIGHT, T_LOAD, RAMP, SPEED = 0.2, 0.35e-3, 0.25e-3, 0.05, 10.0, 0.1, 0.02


def _build(law: fm.LinearPenalty, mu: float = 0.0) -> tuple[fm.Model, fm.Beam, fm.SlidingClearanceJoint]:
    """The wire through the quarter-circle bore: 8 + 48 + 8 elements, in along +y at x = −ρ,
    round the arc about the origin (clockwise from (−ρ, 0) to (0, ρ)), out along +x; the
    outlet node moves along +x by the pull, its other components held."""
    pts, tans = [], []
    for k in range(8):
        pts.append((-RHO, -STRAIGHT + k * STRAIGHT / 8, 0.0))
        tans.append((0.0, 1.0, 0.0))
    for k in range(49):
        phi = math.pi - 0.5 * math.pi * k / 48
        pts.append((RHO * math.cos(phi), RHO * math.sin(phi), 0.0))
        tans.append((math.sin(phi), -math.cos(phi), 0.0))
    for k in range(1, 9):
        pts.append((k * STRAIGHT / 8, RHO, 0.0))
        tans.append((1.0, 0.0, 0.0))
    model = fm.Model(name="damped_bore", gravity=(0.0, 0.0, 0.0))
    wire = model.add_beam(fm.polyline(np.array(pts), np.array(tans)),
                          section=fm.CircularSection(WIRE_R),
                          material=fm.Material(E=2e11, rho=7800.0), name="wire")
    tube = model.add_rigid_body(mass=1.0, inertia=(1e-3, 1e-3, 1e-3), name="tube")
    model.fix_body(tube)
    arc = fm.arc((0.0, 0.0, 0.0), RHO, (-RHO, 0.0, 0.0), -0.5 * math.pi, normal=(0, 0, 1),
                 elements=64)
    joint = model.add_joint(fm.SlidingClearanceJoint(
        wire, tube, hole=fm.CurvedBore(arc, radius=BORE, spacing=2e-3), contact=law,
        friction=fm.Friction(mu=mu) if mu > 0 else None, name="tube"))
    model.add_point_load(wire.first_node, (0.0, -T_LOAD, 0.0),
                         function=fm.Ramp(start=0.0, end=RAMP, value=1.0, smooth=True))
    model.prescribe(wire.last_node, [0], fm.Ramp(start=RAMP, end=RAMP + 1.0, value=SPEED),
                    name="pull")
    model.prescribe(wire.last_node, [1, 2], name="pull_line")
    return model, wire, joint


def test_a_damped_law_without_an_onset_ramps_its_viscous_force_over_the_clearance() -> None:
    """The joint keeps a damped linear law without an onset with its viscous force ramped in
    over DAMPING_ONSET of the radial clearance (0.1 mm here); the others as given."""
    from flexmbs.contact.laws import DAMPING_ONSET

    _, _, joint = _build(fm.LinearPenalty(stiffness=2e5, damping=2.0))
    assert joint.contact.damping_onset == pytest.approx(DAMPING_ONSET * (BORE - WIRE_R))
    assert joint.contact.parameters()[6] == pytest.approx(1e-7)
    for law in (fm.LinearPenalty(stiffness=2e5), fm.LinearPenalty(stiffness=2e5, damping=2.0,
                                                                  damping_onset=0.0),
                fm.Hertz(stiffness=1e9)):
        joint.contact = law
        assert joint.contact is law


def _closes_the_curved_bore_s_contacts() -> None:
    """Issue 53 item 2, the fast form: fixed steps of 2e-6 s through the first contacts (from
    t ≈ 3.85 ms) to 6 ms: every step converges (before the fix: "Newton did not converge"
    at t = 3.852 ms, worst equation the tube body's x) and the wire lies on the inner wall
    (the side of the bend's centre) over several sections."""
    model, wire, joint = _build(fm.LinearPenalty(stiffness=2e5, damping=2.0))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = fm.simulate(model, t_end=6e-3, dt=2e-6, output_interval=1e-3, record_energy=False,
                          integrator=fm.GeneralizedAlpha(rho_inf=0.8, adaptive=False))
    assert res.stats.rejected_steps == 0 and res.t[-1] == pytest.approx(6e-3)
    q = res.q[-1]
    rows = joint.output(res.assembly, q, np.zeros_like(q), np.zeros(res.assembly.n_mult), 6e-3)
    touching = [r for r in rows if r["normal_force"] > 0]
    assert len({r["section"] for r in touching}) >= 5
    for r in touching:       # the wall pushes the wire away from the bend's centre: n·Q < 0
        assert np.dot(r["normal"], r["position"]) < 0


@pytest.mark.slow
def test_the_damped_penalty_pulls_through_the_curved_bore_by_the_capstan_law() -> None:
    """Issue 53 item 2, the whole run's first 0.2 s (0.1 s of load ramp, 0.1 s = 2 mm of
    sliding) with stick friction μ = 0.2, steps of 1e-5 s (cut where Newton needs it): the
    pull over the last 50 ms is T e^{μπ/2} = 13.691 N within 0.2 % (measured 13.689 N, about
    140 s for 0.3 s) with FLEXMBS_FULL=1; the fast form passes the first contacts
    (:func:`_closes_the_curved_bore_s_contacts`)."""
    if not FULL:
        _closes_the_curved_bore_s_contacts()
        return
    model, wire, _ = _build(fm.LinearPenalty(stiffness=2e5, damping=2.0), mu=0.2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = fm.simulate(model, t_end=0.2, dt=1e-5, output_interval=1e-3, record_energy=False,
                          integrator=fm.GeneralizedAlpha(rho_inf=0.8))
    F, _ = res.reaction("pull", wire)
    late = F[res.t > 0.15, 0]
    capstan = T_LOAD * math.exp(0.2 * math.pi / 2)
    assert late.mean() == pytest.approx(capstan, rel=2e-3)
    assert np.ptp(late) < 0.02 * capstan

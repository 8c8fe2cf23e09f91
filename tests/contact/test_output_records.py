"""An output's contact records (contacts.csv rows, section counts, the contact energy and
force) are read from the candidate rows of the kernel's residual at the output's state
(``Assembly.observe``): after a converged step those of its last residual, else of one
residual evaluated there. Independent reference: the joint's own Python path
(:meth:`SlidingClearanceJoint._contacts`: the compiled narrow phase and ``contact_point``
called one by one); and a run that observes ends bit for bit where one that does not.

The model: the guide wire of examples/guide_wire.py pushed 25 mm into the curved tube, its tip
in the bend (open ends: tip sections; friction that sticks and slips)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from flexmbs.assembly import Assembly
from flexmbs.contact.laws import law_energy
from flexmbs.solvers.generalized_alpha import GeneralizedAlpha, State, integrate
from tests.conftest import load_example

T_MID, T_END, DT = 0.25, 0.26, 2e-4


def _run(observe_between: bool) -> tuple[Assembly, object, State, list[State]]:
    """The push to T_MID, then on to T_END (outputs every 5 ms); with ``observe_between`` the
    state at T_MID is observed with a residual of its own in between."""
    ex = load_example("guide_wire")
    model, _wire, joint = ex.build(0.03, 0.1, 60.0, 10.0, 0.1)
    asm = Assembly(model)
    opts = GeneralizedAlpha(rho_inf=0.8)
    seen: list[State] = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        mid, _ = integrate(asm, opts, t_end=T_MID, dt=DT)
        if observe_between:
            part = asm.system.clearance
            before = [np.array(a, copy=True) for a in joint.state if a is not None]
            due = part.tips_due.copy()
            asm.observe(mid.q, mid.v, mid.lam, mid.t)
            after = [a for a in joint.state if a is not None]
            assert all(np.array_equal(x, y) for x, y in zip(before, after, strict=True))
            np.testing.assert_array_equal(part.tips_due, due)
        end, _ = integrate(asm, opts, t_end=T_END, dt=DT, state=mid, output_interval=5e-3,
                           observer=lambda s: seen.append(s.copy()))
    return asm, joint, end, seen


def _same_contacts(kept: list, python: list) -> None:
    assert [c[:4] for c in kept] == [c[:4] for c in python]
    for (*_, a, _a1, _b1, psi_a), (*_, b, _a2, _b2, psi_b) in zip(kept, python, strict=True):
        scale = max(b.f_n, 1e-12)
        assert a.gap == pytest.approx(b.gap, abs=1e-15)
        assert a.f_n == pytest.approx(b.f_n, rel=1e-10, abs=1e-12)
        assert a.fade == pytest.approx(b.fade, rel=1e-12)      # a section a tip reaches
        np.testing.assert_allclose(a.force_on_hole, b.force_on_hole, rtol=0, atol=1e-10 * scale)
        np.testing.assert_allclose(a.P, b.P, rtol=0, atol=1e-15)
        np.testing.assert_allclose(a.Q, b.Q, rtol=0, atol=1e-15)
        np.testing.assert_allclose(a.normal, b.normal, rtol=0, atol=1e-12)
        assert psi_a == psi_b


def test_an_output_reads_the_residuals_contacts_and_changes_nothing():
    asm, joint, end, seen = _run(observe_between=True)
    _, _, end_plain, seen_plain = _run(observe_between=False)
    # observing (a residual of its own, tip sections due kept due) changed no step
    np.testing.assert_array_equal(end.q, end_plain.q)
    np.testing.assert_array_equal(end.v, end_plain.v)
    assert len(seen) == len(seen_plain) == 3
    # the last output's records (the converged step's residual) against the Python path
    q, v = end.q, end.v
    kept = joint._observed(q, v)
    assert joint._records is not None and kept is joint._records[1]    # read, not detected
    python = joint._contacts(q, v, False, False)
    assert len(python) >= 2 and any(c[4].f_n > 0.0 for c in python)
    _same_contacts(kept, python)
    law = joint.contact.parameters()
    assert joint.contact_energy(q, v) == pytest.approx(
        sum(c[2] * c[4].fade * law_energy(law, -c[4].gap) for c in python), rel=1e-12)
    rows = joint.output(asm, q, v, end.lam, end.t)
    assert len(rows) == len(python)
    # a residual of its own at a state (not a step's): the same records
    asm.observe(q, v, end.lam, end.t)
    _same_contacts(joint._observed(q, v), python)
    # another state is detected again, not read from the kept rows
    q2 = q.copy()
    q2[asm.node_dofs(joint.beam.last_node)[1]] += 1e-5
    assert joint._observed(q2, v) is not joint._records[1]

"""Static solver: load stepping and the mass-proportional stabiliser on a slack start."""

from __future__ import annotations

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.assembly import Assembly
from tests.conftest import straight_beam


def _taut_string():
    """Straight, stress-free string pinned at both ends (no slack), gravity across it: the
    reference has no transverse stiffness at all (singular first Newton matrix)."""
    model = fm.Model(gravity=(0, 0, -9.81))
    beam = straight_beam(model, 16, EA=1e4, EI=1e-6, rhoA=1.0)
    model.pin(beam.first_node)
    model.pin(beam.last_node)
    return model, beam


def test_string_sag_and_stabilizer_leaves_equilibrium_unchanged():
    """A straight string (EI ~ 0) between pins has almost no transverse stiffness at the start;
    Newton still reaches the shallow elastic-string sag f^3 = 3 q L^4 / (64 EA) (tension
    qL^2/(8f) = EA (8/3)(f/L)^2): 0.0358 m here, accurate to O((f/L)^2) ~ 1e-3 with negligible
    bending, 1 % tolerance. The stabiliser c_s (1 - load^2) M only changes the Newton matrix of
    the intermediate increments, so the equilibrium is the same to the solver tolerance."""
    sags = []
    for c_s in (0.0, 100.0):
        model, beam = _taut_string()
        asm = Assembly(model)
        st = fm.solve_static(asm, fm.StaticOptions(load_steps=4, stabilizer=c_s))
        sags.append(-st.q[asm.node_dofs(beam.node(8))[2]])
    assert sags[0] == pytest.approx((3 * 9.81 * 1.0 / (64 * 1e4)) ** (1 / 3), rel=1e-2)
    assert sags[1] == pytest.approx(sags[0], rel=1e-9)


def test_load_stepping_grows_and_reports_increments():
    model = fm.Model()
    beam = straight_beam(model, 8, EA=1e8, EI=1.0)
    model.clamp(beam.first_node)
    model.add_point_load(beam.last_node, (0, 0, -10.0))
    st = fm.solve_static(model, fm.StaticOptions(load_steps=8))
    assert 2 <= st.load_increments <= 8   # easy increments grow the step
    assert np.isfinite(st.q).all()


@pytest.mark.parametrize("times", [[], [0.0, 0.0], [1.0, 0.5], [0.0, float("nan")], [[0.0, 1.0]]])
def test_quasi_static_times_must_increase(times):
    model = fm.Model()
    model.add_beam(fm.line((0, 0, 0), (1, 0, 0), elements=2), section=fm.CircularSection(1e-3),
                   material=fm.Material(E=1e9, rho=1e3))
    with pytest.raises(fm.ModelError, match="times: an increasing sequence"):
        fm.solve_quasi_static(model, times)

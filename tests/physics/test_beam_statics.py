"""Static beam validation against closed forms (docs/theory.md §I.7)."""

from __future__ import annotations

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.assembly import Assembly
from flexmbs.simulation import beam_positions
from tests.conftest import quarter_arc_beam, straight_beam


def _cantilever_under_gravity(n_elem: int, EI: float):
    model = fm.Model(gravity=(0, 0, -9.81))
    beam = straight_beam(model, n_elem, EA=1e9, EI=EI, rhoA=0.5)
    model.clamp(beam.first_node)
    asm = Assembly(model)
    st = fm.solve_static(asm)
    return model, beam, asm, st


def test_cantilever_gravity_small_deflection():
    """Tip deflection qL^4/(8EI) and rotation qL^3/(6EI). EI is chosen so that w/L ~ 1e-5: the
    geometric nonlinearity is O((w/L)^2) ~ 1e-10 and cubic Hermite elements reproduce the linear
    solution exactly at the nodes, so 1e-6 relative is a sharp but safe tolerance."""
    EI, q, L = 5e5, 0.5 * 9.81, 1.0
    _, beam, asm, st = _cantilever_under_gravity(4, EI)
    tip = asm.node_dofs(beam.last_node)
    w = st.q[tip[2]] - asm.q_ref[tip[2]]
    slope = st.q[tip[3:6]]
    theta = np.arctan2(-slope[2], slope[0])
    assert w == pytest.approx(-q * L**4 / (8 * EI), rel=1e-6)
    assert theta == pytest.approx(q * L**3 / (6 * EI), rel=1e-6)


def test_cantilever_deflection_field_converges_at_fourth_order():
    """Max error of the deflection field between nodes vs the exact quartic
    w(x) = q x^2 (6L^2 - 4Lx + x^2)/(24EI): cubic Hermite interpolation error is O(h^4)."""
    EI, q, L = 5e5, 0.5 * 9.81, 1.0
    x = np.linspace(0, L, 401)
    exact = -q * x**2 * (6 * L**2 - 4 * L * x + x**2) / (24 * EI)
    ns = [1, 2, 4, 8]
    errs = []
    for n in ns:
        _, beam, asm, st = _cantilever_under_gravity(n, EI)
        z = beam_positions(asm, beam, st.q, x)[:, 2]
        errs.append(np.abs(z - exact).max())
    rate = np.polyfit(np.log(1.0 / np.array(ns)), np.log(errs), 1)[0]
    assert rate == pytest.approx(4.0, abs=0.25)


# inextensible elastica, docs/theory.md §I.7.2(a) [V]: alpha -> (u_h/L, v/L, theta_tip)
ELASTICA = {1.0: (0.05643, 0.30172, 0.46135), 3.0: (0.25442, 0.60325, 0.98602),
            10.0: (0.55500, 0.81061, 1.43029)}


@pytest.mark.parametrize("alpha", sorted(ELASTICA))
def test_large_deflection_cantilever_elastica(alpha):
    """Dead vertical tip load P = alpha EI/L^2 on a nearly inextensible cantilever
    (EA L^2/EI = 1e8). 16 elements with Lobatto axial integration reach 5 digits in
    docs/theory.md §I.1.5; the table has 5 decimals, so 2e-4 absolute (on quantities ~0.05-1.4)."""
    L, EI = 1.0, 1.0
    model = fm.Model()
    beam = straight_beam(model, 16, EA=1e8, EI=EI)
    model.clamp(beam.first_node)
    model.add_point_load(beam.last_node, (0, 0, -alpha * EI / L**2))
    asm = Assembly(model)
    st = fm.solve_static(asm, fm.StaticOptions(load_steps=4))
    tip = asm.node_dofs(beam.last_node)
    u = st.q[tip[:3]] - asm.q_ref[tip[:3]]
    sl = st.q[tip[3:6]]
    theta = np.arctan2(-sl[2], sl[0])
    uh, v, th = ELASTICA[alpha]
    assert -u[0] / L == pytest.approx(uh, abs=2e-4)
    assert -u[2] / L == pytest.approx(v, abs=2e-4)
    assert theta == pytest.approx(th, abs=2e-4)


def test_elastica_mesh_convergence():
    """alpha = 3: error of v/L against 0.60325 decreases with a fitted order >= 2 from 2 to 8
    elements (docs/theory.md §I.1.5 table: 0.60286, 0.60323, 0.60325 for 4, 8, 16)."""
    errs = []
    ns = [2, 4, 8]
    for n in ns:
        model = fm.Model()
        beam = straight_beam(model, n, EA=1e8, EI=1.0)
        model.clamp(beam.first_node)
        model.add_point_load(beam.last_node, (0, 0, -3.0))
        asm = Assembly(model)
        st = fm.solve_static(asm, fm.StaticOptions(load_steps=4))
        v = -(st.q[asm.node_dofs(beam.last_node)[2]])
        errs.append(abs(v - 0.603254))
    rate = np.polyfit(np.log(1.0 / np.array(ns)), np.log(errs), 1)[0]
    assert rate >= 2.0


@pytest.mark.parametrize("direction", ["radial", "tangential"])
def test_quarter_arc_castigliano(direction):
    """Quarter circle, R = EI = 1, small tip load, nearly inextensible (EA = 1e7): Castigliano
    (docs/theory.md §I.7.4a). Radial load (-y): along-load pi/4, transverse (+x) 1/2; tangential load
    (+x): along-load 3pi/4 - 2, transverse (-y)... 1/2 (units P R^3/EI). P = 1e-4 keeps the
    response linear to ~1e-4; 16 elements: discretisation error ~1e-4 -> 1e-3 relative."""
    P = 1e-4
    model = fm.Model()
    beam = quarter_arc_beam(model, 16, EA=1e7, EI=1.0)
    model.clamp(beam.first_node)
    F = (0, -P, 0) if direction == "radial" else (P, 0, 0)
    model.add_point_load(beam.last_node, F)
    asm = Assembly(model)
    st = fm.solve_static(asm)
    d = asm.node_dofs(beam.last_node)
    u = (st.q[d[:3]] - asm.q_ref[d[:3]]) / P
    if direction == "radial":
        assert -u[1] == pytest.approx(np.pi / 4, rel=1e-3)
        assert u[0] == pytest.approx(0.5, rel=1e-3)
    else:
        assert u[0] == pytest.approx(3 * np.pi / 4 - 2, rel=1e-3)
        assert abs(u[1]) == pytest.approx(0.5, rel=1e-3)

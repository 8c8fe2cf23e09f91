"""Declared element layouts: the numbering reads them, unknown elements list the known ones."""

from __future__ import annotations

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.assembly import Assembly
from flexmbs.elements.layout import ELEMENT_TYPES, get_layout


def test_cable_layout_declares_its_sizes():
    lay = get_layout("ancf_cable")
    assert lay.node_size == 6 and lay.element_size == 12
    assert list(lay.centerline) == list(range(12))   # [r0, r0', r1, r1'] in element order
    assert "ancf_cable" in ELEMENT_TYPES


def test_unknown_element_lists_the_known_ones():
    with pytest.raises(fm.ModelError, match=r"unknown element 'hexa' \(known: .*ancf_cable"):
        get_layout("hexa")


def test_numbering_follows_the_layout():
    model = fm.Model()
    beam = model.add_beam(fm.line((0, 0, 0), (1, 0, 0), elements=3),
                          section=fm.CircularSection(1e-3), material=fm.Material(E=1e9, rho=1e3))
    model.clamp(beam.first_node)
    asm = Assembly(model)
    lay = beam.layout
    assert asm.n_coords == lay.node_size * beam.n_nodes
    E = asm.element_dofs(beam)
    assert E.shape == (beam.n_elem, lay.element_size)
    node = beam.node(2)
    q = asm.q_ref[asm.node_dofs(node)]
    np.testing.assert_allclose(q[list(lay.position)], node.position)
    np.testing.assert_allclose(q[list(lay.slope)], node.tangent)


def test_one_hermite_basis_derivatives_by_finite_differences():
    """shape_functions, shape_xi and the third derivative all come from hermite_basis; check
    its ξ-derivatives against central differences and the partition of unity."""
    from flexmbs.elements.hermite import hermite_basis, shape_functions

    L, h = 0.37, 1e-6
    for xi in (-0.3, 0.0, 0.41, 1.0, 1.7):
        S, d, dd, d3 = (np.array(a) for a in hermite_basis(xi, L))
        Sp, dp, ddp, _ = (np.array(a) for a in hermite_basis(xi + h, L))
        Sm, dm, ddm, _ = (np.array(a) for a in hermite_basis(xi - h, L))
        np.testing.assert_allclose(d, (Sp - Sm) / (2 * h), atol=1e-8)
        np.testing.assert_allclose(dd, (dp - dm) / (2 * h), atol=1e-7)
        np.testing.assert_allclose(d3, (ddp - ddm) / (2 * h), atol=1e-6)
        assert abs(S[0] + S[2] - 1.0) < 1e-14
        Sx, dSx, ddSx = shape_functions(np.array([xi]), np.array([L]))
        np.testing.assert_allclose(Sx[0], S, rtol=1e-15)
        np.testing.assert_allclose(dSx[0], d / L, rtol=1e-14)
        np.testing.assert_allclose(ddSx[0], dd / L**2, rtol=1e-14)


def test_centerline_points_of_a_line_and_an_arc():
    from flexmbs.elements.hermite import centerline_points

    model = fm.Model()
    line = model.add_beam(fm.line((0, 0, 0), (2, 0, 0), elements=4),
                          section=fm.CircularSection(1e-3), material=fm.Material(E=1e9, rho=1e3))
    arc = model.add_beam(fm.arc(center=(0, 0, 0), radius=1.0, start=(1, 0, 0), angle=np.pi / 2,
                                elements=16),
                         section=fm.CircularSection(1e-3), material=fm.Material(E=1e9, rho=1e3))
    model.clamp(line.first_node)
    model.clamp(arc.first_node)
    asm = Assembly(model)
    e = np.array([0, 1, 3])
    xi = np.array([0.25, 0.5, 1.0])
    P = centerline_points(asm.q_ref, asm.element_dofs(line), line.centerline.lengths, e, xi)
    np.testing.assert_allclose(P[:, 0], 0.5 * (e + xi), atol=1e-15)
    e = np.arange(16)
    P = centerline_points(asm.q_ref, asm.element_dofs(arc), arc.centerline.lengths, e,
                          np.full(16, 0.5))
    assert np.abs(np.linalg.norm(P, axis=1) - 1.0).max() < 1e-6   # cubic Hermite on an arc


def test_the_assembler_reaches_the_element_through_its_registered_type():
    """A registered element type is what the assembler calls: a copy of the cable registered
    under another name numbers, loads and evaluates the same model identically."""
    from dataclasses import replace

    from flexmbs.elements.layout import get_element_type

    cable_type = get_element_type("ancf_cable")
    ELEMENT_TYPES.register("cable_copy", replace(
        cable_type, layout=replace(cable_type.layout, name="cable_copy")))
    try:
        results = []
        for name in ("ancf_cable", "cable_copy"):
            model = fm.Model(gravity=(0, 0, -9.81))
            beam = model.add_beam(fm.line((0, 0, 0), (1, 0, 0), elements=4),
                                  section=fm.CircularSection(1e-3),
                                  material=fm.Material(E=1e9, rho=1e3))
            beam.element = name
            model.clamp(beam.first_node)
            model.add_point_load((beam, 0.3), (0, 0, -0.1))
            asm = Assembly(model)
            assert asm.groups[0].element_type.layout.name == name
            n, m = asm.n_coords, asm.n_mult
            rq, rl = np.zeros(n), np.zeros(m)
            asm.evaluate(asm.q_ref + 1e-4, np.zeros(n), None, np.zeros(m), 0.0, rq, rl)
            results.append(rq)
        np.testing.assert_array_equal(results[0], results[1])
    finally:
        ELEMENT_TYPES.unregister("cable_copy")


def test_vtu_frames_write_the_output_fields_the_element_type_declares():
    """The frame builder asks the beam's element type for its fields: a registered type that
    adds a field (here the element's mean ξ, known in advance) gets it written per sample."""
    from dataclasses import replace

    from flexmbs.elements.layout import get_element_type
    from flexmbs.io.frames import build_frame
    from flexmbs.solvers.generalized_alpha import State

    cable_type = get_element_type("ancf_cable")

    def fields(q_e: np.ndarray, rest: object, options: object, xi: np.ndarray) -> dict:
        out = cable_type.output_fields(q_e, rest, options, xi)
        out["sample_xi"] = np.broadcast_to(xi, (q_e.shape[0], xi.size)).copy()
        return out

    layout = replace(cable_type.layout, name="cable_fields",
                     output_fields=(*cable_type.layout.output_fields, "sample_xi"))
    ELEMENT_TYPES.register("cable_fields", replace(cable_type, layout=layout,
                                                   output_fields=fields))
    try:
        model = fm.Model()
        beam = model.add_beam(fm.line((0, 0, 0), (1, 0, 0), elements=2),
                              section=fm.CircularSection(1e-3), material=fm.Material(E=1e9, rho=1e3))
        beam.element = "cable_fields"
        model.clamp(beam.first_node)
        asm = Assembly(model)
        n, m = asm.n_coords, asm.n_mult
        state = State(t=0.0, q=asm.q_ref.copy(), v=np.zeros(n), qdd=np.zeros(n), a=np.zeros(n),
                      lam=np.zeros(m))
        mesh = build_frame(asm, state, samples_per_element=4)
        xi = mesh.point_data["sample_xi"]
        arc = mesh.point_data["arc_length"]
        # sample k of element e sits at arc length (e + ξ) L_e, L_e = 0.5 (the element ends
        # are shared, so an end point may carry ξ = 0 of the next element or ξ = 1)
        frac = (arc / 0.5) % 1.0
        ok = np.isclose(xi, frac, atol=1e-12) | (np.isclose(xi, 1.0) & np.isclose(frac, 0.0))
        assert ok.all()
        np.testing.assert_allclose(mesh.point_data["axial_strain"], 0.0, atol=1e-12)
    finally:
        ELEMENT_TYPES.unregister("cable_fields")

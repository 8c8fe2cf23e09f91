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

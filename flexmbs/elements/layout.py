"""Declared layouts of beam elements: what an element module tells the rest of the package.

An element module declares its nodal coordinates (names, which of them are the centreline
position ``r`` and slope ``r′``), nodes per element and output fields in an
:class:`ElementLayout`, and registers it in :data:`ELEMENT_TYPES` under the name scenario files
use (``element = "ancf_cable"``). DOF numbering, constraints on nodes, output and probes read
the layout; kernels read sizes from array shapes. No element size is written outside its module.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..registry import Registry

__all__ = ["ElementLayout", "ElementType", "ELEMENT_TYPES", "get_layout", "get_element_type"]


@dataclass(frozen=True, kw_only=True)
class ElementLayout:
    name: str
    node_coordinates: tuple[str, ...]   #: names of the coordinates of one node, in order
    position: tuple[int, int, int]      #: nodal indices of the centreline point r
    slope: tuple[int, int, int]         #: nodal indices of the centreline slope r′
    nodes_per_element: int = 2
    #: nodal index of a twist angle about the tangent (torsion-capable elements), else None:
    #: a clamp fixes it, a nodal torque does work on it
    twist: int | None = None
    #: names of the element's own output fields (VTU point data beside the displacement and
    #: velocity every beam has), the keys :attr:`ElementType.output_fields` returns
    output_fields: tuple[str, ...] = ()
    #: which of them are 3-vectors (the others are scalars)
    vector_fields: tuple[str, ...] = ()

    @property
    def node_size(self) -> int:
        return len(self.node_coordinates)

    @property
    def element_size(self) -> int:
        return self.node_size * self.nodes_per_element

    @property
    def centerline(self) -> np.ndarray:
        """Element-coordinate indices of the Hermite centreline ``[r0, r0′, r1, r1′]`` (what the
        sliding and clearance joints read), in that order."""
        out = []
        for k in range(self.nodes_per_element):
            out += [k * self.node_size + i for i in (*self.position, *self.slope)]
        return np.array(out, dtype=np.int64)


@dataclass(frozen=True, kw_only=True)
class ElementType:
    """An element module as the assembler sees it: its layout and its functions (all batched
    over the elements of a group of beams sharing the element type and options)."""

    layout: ElementLayout
    #: beams -> section properties per element (concatenated in beam order)
    section_properties: Callable[[list[Any]], Any]
    #: (points, tangents) of a reference centreline -> nodal coordinates (n_nodes, node size)
    reference_nodal_coordinates: Callable[[np.ndarray, np.ndarray], np.ndarray]
    #: (properties, g) -> generalized gravity forces (n_elem, element size)
    gravity_force: Callable[[Any, np.ndarray], np.ndarray]
    #: (properties, force per length) -> generalized forces (n_elem, element size)
    distributed_force: Callable[[Any, np.ndarray], np.ndarray]
    #: (xi, lengths, forces) -> generalized forces of point forces (n, element size)
    point_force: Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]
    #: (element dofs, properties, options, q_ref, matrix positions) -> the packed part
    pack: Callable[..., Any]
    #: (q_e, properties, rest data, options) -> strain energy per element
    strain_energy: Callable[..., np.ndarray]
    #: (q_e, rest data, options, xi) -> output fields at the sample points ξ of every element,
    #: by name: (n_elem, m) scalars or (n_elem, m, 3) vectors (VTU point data, e.g. the
    #: cable's ``axial_strain`` and ``curvature``)
    output_fields: Callable[..., dict[str, np.ndarray]]
    #: the named tuple ``pack`` returns, and its compiled kernels (:mod:`flexmbs.elements.group`):
    #: ``residual(part, q, v, qdd, mode, r) -> force scale`` adds ``Q_int + M q̈``,
    #: ``jacobian(part, q, v, qdd, mode, cM, cC, cK, data) -> stiffness scale`` the matrix block
    part_type: type
    residual: Callable[..., float]
    jacobian: Callable[..., float]
    #: the options of a group when none are given (the empty group of the default element
    #: type that every system holds, see :meth:`flexmbs.assembly.Assembly`)
    default_options: Any = None
    #: fields of the packed rest data shared by all elements of a group (quadrature points):
    #: not sliced when a beam's share of its group is taken
    shared_rest_fields: tuple[str, ...] = ()
    #: (element dofs of a beam, q_ref, node index) -> the node's base (t̄, D̄) of its twist
    #: (elements with a twist angle): what a joint holding the node's section needs
    node_base: Callable[[np.ndarray, np.ndarray, int], tuple[np.ndarray, np.ndarray]] | None = None
    #: optional compiled check after a converged step, ``post_step(part, q, error) -> code``
    #: (0, or an error code with ``error[2]`` = 2 × element + node slot), and the message of
    #: its code: ``(beam, node index, q) -> str``
    post_step: Callable[..., int] | None = None
    post_step_message: Callable[[Any, int, np.ndarray], str] | None = None
    #: elements whose nodal frames change charts (the rod, docs/theory.md §I.2.4): compiled
    #: ``rebase(part, q, v, qdd, acc, log, count) -> count`` after a converged step (appends a
    #: record ``[twist coordinate, t̄ (3), D̄ (3)]`` per re-based node to ``log``),
    #: ``set_bases(part, log, start, stop)`` takes such records (a resumed run), ``bases(part)``
    #: lists every node's current one
    rebase: Callable[..., int] | None = None
    set_bases: Callable[..., int] | None = None
    bases: Callable[[Any], np.ndarray] | None = None
    #: ``(part, q, v) -> kinetic energy`` of elements whose inertia is not the constant mass
    #: alone (the rod's spinning sections); default ``½ q̇ᵀ M q̇``
    kinetic_energy: Callable[[Any, np.ndarray, np.ndarray], float] | None = None


#: columns of a re-basing record (:attr:`ElementType.rebase`): the node's twist coordinate, its
#: new base t̄ (3) and D̄ (3)
BASE_RECORD = 7

#: element types by scenario name
ELEMENT_TYPES: Registry[ElementType] = Registry("element")


def get_element_type(name: str) -> ElementType:
    """A registered element type (an unknown name lists the known ones)."""
    return ELEMENT_TYPES.get(name)


def get_layout(name: str) -> ElementLayout:
    """The layout of a registered element (an unknown name lists the known ones)."""
    return ELEMENT_TYPES.get(name).layout

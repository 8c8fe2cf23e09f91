"""Numbering of a model's coordinates: beams (per node the coordinates of its element layout),
rigid bodies ``[r, p]`` (7 each), then the interactions' extra coordinates; the configuration
and velocity they start from; the groups of beams that share one kernel call."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from ..elements import rigid_body as rb
from ..errors import ModelError
from ..model import Beam, Model, Node, RigidBody

if TYPE_CHECKING:  # pragma: no cover
    from ..elements.layout import ElementType
    from ..terms import DofMap


class GroupSpec(NamedTuple):
    """Beams sharing an element type and its options: one packed part, one kernel call."""

    element_type: ElementType
    options: Any
    beams: list[Beam]
    dofs: np.ndarray         # (n_elem, element size) coordinates of every element of the group
    props: Any               # the element's section properties per element


class Numbering:
    """The global coordinate numbering of a :class:`~flexmbs.model.Model` (the numbering part
    of a :class:`~flexmbs.terms.DofMap`) and the reference configuration ``q_ref``."""

    def __init__(self, model: Model) -> None:
        off = 0
        self.beam_offset: dict[int, int] = {}
        labels: list[tuple[str, str]] = []
        for beam in model.beams:
            self.beam_offset[id(beam)] = off
            comp = beam.layout.node_coordinates
            for i in range(beam.n_nodes):
                labels.extend((f"beam '{beam.name}' node {i}", c) for c in comp)
            off += len(comp) * beam.n_nodes
        self.body_offset: dict[int, int] = {}
        for body in model.bodies:
            self.body_offset[id(body)] = off
            labels.extend((f"body '{body.name}'", c) for c in ("x", "y", "z", "e0", "e1", "e2", "e3"))
            off += 7
        self._extra_dofs: dict[int, np.ndarray] = {}
        for obj in model.interactions:
            names = obj.extra_labels()
            self._extra_dofs[id(obj)] = np.arange(off, off + len(names), dtype=np.int64)
            labels.extend((f"joint '{obj.name}'", c) for c in names)
            off += len(names)
        self.n_coords = off
        if off == 0:
            raise ModelError("the model is empty: add a beam (add_beam) or a rigid body "
                             "(add_rigid_body) before solving")
        self._coord_labels = labels
        q0 = np.zeros(off)
        v0 = np.zeros(off)
        for beam in model.beams:
            o = self.beam_offset[id(beam)]
            nodal = beam.element_type.reference_nodal_coordinates(beam.centerline.points,
                                                                  beam.centerline.tangents)
            q0[o:o + nodal.size] = nodal.ravel()
        for body in model.bodies:
            o = self.body_offset[id(body)]
            p = body.pose.quaternion
            q0[o:o + 3] = body.pose.position
            q0[o + 3:o + 7] = p
            v0[o:o + 3] = body.velocity
            v0[o + 3:o + 7] = rb.pdot_from_omega_global(p, body.angular_velocity)
        self.q_ref = q0
        self.v_init = v0
        # beams that start away from their stress-free shape; the elements' stress-free
        # coordinates: q_ref but where a beam's stress_free says
        self.prestressed = [beam for beam in model.beams if beam.stress_free is not None]
        self.q_free = self.rest_coordinates(1.0)
        self._interactions = list(model.interactions)
        self.groups, self.beam_slices = self._group_beams(model)

    def rest_coordinates(self, fraction: float) -> np.ndarray:
        """The elements' stress-free coordinates part of the way from the starting shapes
        (``fraction`` 0: ``q_ref``) to the beams' ``stress_free`` shapes (1: ``q_free``): the
        nodes moved on straight lines, their tangents turned on great circles (a path for
        statics to follow, :meth:`~flexmbs.assembly.Assembly.relax_towards_stress_free`)."""
        q = self.q_ref.copy()
        f = float(fraction)
        for beam in self.prestressed:
            a, b = beam.centerline, beam.stress_free
            assert b is not None
            t0 = np.asarray(a.tangents, float)
            t1 = np.asarray(b.tangents, float)
            t0 = t0 / np.linalg.norm(t0, axis=1)[:, None]
            t1 = t1 / np.linalg.norm(t1, axis=1)[:, None]
            theta = np.arccos(np.clip(np.einsum("ij,ij->i", t0, t1), -1.0, 1.0))
            worst = int(np.argmax(theta))
            if f < 1.0 and theta[worst] > math.radians(179.0):
                raise ModelError(
                    f"beam '{beam.name}': node {worst}'s stress-free tangent turns "
                    f"{math.degrees(theta[worst]):.1f} deg from its starting one, too far for "
                    "the static path from the starting shape; start the beam nearer its "
                    "stress_free shape")
            sin = np.sin(theta)
            small = sin < 1e-9
            wa = np.where(small, 1.0 - f, np.sin((1.0 - f) * theta) / np.where(small, 1.0, sin))
            wb = np.where(small, f, np.sin(f * theta) / np.where(small, 1.0, sin))
            tangents = wa[:, None] * t0 + wb[:, None] * t1
            points = (1.0 - f) * np.asarray(a.points, float) + f * np.asarray(b.points, float)
            nodal = beam.element_type.reference_nodal_coordinates(points, tangents)
            o = self.beam_offset[id(beam)]
            q[o:o + nodal.size] = nodal.ravel()
        return q

    def bind_interactions(self, dofs: DofMap) -> None:
        """Tell every interaction its numbering (:meth:`Interaction.bind`, through the
        assembler's ``dofs``) and set its extra coordinates' entries of ``q_ref``."""
        for obj in self._interactions:
            d = self._extra_dofs[id(obj)]
            obj.bind(dofs, d)
            self.q_ref[d] = obj.initial_extra(self.q_ref)

    def _group_beams(self, model: Model) -> tuple[list[GroupSpec], dict[int, tuple[int, slice]]]:
        """The groups of beams sharing an element type and its options, and every beam's
        (group, slice of the group's elements)."""
        groups: dict[tuple[str, Any], list[Beam]] = {}
        for beam in model.beams:
            groups.setdefault((beam.element, beam.options), []).append(beam)
        out = []
        slices: dict[int, tuple[int, slice]] = {}
        for gi, ((_, opts), beams) in enumerate(groups.items()):
            etype = beams[0].element_type
            start = 0
            for beam in beams:
                slices[id(beam)] = (gi, slice(start, start + beam.n_elem))
                start += beam.n_elem
            dofs = np.vstack([self.element_dofs(beam) for beam in beams])
            out.append(GroupSpec(etype, opts, beams, np.ascontiguousarray(dofs, dtype=np.int64),
                                 etype.section_properties(beams)))
        return out, slices

    def node_dofs(self, node: Node) -> np.ndarray:
        k = node.beam.layout.node_size
        o = self.beam_offset[id(node.beam)] + k * node.index
        return np.arange(o, o + k)

    def body_dofs(self, body: RigidBody) -> np.ndarray:
        o = self.body_offset[id(body)]
        return np.arange(o, o + 7)

    def beam_dofs(self, beam: Beam) -> np.ndarray:
        o = self.beam_offset[id(beam)]
        return np.arange(o, o + beam.layout.node_size * beam.n_nodes)

    def element_dofs(self, beam: Beam) -> np.ndarray:
        o = self.beam_offset[id(beam)]
        conn = beam.connectivity
        lay = beam.layout
        k = lay.node_size
        return (o + k * conn[:, :, None] + np.arange(k)[None, None, :]).reshape(-1, lay.element_size)

    def extra_dofs(self, owner: object) -> np.ndarray:
        return self._extra_dofs[id(owner)]

    def coordinate_label(self, i: int) -> str:
        """What coordinate ``i`` is: its beam node, body or joint and component."""
        obj, c = self._coord_labels[i]
        return f"{obj}, coordinate {c}"


def length_scale(model: Model) -> float:
    """The size of the model's reference configuration (extent of beams and bodies, at least
    its longest beam): the scale of geometric tolerances."""
    pts = [b.centerline.points for b in model.beams] + [
        b.pose.position[None, :] for b in model.bodies]
    if not pts:
        return 1.0
    P = np.vstack(pts)
    ext = float(np.linalg.norm(P.max(axis=0) - P.min(axis=0)))
    lengths = [b.length for b in model.beams]
    return max(ext, max(lengths, default=0.0), 1e-3 if ext == 0 else 0.0) or 1.0

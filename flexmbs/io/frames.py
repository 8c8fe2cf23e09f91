"""Output frames of a model, in two forms (``output_frames``, docs/cli.md "Output folder"):

- ``"multiblock"`` (default, :meth:`FrameBuilder.multiblock`): a
  :class:`~flexmbs.io.vtu.MultiBlock` (one ``.vtm`` per frame, a ``.vtp`` PolyData piece per
  block) with named blocks, so that ParaView's block selector and *Extract Block* show the
  model's parts::

      beams/<beam name>      one poly line per beam (point data below, ``radius`` included)
      bodies/<body name>     body surface (triangles)
      contacts               contact points (vertices): gap, normal_force, normal,
                             tangential_force, stick, joint_id, section, point_index
      springs                spring-dampers (lines; rotational ones a vertex)
      hole_sections          bore outlines of the clearance joints' sections (closed poly
                             lines; cell data joint_id, section)

  A group is present in every frame when the model has such parts (``contacts`` when it has a
  joint that reports contacts, ``hole_sections`` when it has clearance joints), also when it
  is empty at that time (no active contact: a piece with no points), so the block tree is the
  same for the whole series; a model without springs has no ``springs`` block. The names
  replace the merged form's ``block_id``/``beam_id``/``body_id`` (not written: every array
  costs time in every frame); every piece carries the field data ``time``.
- ``"merged"`` (:meth:`FrameBuilder.__call__`): one :class:`~flexmbs.io.vtu.VTUMesh` per state
  holding every block in a single grid (one ``.vtu`` per frame; meshio reads a frame as one
  mesh). Blocks are told apart by integer cell data (no strings, so every reader handles
  them):

==============  =========================================================================
cell data       meaning
==============  =========================================================================
``block_id``    0 = beam centreline segment (VTK_LINE), 1 = rigid-body surface triangle
                (VTK_TRIANGLE), 2 = contact point (VTK_VERTEX), 3 = spring-damper
                (translational: VTK_LINE between its ends; rotational: VTK_VERTEX at the
                joint point), 4 = bore outline of a clearance joint's hole section (closed,
                as VTK_LINE segments; the multiblock's ``hole_sections``)
``beam_id``     index of the beam in ``model.beams`` (-1 on other blocks)
``body_id``     index of the body in ``model.bodies`` (-1 on other blocks)
``spring_id``   index of the spring in ``model.springs`` (-1 on other blocks)
``joint_id``    index of the joint in ``model.interactions`` (bore outlines; -1 elsewhere)
``section``     index of the hole section in its joint (bore outlines; -1 elsewhere)
==============  =========================================================================

The names behind ``beam_id``/``body_id``/``spring_id`` are listed in ``summary.json`` (``vtu_blocks``).
Point data: ``displacement``, ``velocity`` (beams, bodies; zero on contact points),
``arc_length`` (reference arc length from the first node), ``axial_strain``, ``curvature``
(the curvature vector K = r'×r''/(|r'|² μ) of the cable), ``curvature_magnitude`` (beams),
``gap``, ``normal_force``, ``normal``, ``tangential_force`` (the friction force on the hole,
3-vector), ``stick`` (1 while friction sticks, else 0) (contact points; the multiblock's
``contacts`` also ``joint_id``, index in ``summary.json["vtu_blocks"]["joint_id"]``, and
``section``, ``point_index``: contacts.csv's ``section``, ``point``).
Arrays that do not apply to a block hold NaN there (-1 for integers).
Spring cells carry ``spring_force`` (N, or N m for a rotational spring; tension
positive, damping included) and ``spring_extension`` (length − rest length, or angle − rest
angle, rad). Field data: ``time`` and ``TimeValue`` (the name ParaView/VTK recognise).

Beams are finely sampled polylines: ``samples_per_element`` points per element at ξ = k/n,
positions exact on the cubic Hermite centreline; in the merged grid stored as VTK_LINE segments
(meshio cannot read VTK_POLY_LINE; in ParaView *Extract Surface* then *Tube*), in the multiblock
as one VTK_POLY_LINE per beam in a PolyData piece (ParaView's *Tube* applies directly; "Vary
Radius: By Absolute Scalar" on ``radius`` draws the true section). Body surfaces come from
:mod:`flexmbs.io.surfaces`.
"""

from __future__ import annotations

import copy
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..elements import hermite
from ..elements import rigid_body as rb
from ..errors import ModelError
from ..springs import ANGLE, SpringPart, spring_forces, spring_points
from ..terms import dynamic_mode
from .surfaces import body_surface
from .vtu import VTK_LINE, VTK_POLY_LINE, VTK_TRIANGLE, VTK_VERTEX, MultiBlock, VTUMesh

if TYPE_CHECKING:
    from ..assembly import Assembly
    from ..solvers.generalized_alpha import State

__all__ = ["BLOCK_BEAM", "BLOCK_BODY", "BLOCK_CONTACT", "BLOCK_NAMES", "BLOCK_OUTLINE", "BLOCK_SPRING",
           "OUTPUT_FRAMES", "FrameBuilder", "build_frame", "contact_location"]

BLOCK_BEAM = 0
BLOCK_BODY = 1
BLOCK_CONTACT = 2
BLOCK_SPRING = 3
BLOCK_OUTLINE = 4
BLOCK_NAMES = {BLOCK_BEAM: "beam", BLOCK_BODY: "rigid_body", BLOCK_CONTACT: "contact",
               BLOCK_SPRING: "spring", BLOCK_OUTLINE: "hole_section"}
#: the forms of an output frame (scenario key ``simulation.output_frames``, ``--output-frames``)
OUTPUT_FRAMES = ("multiblock", "merged")
#: contact arrays of the multiblock only (the merged grid would pad them over every point)
_MULTIBLOCK_ONLY = ("joint_id", "section", "point_index")
#: cell data of the merged grid that the multiblock's names replace
_MERGED_IDS = ("block_id", "beam_id", "body_id")
#: points on each bore outline of the ``hole_sections`` block
OUTLINE_SAMPLES = 48


def _constant(a: np.ndarray) -> np.ndarray:
    """``a`` (owning its data) made read-only: the same in every frame, so the VTK writer
    encodes it once (:func:`flexmbs.io.vtu._data_array`)."""
    a = np.array(a) if a.base is not None else a
    a.setflags(write=False)
    return a


def _cross(w: np.ndarray, arm: np.ndarray) -> np.ndarray:
    """``np.cross(w, arm)`` of a 3-vector and rows (n, 3): the same operations, without its
    generic overhead (a body's point velocities in every frame)."""
    out = np.empty(arm.shape)
    out[:, 0] = w[1] * arm[:, 2] - w[2] * arm[:, 1]
    out[:, 1] = w[2] * arm[:, 0] - w[0] * arm[:, 2]
    out[:, 2] = w[0] * arm[:, 1] - w[1] * arm[:, 0]
    return out


@dataclass
class _BeamSampler:
    index: int
    dofs: np.ndarray        # (n_s, 12) element coordinates of each sample
    S: np.ndarray           # (n_s, 4) Hermite shape functions at the samples
    ref: np.ndarray         # (n_s, 3) reference positions
    arc: np.ndarray         # (n_s,) reference arc length
    flat: np.ndarray        # (n_s,) index into the (n_elem, spe+1) strain/curvature table
    segments: np.ndarray    # (n_seg, 2)
    group: int
    slc: slice
    xi: np.ndarray          # (spe+1,)


class FrameBuilder:
    """Builds :class:`VTUMesh` frames of one assembly; body surfaces are prepared once."""

    def __init__(self, asm: Assembly, *, samples_per_element: int = 8) -> None:
        if int(samples_per_element) < 1:
            raise ModelError(f"samples_per_element must be >= 1 (got {samples_per_element})")
        self.asm = asm
        self.spe = spe = int(samples_per_element)
        model = asm.model
        self.beams: list[_BeamSampler] = []
        xi_tab = np.arange(spe + 1) / spe
        for bi, beam in enumerate(model.beams):
            ne = beam.n_elem
            e = np.repeat(np.arange(ne), spe)
            k = np.tile(np.arange(spe), ne)
            if not beam.closed:
                e = np.append(e, ne - 1)
                k = np.append(k, spe)
            ns = e.size
            L = np.asarray(beam.centerline.lengths, float)
            S, dofs = hermite.centerline_interpolation(asm.centerline_dofs(beam), L, e, xi_tab[k])
            ref = hermite.interpolate(S, dofs, asm.q_ref)
            cum = np.concatenate([[0.0], np.cumsum(L)])
            seg = np.column_stack([np.arange(ns - 1), np.arange(1, ns)])
            if beam.closed:
                seg = np.vstack([seg, [ns - 1, 0]])
            gi, sl = asm.beam_slices[id(beam)]
            self.beams.append(_BeamSampler(bi, dofs, S, ref, _constant(cum[e] + xi_tab[k] * L[e]),
                                           e * (spe + 1) + k, seg.astype(np.int64), gi, sl, xi_tab))
        # per-frame constants: sliced reference data, element dofs, radius and cell arrays
        self._field_names = [grp.element_type.layout.output_fields for grp in asm.groups]
        self._beam_const = []
        for b in self.beams:
            beam = model.beams[b.index]
            nseg = b.segments.shape[0]
            self._beam_const.append((
                asm.beam_rest(beam), asm.element_dofs(beam),
                _constant(np.full(b.S.shape[0], np.nan if beam.radius is None
                                  else float(beam.radius))),
                {"block_id": np.full(nseg, BLOCK_BEAM, np.int32),
                 "beam_id": np.full(nseg, b.index, np.int32),
                 "body_id": np.full(nseg, -1, np.int32)}))
        self._polyline = [_constant(np.append(np.arange(b.S.shape[0]),
                                              [0] if model.beams[b.index].closed else []
                                              ).astype(np.int64)) for b in self.beams]
        #: interactions that report contact points / bore outlines (blocks of the multiblock)
        from ..driver import kind_of  # the records declare the output hooks

        kinds = [kind_of(j) for j in model.interactions]
        self._contact_sources = [j for j, k in zip(model.interactions, kinds, strict=True)
                                 if k is not None and k.contacts is not None]
        self._outline_sources = [(i, j, k.outlines) for i, (j, k)
                                 in enumerate(zip(model.interactions, kinds, strict=True))
                                 if k is not None and k.outlines is not None]
        self._joint_ids = {str(getattr(j, "name", i)): i for i, j in enumerate(model.interactions)}
        self._outline_cells: tuple[list[np.ndarray], np.ndarray, np.ndarray] | None = None
        self._outline_segments: tuple[np.ndarray, dict[str, np.ndarray]] | None = None
        self._springs: SpringPart | None = None    # springs_now's copy
        self.bodies = []
        for bi, body in enumerate(model.bodies):
            pts, tri = body_surface(body)
            tri = _constant(np.array(tri, np.int64))
            d = asm.body_dofs(body)
            q0 = asm.q_ref[d]
            ref = q0[:3] + pts @ rb.rotation_matrix(q0[3:]).T
            self.bodies.append((bi, d, pts, tri, ref))

    def _beam_point_data(self, b: _BeamSampler, q: np.ndarray, v: np.ndarray
                         ) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        x = hermite.interpolate(b.S, b.dofs, q)
        vel = hermite.interpolate(b.S, b.dofs, v)
        (etype, rest, options), elem_dofs, radius, _ = self._beam_const[b.index]
        point_data = {"displacement": x - b.ref, "velocity": vel, "arc_length": b.arc}
        fields = etype.output_fields(q[elem_dofs], rest, options, b.xi)
        for name in self._field_names[b.group]:
            values = fields[name]
            n_elem, m = values.shape[:2]
            point_data[name] = values.reshape((n_elem * m, *values.shape[2:]))[b.flat]
        if "curvature" in point_data:
            point_data["curvature_magnitude"] = np.linalg.norm(point_data["curvature"], axis=1)
        # section radius (for tubes: ParaView Tube "vary radius by absolute scalar")
        point_data["radius"] = radius
        return x, point_data

    def beam_mesh(self, b: _BeamSampler, q: np.ndarray, v: np.ndarray) -> VTUMesh:
        """Beam ``b`` as VTK_LINE segments (the merged grid)."""
        x, point_data = self._beam_point_data(b, q, v)
        return VTUMesh(x, [(VTK_LINE, b.segments)], point_data=point_data,
                       cell_data=self._beam_const[b.index][3])

    def beam_polyline(self, b: _BeamSampler, q: np.ndarray, v: np.ndarray) -> VTUMesh:
        """Beam ``b`` as one VTK_POLY_LINE (closed beams end on their first point)."""
        x, point_data = self._beam_point_data(b, q, v)
        return VTUMesh(x, [(VTK_POLY_LINE, [self._polyline[b.index]])], point_data=point_data,
                       cell_data={})

    def body_mesh(self, i: int, q: np.ndarray, v: np.ndarray) -> VTUMesh:
        bi, d, pts, tri, ref = self.bodies[i]
        r, p = q[d[:3]], q[d[3:]]
        arm = pts @ rb.rotation_matrix(p).T
        w = rb.angular_velocity_global(p, v[d[3:]])
        x = r + arm
        nt = tri.shape[0]
        return VTUMesh(
            x, [(VTK_TRIANGLE, tri)],
            point_data={"displacement": x - ref, "velocity": v[d[:3]] + _cross(w, arm)},
            cell_data={"block_id": np.full(nt, BLOCK_BODY, np.int32),
                       "beam_id": np.full(nt, -1, np.int32),
                       "body_id": np.full(nt, bi, np.int32)})

    def contact_mesh(self, contacts: Sequence[dict]) -> VTUMesh:
        """Contact points as vertices (rows of :meth:`output` of the joints; missing values
        NaN, or -1 for the integer arrays)."""
        n = len(contacts)
        nan3 = (np.nan,) * 3

        def vec(key: str) -> np.ndarray:
            return np.array([np.asarray(c.get(key, nan3), float) for c in contacts],
                            float).reshape(n, 3)

        def num(key: str) -> np.ndarray:
            return np.array([float(c[key]) if c.get(key) is not None else np.nan
                             for c in contacts], float).reshape(n)

        def ids(key: str) -> np.ndarray:    # an integer index (``point`` may be a position)
            return np.array([int(c[key]) if c.get(key) is not None and np.ndim(c[key]) == 0
                             else -1 for c in contacts], np.int32).reshape(n)

        pts = np.array([contact_location(c) for c in contacts], float).reshape(n, 3)
        joint = np.array([self._joint_ids.get(str(c.get("joint")), -1) for c in contacts],
                         np.int32).reshape(n)
        return VTUMesh(
            pts, [(VTK_VERTEX, np.arange(n, dtype=np.int64)[:, None])],
            point_data={"gap": num("gap"), "normal_force": num("normal_force"),
                        "normal": vec("normal"), "tangential_force": vec("tangential_force"),
                        "stick": num("stick"), "joint_id": joint, "section": ids("section"),
                        "point_index": ids("point")},
            cell_data={"block_id": np.full(n, BLOCK_CONTACT, np.int32),
                       "beam_id": np.full(n, -1, np.int32),
                       "body_id": np.full(n, -1, np.int32)})

    def outline_mesh(self, q: np.ndarray) -> VTUMesh:
        """The bore outlines of the clearance joints' sections: one closed poly line each,
        cell data ``joint_id``, ``section``. The cells and their data are the same in every
        frame (built at the first)."""
        rings = [outlines(j, q, OUTLINE_SAMPLES) for _, j, outlines in self._outline_sources]
        if self._outline_cells is None:
            rings_ji: list[np.ndarray] = []
            joints: list[int] = []
            sections: list[int] = []
            start = 0
            for (ji, _, _), jr in zip(self._outline_sources, rings, strict=True):
                for k, ring in enumerate(jr):
                    m = ring.shape[0]
                    rings_ji.append(_constant(np.append(np.arange(start, start + m),
                                                        start).astype(np.int64)))
                    joints.append(ji)
                    sections.append(k)
                    start += m
            self._outline_cells = (rings_ji, _constant(np.array(joints, np.int32)),
                                   _constant(np.array(sections, np.int32)))
        lines, joint, section = self._outline_cells
        pts = [ring for jr in rings for ring in jr]
        return VTUMesh(np.vstack(pts) if pts else np.zeros((0, 3)), [(VTK_POLY_LINE, lines)],
                       cell_data={"joint_id": joint, "section": section})

    def outline_segments(self, q: np.ndarray) -> VTUMesh:
        """The bore outlines of :meth:`outline_mesh` as VTK_LINE segments (the merged grid:
        meshio reads no VTK_POLY_LINE), cell data ``block_id`` = :data:`BLOCK_OUTLINE`,
        ``joint_id``, ``section``; cells and cell data built at the first frame."""
        rings = self.outline_mesh(q)
        if self._outline_segments is None:
            closed = rings.cells[0][1]
            segs = [np.column_stack([ring[:-1], ring[1:]]) for ring in closed]
            counts = np.array([s.shape[0] for s in segs], np.int64)
            n = int(counts.sum())
            self._outline_segments = (
                _constant(np.vstack(segs).astype(np.int64) if segs
                          else np.zeros((0, 2), np.int64)),
                {"block_id": _constant(np.full(n, BLOCK_OUTLINE, np.int32)),
                 "beam_id": _constant(np.full(n, -1, np.int32)),
                 "body_id": _constant(np.full(n, -1, np.int32)),
                 "joint_id": _constant(np.repeat(rings.cell_data["joint_id"], counts)),
                 "section": _constant(np.repeat(rings.cell_data["section"], counts))})
        segments, cell_data = self._outline_segments
        return VTUMesh(rings.points, [(VTK_LINE, segments)], cell_data=dict(cell_data))

    def springs_now(self) -> SpringPart | None:
        """The springs as a frame of the present state reads them, their mutable part (the
        rotational springs' turns, ``theta_ref``) copied: what :meth:`spring_mesh` needs of
        the live model when the frame is built later (in the output's writer thread). Its work
        arrays are a copy of the solver's, shared by the frames (built by one thread)."""
        if not self.asm.model.springs:
            return None
        sp = self.asm.system.springs
        if self._springs is None:   # work arrays of its own: the solver's are in use meanwhile
            self._springs = copy.deepcopy(sp)
        return self._springs._replace(theta_ref=sp.theta_ref.copy())

    def spring_mesh(self, q: np.ndarray, v: np.ndarray, springs: SpringPart | None = None
                    ) -> VTUMesh:
        """Translational springs as lines between their ends, rotational ones as a vertex at
        the joint point (their cells in that order); ``springs``: a :meth:`springs_now`
        (default the model's, live)."""
        sp = self.asm.system.springs if springs is None else springs
        x = spring_points(sp, q)
        fo = spring_forces(sp, q, v, dynamic_mode())
        rot = np.flatnonzero(sp.measure == ANGLE)
        lin = np.flatnonzero(sp.measure != ANGLE)
        order = np.concatenate([lin, rot])
        n = order.size
        cells: list[tuple[int, np.ndarray | list[np.ndarray]]] = []
        if lin.size:
            cells.append((VTK_LINE, np.column_stack([2 * lin, 2 * lin + 1]).astype(np.int64)))
        if rot.size:
            cells.append((VTK_VERTEX, (2 * rot)[:, None].astype(np.int64)))
        return VTUMesh(
            x.reshape(-1, 3), cells,
            cell_data={"block_id": np.full(n, BLOCK_SPRING, np.int32),
                       "beam_id": np.full(n, -1, np.int32), "body_id": np.full(n, -1, np.int32),
                       "spring_id": order.astype(np.int32), "spring_force": fo[order, 1],
                       "spring_extension": fo[order, 0] - sp.l0[order]})

    def block_tree(self) -> list[dict]:
        """The pieces of :meth:`multiblock` frames (``summary.json["vtm_blocks"]``): their path
        in the ``.vtm`` (``beams/rail``), kind and, for beams, the section radius (None for a
        beam given by stiffnesses). A ``contacts`` block that only a caller's records create
        (no joint of the model reports contacts) is not listed."""
        model = self.asm.model
        out: list[dict] = [{"path": f"beams/{b.name}", "kind": "beam", "name": b.name,
                            "radius": None if b.radius is None else float(b.radius)}
                           for b in model.beams]
        out += [{"path": f"bodies/{b.name}", "kind": "body", "name": b.name} for b in model.bodies]
        if self._contact_sources:
            out.append({"path": "contacts", "kind": "contacts"})
        if model.springs:
            out.append({"path": "springs", "kind": "springs"})
        if self._outline_sources:
            out.append({"path": "hole_sections", "kind": "hole_sections"})
        return out

    def multiblock(self, state: State, *, contacts: Sequence[dict] | None = None,
                   springs: SpringPart | None = None) -> MultiBlock:
        """One output frame as named blocks (module docstring). Reads nothing of the live
        model but the springs' turns, which ``springs`` (:meth:`springs_now`) may give."""
        q = np.asarray(state.q)
        v = np.asarray(state.v)
        model = self.asm.model
        t = np.array([float(state.t)])
        blocks: list[tuple[str, VTUMesh | MultiBlock]] = []
        if self.beams:
            blocks.append(("beams", MultiBlock([(model.beams[b.index].name,
                                                 self.beam_polyline(b, q, v))
                                                for b in self.beams])))
        if self.bodies:
            blocks.append(("bodies", MultiBlock([(model.bodies[self.bodies[i][0]].name,
                                                  self.body_mesh(i, q, v))
                                                 for i in range(len(self.bodies))])))
        if self._contact_sources or contacts:
            blocks.append(("contacts", self.contact_mesh(list(contacts or []))))
        if model.springs:
            blocks.append(("springs", self.spring_mesh(q, v, springs)))
        if self._outline_sources:
            blocks.append(("hole_sections", self.outline_mesh(q)))
        frame = MultiBlock(blocks)
        for _, mesh in frame.leaves():
            mesh.field_data = {"time": t}
            for k in _MERGED_IDS:
                mesh.cell_data.pop(k, None)
        return frame

    def __call__(self, state: State, *, contacts: Sequence[dict] | None = None,
                 springs: SpringPart | None = None) -> VTUMesh:
        """One output frame as a single merged grid (module docstring); ``springs`` as for
        :meth:`multiblock`."""
        q = np.asarray(state.q)
        v = np.asarray(state.v)
        parts = [self.beam_mesh(b, q, v) for b in self.beams]
        parts += [self.body_mesh(i, q, v) for i in range(len(self.bodies))]
        if contacts:
            part = self.contact_mesh(contacts)
            for k in _MULTIBLOCK_ONLY:      # padded over every point of the grid: left out
                part.point_data.pop(k)
            parts.append(part)
        if self.asm.model.springs:
            parts.append(self.spring_mesh(q, v, springs))
        if self._outline_sources:
            parts.append(self.outline_segments(q))
        mesh = VTUMesh.merge(parts)
        t = np.array([float(state.t)])
        mesh.field_data = {"time": t, "TimeValue": t.copy()}
        return mesh


def contact_location(c: dict) -> np.ndarray:
    """Where a contact is drawn: ``position`` (3), else ``point`` when it is a 3-vector, else
    the hole point ``(qx, qy, qz)`` of the contacts.csv record."""
    if "position" in c:
        return np.asarray(c["position"], float).reshape(3)
    if "point" in c and np.size(c["point"]) == 3:
        return np.asarray(c["point"], float).reshape(3)
    try:
        return np.array([c["qx"], c["qy"], c["qz"]], float)
    except KeyError:
        raise ModelError("a contact record needs 'position' (3), 'point' (3) or qx, qy, qz "
                         f"for output (got keys {sorted(c)})") from None


def build_frame(asm: Assembly, state: State, *, samples_per_element: int = 8,
                contacts: Sequence[dict] | None = None) -> VTUMesh:
    """One output frame of ``asm`` in ``state`` (see the module docstring for the arrays)."""
    return FrameBuilder(asm, samples_per_element=samples_per_element)(state, contacts=contacts)

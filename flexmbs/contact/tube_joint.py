"""A beam inside a flexible tube with clearance: the clearance joint whose bore is the lumen of
another beam (docs/theory.md §II.9).

The tube's sections sit at material stations of the outer beam and move with it
(:mod:`flexmbs.contact.tube`); everything else is the clearance joint's: the consistent
detection of each section, the penalty laws, stick friction, the exact tangent (taken to the
tube's coordinates through the sections' poses), contact tracking and checkpoints. The forces
act equal and opposite on both beams.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..constraints.interaction import ModelParts
from ..elements.ancf_rod import new_turn_work, nodal_bases
from ..elements.rigid_body import quaternion_from_matrix, rotation_matrix
from ..errors import ModelError
from .bores import Hole, refit_section_tree
from .geometry import section_state
from .joint import DetectionFrame, SlidingClearanceJoint, hole_frame
from .laws import ForceLaw, Friction, RegularizedCoulomb
from .sections import CircleSection, HoleSection, section_contains
from .tube import (
    POSE_SIZE,
    POSE_WORK,
    SECTION_COORDS,
    TURN_SIZE,
    TubeSections,
    quaternion_after,
    section_order,
    section_turn,
    tube_pose,
)

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Beam
    from ..terms import DofMap

__all__ = ["TubeJoint", "TubeBore"]


@dataclass(frozen=True)
class TubeBore(Hole):
    """The lumen of a flexible tube: ``section`` at ``sections`` stations along the outer
    beam's reference arc length from ``start`` over ``length`` (both ends included)."""

    start: float = 0.0

    def stations(self) -> np.ndarray:
        """Reference arc lengths of the sections along the outer beam."""
        if self.sections == 1:
            return np.full(1, self.start + 0.5 * self.length)
        return self.start + np.linspace(0.0, self.length, int(self.sections))

    def frames(self) -> tuple[np.ndarray, np.ndarray]:
        """Each section is its own body (its pose follows the tube): origin 0, axes I."""
        n = int(self.sections)
        return np.zeros((n, 3)), np.repeat(np.eye(3)[None], n, axis=0)

    def record(self) -> dict[str, Any]:
        return {**super().record(), "start": float(self.start)}


class TubeJoint(SlidingClearanceJoint):
    """Beam ``inner`` inside the lumen of beam ``outer``, with clearance.

    The lumen's sections are placed along the outer beam every ``spacing`` (or ``sections``
    of them), from ``start`` to ``end`` (reference arc lengths; default: the whole beam),
    and move with it: each section's plane stays normal to the tube's centreline, its centre
    on it. In each section the inner beam's contact with the wall is that of
    :class:`~flexmbs.contact.joint.SlidingClearanceJoint` (consistent detection, contact law,
    friction, exact tangent), its force acting on the inner beam and, equal and opposite, on
    the tube's element at the section.

    Parameters
    ----------
    inner : Beam
        The beam inside (a wire, a guide wire, the inner tube).
    outer : Beam
        The tube (a cable or a rod).
    inner_radius : float, optional
        The lumen's radius [m] (a circular lumen); or give ``lumen``.
    lumen : HoleSection, optional
        The lumen's section (any compiled hole shape). On a rod tube it turns with the rod: its
        y axis is the rod's director ``d2`` at the section. A cable has no twist to turn it:
        there the lumen must be round.
    spacing : float, optional
        Distance between sections along the tube [m]; or give ``sections``.
    sections : int, optional
        Number of sections, both ends of the lumen included.
    start, end : float, optional
        The lumen's extent along the outer beam (reference arc length) [m]; default the
        whole beam.
    open_ends : bool, default True
        The inner beam may enter and leave the lumen (else it must cross every section).
    contact, friction, friction_velocity, beam_radius, tangent, name
        As for :class:`~flexmbs.contact.joint.SlidingClearanceJoint`.
    """

    def __init__(self, inner: Beam, outer: Beam, *, inner_radius: float | None = None,
                 lumen: HoleSection | None = None, spacing: float | None = None,
                 sections: int | None = None, start: float = 0.0, end: float | None = None,
                 open_ends: bool = True, contact: ForceLaw | None = None,
                 friction: Friction | RegularizedCoulomb | float | None = None,
                 friction_velocity: float | None = None, beam_radius: float | None = None,
                 tangent: str = "exact", name: str | None = None) -> None:
        name = name or f"tube_{inner.name}_in_{outer.name}"
        if inner is outer:
            raise ModelError(f"joint '{name}': beam '{inner.name}' cannot run inside itself; "
                             "give the tube as another beam")
        if (inner_radius is None) == (lumen is None):
            raise ModelError(f"joint '{name}': give the lumen as inner_radius = <radius> or "
                             "lumen = <hole section>, one of them")
        section = lumen if inner_radius is None else CircleSection(float(inner_radius))
        if not isinstance(section, CircleSection) and outer.layout.twist is None:
            raise ModelError(f"joint '{name}': lumen: a {type(section).__name__} lumen must turn "
                             f"with the tube, but tube '{outer.name}' is a "
                             f"{outer.layout.name} without twist; give inner_radius (a round "
                             "lumen) or make the tube a rod (element = \"ancf_rod14\")")
        lo = outer.check_arc_length(float(start))
        hi = outer.length if end is None else outer.check_arc_length(float(end))
        if not hi > lo:
            raise ModelError(f"joint '{name}': the lumen must run forward along the tube "
                             f"(start {lo:g} m, end {hi:g} m)")
        if (spacing is None) == (sections is None):
            raise ModelError(f"joint '{name}': give spacing = <distance> or sections = <count>, "
                             "one of them")
        r_b = beam_radius if beam_radius is not None else inner.radius
        if spacing is not None:
            if not spacing > 0:
                raise ModelError(f"joint '{name}': spacing must be > 0 (got {spacing!r})")
            if r_b is not None and spacing < r_b:
                raise ModelError(
                    f"joint '{name}': spacing {spacing:g} m is finer than the inner beam's "
                    f"radius {r_b:g} m, below what the section detection resolves (each "
                    "section sees the contact of its own stretch of wire); use spacing >= "
                    f"{r_b:g}")
            sections = max(2, int(math.ceil((hi - lo) / spacing - 1e-9)) + 1)
        self.outer = outer
        super().__init__(inner, None, hole=TubeBore(section, hi - lo, int(sections), open_ends,  # type: ignore[arg-type]
                                                    start=lo),
                         contact=contact, friction=friction, friction_velocity=friction_velocity,
                         beam_radius=beam_radius, tangent=tangent, name=name)
        ns = len(self.stations)
        at = [outer.locate(float(s)) for s in self.stations]
        self._tube_elem = np.array([e for e, _ in at], np.int64)
        self._tube_xi = np.array([xi for _, xi in at], float)
        self._order = section_order(outer.layout)
        self._work = np.zeros(POSE_WORK)
        self._turn_work = new_turn_work()
        self._turn = np.zeros(TURN_SIZE)
        # the sections' base frames: the tube's reference frames there (x along the tangent),
        # on a rod turned about it onto the rod's director (and the rod's nodal bases)
        self._tube_tbar = np.zeros((ns, 3))
        self._tube_p0 = np.zeros((ns, 4))
        self._node_t = np.zeros((ns, 2, 3))
        self._node_d = np.zeros((ns, 2, 3))
        for k, s in enumerate(self.stations):
            t = outer.frame_at(float(s)).rotation[:, 0]
            self._tube_tbar[k] = t
            self._tube_p0[k] = quaternion_from_matrix(hole_frame(t))
        if outer.layout.twist is not None:
            self._align_to_director(self._reference_coordinates())

    @property
    def _width(self) -> int:
        """The section coordinates of the tube's elements (:func:`~flexmbs.contact.tube.section_order`)."""
        return int(self._order.size)

    def _reference_coordinates(self) -> np.ndarray:
        """The tube's element coordinates (n_elem, element size) in its stress-free reference."""
        outer = self.outer
        return np.ascontiguousarray(outer.element_type.reference_nodal_coordinates(
            outer.centerline.points, outer.centerline.tangents)[outer.connectivity].reshape(
                outer.n_elem, -1), dtype=float)

    def _align_to_director(self, q_elements: np.ndarray) -> None:
        """A rod tube: its elements' nodal bases, as the rod's packing takes them, and each
        section's base frame turned about its tangent onto the rod's director at the station
        in the reference (ψ = 0 there: :func:`~flexmbs.contact.tube.section_turn`)."""
        outer = self.outer
        size = q_elements.shape[1]
        nodes = np.asarray(outer.connectivity, np.int64)
        node_size = outer.layout.node_size
        dofs = (nodes[:, :, None] * node_size + np.arange(node_size)).reshape(outer.n_elem, size)
        q_ref = np.zeros(int(nodes.max() + 1) * node_size)
        q_ref[dofs] = q_elements
        t_bar, d_bar = nodal_bases(dofs, q_ref)
        self._node_t[:] = t_bar[self._tube_elem]
        self._node_d[:] = d_bar[self._tube_elem]
        turned = np.zeros(4)
        for k in range(len(self.stations)):
            e = self._tube_elem[k]
            psi = section_turn(np.ascontiguousarray(q_elements[e, self._order]), self._width,
                               float(outer.centerline.lengths[e]), float(self._tube_xi[k]),
                               self._tube_tbar[k], self._tube_p0[k], self._node_t[k],
                               self._node_d[k], self._turn_work, self._turn, False)
            half = np.r_[np.cos(0.5 * psi), np.sin(0.5 * psi) * self._tube_tbar[k]]
            quaternion_after(half, self._tube_p0[k], turned)
            self._tube_p0[k] = turned / np.linalg.norm(turned)

    # ------------------------------------------------------------------ set-up
    def validate(self, model: ModelParts) -> None:
        for beam, what in ((self.beam, "inner"), (self.outer, "outer")):
            if beam not in model.beams:
                raise ModelError(f"joint '{self.name}': the {what} beam '{beam.name}' is not "
                                 "part of the model")
        qo = np.ascontiguousarray(self._reference_coordinates()[:, self._order])
        self._check_tube_start(qo, self._reference_elements(), warn=True)

    def bind(self, dofs: DofMap, extra_dofs: np.ndarray) -> None:
        self._outer_dofs = np.ascontiguousarray(dofs.element_dofs(self.outer)[:, self._order],
                                                dtype=np.int64)
        self._section_dofs = self._outer_dofs[self._tube_elem]
        self._outer_lengths = np.array(self.outer.centerline.lengths, dtype=float)
        # the coordinates the pattern and the plan give the joint (the hole body's elsewhere):
        # every element that carries a section; its first 7 stand in for the body's
        self._own = np.unique(self._section_dofs)
        body = self._section_dofs[0, :POSE_SIZE]
        self.body = _SectionsOf(self.outer)  # type: ignore[assignment]  # the tube stands in
        dofs_with_body = _WithBody(dofs, body)
        super().bind(dofs_with_body, extra_dofs)    # type: ignore[arg-type]

    def initial_extra(self, q0: np.ndarray) -> np.ndarray:
        self._check_tube_start(np.ascontiguousarray(q0[self._outer_dofs]),
                               np.ascontiguousarray(q0[self.geometry.elem_dofs]), warn=False)
        return np.zeros(0)

    def own_dofs(self) -> np.ndarray:
        return np.asarray(self._own, np.int64)

    def window_owns(self) -> list[np.ndarray]:
        """Every tube element that carries a section, a row of the plan's windows of its own:
        an element couples only with the inner beam near its own sections, so the plan holds
        each against the inner beam's elements there (:func:`~flexmbs.contact.clearance_term.
        window_row`), not the whole tube against the whole wire."""
        elements = np.unique(self._tube_elem)
        return [self._outer_dofs[e] for e in elements]

    def tube_sections(self) -> tuple[np.ndarray, ...]:
        ns = self.n_slots
        n = len(self.stations)
        dofs = np.zeros((ns, self._width), np.int64)
        dofs[:n] = self._section_dofs
        dofs[n:] = self._section_dofs[0]           # tip slots: unused
        length = np.ones(ns)
        length[:n] = self._outer_lengths[self._tube_elem]
        xi = np.zeros(ns)
        xi[:n] = self._tube_xi
        t_bar = np.zeros((ns, 3))
        t_bar[:n] = self._tube_tbar
        t_bar[n:] = self._tube_tbar[0]
        p0 = np.zeros((ns, 4))
        p0[:n] = self._tube_p0
        p0[n:] = self._tube_p0[0]
        row = np.zeros(ns, np.int64)         # tip slots: set where they are placed
        row[:n] = np.searchsorted(np.unique(self._tube_elem), self._tube_elem)
        node_t, node_d = np.zeros((ns, 2, 3)), np.zeros((ns, 2, 3))
        node_t[:n], node_d[:n] = self._node_t, self._node_d
        return dofs, length, xi, t_bar, p0, row, node_t, node_d

    def packed_tube(self, tube: TubeSections, i: int) -> None:
        n = len(self.stations)
        self._tube_tbar = tube.t_bar[i, :n]
        self._tube_p0 = tube.p0[i, :n]
        self._node_t = tube.node_t[i, :n]
        self._node_d = tube.node_d[i, :n]
        self._packed = (tube, i)

    def _slot(self, k: int) -> tuple[np.ndarray, float, float, np.ndarray, np.ndarray,
                                      np.ndarray, np.ndarray]:
        """Section slot k's tube element (section coordinates), its length, the station on it,
        the base and the rod's nodal bases: a bore section's, or a tip section's as the compiled
        step placed it (``clearance_term.tube_tip_slots``)."""
        n = len(self.stations)
        if k < n:
            return (self._section_dofs[k], float(self._outer_lengths[self._tube_elem[k]]),
                    float(self._tube_xi[k]), self._tube_tbar[k], self._tube_p0[k],
                    self._node_t[k], self._node_d[k])
        tube, i = self._packed
        return (tube.dofs[i, k, :self._width], float(tube.length[i, k]), float(tube.xi[i, k]),
                tube.t_bar[i, k], tube.p0[i, k], tube.node_t[i, k], tube.node_d[i, k])

    def _pose_of(self, e: np.ndarray, ve: np.ndarray | None, length: float, xi: float,
                 t_bar: np.ndarray, p0: np.ndarray, node_t: np.ndarray, node_d: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray]:
        """A section's pose and rate from its element's section coordinates ``e`` (rates
        ``ve``; None: at rest), by the compiled :func:`~flexmbs.contact.tube.tube_pose`."""
        pose, rate = np.zeros(POSE_SIZE), np.zeros(POSE_SIZE)
        e = np.ascontiguousarray(e, dtype=float)
        ve = np.zeros_like(e) if ve is None else np.ascontiguousarray(ve, dtype=float)
        tube_pose(e, self._width, length, xi, t_bar, p0, node_t, node_d, self._turn_work,
                  self._turn, ve, pose, rate, np.zeros((POSE_SIZE, SECTION_COORDS)), self._work)
        return pose, rate

    # ------------------------------------------------------------------ the sections
    def section_poses(self, q: np.ndarray, v: np.ndarray | None = None, *, tips: bool = False
                      ) -> tuple[np.ndarray, np.ndarray]:
        """Poses ``[r, p]`` (n, 7) of the tube's sections at ``q`` and their rates (``v``);
        ``tips``: all the slots, the placed tip sections' too (n + N_TIPS; zeros where none)."""
        n = self.n_slots if tips else len(self.stations)
        poses, rates = np.zeros((n, POSE_SIZE)), np.zeros((n, POSE_SIZE))
        for k in range(n):
            if k >= len(self.stations) and not self.state.tip_on[k - len(self.stations)]:
                continue
            d, length, xi, t_bar, p0, node_t, node_d = self._slot(k)
            poses[k], rates[k] = self._pose_of(q[d], None if v is None else v[d], length, xi,
                                               t_bar, p0, node_t, node_d)
        return poses, rates

    def _world_sections(self, poses: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Origins (n, 3) and axes (n, 3, 3) (columns: normal, e_y, e_z) of the sections."""
        return poses[:, :3].copy(), np.array([rotation_matrix(p[3:7]) for p in poses])

    def _planes_at(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        origins, axes = self._world_sections(self.section_poses(q)[0])
        return np.eye(3), origins, axes

    def _detection_frame(self, q: np.ndarray) -> DetectionFrame:
        n = len(self.stations)
        origins, axes = self._world_sections(self.section_poses(q, tips=True)[0])
        on = np.r_[np.ones(n, bool), self.state.tip_on]
        self.state.origins[on], self.state.axes[on] = origins[on], axes[on]
        origins = origins[:n]
        tree = tuple(np.array(a, copy=True) for a in self.geometry.tree)
        refit_section_tree(origins, 2.0 * self.hole.section.bounding_radius() + self.beam_radius,
                           *tree)
        return np.zeros(3), np.eye(3), self.state.origins, self.state.axes, tree

    def _contact_pose(self, q: np.ndarray, v: np.ndarray, k: int
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        d, length, xi, t_bar, p0, node_t, node_d = self._slot(k)
        pose, rate = self._pose_of(q[d], v[d], length, xi, t_bar, p0, node_t, node_d)
        return pose, rate, rotation_matrix(pose[3:7])

    def _history(self, q: np.ndarray, k: int, psi: float, eP: int) -> np.ndarray:
        hist = super()._history(q, k, psi, eP)
        start = self.state.q_start if self.state.q_start is not None else q
        hist[4:4 + POSE_SIZE] = self._contact_pose(start, np.zeros_like(start), k)[0]
        return hist

    def _check_tube_start(self, qo: np.ndarray, qe: np.ndarray, *, warn: bool) -> None:
        """The inner beam must cross the lumen's sections inside it wherever it crosses them
        near the tube's axis, and every section unless ``open_ends``; sets the sections'
        tracking start."""
        n = len(self.stations)
        poses = np.zeros((n, POSE_SIZE))
        for k in range(n):
            e = self._tube_elem[k]
            poses[k] = self._pose_of(qo[e], None, float(self.outer.centerline.lengths[e]),
                                     float(self._tube_xi[k]), self._tube_tbar[k],
                                     self._tube_p0[k], self._node_t[k], self._node_d[k])[0]
        origins, axes = self._world_sections(poses)
        lengths = np.array(self.beam.centerline.lengths, dtype=float)
        section = self.hole.section
        R_out, R_in = section.bounding_radius(), section.inscribed_radius()
        compiled = section.compiled_shape()
        assert compiled is not None
        self.state.elem[:] = -1
        self.state.xi[:] = 0.5
        self.state.ws_list[0] = -1
        for k in range(n):
            found, e, xi, cy, cz, a, _b, _, _ = section_state(
                qe, lengths, origins[k], axes[k][:, 0], axes[k][:, 1], axes[k][:, 2], 0, 0.5,
                self.beam_radius, 2.0 * R_out + self.beam_radius)
            inside = found and section_contains(compiled[0], compiled[1], cy, cz)
            if found and not inside and not (self.hole.open_ends and k in (0, n - 1)):
                raise ModelError(
                    f"joint '{self.name}': beam '{self.beam.name}' crosses the lumen of "
                    f"'{self.outer.name}' outside its wall at section {k} (arc length "
                    f"{self.stations[k]:.6g} m along the tube); start the inner beam inside the "
                    "tube")
            if not found or not inside:
                if not self.hole.open_ends:
                    raise ModelError(
                        f"joint '{self.name}': beam '{self.beam.name}' does not pass through "
                        f"the lumen of '{self.outer.name}' at section {k}; give open_ends = "
                        "true or start the inner beam through the whole tube")
                continue
            if a > R_in * (1 + 1e-12):
                raise ModelError(
                    f"joint '{self.name}': the inner beam is tilted too much to fit the lumen "
                    f"at section {k} (ellipse semi-axis {a:.6g} > lumen {R_in:.6g}: jamming)")
            self.state.elem[k], self.state.xi[k] = e, xi

    # ------------------------------------------------------------------ refused features
    def place_tips(self, qb: np.ndarray, qe: np.ndarray) -> None:
        """A tube's tip sections are placed by the compiled step at its start
        (``clearance_term.place_due_tips``, ``tube_tip_slots``), which needs the tube's
        coordinates too; the Python path (``tangent = "frozen_point"``) has none."""
        self.state.tip_on[:] = False

    def freeze_detection(self, q: np.ndarray | None, v: np.ndarray | None = None) -> None:
        if q is not None:
            raise ModelError(f"joint '{self.name}': a flexible tube's contacts cannot be frozen")
        self._frozen = None

    def rest_on_beam(self, direction: Any) -> float:
        raise ModelError(f"joint '{self.name}': a tube does not rest on its inner beam by moving; "
                         "place the beams")

    def compiled_form(self) -> bool:
        return self.tangent != "frozen_point"

    # ------------------------------------------------------------------ state and records
    def get_state(self) -> dict[str, Any]:
        state = super().get_state()
        state["tube_bases"] = np.concatenate([self._tube_tbar, self._tube_p0], axis=1).tolist()
        return state

    def set_state(self, state: dict[str, Any]) -> None:
        super().set_state(state)
        bases = np.asarray(state.get("tube_bases", []), float)
        if bases.shape == (len(self.stations), 7):
            self._tube_tbar[:] = bases[:, :3]
            self._tube_p0[:] = bases[:, 3:]

    def hole_record(self) -> dict[str, Any]:
        return {**super().hole_record(), "tube": self.outer.name}

    def __repr__(self) -> str:
        return (f"TubeJoint({self.name!r}, inner={self.beam.name!r}, outer={self.outer.name!r}, "
                f"lumen={self.hole.section!r}, sections={len(self.stations)}, law={self.contact!r})")


class _SectionsOf:
    """Stands in for the hole body in the clearance joint's records: the tube's name."""

    def __init__(self, outer: Beam) -> None:
        self.name = outer.name


class _WithBody:
    """A numbering whose ``body_dofs`` answers the tube's stand-in coordinates."""

    def __init__(self, dofs: DofMap, body: np.ndarray) -> None:
        self._dofs = dofs
        self._body = body

    def body_dofs(self, body: object) -> np.ndarray:
        return self._body

    def __getattr__(self, name: str) -> Any:
        return getattr(self._dofs, name)

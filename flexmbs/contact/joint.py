"""Sliding joint WITH clearance: a flexible beam inside a rigid hole (Tang & Liu).

Per hole cross-section k (docs/theory.md §II.8): the section plane at station zeta_k cuts the
beam centreline at r_I (safeguarded Newton across elements, warm-started); the beam's section
there is an ellipse (a = r_b / cos(theta), b = r_b); the common-normal condition gives every
stationary point of the penetration (circle: quartic, superellipse: bracketed Newton); for each
penetrating candidate the hole point Q is projected onto the centreline (P), the gap is
g = |Q - P| - r_b and the penalty law gives the normal force. Forces of local maxima count +1,
of local minima -1 (continuous section force when one contact splits into two, §3).
Detection is redone at every Newton iteration ("fully nonlinear", §5 option 1); warm starts and
the approach velocities of the damped laws are updated after each converged step.
"""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from ..codes import SHAPE_CODES
from ..constraints.interaction import (
    EnergyFlow,
    Following,
    Interaction,
    InteractionKind,
    MatrixSink,
    ModelParts,
)
from ..elements.ancf_rod import new_turn_work
from ..elements.centerline import element_tree, element_tree_size
from ..elements.hermite import CENTERLINE_SIZE
from ..elements.rigid_body import rotation_matrix
from ..errors import ConvergenceError, FlexmbsError, FlexmbsWarning, ModelError
from ..terms import pad_stack
from ._detect import (
    ANCHOR_COL,
    CROSSING_COL,
    DETECT_INT_WORK,
    DETECT_WORK,
    FADE_COL,
    FORCE_COL,
    GAP_COL,
    GEOMETRY_COL,
    MAX_CANDIDATES,
    MAX_CROSSINGS,
    N_COLS,
    N_TIPS,
    _section_plane,
    detect_section,
    end_fade,
    place_tips,
)
from .bores import CircleHole, CurvedBore, Hole, SuperellipseHole, section_tree
from .clearance_term import (
    CONTACTS_PER_SECTION,
    ERR_CONTACT_OFF_PLAN,
    ERR_LEFT_BORE,
    ERR_TOO_MANY_CONTACTS,
    FORCES_WORK,
    TUBE_WORK,
    ClearancePart,
    clearance_update,
    contact_capacity,
    contact_history,
    element_spin,
    tracked_approach,
    tracked_slot,
)
from .geometry import closest_point, section_state
from .laws import (
    N_FRICTION,
    N_LAW,
    ForceLaw,
    Friction,
    LinearPenalty,
    RegularizedCoulomb,
    as_friction,
    check_resumed_friction,
    law_dissipates,
    law_energy,
    mouth_radius,
)
from .pair import (
    N_HISTORY,
    N_LOCAL,
    N_SPIN,
    N_TWIST,
    ContactResult,
    contact_point,
    friction_vector,
    xi_bounds,
)
from .sections import Ellipse2D, section_contains
from .tangent import N_EXT
from .tube import SECTION_COORDS, TubeSections

__all__ = ["SlidingClearanceJoint", "Hole", "CircleHole", "SuperellipseHole", "CurvedBore",
           "CLEARANCE", "MAX_POINTS", "TANGENTS", "DETECTIONS", "hole_frame"]

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Beam, RigidBody
    from ..terms import DofMap, PackContext


#: contact points tracked per section (a circle has at most 4; a superellipse's extra ones
#: beyond this count are treated as first contacts at every step by the dissipative laws)
MAX_POINTS = 8
#: contact tangents of the clearance joint (see :class:`SlidingClearanceJoint`)
TANGENTS = ("exact", "gauss_newton", "frozen_point")
#: contact detections of the clearance joint (see :class:`SlidingClearanceJoint`)
DETECTIONS = ("consistent", "paper")

#: What a joint's detection takes at a state: the hole body's position and rotation, the
#: sections' origins and axes in its coordinates and their bounding-sphere tree.
DetectionFrame = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, tuple[np.ndarray, ...]]


class ClearanceGeometry(NamedTuple):
    """Where a clearance joint's coordinates are and what of its bore stays fixed, built when
    the joint is bound (:meth:`SlidingClearanceJoint.bind`); read by the joint and by its pack
    (:func:`pack_clearance`), which stacks the records of all clearance joints."""

    body_dofs: np.ndarray     # (7,) the hole body's coordinates
    elem_dofs: np.ndarray     # (n_elem, CENTERLINE_SIZE) every element's centreline coordinates
    twist_dofs: np.ndarray    # (n_elem, N_TWIST) the twists of its nodes (−1: a cable)
    beam_dofs: np.ndarray     # every coordinate of the beam (the pattern)
    lengths: np.ndarray       # (n_elem,) element lengths
    stations: np.ndarray      # (slots,) the sections' stations along the bore (tip slots 0)
    tree: tuple[np.ndarray, ...]  # the sections' bounding-sphere tree (bores.section_tree)
    tip_reach: float          # the longest gap between sections (_detect.place_tips)


class ContactRecord(NamedTuple):
    """What an output records of one contact point (the fields of
    :class:`~flexmbs.contact.pair.ContactResult` it reads), as the compiled residual found it
    (:meth:`SlidingClearanceJoint.keep_records`; global vectors)."""

    gap: float
    normal: np.ndarray
    P: np.ndarray
    Q: np.ndarray
    f_n: float
    force_on_hole: np.ndarray
    xi: float
    gap_rate: float
    anchor: np.ndarray
    stuck: float
    fade: float = 1.0


def _faded(res: ContactResult, fade: float) -> ContactResult:
    """A contact's result with its force and tangent weighted by ``fade``
    (:func:`~flexmbs.contact._detect.end_fade`, the Python paths' use of it; their tangent is
    then Gauss–Newton in the weight too)."""
    if fade >= 1.0:
        return res
    return res._replace(f_n=fade * res.f_n, force_on_hole=fade * res.force_on_hole,
                        Q_body=fade * res.Q_body, Q_elem=fade * res.Q_elem,
                        Q_twist=fade * res.Q_twist, K=fade * res.K, C=fade * res.C, fade=fade)


def _row_contact(row: np.ndarray, res: Any) -> tuple:
    """A penetrating candidate row of the compiled detection (:data:`_detect.COLS`) with its
    contact result as :meth:`SlidingClearanceJoint._contacts` lists it: (section, index, kind,
    element, result, a, b, psi)."""
    return (int(row[0]), int(row[1]), int(row[2]), int(row[3]), res, float(row[8]),
            float(row[9]), float(row[11]))


class ClearanceState(NamedTuple):
    """What a clearance joint carries from step to step, per section slot (the bore's
    sections, then the :data:`~flexmbs.contact._detect.N_TIPS` tip sections): built by the
    joint, then views of its packed part's arrays (:func:`pack_clearance`; the compiled steps
    update them in place), saved in checkpoints (:meth:`SlidingClearanceJoint.get_state`)."""

    origins: np.ndarray       # (slots, 3) section origins, body coordinates (tip rows move)
    axes: np.ndarray          # (slots, 3, 3) section axes (columns: normal, e_y, e_z)
    elem: np.ndarray          # (slots,) warm starts of the crossings (element; −1 not crossed)
    xi: np.ndarray            # (slots,)
    ws_list: np.ndarray       # (slots + 1,) the sections with a warm start ([count, k...],
                              #   _detect.reset_crossings; −1: not known, listed again)
    approach: np.ndarray      # (slots, MAX_POINTS) tracked contacts: approach velocity at
    psi: np.ndarray           #   onset, section angle of the hole point (docs/theory.md §II.3),
    active: np.ndarray        #   in use
    anchor: np.ndarray        # (slots, MAX_POINTS, 3) friction: elastic displacement (hole
    stuck: np.ndarray         #   frame), stuck
    tip_on: np.ndarray        # (N_TIPS,) tip section placed (_detect.place_tips), its station
    tip_station: np.ndarray   # (N_TIPS,)
    t_bar: np.ndarray         # (n_elem, N_TWIST, 3) the contact elements' chart bases
    q_start: np.ndarray | None  # (n,) the step's start (the packed part's array)

    @classmethod
    def views(cls, part: ClearancePart, i: int, slots: int, n_elem: int) -> ClearanceState:
        """Joint i's state as views of the packed part's arrays."""
        return cls(origins=part.origins[i, :slots], axes=part.frames[i, :slots],
                   elem=part.elem_ws[i, :slots], xi=part.xi_ws[i, :slots],
                   ws_list=part.ws_list[i], approach=part.approach[i, :slots],
                   psi=part.psi[i, :slots], active=part.active[i, :slots],
                   anchor=part.anchor[i, :slots], stuck=part.stuck[i, :slots],
                   tip_on=part.tip_on[i], tip_station=part.tip_station[i],
                   t_bar=part.t_bar[i, :n_elem], q_start=part.q_start)


def _unit_axis(axis: Any, what: str) -> np.ndarray:
    """``axis`` as a unit vector (3 finite numbers, not zero)."""
    try:
        a = np.asarray(axis, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        a = np.zeros(0)
    if a.shape != (3,) or not np.all(np.isfinite(a)) or not np.linalg.norm(a) > 0:
        shown = a.tolist() if a.size else axis
        raise ModelError(f"{what}: axis must be 3 finite numbers, not all zero (got {shown!r}); "
                         "give the hole's direction in body coordinates, e.g. [1, 0, 0]")
    return a / np.linalg.norm(a)


def hole_frame(axis: Any) -> np.ndarray:
    """The axes (columns: ``axis``, e_y, e_z; body coordinates) of a straight bore along the unit
    ``axis``: e_y is body y made normal to it (body z when the axis is within 26° of body y, the
    rule of :class:`CurvedBore`'s ``up``), e_z = axis × e_y. Body x gives the identity, so a
    section's e_y and e_z (a superellipse's ``a`` and ``b``) stay body y and z there."""
    a = np.asarray(axis, dtype=float)
    up = np.array([0.0, 1.0, 0.0]) if abs(a[1]) < 0.9 else np.array([0.0, 0.0, 1.0])
    ey = up - (up @ a) * a
    ey = ey / np.linalg.norm(ey)
    return np.column_stack([a, ey, np.cross(a, ey)])


class SlidingClearanceJoint(Interaction):
    """Beam through a rigid hole with clearance, penalty contact per hole section.

    ``hole``: :class:`Hole` (through ``hole_point`` along ``axis``, body coordinates, default
    body x: :func:`hole_frame` turns the bore's sections so that their normal is ``axis``);
    ``contact``: a normal force law (default linear penalty); ``friction``: optional
    :class:`~flexmbs.contact.laws.Friction` (or its coefficient: the stick law; with
    ``friction_velocity``, the regularised law); the stick law's default tangential stiffness is
    the normal law's stiffness at 1 % of the radial clearance (for the linear law: its
    stiffness); ``beam_radius`` defaults to the beam's section radius.
    ``tangent`` (the contact's part of Newton's matrix; none changes the converged solution):

    - ``"exact"`` (default): the exact derivative of the contact forces, with the hole point
      sliding along the bore as the detection moves it (:mod:`flexmbs.contact.tangent`):
      quadratic Newton, the right linearised modes. Compiled sections (circle, superellipse);
      a Python-defined section falls back to ``"gauss_newton"``;
    - ``"gauss_newton"``: ``k BᵀB`` (docs/theory.md §II.5), no stiffness along the bore wall;
    - ``"frozen_point"``: adds the geometric terms that are exact for a hole point frozen as a
      material point of the hole (Python path). The true geometric stiffness of a beam pressed
      into a concave bore is about +f_N/clearance, the frozen-point term about −f_N/r_b: for a
      pretensioned wire pressed into a grommet it makes the tangent indefinite.

    ``detection`` (where in a section the contact points are):

    - ``"consistent"`` (default for sections with a compiled boundary): stationary pairs of the
      section wall and the beam axis (docs/theory.md §II.4b, :mod:`flexmbs.contact.stationary`):
      the contact forces are the exact gradient of a potential at every crossing angle, so
      undamped motion keeps its energy and closed paths do no work;
    - ``"paper"``: the paper's 2-D common normal in the section plane, then the closest point of
      the axis (§3–§4; Tang & Liu). Not conservative once the beam crosses the section
      obliquely (closed-loop work 11 % of the path work at 44°–54°); kept to reproduce the
      paper.

    Parameters
    ----------
    beam : Beam
        The beam passing through the hole.
    body : RigidBody
        The body that carries the hole.
    hole : Hole
        The bore: :class:`CircleHole`, :class:`SuperellipseHole`, :class:`Hole` or
        :class:`CurvedBore`.
    contact : LinearPenalty, Hertz, HuntCrossley or LankaraniNikravesh, optional
        Normal force law (default: a linear penalty).
    friction : Friction, RegularizedCoulomb or float, optional
        Friction of the contacts; a number is a Coulomb coefficient (the stick law).
    friction_velocity : float, optional
        With a number ``friction``: the regularised law with this velocity scale [m/s].
    hole_point : array_like of 3 floats, default (0, 0, 0)
        The hole's centre in body coordinates [m].
    beam_radius : float, optional
        The beam's contact radius [m] (default: its section radius).
    tangent : {"exact", "gauss_newton", "frozen_point"}, default "exact"
        The contact's part of Newton's matrix (above).
    detection : {"consistent", "paper"}, optional
        Where in a section the contact points are (above).
    name : str, optional
        The joint's name (default: made from the beam's and body's names).
    axis : array_like of 3 floats, default (1, 0, 0)
        The bore's axis in body coordinates.
    """

    term_kind = "clearance"

    def __init__(self, beam: Beam, body: RigidBody, *, hole: Hole,
                 contact: ForceLaw | None = None,
                 friction: Friction | RegularizedCoulomb | float | None = None,
                 friction_velocity: float | None = None,
                 hole_point=(0.0, 0.0, 0.0), beam_radius: float | None = None,
                 tangent: str = "exact", detection: str | None = None,
                 name: str | None = None, axis: Any = (1.0, 0.0, 0.0)) -> None:
        self.beam = beam
        self.body = body
        self.hole = hole
        law = contact or LinearPenalty(stiffness=1e6)
        self.friction = as_friction(friction, friction_velocity)
        self.hole_point = np.asarray(hole_point, float).reshape(3)
        self.name = name or f"clearance_{body.name}"
        self.axis = _unit_axis(axis, f"joint '{self.name}'")
        if tangent not in TANGENTS:
            raise ModelError(f"joint '{self.name}': tangent must be one of {', '.join(TANGENTS)} "
                             f"(got {tangent!r})")
        self.tangent = tangent
        shape = hole.section.compiled_shape()
        if shape is None:
            raise ModelError(f"joint '{self.name}': {type(hole.section).__name__} has no compiled "
                             "boundary (compiled_shape() is None): a hole shape is a compiled "
                             "boundary kernel and its section class (docs/extending.md, "
                             "\"A hole shape\")")
        if int(shape[0]) not in SHAPE_CODES.values():
            raise ModelError(f"joint '{self.name}': {type(hole.section).__name__} has the "
                             f"compiled shape code {int(shape[0])}, which flexmbs.codes.SHAPE_CODES "
                             "does not list: add the shape there and to the dispatchers of "
                             "flexmbs.contact.shapes")
        if detection is None:
            detection = "consistent"
        if detection not in DETECTIONS:
            raise ModelError(f"joint '{self.name}': detection must be one of "
                             f"{', '.join(DETECTIONS)} (got {detection!r})")
        self.detection = detection
        r_b = beam_radius if beam_radius is not None else beam.radius
        if r_b is None or not r_b > 0:
            raise ModelError(f"joint '{self.name}': the beam radius is unknown; give the beam a "
                             "CircularSection or pass beam_radius=")
        self.beam_radius = float(r_b)
        if not hole.section.inscribed_radius() > self.beam_radius:
            raise ModelError(
                f"joint '{self.name}': the hole (inscribed radius "
                f"{hole.section.inscribed_radius():.6g}) is not larger than the beam (radius "
                f"{self.beam_radius:.6g}); the beam cannot pass")
        self.contact = law
        self.stations = hole.stations()
        ns = len(self.stations)
        # the sections in body coordinates: origins (ns, 3), axes (ns, 3, 3) (normal, e_y, e_z);
        # then the N_TIPS tip sections of an open bore (placed at each step's start where an
        # end of the beam lies inside the bore: _detect.place_tips); the per-section state
        # below has a slot for each
        origins, axes = hole.frames()
        if np.any(self.axis != (1.0, 0.0, 0.0)):      # the bore turned from body x to axis
            if isinstance(hole, CurvedBore):
                raise ModelError(f"joint '{self.name}': axis turns a straight bore; a bore "
                                 "along a path runs along its path (give the path in body "
                                 "coordinates and drop axis)")
            turn = hole_frame(self.axis)
            origins, axes = origins @ turn.T, np.einsum("ij,kjl->kil", turn, axes)
        slots = ns + N_TIPS
        sec_origins = np.zeros((slots, 3))
        sec_origins[:ns] = origins + self.hole_point
        sec_axes = np.repeat(np.eye(3)[None], slots, axis=0)
        sec_axes[:ns] = axes
        self._stations = np.zeros(slots)
        self._stations[:ns] = self.stations
        self._tip_reach = float(np.max(np.diff(self.stations))) if ns > 1 else 0.0
        # the state, updated after each converged step (by the compiled integrator in place)
        self.state = ClearanceState(
            origins=sec_origins, axes=sec_axes,
            elem=np.zeros(slots, np.int64), xi=np.full(slots, 0.5),
            ws_list=np.full(slots + 1, -1, np.int64),
            approach=np.zeros((slots, MAX_POINTS)), psi=np.zeros((slots, MAX_POINTS)),
            active=np.zeros((slots, MAX_POINTS), dtype=bool),
            anchor=np.zeros((slots, MAX_POINTS, 3)), stuck=np.zeros((slots, MAX_POINTS)),
            tip_on=np.zeros(N_TIPS, dtype=bool), tip_station=np.zeros(N_TIPS),
            t_bar=np.zeros((0, N_TWIST, 3)), q_start=None)
        self._frozen: list | None = None
        self._contact_cache: tuple | None = None
        self._records: tuple | None = None      # keep_records: (state key, contacts)
        # the sections' bounding-sphere tree (body coordinates; reach: a crossing that far from
        # a section's centre counts, _detect.detect_section) and the detection's work arrays;
        # the bore's geometry is known here, before the joint is bound (place_tips at validate)
        self._tree = section_tree(self.state.origins[:ns], 2.0 * hole.section.bounding_radius()
                                  + self.beam_radius)
        self._cross = (np.zeros(slots, np.int64), np.zeros((slots, MAX_CROSSINGS), np.int64),
                       np.zeros((slots, MAX_CROSSINGS)), np.zeros(slots, np.int64),
                       np.zeros(slots + DETECT_INT_WORK, np.int64), np.zeros(DETECT_WORK))
        self._rows = np.zeros((MAX_CANDIDATES * slots, N_COLS))  # stationary points per section
        self._elem_out = np.zeros(slots, np.int64)  # crossings of the last evaluation
        self._xi_out = np.zeros(slots)

    # ------------------------------------------------------------------ set-up
    def validate(self, model: ModelParts) -> None:
        if self.beam not in model.beams:
            raise ModelError(f"joint '{self.name}': the beam is not part of the model")
        if self.body not in model.bodies:
            raise ModelError(f"joint '{self.name}': the body is not part of the model")
        # the start in the reference configuration, when the model is built (not at run time)
        pose = self.body.pose
        qb = np.concatenate([np.asarray(pose.position, float), np.asarray(pose.quaternion, float)])
        self._check_start(qb, self._reference_elements(), warn=True)

    def _reference_elements(self) -> np.ndarray:
        """Centreline coordinates of every element of the beam in its reference configuration
        (the same nodal coordinates the assembly starts from)."""
        beam = self.beam
        cl = beam.centerline
        nodal = beam.element_type.reference_nodal_coordinates(cl.points, cl.tangents)
        qe = nodal[beam.connectivity].reshape(beam.n_elem, -1)[:, beam.layout.centerline]
        return np.ascontiguousarray(qe, dtype=float)

    def bind(self, dofs: DofMap, extra_dofs: np.ndarray) -> None:
        """Builds :attr:`geometry` (:class:`ClearanceGeometry`)."""
        lay = self.beam.layout
        ne = len(self.beam.centerline.lengths)
        self.geometry = ClearanceGeometry(
            body_dofs=dofs.body_dofs(self.body),
            # the Hermite centreline coordinates of every element (the element's declared layout)
            elem_dofs=dofs.element_dofs(self.beam)[:, lay.centerline],
            # the twists of every element's nodes (a rod's: its surface turns under the friction)
            twist_dofs=(np.full((ne, N_TWIST), -1, np.int64) if lay.twist is None else
                        np.ascontiguousarray(dofs.element_dofs(self.beam)[
                            :, [lay.twist, lay.node_size + lay.twist]], dtype=np.int64)),
            beam_dofs=dofs.beam_dofs(self.beam),
            # writable contiguous copies: kernels are compiled per array flavour (readonly, layout)
            lengths=np.array(self.beam.centerline.lengths, dtype=float),
            stations=self._stations, tree=self._tree, tip_reach=self._tip_reach)
        # the twists' charts' base tangents (set when packed, then re-based)
        self.state = self.state._replace(t_bar=np.zeros((ne, N_TWIST, 3)))

    def own_dofs(self) -> np.ndarray:
        """The coordinates the bore moves with (the hole body's)."""
        return np.asarray(self.geometry.body_dofs, np.int64)

    def window_owns(self) -> list[np.ndarray]:
        """The coordinates the bore moves with, by the rows of the plan's windows
        (:class:`~flexmbs.constraints.interaction.Following`): each couples with the beam
        (:func:`clearance_pattern`) and the plan holds it against the elements of its window
        only. A rigid bore: its body's, one row."""
        return [self.own_dofs()]

    def tube_sections(self) -> tuple[np.ndarray, ...] | None:
        """A flexible tube's sections (:class:`~flexmbs.contact.tube_joint.TubeJoint`); a rigid
        bore has none."""
        return None

    def packed_tube(self, tube: TubeSections, i: int) -> None:
        """A flexible tube keeps views of its packed sections' state (a rigid bore: nothing)."""

    def initial_extra(self, q0: np.ndarray) -> np.ndarray:
        g = self.geometry
        self._check_start(q0[g.body_dofs], np.ascontiguousarray(q0[g.elem_dofs]), warn=False)
        return np.zeros(0)

    def _planes(self, qb: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Body rotation A, the sections' origins (ns, 3) and axes (ns, 3, 3) (columns: plane
        normal, e_y, e_z), global, at the body coordinates ``qb`` (the bore's own sections,
        not the tip sections)."""
        A = rotation_matrix(qb[3:7])
        ns = len(self.stations)
        return A, qb[:3] + self.state.origins[:ns] @ A.T, A @ self.state.axes[:ns]

    def _planes_at(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`_planes` at the model's coordinates ``q``."""
        return self._planes(q[self.geometry.body_dofs])

    @property
    def contact(self) -> ForceLaw:
        """The normal force law; a damped :class:`LinearPenalty` without an onset is kept with
        its viscous force ramped in over :data:`~flexmbs.contact.laws.DAMPING_ONSET` of the
        radial clearance (:meth:`LinearPenalty.for_clearance`, docs/design-notes.md "The damped
        penalty in a curved bore (issue 53 item 2)")."""
        return self._contact

    @contact.setter
    def contact(self, law: ForceLaw) -> None:
        if isinstance(law, LinearPenalty):
            law = law.for_clearance(self.hole.section.inscribed_radius() - self.beam_radius)
        self._contact = law

    def energy_flow(self) -> EnergyFlow:
        """The wall's potential stores energy; damping and friction dissipate."""
        return "dissipates" if self.friction is not None or law_dissipates(self.contact) \
            else "conserves"

    @property
    def n_slots(self) -> int:
        """Section slots: the bore's sections, then the :data:`N_TIPS` tip sections."""
        return len(self.stations) + N_TIPS

    def place_tips(self, qb: np.ndarray, qe: np.ndarray) -> None:
        """The tip sections at the hole body's coordinates ``qb`` and the beam's centreline
        ``qe`` (:func:`~flexmbs.contact._detect.place_tips`): an open bore with a compiled
        section; else none."""
        kind, params = self._compiled_shape()
        self.state.tip_on[:] = False
        if not self.hole.open_ends:
            return
        place_tips(np.ascontiguousarray(qe), np.array(self.beam.centerline.lengths, dtype=float),
                   np.ascontiguousarray(qb[:3], dtype=float), rotation_matrix(qb[3:7]),
                   self.state.origins, self.state.axes, self._stations, *self._tree,
                   float(self._tip_reach), float(self.beam_radius), int(kind),
                   np.ascontiguousarray(params, dtype=float), self.state.tip_on,
                   self.state.tip_station, self._cross[4])

    def _check_start(self, qb: np.ndarray, qe: np.ndarray, *, warn: bool) -> None:
        """The beam must cross every section plane inside the bore (with ``open_ends``: wherever
        it crosses an inner section near the bore, inside it), and fit (no jamming); it should
        not start deep in the wall (``warn``). Sets the sections' tracking start."""
        _, origins, axes = self._planes(qb)
        lengths = np.array(self.beam.centerline.lengths, dtype=float)
        R_out = self.hole.section.bounding_radius()
        R_in = self.hole.section.inscribed_radius()
        deepest = 0.0
        ns = len(self.stations)
        crossed = 0
        if self.hole.open_ends:       # -1: not crossed inside the bore (the detection's state)
            self.state.elem[:] = -1
            self.state.xi[:] = 0.5
            self.state.ws_list[0] = -1
        for k, zeta in enumerate(self.stations):
            origin, (n, ey, ez) = origins[k], axes[k].T
            found, e, xi, cy, cz, a, _b, eax, eay = section_state(
                qe, lengths, origin, n, ey, ez, 0, 0.5, self.beam_radius,
                2.0 * R_out + self.beam_radius)   # a beam looping back crosses the plane twice
            outside = not section_contains(*self._compiled_shape(), cy, cz)
            if self.hole.open_ends and (not found or (outside and k in (0, ns - 1))):
                continue          # the beam is not in the bore here (yet)
            if not found or outside:
                raise ModelError(
                    f"joint '{self.name}': beam '{self.beam.name}' does not pass through the hole "
                    f"of body '{self.body.name}' at section {k} (axial station {zeta:.6g}); place "
                    "the body on the beam (pose = beam.frame_at(s), scenario pose = {on_beam, s})")
            if a > R_in * (1 + 1e-12):
                raise ModelError(
                    f"joint '{self.name}': the beam is tilted too much to fit the hole at section "
                    f"{k} (ellipse semi-axis {a:.6g} > bore {R_in:.6g}: jamming); align the hole "
                    "axis with the beam")
            self.state.elem[k], self.state.xi[k] = e, xi
            self.state.ws_list[0] = -1
            crossed += 1
            ell = Ellipse2D(np.array([cy, cz]), np.array([eax, eay]), a, _b)
            deepest = max(deepest, max((c.depth for c in self.hole.section.candidates(ell)),
                                       default=0.0))
        self.place_tips(qb, qe)
        if warn and crossed == 0:
            warnings.warn(FlexmbsWarning(
                f"joint '{self.name}': beam '{self.beam.name}' crosses none of the bore's "
                "sections at the start (open ends: it acts once the beam enters)"), stacklevel=2)
        clearance = self.hole.section.inscribed_radius() - self.beam_radius
        if warn and deepest > 0.05 * clearance:
            warnings.warn(FlexmbsWarning(
                f"joint '{self.name}': the beam starts {deepest:.3g} m into the bore wall "
                f"({deepest / clearance:.0%} of the clearance {clearance:.3g} m), so the contact "
                "starts with a large force; place the body with pose = { on_beam, s, rest = "
                "\"bore\" } or fix its offset"), stacklevel=2)

    # ------------------------------------------------------------------ detection + forces
    def _approach_for(self, k: int, psi: float) -> float:
        return tracked_approach(self.state.approach, self.state.active, self.state.psi, int(k), float(psi))

    def _contacts(self, q: np.ndarray, v: np.ndarray, want_tangent: bool, update: bool):
        """(section, index, kind, elem, ContactResult, a, b, psi) for every penetrating point
        (psi: section angle of the hole point); the result for the last state is kept (output
        rows, section records and probes ask for the same state)."""
        if want_tangent or update or self._frozen is not None:
            return self._detect_contacts(q, v, want_tangent, update)
        key = self._state_key(q, v)
        if self._contact_cache is not None and self._contact_cache[0] == key:
            return self._contact_cache[1]
        out = self._detect_contacts(q, v, False, False)
        self._contact_cache = (key, out)
        return out

    def _state_key(self, q: np.ndarray, v: np.ndarray) -> tuple:
        """What the contacts at ``(q, v)`` depend on besides the joint's parameters."""
        st = self.state
        return (q.tobytes(), v.tobytes(), st.elem.tobytes(), st.xi.tobytes(),
                st.approach.tobytes(), st.psi.tobytes(), st.active.tobytes(),
                st.anchor.tobytes(), st.stuck.tobytes(), st.tip_on.tobytes(),
                None if st.q_start is None else st.q_start.tobytes(),
                self.contact, self.friction)

    def keep_records(self, q: np.ndarray, v: np.ndarray, rows: np.ndarray) -> None:
        """The candidate rows (:data:`~flexmbs.contact._detect.COLS`) the compiled residual
        wrote at ``(q, v)``: the contact records of that state (output rows, section counts,
        contact energy and force) are read from them instead of detected again
        (:meth:`~flexmbs.assembly.Assembly.observe`)."""
        self._records = (self._state_key(q, v), rows.copy())

    def _observed(self, q: np.ndarray, v: np.ndarray) -> list:
        """The contacts at ``(q, v)`` as an output reads them: from the rows
        :meth:`keep_records` kept for this state, else :meth:`_contacts`."""
        kept = self._records
        if kept is None or self._frozen is not None or kept[0] != self._state_key(q, v):
            return self._contacts(q, v, False, False)
        if isinstance(kept[1], list):
            return kept[1]
        out = []
        for row in kept[1]:
            if row[GAP_COL] >= 0.0:
                continue
            g = row[GEOMETRY_COL:GEOMETRY_COL + 12]
            rec = ContactRecord(gap=float(row[GAP_COL]), normal=g[0:3], P=g[3:6], Q=g[6:9],
                                f_n=float(row[FORCE_COL]), force_on_hole=g[9:12],
                                xi=float(row[FORCE_COL + 1]), gap_rate=float(row[GAP_COL + 1]),
                                anchor=row[ANCHOR_COL:ANCHOR_COL + 3],
                                stuck=float(row[ANCHOR_COL + 3]), fade=float(row[FADE_COL]))
            out.append(_row_contact(row, rec))
        self._records = (kept[0], out)
        return out

    def _detect_contacts(self, q: np.ndarray, v: np.ndarray, want_tangent: bool, update: bool):
        """:meth:`_contacts` without the cache.

        With ``self._frozen`` (a list from :meth:`freeze_detection`) the detected hole points
        (body coordinates), elements and kinds are reused: the residual is then exactly the
        function whose derivative the tangent is (used by the finite-difference tests)."""
        if self._frozen is not None:
            g = self.geometry
            qb, vb = q[g.body_dofs], v[g.body_dofs]
            out = []
            for k, j, kind, eP, u_Q, xiP, a, b, psi in self._frozen:
                res = contact_point(qb, vb, u_Q, q[g.elem_dofs[eP]], v[g.elem_dofs[eP]],
                                    g.lengths[eP], xiP, self.beam_radius, self.contact,
                                    self.friction, self._approach_for(k, psi),
                                    self.consistent and want_tangent,
                                    history=self._history(q, k, psi, eP),
                                    friction_stiffness=self.friction_stiffness(),
                                    spin=self._spin(q, v, eP),
                                    xi_range=xi_bounds(eP, len(g.lengths)))
                if res.gap < 0.0:
                    out.append((k, j, kind, eP, res, a, b, psi))
            return out
        return self._contacts_compiled(q, v, want_tangent, update)

    def _compiled_shape(self) -> tuple[int, np.ndarray]:
        """The hole section's compiled boundary ``(kind, params)`` (every joint's section has
        one: the constructor refuses a section without)."""
        shape = self.hole.section.compiled_shape()
        assert shape is not None
        return shape

    def _mouth(self, k: int) -> float:
        """The beam radius at an end section of an open bore, whose law lets go as the beam's
        axis nears the rim (:func:`~flexmbs.contact.laws.mouth_weight`), else 0 (the compiled
        path's rule, :func:`~flexmbs.contact.clearance_term.clearance_forces`)."""
        return float(mouth_radius(bool(self.hole.open_ends), k, len(self.stations),
                                  float(self.beam_radius)))

    def _detection_frame(self, q: np.ndarray) -> DetectionFrame:
        """What the detection takes at ``q``: the hole body's position and rotation, the
        sections' origins and axes in its coordinates and their tree."""
        qb = q[self.geometry.body_dofs]
        return (np.ascontiguousarray(qb[:3]), rotation_matrix(qb[3:7]), self.state.origins,
                self.state.axes, self.geometry.tree)

    def _contact_pose(self, q: np.ndarray, v: np.ndarray, k: int
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The pose ``[r, p]``, its rate and rotation of the body that holds section k's wall
        (the hole body)."""
        g = self.geometry
        qb = q[g.body_dofs]
        return qb, v[g.body_dofs], rotation_matrix(qb[3:7])

    def detect_rows(self, q: np.ndarray, update: bool = False) -> int:
        """The compiled narrow phase of every section at ``q`` (:func:`_detect.detect_section`):
        the candidate rows into ``self._rows``; returns their number (``-1 - k``: the axis left
        the bore at section k). ``update``: the crossings become the warm starts."""
        r_H, A, origins, axes, tree = self._detection_frame(q)
        qe = np.ascontiguousarray(q[self.geometry.elem_dofs])
        e_out, x_out = (self.state.elem, self.state.xi) if update else (self._elem_out, self._xi_out)
        unknown = np.full(1, -1, np.int64)        # lists not kept here: every section scanned
        out_list = np.full(self.n_slots + 1, -1, np.int64)
        if update:
            self.state.ws_list[0] = -1
        section = self.hole.section
        shape, params = self._compiled_shape()
        g = self.geometry
        etree = np.zeros((element_tree_size(qe.shape[0]), 4))
        element_tree(qe, g.lengths, etree)
        m = detect_section(qe, g.lengths, r_H, A, origins, axes, *tree, etree,
                           bool(self.hole.open_ends),
                           self.state.tip_on,
                           *self._cross[:5],
                           self.state.elem, self.state.xi, unknown, e_out, x_out, out_list,
                           self.beam_radius, shape, params,
                           float(section.bounding_radius()), float(section.inscribed_radius()),
                           self.detection == "consistent",
                           None if self.detection == "consistent" else np.ones(1, np.bool_),
                           self._rows, self._cross[5])
        return int(m)

    def _contacts_compiled(self, q: np.ndarray, v: np.ndarray, want_tangent: bool,
                           update: bool) -> list:
        """A section with a compiled shape: the narrow phase of all sections runs compiled
        (contact/_detect.py)."""
        m = self.detect_rows(q, update)
        if m < 0:
            self._raise_left_bore(m)
        r_H, A, origins, axes, _ = self._detection_frame(q)
        qe = np.ascontiguousarray(q[self.geometry.elem_dofs])
        plane = np.zeros((4, 3))                 # a section's origin, normal, e_y, e_z
        out = []
        for row in self._rows[:m].copy():
            k, eP = int(row[0]), int(row[3])
            qb, vb, A = self._contact_pose(q, v, k)
            u_Q = A.T @ (row[5:8] - qb[:3])
            ed = self.geometry.elem_dofs[eP]
            res = contact_point(qb, vb, u_Q, q[ed], v[ed], self.geometry.lengths[eP], row[4],
                                self.beam_radius, self.contact, self.friction,
                                self._approach_for(k, row[11]), self.consistent and want_tangent,
                                history=self._history(q, k, row[11], eP),
                                friction_stiffness=self.friction_stiffness(),
                                spin=self._spin(q, v, eP),
                                xi_range=xi_bounds(eP, len(self.geometry.lengths)),
                                mouth=self._mouth(k))
            if res.gap < 0.0:
                fade = 1.0
                if k < len(self.stations):       # a bore's section (the tips: in full)
                    _section_plane(r_H, A, origins[k], axes[k], *plane)
                    fade, _, _ = end_fade(qe, self.geometry.lengths, int(row[CROSSING_COL]),
                                          plane[0], plane[1], self.beam_radius)
                out.append(_row_contact(row, _faded(res, fade)))
        return out

    def freeze_detection(self, q: np.ndarray | None, v: np.ndarray | None = None) -> None:
        """Freeze (or, with ``q=None``, release) the detected contact points at ``q``."""
        if q is None:
            self._frozen = None
            return
        v = np.zeros_like(q) if v is None else v
        qb = q[self.geometry.body_dofs]
        A = rotation_matrix(qb[3:7])
        self._frozen = [(k, j, kind, eP, A.T @ (res.Q - qb[:3]), res.xi, a, b, psi)
                        for k, j, kind, eP, res, a, b, psi in self._contacts(q, v, False, False)]

    def rest_on_beam(self, direction: Any) -> float:
        """Move the body along ``direction`` (projected on the plane normal to the hole axis;
        e.g. gravity) until its bore rests on the beam in the reference configuration: the
        deepest section point just touches (issue "nothing lost", item 9). The placement follows
        the clearance, so a changed hole radius starts in contact, not inside the wall.
        Returns the distance moved [m]."""
        from ..model import Pose

        body = self.body
        A = body.pose.rotation
        axis = A @ self.state.axes[len(self.stations) // 2, :, 0]   # the middle section's normal
        d = np.asarray(direction, float).reshape(3)
        d = d - axis * (axis @ d)
        if not np.linalg.norm(d) > 0:
            raise ModelError(f"joint '{self.name}': the rest direction is along the hole axis; "
                             "give one across it")
        d = d / np.linalg.norm(d)
        L = np.array(self.beam.centerline.lengths, dtype=float)   # writable: one compiled form
        qe = self._reference_elements()
        section = self.hole.section
        R_out = section.bounding_radius()

        def deepest(shift: float) -> float:
            origins = body.pose.position + shift * d + self.state.origins @ A.T
            axes = A @ self.state.axes
            worst = -np.inf
            for k in range(len(self.stations)):
                n, ey, ez = axes[k].T
                found, _e, _xi, cy, cz, a, b, eax, eay = section_state(
                    qe, L, origins[k], n, ey, ez, 0, 0.5, self.beam_radius,
                    4.0 * R_out + self.beam_radius)   # the crossing near the bore
                if not found:
                    return np.inf
                ell = Ellipse2D(np.array([cy, cz]), np.array([eax, eay]), a, b)
                for cand in section.candidates(ell, margin=np.inf):
                    worst = max(worst, cand.depth)
            return worst

        lo, hi = 0.0, 2.0 * R_out
        if not deepest(lo) < 0.0:   # a curved beam may need the bore shifted against d first
            free = [x for x in np.linspace(0.0, -R_out, 41)[1:] if deepest(x) < 0.0]
            if not free:
                raise ModelError(
                    f"joint '{self.name}': the bore cuts the beam wherever it is placed across "
                    "it (the beam bends more than the clearance within the hole, or the beam is "
                    "too thick); a larger hole radius or a shorter hole fits")
            lo = free[0]
        if not deepest(hi) > 0.0:
            raise ModelError(f"joint '{self.name}': moving the body along the rest direction "
                             "never brings the bore onto the beam")
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            if deepest(mid) < 0.0:
                lo = mid
            else:
                hi = mid
        body.pose = Pose(body.pose.position + hi * d, A)
        return hi

    def hole_record(self) -> dict[str, Any]:
        """The hole as data (``summary.json["hole_sections"]``, read by the section view):
        ``shape`` (registered name) and the section's parameters, ``length``, ``sections``
        (:meth:`Hole.record`)."""
        from .sections import HOLE_SECTIONS

        section = self.hole.section
        shape = next((n for n in HOLE_SECTIONS.names() if HOLE_SECTIONS.get(n) is type(section)),
                     type(section).__name__)
        params: dict[str, Any] = dataclasses.asdict(section) if dataclasses.is_dataclass(section) else {}
        return {"shape": shape, **params, **self.hole.record()}

    def compiled_form(self) -> bool:
        """Whether the compiled kernels evaluate this joint (:class:`ClearancePart`): a section
        with a compiled shape, detection not frozen, exact or Gauss–Newton tangent; else the
        per-contact Python path of :meth:`evaluate` does."""
        return self._frozen is None and self.tangent != "frozen_point"

    @property
    def consistent(self) -> bool:
        """The Python path's frozen-point geometric terms are on (``tangent="frozen_point"``)."""
        return self.tangent == "frozen_point"

    def friction_stiffness(self) -> float:
        """Tangential stiffness of the stick law [N/m]: the friction's ``stiffness``, else the
        normal law's stiffness ``∂f_N/∂δ`` at δ = 1 % of the radial clearance (its stiffness
        for the linear law): the contact holds tangentially as stiffly as it does normally."""
        if self.friction is not None and self.friction.stiffness is not None:
            return float(self.friction.stiffness)
        K, n = (float(x) for x in self.contact.parameters()[:2])
        if n == 1.0:
            return K
        delta = 0.01 * (self.hole.section.inscribed_radius() - self.beam_radius)
        return n * K * delta ** (n - 1.0)

    def friction_parameters(self) -> np.ndarray:
        """The friction law as the kernels read it (:meth:`Friction.parameters`)."""
        return friction_vector(self.friction, self.friction_stiffness())

    def _history(self, q: np.ndarray, k: int, psi: float, eP: int) -> np.ndarray:
        """Friction history (pair.N_HISTORY) of the contact of section k at angle psi on
        element eP: its tracked anchor and the step's start (or ``q`` before the model runs)."""
        hist = np.empty(N_HISTORY)
        start = self.state.q_start if self.state.q_start is not None else q
        st = self.state
        contact_history(st.anchor, st.stuck, tracked_slot(st.active, st.psi, int(k), float(psi)),
                        int(k), start, self.geometry.body_dofs, self.geometry.elem_dofs[eP],
                        self.geometry.twist_dofs[eP], hist)
        return hist

    def _spin(self, q: np.ndarray, v: np.ndarray, eP: int) -> np.ndarray:
        """The spin data (pair.N_SPIN) of element eP (:func:`clearance_term.element_spin`)."""
        spin = np.empty(N_SPIN)
        element_spin(q, v, self.geometry.twist_dofs[eP], self.state.t_bar[eP], spin)
        return spin

    def _raise_left_bore(self, m: int) -> None:
        raise self.error(ERR_LEFT_BORE, -1 - m, np.zeros(0), 0.0)

    def error(self, code: int, detail: int, q: np.ndarray, t: float) -> FlexmbsError:
        """A Newton iterate (or a step) pushed the beam axis through the bore wall at section
        ``detail``: the iterate is rejected so that the step or load increment is cut, instead
        of losing the contact silently. (``ERR_TOO_MANY_CONTACTS``: ``detail`` contacts at once,
        more than the tangent holds.)"""
        if code == ERR_CONTACT_OFF_PLAN:
            return ConvergenceError(
                f"joint '{self.name}': a contact on element {detail} of beam "
                f"'{self.beam.name}' lies outside the elements the factorisation follows it on")
        if code == ERR_TOO_MANY_CONTACTS:
            return ConvergenceError(
                f"joint '{self.name}': more than {detail} contact points at once, the most "
                f"its tangent holds ({CONTACTS_PER_SECTION} per section on average); use "
                "fewer sections (a contact per section and element length is plenty)")
        return ConvergenceError(
            f"joint '{self.name}': the beam axis left the bore at hole section {detail} "
            "(penetration larger than the clearance); use a smaller time step, more load "
            "steps or a stiffer contact")

    def evaluate(self, sink: MatrixSink, q: np.ndarray, v: np.ndarray, lam: np.ndarray, t: float,
                 r_q: np.ndarray, matrix: tuple[float, float, float] | None) -> float:
        """Per-contact Python path (joints without a compiled form, :meth:`compiled_form`)."""
        scale = 0.0
        for _k, _j, kind, eP, res, *_ in self._contacts(q, v, matrix is not None, False):
            sign = float(kind)
            r_q[self.geometry.body_dofs] -= sign * res.Q_body
            r_q[self.geometry.elem_dofs[eP]] -= sign * res.Q_elem
            twisted = self.geometry.twist_dofs[eP, 0] >= 0
            if twisted:
                r_q[self.geometry.twist_dofs[eP]] -= sign * res.Q_twist
            scale = max(scale, float(np.abs(res.Q_body).max()), float(np.abs(res.Q_elem).max()))
            if matrix is not None:
                _, cC, cK = matrix
                idx = np.concatenate([self.geometry.body_dofs, self.geometry.elem_dofs[eP]]
                                     + ([self.geometry.twist_dofs[eP]] if twisted else []))
                n = idx.size
                sink.add_to_matrix(idx, idx, sign * (cK * res.K + cC * res.C)[:n, :n])
        return scale

    def post_step(self, q: np.ndarray, v: np.ndarray, t: float) -> None:
        """Per-contact Python path: warm starts and tracked contacts at the converged state."""
        contacts = self._contacts(q, v, False, True)
        rows = np.zeros((len(contacts), N_COLS))
        for i, (k, _j, _kind, _eP, res, _a, _b, psi) in enumerate(contacts):
            rows[i, [0, 11, 12, 13]] = k, psi, res.gap, res.gap_rate
            rows[i, ANCHOR_COL:ANCHOR_COL + 3] = res.anchor
            rows[i, ANCHOR_COL + 3] = res.stuck
        clearance_update(rows, len(contacts), np.full(1, -1, np.int64), self.state.approach,
                         self.state.active, self.state.psi, self.state.anchor, self.state.stuck)
        g = self.geometry
        self.place_tips(q[g.body_dofs], np.ascontiguousarray(q[g.elem_dofs]))

    # ------------------------------------------------------------------ output
    def output(self, dofs: DofMap, q: np.ndarray, v: np.ndarray, lam: np.ndarray,
               t: float) -> list[dict[str, Any]]:
        """One row per contact point (contacts.csv, the VTU contact points): the columns of
        contacts.csv, ``position`` and ``normal``, the friction force on the hole
        ``tangential_force`` (3,) and ``stick`` (1.0 while the stick law holds the contact)."""
        rows = []
        for k, j, kind, _eP, res, a, b, _psi in self._observed(q, v):
            rows.append({
                "t": t, "joint": self.name, "section": k, "point": j, "gap": res.gap,
                "normal_force": float(kind) * res.f_n, "qx": res.Q[0], "qy": res.Q[1],
                "qz": res.Q[2], "px": res.P[0], "py": res.P[1], "pz": res.P[2], "a": a, "b": b,
                "position": res.Q, "normal": res.normal,
                "tangential_force": float(kind) * (res.force_on_hole - res.f_n * res.normal),
                "stick": res.stuck})
        return rows

    def section_records(self, q: np.ndarray, v: np.ndarray, t: float) -> list[dict[str, Any]]:
        """Per hole section: section frame, beam ellipse (section coordinates), bore radius and
        number of contact points (``sections.csv``, used by the section view)."""
        _, origins, axes = self._planes_at(q)
        qe = np.ascontiguousarray(q[self.geometry.elem_dofs])
        R = self.hole.section.bounding_radius()
        counts: dict[int, int] = {}
        for k, *_ in self._observed(q, v):
            counts[k] = counts.get(k, 0) + 1
        rows = []
        for k in range(len(self.stations)):
            origin, (n, ey, ez) = origins[k], axes[k].T
            found, e, xi, cy, cz, a, b, eax, eay = section_state(
                qe, self.geometry.lengths, origin, n, ey, ez, max(0, int(self.state.elem[k])),
                float(self.state.xi[k]), self.beam_radius, 2 * R + self.beam_radius)
            if not found:
                continue
            rows.append({"joint": self.name, "section": k, "ox": origin[0], "oy": origin[1],
                         "oz": origin[2], "eyx": ey[0], "eyy": ey[1], "eyz": ey[2],
                         "ezx": ez[0], "ezy": ez[1], "ezz": ez[2], "cy": cy, "cz": cz,
                         "ey_a": eax, "ez_a": eay, "a": a, "b": b, "R": R,
                         "contacts": counts.get(k, 0)})
        return rows

    def section_outlines(self, q: np.ndarray, samples: int = 48) -> np.ndarray:
        """The bore outline of every hole section at ``q`` (output: the ``hole_sections`` block):
        ``(n_sections, samples, 3)`` global points ``o_k + Y_y(psi) e_y,k + Y_z(psi) e_z,k``
        of the section boundary ``Y(psi)`` at ``psi = 2 pi j / samples`` in each section plane."""
        _, origins, axes = self._planes_at(q)
        cached = getattr(self, "_outline_boundary", None)    # the section's, the same each time
        section = self.hole.section
        if cached is None or cached[0] != int(samples) or cached[1] is not section:
            psi = np.linspace(0.0, 2.0 * np.pi, int(samples), endpoint=False)
            cached = self._outline_boundary = (int(samples), section, section.boundary(psi)[0])
        Y = cached[2]
        return (origins[:, None, :] + Y[None, :, :1] * axes[:, None, :, 1]
                + Y[None, :, 1:] * axes[:, None, :, 2])

    def slide_coordinate(self, q: np.ndarray) -> float:
        """Arc length (from the beam's first node) of the projection of the hole centre (the
        middle section's origin) onto the beam centreline."""
        k = len(self.stations) // 2
        centre = self._planes_at(q)[1][k]
        qe = np.ascontiguousarray(q[self.geometry.elem_dofs])
        e, xi, *_ = closest_point(qe, self.geometry.lengths, centre, max(0, int(self.state.elem[k])),
                                  float(self.state.xi[k]))
        return float(np.sum(self.geometry.lengths[:e]) + xi * self.geometry.lengths[e])

    def contact_energy(self, q: np.ndarray, v: np.ndarray | None = None) -> float:
        """Potential of the contact forces at ``q``: ``Σ_k [Σ_max Φ(δ) − Σ_min Φ(δ)]`` over the
        sections' penetrating points (``Φ`` = :func:`~flexmbs.contact.laws.law_energy`,
        docs/theory.md §II.4b). With ``detection="consistent"`` the elastic contact forces are
        exactly its negative gradient; with ``"paper"`` only at small crossing angles. ``v``
        does not change it; passing the state's velocities reuses the detection of the output
        rows at the same state."""
        law = self.contact.parameters()
        v = np.zeros_like(q) if v is None else v
        return float(sum(kind * res.fade * law_energy(law, -res.gap, self._mouth(k))
                         for k, _j, kind, _eP, res, *_ in self._observed(q, v)))

    def contact_force(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Total contact force on the hole body (global components)."""
        F = np.zeros(3)
        for _k, _j, kind, _eP, res, *_ in self._observed(q, v):
            F += float(kind) * res.force_on_hole
        return F

    def get_state(self) -> dict[str, Any]:
        """Warm starts, tracked contacts ``[section, slot, approach velocity, angle, anchor
        (3), stuck]`` and the friction law they were computed with."""
        return {"elem": self.state.elem.tolist(), "xi": self.state.xi.tolist(),
                "friction": self.friction_parameters().tolist(),
                "approach": [[int(k), int(s), float(self.state.approach[k, s]), float(self.state.psi[k, s]),
                              *(float(x) for x in self.state.anchor[k, s]), float(self.state.stuck[k, s])]
                             for k, s in zip(*np.nonzero(self.state.active), strict=True)]}

    def set_state(self, state: dict[str, Any]) -> None:
        """Restore :meth:`get_state` (bit for bit); a changed friction law is refused."""
        check_resumed_friction(self.name, state.get("friction"), self.friction_parameters())
        elem, xi = state["elem"], state["xi"]   # (older checkpoints: no tip sections)
        self.state.elem[:len(elem)] = elem
        self.state.xi[:len(xi)] = xi
        self.state.ws_list[0] = -1
        self.state.approach[:] = 0.0
        self.state.psi[:] = 0.0
        self.state.active[:] = False
        self.state.anchor[:] = 0.0
        self.state.stuck[:] = 0.0
        for k, s, val, *rest in state["approach"]:
            if int(s) < self.state.approach.shape[1] and rest:   # (older checkpoints: no angle)
                self.state.approach[int(k), int(s)] = float(val)
                self.state.psi[int(k), int(s)] = float(rest[0])
                self.state.active[int(k), int(s)] = True
                if len(rest) == 5:                          # (older checkpoints: no anchor)
                    self.state.anchor[int(k), int(s)] = rest[1:4]
                    self.state.stuck[int(k), int(s)] = float(rest[4])

    def __repr__(self) -> str:
        return (f"SlidingClearanceJoint({self.name!r}, beam={self.beam.name!r}, "
                f"body={self.body.name!r}, hole={type(self.hole.section).__name__}, "
                f"sections={len(self.stations)}, law={self.contact!r})")


# ---------------------------------------------------------------------------------------------
# the clearance-joint term of the assembler (flexmbs.terms)
def clearance_pattern(joint: SlidingClearanceJoint, dofs: DofMap) -> list[tuple[np.ndarray, np.ndarray]]:
    """The hole body couples with itself and with every coordinate of the beam (contacts move
    along it); a flexible tube each element with itself and the beam
    (:meth:`SlidingClearanceJoint.window_owns`). The exact tangent's coupling of a contact
    point's element with a neighbouring crossing element uses the entries the beam already has
    (their shared node): reserving the rest would widen the band of every beam by a node
    (measured: Example 1 20 % slower) for entries of order ξ² near the shared node."""
    out = []
    for own in joint.window_owns():
        cols = np.concatenate([own, joint.geometry.beam_dofs])
        out += [(own, cols), (cols, own)]
    return out


def _chart_tangents(joint: SlidingClearanceJoint, ctx: PackContext) -> np.ndarray:
    """The base tangents t̄ of the charts of every element's nodes (n_elem, 2, 3) at the
    model's start, as the rod's own packing gives them (its ``node_base``); zeros for a beam
    without twist."""
    beam = joint.beam
    out = np.zeros((len(joint.geometry.lengths), N_TWIST, 3))
    node_base = beam.element_type.node_base
    if beam.layout.twist is None or node_base is None:
        return out
    element_dofs = ctx.element_dofs(beam)
    for e, nodes in enumerate(beam.connectivity):
        for a, node in enumerate(nodes):
            out[e, a] = node_base(element_dofs, ctx.q_ref, int(node))[0]
    return out


def pack_clearance(joints: list[SlidingClearanceJoint], ctx: PackContext) -> ClearancePart:
    """All clearance joints; their state arrays become views of the packed ones. The steps
    start from ``ctx.q_ref`` until :meth:`~flexmbs.assembly.Assembly.begin` says otherwise."""
    dofs, n_total, q_ref = ctx, ctx.n_total, ctx.q_ref
    nj = len(joints)
    max_ne = max((len(j.geometry.lengths) for j in joints), default=0)
    max_ns = max((j.n_slots for j in joints), default=0)
    n_contacts = contact_capacity(max_ns)
    pos = np.full((nj, max_ne, N_LOCAL * N_LOCAL), -1, np.int64)
    ne2 = CENTERLINE_SIZE * CENTERLINE_SIZE
    cross = np.zeros((nj, max_ne, 2, ne2), np.int64)
    for i, j in enumerate(joints):
        n_el = len(j.geometry.lengths)
        j.state.t_bar[:] = _chart_tangents(j, ctx)
        for k in range(n_el):
            twisted = j.geometry.twist_dofs[k, 0] >= 0
            idx = np.concatenate([j.geometry.body_dofs, j.geometry.elem_dofs[k]]
                                 + ([j.geometry.twist_dofs[k]] if twisted else []))
            block = pos[i, k].reshape(N_LOCAL, N_LOCAL)   # a cable: no twist rows, columns
            block[:idx.size, :idx.size] = dofs.positions(idx, idx).reshape(idx.size, idx.size)
            for side, other in ((0, k - 1), (1, k + 1)):
                if 0 <= other < n_el:
                    cross[i, k, side] = dofs.positions_present(j.geometry.elem_dofs[k],
                                                               j.geometry.elem_dofs[other])
    i64, c = np.int64, np.ascontiguousarray
    shapes = [j._compiled_shape() for j in joints]
    beam_of, beam_joint, beam_qe, beam_tree = _beams(joints, max_ne)
    indptr, indices = ctx.matrix_pattern()
    part = ClearancePart(
        body=c(np.array([j.geometry.body_dofs for j in joints], i64).reshape(nj, 7)),
        elem_dofs=pad_stack([j.geometry.elem_dofs for j in joints], (CENTERLINE_SIZE,), 0, np.int64),
        twist_dofs=pad_stack([j.geometry.twist_dofs for j in joints], (N_TWIST,), -1, np.int64),
        t_bar=pad_stack([j.state.t_bar for j in joints], (N_TWIST, 3), 0.0, float),
        n_elem=np.array([len(j.geometry.lengths) for j in joints], i64),
        lengths=pad_stack([j.geometry.lengths for j in joints], (), 1.0, float),
        origins=pad_stack([j.state.origins for j in joints], (3,), 0.0, float),
        frames=pad_stack([j.state.axes for j in joints], (3, 3), 0.0, float),
        tree_c=pad_stack([j.geometry.tree[0] for j in joints], (3,), 0.0, float),
        tree_r=pad_stack([j.geometry.tree[1] for j in joints], (), -1.0, float),
        tree_lo=pad_stack([j.geometry.tree[2] for j in joints], (), 0, np.int64),
        tree_hi=pad_stack([j.geometry.tree[3] for j in joints], (), 0, np.int64),
        open_ends=np.array([j.hole.open_ends for j in joints], dtype=np.bool_),
        cross_n=np.zeros(max_ns, i64),
        cross_e=np.zeros((max_ns, MAX_CROSSINGS), i64),
        cross_xi=np.zeros((max_ns, MAX_CROSSINGS)),
        touched=np.zeros(max_ns, i64),
        work=np.zeros(max_ns + DETECT_INT_WORK, i64),
        n_sec=np.array([j.n_slots for j in joints], i64),
        r_b=np.array([j.beam_radius for j in joints], float),
        shape=np.array([shapes[i][0] for i in range(nj)], i64),
        params=c(np.array([shapes[i][1] for i in range(nj)], float).reshape(nj, 4)),
        R_out=np.array([j.hole.section.bounding_radius() for j in joints], float),
        R_in=np.array([j.hole.section.inscribed_radius() for j in joints], float),
        consistent=np.array([j.detection == "consistent" for j in joints], dtype=np.bool_),
        law=c(np.array([j.contact.parameters() for j in joints], float).reshape(nj, N_LAW)),
        fric=c(np.array([j.friction_parameters() for j in joints], float).reshape(nj, N_FRICTION)),
        enabled=np.array([j.compiled_form() for j in joints], dtype=np.bool_),
        exact=np.array([j.tangent == "exact" for j in joints], dtype=np.bool_),
        elem_ws=pad_stack([j.state.elem for j in joints], (), 0, np.int64),
        xi_ws=pad_stack([j.state.xi for j in joints], (), 0.5, float),
        ws_list=np.full((nj, max_ns + 1), -1, i64),
        approach=pad_stack([j.state.approach for j in joints], (MAX_POINTS,), 0.0, float),
        active=pad_stack([j.state.active for j in joints], (MAX_POINTS,), False, np.bool_),
        psi=pad_stack([j.state.psi for j in joints], (MAX_POINTS,), 0.0, float),
        anchor=pad_stack([j.state.anchor for j in joints], (MAX_POINTS, 3), 0.0, float),
        stuck=pad_stack([j.state.stuck for j in joints], (MAX_POINTS,), 0.0, float),
        q_start=np.array(q_ref, dtype=float, copy=True),
        pos=pos,
        cross=cross,
        qe=np.zeros((max_ne, CENTERLINE_SIZE)),
        rows=np.zeros((nj, MAX_CANDIDATES * max_ns, N_COLS)),
        n_candidates=np.zeros(nj, i64),
        elem_out=np.full((nj, max_ns), -1, i64),
        xi_out=np.zeros((nj, max_ns)),
        out_list=np.full((nj, max_ns + 1), -1, i64),
        K=np.zeros((n_contacts, N_LOCAL, N_EXT)),
        C=np.zeros((n_contacts, N_LOCAL, N_LOCAL)),
        kelem=np.zeros(n_contacts, i64),
        kelem_i=np.zeros(n_contacts, i64),
        no_K=np.zeros((0, N_LOCAL, N_EXT)),
        no_C=np.zeros((0, N_LOCAL, N_LOCAL)),
        no_elem=np.zeros(0, i64),
        scratch=np.zeros(n_total),
        stations=pad_stack([j.geometry.stations for j in joints], (), 0.0, float),
        tip_on=pad_stack([j.state.tip_on for j in joints], (), False, np.bool_),
        tip_station=pad_stack([j.state.tip_station for j in joints], (), 0.0, float),
        tip_reach=np.array([j.geometry.tip_reach for j in joints], float),
        tips_due=np.zeros(nj, np.bool_),
        spin=np.zeros(N_SPIN),
        paper=np.array([j.detection != "consistent" for j in joints], dtype=np.bool_),
        fwork=np.zeros(FORCES_WORK),
        window=c(np.array([[0, len(j.geometry.lengths)] for j in joints for _ in j.window_owns()],
                          i64).reshape(-1, 2)),
        win_row=np.cumsum([0] + [len(j.window_owns()) for j in joints[:-1]], dtype=i64)[:nj],
        beam_of=beam_of,
        beam_joint=beam_joint,
        beam_qe=beam_qe,
        beam_tree=beam_tree,
        tube=_tubes(joints, max_ns),
        tube_work=np.zeros(TUBE_WORK),
        ksec=np.zeros(n_contacts, i64),
        kforce=np.zeros((n_contacts, 7)),
        indptr=indptr,
        indices=indices,
        hold=np.zeros(2, i64),
        held=np.zeros((nj, max_ns, MAX_POINTS), np.bool_),
        held_psi=np.zeros((nj, max_ns, MAX_POINTS)))
    for i, j in enumerate(joints):     # the joint's state lives in the packed arrays
        j.state = ClearanceState.views(part, i, j.n_slots, len(j.geometry.lengths))
        j.packed_tube(part.tube, i)
    return part


def _tubes(joints: list[SlidingClearanceJoint], max_ns: int) -> TubeSections:
    """The sections of the joints whose bore is a flexible tube (:meth:`tube_sections`; zeros
    for the others)."""
    nj = len(joints)
    out = TubeSections(on=np.zeros(nj, np.bool_), width=np.full(nj, CENTERLINE_SIZE, np.int64),
                       dofs=np.zeros((nj, max_ns, SECTION_COORDS), np.int64),
                       length=np.ones((nj, max_ns)), xi=np.zeros((nj, max_ns)),
                       t_bar=np.zeros((nj, max_ns, 3)), p0=np.zeros((nj, max_ns, 4)),
                       row=np.zeros((nj, max_ns), np.int64),
                       node_t=np.zeros((nj, max_ns, 2, 3)), node_d=np.zeros((nj, max_ns, 2, 3)),
                       turn=new_turn_work())
    for i, j in enumerate(joints):
        sections = j.tube_sections()
        if sections is None:
            continue
        dofs, length, xi, t_bar, p0, row, node_t, node_d = sections
        n, width = len(xi), dofs.shape[1]
        out.on[i] = True
        out.width[i] = width
        out.dofs[i, :n, :width], out.length[i, :n], out.xi[i, :n] = dofs, length, xi
        out.t_bar[i, :n], out.p0[i, :n], out.row[i, :n] = t_bar, p0, row
        out.node_t[i, :n], out.node_d[i, :n] = node_t, node_d
    return out


def _beams(joints: list[SlidingClearanceJoint], max_ne: int
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The joints' beams (:class:`ClearancePart`'s ``beam_of``, ``beam_joint``, ``beam_qe``,
    ``beam_tree``): joints on the same elements share one copy of the beam's coordinates and
    one element tree per evaluation (clearance_term.beam_geometry)."""
    keys: dict[bytes, int] = {}
    beam_of = np.zeros(len(joints), np.int64)
    first: list[int] = []
    for i, j in enumerate(joints):
        key = (np.ascontiguousarray(j.geometry.elem_dofs, np.int64).tobytes()
               + np.ascontiguousarray(j.geometry.lengths, float).tobytes())
        if key not in keys:
            keys[key] = len(first)
            first.append(i)
        beam_of[i] = keys[key]
    nb = len(first)
    return (beam_of, np.array(first, np.int64), np.zeros((nb, max_ne, CENTERLINE_SIZE)),
            np.zeros((nb, element_tree_size(max_ne), 4)))


def _compiled_view(part: ClearancePart) -> ClearancePart:
    """What the compiled kernel receives: the features no clearance joint of the model uses are
    None, so that their code is not compiled for it (docs/design-notes.md, "Compile time"):
    the tip sections of open bores, a rod's spin in the contact, the paper's detection."""
    unused = {"tips_due": not part.open_ends.any(), "spin": not (part.twist_dofs >= 0).any(),
              "paper": not part.paper.any(), "tube": not part.tube.on.any()}
    none: dict[str, Any] = {name: None for name, off in unused.items() if off}
    if not unused["tube"] and not (part.tube.width > CENTERLINE_SIZE).any():
        none["tube"] = part.tube._replace(turn=None)    # no tube is a rod: no turn compiled
    return part._replace(**none)


def _enable_clearance(part: ClearancePart, i: int, on: bool) -> None:
    part.enabled[i] = on


def _begin_clearance(part: ClearancePart, q: np.ndarray) -> None:
    """``q`` starts the next step: the friction's reference, and the tip sections of open bores
    placed there (as after every converged step, clearance_term.clearance_post_step_all; a resumed
    run places them as the uninterrupted one did)."""
    part.q_start[:] = q
    part.tips_due[:] = False
    for j in range(part.r_b.size):
        part.tip_on[j] = False
        if part.tube.on[j]:      # a tube's: the step's first evaluation, with the tube's pose
            part.tips_due[j] = part.open_ends[j]
            continue
        if not part.open_ends[j]:
            continue
        ne, ns = int(part.n_elem[j]), int(part.n_sec[j])
        qb = q[part.body[j]]
        place_tips(np.ascontiguousarray(q[part.elem_dofs[j, :ne]]), part.lengths[j, :ne],
                   np.ascontiguousarray(qb[:3]), rotation_matrix(qb[3:7]),
                   part.origins[j, :ns], part.frames[j, :ns], part.stations[j, :ns],
                   part.tree_c[j], part.tree_r[j], part.tree_lo[j], part.tree_hi[j],
                   float(part.tip_reach[j]), float(part.r_b[j]), int(part.shape[j]),
                   part.params[j], part.tip_on[j], part.tip_station[j], part.work)


def _observe_clearance(part: ClearancePart, joints: list[SlidingClearanceJoint], q: np.ndarray,
                       v: np.ndarray, residual: Callable[[], None] | None) -> None:
    """An output's state: the compiled joints keep the contact points of the kernel's last
    residual, at that state (:meth:`SlidingClearanceJoint.keep_records`), after evaluating it
    with ``residual`` if given; the tip sections due at the next step then stay due (the
    output sees the sections the step's equilibrium was found with)."""
    on = [i for i in range(len(joints)) if part.enabled[i]]
    if not on:
        return
    if residual is not None:
        due = part.tips_due.copy()
        part.tips_due[:] = False
        try:
            residual()
        finally:
            part.tips_due[:] = due
    for i in on:
        joints[i].keep_records(q, v, part.rows[i, :int(part.n_candidates[i])])


def _joint_elements(joint: SlidingClearanceJoint) -> np.ndarray:
    """Every element's coordinates of the joint's beam, its centreline's and its nodes' twists
    (−1 padded for a cable): what the hole body's entries couple with."""
    g = joint.geometry
    return np.concatenate([g.elem_dofs, g.twist_dofs], axis=1).astype(np.int64)


def _current_windows(part: ClearancePart, reach: int) -> np.ndarray:
    """Per window row (a joint's; a flexible tube's per element, :func:`~flexmbs.contact.
    clearance_term.window_row`) the elements its sections cross at the step's start
    (``elem_ws``, the placed tip sections too), ``reach`` either side, clipped to its beam;
    none crossed: an empty window (a contact found later re-plans)."""
    lo = np.full(part.window.shape[0], np.iinfo(np.int64).max, np.int64)
    hi = np.full(part.window.shape[0], -1, np.int64)
    for j in range(part.r_b.size):
        ns = int(part.n_sec[j])
        slots = np.r_[np.arange(ns - N_TIPS), ns - N_TIPS + np.flatnonzero(part.tip_on[j])]
        crossed = part.elem_ws[j, slots]
        slots, crossed = slots[crossed >= 0], crossed[crossed >= 0]
        rows = part.win_row[j] + (part.tube.row[j, slots] if part.tube.on[j]
                                  else np.zeros(slots.size, np.int64))
        np.minimum.at(lo, rows, crossed)
        np.maximum.at(hi, rows, crossed)
    ne = part.n_elem[np.searchsorted(part.win_row, np.arange(lo.size), side="right") - 1]
    out = np.zeros((lo.size, 2), np.int64)
    on = hi >= 0
    out[on, 0] = np.maximum(lo[on] - reach, 0)
    out[on, 1] = np.minimum(hi[on] + reach + 1, ne[on])
    return out


#: the clearance joint's term kind (:class:`~flexmbs.constraints.interaction.InteractionKind`);
#: a joint without a compiled form at the moment is switched off here and evaluated in Python;
#: its contact potential is the energy "contact"
CLEARANCE = InteractionKind(
    name="clearance", pattern=clearance_pattern, pack=pack_clearance,
    errors=(ERR_LEFT_BORE, ERR_TOO_MANY_CONTACTS, ERR_CONTACT_OFF_PLAN),
    enable=_enable_clearance, begin=_begin_clearance, compiled_view=_compiled_view,
    # the hooks call the joint's methods, so that a subclass's own (a tube's record) answer
    energy=("contact", lambda joint, *a: joint.contact_energy(*a)), observe=_observe_clearance,
    contacts=lambda joint, *a: joint.output(*a),
    sections=lambda joint, *a: joint.section_records(*a),
    outlines=lambda joint, *a: joint.section_outlines(*a),
    hole_record=lambda joint: joint.hole_record(),
    follow=Following(off_plan=ERR_CONTACT_OFF_PLAN,
                     own=lambda joint, dofs: joint.window_owns(),
                     elements=_joint_elements, current=_current_windows))

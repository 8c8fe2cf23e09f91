"""Tendons: a wire routed through holes in a sequence of bodies, anchored at its end and pulled at
its start (the disks of a tendon-driven continuum robot; issue 52, item 4).

A :class:`Tendon` is a spec; :meth:`Model.add_tendon <flexmbs.model.Model.add_tendon>` expands it
into what a user would otherwise build by hand (``benchmarks/tendon_robot.py``):

- the wire, an ANCF cable named as the tendon, on the C¹ centreline start → holes → anchor
  (:meth:`Tendon.layout`): straight segments where the route is straight (a straight route is a
  straight line to rounding), else one cubic Hermite curve per segment through the route's points
  with the hole axes as tangents, so that the wire runs along every hole's axis;
- per hole k (1, 2, ...) a :class:`~flexmbs.contact.joint.SlidingClearanceJoint`
  ``<name>_hole<k>_<body>`` with a circular bore of radius ``radius + clearance`` along the route
  there (the direction from the previous route point to the next, the joint's ``axis``);
- ``<name>_anchor``: a spherical joint of the wire's last node to the anchor body;
- ``<name>_hold``: the start node held across the route's first direction (a node-to-ground
  joint, translation mask (0, 1, 1), its x axis the pull direction);
- ``<name>_tension``, a point load pulling the start node back along the route's first direction,
  or ``<name>_pull``, a slide driver of the hold (displacement control).

:class:`TendonParts` holds them and measures the wire's axial force N = EA(ε − ε0) in every
free span (actuator → hole 1, ..., last hole → anchor), and the pulled length (the probes
``tendon_tension`` and ``tendon_displacement``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from .beam_sections import BeamStiffness, CircularSection, Material
from .errors import ModelError
from .geometry.curves import Centerline, polyline
from .loads import TimeFunction, as_time_function

if TYPE_CHECKING:  # pragma: no cover
    from .contact.joint import SlidingClearanceJoint
    from .contact.laws import ForceLaw, Friction, RegularizedCoulomb
    from .model import Beam, ConstraintSpec, LoadSpec, Model, RigidBody

__all__ = ["Tendon", "TendonLayout", "TendonParts", "add_tendon", "sections_per_hole"]

#: turns of the route sharper than this at a hole are refused (degrees)
MAX_TURN = 90.0
#: the holes' default contact: a linear penalty of this stiffness [N/m] (the clearance joint's
#: default) ...
DEFAULT_STIFFNESS = 1e6
#: ... with a smooth onset over this fraction of the clearance (LinearPenalty(onset=...)): a
#: slack wire grazes its holes, and the plain linear law's jump of stiffness at first touch
#: keeps Newton cycling between contact sets (design notes, "Statics of tendon-routed
#: structures"); a loaded contact sits half of it (0.5 % of the clearance) deeper
ONSET = 1e-2


def _positive(name: str, key: str, value: Any, *, allow_zero: bool = False) -> float:
    ok = (isinstance(value, (int, float, np.floating)) and not isinstance(value, bool)
          and math.isfinite(value) and (value >= 0 if allow_zero else value > 0))
    if not ok:
        raise ModelError(f"tendon '{name}': {key} must be a finite number "
                         f"{'>=' if allow_zero else '>'} 0 (got {value!r})")
    return float(value)


@dataclass(frozen=True, kw_only=True, eq=False)
class Tendon:
    """A wire through holes in a sequence of bodies (module docstring); lengths in m.

    ``route``: ``(body, point)`` per hole in route order, the hole centre in body coordinates;
    ``anchor``: ``(body, point)``, the wire's end; ``lead``: free length before the first hole
    (the start lies on the line of the route's first segment, ``lead`` before the first hole).
    The wire: ``radius``, ``material`` (:class:`~flexmbs.beam_sections.Material`) or ``section``
    (:class:`~flexmbs.beam_sections.BeamStiffness`; ``radius`` is then its contact radius),
    ``element_length`` or ``elements`` (default: half the mean route segment), ``damping``
    [s] (stiffness-proportional, as :meth:`Model.add_beam`). The holes: ``clearance`` (hole
    radius − wire radius), ``hole_length``, ``hole_sections`` (default :func:`sections_per_hole`),
    ``contact`` (default a linear penalty of :data:`DEFAULT_STIFFNESS` with a smooth onset over
    :data:`ONSET` of the clearance) and ``friction`` (as :class:`SlidingClearanceJoint` takes
    it).
    Actuation, exactly one of ``tension`` [N] (number or time function: a force on the start
    node back along the route's first direction) and ``pulled_length`` [m] (time function: the
    start node driven back along it).

    Parameters
    ----------
    name : str
        Unique name; also the wire's beam name.
    route : sequence of (RigidBody, array_like)
        The holes in route order: body and hole centre in body coordinates [m].
    anchor : (RigidBody, array_like)
        The wire's end [m].
    lead : float
        Free length before the first hole [m].
    radius : float
        The wire's radius [m].
    clearance : float
        Hole radius − wire radius [m].
    material : Material, optional
        The wire's material (or ``section``).
    section : BeamStiffness, optional
        The wire's section resultants (or ``material``).
    element_length : float, optional
        Element length [m].
    elements : int, optional
        Number of elements, instead of ``element_length``.
    damping : float, default 0
        Stiffness-proportional damping [s].
    hole_length : float, default 1e-3
        Length of every hole [m].
    hole_sections : int, optional
        Sections of every hole.
    contact : LinearPenalty, Hertz, HuntCrossley or LankaraniNikravesh, optional
        Normal force law of the holes.
    friction : Friction, RegularizedCoulomb or float, optional
        Friction of the holes.
    tension : float or TimeFunction, optional
        Pulling force [N] (or ``pulled_length``).
    pulled_length : float or TimeFunction, optional
        Pulled length [m] (or ``tension``).
    """

    name: str
    route: Sequence[tuple[RigidBody, Any]]
    anchor: tuple[RigidBody, Any]
    lead: float
    radius: float
    clearance: float
    material: Material | None = None
    section: BeamStiffness | None = None
    element_length: float | None = None
    elements: int | None = None
    damping: float = 0.0
    hole_length: float = 1e-3
    hole_sections: int | None = None
    contact: ForceLaw | None = None
    friction: Friction | RegularizedCoulomb | float | None = None
    tension: TimeFunction | float | None = None
    pulled_length: TimeFunction | float | None = None

    def __post_init__(self) -> None:
        name = self.name
        if not isinstance(name, str) or not name:
            raise ModelError(f"Tendon: name must be a non-empty string (got {name!r})")
        if isinstance(self.route, (str, bytes)) or not isinstance(self.route, Sequence) \
                or len(self.route) < 1:
            raise ModelError(f"tendon '{name}': route must list at least one hole as (body, "
                             f"point in body coordinates) (got {self.route!r})")
        route = []
        for k, entry in enumerate(self.route):
            route.append(_body_point(name, f"route[{k}]", entry))
        object.__setattr__(self, "route", tuple(route))
        object.__setattr__(self, "anchor", _body_point(name, "anchor", self.anchor))
        for key in ("lead", "radius", "clearance", "hole_length"):
            object.__setattr__(self, key, _positive(name, key, getattr(self, key)))
        object.__setattr__(self, "damping", _positive(name, "damping", self.damping,
                                                      allow_zero=True))
        n = self.hole_sections
        if n is not None and (isinstance(n, bool) or not isinstance(n, (int, np.integer))
                              or n < 1):
            raise ModelError(f"tendon '{name}': hole_sections must be an integer >= 1 (got {n!r})")
        if (self.material is None) == (self.section is None):
            raise ModelError(f"tendon '{name}': give the wire's material=Material(E=..., rho=...) "
                             "or its section=BeamStiffness(...), one of the two")
        if self.element_length is not None and self.elements is not None:
            raise ModelError(f"tendon '{name}': give element_length or elements, not both")
        if self.element_length is not None:
            _positive(name, "element_length", self.element_length)
        if self.elements is not None and (isinstance(self.elements, bool) or not isinstance(
                self.elements, (int, np.integer)) or self.elements < 1):
            raise ModelError(f"tendon '{name}': elements must be an integer >= 1 "
                             f"(got {self.elements!r})")
        if (self.tension is None) == (self.pulled_length is None):
            raise ModelError(f"tendon '{name}': give exactly one of tension [N] (a force pulling "
                             "the start) and pulled_length [m] (the start's displacement)")

    def add_to(self, model: Model) -> TendonParts:
        """:func:`add_tendon` (what :meth:`Model.add_tendon` calls)."""
        return add_tendon(model, self)

    @property
    def hole_radius(self) -> float:
        """Radius of every hole: the wire's radius plus the clearance."""
        return self.radius + self.clearance

    def layout(self, model: Model, *, where: str | None = None) -> TendonLayout:
        """The route in the reference configuration, checked: every message names its key,
        after ``where`` (a scenario's key path, e.g. ``tendons[t2]``) or the tendon's name."""

        def key(k: str) -> str:
            return f"{where}.{k}" if where else f"tendon '{self.name}': {k}"

        bodies = [b for b, _ in self.route]
        for k, body in enumerate([*bodies, self.anchor[0]]):
            if not any(body is b for b in model.bodies):
                which = f"route[{k}]" if k < len(bodies) else "anchor"
                raise ModelError(f"{key(which + '.body')}: {body!r} is not a rigid body of this "
                                 "model (add it first)")
        for k, body in enumerate(bodies):
            first = next(i for i, b in enumerate(bodies) if b is body)
            if first < k:
                raise ModelError(f"{key(f'route[{k}].body')}: body '{body.name}' is visited "
                                 f"twice (route[{first}] and route[{k}]); a tendon passes each "
                                 "body once")
        for k, (body, point) in enumerate(self.route):
            _check_inside(body, point, self.hole_radius, key(f"route[{k}].point"))
        holes = np.array([b.pose.position + b.pose.rotation @ p for b, p in self.route])
        anchor = self.anchor[0].pose.position + self.anchor[0].pose.rotation @ self.anchor[1]
        ends = np.vstack([holes, anchor[None]])
        gaps = np.linalg.norm(np.diff(ends, axis=0), axis=1)
        scale = max(1.0, float(np.abs(ends).max()))
        for k, gap in enumerate(gaps):
            if not gap > 1e-12 * scale:
                which = f"route[{k + 1}].point" if k + 1 < len(holes) else "anchor.point"
                raise ModelError(f"{key(which)}: coincides with route[{k}] (global "
                                 f"{ends[k].tolist()}); consecutive points of a route must differ")
        direction = (ends[1] - ends[0]) / gaps[0]
        start = holes[0] - self.lead * direction
        points = np.vstack([start[None], ends])            # start, holes, anchor
        chords = np.diff(points, axis=0)
        lengths = np.linalg.norm(chords, axis=1)
        units = chords / lengths[:, None]
        n = len(holes)
        for k in range(n):                                   # the turn at hole k
            turn = math.degrees(math.acos(min(1.0, max(-1.0, float(units[k] @ units[k + 1])))))
            if turn < MAX_TURN:
                continue
            if k == n - 1:
                behind = -float((anchor - holes[k]) @ units[k])
                raise ModelError(f"{key('anchor.point')}: the anchor is {behind:.4g} m behind "
                                 f"the last hole (route[{k}], body '{bodies[k].name}') along the "
                                 "route's last direction; anchor the tendon beyond it")
            raise ModelError(f"{key(f'route[{k}].point')}: the route turns by {turn:.1f}° at "
                             f"this hole (body '{bodies[k].name}'), at most {MAX_TURN:g}° can "
                             "pass a hole; reorder the route or add holes between")
        axes = points[2:] - points[:-2]
        axes /= np.linalg.norm(axes, axis=1)[:, None]
        self._check_room(points, axes, key)
        tangents = np.vstack([direction[None], axes, units[-1][None]])
        straight = bool(np.all(np.abs(np.cross(points - start, direction)).max(axis=1)
                               <= 1e-12 * max(1.0, float(lengths.sum()))))
        coarse = None if straight else polyline(points, tangents)
        seg = lengths if coarse is None else np.asarray(coarse.lengths, float)
        counts = self._counts(seg, key)
        if coarse is None:
            s = np.concatenate([[0.0], np.cumsum(seg)])
            nodes = np.concatenate([np.linspace(s[i], s[i + 1], m + 1)[:-1]
                                    for i, m in enumerate(counts)] + [s[-1:]])
            centerline = Centerline(start + nodes[:, None] * direction,
                                    np.tile(direction, (nodes.size, 1)), np.diff(nodes))
        else:
            self._check_holes(coarse, points, axes, key)
            centerline = _sampled(coarse, counts, points, tangents)
        return TendonLayout(start=start, holes=holes, anchor=anchor, axes=axes,
                            direction=direction, centerline=centerline)

    def _counts(self, seg: np.ndarray, key: Callable[[str], str]) -> np.ndarray:
        """Elements of every route segment (start → hole 1, ..., last hole → anchor)."""
        if self.elements is not None:
            total = int(self.elements)
            if total < seg.size:
                raise ModelError(f"{key('elements')}: {total} is fewer than the route's "
                                 f"{seg.size} segments (start, holes, anchor); give at least "
                                 f"{seg.size}")
            share = total * seg / seg.sum()
            counts = np.maximum(1, np.floor(share)).astype(int)
            while counts.sum() < total:
                counts[int(np.argmax(share - counts))] += 1
            while counts.sum() > total:
                counts[int(np.argmax(np.where(counts > 1, counts - share, -np.inf)))] -= 1
            return counts
        h = self.element_length if self.element_length is not None else 0.5 * float(seg.mean())
        return np.maximum(1, np.ceil(seg / h - 1e-9)).astype(int)

    def _check_room(self, points: np.ndarray, axes: np.ndarray,
                    key: Callable[[str], str]) -> None:
        """Every hole must end before the route's neighbouring points (along its axis): the
        wire crosses all of a hole's sections."""
        half = 0.5 * self.hole_length
        last = len(axes) - 1
        for k, a in enumerate(axes):
            back = float((points[k + 1] - points[k]) @ a)
            ahead = float((points[k + 2] - points[k + 1]) @ a)
            if k == 0 and not back > half:
                raise ModelError(f"{key('lead')}: {self.lead:g} m puts the wire's start inside "
                                 f"the first hole (half its length {half:g} m); give lead > "
                                 "hole_length/2")
            if k == last and not ahead > half:
                raise ModelError(f"{key('anchor.point')}: the anchor is {ahead:.4g} m beyond the "
                                 f"last hole's centre (route[{k}]), inside the hole (half its "
                                 f"length {half:g} m); anchor the tendon beyond the hole")
            if not min(back, ahead) > half:
                near = k - 1 if back <= half else k + 1
                raise ModelError(f"{key('hole_length')}: {self.hole_length:g} m: the hole of "
                                 f"route[{k}] reaches past route[{near}] "
                                 f"({min(back, ahead):.4g} m from it along its axis); "
                                 "shorten the holes")

    def _check_holes(self, coarse: Centerline, points: np.ndarray, axes: np.ndarray,
                     key: Callable[[str], str]) -> None:
        """The curved centreline must stay within the clearance of every hole's axis over the
        hole's length (it passes each hole's centre along its axis)."""
        s = np.concatenate([[0.0], np.cumsum(coarse.lengths)])
        half = 0.5 * self.hole_length
        for k, a in enumerate(axes):
            j = k + 1                                   # the hole's point in ``points``
            for zeta, lo, hi in ((-half, s[j - 1], s[j]), (half, s[j], s[j + 1])):
                a_, b_ = lo, hi                         # bisection on the axial station
                for _ in range(50):
                    mid = 0.5 * (a_ + b_)
                    ahead = (coarse.frame_at(mid)[0] - points[j]) @ a > zeta
                    a_, b_ = (a_, mid) if ahead else (mid, b_)
                off = coarse.frame_at(0.5 * (a_ + b_))[0] - points[j]
                off = float(np.linalg.norm(off - (off @ a) * a))
                if off >= self.clearance:
                    raise ModelError(f"{key(f'route[{k}].point')}: the route bends so much at "
                                     f"this hole that the wire leaves its axis by {off:.3g} m "
                                     f"within its length, more than the clearance "
                                     f"{self.clearance:.3g} m; straighten the route, shorten "
                                     "hole_length or widen the clearance")


class TendonLayout(NamedTuple):
    """A tendon's route in the reference configuration (global coordinates)."""

    start: np.ndarray        # the actuated start
    holes: np.ndarray        # (n, 3) hole centres
    anchor: np.ndarray       # the anchor point
    axes: np.ndarray         # (n, 3) unit hole axes: previous route point to the next
    direction: np.ndarray    # unit direction of the route's first segment (into the first hole)
    centerline: Centerline   # the wire's reference centreline


def _body_point(name: str, key: str, entry: Any) -> tuple[RigidBody, np.ndarray]:
    from .model import RigidBody

    point = None
    if isinstance(entry, (tuple, list)) and len(entry) == 2 and isinstance(entry[0], RigidBody):
        try:
            point = np.asarray(entry[1], dtype=float).reshape(-1)
        except (TypeError, ValueError):
            point = None
    if point is None or point.shape != (3,) or not np.all(np.isfinite(point)):
        raise ModelError(f"tendon '{name}': {key} must be (body, point): a RigidBody and 3 "
                         f"finite numbers in its coordinates (got {entry!r})")
    return entry[0], point


def _check_inside(body: RigidBody, point: np.ndarray, hole_radius: float, key: str) -> None:
    """A hole in a cylinder (axis body x) must lie within its radius."""
    shape = body.shape or {}
    if shape.get("type") != "cylinder" or "radius" not in shape:
        return
    outer = float(shape["radius"])
    reach = math.hypot(float(point[1]), float(point[2])) + hole_radius
    if reach > outer:
        raise ModelError(f"{key}: the hole (radius {hole_radius:.4g} m) reaches {reach - outer:.3g} "
                         f"m beyond body '{body.name}' (a cylinder of radius {outer:g} m, the "
                         f"hole's centre {reach - hole_radius:.4g} m from its axis); move the "
                         "point inwards")


def _sampled(coarse: Centerline, counts: np.ndarray, points: np.ndarray,
             tangents: np.ndarray) -> Centerline:
    """Nodes on the route's C¹ curve ``coarse`` (one cubic per segment): ``counts[i]`` elements
    of equal steps on segment i; the route's ``points`` with their ``tangents`` are nodes."""
    s = np.concatenate([[0.0], np.cumsum(coarse.lengths)])
    nodes, slopes = [], []
    for i, m in enumerate(counts):
        nodes.append(points[i])
        slopes.append(tangents[i])
        for j in range(1, m):
            x, t = coarse.frame_at(float(s[i] + coarse.lengths[i] * j / m))
            nodes.append(x)
            slopes.append(t)
    nodes.append(points[-1])
    slopes.append(tangents[-1])
    return polyline(np.array(nodes), np.array(slopes))


@dataclass(frozen=True, eq=False)
class TendonParts:
    """What :meth:`Model.add_tendon <flexmbs.model.Model.add_tendon>` built for ``tendon``: the
    wire ``beam``, its clearance joints ``holes`` (route order), the ``anchor`` (spherical joint),
    the ``hold`` of its start, the ``actuator`` (the tension's point load or the pull's driver),
    the ``start`` point and the unit ``pull`` direction (back along the route's first segment).

    Parameters
    ----------
    tendon : Tendon
        The tendon.
    beam : Beam
        The wire.
    holes : tuple of SlidingClearanceJoint
        The clearance joints, in route order.
    anchor : ConstraintSpec
        The spherical joint at the wire's end.
    hold : ConstraintSpec
        The joint holding the start across the pull.
    actuator : LoadSpec or ConstraintSpec
        The tension's point load or the pull's driver.
    start : ndarray, shape (3,)
        The wire's start point [m].
    pull : ndarray, shape (3,)
        Unit pull direction.
    """

    tendon: Tendon
    beam: Beam
    holes: tuple[SlidingClearanceJoint, ...]
    anchor: ConstraintSpec
    hold: ConstraintSpec
    actuator: LoadSpec | ConstraintSpec
    start: np.ndarray
    pull: np.ndarray

    @property
    def name(self) -> str:
        return self.tendon.name

    def span_stations(self, q: np.ndarray) -> np.ndarray:
        """Arc lengths [m] (reference, from the start) of the middle of every free span of the
        wire: start → hole 1, hole k → hole k + 1, ..., last hole → anchor (n + 1 values), the
        holes where their clearance joints are on the wire now (slide coordinates)."""
        q = np.asarray(q, dtype=float)
        s = ([0.0] + [j.slide_coordinate(q) for j in self.holes]
             + [float(np.sum(self.beam.centerline.lengths))])
        return 0.5 * (np.asarray(s[:-1]) + np.asarray(s[1:]))

    def axial_forces(self, asm: Any, q: np.ndarray) -> np.ndarray:
        """The wire's tension along the route: its axial force N = EA(ε − ε0) [N] in the middle
        of every free span (:meth:`span_stations`; span 0 is the actuator's, span k follows
        hole k), from the element's own output field ``axial_strain`` and the section data
        the assembly packed (elastic part: no damping force). In the middle of a span, not
        at a hole: a hole presses its element at one point, and a cubic element's axial strain
        there is off by the bending it cannot follow (on the 4-disk robot with 17 mm elements,
        35 % at a hole, 0.4 % in the spans; design notes, "Statics of tendon-routed
        structures"). The drop across hole k is ``N[k - 1] − N[k]``."""
        beam = self.beam
        q = np.asarray(q, dtype=float)
        where = [beam.locate(float(x)) for x in self.span_stations(q)]
        elements = np.array([e for e, _ in where])
        xi = np.array([x for _, x in where])
        etype, rest, options = asm.beam_rest(beam, elements)
        fields = etype.output_fields(q[asm.element_dofs(beam)[elements]], rest, options, xi)
        i = np.arange(elements.size)
        eps = np.asarray(fields["axial_strain"], dtype=float)[i, i]   # element i at xi[i]
        gi, sl = asm.beam_slices[id(beam)]
        props = asm.groups[gi].props
        at = sl.start + elements
        return np.asarray(props.axial_stiffness, float)[at] * (
            eps - np.asarray(props.reference_axial_strain, float)[at])

    def pulled(self, asm: Any, q: np.ndarray) -> float:
        """How far the start node has moved along :attr:`pull` [m] (positive: pulled)."""
        d = asm.node_dofs(self.beam.first_node)[:3]
        return float((np.asarray(q, float)[d] - np.asarray(asm.q_ref, float)[d]) @ self.pull)


def sections_per_hole(hole_length: float, element_length: float) -> int:
    """Contact sections of a hole ``hole_length`` long on a wire of elements at least
    ``element_length`` long: one (at the hole's centre) where the hole is shorter than an
    element, else about one per element length, both end faces included.

    Several sections within one element support one cubic at nearly collinear stations: which
    of them carries the wire then turns on displacements of the penalty's order, and Newton's
    iterates jump between those contact sets. On the 10-disk robot with one taut tendon
    (``benchmarks/tendon_robot.py``, 1 mm holes, 7.4 mm elements) statics took 124 load
    increments (1 091 Newton iterations) with 3 sections, 225 (2 730) with 2, and 12 (146)
    with 1, to the same tip position within 0.02 % (design notes, "Statics of
    tendon-routed structures")."""
    if hole_length < element_length:
        return 1
    return int(math.ceil(hole_length / element_length - 1e-9)) + 1


def add_tendon(model: Model, tendon: Tendon) -> TendonParts:
    """Expand ``tendon`` into ``model`` (module docstring); nothing is added when a check
    fails. Prefer :meth:`Model.add_tendon <flexmbs.model.Model.add_tendon>`."""
    from .contact.bores import CircleHole
    from .contact.joint import SlidingClearanceJoint
    from .contact.laws import LinearPenalty
    from .model import GROUND

    if not isinstance(tendon, Tendon):
        raise ModelError(f"add_tendon: expected a flexmbs.Tendon (got {tendon!r})")
    lay = tendon.layout(model)
    name = tendon.name
    holes = [f"{name}_hole{k + 1}_{body.name}" for k, (body, _) in enumerate(tendon.route)]
    actuator = f"{name}_tension" if tendon.tension is not None else f"{name}_pull"
    wanted = {"beams and rigid bodies": [name], "joints": holes,
              "constraints": [f"{name}_anchor", f"{name}_hold"]
              + ([actuator] if tendon.tension is None else []),
              "loads": [actuator] if tendon.tension is not None else []}
    used = {"beams and rigid bodies": {b.name for b in model.beams} | {b.name for b in model.bodies},
            "joints": {j.name for j in model.interactions},
            "constraints": {c.name for c in model.constraints},
            "loads": {ld.name for ld in model.loads}}
    for kind, names in wanted.items():
        taken = [x for x in names if x in used[kind]]
        if taken:
            raise ModelError(f"tendon '{name}': the name '{taken[0]}' of its parts is already "
                             f"used by the model's {kind}; rename the tendon")

    if tendon.material is not None:
        beam = model.add_beam(lay.centerline, section=CircularSection(tendon.radius),
                              material=tendon.material, damping=tendon.damping, name=name)
    else:
        assert tendon.section is not None
        beam = model.add_beam(lay.centerline, section=tendon.section, damping=tendon.damping,
                              name=name)
    contact = tendon.contact
    if contact is None:
        contact = LinearPenalty(stiffness=DEFAULT_STIFFNESS, onset=ONSET * tendon.clearance)
    sections = tendon.hole_sections
    if sections is None:
        sections = sections_per_hole(tendon.hole_length,
                                     float(np.min(lay.centerline.lengths)))
    joints = []
    for k, (body, point) in enumerate(tendon.route):
        joints.append(model.add_joint(SlidingClearanceJoint(
            beam, body, hole=CircleHole(tendon.hole_radius, tendon.hole_length, int(sections)),
            hole_point=point, axis=body.pose.rotation.T @ lay.axes[k], contact=contact,
            friction=tendon.friction, beam_radius=tendon.radius, name=holes[k])))
    anchor = model.spherical(beam.last_node, tendon.anchor[0], point=lay.anchor,
                             name=f"{name}_anchor")
    pull = -lay.direction
    hold = model.joint(beam.first_node, GROUND, point=lay.start, axis=pull, translation=(0, 1, 1),
                       name=f"{name}_hold")
    act: LoadSpec | ConstraintSpec
    if tendon.tension is not None:
        if isinstance(tendon.tension, (int, float, np.floating)) and not isinstance(
                tendon.tension, bool):
            act = model.add_point_load(beam.first_node, float(tendon.tension) * pull,
                                       name=actuator)
        else:
            act = model.add_point_load(beam.first_node, pull,
                                       function=as_time_function(tendon.tension), name=actuator)
    else:
        act = model.add_driver(hold, as_time_function(tendon.pulled_length), motion="slide",
                               name=actuator)
    return TendonParts(tendon=tendon, beam=beam, holes=tuple(joints), anchor=anchor, hold=hold,
                       actuator=act, start=lay.start, pull=pull)

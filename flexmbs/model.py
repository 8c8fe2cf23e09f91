"""Model: a plain container of beams, rigid bodies, constraints and loads.

The model holds no solver state and no DOF numbering: :class:`flexmbs.assembly.Assembly`
derives the DOF map from it. Objects are identified by name; every name is unique per kind.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from .beam_sections import BeamStiffness, CircularSection, Material
from .elements import rigid_body as rb
from .elements.ancf_cable import CableOptions
from .elements.layout import ElementLayout, ElementType, get_element_type
from .elements.rigid_body import quaternion_from_matrix, rotation_matrix
from .errors import ModelError
from .geometry.curves import Centerline
from .loads import TimeFunction, as_time_function
from .springs import SpringDamper, check_table

if TYPE_CHECKING:  # pragma: no cover
    from .constraints.interaction import Interaction

ArrayLike3 = Sequence[float] | np.ndarray


def _vec3(x: ArrayLike3, what: str) -> np.ndarray:
    a = np.asarray(x, dtype=float)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise ModelError(f"{what} must be 3 finite numbers (got {x!r})")
    return a


def _unit(x: ArrayLike3, what: str) -> np.ndarray:
    a = _vec3(x, what)
    n = np.linalg.norm(a)
    if n == 0:
        raise ModelError(f"{what} must not be the zero vector")
    return a / n


@dataclass(frozen=True)
class Pose:
    """Position and orientation (rotation matrix, columns = body axes in global components).

    Parameters
    ----------
    position : ndarray, shape (3,)
        Position [m].
    rotation : ndarray, shape (3, 3), default identity
        Rotation matrix (columns: the body axes in global components).
    """

    position: np.ndarray
    rotation: np.ndarray = field(default_factory=lambda: np.eye(3))

    def __post_init__(self) -> None:
        R = np.asarray(self.rotation, dtype=float)
        if R.shape != (3, 3) or not np.all(np.isfinite(R)):
            raise ModelError(f"Pose rotation must be a finite 3x3 matrix (got shape {R.shape})")
        object.__setattr__(self, "position", _vec3(self.position, "Pose position"))
        object.__setattr__(self, "rotation", R)

    @property
    def quaternion(self) -> np.ndarray:
        """Unit Euler parameters ``[e0, e1, e2, e3]`` with ``e0 >= 0`` (rigid_body's Shepperd
        conversion, normalised here so that a slightly non-orthonormal rotation still gives
        ``|p| = 1``)."""
        p = quaternion_from_matrix(self.rotation)
        return p / np.linalg.norm(p)

    def shifted(self, offset: ArrayLike3, *, local: bool = False) -> Pose:
        """Pose moved by ``offset`` (global components, or body components with ``local=True``)."""
        d = _vec3(offset, "offset")
        if local:
            d = self.rotation @ d
        return Pose(self.position + d, self.rotation)

    @staticmethod
    def from_quaternion(position: ArrayLike3, quaternion: ArrayLike3) -> Pose:
        q = np.asarray(quaternion, float)
        if q.shape != (4,) or not np.linalg.norm(q) > 0:
            raise ModelError(f"quaternion must be 4 numbers [w, x, y, z], not zero (got {quaternion!r})")
        return Pose(_vec3(position, "position"), rotation_matrix(q / np.linalg.norm(q)))


class Ground:
    """The inertial frame (no coordinates)."""

    name = "ground"

    def __repr__(self) -> str:
        return "GROUND"


GROUND = Ground()


@dataclass(frozen=True, eq=False)
class Node:
    """A node of a beam (``beam.first_node``, ``beam.last_node``, ``beam.node(i)``).

    Parameters
    ----------
    beam : Beam
        The beam.
    index : int
        The node's index along the beam (0 is the first node).
    """

    beam: Beam
    index: int

    @property
    def name(self) -> str:
        return f"{self.beam.name}.node[{self.index}]"

    @property
    def position(self) -> np.ndarray:
        return self.beam.centerline.points[self.index]

    @property
    def tangent(self) -> np.ndarray:
        return self.beam.centerline.tangents[self.index]


class Beam:
    """A beam of elements of type ``element`` (a registered
    :class:`~flexmbs.elements.layout.ElementLayout`, default the 12-DOF ANCF cable) on a
    stress-free reference ``centerline``.

    Made by :meth:`Model.add_beam`, not by hand.

    Parameters
    ----------
    name : str
        Unique name in the model.
    centerline : Centerline
        The stress-free reference centreline (nodes, tangents, element lengths).
    stiffness : BeamStiffness
        Section resultants (EA, EI, ρA, ...).
    options : CableOptions or None
        The cable's formulation options.
    damping : float
        Stiffness-proportional damping [s].
    reference_axial_strain : float
        ε0 of the normal force ``N = EA (ε − ε0)`` (ε0 < 0: pretension).
    element : str, default "ancf_cable"
        Element type: ``"ancf_cable"`` or ``"ancf_rod14"``.
    stress_free : Centerline or None
        The stress-free shape when it is not ``centerline`` (which is then only where the beam
        starts): the same elements, node for node.
    """

    def __init__(self, name: str, centerline: Centerline, stiffness: BeamStiffness, *,
                 options: CableOptions | None, damping: float, reference_axial_strain: float,
                 element: str = "ancf_cable", stress_free: Centerline | None = None) -> None:
        self.name = name
        self.centerline = centerline
        self.stress_free = stress_free
        self.stiffness = stiffness
        self.options = options
        self.damping = float(damping)
        self.reference_axial_strain = float(reference_axial_strain)
        self.element = element

    @property
    def element_type(self) -> ElementType:
        """Its registered element type (layout and functions)."""
        return get_element_type(self.element)

    @property
    def layout(self) -> ElementLayout:
        """The declared layout of its elements (nodal coordinates, sizes)."""
        return self.element_type.layout

    @property
    def n_elem(self) -> int:
        return int(self.centerline.n_elem)

    @property
    def n_nodes(self) -> int:
        return int(self.centerline.n_nodes)

    @property
    def closed(self) -> bool:
        return bool(self.centerline.closed)

    @property
    def length(self) -> float:
        return float(np.sum(self.centerline.lengths))

    @property
    def length_tolerance(self) -> float:
        """How far past an end an arc length still counts as that end: the curve's own
        discretisation uncertainty, the difference between its element lengths and the chords
        of its nodes (a quarter circle sampled by 129 points: 1e-5), at most 1e-3 of the
        shortest element and at least 1e-12 of the length."""
        cl = self.centerline
        pts = np.asarray(cl.points, float)
        lengths = np.asarray(cl.lengths, float)
        chords = np.linalg.norm(np.diff(pts, axis=0), axis=1)
        if cl.closed:
            chords = np.append(chords, np.linalg.norm(pts[0] - pts[-1]))
        total = float(np.sum(lengths))
        spread = abs(total - float(np.sum(chords[: lengths.size])))
        return max(1e-12 * total, min(spread, 1e-3 * float(lengths.min())))

    def check_arc_length(self, s: float) -> float:
        """``s`` within ``[0, length]`` up to :attr:`length_tolerance`, clamped; else
        ModelError (lengths printed with all their digits)."""
        tol = self.length_tolerance
        if not -tol <= s <= self.length + tol:
            raise ModelError(f"s = {s!r} is outside beam '{self.name}' (0 <= s <= "
                             f"{self.length!r}, tolerance {tol:.3g})")
        return min(max(float(s), 0.0), self.length)

    @property
    def radius(self) -> float | None:
        return self.stiffness.radius

    def node(self, index: int | Literal["first", "last"]) -> Node:
        if index == "first":
            index = 0
        elif index == "last":
            index = self.n_nodes - 1
        if not isinstance(index, (int, np.integer)) or not -self.n_nodes <= index < self.n_nodes:
            raise ModelError(
                f"beam '{self.name}' has nodes 0..{self.n_nodes - 1}; node {index!r} does not exist"
            )
        return Node(self, int(index) % self.n_nodes)

    @property
    def first_node(self) -> Node:
        return self.node(0)

    @property
    def last_node(self) -> Node:
        return self.node(self.n_nodes - 1)

    @property
    def connectivity(self) -> np.ndarray:
        """(n_elem, 2) node indices of each element."""
        i = np.arange(self.n_elem)
        return np.stack([i, (i + 1) % self.n_nodes], axis=1)

    def locate(self, s: float) -> tuple[int, float]:
        """Element index and local xi in [0, 1] of reference arc length ``s`` from the first node."""
        return self.centerline.locate(self.check_arc_length(s))

    def frame_at(self, s: float, *, up: ArrayLike3 | None = None) -> Pose:
        """Reference pose at arc length ``s``: x axis along the tangent, y/z completing a frame.

        ``up`` (optional) fixes the body z axis direction (projected normal to the tangent).
        """
        self.locate(s)
        pos, t = self.centerline.frame_at(s)
        t = t / np.linalg.norm(t)
        if up is None:
            up = np.array([0.0, 0.0, 1.0]) if abs(t[2]) < 0.9 else np.array([0.0, 1.0, 0.0])
        up = np.asarray(up, float)
        if not np.all(np.isfinite(up)):
            raise ModelError(f"frame_at: 'up' must be finite (got {up.tolist()})")
        if not np.any(up):
            raise ModelError("frame_at: 'up' is zero ([0, 0, 0]); give a direction across the "
                             "beam, e.g. [0, 0, 1]")
        z = up - np.dot(up, t) * t
        if np.linalg.norm(z) < 1e-9 * np.linalg.norm(up):
            raise ModelError("frame_at: 'up' is parallel to the beam tangent")
        z /= np.linalg.norm(z)
        y = np.cross(z, t)
        return Pose(np.asarray(pos, float), np.column_stack([t, y, z]))

    def __repr__(self) -> str:
        return f"Beam({self.name!r}, elements={self.n_elem}, length={self.length:.6g})"


class RigidBody:
    """A rigid body in Cartesian coordinates with Euler parameters (Haug 1989).

    Made by :meth:`Model.add_rigid_body`, not by hand.

    Parameters
    ----------
    name : str
        Unique name in the model.
    mass : float
        Mass [kg].
    inertia : ndarray, shape (3, 3)
        Inertia tensor about the centre of mass, body frame [kg m^2].
    pose : Pose
        Initial position of the centre of mass and orientation.
    velocity : ndarray, shape (3,)
        Initial velocity of the centre of mass [m/s].
    angular_velocity : ndarray, shape (3,)
        Initial angular velocity, global components [rad/s].
    shape : dict, optional
        Output geometry (``{"type": "cylinder", ...}``, ``"box"``, ``"mesh"``); default a small
        box sized from the inertia.
    """

    def __init__(self, name: str, mass: float, inertia: np.ndarray, pose: Pose,
                 velocity: np.ndarray, angular_velocity: np.ndarray,
                 shape: dict | None = None) -> None:
        self.name = name
        #: output geometry, e.g. {"type": "cylinder", "radius": .., "length": .., "inner_radius": ..}
        #: (axis = body x), {"type": "box", "size": [lx, ly, lz]}, {"type": "mesh", "file": ..};
        #: None: a small box sized from the inertia
        self.shape = shape
        self.mass = float(mass)
        self.inertia = inertia
        self.pose = pose
        self.velocity = velocity
        self.angular_velocity = angular_velocity

    def __repr__(self) -> str:
        return f"RigidBody({self.name!r}, mass={self.mass:.6g})"


Target = Node | RigidBody | Ground


@dataclass(frozen=True)
class ConstraintSpec:
    """What the user asked for; the assembly turns it into equations with DOF indices."""

    kind: str
    name: str
    a: Target
    b: Target = GROUND
    point_a: np.ndarray | None = None   # body frame of a (rigid) / global (ground)
    point_b: np.ndarray | None = None
    frame_a: np.ndarray | None = None   # joint frame, columns in body coordinates of a
    frame_b: np.ndarray | None = None
    translation: tuple[int, int, int] = (1, 1, 1)
    rotation: tuple[int, int, int] = (0, 0, 0)
    components: tuple[int, ...] = ()
    function: TimeFunction | None = None
    motion: str = ""                    # drivers: "rotation" or "slide"


@dataclass(frozen=True)
class LoadSpec:
    kind: Literal["point", "distributed", "torque"]
    name: str
    target: Node | RigidBody | Beam | tuple[Beam, float]
    force: np.ndarray
    moment: np.ndarray | None
    point: np.ndarray | None          # body-frame point for rigid-body point loads
    function: TimeFunction


def _stress_free_shape(shape: Centerline, centerline: Centerline, element: str,
                       elements: int | None) -> Centerline:
    """``add_beam``'s ``stress_free``, checked against the starting ``centerline``: a
    Centerline of the same elements (resampled to ``elements`` when given), lengths and
    closure."""
    if not isinstance(shape, Centerline):
        raise ModelError("add_beam: stress_free must be a flexmbs Centerline (use fm.line, "
                         "fm.arc, fm.polyline or fm.read_curve)")
    if element != "ancf_cable":
        raise ModelError(f"add_beam: stress_free is for element 'ancf_cable'; element {element!r} "
                         "takes its twist charts from one shape: give its stress-free shape as "
                         "the centreline")
    if elements is not None and elements != shape.n_elem:
        from .geometry.curves import polyline

        shape = polyline(shape.points, shape.tangents, closed=shape.closed, elements=int(elements))
    if shape.n_elem != centerline.n_elem or shape.closed != centerline.closed:
        raise ModelError(f"add_beam: stress_free has {shape.n_elem} elements"
                         f"{' (closed)' if shape.closed else ''}, the centreline "
                         f"{centerline.n_elem}{' (closed)' if centerline.closed else ''}: give "
                         "both the same elements (or elements = <n> to resample both)")
    a, b = np.asarray(shape.lengths, float), np.asarray(centerline.lengths, float)
    worst = int(np.argmax(np.abs(a - b) / b))
    if abs(a[worst] - b[worst]) > 1e-6 * b[worst]:
        raise ModelError(f"add_beam: stress_free element {worst} is {a[worst]:.6g} m long, the "
                         f"centreline's {b[worst]:.6g} m: the stress-free shape must have the "
                         "starting shape's element lengths (use reference_axial_strain for a "
                         "stretch)")
    return shape


class Model:
    """Container of the mechanical system.

    Beams, rigid bodies, constraints, joints, loads and force elements are added by its
    ``add_*`` methods and constraint methods (``clamp``, ``pin``, ``spherical``, ...); solvers
    take the model (:func:`simulate`, :func:`solve_static`, :func:`modes`).

    Parameters
    ----------
    gravity : array_like of 3 floats, default (0, 0, 0)
        Gravitational acceleration [m/s^2].
    name : str, default "model"
        The model's name (the output files' name by default).
    """

    def __init__(self, *, gravity: ArrayLike3 = (0.0, 0.0, 0.0), name: str = "model") -> None:
        self.name = name
        self.gravity = _vec3(gravity, "gravity")
        self.beams: list[Beam] = []
        self.bodies: list[RigidBody] = []
        self.constraints: list[ConstraintSpec] = []
        self.loads: list[LoadSpec] = []
        self.interactions: list[Interaction] = []
        self.springs: list[SpringDamper] = []
        self._names: dict[str, set[str]] = {}

    # ------------------------------------------------------------------ naming
    _KIND = {"beam": "beam", "body": "rigid body", "joint": "joint", "load": "load",
             "spring": "spring"}
    #: kinds that share one namespace: a beam and a rigid body are both "parts" (output
    #: blocks, probes and the section view name them without saying which kind)
    _NAMESPACE = {"beam": "part", "rigid body": "part"}

    def _unique(self, name: str | None, prefix: str) -> str:
        """A name unique among objects of the same kind (beams, bodies, joints, loads,
        constraints); ``prefix`` also numbers unnamed objects."""
        kind = self._KIND.get(prefix, "constraint")
        used = self._names.setdefault(self._NAMESPACE.get(kind, kind), set())
        if name is None:
            i = 1
            while f"{prefix}{i}" in used:
                i += 1
            name = f"{prefix}{i}"
        if not isinstance(name, str) or not name:
            raise ModelError(f"name must be a non-empty string (got {name!r})")
        if not name.isprintable():
            raise ModelError(f"name {name!r} contains a control character (NUL, newline, tab...); "
                             "names appear in file names and tables: use printable characters")
        if name in used:
            what = ("beams and rigid bodies" if kind in self._NAMESPACE else f"{kind}s")
            raise ModelError(f"the name '{name}' is already used in this model; names of "
                             f"{what} must be unique")
        used.add(name)
        return name

    def beam(self, name: str) -> Beam:
        for b in self.beams:
            if b.name == name:
                return b
        raise ModelError(f"no beam named '{name}' (beams: {[b.name for b in self.beams]})")

    def body(self, name: str) -> RigidBody:
        for b in self.bodies:
            if b.name == name:
                return b
        raise ModelError(f"no rigid body named '{name}' (bodies: {[b.name for b in self.bodies]})")

    # ------------------------------------------------------------------ beams and bodies
    def add_beam(self, centerline: Centerline, *, section: CircularSection | BeamStiffness,
                 material: Material | None = None, name: str | None = None,
                 options: CableOptions | None = None, damping: float = 0.0,
                 reference_axial_strain: float = 0.0, elements: int | None = None,
                 element: str = "ancf_cable", stress_free: Centerline | None = None) -> Beam:
        """Add a beam of ``element``s on ``centerline`` (stress-free reference): the 12-DOF
        ``"ancf_cable"`` (default) or the torsion-capable 14-DOF ``"ancf_rod14"``.

        ``stress_free``: the beam starts on ``centerline`` but its stress-free shape is this
        one (a pre-curved tube inserted straight, a bent wire threaded through a tube): the
        same number of elements of the same lengths (resampled with ``elements`` too), its
        nodes matched in order. The cable only: the rod's twist charts are taken from one
        shape.

        ``section`` is a :class:`CircularSection` (with ``material``) or explicit
        :class:`BeamStiffness`. ``damping`` is stiffness-proportional [s]: axial and bending
        damping coefficients are ``damping*EA`` and ``damping*EI``. ``reference_axial_strain``
        eps0 gives the normal force ``N = EA (eps - eps0)`` (eps0 < 0: pretension).
        ``elements`` resamples the centreline to that many equal elements. ``options``
        (:class:`CableOptions`) are the cable's; the rod has none. The rod needs a torsional
        stiffness (a :class:`CircularSection` with its material gives ``G J_p``).
        """
        etype = get_element_type(element)
        if options is not None and element != "ancf_cable":
            raise ModelError(f"add_beam: options (CableOptions) belong to element 'ancf_cable'; "
                             f"element {element!r} takes none")
        if not isinstance(centerline, Centerline):
            raise ModelError("add_beam: centerline must be a flexmbs Centerline (use fm.line, "
                             "fm.arc, fm.polyline or fm.read_curve)")
        if elements is not None and elements != centerline.n_elem:
            from .geometry.curves import polyline

            pts = centerline.points
            tans = centerline.tangents
            centerline = polyline(pts, tans, closed=centerline.closed, elements=int(elements))
        if isinstance(section, CircularSection):
            if material is None:
                raise ModelError("add_beam: a CircularSection needs a material=Material(E=..., rho=...)")
            stiffness = BeamStiffness.from_section(section, material)
        elif isinstance(section, BeamStiffness):
            stiffness = section
        else:
            raise ModelError("add_beam: section must be CircularSection or BeamStiffness")
        if damping < 0:
            raise ModelError(f"add_beam: damping must be >= 0 (got {damping})")
        if etype.layout.twist is not None and stiffness.torsional_stiffness is None:
            raise ModelError(f"add_beam: element {element!r} carries torsion and needs a "
                             "torsional stiffness: give BeamStiffness(torsional_stiffness=...) "
                             "or a CircularSection with a Material")
        if element == "ancf_cable":
            options = options or CableOptions()
        if stress_free is not None:
            stress_free = _stress_free_shape(stress_free, centerline, element, elements)
        beam = Beam(self._unique(name, "beam"), centerline, stiffness,
                    options=options, damping=damping,
                    reference_axial_strain=reference_axial_strain, element=element,
                    stress_free=stress_free)
        self.beams.append(beam)
        return beam

    def add_rigid_body(self, *, mass: float, inertia: Sequence[float] | np.ndarray,
                       pose: Pose | None = None, position: ArrayLike3 = (0.0, 0.0, 0.0),
                       quaternion: Sequence[float] = (1.0, 0.0, 0.0, 0.0),
                       velocity: ArrayLike3 = (0.0, 0.0, 0.0),
                       angular_velocity: ArrayLike3 = (0.0, 0.0, 0.0),
                       name: str | None = None, shape: dict | None = None) -> RigidBody:
        """Add a rigid body; ``inertia`` = principal moments (3) or a 3x3 tensor, body frame,
        about the centre of mass; ``angular_velocity`` in global components."""
        if not (isinstance(mass, (int, float, np.floating)) and math.isfinite(mass) and mass > 0):
            raise ModelError(f"add_rigid_body: mass must be a finite number > 0 (got {mass!r})")
        try:
            J = rb.inertia_tensor(inertia)
        except ValueError as exc:
            raise ModelError(f"add_rigid_body: {exc}") from None
        if pose is None:
            pose = Pose.from_quaternion(position, quaternion)
        body = RigidBody(self._unique(name, "body"), mass, J, pose,
                         _vec3(velocity, "velocity"), _vec3(angular_velocity, "angular_velocity"),
                         shape)
        self.bodies.append(body)
        return body

    # ------------------------------------------------------------------ constraints
    def _add_constraint(self, spec: ConstraintSpec) -> ConstraintSpec:
        self.constraints.append(spec)
        return spec

    def clamp(self, node: Node, *, name: str | None = None) -> ConstraintSpec:
        """Fix the node position and the transverse components of its slope (not the axial one)."""
        self._check_node(node, "clamp")
        return self._add_constraint(ConstraintSpec("clamp", self._unique(name, "clamp"), node))

    def pin(self, node: Node, *, name: str | None = None) -> ConstraintSpec:
        """Fix the node position (spherical hinge to ground)."""
        self._check_node(node, "pin")
        return self._add_constraint(ConstraintSpec("pin", self._unique(name, "pin"), node))

    def prescribe(self, target: Node | RigidBody, components: Sequence[int], function=None, *,
                  name: str | None = None) -> ConstraintSpec:
        """Prescribe coordinates: ``q_i(t) = q_i(0) + f(t)`` for the listed local coordinate
        indices (node: 0-2 position, 3-5 slope, 6 the twist of a rod's node — the section's turn
        about its tangent, rad, which needs the node's slope held; body: 0-2 position, 3-6
        Euler parameters)."""
        n = target.beam.layout.node_size if isinstance(target, Node) else 7
        comps = tuple(int(c) for c in components)
        if not comps or any(not 0 <= c < n for c in comps):
            twist = (" (a cable's node has no twist: element = \"ancf_rod14\")"
                     if isinstance(target, Node) and 6 in comps else "")
            raise ModelError(f"prescribe: components must be in 0..{n - 1} (got {components!r})"
                             + twist)
        return self._add_constraint(ConstraintSpec(
            "prescribed", self._unique(name, "prescribed"), target, components=comps,
            function=as_time_function(function if function is not None else 0.0)))

    def fix_body(self, body: RigidBody, *, name: str | None = None) -> ConstraintSpec:
        self._check_body(body, "fix_body")
        return self.joint(body, GROUND, point=body.pose.position, translation=(1, 1, 1),
                          rotation=(1, 1, 1), name=name, kind="fix_body")

    def spherical(self, a: RigidBody | Node, b: RigidBody | Node | Ground = GROUND, *,
                  point: ArrayLike3 | None = None, name: str | None = None) -> ConstraintSpec:
        """Spherical joint at global ``point`` (default: the position of ``a``) between a and b."""
        if point is None:
            point = a.position if isinstance(a, Node) else a.pose.position
        return self.joint(a, b, point=point, translation=(1, 1, 1), rotation=(0, 0, 0),
                          name=name, kind="spherical")

    def revolute(self, a: RigidBody, b: RigidBody | Ground = GROUND, *, point: ArrayLike3,
                 axis: ArrayLike3, name: str | None = None) -> ConstraintSpec:
        """Revolute joint about global ``axis`` through global ``point`` (initial configuration)."""
        return self.joint(a, b, point=point, axis=axis, translation=(1, 1, 1), rotation=(0, 1, 1),
                          name=name, kind="revolute")

    def prismatic(self, a: RigidBody, b: RigidBody | Ground = GROUND, *, point: ArrayLike3,
                  axis: ArrayLike3, name: str | None = None) -> ConstraintSpec:
        """Prismatic joint sliding along global ``axis`` (initial configuration)."""
        return self.joint(a, b, point=point, axis=axis, translation=(0, 1, 1), rotation=(1, 1, 1),
                          name=name, kind="prismatic")

    def rigid(self, node: Node, body: RigidBody | Ground, *, name: str | None = None) -> ConstraintSpec:
        """Rigid connection of a beam node (position, slope direction and, on the rod, the turn
        of its section) to a body or ground."""
        self._check_node(node, "rigid")
        return self._add_constraint(ConstraintSpec("rigid", self._unique(name, "rigid"), node, body))

    def joint(self, a: RigidBody | Node, b: RigidBody | Node | Ground = GROUND, *, point: ArrayLike3,
              axis: ArrayLike3 | None = None, frame: np.ndarray | None = None,
              translation: Sequence[int] = (1, 1, 1), rotation: Sequence[int] = (0, 0, 0),
              name: str | None = None, kind: str = "joint") -> ConstraintSpec:
        """Generic joint: lock the relative translations/rotations selected by the masks, in a
        joint frame at global ``point`` with x axis ``axis`` (or a full 3x3 ``frame``)."""
        tr = tuple(int(bool(x)) for x in translation)
        ro = tuple(int(bool(x)) for x in rotation)
        if len(tr) != 3 or len(ro) != 3 or sum(tr) + sum(ro) == 0:
            raise ModelError(f"{kind}: translation and rotation masks need 3 entries and at least one 1")
        if isinstance(a, Ground):
            raise ModelError(f"{kind}: the first object must be a body or a beam node, not ground")
        if isinstance(a, Node) and isinstance(b, Node):
            raise ModelError(f"{kind}: node-to-node joints are not supported; connect nodes to a body")
        if isinstance(b, Node):
            a, b = b, a
        if isinstance(a, Node) and sum(ro) > 0:
            raise ModelError(f"{kind}: a beam node has no rotation frame; use model.rigid(node, body) "
                             "for a rigid connection or only translation constraints")
        x = _vec3(point, f"{kind}: point")
        if frame is None:
            ex = _unit(axis, f"{kind}: axis") if axis is not None else np.array([1.0, 0.0, 0.0])
            helper = np.array([0.0, 0.0, 1.0]) if abs(ex[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
            ey = np.cross(helper, ex)
            ey /= np.linalg.norm(ey)
            frame = np.column_stack([ex, ey, np.cross(ex, ey)])
        frame = np.asarray(frame, float)
        if frame.shape != (3, 3) or not np.allclose(frame.T @ frame, np.eye(3), atol=1e-9):
            raise ModelError(f"{kind}: frame must be a 3x3 rotation matrix")

        def local(obj: Target) -> tuple[np.ndarray, np.ndarray]:
            if isinstance(obj, RigidBody):
                R = obj.pose.rotation
                return R.T @ (x - obj.pose.position), R.T @ frame
            return x.copy(), frame.copy()

        for obj in (a, b):
            if isinstance(obj, RigidBody):
                self._check_body(obj, kind)
            elif isinstance(obj, Node):
                self._check_node(obj, kind)
        pa, fa = local(a)
        pb, fb = local(b)
        return self._add_constraint(ConstraintSpec(kind, self._unique(name, kind), a, b, pa, pb, fa, fb,
                                                   translation=tr, rotation=ro))

    def add_driver(self, joint: ConstraintSpec, function=None, *,
                   motion: Literal["rotation", "slide"] | None = None,
                   name: str | None = None) -> ConstraintSpec:
        """A motor on ``joint``: its relative rotation about the joint axis (``motion =
        "rotation"``, a revolute joint) or slide along it (``"slide"``, a prismatic joint) follows
        ``value(t) = value(0) + function(t)`` (:mod:`flexmbs.constraints.drivers`). The driving
        torque (force) is its reaction (``reaction`` probe, :meth:`Result.reaction`). A generic
        joint of a beam node (which has no rotation to lock) takes a slide driver too: the
        node's slide along the joint's x axis."""
        kind = "add_driver"
        if not isinstance(joint, ConstraintSpec) or not any(c is joint for c in self.constraints) \
                or joint.frame_a is None:
            raise ModelError(f"{kind}: joint must be a revolute, prismatic or generic joint of "
                             f"this model (got {joint!r})")
        free_rotation = joint.rotation == (0, 1, 1)
        free_slide = joint.translation[0] == 0 and (joint.rotation[1:] == (1, 1)
                                                    or isinstance(joint.a, Node))
        if motion is None:
            if free_rotation == free_slide:
                raise ModelError(f"{kind}: joint '{joint.name}' ({joint.kind}) needs motion = "
                                 "\"rotation\" or \"slide\"")
            motion = "rotation" if free_rotation else "slide"
        if motion == "rotation" and not free_rotation:
            raise ModelError(f"{kind}: a rotation driver needs a joint that leaves only the "
                             f"rotation about its x axis free among rotations (revolute); "
                             f"'{joint.name}' has rotation mask {list(joint.rotation)}")
        if motion == "slide" and not free_slide:
            raise ModelError(f"{kind}: a slide driver needs a joint whose x translation is free "
                             f"and whose y, z rotations are locked (prismatic; or a joint of a "
                             f"beam node, x translation free); '{joint.name}' "
                             f"has translation {list(joint.translation)}, rotation "
                             f"{list(joint.rotation)}")
        if motion not in ("rotation", "slide"):
            raise ModelError(f"{kind}: motion must be \"rotation\" or \"slide\" (got {motion!r})")
        if motion == "rotation" and (isinstance(joint.a, Node) or isinstance(joint.b, Node)):
            raise ModelError(f"{kind}: a beam node has no rotation frame to drive")
        return self._add_constraint(replace(
            joint, kind="driver", name=self._unique(name, "driver"), motion=motion,
            function=as_time_function(function if function is not None else 0.0)))

    def add_joint(self, joint):
        """Attach a joint or contact interaction (e.g. :class:`flexmbs.SlidingJoint`)."""
        from .constraints.interaction import Interaction

        if not isinstance(joint, Interaction):
            raise ModelError(f"add_joint: expected a joint object such as SlidingJoint (got {joint!r})")
        joint.validate(self)
        joint.name = self._unique(joint.name, "joint")
        self.interactions.append(joint)
        return joint

    def add_tendon(self, tendon: Any) -> Any:
        """A wire through holes in a sequence of bodies, anchored and pulled
        (:class:`flexmbs.Tendon`, :mod:`flexmbs.tendons`): its beam, a clearance joint per hole,
        the anchor, the hold of its start and its tension load or pull driver, named after the
        tendon; the route is checked before anything is added. Returns its
        :class:`flexmbs.TendonParts`. (The tendon adds itself: this module composes no
        tendon, so the tendons module, above the model and the contact joints, stays above.)"""
        add = getattr(tendon, "add_to", None)
        if add is None:
            raise ModelError(f"add_tendon: expected a flexmbs.Tendon (got {tendon!r})")
        return add(self)

    # ------------------------------------------------------------------ force elements
    def add_spring_damper(self, a: Node | RigidBody | Ground, b: Node | RigidBody | Ground = GROUND,
                          *, point_a: ArrayLike3 = (0.0, 0.0, 0.0),
                          point_b: ArrayLike3 = (0.0, 0.0, 0.0), stiffness: float = 0.0,
                          damping: float = 0.0, rest_length: float | None = None,
                          preload: float = 0.0, table: Sequence[Sequence[float]] | None = None,
                          name: str | None = None) -> SpringDamper:
        """Translational spring-damper between two points (:mod:`flexmbs.springs`): a body
        point (``point_*`` in the body frame), a beam node, or a fixed point of the ground
        (``point_*`` global). Force along the line, tension positive: ``stiffness * (l -
        rest_length)`` or the force-elongation ``table`` ([[e, f], ...], piecewise linear),
        plus ``preload`` and ``damping * dl/dt``. ``rest_length`` defaults to the reference
        distance."""
        ends = [self.end_point(obj, pt, what, "add_spring_damper")
                for obj, pt, what in ((a, point_a, "a"), (b, point_b, "b"))]
        for key, val in (("stiffness", stiffness), ("damping", damping)):
            if not (math.isfinite(val) and val >= 0):
                raise ModelError(f"add_spring_damper: {key} must be a finite number >= 0 "
                                 f"(got {val!r})")
        if not math.isfinite(preload):
            raise ModelError(f"add_spring_damper: preload must be finite (got {preload!r})")
        spring_name = self._unique(name, "spring")
        tab = None if table is None else check_table(table, spring_name)
        spring = SpringDamper(spring_name, a, b, ends[0], ends[1], float(stiffness),
                              float(damping), 0.0, float(preload), tab)
        length = float(np.linalg.norm(spring.end_position(1) - spring.end_position(0)))
        if rest_length is None:
            rest_length = length
        if not (math.isfinite(rest_length) and rest_length >= 0):
            raise ModelError(f"add_spring_damper: rest_length must be a finite number >= 0 "
                             f"(got {rest_length!r})")
        if not length > 0:
            raise ModelError(f"spring '{spring_name}': its ends coincide in the reference "
                             "configuration; the direction of its force is undefined")
        spring.rest_length = float(rest_length)
        self.springs.append(spring)
        return spring

    def add_rotational_spring(self, joint: ConstraintSpec, *, stiffness: float = 0.0,
                              damping: float = 0.0, rest_angle: float = 0.0, preload: float = 0.0,
                              table: Sequence[Sequence[float]] | None = None,
                              name: str | None = None) -> SpringDamper:
        """Rotational spring-damper about the axis of a revolute (or generic, x rotation free)
        ``joint`` (:mod:`flexmbs.springs`): torque ``stiffness * (θ - rest_angle)`` or the
        torque-angle ``table`` ([[θ - rest_angle, τ], ...], piecewise linear), plus ``preload``
        and ``damping * dθ/dt``, resisting an increase of θ, the rotation of the joint's first
        part relative to its second (0 as assembled). θ is taken within ±π of ``rest_angle``."""
        what = "add_rotational_spring"
        if not isinstance(joint, ConstraintSpec) or not any(c is joint for c in self.constraints) \
                or joint.frame_a is None or joint.frame_b is None:
            raise ModelError(f"{what}: joint must be a revolute or generic joint of this model "
                             f"(got {joint!r})")
        if joint.rotation != (0, 1, 1) or joint.kind == "driver":
            raise ModelError(f"{what}: joint '{joint.name}' must leave the rotation about its x "
                             f"axis free and lock the other two (rotation mask [0, 1, 1], got "
                             f"{list(joint.rotation)})")
        for key, val in (("stiffness", stiffness), ("damping", damping)):
            if not (math.isfinite(val) and val >= 0):
                raise ModelError(f"{what}: {key} must be a finite number >= 0 (got {val!r})")
        for key, val in (("rest_angle", rest_angle), ("preload", preload)):
            if not math.isfinite(val):
                raise ModelError(f"{what}: {key} must be finite (got {val!r})")
        spring_name = self._unique(name, "spring")
        tab = None if table is None else check_table(table, spring_name)
        spring = SpringDamper(spring_name, joint.a, joint.b, np.asarray(joint.point_a, float),
                              np.asarray(joint.point_b, float), float(stiffness), float(damping),
                              float(rest_angle), float(preload), tab,
                              frame_a=np.asarray(joint.frame_a, float),
                              frame_b=np.asarray(joint.frame_b, float))
        self.springs.append(spring)
        return spring

    # ------------------------------------------------------------------ loads
    def add_point_load(self, target: Node | RigidBody | tuple[Beam, float], force: ArrayLike3 = (0, 0, 0),
                       *, moment: ArrayLike3 | None = None, point: ArrayLike3 = (0.0, 0.0, 0.0),
                       function=None, name: str | None = None) -> LoadSpec:
        """Force (global, fixed direction) on a node, at arc length ``(beam, s)``, or on a body
        at body-frame ``point``; optional ``moment`` (global). Scaled by ``function(t)``."""
        F = _vec3(force, "force")
        M = None if moment is None else _vec3(moment, "moment")
        if isinstance(target, tuple):
            beam, s = target
            beam.locate(float(s))
        elif isinstance(target, Node):
            self._check_node(target, "add_point_load")
        elif isinstance(target, RigidBody):
            self._check_body(target, "add_point_load")
        else:
            raise ModelError("add_point_load: target must be a Node, a RigidBody or (beam, s)")
        spec = LoadSpec("point", self._unique(name, "load"), target, F, M,
                        _vec3(point, "point"), as_time_function(function))
        self.loads.append(spec)
        return spec

    def add_distributed_load(self, beam: Beam, force_per_length: ArrayLike3, *, function=None,
                             name: str | None = None) -> LoadSpec:
        """Constant force per unit reference length on a whole beam, scaled by ``function(t)``."""
        if beam not in self.beams:
            raise ModelError("add_distributed_load: the beam is not part of this model")
        spec = LoadSpec("distributed", self._unique(name, "load"), beam,
                        _vec3(force_per_length, "force_per_length"), None, None,
                        as_time_function(function))
        self.loads.append(spec)
        return spec

    # ------------------------------------------------------------------ checks
    def end_point(self, obj: object, point: ArrayLike3, end: str, what: str) -> np.ndarray:
        """The point of end ``end`` ("a", "b") of a two-point element (a spring-damper, a rope)
        on ``obj``, checked: a rigid body of this model (``point`` in its frame), a node of
        one of its beams (``point`` zero: the element acts at the node) or GROUND (``point``
        global)."""
        if isinstance(obj, RigidBody):
            self._check_body(obj, what)
        elif isinstance(obj, Node):
            self._check_node(obj, what)
            if np.any(np.asarray(point, float) != 0.0):
                raise ModelError(f"{what}: point_{end} is not used with a beam node (the "
                                 "element acts at the node)")
        elif obj is not GROUND:
            raise ModelError(f"{what}: {end} must be a RigidBody, a beam Node or GROUND "
                             f"(got {obj!r})")
        return _vec3(point, f"point_{end}")

    def _check_node(self, node: object, what: str) -> None:
        if not isinstance(node, Node) or node.beam not in self.beams:
            raise ModelError(f"{what}: expected a node of a beam of this model (got {node!r})")

    def _check_body(self, body: object, what: str) -> None:
        if not isinstance(body, RigidBody) or body not in self.bodies:
            raise ModelError(f"{what}: expected a rigid body of this model (got {body!r})")

    def __repr__(self) -> str:
        return (f"Model({self.name!r}: {len(self.beams)} beams, {len(self.bodies)} bodies, "
                f"{len(self.constraints)} constraints, {len(self.loads)} loads)")

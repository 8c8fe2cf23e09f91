"""``[[joints]]`` builders, registry :data:`JOINTS` (``sliding``, ``sliding_clearance``, ``rope``,
``tube``).

The bore of a clearance joint and its contact law are plug-in parts with registries of their own,
shared with the Python API: ``hole = { shape = ... }`` looks the section class up in
:data:`~flexmbs.contact.sections.HOLE_SECTIONS` and ``contact = { law = ... }`` the law class in
:data:`~flexmbs.contact.laws.CONTACT_LAWS`; the keys of either are the dataclass fields of the
class (:meth:`~flexmbs.io.tables.Table.parameters`), so a registered shape or law needs no
scenario code.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...contact.laws import CONTACT_LAWS, FRICTION_LAWS, ForceLaw, Friction, get_law
from ...contact.sections import HOLE_SECTIONS, HoleSection, get_section
from ...contact.shapes.superellipse import SuperellipseSection
from ...contact.shapes.superellipse_limits import check_exponent
from ...errors import ModelError, ScenarioError
from ...registry import Registry
from ..tables import Table, at, one_line
from .context import BuildContext, Builder
from .loads import read_function

__all__ = ["FRICTION_KEYS", "HOLE_KEYS", "JOINTS", "read_contact_law", "read_friction",
           "read_hole_section"]

#: ``[[joints]] type = ...`` -> builder(table, ctx) -> joint
JOINTS: Registry[Builder] = Registry("joint type")

#: keys of ``hole = { ... }`` besides the section's own parameters
HOLE_KEYS = ("shape", "length", "sections", "point", "path", "spacing", "up", "open_ends")
_CONTACT_KEYS = ("law", "friction", "friction_velocity")
#: keys of ``friction = { ... }`` (the fields of :class:`~flexmbs.contact.laws.Friction`)
FRICTION_KEYS = ("mu", "mu_static", "law", "stiffness", "damping", "velocity")


def read_friction(t: Table, key: str = "friction") -> Friction | None:
    """``friction`` of a joint (``t``: the table holding it): a coefficient (stick law; with a
    ``friction_velocity`` beside it, the regularised law of earlier versions) or a table
    ``{ mu, mu_static, law = "stick" | "regularised", stiffness, damping, velocity }``. None if
    absent or zero."""
    t.note(key, "value")        # a number or a table
    if not t.has(key):
        return None
    if not isinstance(t.raw[key], dict):
        mu = t.number(key, ge=0.0, unit="1")
        if t.has("friction_velocity"):
            velocity = t.number("friction_velocity", gt=0.0, unit="m/s")
            return Friction(mu=mu, law="regularised", velocity=velocity) if mu > 0 else None
        return Friction(mu=mu) if mu > 0 else None
    if t.has("friction_velocity"):
        raise ScenarioError(f"{t.key('friction_velocity')}: with a friction table give the "
                            f"regularisation velocity inside it: {t.key(key)} = {{ ..., "
                            "law = \"regularised\", velocity = ... }")
    f = t.table(key)
    f.allow(FRICTION_KEYS)
    law = f.choice("law", FRICTION_LAWS, "stick", what="friction law")
    mu = f.number("mu", ge=0.0, unit="1")
    mu_s = f.number("mu_static", None, ge=0.0, unit="1")
    if mu_s is not None and mu_s < mu:
        raise ScenarioError(f"{f.key('mu_static')}: expected a static coefficient >= mu ({mu:g}), "
                            f"got {mu_s:g}")
    for k in ("mu_static", "stiffness", "damping"):
        if law == "regularised" and f.has(k):
            raise ScenarioError(f"{f.key(k)}: belongs to law = \"stick\" (law \"regularised\" "
                                "takes mu and velocity)")
    if law == "stick" and f.has("velocity"):
        raise ScenarioError(f"{f.key('velocity')}: belongs to law = \"regularised\" (law \"stick\" "
                            "takes mu, mu_static, stiffness and damping)")
    with at(f.path):
        friction = Friction(mu=mu, mu_static=mu_s, law=law,
                            stiffness=f.number("stiffness", None, gt=0.0, unit="N/m"),
                            damping=f.number("damping", 0.0, ge=0.0, unit="N s/m"),
                            velocity=f.number("velocity", 1e-3, gt=0.0, unit="m/s"))
    return friction if mu > 0 or (mu_s or 0.0) > 0 else None


@JOINTS.register("sliding")
def _sliding(t: Table, ctx: BuildContext) -> Any:
    """``type = "sliding"``: SlidingJoint (no clearance), docs/theory.md §II.7."""
    from ...constraints.sliding import SlidingJoint

    t.allow(("name", "type", "beam", "body", "variant", "s0", "hole_point", "axis", "friction",
             "friction_velocity", "axial_force"))
    beam = ctx.beam(t)
    body = ctx.body(t)
    s0 = ctx.arc_length(t, beam, "s0") if t.has("s0") else None
    joint = SlidingJoint(
        beam, body, name=t.raw["name"],
        variant=t.choice("variant", ("cylindrical", "ring"), "cylindrical", what="variant"),
        s0=s0, hole_point=t.vector("hole_point", (0.0, 0.0, 0.0), unit="m"),
        axis=t.vector("axis", (1.0, 0.0, 0.0), unit="1"),
        friction=read_friction(t),
        axial_force=read_function(t, "axial_force", None, unit="N"))
    return ctx.model.add_joint(joint)


@JOINTS.register("sliding_clearance")
def _sliding_clearance(t: Table, ctx: BuildContext) -> Any:
    """``type = "sliding_clearance"``: SlidingClearanceJoint, docs/theory.md §II.1-§II.8."""
    from ...contact.joint import DETECTIONS, TANGENTS, Hole, SlidingClearanceJoint

    t.allow(("name", "type", "beam", "body", "hole", "contact", "beam_radius", "tangent",
             "detection", "axis"))
    beam = ctx.beam(t)
    body = ctx.body(t)
    h = t.table("hole")
    section = read_hole_section(h)
    for k in ("spacing", "up"):
        if h.has(k) and not h.has("path"):
            raise ScenarioError(f"{h.key(k)}: only for a bore along a curve (hole.path = "
                                "{ line | arc | polyline | mesh }); a straight bore takes "
                                "length and sections")
    hole = read_bore(h, section, ctx) if h.has("path") else Hole(
        section, h.number("length", gt=0.0, unit="m"), h.integer("sections", 9, ge=1),
        h.boolean("open_ends", False))
    c = t.table("contact") if t.has("contact") else Table({}, t.key("contact"))
    contact_law = read_contact_law(c)
    friction = read_friction(c)
    tangent = t.choice("tangent", TANGENTS, "exact", what="tangent")
    detection = (t.choice("detection", DETECTIONS, "consistent", what="detection")
                 if t.has("detection") else None)
    if t.has("axis") and h.has("path"):
        raise ScenarioError(f"{t.key('axis')}: turns a straight bore; a bore along a path runs "
                            f"along its path ({h.key('path')}, body coordinates): drop axis")
    axis = t.vector("axis", (1.0, 0.0, 0.0), unit="1")
    if not np.linalg.norm(axis) > 0:
        raise t.fail("axis", "the hole's direction in body coordinates, not zero", t.raw["axis"])
    with at(h.path):        # the hole against the beam: "joints[j].hole: the hole ... "
        joint = SlidingClearanceJoint(
            beam, body, hole=hole, contact=contact_law, friction=friction,
            hole_point=h.vector("point", (0.0, 0.0, 0.0), unit="m"),
            beam_radius=t.number("beam_radius", gt=0.0, unit="m") if t.has("beam_radius") else None,
            tangent=tangent, detection=detection, name=t.raw["name"], axis=axis)
    if body.name in ctx.resting:      # pose = { on_beam, s, rest = "bore" }
        direction, where = ctx.resting.pop(body.name)
        if direction is None:
            direction = np.asarray(ctx.model.gravity, float)
            if not np.linalg.norm(direction) > 0:
                raise ScenarioError(f"{where}.rest: rest = \"bore\" lets the bore rest on the "
                                    "beam along gravity, which is zero here; give "
                                    "rest_direction = [x, y, z]")
        try:
            joint.rest_on_beam(direction)
        except ModelError as exc:
            raise ScenarioError(f"{where}.rest: {exc}") from None
    try:
        return ctx.model.add_joint(joint)
    except ModelError as exc:   # the start: the body's pose against the beam
        raise ScenarioError(f"{t.path} (with rigid_bodies[{body.name}].pose): "
                            f"{one_line(exc)}") from None


@JOINTS.register("rope")
def _rope(t: Table, ctx: BuildContext) -> Any:
    """``type = "rope"``: Rope (flexmbs.ropes), ends as a translational spring's (body / beam +
    node / point, body2 / beam2 + node2 / point2; no second end: the ground at point2)."""
    from ...ropes import Rope
    from .springs import read_end

    t.allow(("name", "type", "body", "beam", "node", "point", "body2", "beam2", "node2",
             "point2", "length", "contact"))
    a = read_end(t, ctx, "")
    b = read_end(t, ctx, "2")
    for k in ("point", "point2"):
        if t.has(k) and not isinstance(t.raw[k], list):
            raise t.fail(k, "[x, y, z]", t.raw[k])
    c = t.table("contact")
    if c.has("friction") or c.has("friction_velocity"):
        key = "friction" if c.has("friction") else "friction_velocity"
        raise ScenarioError(f"{c.key(key)}: a rope has no friction (contact = {{ law, its "
                            "parameters }})")
    law = read_contact_law(c)
    length = t.number("length", gt=0.0, unit="m")
    with at(t.path):
        rope = Rope(a, b, length=length, contact=law, name=t.raw["name"],
                    point_a=t.vector("point", (0.0, 0.0, 0.0), unit="m"),
                    point_b=t.vector("point2", (0.0, 0.0, 0.0), unit="m"))
        return ctx.model.add_joint(rope)


@JOINTS.register("tube")
def _tube(t: Table, ctx: BuildContext) -> Any:
    """``type = "tube"``: TubeJoint, a beam inside a flexible tube, docs/theory.md §II.9."""
    from ...contact.joint import TANGENTS
    from ...contact.tube_joint import TubeJoint

    t.allow(("name", "type", "beam", "tube", "lumen", "spacing", "sections", "start", "end",
             "open_ends", "contact", "beam_radius", "tangent"))
    inner = ctx.beam(t)
    outer = ctx.beam(t, "tube")
    lumen = read_hole_section(t.table("lumen"), keys=("shape",))
    which = t.exclusive("sections", "spacing")
    if which is None:
        raise ScenarioError(f"{t.path}: a tube needs sections = <count> or spacing = <distance "
                            "along the tube> [m]")
    c = t.table("contact") if t.has("contact") else Table({}, t.key("contact"))
    contact_law = read_contact_law(c)
    friction = read_friction(c)
    with at(t.path):
        joint = TubeJoint(
            inner, outer, lumen=lumen,
            spacing=t.number("spacing", gt=0.0, unit="m") if which == "spacing" else None,
            sections=t.integer("sections", ge=2) if which == "sections" else None,
            start=ctx.arc_length(t, outer, "start") if t.has("start") else 0.0,
            end=ctx.arc_length(t, outer, "end") if t.has("end") else None,
            open_ends=t.boolean("open_ends", True), contact=contact_law, friction=friction,
            beam_radius=t.number("beam_radius", gt=0.0, unit="m") if t.has("beam_radius") else None,
            tangent=t.choice("tangent", TANGENTS[:2], "exact", what="tangent"), name=t.raw["name"])
    try:
        return ctx.model.add_joint(joint)
    except ModelError as exc:   # the start: the inner beam against the tube
        raise ScenarioError(f"{t.path}: {one_line(exc)}") from None


def read_hole_section(h: Table, keys: tuple[str, ...] = HOLE_KEYS) -> HoleSection:
    """The section of ``hole = { shape = "<name>", <its parameters>, length, sections, point }``
    (shape default ``"circle"``; ``keys``: the table's keys beyond the section's), built by
    :func:`~flexmbs.contact.sections.get_section`."""
    if h.has("semi_axes"):
        raise ScenarioError(f"{h.key('semi_axes')}: renamed; give the semi-axes as a = ... "
                            "(body y) and b = ... (body z)")
    shape, cls = h.lookup("shape", HOLE_SECTIONS, "circle")
    h.allow((*keys, *Table.parameter_names(cls)))
    params = h.parameters(cls)
    with at(h.path):
        section = get_section(shape, **params)
    if isinstance(section, SuperellipseSection):     # before the run, naming the key
        try:
            check_exponent(section.a, section.b, section.exponent, key=h.key("exponent"))
        except ModelError as exc:
            raise ScenarioError(one_line(exc)) from None
    return section


#: cubic elements of a ``line`` or ``arc`` bore path (an arc's position error ~1e-8 of its
#: radius for a quarter circle; the sections are placed along the curve, not at its nodes)
PATH_ELEMENTS = 64


def read_bore(h: Table, section: HoleSection, ctx: BuildContext) -> Any:
    """``hole = { ..., path = { line | arc | polyline | mesh }, sections | spacing, up }``: a
    :class:`~flexmbs.contact.bores.CurvedBore` along the path (body coordinates; ``point``
    shifts it)."""
    from ...contact.bores import CurvedBore
    from .beams import read_geometry

    if h.has("length"):
        raise ScenarioError(f"{h.key('length')}: a bore along a path is as long as its path; "
                            "drop length (or drop path for a straight bore along body x)")
    which = h.exclusive("sections", "spacing")
    if which is None:
        raise ScenarioError(f"{h.path}: a bore along a path needs sections = <count> or "
                            "spacing = <distance along the path> [m]")
    g = h.table("path")
    path = read_geometry(ctx, g, PATH_ELEMENTS if g.present(("line", "arc")) else None, h)
    with at(h.path):
        return CurvedBore(path, section=section,
                          sections=h.integer("sections", ge=2) if which == "sections" else None,
                          spacing=h.number("spacing", gt=0.0, unit="m") if which == "spacing" else None,
                          up=h.vector("up", unit="1") if h.has("up") else None,
                          open_ends=h.boolean("open_ends", True))


def read_contact_law(c: Table) -> ForceLaw:
    """The normal force law of ``contact = { law = "<name>", <its parameters>, friction, ... }``
    (law default ``"linear"``), built by :func:`~flexmbs.contact.laws.get_law`."""
    law, cls = c.lookup("law", CONTACT_LAWS, "linear")
    c.allow((*_CONTACT_KEYS, *Table.parameter_names(cls)))
    params = c.parameters(cls)
    with at(c.path):
        return get_law(law, **params)

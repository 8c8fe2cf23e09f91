"""``[[joints]]`` builders, registry :data:`JOINTS` (``sliding``, ``sliding_clearance``).

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

from ...contact.laws import CONTACT_LAWS, ForceLaw, RegularizedCoulomb, get_law
from ...contact.sections import HOLE_SECTIONS, HoleSection, get_section
from ...errors import ModelError, ScenarioError
from ...registry import Registry
from ..tables import Table, at, one_line
from .context import BuildContext, Builder
from .loads import read_function

__all__ = ["HOLE_KEYS", "JOINTS", "read_contact_law", "read_hole_section"]

#: ``[[joints]] type = ...`` -> builder(table, ctx) -> joint
JOINTS: Registry[Builder] = Registry("joint type")

#: keys of ``hole = { ... }`` besides the section's own parameters
HOLE_KEYS = ("shape", "length", "sections", "point")
_CONTACT_KEYS = ("law", "friction", "friction_velocity")


@JOINTS.register("sliding")
def _sliding(t: Table, ctx: BuildContext) -> Any:
    """``type = "sliding"``: SlidingJoint (no clearance), FORMULATION Part II §7."""
    from ...constraints.sliding import SlidingJoint

    t.allow(("name", "type", "beam", "body", "variant", "s0", "hole_point", "axis", "friction",
             "friction_velocity", "axial_force"))
    beam = ctx.beam(t)
    body = ctx.body(t)
    s0 = ctx.arc_length(t, beam, "s0") if t.has("s0") else None
    joint = SlidingJoint(
        beam, body, name=t.raw["name"],
        variant=t.choice("variant", ("cylindrical", "ring"), "cylindrical", what="variant"),
        s0=s0, hole_point=t.vector("hole_point", (0.0, 0.0, 0.0)),
        axis=t.vector("axis", (1.0, 0.0, 0.0)),
        friction=t.number("friction", 0.0, ge=0.0),
        friction_velocity=t.number("friction_velocity", 1e-3, gt=0.0),
        axial_force=read_function(t, "axial_force", None))
    return ctx.model.add_joint(joint)


@JOINTS.register("sliding_clearance")
def _sliding_clearance(t: Table, ctx: BuildContext) -> Any:
    """``type = "sliding_clearance"``: SlidingClearanceJoint, FORMULATION Part II §1-§8."""
    from ...contact.joint import DETECTIONS, TANGENTS, Hole, SlidingClearanceJoint

    t.allow(("name", "type", "beam", "body", "hole", "contact", "beam_radius", "tangent",
             "detection"))
    beam = ctx.beam(t)
    body = ctx.body(t)
    h = t.table("hole")
    section = read_hole_section(h)
    hole = Hole(section, h.number("length", gt=0.0), h.integer("sections", 9, ge=1))
    c = t.table("contact") if t.has("contact") else Table({}, t.key("contact"))
    contact_law = read_contact_law(c)
    mu = c.number("friction", 0.0, ge=0.0)
    friction = (RegularizedCoulomb(mu=mu, eps_v=c.number("friction_velocity", 1e-3, gt=0.0))
                if mu > 0 else None)
    tangent = t.choice("tangent", TANGENTS, "exact", what="tangent")
    detection = (t.choice("detection", DETECTIONS, "consistent", what="detection")
                 if t.has("detection") else None)
    with at(h.path):        # the hole against the beam: "joints[j].hole: the hole ... "
        joint = SlidingClearanceJoint(
            beam, body, hole=hole, contact=contact_law, friction=friction,
            hole_point=h.vector("point", (0.0, 0.0, 0.0)),
            beam_radius=t.number("beam_radius", gt=0.0) if t.has("beam_radius") else None,
            tangent=tangent, detection=detection, name=t.raw["name"])
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


def read_hole_section(h: Table) -> HoleSection:
    """The section of ``hole = { shape = "<name>", <its parameters>, length, sections, point }``
    (shape default ``"circle"``), built by :func:`~flexmbs.contact.sections.get_section`."""
    if h.has("semi_axes"):
        raise ScenarioError(f"{h.key('semi_axes')}: renamed; give the semi-axes as a = ... "
                            "(body y) and b = ... (body z)")
    shape, cls = h.lookup("shape", HOLE_SECTIONS, "circle")
    h.allow((*HOLE_KEYS, *Table.parameter_names(cls)))
    params = h.parameters(cls)
    with at(h.path):
        return get_section(shape, **params)


def read_contact_law(c: Table) -> ForceLaw:
    """The normal force law of ``contact = { law = "<name>", <its parameters>, friction, ... }``
    (law default ``"linear"``), built by :func:`~flexmbs.contact.laws.get_law`."""
    law, cls = c.lookup("law", CONTACT_LAWS, "linear")
    c.allow((*_CONTACT_KEYS, *Table.parameter_names(cls)))
    params = c.parameters(cls)
    with at(c.path):
        return get_law(law, **params)

"""``[[tendons]]``: a wire routed through holes of rigid bodies, anchored at its end and pulled at
its start (:class:`~flexmbs.tendons.Tendon`, :meth:`Model.add_tendon
<flexmbs.model.Model.add_tendon>`).

The wire's section keys are those of ``[[beams]]`` (:func:`~.beams.read_stiffness`), the holes'
``contact`` table that of ``[[joints]] type = "sliding_clearance"`` (:func:`~.joints.read_contact_law`,
:func:`~.joints.read_friction`), ``tension`` and ``pulled_length`` time functions as loads take
them (:func:`~.loads.read_function`). The parts it builds are named after the tendon and can be
referred to by later entries: the wire is a beam (``<name>``), its holes are joints
(``<name>_hole<k>_<body>``; e.g. ``contact_force`` probes); probes ``tendon_tension`` and
``tendon_displacement`` take ``tendon = "<name>"``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from ...errors import ModelError, ScenarioError
from ...tendons import Tendon, TendonParts
from ..tables import Table, at, one_line
from .beams import read_stiffness
from .context import BuildContext
from .joints import read_contact_law, read_friction
from .loads import read_function

__all__ = ["TENDON_KEYS", "build_tendon"]

_SECTION_KEYS = ("radius", "youngs_modulus", "density", "poisson_ratio", "shear_modulus",
                 "axial_stiffness", "bending_stiffness", "mass_per_length")
#: keys of a ``[[tendons]]`` entry
TENDON_KEYS = ("name", "route", "anchor", "lead", *_SECTION_KEYS, "element_length", "elements",
               "damping", "clearance", "hole_length", "hole_sections", "contact", "tension",
               "pulled_length")


def _body_point(e: Table, ctx: BuildContext) -> tuple[Any, Any]:
    """``{ body = "<name>", point = [x, y, z] }`` (body coordinates, m)."""
    e.allow(("body", "point"))
    return ctx.body(e), e.vector("point", unit="m")


def _route(t: Table, ctx: BuildContext) -> list[tuple[Any, Any]]:
    expected = "an array of at least one hole { body = \"<name>\", point = [x, y, z] }"
    v = t.get("route", expected=expected)
    if not isinstance(v, list) or not v or not all(isinstance(e, Mapping) for e in v):
        raise t.fail("route", expected, v)
    return [_body_point(Table(e, f"{t.key('route')}[{k}]"), ctx) for k, e in enumerate(v)]


def build_tendon(t: Table, ctx: BuildContext) -> TendonParts:
    """A ``[[tendons]]`` entry: the :class:`~flexmbs.tendons.Tendon`, checked with key paths
    (``tendons[t2].route[3].point: ...``), added to the model; its wire and holes join the
    context's beams and joints, the parts its tendons."""
    t.allow(TENDON_KEYS)
    route = _route(t, ctx)
    anchor = _body_point(t.table("anchor"), ctx)
    section = read_stiffness(t)
    if section.radius is None:
        raise ScenarioError(f"{t.key('radius')}: missing required key (expected the wire's "
                            "radius [m]: the holes are radius + clearance)")
    t.exclusive("element_length", "elements")     # neither: half the mean route segment
    which = t.exclusive("tension", "pulled_length")
    if which is None:
        raise ScenarioError(f"{t.path}: missing actuation: give tension = <N or time function> "
                            "or pulled_length = <m or time function>")
    contact, friction = None, None       # the Tendon's default law, no friction
    if t.has("contact"):
        c = t.table("contact")
        contact, friction = read_contact_law(c), read_friction(c)
    with at(t.path):
        spec = Tendon(
            name=t.raw["name"], route=route, anchor=anchor, lead=t.number("lead", gt=0.0, unit="m"),
            radius=section.radius, section=section, clearance=t.number("clearance", gt=0.0, unit="m"),
            element_length=t.number("element_length", None, gt=0.0, unit="m"),
            elements=t.integer("elements", None, ge=1), damping=t.number("damping", 0.0, ge=0.0, unit="s"),
            hole_length=t.number("hole_length", 1e-3, gt=0.0, unit="m"),
            hole_sections=t.integer("hole_sections", None, ge=1), contact=contact,
            friction=friction, tension=read_function(t, "tension", None, unit="N"),
            pulled_length=read_function(t, "pulled_length", None, unit="m"))
    try:
        spec.layout(ctx.model, where=t.path)     # a bad route, named by its key path
    except ModelError as exc:
        raise ScenarioError(one_line(exc)) from None
    with at(t.path):
        parts = ctx.model.add_tendon(spec)
    ctx.beams[parts.beam.name] = parts.beam
    for joint in parts.holes:
        ctx.joints[joint.name] = joint
    ctx.tendons[spec.name] = parts
    return parts

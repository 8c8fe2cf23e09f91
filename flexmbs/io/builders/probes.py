"""``[[probes]]`` builders, registry :data:`PROBES` (the probe classes are in
:mod:`flexmbs.io.probes`)."""

from __future__ import annotations

from typing import Any

from ...errors import ScenarioError
from ...registry import Registry
from .. import probes
from ..tables import Table
from .context import BuildContext, Builder, build_entry

__all__ = ["PROBES", "build_probe"]

#: ``[[probes]] type = ...`` -> builder(table, ctx) -> Probe
PROBES: Registry[Builder] = Registry("probe type")


def build_probe(t: Table, ctx: BuildContext) -> probes.Probe:
    """A ``[[probes]]`` entry; its name must be usable as a CSV column."""
    name = t.raw["name"]
    if any(c in name for c in ",\"\n\r") or name.strip() != name:
        raise t.fail("name", "a probe name usable as a CSV column (no commas, quotes or "
                     "surrounding spaces)", name)
    probe: probes.Probe = build_entry(PROBES, t, ctx)
    return probe


@PROBES.register("beam_point")
def _beam_point(t: Table, ctx: BuildContext) -> probes.Probe:
    t.allow(("name", "type", "beam", "s", "quantity"))
    beam = ctx.beam(t)
    s = ctx.arc_length(t, beam)
    quantity = t.choice("quantity", probes.BeamPointProbe.quantities(beam), "position",
                        what="quantity")
    return probes.BeamPointProbe(t.raw["name"], beam, s, quantity)


@PROBES.register("body_position")
def _body_position(t: Table, ctx: BuildContext) -> probes.Probe:
    t.allow(("name", "type", "body"))
    return probes.BodyPositionProbe(t.raw["name"], ctx.body(t))


@PROBES.register("body_orientation")
def _body_orientation(t: Table, ctx: BuildContext) -> probes.Probe:
    t.allow(("name", "type", "body"))
    return probes.BodyOrientationProbe(t.raw["name"], ctx.body(t))


@PROBES.register("body_point")
def _body_point(t: Table, ctx: BuildContext) -> probes.Probe:
    t.allow(("name", "type", "body", "point", "quantity"))
    quantity = t.choice("quantity", ("position", "displacement"), "position", what="quantity")
    return probes.BodyPointProbe(t.raw["name"], ctx.body(t), t.vector("point", unit="m"), quantity)


@PROBES.register("energy")
def _energy(t: Table, ctx: BuildContext) -> probes.Probe:
    t.allow(("name", "type", "quantity"))
    quantity = t.choice("quantity", probes.EnergyProbe.quantities(), "total", what="quantity")
    return probes.EnergyProbe(t.raw["name"], quantity)


def _joint_probe(cls: type[Any], kinds: tuple[str, ...], what: str) -> Builder:
    """Builder of a probe on a joint of one of the term kinds ``kinds`` (``joint = "name"``;
    ``what``: how the message names them)."""

    def build(t: Table, ctx: BuildContext) -> probes.Probe:
        t.allow(("name", "type", "joint"))
        name = t.string("joint")
        joint = ctx.joints.get(name)
        if joint is None or joint.term_kind not in kinds:
            known = ", ".join(k for k, j in ctx.joints.items() if j.term_kind in kinds)
            raise ScenarioError(f"{t.key('joint')}: no {what} joint named '{name}' "
                                f"({what} joints: {known or 'none'})")
        probe: probes.Probe = cls(t.raw["name"], joint)
        return probe

    return build


PROBES.register("slide_coordinate",
                _joint_probe(probes.SlideCoordinateProbe, ("sliding", "clearance"), "sliding"))
PROBES.register("contact_force",
                _joint_probe(probes.ContactForceProbe, ("clearance",), "clearance"))
PROBES.register("rope", _joint_probe(probes.RopeProbe, ("rope",), "rope"))


@PROBES.register("reaction")
def _reaction(t: Table, ctx: BuildContext) -> probes.Probe:
    """``type = "reaction"``, ``constraint = NAME`` (a constraint or joint), ``part = NAME``
    (optional: the beam or body it acts on)."""
    t.allow(("name", "type", "constraint", "part"))
    name = t.string("constraint")
    known = [c.name for c in ctx.model.constraints] + [j.name for j in ctx.model.interactions
                                                       if j.constraints()]
    if name not in known:
        raise ScenarioError(f"{t.key('constraint')}: no constraint or joint named '{name}' "
                            f"(with reactions: {', '.join(known) or 'none'})")
    part = t.string("part", None)
    if part is not None and part not in ctx.beams and part not in ctx.bodies:
        raise ScenarioError(f"{t.key('part')}: no beam or rigid body named '{part}'")
    return probes.ReactionProbe(t.raw["name"], name, part)


PROBES.register("joint_reaction",
                _joint_probe(probes.JointReactionProbe, ("sliding",), "sliding"))


def _tendon_probe(cls: type[Any]) -> Builder:
    """Builder of a probe on a tendon (``tendon = "name"``, a ``[[tendons]]`` entry)."""

    def build(t: Table, ctx: BuildContext) -> probes.Probe:
        t.allow(("name", "type", "tendon"))
        name = t.string("tendon")
        tendon = ctx.tendons.get(name)
        if tendon is None:
            raise ScenarioError(f"{t.key('tendon')}: no tendon named '{name}' (tendons: "
                                f"{', '.join(ctx.tendons) or 'none'})")
        probe: probes.Probe = cls(t.raw["name"], tendon)
        return probe

    return build


PROBES.register("tendon_tension", _tendon_probe(probes.TendonTensionProbe))
PROBES.register("tendon_displacement", _tendon_probe(probes.TendonDisplacementProbe))

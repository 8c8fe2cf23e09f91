"""``[[springs]]`` builders, registry :data:`SPRINGS` (``type = "translational"``, ``"rotational"``)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ...errors import ScenarioError
from ...model import GROUND
from ...registry import Registry
from ..tables import Table, is_number, show_value
from .context import BuildContext, Builder

__all__ = ["SPRINGS", "read_end"]

#: ``[[springs]] type = ...`` -> builder(table, ctx)
SPRINGS: Registry[Builder] = Registry("spring type")


def read_end(t: Table, ctx: BuildContext, suffix: str) -> Any:
    """End ``a`` of a two-point element (a spring-damper, a rope; keys body / beam + node /
    point) or ``b`` (body2 / beam2 + node2 / point2; absent: the ground at ``point2``)."""
    body, beam, node = f"body{suffix}", f"beam{suffix}", f"node{suffix}"
    which = t.exclusive(body, beam)
    if which == body:
        return ctx.body(t, body)
    if which == beam:
        return ctx.node(t, ctx.beam(t, beam), node)
    if not suffix:
        raise ScenarioError(f"{t.key('body')}: missing required key (the first end: body = "
                            "\"name\" or beam = \"name\" with node = ...)")
    if not t.has(f"point{suffix}"):
        raise ScenarioError(f"{t.key('point2')}: missing required key (the second end is the "
                            "ground: give its global point, or body2 / beam2 + node2)")
    return GROUND


def _table(t: Table, expected: str = "[[elongation, force], ...] with at least 2 rows") -> Any:
    v = t.get("table", None)
    if v is None:
        return None
    ok = (isinstance(v, list) and len(v) >= 2 and all(
        isinstance(r, list) and len(r) == 2 and all(is_number(x) for x in r) for r in v))
    if not ok:
        raise t.fail("table", expected, v)
    return np.array(v, dtype=float)


@SPRINGS.register("translational")
def _translational(t: Table, ctx: BuildContext) -> Any:
    """A spring-damper between two points (Model.add_spring_damper)."""
    t.allow(("type", "name", "body", "beam", "node", "point", "body2", "beam2", "node2",
             "point2", "stiffness", "damping", "rest_length", "preload", "table"))
    a = read_end(t, ctx, "")
    b = read_end(t, ctx, "2")
    if t.has("table") and t.has("stiffness"):
        raise ScenarioError(f"{t.key('table')}: give either stiffness or table, not both")
    if not t.has("table") and not t.has("stiffness"):
        raise ScenarioError(f"{t.key('stiffness')}: missing required key (N/m; or a "
                            "force-elongation table)")
    table = _table(t)
    rest = t.number("rest_length", None, ge=0.0, unit="m") if t.has("rest_length") else None
    for k in ("point", "point2"):
        if t.has(k) and not isinstance(t.raw[k], list):
            raise t.fail(k, "[x, y, z]", show_value(t.raw[k]))
    return ctx.model.add_spring_damper(
        a, b, point_a=t.vector("point", (0.0, 0.0, 0.0), unit="m"),
        point_b=t.vector("point2", (0.0, 0.0, 0.0), unit="m"),
        stiffness=t.number("stiffness", 0.0, ge=0.0, unit="N/m"),
        damping=t.number("damping", 0.0, ge=0.0, unit="N s/m"),
        rest_length=rest, preload=t.number("preload", 0.0, unit="N"), table=table, name=t.raw.get("name"))


@SPRINGS.register("rotational")
def _rotational(t: Table, ctx: BuildContext) -> Any:
    """A torsional spring-damper about the axis of a revolute joint (Model.add_rotational_spring)."""
    t.allow(("type", "name", "joint", "stiffness", "damping", "rest_angle", "preload", "table"))
    joint = ctx.constraint(t, "joint")
    if t.has("table") and t.has("stiffness"):
        raise ScenarioError(f"{t.key('table')}: give either stiffness or table, not both")
    if not t.has("table") and not t.has("stiffness"):
        raise ScenarioError(f"{t.key('stiffness')}: missing required key (N m/rad; or a "
                            "torque-angle table)")
    table = _table(t, "[[angle, torque], ...] with at least 2 rows")
    return ctx.model.add_rotational_spring(
        joint, stiffness=t.number("stiffness", 0.0, ge=0.0, unit="N m/rad"),
        damping=t.number("damping", 0.0, ge=0.0, unit="N m s/rad"),
        rest_angle=t.number("rest_angle", 0.0, unit="rad"),
        preload=t.number("preload", 0.0, unit="N m"), table=table, name=t.raw.get("name"))

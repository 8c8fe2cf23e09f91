"""``[[loads]]`` builders (registry :data:`LOADS`) and time functions (``function = ...``)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, TypeVar

import numpy as np

from ...errors import ScenarioError
from ...loads import Constant, HalfSine, Moves, Ramp, Sine, TimeFunction
from ...loads import Table as TableFunction
from ...registry import Registry
from ..tables import Table, is_number
from .context import BuildContext, Builder

__all__ = ["FUNCTIONS", "LOADS", "read_function"]

#: ``[[loads]] type = ...`` -> builder(table, ctx)
LOADS: Registry[Builder] = Registry("load type")

#: ``function = { type = ... }``
FUNCTIONS = ("constant", "ramp", "half_sine", "sine", "table", "moves")

D = TypeVar("D", bound="TimeFunction | None")


def read_function(t: Table, key: str, default: D, *, unit: str) -> TimeFunction | D:
    """A time function: a number (constant) or ``{ type = "ramp" | "half_sine" | ... }``;
    ``unit``: that of its values (:data:`~flexmbs.io.tables.UNITS`)."""
    t.note(key, "function", unit=unit)
    if not t.has(key):
        return default
    v = t.raw[key]
    if is_number(v):
        return Constant(float(t.number(key, unit=unit)))
    if not isinstance(v, Mapping):
        raise t.fail(key, "a number or a time function table { type = "
                     f"{' | '.join(repr(k) for k in FUNCTIONS)}, ... }}", v)
    f = t.table(key)
    kind = f.choice("type", FUNCTIONS, what="time function")
    if kind == "constant":
        f.allow(("type", "value"))
        return Constant(f.number("value", unit=unit))
    if kind == "ramp":
        f.allow(("type", "start", "end", "value", "smooth"))
        start, end = f.number("start", 0.0, unit="s"), f.number("end", unit="s")
        if not end > start:
            raise f.fail("end", f"a time > start = {start:g}", end)
        return Ramp(start=start, end=end, value=f.number("value", 1.0, unit=unit),
                    smooth=f.boolean("smooth", False))
    if kind == "half_sine":
        f.allow(("type", "duration", "start", "amplitude"))
        return HalfSine(duration=f.number("duration", gt=0, unit="s"),
                        start=f.number("start", 0.0, unit="s"),
                        amplitude=f.number("amplitude", 1.0, unit=unit))
    if kind == "sine":
        f.allow(("type", "amplitude", "frequency", "phase"))
        return Sine(amplitude=f.number("amplitude", 1.0, unit=unit),
                    frequency=f.number("frequency", gt=0, unit="Hz"),
                    phase=f.number("phase", 0.0, unit="rad"))
    if kind == "moves":
        f.allow(("type", "moves"))
        moves = f.get("moves", expected="a list of [start, end, change]")
        if not (isinstance(moves, list) and moves and all(
                isinstance(m, list) and len(m) == 3 and all(is_number(x) and math.isfinite(x)
                                                            for x in m) for m in moves)):
            raise f.fail("moves", "a non-empty list of [start, end, change] (3 numbers each: "
                         f"s, s, {unit})", moves)
        f.check_size("moves", [x for m in moves for x in m[:2]], "s", "times")
        f.check_size("moves", [m[2] for m in moves], unit, "changes")
        for i, (start, end, _) in enumerate(moves):
            if not end > start:
                raise f.fail("moves", f"move {i} ending after it starts (end > start = "
                             f"{start:g})", moves)
        return Moves([(float(a), float(b), float(c)) for a, b, c in moves])
    f.allow(("type", "times", "values"))
    times = f.get("times", expected="a list of times")
    values = f.get("values", expected="a list of numbers")
    for k, arr in (("times", times), ("values", values)):
        if not (isinstance(arr, list) and arr and all(is_number(x) and math.isfinite(x)
                                                       for x in arr)):
            raise f.fail(k, "a non-empty list of numbers", arr)
        f.check_size(k, arr, "s" if k == "times" else unit, "a list of numbers")
    if len(times) != len(values):
        raise f.fail("values", f"{len(times)} numbers (one per entry of times)", values)
    if any(b <= a for a, b in zip(times[:-1], times[1:], strict=True)):
        raise f.fail("times", "strictly increasing times", times)
    return TableFunction(times, values)


@LOADS.register("point")
def _point_load(t: Table, ctx: BuildContext) -> Any:
    """Force (and moment) at a beam node, at arc length ``s``, or at a body point."""
    t.allow(("type", "name", "beam", "node", "s", "body", "point", "force", "moment", "function"))
    which = t.exclusive("beam", "body")
    if which is None:
        raise ScenarioError(f"{t.path}: missing target: give beam (+ node or s) or body (+ point)")
    if not t.has("force") and not t.has("moment"):
        raise ScenarioError(f"{t.key('force')}: missing required key (expected 3 numbers [N]; "
                            "give force and/or moment)")
    force = t.vector("force", np.zeros(3), unit="N")
    moment = t.vector("moment", None, unit="N m")
    fn = read_function(t, "function", Constant(1.0), unit="1")
    target: Any
    if which == "body":
        for k in ("node", "s"):
            if t.has(k):
                raise ScenarioError(f"{t.key(k)}: only with beam = \"<beam name>\"")
        target = ctx.body(t)
    else:
        if t.has("point"):
            raise ScenarioError(f"{t.key('point')}: only with body = \"<body name>\" (a beam load "
                                "acts at node or s)")
        beam = ctx.beam(t)
        at = t.exclusive("node", "s")
        if at is None:
            raise ScenarioError(f"{t.key('node')}: missing required key (expected 'first', 'last', "
                                "a node index, or s = arc length)")
        if at == "node":
            target = ctx.node(t, beam)
        else:
            if moment is not None:
                raise ScenarioError(f"{t.key('moment')}: moments on a beam act at nodes only; "
                                    "give node instead of s")
            target = (beam, ctx.arc_length(t, beam))
    return ctx.model.add_point_load(target, force, moment=moment,
                                    point=t.vector("point", np.zeros(3), unit="m"), function=fn,
                                    name=t.raw.get("name"))


@LOADS.register("distributed")
def _distributed_load(t: Table, ctx: BuildContext) -> Any:
    """Force per length on a whole beam."""
    t.allow(("type", "name", "beam", "force", "function"))
    beam = ctx.beam(t)
    return ctx.model.add_distributed_load(beam, t.vector("force", unit="N/m"),
                                          function=read_function(t, "function", Constant(1.0), unit="1"),
                                          name=t.raw.get("name"))

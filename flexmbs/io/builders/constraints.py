"""``[[constraints]]`` builders, registry :data:`CONSTRAINTS` (``type = "clamp"``, ...)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ...errors import ScenarioError
from ...loads import Constant
from ...model import GROUND, Ground, Node, RigidBody
from ...registry import Registry
from ..tables import MISSING, Table, is_number, show_value
from .context import BuildContext, Builder
from .loads import read_function

__all__ = ["CONSTRAINTS"]

#: ``[[constraints]] type = ...`` -> builder(table, ctx)
CONSTRAINTS: Registry[Builder] = Registry("constraint type")


def _keys(*keys: str) -> tuple[str, ...]:
    return ("type", "name", *keys)


@CONSTRAINTS.register("clamp")
def _clamp(t: Table, ctx: BuildContext) -> Any:
    """Node position and slope fixed."""
    t.allow(_keys("beam", "node"))
    return ctx.model.clamp(ctx.node(t, ctx.beam(t)), name=t.raw.get("name"))


@CONSTRAINTS.register("pin")
def _pin(t: Table, ctx: BuildContext) -> Any:
    """Node position fixed."""
    t.allow(_keys("beam", "node"))
    return ctx.model.pin(ctx.node(t, ctx.beam(t)), name=t.raw.get("name"))


@CONSTRAINTS.register("fix_body")
def _fix_body(t: Table, ctx: BuildContext) -> Any:
    """All coordinates of a body fixed."""
    t.allow(_keys("body"))
    return ctx.model.fix_body(ctx.body(t), name=t.raw.get("name"))


def _first(ctx: BuildContext, t: Table, allow_node: bool = True) -> RigidBody | Node:
    """The first connected object: ``body`` or (``beam`` + ``node``)."""
    which = t.exclusive("body", "beam") if allow_node else ("body" if t.has("body") else None)
    if which is None:
        raise ScenarioError(f"{t.key('body')}: missing required key (expected the name of a "
                            f"rigid body{' or beam + node' if allow_node else ''})")
    if which == "body":
        if t.has("node"):
            raise ScenarioError(f"{t.key('node')}: only with beam = \"<beam name>\"")
        return ctx.body(t)
    return ctx.node(t, ctx.beam(t))


def _second(ctx: BuildContext, t: Table, key: str = "body2") -> RigidBody | Ground:
    """The second connected object: the body ``t[key]``, or the ground if absent."""
    return ctx.body(t, key) if t.has(key) else GROUND


def _global_point(obj: RigidBody | Ground | Node, local: np.ndarray) -> np.ndarray:
    if isinstance(obj, Node):
        return obj.position.copy()
    if isinstance(obj, RigidBody):
        return obj.pose.position + obj.pose.rotation @ local
    return np.asarray(local, dtype=float)


def _axis(t: Table, default: Any = MISSING) -> Any:
    ax = t.vector("axis", default, unit="1")
    if ax is not None and not np.linalg.norm(ax) > 0:
        raise t.fail("axis", "a non-zero direction [x, y, z]", ax.tolist())
    return ax


@CONSTRAINTS.register("spherical")
def _spherical(t: Table, ctx: BuildContext) -> Any:
    """A point of a body (or a beam node) held at a point of another body or the ground."""
    t.allow(_keys("body", "beam", "node", "point", "body2", "point2", "ground_point"))
    a = _first(ctx, t)
    if isinstance(a, Node) and t.has("point"):
        raise ScenarioError(f"{t.key('point')}: a beam node has no body frame; omit 'point'")
    x = _global_point(a, t.vector("point", np.zeros(3), unit="m"))
    b: RigidBody | Ground
    if t.has("body2"):
        if t.has("ground_point"):
            raise ScenarioError(f"{t.path}: give either body2 (+ point2) or ground_point, not both")
        b = ctx.body(t, "body2")
        other, key = _global_point(b, t.vector("point2", np.zeros(3), unit="m")), "point2"
    else:
        if t.has("point2"):
            raise ScenarioError(f"{t.key('point2')}: only with body2 = \"<body name>\"")
        b = GROUND
        other, key = ((t.vector("ground_point", unit="m"), "ground_point")
                      if t.has("ground_point") else (x, ""))
    gap = float(np.linalg.norm(other - x))
    if key and gap > 1e-9 * max(1.0, float(np.linalg.norm(x))):
        raise ScenarioError(f"{t.key(key)}: expected the same global point as the first object's "
                            f"point {show_value(x.tolist())} in the initial configuration, "
                            f"got {show_value(other.tolist())} ({gap:.3g} m apart)")
    return ctx.model.spherical(a, b, point=x, name=t.raw.get("name"))


def _body(ctx: BuildContext, t: Table) -> RigidBody:
    a = _first(ctx, t, allow_node=False)
    assert isinstance(a, RigidBody)  # allow_node=False
    return a


@CONSTRAINTS.register("revolute")
def _revolute(t: Table, ctx: BuildContext) -> Any:
    """Rotation about ``axis`` through ``point`` only."""
    t.allow(_keys("body", "body2", "point", "axis"))
    return ctx.model.revolute(_body(ctx, t), _second(ctx, t), point=t.vector("point", unit="m"),
                              axis=_axis(t), name=t.raw.get("name"))


@CONSTRAINTS.register("prismatic")
def _prismatic(t: Table, ctx: BuildContext) -> Any:
    """Translation along ``axis`` only."""
    t.allow(_keys("body", "body2", "point", "axis"))
    return ctx.model.prismatic(_body(ctx, t), _second(ctx, t), point=t.vector("point", unit="m"),
                               axis=_axis(t), name=t.raw.get("name"))


@CONSTRAINTS.register("rigid")
def _rigid(t: Table, ctx: BuildContext) -> Any:
    """A beam node rigidly attached to a body (or the ground)."""
    t.allow(_keys("beam", "node", "body"))
    node = ctx.node(t, ctx.beam(t))
    return ctx.model.rigid(node, _second(ctx, t, "body"), name=t.raw.get("name"))


@CONSTRAINTS.register("prescribed")
def _prescribed(t: Table, ctx: BuildContext) -> Any:
    """Coordinates of a node or body following a time function."""
    t.allow(_keys("body", "beam", "node", "components", "function"))
    target = _first(ctx, t)
    n = 6 if isinstance(target, Node) else 7
    comps = t.get("components", expected=f"a list of coordinate indices in 0..{n - 1}")
    if (not isinstance(comps, list) or not comps or len(set(map(str, comps))) != len(comps)
            or not all(isinstance(c, int) and not isinstance(c, bool) and 0 <= c < n for c in comps)):
        what = "node: 0-2 position, 3-5 slope" if n == 6 else "body: 0-2 position, 3-6 Euler parameters"
        raise t.fail("components", f"a list of distinct indices in 0..{n - 1} ({what})", comps)
    fn = read_function(t, "function", Constant(0.0), unit="m")
    return ctx.model.prescribe(target, comps, fn, name=t.raw.get("name"))


@CONSTRAINTS.register("joint")
def _joint(t: Table, ctx: BuildContext) -> Any:
    """A general algebraic joint: locked translation/rotation components in a joint frame."""
    t.allow(_keys("body", "beam", "node", "body2", "point", "axis", "frame", "translation",
                  "rotation"))
    a = _first(ctx, t)
    b = _second(ctx, t)
    frame = None
    if t.exclusive("axis", "frame") == "frame":
        v = t.get("frame")
        F = np.array(v, dtype=float) if (isinstance(v, list) and len(v) == 3 and all(
            isinstance(r, list) and len(r) == 3 and all(is_number(x) for x in r) for r in v)) else None
        if F is None or not np.allclose(F.T @ F, np.eye(3), atol=1e-9) or np.linalg.det(F) < 0:
            raise t.fail("frame", "a 3x3 rotation matrix (columns = joint axes, global)", v)
        frame = F
    masks = {}
    for k, default in (("translation", [1, 1, 1]), ("rotation", [0, 0, 0])):
        m = t.get(k, default)
        if not (isinstance(m, list) and len(m) == 3 and all(x in (0, 1) for x in m)):
            raise t.fail(k, "3 flags [x, y, z], each 0 (free) or 1 (locked)", m)
        masks[k] = tuple(int(x) for x in m)
    if sum(masks["translation"]) + sum(masks["rotation"]) == 0:
        raise ScenarioError(f"{t.path}: translation and rotation lock nothing; set at least one 1")
    return ctx.model.joint(a, b, point=t.vector("point", unit="m"), axis=_axis(t, None), frame=frame,
                           translation=masks["translation"], rotation=masks["rotation"],
                           name=t.raw.get("name"))


@CONSTRAINTS.register("driver")
def _driver(t: Table, ctx: BuildContext) -> Any:
    """A motor: the rotation (revolute) or slide (prismatic) of ``joint`` follows ``function``."""
    t.allow(_keys("joint", "motion", "function"))
    joint = ctx.constraint(t, "joint")
    motion = t.get("motion", None)
    if motion is not None and motion not in ("rotation", "slide"):
        raise t.fail("motion", '"rotation" or "slide"', motion)
    fn = read_function(t, "function", Constant(0.0), unit="m" if motion == "slide" else "rad")
    return ctx.model.add_driver(joint, fn, motion=motion, name=t.raw.get("name"))

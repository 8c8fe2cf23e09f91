"""``[[rigid_bodies]]``: mass, inertia, initial pose and velocity, output shape."""

from __future__ import annotations

from typing import Any

import numpy as np

from ...elements.rigid_body import inertia_tensor
from ...errors import ScenarioError
from ...model import Pose, RigidBody
from ..tables import Table, at, display_path, is_number
from .context import BuildContext

__all__ = ["SHAPES", "build_rigid_body"]

#: ``shape = { type = ... }`` of a body (drawn in the VTU output)
SHAPES = ("cylinder", "box", "mesh")


def build_rigid_body(t: Table, ctx: BuildContext) -> RigidBody:
    """A ``[[rigid_bodies]]`` entry."""
    t.allow(("name", "mass", "inertia", "pose", "velocity", "angular_velocity", "shape"))
    mass = t.number("mass", gt=0, unit="kg")
    inertia = _inertia(t)
    pt = t.table("pose", None)
    pose = Pose(np.zeros(3)) if pt is None else _pose(ctx, pt)
    shape = _shape(ctx, t.table("shape")) if t.has("shape") else None
    body = ctx.model.add_rigid_body(mass=mass, inertia=inertia, pose=pose, name=t.raw["name"],
                                    velocity=t.vector("velocity", np.zeros(3), unit="m/s"),
                                    angular_velocity=t.vector("angular_velocity", np.zeros(3), unit="rad/s"),
                                    shape=shape)
    if pt is not None and pt.has("rest"):
        pt.choice("rest", ("bore",), what="rest placement")
        direction = pt.vector("rest_direction", None, unit="1")
        ctx.resting[body.name] = (direction, pt.path)
    elif pt is not None and pt.has("rest_direction"):
        raise ScenarioError(f"{pt.key('rest_direction')}: only with rest = \"bore\"")
    return body


def _inertia(t: Table) -> np.ndarray:
    expected = "3 principal moments > 0 or a symmetric positive definite 3x3 matrix [kg m^2]"
    v = t.get("inertia", expected=expected)
    J: np.ndarray | None = None
    if isinstance(v, list) and len(v) == 3 and all(is_number(x) for x in v):
        J = np.diag(np.array(v, dtype=float))
    elif (isinstance(v, list) and len(v) == 3
          and all(isinstance(r, list) and len(r) == 3 and all(is_number(x) for x in r) for r in v)):
        J = np.array(v, dtype=float)
    if J is None:
        raise t.fail("inertia", expected, v)
    try:
        return inertia_tensor(J)          # the API's own check (add_rigid_body)
    except ValueError as exc:
        raise ScenarioError(f"{t.key('inertia')}: {exc}") from None


def _pose(ctx: BuildContext, p: Table) -> Pose:
    p.allow(("position", "quaternion", "on_beam", "s", "offset", "up", "rest", "rest_direction"))
    if p.has("on_beam"):
        bad = p.present(("position", "quaternion"))
        if bad:
            raise ScenarioError(f"{p.path}: give either {{ position, quaternion }} or "
                                f"{{ on_beam, s, offset }}, not both (got on_beam and {bad[0]})")
        beam = ctx.beam(p, "on_beam")
        s = ctx.arc_length(p, beam)
        up = p.vector("up", None, unit="1")
        with at(p.path):
            frame = beam.frame_at(s, up=up)
        return frame.shifted(p.vector("offset", np.zeros(3), unit="m"))
    bad = p.present(("s", "offset", "up", "rest", "rest_direction"))
    if bad:
        raise ScenarioError(f"{p.key(bad[0])}: only with on_beam = \"<beam name>\"")
    position = p.vector("position", unit="m")
    q = p.vector("quaternion", np.array([1.0, 0, 0, 0]), n=4,
                 what="a unit quaternion [w, x, y, z] (4 numbers)", unit="1")
    if abs(np.linalg.norm(q) - 1.0) > 1e-3:
        raise p.fail("quaternion", f"a unit quaternion [w, x, y, z] (norm {np.linalg.norm(q):.6g})",
                     q.tolist())
    return Pose.from_quaternion(position, q)


def _shape(ctx: BuildContext, s: Table) -> dict[str, Any]:
    kind = s.choice("type", SHAPES, what="shape type")
    if kind == "cylinder":
        s.allow(("type", "radius", "length", "inner_radius"))
        r = s.number("radius", gt=0, unit="m")
        out: dict[str, Any] = {"type": kind, "radius": r, "length": s.number("length", gt=0, unit="m")}
        if s.has("inner_radius"):
            out["inner_radius"] = s.number("inner_radius", ge=0, lt=r, unit="m")
        return out
    if kind == "box":
        s.allow(("type", "size"))
        size = s.vector("size", what="3 sizes [lx, ly, lz] > 0", unit="m")
        if np.any(size <= 0):
            raise s.fail("size", "3 sizes [lx, ly, lz] > 0", size.tolist())
        return {"type": kind, "size": size.tolist()}
    s.allow(("type", "file", "scale"))
    file = ctx.resolve(s.string("file"))
    if not file.is_file():
        raise ScenarioError(f"{s.key('file')}: shape file not found: {display_path(file)}")
    return {"type": kind, "file": str(file), "scale": s.number("scale", 1.0, gt=0, unit="1")}

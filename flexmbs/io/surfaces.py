"""Triangulated body surfaces for the output (body frame): cylinders, boxes, mesh files, and
the inertia box drawn for a body without ``shape``."""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from ..errors import ModelError

if TYPE_CHECKING:
    from ..model import RigidBody

__all__ = ["body_surface", "box_surface", "cylinder_surface", "inertia_box"]


def _ring(x: float, r: float, theta: np.ndarray) -> np.ndarray:
    return np.column_stack([np.full_like(theta, x), r * np.cos(theta), r * np.sin(theta)])


def cylinder_surface(radius: float, length: float, inner_radius: float | None = None,
                     resolution: int = 32) -> tuple[np.ndarray, np.ndarray]:
    """Closed triangulated (hollow) cylinder along x, centred at the origin: (points, triangles)."""
    n = int(resolution)
    th = 2 * np.pi * np.arange(n) / n
    i = np.arange(n)
    j = (i + 1) % n
    h = 0.5 * length

    def band(a: int, b: int, flip: bool) -> np.ndarray:  # quads between rings a and b
        t1 = np.column_stack([a + i, a + j, b + j])
        t2 = np.column_stack([a + i, b + j, b + i])
        t = np.vstack([t1, t2])
        return t[:, ::-1] if flip else t

    if inner_radius:
        pts = np.vstack([_ring(-h, radius, th), _ring(h, radius, th),
                         _ring(-h, inner_radius, th), _ring(h, inner_radius, th)])
        tri = np.vstack([band(0, n, True), band(2 * n, 3 * n, False),   # outer, inner side
                         band(0, 2 * n, False), band(n, 3 * n, True)])   # end annuli
    else:
        pts = np.vstack([_ring(-h, radius, th), _ring(h, radius, th), [[-h, 0, 0], [h, 0, 0]]])
        c0, c1 = 2 * n, 2 * n + 1
        tri = np.vstack([band(0, n, True), np.column_stack([np.full(n, c0), i, j]),
                         np.column_stack([np.full(n, c1), n + j, n + i])])
    return pts, tri.astype(np.int64)


def box_surface(size: Sequence[float] | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Triangulated box of edge lengths ``size`` centred at the origin: (points, triangles)."""
    s = 0.5 * np.asarray(size, float)
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float) * s
    quads = np.array([[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4],
                      [1, 5, 7, 3]])
    tri = np.vstack([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    return corners, tri.astype(np.int64)


def inertia_box(mass: float, inertia: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Box with the inertia of ``inertia`` for a uniform box of mass ``mass``, on the
    principal axes: (points, triangles). Edge a_i² = 6 (I_j + I_k − I_i)/m."""
    ev, V = np.linalg.eigh(np.asarray(inertia, float))
    side2 = 6.0 * (ev.sum() - 2.0 * ev) / mass
    side = np.sqrt(np.clip(side2, 0.0, None))
    # a flat or needle-like inertia would give a degenerate box: keep it visible
    side = np.maximum(side, 1e-2 * side.max() if side.max() > 0 else 1e-3)
    pts, tri = box_surface(side)
    return pts @ V.T, tri


#: a body's shape mesh larger than this [m] (after ``scale``) is a unit or file error
MAX_SHAPE_SIZE = 1e3


def _mesh_surface(shape: dict, body_name: str) -> tuple[np.ndarray, np.ndarray]:
    import meshio

    try:
        # meshio's readers warn on overflowing coordinates (an STL's float32): the check
        # below says it in one line
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            m = meshio.read(shape["file"])
    except Exception as exc:
        raise ModelError(f"body '{body_name}': cannot read shape mesh {shape['file']!r} ({exc})") from exc
    with np.errstate(all="ignore"):
        size = float(np.abs(np.asarray(m.points, float) * float(shape.get("scale", 1.0))).max(
            initial=0.0))
    if not size <= MAX_SHAPE_SIZE:
        raise ModelError(f"body '{body_name}': shape mesh {shape['file']!r} has coordinates of "
                         f"{size:.3g} m (times its scale): not finite or beyond "
                         f"{MAX_SHAPE_SIZE:g} m; give the file in metres or set the shape's "
                         "scale (e.g. 1e-3 for millimetres)")
    tris = []
    for block in m.cells:
        if block.type == "triangle":
            tris.append(block.data)
        elif block.type == "quad":
            tris.extend([block.data[:, [0, 1, 2]], block.data[:, [0, 2, 3]]])
    if not tris:
        raise ModelError(f"body '{body_name}': shape mesh {shape['file']!r} has no triangles or quads")
    scale = float(shape.get("scale", 1.0))
    return np.asarray(m.points[:, :3], float) * scale, np.vstack(tris).astype(np.int64)


_SHAPE_KEYS = {"cylinder": {"radius", "length", "inner_radius", "resolution"},
               "box": {"size"}, "mesh": {"file", "scale"}}


def body_surface(body: RigidBody) -> tuple[np.ndarray, np.ndarray]:
    """Body-frame surface (points, triangles) of ``body.shape`` (see RigidBody.shape)."""
    shape = body.shape
    name = body.name
    if shape is None:
        return inertia_box(body.mass, body.inertia)
    kind = shape.get("type")
    if kind not in _SHAPE_KEYS:
        raise ModelError(f"body '{name}': unknown shape type {kind!r} (known: {sorted(_SHAPE_KEYS)})")
    unknown = set(shape) - _SHAPE_KEYS[kind] - {"type"}
    if unknown:
        raise ModelError(f"body '{name}': unknown keys {sorted(unknown)} in {kind} shape "
                         f"(allowed: {sorted(_SHAPE_KEYS[kind])})")
    try:
        if kind == "cylinder":
            r, length = float(shape["radius"]), float(shape["length"])
            ri = shape.get("inner_radius")
            ri = None if ri is None else float(ri)
            if not (r > 0 and length > 0) or (ri is not None and not 0 <= ri < r):
                raise ModelError(f"body '{name}': cylinder needs radius > 0, length > 0 and "
                                 f"0 <= inner_radius < radius (got {shape})")
            return cylinder_surface(r, length, ri, int(shape.get("resolution", 32)))
        if kind == "box":
            size = np.asarray(shape["size"], float)
            if size.shape != (3,) or np.any(size <= 0):
                raise ModelError(f"body '{name}': box size must be 3 positive lengths (got {shape['size']})")
            return box_surface(size)
        return _mesh_surface(shape, name)
    except KeyError as exc:
        raise ModelError(f"body '{name}': {kind} shape needs the key {exc.args[0]!r}") from None

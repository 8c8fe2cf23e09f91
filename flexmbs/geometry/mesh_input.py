"""Beam centrelines from mesh files (any format meshio reads: gmsh .msh 2/4, .vtu, .vtk, ...).

The 1D cells (``line``, ``line3``, ``line4``, ... and ``VTK_LAGRANGE_CURVE``) are chained into one
ordered path. Higher-order cells store their end points first and their interior points after,
ordered from the first end to the second (gmsh ``line3`` = [end0, end1, mid], ``line4`` =
[end0, end1, i1, i2]; VTK quadratic/cubic edges and Lagrange curves use the same order).
"""

from __future__ import annotations

import contextlib
import io
import os
import re
import warnings
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from ..errors import FlexmbsWarning, GeometryError
from .curves import Centerline, bessel_tangents, hermite_lengths, polyline

if TYPE_CHECKING:
    from meshio import Mesh

__all__ = ["read_curve"]

# Points closer than this fraction of the bounding-box diagonal are merged (gmsh writes shared
# end nodes once, but files glued from several curves or written as separate VTK pieces repeat
# them).
MERGE_TOL = 1e-9

_CURVE_CELL = re.compile(r"^(line\d*|VTK_LAGRANGE_CURVE)$")


@dataclass(frozen=True)
class _Segment:
    """One 1D cell: end point ids and interior point ids (ordered from ``a`` to ``b``)."""

    a: int
    b: int
    interior: tuple[int, ...]


def _read(path: str | os.PathLike[str]) -> Mesh:
    p = Path(path)
    if not p.exists():
        raise GeometryError(f"mesh file not found: {p}")
    if p.is_dir():
        raise GeometryError(f"mesh path is a folder, not a file: {p}")
    if not p.is_file():
        raise GeometryError(f"mesh path is not a regular file (a device or a pipe): {p}")
    import meshio

    # meshio prints its per-format failures and then calls sys.exit(1) when no reader accepts the
    # file (meshio 5.3 _helpers._read_file): capture that output to turn it into our error.
    out, err = io.StringIO(), io.StringIO()
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            mesh = meshio.read(p)
    except SystemExit as exc:
        lines = [ln.strip() for ln in (out.getvalue() + err.getvalue()).splitlines() if ln.strip()]
        reason = "; ".join(lines) or "meshio found no reader that accepts it"
        raise GeometryError(f"cannot read mesh file {p}: {reason}") from exc
    except Exception as exc:  # meshio raises ReadError, ValueError, KeyError... by format
        reason = str(exc) or type(exc).__name__
        raise GeometryError(f"cannot read mesh file {p}: {reason}") from exc
    # meshio's own messages (e.g. unsupported cells; a bare newline for some gmsh files) become
    # one flexmbs warning naming the file, not loose lines in the terminal
    lines = [ln.strip() for ln in (out.getvalue() + err.getvalue()).splitlines() if ln.strip()]
    if lines:
        warnings.warn(f"{p}: meshio says: {'; '.join(lines)}", FlexmbsWarning, stacklevel=3)
    return mesh


def _curve_groups(mesh: Mesh) -> dict[str, int]:
    """Names of gmsh physical groups of dimension 1 -> physical tag."""
    out = {}
    for name, data in (mesh.field_data or {}).items():
        arr = np.asarray(data).reshape(-1)
        if arr.size >= 2 and int(arr[1]) == 1:
            out[str(name)] = int(arr[0])
    return out


def _select_cells(mesh: Mesh, group: str | None, path: Path) -> list[tuple[str, NDArray[np.int64]]]:
    """1D cell blocks (type, connectivity), restricted to the physical group ``group`` if given."""
    blocks = [(i, b.type, np.asarray(b.data)) for i, b in enumerate(mesh.cells)
              if _CURVE_CELL.match(b.type) and len(b.data)]
    if not blocks:
        found = sorted({b.type for b in mesh.cells}) or ["none"]
        raise GeometryError(f"{path} has no 1D (line) cells to build a curve from; cell types "
                            f"found: {', '.join(found)}")
    if group is None:
        return [(t, d) for _, t, d in blocks]
    groups = _curve_groups(mesh)
    phys = (mesh.cell_data or {}).get("gmsh:physical")
    sets = _line_cell_sets(mesh, [i for i, _, _ in blocks])
    out = []
    if group in groups and phys is not None:
        tag = groups[group]
        for i, t, d in blocks:
            mask = np.asarray(phys[i]).reshape(-1) == tag
            if np.any(mask):
                out.append((t, d[mask]))
    elif group in sets:
        for i, t, d in blocks:
            idx = sets[group].get(i)
            if idx is not None and idx.size:
                out.append((t, d[idx]))
    else:
        names = ", ".join(sorted(set(groups) | set(sets))) or "none (the file has no named curves)"
        other = {str(k): int(np.asarray(v).reshape(-1)[1])
                 for k, v in (mesh.field_data or {}).items() if np.asarray(v).size >= 2}
        if group in other:
            raise GeometryError(f"group '{group}' in {path} has dimension {other[group]}, not a "
                                f"curve; curve groups: {names}")
        raise GeometryError(f"unknown group '{group}' in {path}; available curve groups: {names}")
    if not out:
        raise GeometryError(f"group '{group}' in {path} contains no line cells")
    return out


def _line_cell_sets(mesh: Mesh, line_blocks: list[int]) -> dict[str, dict[int, NDArray[np.int64]]]:
    """Named cell sets (meshio ``cell_sets``, e.g. from XDMF or gmsh) that contain line cells."""
    out: dict[str, dict[int, NDArray[np.int64]]] = {}
    for name, per_block in (getattr(mesh, "cell_sets", None) or {}).items():
        if str(name).startswith("gmsh:") or len(per_block) != len(mesh.cells):
            continue
        sel = {i: np.asarray(per_block[i], dtype=np.int64).reshape(-1) for i in line_blocks
               if per_block[i] is not None and np.asarray(per_block[i]).size}
        if sel:
            out[str(name)] = sel
    return out


def _merge_points(points: NDArray[np.float64], used: NDArray[np.int64]) -> NDArray[np.int64]:
    """Map every used point id to a representative id (points within the merge tolerance)."""
    rep = np.arange(points.shape[0])
    sub = points[used]
    diag = float(np.linalg.norm(np.ptp(sub, axis=0))) if len(used) > 1 else 0.0
    if diag == 0.0:
        return rep
    pairs = cKDTree(sub).query_pairs(MERGE_TOL * diag, output_type="ndarray")
    if len(pairs):
        n = len(used)
        graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
        _, label = connected_components(graph, directed=False)
        first = np.full(label.max() + 1, -1)
        for k in range(n - 1, -1, -1):  # smallest local index of each cluster represents it
            first[label[k]] = k
        rep[used] = used[first[label]]
    return rep


def _segments(cells: list[tuple[str, NDArray[np.int64]]], rep: NDArray[np.int64],
              points: NDArray[np.float64], path: Path) -> list[_Segment]:
    segs: list[_Segment] = []
    seen: set[tuple[int, int, tuple[int, ...]]] = set()
    for _, data in cells:
        for row in data:
            ids = [int(rep[k]) for k in row]
            a, b, interior = ids[0], ids[1], tuple(ids[2:])
            if a == b:
                raise GeometryError(f"{path}: a line cell starts and ends at the same point "
                                    f"{points[a].tolist()}; remove degenerate cells")
            # the same cell listed twice (e.g. a curve in two physical groups) counts once;
            # listed in both directions, the curve goes out and back along it: not a beam
            if (a, b, interior) in seen:
                continue
            if (b, a, interior[::-1]) in seen:
                raise GeometryError(
                    f"{path}: the curve folds back on itself: the cell from "
                    f"{points[a].tolist()} to {points[b].tolist()} is traversed in both "
                    "directions; a beam centreline cannot retrace itself (split it into two "
                    "beams or remove the returning cells)")
            seen.add((a, b, interior))
            segs.append(_Segment(a, b, interior))
    return segs


def _chain(segs: list[_Segment], points: NDArray[np.float64], path: Path,
           group: str | None, groups: list[str]) -> tuple[list[tuple[_Segment, bool]], bool]:
    """Order segments into one path. Returns [(segment, reversed?)] and whether it is closed."""
    degree: Counter[int] = Counter()
    adj: dict[int, list[int]] = {}
    for k, s in enumerate(segs):
        for v in (s.a, s.b):
            degree[v] += 1
            adj.setdefault(v, []).append(k)
    nodes = sorted(adj)
    index = {v: i for i, v in enumerate(nodes)}
    rows = [index[s.a] for s in segs]
    cols = [index[s.b] for s in segs]
    graph = coo_matrix((np.ones(len(segs)), (rows, cols)), shape=(len(nodes), len(nodes)))
    n_comp, _ = connected_components(graph, directed=False)
    if n_comp > 1:
        if group is None:
            hint = (f"pass group=... (curve groups in the file: {', '.join(groups)})" if groups
                    else "split the file or give it physical groups and pass group=...")
            raise GeometryError(f"{path} contains {n_comp} disconnected curves; {hint}")
        raise GeometryError(f"group '{group}' in {path} contains {n_comp} disconnected curves; "
                            "one beam needs one connected curve")
    branch = [v for v in nodes if degree[v] > 2]
    if branch:
        raise GeometryError(f"{path}: the curve branches at point {points[branch[0]].tolist()} "
                            f"({degree[branch[0]]} cells meet there); a beam centreline must be "
                            "a single unbranched path")
    ends = [v for v in nodes if degree[v] == 1]
    closed = not ends
    v, k = (segs[0].a, 0) if closed else (ends[0], adj[ends[0]][0])
    order: list[tuple[_Segment, bool]] = []
    used = np.zeros(len(segs), dtype=bool)
    first_flipped = False
    while True:
        used[k] = True
        s = segs[k]
        flipped = s.a != v
        if k == 0:
            first_flipped = flipped
        order.append((s, flipped))
        v = s.a if flipped else s.b
        nxt = [j for j in adj[v] if not used[j]]
        if not nxt:
            break
        k = nxt[0]
    # orientation: follow the stored direction of most cells (a tie: that of the first cell)
    forward = sum(not f for _, f in order)
    if 2 * forward < len(order) or (2 * forward == len(order) and first_flipped):
        order = [(s, not f) for s, f in reversed(order)]
    return order, closed


def _tangent_data(mesh: Mesh, name: str, path: Path) -> NDArray[np.float64]:
    data = (mesh.point_data or {}).get(name)
    if data is None:
        known = ", ".join(sorted(mesh.point_data or {})) or "none"
        raise GeometryError(f"point data '{name}' not found in {path}; point data fields: {known}")
    t = np.asarray(data, dtype=float)
    if t.ndim != 2 or t.shape[1] not in (2, 3):
        raise GeometryError(f"point data '{name}' in {path} must be vectors (n, 3), got {t.shape}")
    if t.shape[1] == 2:
        t = np.hstack([t, np.zeros((t.shape[0], 1))])
    return t


def _tangent_dots(pts: NDArray[np.float64], t: NDArray[np.float64],
                  closed: bool) -> NDArray[np.float64]:
    """Smallest projection of each point's tangent on its adjacent chords (both neighbours)."""
    nxt = np.roll(pts, -1, axis=0) - pts
    if not closed:
        nxt[-1] = pts[-1] - pts[-2]
    prev = np.roll(nxt, 1, axis=0)
    if not closed:
        prev[0] = nxt[0]
    return np.minimum(np.einsum("ij,ij->i", t, nxt), np.einsum("ij,ij->i", t, prev))


def read_curve(path: str | os.PathLike[str], *, group: str | None = None,
               elements: int | None = None, tangents_field: str | None = None) -> Centerline:
    """Centreline from the 1D cells of a mesh file.

    - ``group``: gmsh physical curve name selecting the cells (needed when the file holds several
      disconnected curves).
    - ``elements``: resample to that many equal arc-length elements (see :func:`polyline`);
      ``None`` gives one element per cell (higher-order cells: their interior points only
      help to fit the nodal tangents).
    - ``tangents_field``: point-data vectors to use as nodal tangents instead of Bessel tangents.

    The path follows the stored direction of most cells; a closed chain gives a closed Centerline.
    """
    p = Path(path)
    mesh = _read(p)
    cells = _select_cells(mesh, group, p)
    points = np.asarray(mesh.points, dtype=float)
    if points.ndim != 2 or points.shape[1] not in (2, 3):
        raise GeometryError(f"{p}: points must have 2 or 3 coordinates, got shape {points.shape}")
    if points.shape[1] == 2:
        points = np.hstack([points, np.zeros((points.shape[0], 1))])
    used = np.unique(np.concatenate([d.reshape(-1) for _, d in cells]))
    if not np.all(np.isfinite(points[used])):
        raise GeometryError(f"{p}: curve points contain NaN or infinite coordinates")
    rep = _merge_points(points, used)
    segs = _segments(cells, rep, points, p)
    line_blocks = [i for i, b in enumerate(mesh.cells) if _CURVE_CELL.match(b.type)]
    names = sorted(set(_curve_groups(mesh)) | set(_line_cell_sets(mesh, line_blocks)))
    order, closed = _chain(segs, points, p, group, names)

    # node ids along the path: cell end points, and all points (with interior ones)
    nodes = [order[0][0].b if order[0][1] else order[0][0].a]
    dense = list(nodes)
    is_node = [True]
    for s, flipped in order:
        inner = s.interior[::-1] if flipped else s.interior
        end = s.a if flipped else s.b
        dense.extend(inner)
        is_node.extend([False] * len(inner))
        dense.append(end)
        is_node.append(True)
        nodes.append(end)
    if closed:  # the last end point is the first node again
        nodes, dense, is_node = nodes[:-1], dense[:-1], is_node[:-1]

    tangents = None
    if tangents_field is not None:
        tdata = _tangent_data(mesh, tangents_field, p)
        if tdata.shape[0] != points.shape[0]:
            raise GeometryError(f"point data '{tangents_field}' has {tdata.shape[0]} rows for "
                                f"{points.shape[0]} points")
        tangents = tdata[dense]
        dots = _tangent_dots(points[dense], tangents, closed)
        if np.sum(dots) < 0.0:  # the field runs the other way: follow it
            dense, is_node, nodes = dense[::-1], is_node[::-1], nodes[::-1]
            if closed:  # keep the same first node
                dense, is_node, nodes = dense[-1:] + dense[:-1], is_node[-1:] + is_node[:-1], \
                    nodes[-1:] + nodes[:-1]
            tangents = tdata[dense]
            dots = _tangent_dots(points[dense], tangents, closed)
        bad = np.flatnonzero(dots <= 0.0)
        if bad.size:
            raise GeometryError(f"tangent field '{tangents_field}' points against the curve near "
                                f"{points[dense[int(bad[0])]].tolist()}; fix its sign or omit it")

    dense_pts = points[dense]
    if elements is not None:
        return polyline(dense_pts, tangents, closed=closed, elements=elements)
    if len(nodes) == len(dense):
        return polyline(dense_pts, tangents, closed=closed)
    # higher-order cells: elements between cell end points, tangents fitted through all points
    t_all = bessel_tangents(dense_pts, closed) if tangents is None else tangents
    mask = np.asarray(is_node)
    node_pts, node_t = dense_pts[mask], t_all[mask]
    return Centerline(node_pts, node_t, hermite_lengths(node_pts, node_t, closed), closed=closed)

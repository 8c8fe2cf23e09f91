"""VTU/PVD time series of the deformed system (DESIGN.md, "Output folder").

Each output step is **one** ``.vtu`` file (XML UnstructuredGrid, written here without vtk or
pyvista) holding every block of the model in a single grid, and the ``.pvd`` collection lists
one ``DataSet`` per step. One grid per step keeps the series to one file per frame, lets meshio
read a frame as one mesh and lets ParaView show everything after opening the ``.pvd``; blocks
are told apart by integer cell data (no strings, so every reader handles them):

==============  =========================================================================
cell data       meaning
==============  =========================================================================
``block_id``    0 = beam centreline segment (VTK_LINE), 1 = rigid-body surface triangle
                (VTK_TRIANGLE), 2 = contact point (VTK_VERTEX)
``beam_id``     index of the beam in ``model.beams`` (-1 on other blocks)
``body_id``     index of the body in ``model.bodies`` (-1 on other blocks)
==============  =========================================================================

The names behind ``beam_id``/``body_id`` are listed in ``summary.json`` (``vtu_blocks``).
Point data: ``displacement``, ``velocity`` (beams, bodies; zero on contact points),
``arc_length`` (reference arc length from the first node), ``axial_strain``, ``curvature``
(the curvature vector K = r'×r''/(|r'|² μ) of the cable), ``curvature_magnitude`` (beams),
``gap``, ``normal_force``, ``normal`` (contact points). Arrays that do not apply to a block
hold NaN there. Field data: ``time`` and ``TimeValue`` (the name ParaView/VTK recognise).

Beams are finely sampled polylines stored as VTK_LINE segments (meshio cannot read
VTK_POLY_LINE): ``samples_per_element`` points per element at ξ = k/n, positions exact on the
cubic Hermite centreline. In ParaView use *Extract Surface* then *Tube* to draw them as rods
(pyvista: ``extract_surface().strip().tube(radius=...)``).

Writing is crash-safe: every ``.vtu`` goes to a temporary file renamed into place, and the
``.pvd`` index is rewritten atomically after every frame, so a run that stops early leaves a
readable series of all frames written so far.
"""

from __future__ import annotations

import base64
import os
import re
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING

import numpy as np

from ..elements import ancf_cable as cable
from ..elements import rigid_body as rb
from ..errors import ModelError

if TYPE_CHECKING:
    from ..assembly import Assembly
    from ..model import RigidBody
    from ..solvers.generalized_alpha import State

VTK_VERTEX = 1
VTK_LINE = 3
VTK_POLY_LINE = 4
VTK_TRIANGLE = 5
VTK_QUAD = 9
VTK_LAGRANGE_CURVE = 68

BLOCK_BEAM = 0
BLOCK_BODY = 1
BLOCK_CONTACT = 2
BLOCK_NAMES = {BLOCK_BEAM: "beam", BLOCK_BODY: "rigid_body", BLOCK_CONTACT: "contact"}

#: point-data arrays padded with zeros (not NaN) on blocks where they do not apply, so that
#: "warp by vector" keeps every point finite
_ZERO_PADDED = ("displacement", "velocity")

_VTK_TYPES = {
    np.dtype(np.float64): "Float64", np.dtype(np.float32): "Float32",
    np.dtype(np.int64): "Int64", np.dtype(np.int32): "Int32", np.dtype(np.uint8): "UInt8",
}


# =============================================================================== mesh container
def _cat(parts: list[np.ndarray], dtype: type) -> np.ndarray:
    return np.concatenate(parts).astype(dtype) if parts else np.zeros(0, dtype)


@dataclass
class VTUMesh:
    """One unstructured grid: points (n, 3), cell blocks, point/cell/field data.

    ``cells`` is a list of ``(vtk_cell_type, connectivity)``; ``connectivity`` is an integer
    array ``(n_cells, nodes_per_cell)`` or, for variable-size cells (poly lines), a list of 1-D
    arrays. ``point_data`` values are ``(n,)`` or ``(n, k)``; ``cell_data`` values have one row
    per cell in the order of ``cells``; ``field_data`` values are small 1-D arrays.
    """

    points: np.ndarray
    cells: list[tuple[int, np.ndarray | list[np.ndarray]]] = field(default_factory=list)
    point_data: dict[str, np.ndarray] = field(default_factory=dict)
    cell_data: dict[str, np.ndarray] = field(default_factory=dict)
    field_data: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def n_points(self) -> int:
        return int(np.asarray(self.points).shape[0])

    @property
    def n_cells(self) -> int:
        return sum(len(c) for _, c in self.cells)

    def flat_cells(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(connectivity, offsets, types) as VTK stores them."""
        conn, offs, types = [], [], []
        end = 0
        for ctype, c in self.cells:
            if isinstance(c, np.ndarray) and c.ndim == 2:
                n, k = c.shape
                conn.append(c.reshape(-1))
                offs.append(end + k * np.arange(1, n + 1))
                end += n * k
            else:
                sizes = np.array([len(x) for x in c], dtype=np.int64)
                conn.extend(np.asarray(x, np.int64) for x in c)
                offs.append(end + np.cumsum(sizes))
                end += int(sizes.sum())
            types.append(np.full(len(c), ctype, np.uint8))
        return _cat(conn, np.int64), _cat(offs, np.int64), _cat(types, np.uint8)

    @staticmethod
    def merge(meshes: Sequence[VTUMesh]) -> VTUMesh:
        """One grid from several; arrays missing in a part are padded (NaN for floats, -1 for
        integers, zeros for ``displacement``/``velocity``)."""
        meshes = [m for m in meshes if m.n_points or m.n_cells]
        offsets = np.cumsum([0] + [m.n_points for m in meshes])
        points = (np.vstack([np.asarray(m.points, float).reshape(-1, 3) for m in meshes])
                  if meshes else np.zeros((0, 3)))
        cells: list[tuple[int, np.ndarray | list[np.ndarray]]] = []
        for m, o in zip(meshes, offsets, strict=False):
            for ctype, c in m.cells:
                if isinstance(c, np.ndarray) and c.ndim == 2:
                    cells.append((ctype, c.astype(np.int64) + o))
                else:
                    cells.append((ctype, [np.asarray(x, np.int64) + o for x in c]))

        def pad(key: str, parts: list[tuple[dict, int]]) -> np.ndarray:
            ref = next(d[key] for d, _ in parts if key in d)
            ref = np.asarray(ref)
            out = []
            for d, n in parts:
                if key in d:
                    out.append(np.asarray(d[key]).astype(ref.dtype, copy=False))
                    continue
                shape = (n,) + ref.shape[1:]
                if np.issubdtype(ref.dtype, np.integer):
                    out.append(np.full(shape, -1, ref.dtype))
                elif key in _ZERO_PADDED:
                    out.append(np.zeros(shape, ref.dtype))
                else:
                    out.append(np.full(shape, np.nan, ref.dtype))
            return np.concatenate(out) if out else ref

        pkeys = list(dict.fromkeys(k for m in meshes for k in m.point_data))
        ckeys = list(dict.fromkeys(k for m in meshes for k in m.cell_data))
        pparts = [(m.point_data, m.n_points) for m in meshes]
        cparts = [(m.cell_data, m.n_cells) for m in meshes]
        fdata: dict[str, np.ndarray] = {}
        for m in meshes:
            fdata.update(m.field_data)
        return VTUMesh(points, cells, {k: pad(k, pparts) for k in pkeys},
                       {k: pad(k, cparts) for k in ckeys}, fdata)


# =============================================================================== XML writing
def _format_array(a: np.ndarray, binary: bool) -> str:
    if binary:
        raw = np.ascontiguousarray(a).astype(a.dtype.newbyteorder("<"), copy=False).tobytes()
        return base64.b64encode(np.uint64(len(raw)).tobytes() + raw).decode("ascii")
    flat = a.reshape(-1).tolist()
    # repr of a Python float is the shortest string that round-trips exactly
    return " ".join(map(repr, flat)) if a.dtype.kind == "f" else " ".join(map(str, flat))


def _data_array(name: str, a: np.ndarray, binary: bool, *, tuples: bool = False) -> str:
    a = np.asarray(a)
    if a.dtype.kind == "b":
        a = a.astype(np.uint8)
    elif a.dtype.kind in "iu" and a.dtype not in _VTK_TYPES:
        a = a.astype(np.int64)
    elif a.dtype.kind == "f" and a.dtype not in _VTK_TYPES:
        a = a.astype(np.float64)
    ncomp = 1 if a.ndim == 1 else int(np.prod(a.shape[1:]))
    attrs = f'type="{_VTK_TYPES[a.dtype]}" Name="{name}" format="{"binary" if binary else "ascii"}"'
    if ncomp > 1:
        attrs += f' NumberOfComponents="{ncomp}"'
    if tuples:
        attrs += f' NumberOfTuples="{a.shape[0] if a.ndim else 1}"'
    return f"<DataArray {attrs}>\n{_format_array(a, binary)}\n</DataArray>\n"


def _atomic_write_text(path: Path, text: str) -> None:
    tmp = path.with_name(f".{path.name}.tmp")
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(text)
    os.replace(tmp, path)


def write_vtu(path: str | os.PathLike, mesh: VTUMesh, *, encoding: str = "binary",
              atomic: bool = True) -> Path:
    """Write ``mesh`` as a VTK XML UnstructuredGrid (``atomic``: temp file + rename; a series
    writes each frame to a new file that its ``.pvd`` lists only once complete, so it skips
    the rename).

    ``encoding="binary"`` (inline base64, exact bits) or ``"ascii"`` (shortest round-trip
    decimal, also exact)."""
    if encoding not in ("binary", "ascii"):
        raise ValueError(f"encoding must be 'binary' or 'ascii' (got {encoding!r})")
    binary = encoding == "binary"
    path = Path(path)
    pts = np.asarray(mesh.points, np.float64).reshape(-1, 3)
    conn, offs, types = mesh.flat_cells()
    n, m = pts.shape[0], types.size
    for k, v in mesh.point_data.items():
        if np.asarray(v).shape[0] != n:
            raise ValueError(f"point data '{k}' has {np.asarray(v).shape[0]} rows, mesh has {n} points")
    for k, v in mesh.cell_data.items():
        if np.asarray(v).shape[0] != m:
            raise ValueError(f"cell data '{k}' has {np.asarray(v).shape[0]} rows, mesh has {m} cells")
    out = ['<?xml version="1.0"?>\n',
           '<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" '
           'header_type="UInt64">\n<UnstructuredGrid>\n']
    if mesh.field_data:
        out.append("<FieldData>\n")
        for k, v in mesh.field_data.items():
            out.append(_data_array(k, np.atleast_1d(np.asarray(v)), binary, tuples=True))
        out.append("</FieldData>\n")
    out.append(f'<Piece NumberOfPoints="{n}" NumberOfCells="{m}">\n')
    out.append("<PointData>\n")
    out.extend(_data_array(k, np.asarray(v), binary) for k, v in mesh.point_data.items())
    out.append("</PointData>\n<CellData>\n")
    out.extend(_data_array(k, np.asarray(v), binary) for k, v in mesh.cell_data.items())
    out.append("</CellData>\n<Points>\n")
    out.append(_data_array("Points", pts, binary))
    out.append("</Points>\n<Cells>\n")
    out.append(_data_array("connectivity", conn, binary))
    out.append(_data_array("offsets", offs, binary))
    out.append(_data_array("types", types, binary))
    out.append("</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n")
    if atomic:
        _atomic_write_text(path, "".join(out))
    else:
        path.write_text("".join(out), encoding="utf-8")
    return path


class VTUSeries:
    """A time series of ``.vtu`` files indexed by a ``.pvd`` collection (context manager)::

        with VTUSeries(out_dir / "run.pvd") as series:
            series.write(t, mesh)      # vtu/run_000000.vtu, then run.pvd rewritten

    The ``.pvd`` is valid after construction (empty collection) and after every write: it is
    rewritten (atomically) after each of the first frames, then at most every
    ``pvd_interval`` seconds of wall time, and with every frame on :meth:`close` (a long series
    would otherwise rewrite an ever longer index per frame). Stale frames
    ``<name>_NNNNNN.vtu`` of an earlier run in the same folder are removed on creation.

    ``resume_at=t`` continues an existing series instead (a resumed run): the frames of the
    ``.pvd`` at times ``<= t`` are kept, later ones (and their files) are removed, and new
    frames are appended after them.
    """

    #: frames after which the index is rewritten each time, whatever ``pvd_interval``
    EAGER_FRAMES = 10

    def __init__(self, pvd_path: str | os.PathLike, *, vtu_subdir: str = "vtu",
                 encoding: str = "binary", resume_at: float | None = None,
                 pvd_interval: float = 1.0) -> None:
        if encoding not in ("binary", "ascii"):
            raise ValueError(f"encoding must be 'binary' or 'ascii' (got {encoding!r})")
        self.pvd_path = Path(pvd_path)
        self.name = self.pvd_path.stem
        self.vtu_subdir = vtu_subdir
        self.encoding = encoding
        self.vtu_dir = self.pvd_path.parent / vtu_subdir
        self.vtu_dir.mkdir(parents=True, exist_ok=True)
        self.entries: list[tuple[float, str]] = []
        if resume_at is not None:
            self.entries = [(t, f) for t, f in read_pvd(self.pvd_path) if t <= resume_at]
        keep = {Path(f).name for _, f in self.entries}
        stale = re.compile(rf"{re.escape(self.name)}_\d{{6,}}\.vtu")
        for f in self.vtu_dir.iterdir():
            if stale.fullmatch(f.name) and f.name not in keep:
                f.unlink()
        self.closed = False
        self.pvd_interval = float(pvd_interval)
        self._pvd_written = time.perf_counter()
        self._pvd_stale = False
        self._write_pvd()

    @property
    def step(self) -> int:
        """Number of frames written so far (= index of the next frame)."""
        return len(self.entries)

    def write(self, t: float, mesh: VTUMesh) -> Path:
        """Write one frame at time ``t``; returns the path of its ``.vtu``."""
        if self.closed:
            raise ValueError(f"VTUSeries {self.pvd_path} is closed")
        fname = f"{self.name}_{self.step:06d}.vtu"
        path = write_vtu(self.vtu_dir / fname, mesh, encoding=self.encoding, atomic=False)
        self.entries.append((float(t), f"{self.vtu_subdir}/{fname}"))
        self._pvd_stale = True
        if (len(self.entries) <= self.EAGER_FRAMES
                or time.perf_counter() - self._pvd_written >= self.pvd_interval):
            self._write_pvd()
        return path

    def _write_pvd(self) -> None:
        lines = ['<?xml version="1.0"?>\n',
                 '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n',
                 "<Collection>\n"]
        lines.extend(f'<DataSet timestep="{t!r}" group="" part="0" file="{f}"/>\n'
                     for t, f in self.entries)
        lines.append("</Collection>\n</VTKFile>\n")
        _atomic_write_text(self.pvd_path, "".join(lines))
        self._pvd_written = time.perf_counter()
        self._pvd_stale = False

    def close(self) -> None:
        if not self.closed and self._pvd_stale:
            self._write_pvd()
        self.closed = True

    def __enter__(self) -> VTUSeries:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.close()


_PVD_DATASET = re.compile(r'<DataSet\b[^>]*\btimestep="([^"]*)"[^>]*\bfile="([^"]*)"')


def read_pvd(pvd_path: str | os.PathLike) -> list[tuple[float, str]]:
    """``(time, relative file)`` of every ``DataSet`` of a ``.pvd`` written by
    :class:`VTUSeries` (in file order); a missing file is an empty series."""
    p = Path(pvd_path)
    if not p.is_file():
        return []
    return [(float(t), f) for t, f in _PVD_DATASET.findall(p.read_text(encoding="utf-8"))]


# =============================================================================== body shapes
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


def _mesh_surface(shape: dict, body_name: str) -> tuple[np.ndarray, np.ndarray]:
    import meshio

    try:
        m = meshio.read(shape["file"])
    except Exception as exc:  # noqa: BLE001 - re-raised with the body named
        raise ModelError(f"body '{body_name}': cannot read shape mesh {shape['file']!r} ({exc})") from exc
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


# =============================================================================== frame builder
@dataclass
class _BeamSampler:
    index: int
    dofs: np.ndarray        # (n_s, 12) element coordinates of each sample
    S: np.ndarray           # (n_s, 4) Hermite shape functions at the samples
    ref: np.ndarray         # (n_s, 3) reference positions
    arc: np.ndarray         # (n_s,) reference arc length
    flat: np.ndarray        # (n_s,) index into the (n_elem, spe+1) strain/curvature table
    segments: np.ndarray    # (n_seg, 2)
    group: int
    slc: slice
    xi: np.ndarray          # (spe+1,)


class FrameBuilder:
    """Builds :class:`VTUMesh` frames of one assembly; body surfaces are prepared once."""

    def __init__(self, asm: Assembly, *, samples_per_element: int = 8) -> None:
        if int(samples_per_element) < 1:
            raise ModelError(f"samples_per_element must be >= 1 (got {samples_per_element})")
        self.asm = asm
        self.spe = spe = int(samples_per_element)
        model = asm.model
        self.beams: list[_BeamSampler] = []
        xi_tab = np.arange(spe + 1) / spe
        for bi, beam in enumerate(model.beams):
            ne = beam.n_elem
            e = np.repeat(np.arange(ne), spe)
            k = np.tile(np.arange(spe), ne)
            if not beam.closed:
                e = np.append(e, ne - 1)
                k = np.append(k, spe)
            ns = e.size
            L = np.asarray(beam.centerline.lengths, float)
            S, _, _ = cable.shape_functions(xi_tab[k], L[e])
            dofs = asm.element_dofs(beam)[e]
            ref = np.einsum("pk,pkc->pc", S, asm.q_ref[dofs].reshape(ns, 4, 3))
            cum = np.concatenate([[0.0], np.cumsum(L)])
            seg = np.column_stack([np.arange(ns - 1), np.arange(1, ns)])
            if beam.closed:
                seg = np.vstack([seg, [ns - 1, 0]])
            gi, sl = asm.beam_slices[id(beam)]
            self.beams.append(_BeamSampler(bi, dofs, S, ref, cum[e] + xi_tab[k] * L[e],
                                           e * (spe + 1) + k, seg.astype(np.int64), gi, sl, xi_tab))
        # per-frame constants: sliced reference data, element dofs, radius and cell arrays
        self._beam_const = []
        for b in self.beams:
            beam = model.beams[b.index]
            nseg = b.segments.shape[0]
            self._beam_const.append((
                self._beam_rest(b), asm.element_dofs(beam),
                np.full(b.S.shape[0], np.nan if beam.radius is None else float(beam.radius)),
                {"block_id": np.full(nseg, BLOCK_BEAM, np.int32),
                 "beam_id": np.full(nseg, b.index, np.int32),
                 "body_id": np.full(nseg, -1, np.int32)}))
        self.bodies = []
        for bi, body in enumerate(model.bodies):
            pts, tri = body_surface(body)
            d = asm.body_dofs(body)
            q0 = asm.q_ref[d]
            ref = q0[:3] + pts @ rb.rotation_matrix(q0[3:]).T
            self.bodies.append((bi, d, pts, tri, ref))

    def _beam_rest(self, b: _BeamSampler) -> tuple[cable.CableRest, cable.CableOptions]:
        grp = self.asm.groups[b.group]
        rest: cable.CableRest = grp.rest  # type: ignore[assignment]
        n_grp = rest.length.shape[0]
        sliced = {f: (v[b.slc] if isinstance(v, np.ndarray) and v.ndim >= 1 and v.shape[0] == n_grp
                      and f not in ("axial_xi", "bending_xi") else v)
                  for f, v in rest._asdict().items()}
        return type(rest)(**sliced), grp.options

    def beam_mesh(self, b: _BeamSampler, q: np.ndarray, v: np.ndarray) -> VTUMesh:
        ns = b.S.shape[0]
        x = np.einsum("pk,pkc->pc", b.S, q[b.dofs].reshape(ns, 4, 3))
        vel = np.einsum("pk,pkc->pc", b.S, v[b.dofs].reshape(ns, 4, 3))
        (rest, options), elem_dofs, radius, cells = self._beam_const[b.index]
        eps, K = cable.axial_strain_and_curvature(q[elem_dofs], rest, options, b.xi)
        eps = eps.reshape(-1)[b.flat]
        K = K.reshape(-1, 3)[b.flat]
        return VTUMesh(
            x, [(VTK_LINE, b.segments)],
            point_data={"displacement": x - b.ref, "velocity": vel, "arc_length": b.arc,
                        "axial_strain": eps, "curvature": K,
                        "curvature_magnitude": np.linalg.norm(K, axis=1),
                        # section radius (for tubes: ParaView Tube "vary radius by scalar")
                        "radius": radius},
            cell_data=cells)

    def body_mesh(self, i: int, q: np.ndarray, v: np.ndarray) -> VTUMesh:
        bi, d, pts, tri, ref = self.bodies[i]
        r, p = q[d[:3]], q[d[3:]]
        arm = pts @ rb.rotation_matrix(p).T
        w = rb.angular_velocity_global(p, v[d[3:]])
        x = r + arm
        nt = tri.shape[0]
        return VTUMesh(
            x, [(VTK_TRIANGLE, tri)],
            point_data={"displacement": x - ref, "velocity": v[d[:3]] + np.cross(w, arm)},
            cell_data={"block_id": np.full(nt, BLOCK_BODY, np.int32),
                       "beam_id": np.full(nt, -1, np.int32),
                       "body_id": np.full(nt, bi, np.int32)})

    @staticmethod
    def contact_mesh(contacts: Sequence[dict]) -> VTUMesh:
        n = len(contacts)
        pts = np.array([contact_location(c) for c in contacts], float).reshape(n, 3)
        normal = np.array([np.asarray(c.get("normal", (np.nan,) * 3), float) for c in contacts],
                          float).reshape(n, 3)
        return VTUMesh(
            pts, [(VTK_VERTEX, np.arange(n, dtype=np.int64)[:, None])],
            point_data={"gap": np.array([float(c["gap"]) for c in contacts]),
                        "normal_force": np.array([float(c["normal_force"]) for c in contacts]),
                        "normal": normal},
            cell_data={"block_id": np.full(n, BLOCK_CONTACT, np.int32),
                       "beam_id": np.full(n, -1, np.int32),
                       "body_id": np.full(n, -1, np.int32)})

    def __call__(self, state: State, *, contacts: Sequence[dict] | None = None) -> VTUMesh:
        q = np.asarray(state.q)
        v = np.asarray(state.v)
        parts = [self.beam_mesh(b, q, v) for b in self.beams]
        parts += [self.body_mesh(i, q, v) for i in range(len(self.bodies))]
        if contacts:
            parts.append(self.contact_mesh(contacts))
        mesh = VTUMesh.merge(parts)
        t = np.array([float(state.t)])
        mesh.field_data = {"time": t, "TimeValue": t.copy()}
        return mesh


def contact_location(c: dict) -> np.ndarray:
    """Where a contact is drawn: ``position`` (3), else ``point`` when it is a 3-vector, else
    the hole point ``(qx, qy, qz)`` of the contacts.csv record."""
    if "position" in c:
        return np.asarray(c["position"], float).reshape(3)
    if "point" in c and np.size(c["point"]) == 3:
        return np.asarray(c["point"], float).reshape(3)
    try:
        return np.array([c["qx"], c["qy"], c["qz"]], float)
    except KeyError:
        raise ModelError("a contact record needs 'position' (3), 'point' (3) or qx, qy, qz "
                         f"for output (got keys {sorted(c)})") from None


def build_frame(asm: Assembly, state: State, *, samples_per_element: int = 8,
                contacts: Sequence[dict] | None = None) -> VTUMesh:
    """One output frame of ``asm`` in ``state`` (see the module docstring for the arrays)."""
    return FrameBuilder(asm, samples_per_element=samples_per_element)(state, contacts=contacts)

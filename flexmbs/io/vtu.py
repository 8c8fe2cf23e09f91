"""The VTK XML files of the output (docs/design.md, "Output folder"): frames and their time series.

:class:`VTUMesh` holds one grid (points, cell blocks, point/cell/field data); :func:`write_vtu`
writes it as a VTK XML UnstructuredGrid, :func:`write_vtp` as PolyData, both without vtk or
pyvista (inline base64 binary or exact ASCII). :class:`MultiBlock` is a tree of named grids;
:func:`write_vtm` writes it as a VTK XML multiblock ``.vtm`` with one ``.vtp`` per leaf beside
it (ParaView's block selector shows the names). :class:`VTUSeries` writes one frame per output
(a ``.vtu``, or a ``.vtm`` and its pieces) and the ``.pvd`` collection listing them;
:func:`read_pvd` reads that index back. What a frame of a model contains is
:mod:`flexmbs.io.frames`; body surfaces are :mod:`flexmbs.io.surfaces`.

Writing is crash-safe: every ``.vtu`` goes to a temporary file renamed into place, and the
``.pvd`` index is rewritten atomically after every frame, so a run that stops early leaves a
readable series of all frames written so far.
"""

from __future__ import annotations

import base64
import os
import re
import time
import weakref
import zlib
from collections.abc import Callable, Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from types import TracebackType
from typing import Any

import numpy as np

__all__ = ["VTK_LAGRANGE_CURVE", "VTK_LINE", "VTK_POLY_LINE", "VTK_QUAD", "VTK_TRIANGLE",
           "VTK_VERTEX", "MultiBlock", "VTUMesh", "VTUSeries", "frame_files", "read_pvd",
           "write_vtm", "write_vtp", "write_vtu"]

VTK_VERTEX = 1
VTK_LINE = 3
VTK_POLY_LINE = 4
VTK_TRIANGLE = 5
VTK_QUAD = 9
VTK_LAGRANGE_CURVE = 68

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
#: the encodings of the data arrays: inline base64 of the raw bytes, the same of zlib-compressed
#: blocks (VTK's ``vtkZLibDataCompressor``), or decimal text
ENCODINGS = ("binary", "zlib", "ascii")
#: uncompressed bytes per compressed block (VTK's default) and zlib's level: 1, the fastest,
#: compresses the frames' doubles nearly as well as the default 6 (benchmarks/README.md,
#: "Compressed frames")
_ZLIB_BLOCK = 32768
_ZLIB_LEVEL = 1


def _zlib_blocks(raw: bytes) -> str:
    """``raw`` as VTK's inline compressed binary: the UInt64 header (number of blocks, block
    size, size of a partial last block or 0, each block's compressed size) in base64, then the
    compressed blocks in base64 (two base64 runs, as VTK reads them)."""
    blocks = [zlib.compress(raw[i:i + _ZLIB_BLOCK], _ZLIB_LEVEL)
              for i in range(0, len(raw), _ZLIB_BLOCK)]
    header = np.array([len(blocks), _ZLIB_BLOCK, len(raw) % _ZLIB_BLOCK,
                       *(len(b) for b in blocks)], dtype="<u8")
    return (base64.b64encode(header.tobytes()).decode("ascii")
            + base64.b64encode(b"".join(blocks)).decode("ascii"))


def _zlib_unblocks(text: str) -> bytes:
    """The raw bytes of a DataArray written by :func:`_zlib_blocks`."""
    head = base64.b64decode(text[:32])           # 24 bytes: the first three UInt64 = 32 chars
    n = int(np.frombuffer(head[:8], "<u8")[0])
    size = 8 * (3 + n)
    chars = 4 * ((size + 2) // 3)
    header = np.frombuffer(base64.b64decode(text[:chars]), "<u8")
    data = base64.b64decode(text[chars:])
    out, pos = [], 0
    for c in header[3:3 + n]:
        out.append(zlib.decompress(data[pos:pos + int(c)]))
        pos += int(c)
    return b"".join(out)


def _format_array(a: np.ndarray, mode: str) -> str:
    if mode != "ascii":
        raw = np.ascontiguousarray(a).astype(a.dtype.newbyteorder("<"), copy=False).tobytes()
        if mode == "zlib":
            return _zlib_blocks(raw)
        return base64.b64encode(np.uint64(len(raw)).tobytes() + raw).decode("ascii")
    flat = a.reshape(-1).tolist()
    # repr of a Python float is the shortest string that round-trips exactly
    return " ".join(map(repr, flat)) if a.dtype.kind == "f" else " ".join(map(str, flat))


#: the encoded ``DataArray`` of read-only arrays that own their data (a series' constants:
#: cells, reference data, marked so by :class:`~flexmbs.io.frames.FrameBuilder`), by identity
_FROZEN: dict[tuple, tuple[weakref.ref, Any]] = {}


def _frozen(a: Any) -> bool:
    """Whether ``a`` is an array that nothing can change: read-only and owning its data."""
    return isinstance(a, np.ndarray) and not a.flags.writeable and a.base is None


def _remember(key: tuple, arrays: Sequence[np.ndarray], value: Any) -> None:
    if len(_FROZEN) > 4096:     # arrays gone: forget them
        for k in [k for k, (ref, _) in _FROZEN.items() if ref() is None]:
            _FROZEN.pop(k, None)
    _FROZEN[key] = (weakref.ref(arrays[0]), (tuple(weakref.ref(x) for x in arrays[1:]), value))


def _recall(key: tuple, arrays: Sequence[np.ndarray]) -> Any:
    hit = _FROZEN.get(key)
    if hit is None or hit[0]() is not arrays[0]:
        return None
    refs, value = hit[1]
    if len(refs) != len(arrays) - 1 or any(r() is not x for r, x in zip(refs, arrays[1:],
                                                                       strict=True)):
        return None
    return value


def _data_array(name: str, a: np.ndarray, mode: str, *, tuples: bool = False) -> str:
    """The ``DataArray`` element of ``a`` (that of a read-only array that owns its data is
    encoded once: such an array cannot change)."""
    if _frozen(a):
        key = ("array", id(a), name, mode, tuples)
        text = _recall(key, [a])
        if text is None:
            text = _encode_array(name, a, mode, tuples=tuples)
            _remember(key, [a], text)
        return text
    return _encode_array(name, np.asarray(a), mode, tuples=tuples)


def _encode_array(name: str, a: np.ndarray, mode: str, *, tuples: bool = False) -> str:
    if a.dtype.kind == "b":
        a = a.astype(np.uint8)
    elif a.dtype.kind in "iu" and a.dtype not in _VTK_TYPES:
        a = a.astype(np.int64)
    elif a.dtype.kind == "f" and a.dtype not in _VTK_TYPES:
        a = a.astype(np.float64)
    ncomp = 1 if a.ndim == 1 else int(np.prod(a.shape[1:]))
    form = "ascii" if mode == "ascii" else "binary"
    attrs = f'type="{_VTK_TYPES[a.dtype]}" Name="{name}" format="{form}"'
    if ncomp > 1:
        attrs += f' NumberOfComponents="{ncomp}"'
    if tuples:
        attrs += f' NumberOfTuples="{a.shape[0] if a.ndim else 1}"'
    return f"<DataArray {attrs}>\n{_format_array(a, mode)}\n</DataArray>\n"


def _atomic_write_text(path: Path, text: str) -> None:
    tmp = path.with_name(f".{path.name}.tmp")
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(text)
    os.replace(tmp, path)


def _checked_arrays(mesh: VTUMesh, n: int, m: int) -> None:
    for k, v in mesh.point_data.items():
        if np.asarray(v).shape[0] != n:
            raise ValueError(f"point data '{k}' has {np.asarray(v).shape[0]} rows, mesh has {n} points")
    for k, v in mesh.cell_data.items():
        if np.asarray(v).shape[0] != m:
            raise ValueError(f"cell data '{k}' has {np.asarray(v).shape[0]} rows, mesh has {m} cells")


def _field_xml(mesh: VTUMesh, mode: str) -> list[str]:
    if not mesh.field_data:
        return []
    out = ["<FieldData>\n"]
    out.extend(_data_array(k, np.atleast_1d(np.asarray(v)), mode, tuples=True)
               for k, v in mesh.field_data.items())
    out.append("</FieldData>\n")
    return out


def _attributes_xml(point_data: dict[str, np.ndarray], cell_data: dict[str, np.ndarray],
                    pts: np.ndarray, mode: str) -> list[str]:
    out = ["<PointData>\n"]
    out.extend(_data_array(k, np.asarray(v), mode) for k, v in point_data.items())
    out.append("</PointData>\n<CellData>\n")
    out.extend(_data_array(k, np.asarray(v), mode) for k, v in cell_data.items())
    out.append("</CellData>\n<Points>\n")
    out.append(_data_array("Points", pts, mode))
    out.append("</Points>\n")
    return out


def _encoding(encoding: str) -> str:
    if encoding not in ENCODINGS:
        raise ValueError(f"encoding must be one of {', '.join(map(repr, ENCODINGS))} "
                         f"(got {encoding!r})")
    return encoding


def _header(kind: str, mode: str) -> str:
    """The ``VTKFile`` element's opening tag (``compressor`` on zlib-compressed files)."""
    compressor = ' compressor="vtkZLibDataCompressor"' if mode == "zlib" else ""
    return (f'<VTKFile type="{kind}" version="1.0" byte_order="LittleEndian" '
            f'header_type="UInt64"{compressor}>\n<{kind}>\n')


#: ``store(path, text) -> path``: where a rendered file goes (see :func:`write_vtu`)
Store = Callable[[Path, str], Path]


def _store(path: Path, text: str, atomic: bool) -> Path:
    if atomic:
        _atomic_write_text(path, text)
    else:
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        try:
            data = memoryview(text.encode("utf-8"))
            while data:
                data = data[os.write(fd, data):]
        finally:
            os.close(fd)
    return path


def write_vtu(path: str | os.PathLike, mesh: VTUMesh, *, encoding: str = "binary",
              atomic: bool = True, store: Store | None = None) -> Path:
    """Write ``mesh`` as a VTK XML UnstructuredGrid (``atomic``: temp file + rename; a series
    writes each frame to a new file that its ``.pvd`` lists only once complete, so it skips
    the rename).

    ``encoding="binary"`` (inline base64, exact bits), ``"zlib"`` (the same, zlib-compressed
    in blocks as VTK's ``vtkZLibDataCompressor``: exact bits, smaller files) or ``"ascii"``
    (shortest round-trip decimal, also exact). ``store(path, text)``, if given, takes the
    file's text instead of writing it (a series writing in the background renders here and
    stores there)."""
    mode = _encoding(encoding)
    pts = np.asarray(mesh.points, np.float64).reshape(-1, 3)
    conn, offs, types = mesh.flat_cells()
    n, m = pts.shape[0], types.size
    _checked_arrays(mesh, n, m)
    out = ['<?xml version="1.0"?>\n',
           _header("UnstructuredGrid", mode)]
    out.extend(_field_xml(mesh, mode))
    out.append(f'<Piece NumberOfPoints="{n}" NumberOfCells="{m}">\n')
    out.extend(_attributes_xml(mesh.point_data, mesh.cell_data, pts, mode))
    out.append("<Cells>\n")
    out.append(_data_array("connectivity", conn, mode))
    out.append(_data_array("offsets", offs, mode))
    out.append(_data_array("types", types, mode))
    out.append("</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n")
    if store is not None:
        return store(Path(path), "".join(out))
    return _store(Path(path), "".join(out), atomic)


#: VTK PolyData's cell sections, in the order it numbers cells, and the cell types they hold
_POLY_SECTIONS = (("Verts", (VTK_VERTEX, 2)), ("Lines", (VTK_LINE, VTK_POLY_LINE)),
                  ("Polys", (VTK_TRIANGLE, VTK_QUAD, 7)))
#: section of each VTK cell type (-1: not a PolyData cell)
_SECTION_OF_TYPE = np.full(256, -1, np.int64)
for _k, (_, _kinds) in enumerate(_POLY_SECTIONS):
    _SECTION_OF_TYPE[list(_kinds)] = _k


def write_vtp(path: str | os.PathLike, mesh: VTUMesh, *, encoding: str = "binary",
              atomic: bool = True, store: Store | None = None) -> Path:
    """Write ``mesh`` as a VTK XML PolyData file: vertices, lines/poly lines and polygons
    (triangles, quads) only. PolyData numbers its cells verts, then lines, then polys: cell data
    is reordered so (a stable sort by section). Arguments as :func:`write_vtu`."""
    mode = _encoding(encoding)
    pts = np.asarray(mesh.points, np.float64).reshape(-1, 3)
    m, counts, order, cells_xml = _poly_cells(mesh, mode)
    n = pts.shape[0]
    _checked_arrays(mesh, n, m)
    cell_data = mesh.cell_data
    if order is not None:
        cell_data = {k: np.asarray(v)[order] for k, v in mesh.cell_data.items()}
    out = ['<?xml version="1.0"?>\n',
           _header("PolyData", mode)]
    out.extend(_field_xml(mesh, mode))
    out.append(f'<Piece NumberOfPoints="{n}" NumberOfVerts="{counts[0]}" '
               f'NumberOfLines="{counts[1]}" NumberOfStrips="0" NumberOfPolys="{counts[2]}">\n')
    out.extend(_attributes_xml(mesh.point_data, cell_data, pts, mode))
    out.extend(cells_xml)
    out.append("</Piece>\n</PolyData>\n</VTKFile>\n")
    if store is not None:
        return store(Path(path), "".join(out))
    return _store(Path(path), "".join(out), atomic)


def _poly_cells(mesh: VTUMesh, mode: str
                ) -> tuple[int, list[int], np.ndarray | None, list[str]]:
    """The cells of ``mesh`` as PolyData stores them: (number of cells, cells per section,
    the order of the cell data or None when it keeps its order, the sections' XML). Cells
    given as read-only arrays that own their data (:func:`_frozen`) are converted once."""
    arrays: list[np.ndarray] = []
    for _, c in mesh.cells:
        arrays.extend([c] if isinstance(c, np.ndarray) else c)
    key: tuple | None = None
    if arrays and all(_frozen(a) for a in arrays):
        key = ("cells", mode, tuple((t, isinstance(c, np.ndarray), len(c)) for t, c in mesh.cells),
               tuple(id(a) for a in arrays))
        hit = _recall(key, arrays)
        if hit is not None:
            return hit
    conn, offs, types = mesh.flat_cells()
    m = types.size
    section = _SECTION_OF_TYPE[types]
    if m and section.min() < 0:
        bad = sorted(set(types[section < 0].tolist()))
        raise ValueError(f"PolyData holds vertices, lines and polygons only (cell types {bad})")
    starts = np.concatenate([[0], offs[:-1]]) if m else np.zeros(0, np.int64)
    order = np.argsort(section, kind="stable")
    counts = np.bincount(section, minlength=len(_POLY_SECTIONS)).tolist()
    out: list[str] = []
    for k, (tag, _) in enumerate(_POLY_SECTIONS):
        if not counts[k]:
            continue
        ids = order[section[order] == k]
        sizes = offs[ids] - starts[ids]
        ends = np.cumsum(sizes)
        sel = conn[np.repeat(starts[ids] - (ends - sizes), sizes) + np.arange(int(ends[-1]))]
        out.append(f"<{tag}>\n")
        out.append(_data_array("connectivity", sel.astype(np.int64), mode))
        out.append(_data_array("offsets", ends.astype(np.int64), mode))
        out.append(f"</{tag}>\n")
    result = (m, counts, order if m and (np.diff(section) < 0).any() else None, out)
    if key is not None:
        _remember(key, arrays, result)
    return result


@dataclass
class MultiBlock:
    """A tree of named grids (a VTK multiblock data set): ``blocks`` is a list of
    ``(name, VTUMesh | MultiBlock)``; names are what ParaView's block selector shows."""

    blocks: list[tuple[str, VTUMesh | MultiBlock]] = field(default_factory=list)

    def leaves(self, prefix: str = "") -> list[tuple[str, VTUMesh]]:
        """``(path, grid)`` of every grid, depth first; paths join the names with ``/``."""
        out: list[tuple[str, VTUMesh]] = []
        for name, b in self.blocks:
            path = f"{prefix}{name}"
            out.extend(b.leaves(path + "/") if isinstance(b, MultiBlock) else [(path, b)])
        return out


_SLUG = re.compile(r"[^A-Za-z0-9]+")


def _piece_names(frame: MultiBlock, stem: str) -> list[str]:
    """File names of the leaves of ``frame``: ``<stem>_<top block>[_<index>...].vtp`` (the top
    block's name reduced to letters and digits, then the leaf's indices below it)."""
    names: list[str] = []

    def walk(b: MultiBlock, slug: str) -> None:
        for i, (name, child) in enumerate(b.blocks):
            part = f"{slug}_{i}" if slug else (_SLUG.sub("_", name).strip("_") or f"block{i}")
            if isinstance(child, MultiBlock):
                walk(child, part)
            else:
                names.append(f"{stem}_{part}.vtp")

    walk(frame, "")
    if len(set(names)) != len(names):    # top-level names that reduce to the same slug
        names = [f"{stem}_{i}.vtp" for i in range(len(names))]
    return names


def write_vtm(path: str | os.PathLike, frame: MultiBlock, *, encoding: str = "binary",
              atomic: bool = True, store: Store | None = None) -> list[Path]:
    """Write ``frame`` as ``path`` (``.vtm``, VTK XML multiblock) and one PolyData ``.vtp`` per
    leaf beside it (:func:`write_vtp`; named ``<stem>_<top block>[_<index>].vtp``). The pieces
    are written first, the ``.vtm`` last, so a complete ``.vtm`` lists complete pieces. Returns
    the paths, the ``.vtm`` last."""
    from xml.sax.saxutils import quoteattr

    path = Path(path)
    files = iter(_piece_names(frame, path.stem))
    written: list[Path] = []

    def block_xml(b: MultiBlock, depth: int) -> list[str]:
        out: list[str] = []
        pad = "  " * depth
        for i, (name, child) in enumerate(b.blocks):
            if isinstance(child, MultiBlock):
                out.append(f"{pad}<Block index=\"{i}\" name={quoteattr(name)}>\n")
                out.extend(block_xml(child, depth + 1))
                out.append(f"{pad}</Block>\n")
            else:
                fname = next(files)
                written.append(write_vtp(path.parent / fname, child, encoding=encoding,
                                         atomic=atomic, store=store))
                out.append(f"{pad}<DataSet index=\"{i}\" name={quoteattr(name)} "
                           f"file={quoteattr(fname)}/>\n")
        return out

    body = block_xml(frame, 1)
    text = ('<?xml version="1.0"?>\n<VTKFile type="vtkMultiBlockDataSet" version="1.0" '
            'byte_order="LittleEndian" header_type="UInt64">\n<vtkMultiBlockDataSet>\n'
            + "".join(body) + "</vtkMultiBlockDataSet>\n</VTKFile>\n")
    written.append(store(path, text) if store is not None else _store(path, text, atomic))
    return written


class VTUSeries:
    """A time series of frames indexed by a ``.pvd`` collection (context manager)::

        with VTUSeries(out_dir / "run.pvd") as series:
            series.write(t, mesh)      # vtu/run_000000.vtu, then run.pvd rewritten
            series.write(t, blocks)    # a MultiBlock: vtu/run_000001.vtm + run_000001_*.vtp

    A frame is a :class:`VTUMesh` (one ``.vtu``) or a :class:`MultiBlock` (a ``.vtm`` and its
    ``.vtp`` pieces, :func:`write_vtm`). The ``.pvd`` is valid after construction (empty
    collection) and after every write: it is rewritten (atomically) after each of the first
    frames, then at most every ``pvd_interval`` seconds of wall time, and with every frame on
    :meth:`close` (a long series would otherwise rewrite an ever longer index per frame). Stale
    frames ``<name>_NNNNNN.vtu|.vtm`` (and pieces ``<name>_NNNNNN_*.vtp``) of an earlier run in
    the same folder are removed on creation.

    ``background=True`` writes each frame's files in a worker thread while the caller goes
    on (at most one frame in flight; :meth:`flush` waits for it): the compiled integrator
    releases the GIL, so on a second core the writing costs the run nothing (an output folder's
    series is written so).

    ``resume_at=t`` continues an existing series instead (a resumed run): the frames of the
    ``.pvd`` at times ``<= t`` are kept, later ones (and their files) are removed, and new
    frames are appended after them.
    """

    #: frames after which the index is rewritten each time, whatever ``pvd_interval``
    EAGER_FRAMES = 10

    def __init__(self, pvd_path: str | os.PathLike, *, vtu_subdir: str = "vtu",
                 encoding: str = "binary", resume_at: float | None = None,
                 pvd_interval: float = 1.0, background: bool = False) -> None:
        _encoding(encoding)
        self.pvd_path = Path(pvd_path)
        self.name = self.pvd_path.stem
        self.vtu_subdir = vtu_subdir
        self.encoding = encoding
        self.vtu_dir = self.pvd_path.parent / vtu_subdir
        self.vtu_dir.mkdir(parents=True, exist_ok=True)
        self.entries: list[tuple[float, str]] = []
        if resume_at is not None:
            self.entries = [(t, f) for t, f in read_pvd(self.pvd_path) if t <= resume_at]
            self._recover_unlisted(resume_at)
        keep = {Path(f).stem for _, f in self.entries}
        stale = re.compile(rf"({re.escape(self.name)}_\d{{6,}})(\.vtu|\.vtm|_[A-Za-z0-9_]+\.vtp)")
        for f in self.vtu_dir.iterdir():
            m = stale.fullmatch(f.name)
            if m and m.group(1) not in keep:
                f.unlink()
        self.closed = False
        self.pvd_interval = float(pvd_interval)
        self._pvd_written = time.perf_counter()
        self._pvd_stale = False
        self._next = len(self.entries)
        # background writing: one worker thread, at most one frame in flight (the compiled
        # integrator releases the GIL, so the frame is written while the next steps run)
        self._worker = (ThreadPoolExecutor(max_workers=1, thread_name_prefix="flexmbs-frames")
                        if background else None)
        self._pending: Future[None] | None = None
        self._failed: BaseException | None = None
        self._write_pvd()

    def _recover_unlisted(self, resume_at: float) -> None:
        """Frames written after the last ``.pvd`` update (it is rewritten at most once per
        ``pvd_interval``) but at or before the checkpoint are part of the resumed run: list
        them again, in order, up to the first missing, unreadable (cut short by a kill) or
        later frame."""
        last = self.entries[-1][0] if self.entries else -np.inf
        k = len(self.entries)
        while True:
            t = None
            for ext in (".vtm", ".vtu"):
                fname = f"{self.name}_{k:06d}{ext}"
                if (self.vtu_dir / fname).is_file():
                    t = frame_time(self.vtu_dir / fname)
                    break
            if t is None or not last < t <= resume_at:
                return
            self.entries.append((t, f"{self.vtu_subdir}/{fname}"))
            last = t
            k += 1

    @property
    def step(self) -> int:
        """Number of frames written or being written (= index of the next frame)."""
        return self._next

    def next_path(self, frame: VTUMesh | MultiBlock) -> Path:
        """The file the next :meth:`write` of ``frame`` creates (``.vtm`` or ``.vtu``)."""
        ext = ".vtm" if isinstance(frame, MultiBlock) else ".vtu"
        return self.vtu_dir / f"{self.name}_{self.step:06d}{ext}"

    def write(self, t: float, frame: VTUMesh | MultiBlock) -> Path:
        """Write one frame at time ``t``; returns the path of its ``.vtu`` or ``.vtm``. The files
        are rendered here; with ``background`` the worker thread stores them, and an error of
        an earlier frame's write is raised here, at :meth:`flush` or at :meth:`close`."""
        if self.closed:
            raise ValueError(f"VTUSeries {self.pvd_path} is closed")
        path = self.next_path(frame)
        self._next += 1
        files: list[tuple[Path, str]] = []

        def collect(p: Path, text: str) -> Path:
            files.append((p, text))
            return p

        if isinstance(frame, MultiBlock):   # rendered here (the caller holds the GIL anyway)
            write_vtm(path, frame, encoding=self.encoding, store=collect)
        else:
            write_vtu(path, frame, encoding=self.encoding, store=collect)
        if self._worker is None:
            self._store_frame(float(t), path, files)
            return path
        self.flush()            # at most one frame in flight; it had a whole output interval
        self._pending = self._worker.submit(self._store_frame, float(t), path, files)
        return path

    def _store_frame(self, t: float, path: Path, files: list[tuple[Path, str]]) -> None:
        """The files of one frame (pieces first, the frame file last), then (when due) the
        index that lists them. File creation and writing release the GIL."""
        current = path
        try:
            for current, text in files:
                _store(current, text, atomic=False)
        except OSError as exc:    # name the file (a full disk gives no file name)
            if exc.filename is None:
                raise OSError(exc.errno, exc.strerror or str(exc), str(current)) from exc
            raise
        self.entries.append((t, f"{self.vtu_subdir}/{path.name}"))
        self._pvd_stale = True
        if (len(self.entries) <= self.EAGER_FRAMES
                or time.perf_counter() - self._pvd_written >= self.pvd_interval):
            self._write_pvd()

    def flush(self) -> None:
        """Wait for the frame being written in the background; raises its error, if any (and
        every later call raises it again: the series is broken)."""
        if self._pending is not None:
            # an interrupt (Ctrl-C, a signal turned into one) while waiting propagates and
            # leaves the frame pending, so the writer's finish waits for it again; only the
            # worker's own error breaks the series
            error = self._pending.exception()
            self._pending = None
            if error is not None:
                self._failed = error
        if self._failed is not None:
            raise self._failed

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
        """Finish the frame in flight and list every written frame in the index."""
        if self.closed:
            return
        self.closed = True
        try:
            self.flush()
        finally:
            if self._worker is not None:
                self._worker.shutdown(wait=True)
            if self._pvd_stale:
                self._write_pvd()

    def __enter__(self) -> VTUSeries:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.close()


def frame_files(path: str | os.PathLike) -> list[Path] | None:
    """The pieces a ``.vtm`` frame lists (paths beside it), or None when it is missing or
    incomplete."""
    import xml.etree.ElementTree as ET

    path = Path(path)
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError):
        return None
    return [path.parent / str(ds.get("file")) for ds in root.iter("DataSet") if ds.get("file")]


def frame_time(path: str | os.PathLike) -> float | None:
    """The ``time`` field data of a frame written by :func:`write_vtu` (of the first piece of a
    ``.vtm`` whose pieces all exist), or None when the file is missing, incomplete or has none."""
    import xml.etree.ElementTree as ET

    if str(path).endswith(".vtm"):
        pieces = frame_files(path)
        if not pieces or not all(p.is_file() for p in pieces):
            return None
        path = pieces[0]
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError):
        return None
    for arr in root.iter("DataArray"):
        if arr.get("Name") != "time":
            continue
        text = (arr.text or "").strip()
        try:
            if arr.get("format") == "binary" and root.get("compressor"):
                raw = _zlib_unblocks(text)
                return float(np.frombuffer(raw, dtype="<f8")[0])
            if arr.get("format") == "binary":
                raw = base64.b64decode(text)[8:]
                return float(np.frombuffer(raw, dtype="<f8")[0])
            return float(text.split()[0])
        except (ValueError, IndexError):
            return None
    return None


def read_pvd(pvd_path: str | os.PathLike) -> list[tuple[float, str]]:
    """``(time, relative file)`` of every ``DataSet`` of a ``.pvd`` written by
    :class:`VTUSeries` (in file order; parsed as XML, so any attribute order and quoting is
    read); a missing file is an empty series, a file that is not a ``.pvd`` index an error."""
    import xml.etree.ElementTree as ET

    from ..errors import FlexmbsError

    p = Path(pvd_path)
    if not p.is_file():
        return []
    try:
        root = ET.parse(p).getroot()
        return [(float(ds.attrib["timestep"]), ds.attrib["file"]) for ds in root.iter("DataSet")]
    except (ET.ParseError, KeyError, ValueError) as exc:
        raise FlexmbsError(f"{p}: not a readable .pvd index ({type(exc).__name__}: {exc})") from None

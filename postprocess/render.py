"""Off-screen rendering of an output folder with pyvista: PNG frames and movies.

Frames are read in either form flexmbs writes: a multiblock ``.vtm`` (groups ``beams``,
``bodies``, ``contacts``, ``springs``, ``hole_sections``) or a merged ``.vtu`` (told apart by
``block_id``), and drawn the same.
Beams (cells with ``block_id == 0``, VTK_LINE segments, or poly lines) are joined into polylines and drawn as
tubes of their section radius, coloured by a beam point field with a scalar bar; rigid bodies
(``block_id == 1``) are translucent surfaces in their pose; contact points (``block_id == 2``)
are spheres with arrows of the force on the beam, ``-normal_force * normal``, scaled so that the
largest normal force of the run is 8 % of the scene diagonal; translational spring-dampers
(``block_id == 3``, lines) are drawn as thin dark-green lines; the bore outlines of clearance
joints (``block_id == 4``, the multiblock group ``hole_sections``, e.g. a curved tube's rings)
as thin grey lines. A time label sits in the upper left;
the camera frames the bounding box of the whole motion (union over all frames), so it does not
move during a movie.

Off-screen rendering needs no X server: without ``DISPLAY`` this module selects VTK's EGL window
(``VTK_DEFAULT_OPENGL_WINDOW=vtkEGLRenderWindow``) when ``libEGL`` is installed, unless the variable
is already set (``vtkOSOpenGLRenderWindow`` selects OSMesa, if VTK finds ``libOSMesa``). See
docs/postprocess.md.
"""

from __future__ import annotations

import ctypes.util
import json
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .data import Run, read_run

CAMERAS = ("iso", "xy", "xz", "yz")
#: view direction (from the centre towards the camera) and view-up of the named cameras
_VIEWS = {"iso": ((1.0, -1.0, 1.0), (0.0, 0.0, 1.0)), "xy": ((0.0, 0.0, 1.0), (0.0, 1.0, 0.0)),
          "xz": ((0.0, -1.0, 0.0), (0.0, 0.0, 1.0)), "yz": ((1.0, 0.0, 0.0), (0.0, 0.0, 1.0))}
#: a beam radius that is not in the output is drawn as this fraction of the scene diagonal
DEFAULT_RADIUS_FRACTION = 0.004
BACKGROUND = "white"


def configure_offscreen() -> None:
    """Select VTK's EGL render window when there is no display (avoids VTK's failed attempt
    to open an X window and its warning). A user's ``VTK_DEFAULT_OPENGL_WINDOW`` is kept."""
    if os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"):
        return
    if "VTK_DEFAULT_OPENGL_WINDOW" not in os.environ and ctypes.util.find_library("EGL"):
        os.environ["VTK_DEFAULT_OPENGL_WINDOW"] = "vtkEGLRenderWindow"


#: the group of a multiblock frame that holds each block_id of the merged frame
_GROUPS = {0: "beams", 1: "bodies", 2: "contacts", 3: "springs", 4: "hole_sections"}
#: the bore outlines of clearance joints (merged frames written before they held them: none)
BORE_OUTLINES = 4


def _leaves(mb: Any) -> list[Any]:
    out: list[Any] = []
    for b in mb:
        if b is None:
            continue
        out.extend(_leaves(b) if hasattr(b, "n_blocks") else [b])
    return out


def _block(grid: Any, block: int) -> Any:
    """The cells of one block as PolyData (None when absent or empty)."""
    if hasattr(grid, "n_blocks"):        # a multiblock frame: the named group
        import pyvista as pv

        group = _GROUPS[block]
        if group not in grid.keys():   # noqa: SIM118 - block names, not data sets
            return None
        node = grid[group]
        parts = [p for p in (_leaves(node) if hasattr(node, "n_blocks") else [node])
                 if p is not None and p.n_points]
        if not parts:
            return None
        one = parts[0] if len(parts) == 1 else pv.merge(parts)
        return one if isinstance(one, pv.PolyData) else one.extract_surface(algorithm=None)
    ids = np.flatnonzero(np.asarray(grid.cell_data.get("block_id", np.zeros(grid.n_cells))) == block)
    if not ids.size:
        return None
    return grid.extract_cells(ids).extract_surface(algorithm=None)


def _bounds_union(grids: Sequence[Any]) -> np.ndarray:
    parts = [p for g in grids for p in (_leaves(g) if hasattr(g, "n_blocks") else [g])]
    b = np.array([g.bounds for g in parts if g.n_points])
    return np.array([b[:, 0].min(), b[:, 1].max(), b[:, 2].min(), b[:, 3].max(),
                     b[:, 4].min(), b[:, 5].max()])


def _scalar(mesh: Any, name: str) -> np.ndarray:
    """Point field ``name`` as a scalar (vectors by their magnitude)."""
    v = np.asarray(mesh.point_data[name], float)
    return np.linalg.norm(v, axis=1) if v.ndim == 2 else v


def _beam_fields(grid: Any) -> list[str]:
    beams = _block(grid, 0)
    if beams is None:
        return []
    return [k for k in beams.point_data if k not in ("vtkOriginalPointIds", "gap", "normal_force",
                                                     "normal", "radius")]


def _metadata_radius(run: Run) -> float | None:
    """A beam radius stored in ``summary.json["metadata"]`` (``beam_radius`` or
    ``beams: [{radius}]``), if any."""
    meta = run.summary.get("metadata") or {}
    r = meta.get("beam_radius")
    if r is None and isinstance(meta.get("beams"), list):
        rs = [float(b["radius"]) for b in meta["beams"] if isinstance(b, dict) and b.get("radius")]
        r = max(rs) if rs else None
    try:
        return float(r) if r is not None and float(r) > 0 else None
    except (TypeError, ValueError):
        return None


def _tubes(beams: Any, radius: float | None, meta_radius: float | None, fallback: float,
           scale: float) -> tuple[Any, float]:
    """One tube per beam (``beam_id``), of the radius in the point data ``radius`` (the
    section radius written by flexmbs), else ``meta_radius``, else ``fallback``; ``radius``
    overrides them all. Returns (tubes, largest drawn radius)."""
    import pyvista as pv

    ids = np.asarray(beams.cell_data.get("beam_id", np.zeros(beams.n_cells)), int)
    parts = []
    drawn = 0.0
    for bid in np.unique(ids):
        one = beams.extract_cells(np.flatnonzero(ids == bid)).extract_surface(algorithm=None)
        r = radius
        if r is None and "radius" in one.point_data:
            rr = np.asarray(one.point_data["radius"], float)
            r = float(np.nanmax(rr)) if np.isfinite(rr).any() else None
        r = r if r is not None else (meta_radius if meta_radius is not None else fallback)
        drawn = max(drawn, r * scale)
        parts.append(one.strip().tube(radius=r * scale, n_sides=20, capping=True))
    return (parts[0] if len(parts) == 1 else pv.merge(parts)), drawn


def _camera(plotter: Any, camera: str | Sequence[float] | None, bounds: np.ndarray) -> None:
    centre = 0.5 * (bounds[0::2] + bounds[1::2])
    diag = float(np.linalg.norm(bounds[1::2] - bounds[0::2])) or 1.0
    if camera is None:
        camera = "iso"
    if isinstance(camera, str):
        if camera not in CAMERAS:
            raise ValueError(f"camera must be one of {', '.join(CAMERAS)} or a position (x, y, z) "
                             f"(got '{camera}')")
        direction, up = (np.array(v) for v in _VIEWS[camera])
    else:
        pos = np.asarray(camera, float).reshape(-1)
        if pos.size != 3 or not np.all(np.isfinite(pos)):
            raise ValueError(f"a camera position needs 3 finite numbers (got {camera})")
        direction = pos - centre
        if np.linalg.norm(direction) == 0:
            raise ValueError("the camera position is the centre of the scene")
        up = np.array([0.0, 0.0, 1.0])
        if np.linalg.norm(np.cross(direction, up)) < 1e-9 * np.linalg.norm(direction):
            up = np.array([0.0, 1.0, 0.0])
    direction = direction / np.linalg.norm(direction)
    plotter.camera_position = [tuple(centre + 2.0 * diag * direction), tuple(centre), tuple(up)]
    plotter.reset_camera(render=False, bounds=tuple(bounds))
    # reset_camera fits the bounding sphere; zoom in until the box's corners fill 85 % of the
    # window (perspective projection of the 8 corners)
    cam = plotter.camera
    eye, focal = np.array(cam.position), np.array(cam.focal_point)
    fwd = (focal - eye) / np.linalg.norm(focal - eye)
    right = np.cross(fwd, np.array(cam.up))
    right /= np.linalg.norm(right)
    upv = np.cross(right, fwd)
    corners = np.array([[x, y, z] for x in bounds[0:2] for y in bounds[2:4] for z in bounds[4:6]])
    rel = corners - eye
    depth = np.maximum(rel @ fwd, 1e-12 * diag)
    tan_half = np.tan(np.radians(cam.view_angle) / 2.0)
    w, h = plotter.window_size
    extent = max(np.max(np.abs(rel @ right) / depth) / (tan_half * w / h),
                 np.max(np.abs(rel @ upv) / depth) / tan_half)
    if extent > 0:
        cam.zoom(float(np.clip(0.85 / extent, 0.2, 5.0)))


def _field_range(beam_meshes: Sequence[Any], name: str) -> tuple[float, float]:
    lo, hi = np.inf, -np.inf
    for m in beam_meshes:
        if m is not None and name in m.point_data:
            v = _scalar(m, name)
            v = v[np.isfinite(v)]
            if v.size:
                lo, hi = min(lo, float(v.min())), max(hi, float(v.max()))
    if not np.isfinite(lo):
        return 0.0, 1.0
    return (lo, hi) if hi > lo else (lo - 0.5 * (abs(lo) or 1.0), hi + 0.5 * (abs(hi) or 1.0))


def _resume_command(frame: Path) -> str:
    """``flexmbs run SCENARIO --resume DIR`` for the run folder that holds ``frame`` (the
    nearest folder above it with a ``summary.json``; the scenario from its metadata)."""
    for folder in frame.parents:
        summary = folder / "summary.json"
        if summary.is_file():
            try:
                meta = json.loads(summary.read_text(encoding="utf-8")).get("metadata") or {}
            except (OSError, ValueError, AttributeError):
                meta = {}
            scenario = meta.get("scenario_file") if isinstance(meta, dict) else None
            return f"flexmbs run {scenario or 'SCENARIO'} --resume {folder}"
    return "flexmbs run SCENARIO --resume RUN_FOLDER"


def _read_frame(pv: Any, path: Path) -> Any:
    """One frame; a missing, empty or unreadable file is an error naming it (VTK would return
    an empty grid and print to the terminal)."""
    if not path.is_file():
        raise FileNotFoundError(f"frame listed in the .pvd is missing: {path}")
    if path.stat().st_size == 0:
        raise ValueError(f"frame {path} is empty (0 bytes); the run that wrote it was cut off: "
                         f"{_resume_command(path)} rewrites the series from its checkpoint")
    import vtk

    vtk.vtkObject.GlobalWarningDisplayOff()
    try:
        grid = pv.read(str(path))
    except Exception as exc:
        raise ValueError(f"frame {path} cannot be read ({exc})") from None
    if getattr(grid, "n_blocks", None) == 0 or getattr(grid, "n_points", 1) == 0 or (
            hasattr(grid, "n_blocks") and not any(p.n_points for p in _leaves(grid))):
        raise ValueError(f"frame {path} holds no data (damaged or cut off); flexmbs run "
                         "--resume rewrites the series from its checkpoint")
    return grid


def render(out_dir: str | Path, *, movie: str | Path | None = None, png_every: int | None = None,
           camera: str | Sequence[float] | None = None, color_by: str = "curvature_magnitude",
           window_size: tuple[int, int] = (1280, 720), tube_scale: float = 1.0,
           radius: float | None = None, frames: Sequence[int] | None = None,
           framerate: float = 24.0, progress: bool = True) -> list[Path]:
    """Render the ``.pvd`` series of ``out_dir`` off-screen; returns the written files (the
    movie first, then the PNGs).

    ``movie``: ``.mp4`` (imageio-ffmpeg) or ``.gif``, one movie frame per output frame;
    ``png_every``: every N-th frame as ``out_dir/frames/<name>_<index>.png`` (default 1 when no
    movie is asked for). ``camera``: ``"iso"`` (default), ``"xy"``, ``"xz"``, ``"yz"`` or a
    camera position (x, y, z); its direction from the scene centre is kept and the distance
    chosen to frame the whole motion. ``color_by``: a beam point field (vectors by magnitude):
    ``curvature_magnitude``, ``axial_strain``, ``displacement``, ``velocity``, ``curvature``,
    ``arc_length``. Beam tubes have the section radius written in the frames (else
    ``summary.json["metadata"]["beam_radius"]``, else 0.4 % of the scene diagonal), times
    ``tube_scale``; ``radius`` overrides it. ``frames``: indices of the frames to draw (default
    all; negative indices count from the end).
    """
    configure_offscreen()
    import pyvista as pv

    pv.OFF_SCREEN = True
    run: Run = read_run(out_dir)
    if not run.frames:
        raise FileNotFoundError(f"{out_dir}: no frames in the .pvd series")
    if png_every is None and movie is None:
        png_every = 1
    if png_every is not None and int(png_every) < 1:
        raise ValueError(f"png_every must be >= 1 (got {png_every})")
    if tube_scale <= 0 or (radius is not None and radius <= 0):
        raise ValueError("tube_scale and radius must be > 0")
    if not (np.isfinite(framerate) and framerate > 0):
        raise ValueError(f"--fps: the movie frame rate must be > 0 (got {framerate:g})")
    movie_path = Path(movie) if movie is not None else None
    if movie_path is not None and movie_path.suffix.lower() not in (".mp4", ".gif"):
        raise ValueError(f"movie must end in .mp4 or .gif (got {movie_path.name})")
    w, h = (int(x) for x in window_size)
    if w < 16 or h < 16:
        raise ValueError(f"window_size too small: {window_size}")

    grids = [_read_frame(pv, p) for _, p in run.frames]
    beams_all = [_block(g, 0) for g in grids]
    fields = _beam_fields(grids[0])
    if fields and color_by not in fields:
        raise ValueError(f"unknown beam field '{color_by}' (known: {', '.join(fields)})")
    bounds = _bounds_union(grids)
    diag = float(np.linalg.norm(bounds[1::2] - bounds[0::2])) or 1.0
    clim = _field_range(beams_all, color_by)
    meta_radius = _metadata_radius(run)
    f_max = max((abs(float(c.get("normal_force") or 0.0)) for c in run.contacts), default=0.0)
    n = len(grids)
    selected = sorted(set(range(n)) if frames is None else {int(i) % n for i in frames})
    if movie_path is None:
        selected = [k for k in selected if k % int(png_every) == 0]  # type: ignore[arg-type]

    plotter = pv.Plotter(off_screen=True, window_size=[w, h])
    plotter.set_background(BACKGROUND)  # type: ignore[arg-type]
    written: list[Path] = []
    if movie_path is not None:
        movie_path.parent.mkdir(parents=True, exist_ok=True)
        if movie_path.suffix.lower() == ".gif":
            plotter.open_gif(str(movie_path), fps=framerate)
        else:   # even sizes are kept (yuv420p needs them); odd ones are rounded up by imageio
            plotter.open_movie(str(movie_path), framerate=max(1, round(framerate)), quality=7,
                               macro_block_size=2)
    frames_dir = run.directory / "frames"
    bar_title = color_by if color_by != "curvature_magnitude" else "curvature magnitude [1/m]"
    tube_mesh = None
    transient: list[Any] = []
    text = plotter.add_text(" ", position="upper_left", font_size=12, color="black")
    sphere_r = None
    try:
        from tqdm import tqdm

        it = tqdm(selected, desc="render", unit="frame", disable=not progress)
    except ImportError:  # pragma: no cover - tqdm is a core dependency
        it = selected
    for k in it:
        grid, beams = grids[k], beams_all[k]
        for actor in transient:
            plotter.remove_actor(actor, render=False)
        transient = []
        if beams is not None and beams.n_points:
            tube, tube_r = _tubes(beams, radius, meta_radius, DEFAULT_RADIUS_FRACTION * diag, tube_scale)
            sphere_r = max(1.5 * tube_r, 0.003 * diag)
            if fields:
                tube["color"] = _scalar(tube, color_by)
            if tube_mesh is None:
                tube_mesh = tube
                kw: dict[str, Any] = {"color": "steelblue"}
                if fields:
                    kw = {"scalars": "color", "clim": clim, "cmap": "viridis",
                          "scalar_bar_args": {"title": bar_title, "color": "black",
                                              "fmt": "%.3g", "vertical": False,
                                              "position_x": 0.3, "position_y": 0.04,
                                              "width": 0.4, "height": 0.07}}
                plotter.add_mesh(tube_mesh, smooth_shading=True, render=False, reset_camera=False,
                                 **kw)
            else:
                tube_mesh.copy_from(tube)
        bodies = _block(grid, 1)
        if bodies is not None and bodies.n_points:
            transient.append(plotter.add_mesh(bodies, color="orange", opacity=0.35,
                                              smooth_shading=True, render=False,
                                              reset_camera=False))
        bores = _block(grid, BORE_OUTLINES)
        if bores is not None and bores.n_points:
            transient.append(plotter.add_mesh(bores, color="dimgray", line_width=1,
                                              opacity=0.6, render=False, reset_camera=False))
        springs = _block(grid, 3)
        if springs is not None and springs.n_lines:
            transient.append(plotter.add_mesh(springs, color="darkgreen", line_width=3,
                                              render=False, reset_camera=False))
        contacts = _block(grid, 2)
        if contacts is not None and contacts.n_points:
            r_s = sphere_r if sphere_r is not None else 0.003 * diag
            pts = pv.PolyData(np.asarray(contacts.points))
            transient.append(plotter.add_mesh(
                pts.glyph(geom=pv.Sphere(radius=r_s), scale=False, orient=False), color="red",
                render=False, reset_camera=False))
            if f_max > 0 and {"normal", "normal_force"} <= set(contacts.point_data):
                vec = -(np.asarray(contacts.point_data["normal"], float)
                        * np.asarray(contacts.point_data["normal_force"], float)[:, None])
                vec = np.nan_to_num(vec) * (0.08 * diag / f_max)
                if np.abs(vec).max() > 0:
                    pts["force"] = vec
                    arrows = pts.glyph(orient="force", scale="force", factor=1.0,
                                       geom=pv.Arrow(tip_length=0.3, tip_radius=0.12,
                                                     shaft_radius=0.04))
                    transient.append(plotter.add_mesh(arrows, color="darkred", render=False,
                                                      reset_camera=False))
        text.set_text("upper_left", f"{run.name}   t = {run.frames[k][0]:.4f} s")
        if k == selected[0]:
            _camera(plotter, camera, bounds)
        plotter.render()
        if movie_path is not None:
            plotter.write_frame()
        if png_every is not None and k % int(png_every) == 0:
            frames_dir.mkdir(exist_ok=True)
            p = frames_dir / f"{run.name}_{k:06d}.png"
            plotter.screenshot(str(p))
            written.append(p)
    plotter.close()
    if movie_path is not None:
        written.insert(0, movie_path)
    return written

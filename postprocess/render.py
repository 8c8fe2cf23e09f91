"""Off-screen rendering of an output folder with pyvista: PNG frames and movies.

Beams (``block_id == 0``) are drawn as tubes of their section radius (point data ``radius``)
coloured by a point field, rigid bodies (``block_id == 1``) as translucent surfaces, contact
points (``block_id == 2``) as spheres with normal-force arrows. The camera frames the bounding
box of the whole motion. Off-screen rendering needs no display with the VTK wheels from PyPI
(they fall back to EGL/OSMesa); on systems where it does not, run under ``xvfb-run`` or set
``PYVISTA_OFF_SCREEN=true`` and a VTK build with OSMesa.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .data import Run, read_run

CAMERAS = ("iso", "xy", "xz", "yz")


def _split(grid):  # noqa: ANN001, ANN202
    """(beams, bodies, contacts) sub-meshes of one frame (None where absent)."""
    out = []
    block = np.asarray(grid.cell_data.get("block_id", np.zeros(grid.n_cells)))
    for b in (0, 1, 2):
        ids = np.flatnonzero(block == b)
        out.append(grid.extract_cells(ids).extract_surface(algorithm=None) if ids.size else None)
    return out


def _bounds_union(grids) -> np.ndarray:  # noqa: ANN001
    b = np.array([g.bounds for g in grids])
    return np.array([b[:, 0].min(), b[:, 1].max(), b[:, 2].min(), b[:, 3].max(), b[:, 4].min(),
                     b[:, 5].max()])


def render(out_dir: str | Path, *, movie: str | Path | None = None, png_every: int | None = None,
           camera: str | Sequence[float] = "iso", color_by: str = "curvature_magnitude",
           window_size: tuple[int, int] = (1280, 720), tube_scale: float = 1.0,
           frames: Sequence[int] | None = None, progress: bool = True) -> list[Path]:
    """Render the frames of ``out_dir``; returns the written files (movie and/or PNGs).

    Without ``movie`` and ``png_every`` every frame is written as PNG to ``out_dir/frames``.
    ``tube_scale`` multiplies the beam radius (thin beams in large models are invisible at
    their true radius). ``camera``: one of :data:`CAMERAS` or a camera position (x, y, z).
    ``frames``: indices of the frames to draw (default: all); frames that are neither written
    as PNG nor part of a movie are not drawn.
    """
    import pyvista as pv

    pv.OFF_SCREEN = True
    run: Run = read_run(out_dir)
    if not run.frames:
        raise FileNotFoundError(f"{out_dir}: no frames in the .pvd series")
    if png_every is None and movie is None:
        png_every = 1
    if png_every is not None and png_every < 1:
        raise ValueError("png_every must be >= 1")
    grids = [pv.read(str(p)) for _, p in run.frames]
    bounds = _bounds_union(grids)
    diag = float(np.linalg.norm(bounds[1::2] - bounds[0::2])) or 1.0
    written: list[Path] = []
    plotter = pv.Plotter(off_screen=True, window_size=list(window_size))
    plotter.set_background("white")
    movie_path = Path(movie) if movie is not None else None
    if movie_path is not None:
        movie_path.parent.mkdir(parents=True, exist_ok=True)
        if movie_path.suffix.lower() == ".gif":
            plotter.open_gif(str(movie_path))
        elif movie_path.suffix.lower() in (".mp4", ".mov", ".avi"):
            plotter.open_movie(str(movie_path), framerate=24)
        else:
            raise ValueError(f"movie must end in .mp4 or .gif (got {movie_path.name})")
    frames_dir = run.directory / "frames"
    field_range = None
    for g in grids:
        if color_by in g.point_data and g.n_points:
            vals = np.asarray(g.point_data[color_by])
            vals = np.linalg.norm(vals, axis=1) if vals.ndim == 2 else vals
            vals = vals[np.isfinite(vals)]
            if vals.size:
                lo, hi = float(vals.min()), float(vals.max())
                field_range = (min(lo, field_range[0]), max(hi, field_range[1])) if field_range \
                    else (lo, hi)
    try:
        from tqdm import tqdm
        it = tqdm(list(zip(run.frames, grids, strict=True)), desc="render", unit="frame",
                  disable=not progress)
    except ImportError:  # pragma: no cover
        it = zip(run.frames, grids, strict=True)
    f_max = max((abs(float(c.get("normal_force") or 0.0)) for c in run.contacts), default=0.0)
    selected = set(range(len(grids))) if frames is None else {int(i) % len(grids) for i in frames}
    for k, ((t, _), grid) in enumerate(it):
        if k not in selected or (movie_path is None and k % png_every):  # type: ignore[operator]
            continue
        plotter.clear()
        beams, bodies, contacts = _split(grid)
        if beams is not None and beams.n_points:
            r = np.asarray(beams.point_data.get("radius", np.full(beams.n_points, np.nan)))
            radius = float(np.nanmax(r)) if np.isfinite(r).any() else 0.004 * diag
            tube = beams.tube(radius=radius * tube_scale, n_sides=16)
            if color_by in tube.point_data:
                plotter.add_mesh(tube, scalars=color_by, clim=field_range, cmap="viridis",
                                 scalar_bar_args={"title": color_by, "color": "black"})
            else:
                plotter.add_mesh(tube, color="steelblue")
        if bodies is not None and bodies.n_points:
            plotter.add_mesh(bodies, color="orange", opacity=0.35, smooth_shading=True)
        if contacts is not None and contacts.n_points:
            plotter.add_mesh(pv.PolyData(contacts.points).glyph(
                geom=pv.Sphere(radius=0.01 * diag), scale=False, orient=False), color="red")
            if "normal" in contacts.point_data and "normal_force" in contacts.point_data and f_max:
                arrows = pv.PolyData(contacts.points)
                arrows["vec"] = (np.asarray(contacts.point_data["normal"])
                                 * np.asarray(contacts.point_data["normal_force"])[:, None]
                                 * (0.1 * diag / f_max))
                plotter.add_mesh(arrows.glyph(orient="vec", scale="vec", factor=1.0,
                                              geom=pv.Arrow()), color="darkred")
        plotter.add_text(f"t = {t:.4f} s", position="upper_left", font_size=12, color="black")
        if isinstance(camera, str):
            if camera not in CAMERAS:
                raise ValueError(f"camera must be one of {CAMERAS} or a position (x, y, z)")
            {"iso": plotter.view_isometric, "xy": plotter.view_xy, "xz": plotter.view_xz,
             "yz": plotter.view_yz}[camera]()
        else:
            centre = 0.5 * (bounds[0::2] + bounds[1::2])
            plotter.camera_position = [tuple(camera), tuple(centre), (0, 0, 1)]
        plotter.reset_camera(bounds=bounds)
        if movie_path is not None:
            plotter.write_frame()
        if png_every is not None and k % png_every == 0:
            frames_dir.mkdir(exist_ok=True)
            p = frames_dir / f"{run.name}_{k:06d}.png"
            plotter.screenshot(str(p))
            written.append(p)
    plotter.close()
    if movie_path is not None:
        written.insert(0, movie_path)
    return written

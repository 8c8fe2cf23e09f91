"""``flexmbs render DIR`` and ``flexmbs plot DIR``: pictures of an output folder by
:mod:`postprocess` (imported, with pyvista or matplotlib, only here; docs/postprocess.md)."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from ._common import EXIT_BAD_INPUT, Number, add_quiet, docs

__all__ = ["add_parsers", "run"]


def add_parsers(sub: Any) -> None:
    render = sub.add_parser("render", help="off-screen rendering of an output folder",
                            description="Render the .pvd series of DIR off-screen (pyvista): "
                                        "PNG frames and/or a movie ("
                                        f"{docs('postprocess', 'flexmbs-render-dir')}).")
    render.add_argument("directory", metavar="DIR")
    render.add_argument("--movie", metavar="FILE", help="movie file (.mp4 or .gif)")
    render.add_argument("--png-every", type=Number(integer=True, ge=1), metavar="N",
                        help="write every N-th frame as PNG to DIR/frames (default: every frame "
                             "when no --movie is given)")
    render.add_argument("--camera", default="iso",
                        help="iso | xy | xz | yz | x,y,z camera position (default iso)")
    render.add_argument("--color-by", default="curvature_magnitude", metavar="FIELD",
                        help="beam point field: curvature_magnitude (default), axial_strain, "
                             "displacement, velocity, curvature, arc_length")
    render.add_argument("--tube-scale", type=Number(gt=0), default=1.0, metavar="F",
                        help="draw beams F times thicker than their radius")
    render.add_argument("--radius", type=Number(gt=0), metavar="R",
                        help="tube radius [m] (default: the beam radius in the output)")
    render.add_argument("--size", default="1280x720", metavar="WxH", help="image size in pixels")
    render.add_argument("--fps", type=Number(gt=0), default=24.0, help="movie frame rate (default 24)")
    add_quiet(render, "no progress bar and no list of the files written")
    plot = sub.add_parser("plot", help="time-history figures of an output folder",
                          description="Write matplotlib figures (probes, energies, contact "
                                      "forces, active contacts, hole sections) to DIR/figures ("
                                      f"{docs('postprocess', 'flexmbs-plot-dir')}).")
    plot.add_argument("directory", metavar="DIR")
    plot.add_argument("--compare", metavar="OTHER_DIR", help="overlay a second run")
    plot.add_argument("--against", metavar="COLUMN",
                      help="draw the probes against this probes.csv column instead of the "
                           "time (e.g. depth_x: an insertion force against the depth)")
    plot.add_argument("--format", action="append", choices=("png", "svg", "pdf"),
                      help="figure format (repeatable; default png and svg)")
    plot.add_argument("--section", action="store_true",
                      help="also draw a hole section of each clearance joint (the paper's "
                           "Fig. 2(b); default: the middle section at the last output) and "
                           "where its contact points sit over time")
    plot.add_argument("--joint", metavar="NAME", help="section view: only this joint")
    plot.add_argument("--section-index", type=Number(integer=True), metavar="K",
                      help="section view: section K")
    plot.add_argument("--time", type=Number(), metavar="T",
                      help="section view: the output nearest to T")
    plot.add_argument("--radius", type=Number(gt=0), metavar="R",
                      help="section view: bore radius [m] (default: sections.csv)")
    plot.add_argument("--exaggeration", type=Number(gt=0), metavar="F",
                      help="section view: factor on offsets and clearance (default: clearance "
                           "drawn as half the bore radius)")
    add_quiet(plot, "do not print the files written")


def run(args: argparse.Namespace) -> int:
    """``flexmbs render`` / ``flexmbs plot``: postprocess/ (and pyvista/matplotlib) imported
    lazily; a missing extra is a one-line error."""
    import importlib.util

    needed = ("pyvista", "vtk", "matplotlib") if args.command == "render" else ("matplotlib",)
    missing = [m for m in needed if importlib.util.find_spec(m) is None]
    if args.command == "render" and args.movie and args.movie.lower().endswith(".mp4") \
            and importlib.util.find_spec("imageio_ffmpeg") is None:
        missing.append("imageio-ffmpeg")
    if missing:
        print(f"flexmbs: error: needs {', '.join(missing)}; install them with "
              'pip install -e ".[render]"', file=sys.stderr)
        return EXIT_BAD_INPUT
    try:
        import postprocess
    except ImportError as exc:
        print(f"flexmbs: error: cannot import postprocess ({exc}); install with "
              'pip install -e ".[render]"', file=sys.stderr)
        return EXIT_BAD_INPUT
    try:
        if args.command == "render":
            cam: Any = args.camera
            if "," in cam:
                try:
                    cam = tuple(float(x) for x in cam.split(","))
                except ValueError:
                    raise ValueError(f"--camera: expected x,y,z numbers (got {cam})") from None
            try:
                w, h = (int(x) for x in args.size.lower().split("x"))
            except ValueError:
                raise ValueError(f"--size: expected WxH, e.g. 1280x720 (got {args.size})") from None
            files = postprocess.render(args.directory, movie=args.movie, png_every=args.png_every,
                                       camera=cam, color_by=args.color_by, window_size=(w, h),
                                       tube_scale=args.tube_scale, radius=args.radius,
                                       framerate=args.fps, progress=not args.quiet)
        else:
            joints: list[str] = []
            if args.section:     # checked before any figure is written
                run = postprocess.read_run(args.directory)
                known = sorted({r["joint"] for r in run.sections})
                if not known:
                    raise FileNotFoundError(f"{args.directory}: no sections.csv (only clearance "
                                            "joints write it); nothing for --section")
                if args.joint and args.joint not in known:
                    raise ValueError(f"--joint {args.joint}: no such clearance joint in "
                                     f"{args.directory} (known: {', '.join(known)})")
                joints = [args.joint] if args.joint else known
            files = postprocess.plot(args.directory, compare=args.compare,
                                     formats=tuple(args.format or ("png", "svg")),
                                     against=args.against)
            for joint in joints:
                files.append(postprocess.section_view(
                    args.directory, joint=joint, section=args.section_index, time=args.time,
                    radius=args.radius, exaggeration=args.exaggeration))
                files.append(postprocess.contact_angles_view(args.directory, joint=joint))
    except (FileNotFoundError, ValueError) as exc:
        print(f"flexmbs: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    if not args.quiet:
        print(f"wrote {len(files)} file(s): {files[0] if files else '-'}"
              f"{' ...' if len(files) > 1 else ''}")
    return 0

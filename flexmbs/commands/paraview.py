"""``flexmbs paraview DIR [--screenshot PNG]``: a ready-made ParaView view of a run (issue 35).

Writes ``DIR/<name>_view.py``, a ParaView Python script (``paraview --script=...``, ``pvpython``
or ``pvbatch``) that opens the run's series (``<name>.pvd``) and draws the beams as
tubes of their true section radius (the point data ``radius``, times ``--tube-scale``), the
bodies as translucent surfaces, the contact points with arrows along the contact normal scaled
by the normal force, springs and bore outlines as lines, coloured by a beam field, with the
camera on the whole model. ``--screenshot PNG`` runs the script with ``pvbatch`` (one frame,
off-screen) when ParaView is installed; without ``pvbatch`` on PATH it says so in one line and
exits 2 (the script is written all the same). See the docs site's "Post-processing" page,
"ParaView" (docs/postprocess.md).

Both forms of frames are read: multiblock ones (the parts are blocks, taken by name with
*Extract Block*) and merged ones (one grid, the parts taken by the cell data ``block_id`` with
*Threshold*; the beams' line segments through *Extract Surface* to the *Tube*), with the same
view.

The command reads the output folder only (``summary.json``, ``contacts.csv``, the ``.pvd`` and
the first frame's beam piece, or merged grid, for the field names); it needs neither VTK nor
ParaView.
"""

from __future__ import annotations

import argparse
import atexit
import csv
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from time import sleep
from typing import Any

from ..io.vtu import frame_files, read_pvd
from ._common import Number, add_quiet, docs

__all__ = ["CAMERAS", "ViewOptions", "add_parser", "run", "screenshot", "view_script",
           "write_view_script"]

#: view direction (from the model's centre towards the camera) and view-up, as ``flexmbs render``
CAMERAS = {"iso": ((1.0, -1.0, 1.0), (0.0, 0.0, 1.0)), "xy": ((0.0, 0.0, 1.0), (0.0, 1.0, 0.0)),
           "xz": ((0.0, -1.0, 0.0), (0.0, 0.0, 1.0)), "yz": ((1.0, 0.0, 0.0), (0.0, 0.0, 1.0))}
#: beam point data that is not a field to colour by
_NOT_FIELDS = ("radius",)
#: point data of a merged frame that belongs to its contact points, not to the beams
_CONTACT_FIELDS = ("gap", "normal_force", "normal", "tangential_force", "stick")


@dataclass(frozen=True, kw_only=True)
class ViewOptions:
    """How the view draws the run: the beam field to colour by (vectors by magnitude), the
    camera (:data:`CAMERAS`), a factor on the tube radius, the screenshot size in pixels."""

    color_by: str = "curvature_magnitude"
    camera: str = "iso"
    tube_scale: float = 1.0
    size: tuple[int, int] = (1280, 720)


@dataclass(frozen=True)
class _Series:
    name: str
    pvd: Path
    blocks: list[dict]
    fields: dict[str, int]          #: beam point field -> number of components
    force_max: float                #: largest |normal force| of contacts.csv (0: none)
    merged: bool = False            #: merged frames (one .vtu each), not multiblocks


def _read_series(run_dir: Path) -> _Series:
    if not run_dir.is_dir():
        raise FileNotFoundError(f"output folder not found: {run_dir}")
    try:
        summary = json.loads((run_dir / "summary.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        raise FileNotFoundError(f"{run_dir}: no readable summary.json; not a flexmbs output "
                                "folder") from None
    pvd_name = (summary.get("files") or {}).get("pvd")
    if not pvd_name:
        raise FileNotFoundError(f"{run_dir}: the run wrote no frames (no .pvd)")
    pvd = run_dir / pvd_name
    frames = read_pvd(pvd)
    if not frames:
        raise FileNotFoundError(f"{pvd}: no frames in the series")
    forces: list[str] | None = None         # contacts.csv's normal forces (None: no file)
    contacts = run_dir / "contacts.csv"
    if contacts.is_file():
        with open(contacts, newline="", encoding="utf-8") as f:
            forces = [row.get("normal_force") or "0" for row in csv.DictReader(f)]
    try:
        force_max = max((abs(float(x)) for x in forces or ()), default=0.0)
    except ValueError:
        raise ValueError(f"{contacts}: a normal_force is not a number") from None
    force_max = force_max if math.isfinite(force_max) else 0.0
    name = str(summary.get("scenario") or pvd.stem)
    first = run_dir / frames[0][1]
    if not frames[0][1].endswith(".vtm"):       # merged frames: one grid each
        blocks = _merged_parts(summary, has_contacts=bool(forces))
        if not first.is_file():
            raise FileNotFoundError(f"{first}: missing or damaged")
        skip = _NOT_FIELDS + _CONTACT_FIELDS
        fields = _point_fields(first, skip) if any(b["kind"] == "beam" for b in blocks) else {}
        return _Series(name, pvd, blocks, fields, force_max, merged=True)
    blocks = summary.get("vtm_blocks")
    if not blocks:
        raise ValueError(f"{run_dir}/summary.json lists no blocks (vtm_blocks) of its multiblock "
                         "frames; rerun the scenario with this flexmbs")
    pieces = frame_files(first)
    if not pieces:
        raise FileNotFoundError(f"{first}: missing or damaged")
    beams = [i for i, b in enumerate(blocks) if b.get("kind") == "beam"]
    fields = _point_fields(Path(pieces[beams[0]]), _NOT_FIELDS) if beams else {}
    return _Series(name, pvd, list(blocks), fields, force_max)


def _point_fields(path: Path, skip: tuple[str, ...]) -> dict[str, int]:
    """The point data arrays of the VTK XML file ``path`` but ``skip``: name -> components."""
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError):
        raise FileNotFoundError(f"{path}: missing or damaged") from None
    return {str(arr.get("Name")): int(arr.get("NumberOfComponents", "1"))
            for pd in root.iter("PointData") for arr in pd.iter("DataArray")
            if arr.get("Name") not in skip}


def _merged_parts(summary: dict, *, has_contacts: bool) -> list[dict]:
    """The parts of merged frames as ``vtm_blocks`` lists them for multiblock ones (kind, name,
    beam radius), from ``summary.json``'s ``vtu_blocks`` (the names behind ``block_id``,
    ``beam_id``, ...): contact points when contacts.csv has rows, bore outlines when the frames
    have ``block_id`` 4 and the model clearance joints. A run of a flexmbs that wrote no
    ``beam_radius`` gets beams without radius (drawn with one radius, as stiffness beams)."""
    ids = summary.get("vtu_blocks") or {}
    radii = list(ids.get("beam_radius") or [])
    parts: list[dict] = [{"kind": "beam", "name": n,
                          "radius": radii[i] if i < len(radii) else None}
                         for i, n in enumerate(ids.get("beam_id") or [])]
    parts += [{"kind": "body", "name": n} for n in ids.get("body_id") or []]
    if has_contacts:
        parts.append({"kind": "contacts"})
    if ids.get("spring_id"):
        parts.append({"kind": "springs"})
    if "4" in (ids.get("block_id") or {}) and summary.get("hole_sections"):
        parts.append({"kind": "hole_sections"})
    return parts


def view_script(run_dir: str | os.PathLike[str], options: ViewOptions = ViewOptions()) -> str:
    """The text of the ParaView script for the run in ``run_dir`` (see the module docstring);
    an unknown ``color_by`` or camera is a :class:`ValueError` listing the known ones."""
    from .. import __version__

    run_dir = Path(run_dir)
    series = _read_series(run_dir)
    if series.fields and options.color_by not in series.fields:
        raise ValueError(f"unknown beam field '{options.color_by}' (known: "
                         f"{', '.join(series.fields)})")
    if options.camera not in CAMERAS:
        raise ValueError(f"unknown camera '{options.camera}' (known: {', '.join(CAMERAS)})")
    if not (math.isfinite(options.tube_scale) and options.tube_scale > 0):
        raise ValueError(f"--tube-scale must be a number > 0 (got {options.tube_scale})")
    w, h = (int(x) for x in options.size)
    if w < 16 or h < 16:
        raise ValueError(f"--size too small: {w}x{h}")
    kinds = {b.get("kind") for b in series.blocks}
    radii = [b.get("radius") for b in series.blocks if b.get("kind") == "beam"]
    direction, up = CAMERAS[options.camera]
    consts = {
        "NAME": series.name,
        "PVD": str(series.pvd.resolve()),
        "PVD_FILE": series.pvd.name,
        "COLOR_BY": options.color_by if series.fields else None,
        "COLOR_IS_VECTOR": series.fields.get(options.color_by, 1) > 1,
        "TUBE_SCALE": float(options.tube_scale),
        # beams given by stiffnesses have no radius: then every beam is drawn with one radius,
        # 0.4 % of the model's size (as flexmbs render does)
        "TRUE_RADIUS": bool(radii) and all(r is not None for r in radii),
        "HAS": {k: k in kinds for k in ("beam", "body", "contacts", "springs", "hole_sections")},
        # merged frames: the parts by the cell data block_id (Threshold), not by block name
        "MERGED": series.merged,
        "FORCE_MAX": series.force_max,
        "CAMERA_DIRECTION": direction,
        "CAMERA_UP": up,
        "IMAGE_SIZE": [w, h],
    }
    header = "\n".join(f"{k} = {v!r}" for k, v in consts.items())
    return (_TEMPLATE.replace("@VERSION@", __version__).replace("@NAME@", series.name)
            .replace("@FILE@", f"{series.name}_view.py").replace("@CONSTANTS@", header))


def write_view_script(run_dir: str | os.PathLike[str], options: ViewOptions = ViewOptions()
                      ) -> Path:
    """Write ``run_dir/<name>_view.py`` (:func:`view_script`); returns its path."""
    run_dir = Path(run_dir)
    text = view_script(run_dir, options)
    name = _read_series(run_dir).name
    path = run_dir / f"{name}_view.py"
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(text, encoding="utf-8")
    os.replace(tmp, path)
    return path


def headless(cmd: list[str]) -> list[str]:
    """``cmd`` (a ParaView program) run under ``xvfb-run -a`` when there is no display and
    xvfb-run is installed: ParaView builds whose rendering needs X (Debian's 5.11: pvbatch
    aborts with "bad X server connection" even with --force-offscreen-rendering) then render
    on a virtual screen; builds with EGL or OSMesa do not need it, and with a display nothing
    changes."""
    if os.environ.get("DISPLAY") or shutil.which("xvfb-run") is None:
        return cmd
    # its own auth file (xvfb-run's default, ./.Xauthority, is shared by concurrent runs from
    # one folder: a test suite's workers then failed with "bad X server connection") and its
    # own first display number to try
    pid = os.getpid()
    auth = Path(tempfile.gettempdir()) / f"flexmbs-xauth-{pid}"
    if auth not in _AUTH_FILES:
        _AUTH_FILES.add(auth)
        atexit.register(auth.unlink, missing_ok=True)
    return ["xvfb-run", "-a", "-n", str(100 + pid % 4000), "-f", str(auth), *cmd]


#: the auth files of this process's headless runs (removed when it exits)
_AUTH_FILES: set[Path] = set()

#: what ParaView says when the virtual screen it was given is not there (yet): seen under
#: xvfb-run on a loaded machine (a test suite compiling beside it); tried once more
_NO_SCREEN = "bad X server connection"


def run_headless(cmd: list[str], *, timeout: float | None = 600.0) -> subprocess.CompletedProcess:
    """Run the ParaView program ``cmd`` (under :func:`headless`), its output captured; a run
    whose virtual screen was not there is tried again, up to :data:`_SCREEN_TRIES` times in
    all, a second apart (twice was not enough once in a CI run on a loaded machine)."""
    wrapped = headless(cmd)
    proc = subprocess.run(wrapped, capture_output=True, text=True, timeout=timeout, check=False)
    for _ in range(_SCREEN_TRIES - 1):
        if proc.returncode == 0 or wrapped == cmd or _NO_SCREEN not in (proc.stderr or ""):
            break
        sleep(1.0)
        proc = subprocess.run(wrapped, capture_output=True, text=True, timeout=timeout,
                              check=False)
    return proc


#: runs of a ParaView program whose virtual screen was not there, in all (:func:`run_headless`)
_SCREEN_TRIES = 4


def screenshot(script: str | os.PathLike[str], png: str | os.PathLike[str], *,
               time: float | None = None, pvbatch: str | None = None,
               timeout: float | None = 600.0) -> Path:
    """Render one frame of the view ``script`` (at ``time``, default the last output) to
    ``png`` with ParaView's ``pvbatch`` (off-screen). Raises :class:`FileNotFoundError` when
    ``pvbatch`` is not on PATH and :class:`RuntimeError` (with pvbatch's last line) when it
    fails."""
    exe = pvbatch or shutil.which("pvbatch")
    if exe is None:
        raise FileNotFoundError("pvbatch")
    png = Path(png).resolve()
    png.parent.mkdir(parents=True, exist_ok=True)
    cmd = [exe, str(Path(script).resolve()), "--screenshot", str(png)]
    if time is not None:
        cmd += ["--time", repr(float(time))]
    before = png.stat().st_mtime_ns if png.is_file() else None
    proc = run_headless(cmd, timeout=timeout)
    lines = (proc.stderr or proc.stdout or "").strip().splitlines()
    written = png.is_file() and png.stat().st_mtime_ns != before
    if proc.returncode != 0 and written and lines and lines[-1].startswith(_XVFB_CLEANUP):
        return png     # pvbatch rendered; only xvfb-run failed to remove its own temp folder
    if proc.returncode != 0 or not png.is_file():
        raise RuntimeError(f"pvbatch failed (exit {proc.returncode})"
                           + (f": {lines[-1]}" if lines else ""))
    return png


#: xvfb-run's last line when it cannot remove its temporary folder after the program ran (it
#: then exits 5; seen with two xvfb-run at once on a loaded machine)
_XVFB_CLEANUP = "xvfb-run: error: problem while cleaning up temporary directory"


# ================================================================================ CLI
def add_parser(sub: Any) -> argparse.ArgumentParser:
    """The ``paraview`` subcommand on the subparsers ``sub`` of the ``flexmbs`` parser."""
    p = sub.add_parser(
        "paraview", help="write a ParaView view script for an output folder",
        description="Write DIR/<name>_view.py, a ParaView Python script that opens the run's "
                    "series (multiblock or merged frames) with beams as tubes of their radius, "
                    "bodies, contact "
                    "forces and the camera on the model "
                    f"({docs('postprocess', 'paraview')}).")
    p.add_argument("directory", metavar="DIR", help="output folder of a run")
    p.add_argument("--color-by", default="curvature_magnitude", metavar="FIELD",
                   help="beam point field: curvature_magnitude (default), axial_strain, "
                        "displacement, velocity, curvature, arc_length, ...")
    p.add_argument("--camera", default="iso", choices=tuple(CAMERAS),
                   help="view direction (default iso)")
    p.add_argument("--tube-scale", type=Number(gt=0), default=1.0, metavar="F",
                   help="draw beams F times thicker than their radius (default 1)")
    p.add_argument("--screenshot", metavar="PNG",
                   help="also render one frame to PNG with pvbatch (needs ParaView)")
    p.add_argument("--time", type=Number(), metavar="T",
                   help="screenshot: the output at time T (default: the last)")
    p.add_argument("--size", default="1280x720", metavar="WxH", help="screenshot size in pixels")
    add_quiet(p, "do not print the files written")
    return p


def run(args: argparse.Namespace) -> int:
    """``flexmbs paraview``: write the script, then the screenshot if asked. Exit status 0; 2 on
    a bad folder or option, or when ``--screenshot`` needs ParaView and ``pvbatch`` is not on
    PATH (the script is written); 3 when pvbatch fails."""
    try:
        w, h = (int(x) for x in str(args.size).lower().split("x"))
    except ValueError:
        print(f"flexmbs: error: --size: expected WxH, e.g. 1280x720 (got {args.size})",
              file=sys.stderr)
        return 2
    options = ViewOptions(color_by=args.color_by, camera=args.camera,
                          tube_scale=args.tube_scale, size=(w, h))
    try:
        path = write_view_script(args.directory, options)
    except (FileNotFoundError, ValueError) as exc:
        print(f"flexmbs: error: {' '.join(str(exc).split())}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"flexmbs: error: cannot write {exc.filename or args.directory}: {exc.strerror}",
              file=sys.stderr)
        return 2
    if not args.quiet:
        print(f"wrote {path}; open it with: paraview --script={path}")
    if not args.screenshot:
        return 0
    if shutil.which("pvbatch") is None:
        print("flexmbs: error: --screenshot needs ParaView's pvbatch, which is not on PATH "
              "(ParaView is not installed here); the script is written, no screenshot",
              file=sys.stderr)
        return 2
    try:
        png = screenshot(path, args.screenshot, time=args.time)
    except (RuntimeError, subprocess.TimeoutExpired) as exc:
        print(f"flexmbs: error: {' '.join(str(exc).split())}", file=sys.stderr)
        return 3
    if not args.quiet:
        print(f"wrote {png}")
    return 0


# ================================================================================ the script
#: The generated script. Only paraview.simple API present in ParaView 5.11, checked against
#: ParaView's Python documentation (paraview.org/paraview-docs, the paraview.simple pages of
#: PVDReader, ExtractBlock: ``Selectors`` = ``/Root/<block>`` paths of the data assembly, since
#: 5.10; Tube: ``Scalars``, ``VaryRadius`` 'By Absolute Scalar', ``Capping``; Glyph:
#: ``GlyphType``, ``OrientationArray``, ``ScaleArray``, ``ScaleFactor``, ``GlyphMode``
#: 'All Points'; Threshold: ``Scalars``, ``LowerThreshold``, ``UpperThreshold``,
#: ``ThresholdMethod`` 'Between', since 5.10, as pvpython 5.11's ``ListProperties()`` lists them;
#: ExtractSurface) and against ParaView 5.10/5.11 trace scripts (ColorBy, GetDisplayProperties,
#: RescaleTransferFunctionToDataRange, SetScalarBarVisibility, GetAnimationScene,
#: UpdateAnimationUsingDataTimeSteps, SaveScreenshot with ImageResolution). The Tube's number of
#: sides was renamed (NumberofSides -> NumberOfSides) between versions: the script sets
#: whichever the proxy has. Run under Debian's ParaView 5.11 (pvpython, pvbatch under
#: xvfb-run): tests/commands/test_paraview.py does so when ParaView is on PATH.
_TEMPLATE = '''"""ParaView view of the flexmbs run '@NAME@'
(written by `flexmbs paraview`, flexmbs @VERSION@).

    paraview --script=@FILE@
        the GUI, with the pipeline built
    pvpython @FILE@
        builds the view and renders it
    pvbatch @FILE@ --screenshot view.png [--time T]
        one frame (default: the last output) to a PNG, off-screen

Beams are tubes of their section radius (point data `radius`, times TUBE_SCALE), coloured by
COLOR_BY; bodies translucent surfaces; contact points with arrows along the contact normal,
their length proportional to the normal force (the largest of the run: 8 % of the model's
size); springs and the bore outlines of the hole sections as lines. The blocks of multiblock
frames are selected by name (Extract Block, /Root/beams, /Root/bodies, /Root/contacts, ...);
the parts of merged frames (MERGED) by their cell data block_id (Threshold: 0 beams, 1 bodies,
2 contact points, 3 springs, 4 bore outlines), the beams' segments through Extract Surface.
Edit the constants below to change the view.
"""
import os
import sys

from paraview.simple import (Calculator, ColorBy, ExtractBlock, ExtractSurface,
                             GetActiveViewOrCreate, GetAnimationScene, GetColorTransferFunction,
                             GetScalarBar, Glyph, PVDReader, Render, SaveScreenshot,
                             SetActiveSource, Show, Threshold, Tube)

@CONSTANTS@

# the series beside this script if the folder was moved since the script was written
try:
    _here = os.path.dirname(os.path.abspath(__file__))
    if os.path.isfile(os.path.join(_here, PVD_FILE)):
        PVD = os.path.join(_here, PVD_FILE)
except NameError:       # paraview --script runs it without __file__
    pass


def _set_first(proxy, names, value):
    """Set the first of ``names`` the proxy has (property names differ between versions)."""
    for name in names:
        try:
            setattr(proxy, name, value)
            return
        except AttributeError:
            continue


def _part(reader, name, selector, block_id):
    """One part of the series: the block ``selector`` of multiblock frames, the cells whose
    cell data block_id is ``block_id`` of merged ones."""
    if not MERGED:
        return ExtractBlock(registrationName=name, Input=reader, Selectors=[selector])
    part = Threshold(registrationName=name, Input=reader)
    part.Scalars = ["CELLS", "block_id"]
    part.LowerThreshold = block_id
    part.UpperThreshold = block_id
    _set_first(part, ("ThresholdMethod",), "Between")
    return part


def _solid_block(reader, view, name, selector, block_id, colour):
    """Show the part ``selector``/``block_id`` of the series in one colour; returns its
    display."""
    part = _part(reader, name, selector, block_id)
    shown = Show(part, view)
    shown.ColorArrayName = ["POINTS", ""]   # a solid colour (not ColorBy(.., None): 5.11)
    shown.DiffuseColor = colour
    return shown


#: the coloured displays: their colour ranges are set to the data of the time shown
_COLOURED = []


def _place_bar(lut, view, corner):
    """The colour legend of ``lut`` in a corner of its own, a third of the height, small text
    (ParaView stacks every legend at the same place by default)."""
    bar = GetScalarBar(lut, view)
    bar.WindowLocation = corner
    bar.ScalarBarLength = 0.33
    bar.TitleFontSize = 12
    bar.LabelFontSize = 10


def _option(argv, flag):
    return argv[argv.index(flag) + 1] if flag in argv and argv.index(flag) + 1 < len(argv) else None


def build_view():
    """The pipeline and the view; returns (view, reader, the output times)."""
    view = GetActiveViewOrCreate("RenderView")
    reader = PVDReader(registrationName=NAME, FileName=PVD)
    reader.UpdatePipelineInformation()
    times = list(reader.TimestepValues) if reader.TimestepValues else [0.0]
    scene = GetAnimationScene()
    scene.UpdateAnimationUsingDataTimeSteps()
    reader.UpdatePipeline(times[-1])
    b = reader.GetDataInformation().GetBounds()
    centre = [0.5 * (b[0] + b[1]), 0.5 * (b[2] + b[3]), 0.5 * (b[4] + b[5])]
    size = max(((b[1] - b[0]) ** 2 + (b[3] - b[2]) ** 2 + (b[5] - b[4]) ** 2) ** 0.5, 1e-9)

    if HAS["beam"]:
        beams = _part(reader, "beams", "/Root/beams", 0)
        if MERGED:      # line segments of an unstructured grid: the Tube takes poly data
            beams = ExtractSurface(registrationName="beam lines", Input=beams)
        if TRUE_RADIUS:
            source, scalar = beams, "radius"
            if TUBE_SCALE != 1.0:
                source = Calculator(registrationName="tube_radius", Input=beams)
                source.ResultArrayName = "tube_radius"
                source.Function = "radius*%r" % TUBE_SCALE
                scalar = "tube_radius"
            tube = Tube(registrationName="beam tubes", Input=source)
            tube.Scalars = ["POINTS", scalar]
            tube.VaryRadius = "By Absolute Scalar"
        else:
            tube = Tube(registrationName="beam tubes", Input=beams)
            tube.VaryRadius = "Off"
            tube.Radius = 0.004 * size * TUBE_SCALE
        tube.Capping = 1
        _set_first(tube, ("NumberOfSides", "NumberofSides"), 24)
        shown = Show(tube, view)
        if COLOR_BY:
            ColorBy(shown, ("POINTS", COLOR_BY, "Magnitude") if COLOR_IS_VECTOR
                    else ("POINTS", COLOR_BY))
            shown.SetScalarBarVisibility(view, True)
            GetColorTransferFunction(COLOR_BY).ApplyPreset("Viridis (matplotlib)", True)
            _COLOURED.append(shown)
            _place_bar(GetColorTransferFunction(COLOR_BY), view, "Upper Right Corner")
    if HAS["body"]:
        shown = _solid_block(reader, view, "bodies", "/Root/bodies", 1, [1.0, 0.6, 0.1])
        shown.Opacity = 0.35
    if HAS["contacts"]:
        contacts = _part(reader, "contacts", "/Root/contacts", 2)
        points = Show(contacts, view)
        points.SetRepresentationType("Points")
        points.PointSize = 8.0
        points.RenderPointsAsSpheres = 1
        points.ColorArrayName = ["POINTS", ""]
        points.DiffuseColor = [0.8, 0.0, 0.0]
        arrows = Glyph(registrationName="contact forces", Input=contacts, GlyphType="Arrow")
        arrows.OrientationArray = ["POINTS", "normal"]
        arrows.ScaleArray = ["POINTS", "normal_force"]
        arrows.ScaleFactor = 0.08 * size / (FORCE_MAX if FORCE_MAX > 0 else 1.0)
        arrows.GlyphMode = "All Points"
        shown = Show(arrows, view)
        ColorBy(shown, ("POINTS", "normal_force"))
        shown.SetScalarBarVisibility(view, True)
        _COLOURED.append(shown)
        _place_bar(GetColorTransferFunction("normal_force"), view, "Upper Left Corner")
    if HAS["springs"]:
        shown = _solid_block(reader, view, "springs", "/Root/springs", 3, [0.0, 0.45, 0.0])
        shown.LineWidth = 3.0
    if HAS["hole_sections"]:
        _solid_block(reader, view, "hole sections", "/Root/hole_sections", 4, [0.2, 0.2, 0.2])

    view.OrientationAxesVisibility = 1
    view.CameraFocalPoint = centre
    view.CameraPosition = [c + 2.0 * size * d / sum(x * x for x in CAMERA_DIRECTION) ** 0.5
                           for c, d in zip(centre, CAMERA_DIRECTION)]
    view.CameraViewUp = list(CAMERA_UP)
    view.ResetCamera()
    SetActiveSource(reader)
    return view, reader, times


def main(argv):
    view, reader, times = build_view()
    scene = GetAnimationScene()
    when = _option(argv, "--time")
    t = times[-1] if when is None else min(times, key=lambda x: abs(x - float(when)))
    scene.AnimationTime = t
    for shown in _COLOURED:      # colour ranges of the frame shown (not of the first one)
        shown.RescaleTransferFunctionToDataRange(False, True)
    png = _option(argv, "--screenshot")
    if png:
        SaveScreenshot(png, view, ImageResolution=IMAGE_SIZE)
        print("wrote %s (t = %g s)" % (png, t))
    else:
        Render(view)


main(list(getattr(sys, "argv", None) or []))
'''

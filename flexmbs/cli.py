"""Command line: ``flexmbs run | info | render | plot | sweep | compile | paraview`` (DESIGN.md,
"CLI"; ``paraview`` is :mod:`flexmbs.commands.paraview`).

``main(argv)`` returns the exit status, so tests call it directly::

    main(["run", "examples/cantilever.toml", "--t-end", "0.05", "--quiet"])

Exit status: 0 success; 2 bad input (invalid scenario or override, model or geometry error,
a folder that cannot be resumed, usage errors); 3 the run failed (divergence); 130 interrupted
(Ctrl-C). Errors are one line ``flexmbs: error: <message>`` on stderr, never a traceback; an
unexpected internal error keeps its traceback (exit 1) so that it can be reported.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, NoReturn, TextIO

from .errors import ConvergenceError, FlexmbsError, Interrupted

EXIT_OK = 0
EXIT_BAD_INPUT = 2
EXIT_FAILED = 3
EXIT_INTERRUPTED = 130

def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split()) or type(exc).__name__


def _error(message: str) -> None:
    print(f"flexmbs: error: {' '.join(message.split())}", file=sys.stderr)


# ================================================================================ parser
class _OneLineParser(argparse.ArgumentParser):
    """Usage errors in one line (``flexmbs run: error: ...; see flexmbs run -h``), exit 2,
    instead of argparse's usage block."""

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_BAD_INPUT, f"{self.prog}: error: {message}; see {self.prog} -h\n")


def build_parser() -> argparse.ArgumentParser:
    from . import __version__

    parser = _OneLineParser(
        prog="flexmbs", description="Flexible multibody dynamics: ANCF beams, rigid bodies, "
        "sliding joints with clearance. See docs/cli.md.")
    parser.add_argument("--version", action="version", version=f"flexmbs {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True,
                                parser_class=_OneLineParser)

    overrides = _OneLineParser(add_help=False)
    overrides.add_argument("--set", dest="overrides", action="append", default=[],
                           metavar="KEY=VALUE",
                           help="override a scenario value, e.g. simulation.dt=5e-4 or "
                                "beams.rod.elements=8 (repeatable)")

    run = sub.add_parser("run", parents=[overrides], help="run a scenario",
                         description="Run a scenario and write its output folder.")
    run.add_argument("scenario", metavar="SCENARIO", help="scenario file (.toml)")
    run.add_argument("--out", metavar="DIR",
                     help="output folder (default: out/<scenario name> in the current directory)")
    run.add_argument("--t-end", type=float, metavar="T", help="end time (= --set simulation.t_end=T)")
    run.add_argument("--dt", type=float, metavar="H", help="time step (= --set simulation.dt=H)")
    run.add_argument("--quiet", "-q", action="store_true",
                     help="no progress bar and no final summary (errors are still printed)")
    run.add_argument("--resume", metavar="OUT_DIR",
                     help="continue the stopped run in OUT_DIR from its checkpoint.npz to t_end, "
                          "appending to its files")
    run.add_argument("--overwrite", action="store_true",
                     help="replace the output of another scenario in the output folder")
    run.add_argument("--output-frames", choices=("multiblock", "merged"),
                     help="frames as VTK multiblocks of named blocks (.vtm, default) or one "
                          "merged grid each (.vtu) (= --set simulation.output_frames=...)")

    info = sub.add_parser("info", parents=[overrides], help="print the model of a scenario",
                          description="Print the model: coordinates, beams, bodies, constraints, "
                                      "loads, joints, probes and solver settings.")
    info.add_argument("scenario", metavar="SCENARIO", help="scenario file (.toml)")

    render = sub.add_parser("render", help="off-screen rendering of an output folder",
                            description="Render the .pvd series of DIR off-screen (pyvista): "
                                        "PNG frames and/or a movie (docs/postprocess.md).")
    render.add_argument("directory", metavar="DIR")
    render.add_argument("--movie", metavar="FILE", help="movie file (.mp4 or .gif)")
    render.add_argument("--png-every", type=int, metavar="N",
                        help="write every N-th frame as PNG to DIR/frames (default: every frame "
                             "when no --movie is given)")
    render.add_argument("--camera", default="iso",
                        help="iso | xy | xz | yz | x,y,z camera position (default iso)")
    render.add_argument("--color-by", default="curvature_magnitude", metavar="FIELD",
                        help="beam point field: curvature_magnitude (default), axial_strain, "
                             "displacement, velocity, curvature, arc_length")
    render.add_argument("--tube-scale", type=float, default=1.0, metavar="F",
                        help="draw beams F times thicker than their radius")
    render.add_argument("--radius", type=float, metavar="R",
                        help="tube radius [m] (default: the beam radius in the output)")
    render.add_argument("--size", default="1280x720", metavar="WxH", help="image size in pixels")
    render.add_argument("--fps", type=float, default=24.0, help="movie frame rate (default 24)")
    render.add_argument("--quiet", action="store_true", help="no progress bar")
    plot = sub.add_parser("plot", help="time-history figures of an output folder",
                          description="Write matplotlib figures (probes, energies, contact "
                                      "forces, active contacts, hole sections) to DIR/figures.")
    plot.add_argument("directory", metavar="DIR")
    plot.add_argument("--compare", metavar="OTHER_DIR", help="overlay a second run")
    plot.add_argument("--format", action="append", choices=("png", "svg", "pdf"),
                      help="figure format (repeatable; default png and svg)")
    plot.add_argument("--section", action="store_true",
                      help="also draw a hole section of each clearance joint (the paper's "
                           "Fig. 2(b); default: the middle section at the last output) and "
                           "where its contact points sit over time")
    plot.add_argument("--joint", metavar="NAME", help="section view: only this joint")
    plot.add_argument("--section-index", type=int, metavar="K", help="section view: section K")
    plot.add_argument("--time", type=float, metavar="T",
                      help="section view: the output nearest to T")
    plot.add_argument("--radius", type=float, metavar="R",
                      help="section view: bore radius [m] (default: sections.csv)")
    plot.add_argument("--exaggeration", type=float, metavar="F",
                      help="section view: factor on offsets and clearance (default: clearance "
                           "drawn as half the bore radius)")
    comp = sub.add_parser(
        "compile", parents=[overrides], help="compile the numba kernels ahead of a first run",
        description="Compile (or load from the cache) the numba kernels for the named kinds of "
                    "model (cable, rod: a clamped beam of these elements) or for the models of "
                    "scenario files, so that the first run starts at once (docs/cli.md).")
    comp.add_argument("targets", nargs="*", metavar="KIND_OR_SCENARIO",
                      help="cable, rod, or a scenario file (.toml); default: cable")
    comp.add_argument("--quiet", "-q", action="store_true", help="no output but errors")

    sweep = sub.add_parser(
        "sweep", parents=[overrides], help="run variants of a scenario on Dask (parameter study)",
        description="Run the Cartesian product of --grid lists (times the --zip lists taken side "
                    "by side) of --set overrides on Dask, one output folder per case, and write "
                    "the table sweep.csv (docs/sweeps.md). A rerun skips completed cases.")
    sweep.add_argument("scenario", metavar="SCENARIO", help="scenario file (.toml)")
    sweep.add_argument("--grid", action="append", default=[], metavar="KEY=V1,V2,...",
                       help="values of one --set key; several --grid give their product")
    sweep.add_argument("--zip", action="append", default=[], metavar="KEY=V1,V2,...",
                       help="values taken side by side with the other --zip lists (same length)")
    sweep.add_argument("--out", metavar="DIR",
                       help="sweep folder (default: out/<scenario name>_sweep)")
    sweep.add_argument("--scheduler", metavar="ADDRESS",
                       help="an existing Dask scheduler (tcp://host:8786 or a scheduler file); "
                            "default: a LocalCluster on this machine")
    sweep.add_argument("--workers", type=int, metavar="N",
                       help="LocalCluster worker processes (default: one per core)")
    sweep.add_argument("--quiet", "-q", action="store_true", help="no progress output")
    from .commands import paraview as paraview_command

    paraview_command.add_parser(sub)
    return parser


def _one_line_warnings() -> None:
    """Every warning as one line on stderr: flexmbs' own as ``flexmbs: warning: ...``, a
    library's (numpy, meshio, ...) as ``flexmbs: warning: RuntimeWarning (numpy, file.py:12):
    ...`` instead of Python's two lines with the source line (issue "nothing lost")."""
    import warnings

    from .errors import FlexmbsWarning

    if getattr(warnings.showwarning, "flexmbs", False):
        return

    def showwarning(message: Any, category: type[Warning], filename: str, lineno: int,
                    file: Any = None, line: str | None = None) -> None:
        text = " ".join(str(message).split())
        if not issubclass(category, FlexmbsWarning):
            parts = Path(filename).parts
            origin = next((p for p in reversed(parts[:-1]) if p not in ("site-packages", "lib")),
                          "")
            where = "/".join(x for x in (origin, Path(filename).name) if x)
            text = f"{category.__name__} ({where}:{lineno}): {text}"
        print(f"flexmbs: warning: {text}", file=sys.stderr)

    showwarning.flexmbs = True  # type: ignore[attr-defined]
    warnings.showwarning = showwarning


def main(argv: Sequence[str] | None = None) -> int:
    """The ``flexmbs`` command; returns the exit status. Ctrl-C at any moment (also while the
    libraries load) is one line and exit 130."""
    try:
        return _main(argv)
    except KeyboardInterrupt:
        _error("interrupted")
        return EXIT_INTERRUPTED


def console_main() -> None:
    """Entry point of the ``flexmbs`` console script and of ``python -m flexmbs``: runs the
    command, then leaves with its status. Once the command has returned its files are closed,
    so a Ctrl-C arriving then is ignored rather than ending the process by SIGINT; after an
    interrupt, a flag left set by a Ctrl-C that landed while a library was loading could end it
    so as well: the process leaves at once with 130."""
    import os
    import signal

    code = main()
    with contextlib.suppress(ValueError):
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    sys.stdout.flush()
    sys.stderr.flush()
    if code == EXIT_INTERRUPTED:
        os._exit(code)
    sys.exit(code)


def _main(argv: Sequence[str] | None) -> int:
    _one_line_warnings()
    parser = build_parser()
    try:
        args = parser.parse_args(None if argv is None else list(argv))
    except SystemExit as exc:   # --help, --version, usage errors (argparse printed them)
        return exc.code if isinstance(exc.code, int) else EXIT_BAD_INPUT
    try:
        if args.command == "run":
            return cmd_run(args)
        if args.command == "info":
            return cmd_info(args)
        if args.command in ("render", "plot"):
            return cmd_postprocess(args)
        if args.command == "sweep":
            return cmd_sweep(args)
        if args.command == "compile":
            return cmd_compile(args)
        if args.command == "paraview":
            from .commands import paraview as paraview_command

            return paraview_command.run(args)
    except BrokenPipeError:   # e.g. `flexmbs info ... | head`: the reader left, not an error
        import os

        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 0
    raise AssertionError(f"unhandled command {args.command}")  # pragma: no cover


def cmd_postprocess(args: argparse.Namespace) -> int:
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
                                     formats=tuple(args.format or ("png", "svg")))
            for joint in joints:
                files.append(postprocess.section_view(
                    args.directory, joint=joint, section=args.section_index, time=args.time,
                    radius=args.radius, exaggeration=args.exaggeration))
                files.append(postprocess.contact_angles_view(args.directory, joint=joint))
    except (FileNotFoundError, ValueError) as exc:
        print(f"flexmbs: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    print(f"wrote {len(files)} file(s): {files[0] if files else '-'}"
          f"{' ...' if len(files) > 1 else ''}")
    return 0


# ================================================================================ run
def _overrides(args: argparse.Namespace) -> list[str]:
    sets = list(args.overrides)
    if getattr(args, "t_end", None) is not None:
        sets.append(f"simulation.t_end={args.t_end!r}")
    if getattr(args, "dt", None) is not None:
        sets.append(f"simulation.dt={args.dt!r}")
    if getattr(args, "output_frames", None) is not None:
        sets.append(f"simulation.output_frames={args.output_frames}")
    return sets


class _Progress:
    """tqdm bar over simulated time with steps/s and Newton iterations in the postfix."""

    def __init__(self, t0: float, t_end: float, *, disable: bool, name: str) -> None:
        self.bar: Any = None
        self.t0 = t0
        self.wall0 = time.perf_counter()
        self.last = 0.0
        if disable:
            return
        from tqdm import tqdm

        self.bar = tqdm(total=t_end, initial=t0, desc=name, unit="s", file=sys.stderr,
                        dynamic_ncols=True, leave=True,
                        bar_format="{desc}: {percentage:3.0f}%|{bar}| t = {n:.4g}/{total:.4g} s "
                                   "[{elapsed}<{remaining}{postfix}]")

    def __call__(self, state: Any, stats: Any) -> None:
        _raise_pending()
        if self.bar is None:
            return
        self.stats = stats
        self.bar.n = float(state.t)
        now = time.perf_counter()
        if now - self.last >= 0.1:
            self.last = now
            self._postfix(now)
            self.bar.refresh()

    def _postfix(self, now: float) -> None:
        stats = getattr(self, "stats", None)
        if stats is None:
            return
        rate = stats.steps / max(now - self.wall0, 1e-9)
        post = {"steps": stats.steps, "steps/s": f"{rate:.3g}"}
        # the integrator totals Newton iterations at the end of a run; show them once known
        if stats.newton_iterations:
            post["newton"] = stats.newton_iterations
        if stats.rejected_steps:
            post["rejected"] = stats.rejected_steps
        self.bar.set_postfix(post, refresh=False)

    def close(self) -> None:
        if self.bar is not None:
            self._postfix(time.perf_counter())   # final counts (same stats object, now totalled)
            self.bar.close()
            self.bar = None


def _terminate_like_ctrl_c() -> Callable[[], None]:
    """SIGINT, SIGTERM and SIGHUP raise :class:`~flexmbs.errors.Interrupted` (a
    KeyboardInterrupt), so a terminated run finishes like Ctrl-C: frame, checkpoint,
    ``summary.json``. A signal that lands while numba runs Python code from C (loading or
    compiling a kernel) is not raised there (an exception inside numba can leave its
    libraries half built: a crash or a traceback later): it is remembered and raised at the
    next progress report; a second signal raises at once. Returns the function that restores
    the previous handlers."""
    import signal

    pending: list[str] = []

    def handler(signum: int, frame: Any) -> None:
        name = signal.Signals(signum).name
        pending.append(name)
        if len(pending) == 1 and _inside_compiler(frame):
            # numba is loading or compiling a kernel: an exception there can leave its
            # libraries half built (a crash or a traceback later); the progress report of the
            # next step raises it instead (a second signal raises at once)
            return
        raise Interrupted("" if name == "SIGINT" else name)

    previous: dict[Any, Any] = {}
    for name in ("SIGINT", "SIGTERM", "SIGHUP"):
        sig = getattr(signal, name, None)
        if sig is not None:
            with contextlib.suppress(ValueError):   # not the main thread (e.g. a worker)
                previous[sig] = signal.signal(sig, handler)
    hook = sys.unraisablehook

    def unraisable(info: Any) -> None:
        if not (pending and isinstance(info.exc_value, KeyboardInterrupt)):
            hook(info)

    sys.unraisablehook = unraisable
    _PENDING[:] = [pending]

    def restore() -> None:
        for sig, old in previous.items():
            signal.signal(sig, old)
        sys.unraisablehook = hook

    return restore


#: the signals received by the running command (see _terminate_like_ctrl_c)
_PENDING: list[list[str]] = []


def _inside_compiler(frame: Any) -> bool:
    """Whether the interrupted Python code runs inside numba or llvmlite."""
    while frame is not None:
        module = frame.f_globals.get("__name__", "")
        if module.startswith(("numba.", "llvmlite.")) or module in ("numba", "llvmlite"):
            return True
        frame = frame.f_back
    return False


def _raise_pending() -> None:
    """Raise a signal that numba swallowed (called from the progress report of every step)."""
    if _PENDING and _PENDING[0]:
        name = _PENDING[0][-1]
        _PENDING[0].clear()
        raise Interrupted("" if name == "SIGINT" else name)


def _is_end_time(assignment: str) -> bool:
    return assignment.replace(" ", "").startswith("simulation.t_end=")


def _is_output_form(assignment: str) -> bool:
    return assignment.replace(" ", "").startswith("simulation.output_frames=")


def _resume_overrides(args: argparse.Namespace) -> list[str]:
    """The overrides of a resumed run: the first run's (from ``summary.json``, without its end
    time) unless the same are given again; a different model is refused with one line naming
    the difference (issue "nothing lost", item 5). The scenario file and its content must be
    those of the first run."""
    from .errors import ScenarioError
    from .runs import scenario_digest

    given = _overrides(args)
    try:
        meta = json.loads((Path(args.resume) / "summary.json").read_text(encoding="utf-8"))
        meta = meta.get("metadata") or {}
    except (OSError, ValueError):
        return given                     # resume_point reports what is missing
    where = f"--resume {args.resume}"
    first_file = meta.get("scenario_file")
    if first_file and os.path.abspath(args.scenario) != first_file:
        raise ScenarioError(f"{where}: that run was made from {first_file}, not "
                            f"{os.path.abspath(args.scenario)}")
    digest = meta.get("scenario_sha1")
    if digest and Path(args.scenario).is_file() and scenario_digest(args.scenario) != digest:
        raise ScenarioError(f"{where}: {args.scenario} has changed since that run started; a "
                            "resumed run must be the same model (only the end time may change)")
    first = [o for o in meta.get("overrides") or [] if not _is_end_time(o)]
    # the form of the frames is not the model's: a resume continues the series in its form
    model = [o for o in first if not _is_output_form(o)]
    now = [o for o in given if not _is_end_time(o) and not _is_output_form(o)]
    if now and now != model:
        extra = [o for o in now if o not in model] or [o for o in model if o not in now] or now
        raise ScenarioError(f"{where}: that run used --set {' '.join(model) or '(none)'}; this "
                            f"one differs ({extra[0]}); a resumed run must be the same model "
                            "(only the end time may change)")
    return first + [o for o in given if _is_end_time(o)]


def _compile_notice(estimate: float | None, same_kind: bool = True) -> str:
    """The one line printed while the kernels compile for a new kind of model."""
    if estimate is None:
        about = "a minute or two on a 2-core machine"
    elif same_kind:
        about = f"about {estimate:.0f} s, as its last compile here"
    else:
        about = f"the longest compile here so far took {estimate:.0f} s"
    return (f"flexmbs: compiling the numba kernels for this kind of model (once; {about}; "
            "cached for later runs)")


def _announce_compiles() -> None:
    """Print :func:`_compile_notice` on stderr whenever the kernel compiles in this process."""
    from . import kernel

    def announce(estimate: float | None, kind: str, same_kind: bool) -> None:
        print(_compile_notice(estimate, same_kind), file=sys.stderr, flush=True)

    kernel.announce_compile = announce


def cmd_compile(args: argparse.Namespace) -> int:
    """``flexmbs compile``: compile (or load) the kernels of the named kinds of model or
    scenario files ahead of a run; one line per kind."""
    from .io.scenario import load_scenario

    targets = list(args.targets) or ["cable"]
    restore = _terminate_like_ctrl_c()
    if not args.quiet:
        _announce_compiles()
    try:
        for target in targets:
            start = time.perf_counter()
            if target in _COMPILE_KINDS:
                model = _COMPILE_KINDS[target]()
                name = target
            else:
                if not target.endswith(".toml") and not Path(target).exists():
                    _error(f"compile: {target!r} is neither a kind of model "
                           f"({', '.join(_COMPILE_KINDS)}) nor a scenario file")
                    return EXIT_BAD_INPUT
                sc = load_scenario(target, _overrides(args))
                model, name = sc.model, target
            from .assembly import Assembly
            from .kernel import model_kind

            asm = Assembly(model)
            _compile_python_paths(asm)
            if not args.quiet:
                print(f"flexmbs: {name}: kernels ready ({model_kind(asm.kernel_system)}, "
                      f"{time.perf_counter() - start:.1f} s)", flush=True)
    except KeyboardInterrupt:
        _error("interrupted")
        return EXIT_INTERRUPTED
    except FlexmbsError as exc:
        _error(_one_line(exc))
        return EXIT_BAD_INPUT
    except OSError as exc:
        where = f" {exc.filename}" if getattr(exc, "filename", None) else ""
        _error(f"{exc.strerror or exc}{where}")
        return EXIT_BAD_INPUT
    finally:
        restore()
    return EXIT_OK


def _compile_python_paths(asm: Any) -> None:
    """The compiled functions a run calls from Python besides the kernel (the banded
    factorisation's set-up, the output's beam fields), by one small dynamic step."""
    from .simulation import simulate
    from .solvers.generalized_alpha import GeneralizedAlpha

    with contextlib.suppress(FlexmbsError):   # a model that cannot step still has its kernel
        simulate(asm, t_end=2e-6, dt=1e-6, integrator=GeneralizedAlpha(adaptive=False),
                 output_interval=1e-6, record_energy=False)


def _cantilever(element: str) -> Any:
    """A clamped beam under gravity: the kernels of every model of this element's beams with
    clamps, pins, prescribed motion and loads."""
    import flexmbs as fm

    model = fm.Model(gravity=(0.0, 0.0, -9.81))
    beam = model.add_beam(fm.line((0, 0, 0), (1, 0, 0), elements=2),
                          section=fm.CircularSection(5e-3),
                          material=fm.Material(E=2.1e11, rho=7800.0), element=element)
    model.clamp(beam.first_node)
    return model


#: kinds of model ``flexmbs compile`` knows by name (scenario files name any other)
_COMPILE_KINDS: dict[str, Callable[[], Any]] = {
    "cable": lambda: _cantilever("ancf_cable"),
    "rod": lambda: _cantilever("ancf_rod14"),
}


def cmd_run(args: argparse.Namespace) -> int:
    """``flexmbs run``: load the scenario, resolve the output folder and call
    :func:`flexmbs.runs.run_scenario`, which claims the folder and runs the scenario
    (:func:`~flexmbs.simulation.solve_static` or :func:`~flexmbs.simulation.simulate`); print
    one line."""
    from .io.scenario import load_scenario
    from .runs import run_scenario

    quiet = bool(args.quiet)
    out: Path | None = None
    t_wall = time.perf_counter()
    bars: list[_Progress] = []

    def progress(start: float, t_end: float, name: str) -> _Progress:
        bars.append(_Progress(start, t_end, name=name, disable=quiet or not sys.stderr.isatty()))
        return bars[-1]

    def close_bars() -> None:
        for bar in bars:
            bar.close()

    restore = _terminate_like_ctrl_c()
    try:
        overrides = _resume_overrides(args) if args.resume is not None else _overrides(args)
        sc = load_scenario(args.scenario, overrides)
        sim = sc.simulation
        if args.resume is not None:
            if args.out is not None and Path(args.out).resolve() != Path(args.resume).resolve():
                _error(f"--out {args.out} and --resume {args.resume} name different folders")
                return EXIT_BAD_INPUT
            out = Path(args.resume)
            if not out.is_dir():
                _error(f"cannot resume: {out} is not a folder")
                return EXIT_BAD_INPUT
            if sim.integrator == "static":
                _error("--resume: a static scenario has nothing to resume")
                return EXIT_BAD_INPUT
        else:
            if args.out is not None and not args.out.strip():
                _error("--out: empty path; give the output folder")
                return EXIT_BAD_INPUT
            out = Path(args.out) if args.out is not None else Path("out") / sc.name
        if not quiet:
            _announce_compiles()
        outcome = run_scenario(sc, out, overrides=overrides, resume=args.resume is not None,
                               overwrite=bool(getattr(args, "overwrite", False)),
                               progress=progress)
        close_bars()
    except KeyboardInterrupt:
        close_bars()
        _error("interrupted" + (f" (output so far in {out})" if out is not None else ""))
        return EXIT_INTERRUPTED
    except FlexmbsError as exc:
        close_bars()
        _error(_one_line(exc))
        return EXIT_FAILED if isinstance(exc, ConvergenceError) else EXIT_BAD_INPUT
    except OSError as exc:
        close_bars()
        where = f" {exc.filename}" if getattr(exc, "filename", None) else ""
        _error(f"cannot write or read{where}: {exc.strerror or _one_line(exc)}")
        # a run that had started (its summary exists) failed, e.g. on a full disk; before
        # that it is a bad path
        started = out is not None and (out / "summary.json").is_file()
        return EXIT_FAILED if started else EXIT_BAD_INPUT
    finally:
        restore()
    if not quiet:
        wall = time.perf_counter() - t_wall
        print(f"{sc.name}: {outcome.status} at t = {sim.t_end:.6g} s: {outcome.steps} steps, "
              f"{outcome.newton_iterations} Newton iterations, {outcome.rejected_steps} rejected, "
              f"wall time {wall:.3g} s; output: {out}")
    return EXIT_OK


# ================================================================================ sweep
def cmd_sweep(args: argparse.Namespace) -> int:
    """``flexmbs sweep``: :func:`flexmbs.sweeps.sweep` with a progress line per case; exit 0
    when every case completed, 3 when some failed (the table lists them), 2 on bad input."""
    import importlib.util

    from .sweeps import Case, parse_values, sweep

    if importlib.util.find_spec("distributed") is None:
        _error('sweep needs dask.distributed; install it with pip install "dask[distributed]"')
        return EXIT_BAD_INPUT
    quiet = bool(args.quiet)
    t0 = time.perf_counter()

    def report(case: Case, row: dict[str, Any], done: int, total: int, reused: bool) -> None:
        status = str(row.get("status"))
        if quiet:
            return
        if status != "completed":
            _error(f"case {case.name} {status}")
        elif reused:
            print(f"[{done}/{total}] {case.name}: completed by an earlier run (kept)",
                  file=sys.stderr, flush=True)
        else:
            print(f"[{done}/{total}] {case.name}: completed in {row.get('wall_time', 0):.3g} s, "
                  f"{row.get('steps')} steps", file=sys.stderr, flush=True)

    restore = _terminate_like_ctrl_c()
    try:
        grid = dict(parse_values(g, "--grid") for g in args.grid)
        zipped = dict(parse_values(z, "--zip") for z in args.zip)
        if len(grid) != len(args.grid) or len(zipped) != len(args.zip):
            _error("sweep: a key is given twice; give each --grid/--zip key once")
            return EXIT_BAD_INPUT
        rows = sweep(args.scenario, grid, zip=zipped, overrides=args.overrides, out=args.out,
                     scheduler=args.scheduler, workers=args.workers, report=report)
    except KeyboardInterrupt:
        _error("sweep interrupted (finished cases are in the table; rerun to continue)")
        return EXIT_INTERRUPTED
    except FlexmbsError as exc:
        _error(_one_line(exc))
        return EXIT_BAD_INPUT
    except OSError as exc:
        where = f" {exc.filename}" if getattr(exc, "filename", None) else ""
        _error(f"cannot write or read{where}: {exc.strerror or _one_line(exc)}")
        return EXIT_BAD_INPUT
    finally:
        restore()
    failed = [r for r in rows if r.get("status") != "completed"]
    if not quiet:
        from .sweeps import TABLE_FILE

        table = Path(str(rows[0]["folder"])).parent / TABLE_FILE
        print(f"sweep: {len(rows) - len(failed)} of {len(rows)} cases completed, {len(failed)} "
              f"failed, wall time {time.perf_counter() - t0:.3g} s; table: {table}")
    return EXIT_FAILED if failed else EXIT_OK


# ================================================================================ info
def _fmt(x: Any) -> str:
    import numpy as np

    if isinstance(x, (float, np.floating)):
        return f"{float(x):.6g}"
    if isinstance(x, np.ndarray):
        return "[" + ", ".join(_fmt(v) for v in x.reshape(-1)) + "]"
    if isinstance(x, (list, tuple)):
        return "[" + ", ".join(_fmt(v) for v in x) + "]"
    return str(x)


def _target(obj: Any) -> str:
    return str(getattr(obj, "name", obj))


def print_info(sc: Any, asm: Any, file: TextIO) -> None:
    """The model of a loaded scenario, human readable."""
    import numpy as np

    def p(*parts: Any) -> None:
        print(*parts, file=file)

    model = sc.model
    sim = sc.simulation
    p(f"scenario     {sc.name}  ({sc.path})")
    if sc.description:
        p(f"description  {' '.join(sc.description.split())}")
    p(f"coordinates  {asm.n_coords}")
    p(f"multipliers  {asm.n_mult}")
    p(f"gravity      {_fmt(model.gravity)} m/s^2")
    p(f"beams ({len(model.beams)})")
    for b in model.beams:
        k = b.stiffness
        opts = getattr(b, "options", None)
        p(f"  {b.name}: {b.n_elem} elements, {b.n_nodes} nodes, length {_fmt(b.length)} m"
          f"{', closed' if b.closed else ''} (element {b.element})")
        p(f"    EA {_fmt(k.axial_stiffness)} N, EI {_fmt(k.bending_stiffness)} N m^2, "
          f"rhoA {_fmt(k.mass_per_length)} kg/m"
          + (f", GJ {_fmt(k.torsional_stiffness)} N m^2" if k.torsional_stiffness else "")
          + (f", rhoJp {_fmt(k.polar_mass_moment)} kg m" if b.layout.twist is not None else "")
          + (f", radius {_fmt(k.radius)} m" if k.radius else ""))
        p(f"    damping {_fmt(b.damping)} s, reference axial strain "
          f"{_fmt(b.reference_axial_strain)}" + (f", options {opts}" if opts is not None else ""))
    p(f"rigid bodies ({len(model.bodies)})")
    for body in model.bodies:
        pose = body.pose
        p(f"  {body.name}: mass {_fmt(body.mass)} kg, inertia "
          f"{_fmt(np.asarray(body.inertia, float))} kg m^2")
        p(f"    position {_fmt(pose.position)} m, quaternion {_fmt(pose.quaternion)}")
    p(f"constraints ({len(model.constraints)}; {asm.n_mult} equations)")
    labels = list(asm.multiplier_labels)
    for c in model.constraints:
        eqs = [lab for lab in labels if f"'{c.name}'" in lab]
        target = _target(c.a) + (f" -> {_target(c.b)}" if c.kind not in ("clamp", "pin") and
                                 c.kind != "prescribed" else "")
        p(f"  {c.name}: {c.kind} {target}, {len(eqs)} equations")
        for lab in eqs:
            p(f"    {lab}")
    other = [lab for lab in labels if not any(f"'{c.name}'" in lab for c in model.constraints)]
    if other:
        p(f"  other equations ({len(other)})")
        for lab in other:
            p(f"    {lab}")
    dropped = list(getattr(asm, "dropped_equations", []))
    p(f"dropped redundant equations ({len(dropped)})" + (": " + "; ".join(dropped) if dropped else ""))
    p(f"loads ({len(model.loads)})")
    for ld in model.loads:
        tgt = ld.target
        where = (f"{tgt[0].name} at s = {_fmt(tgt[1])}" if isinstance(tgt, tuple) else _target(tgt))
        p(f"  {ld.name}: {ld.kind} on {where}, force {_fmt(ld.force)}"
          + (f", moment {_fmt(ld.moment)}" if ld.moment is not None else "")
          + f", function {ld.function!r}")
    joints = list(model.interactions)
    p(f"joints/interactions ({len(joints)})")
    for j in joints:
        p(f"  {j!r}")
    p(f"probes ({len(sc.probes)})")
    for pr in sc.probes:
        p(f"  {pr.name}: {type(pr).__name__} -> {', '.join(pr.columns())}")
    p("simulation")
    for k, v in vars(sim).items():
        if k == "newton":
            v = v or "{} (defaults)"
        p(f"  {k:22s} {_fmt(v)}")
    opts_i = sc.integrator_options()
    p(f"  solver                 {opts_i if opts_i is not None else sc.static_options()}")
    if opts_i is not None:
        reason = asm.compiled_reason()
        path = ("compiled (whole steps in numba)" if not reason and opts_i.compiled
                else "Python Newton loop (compiled = false)" if not reason
                else f"Python Newton loop: {reason}")
        p(f"  integrator path        {path}")


def cmd_info(args: argparse.Namespace) -> int:
    from .assembly import Assembly
    from .io.scenario import load_scenario

    try:
        sc = load_scenario(args.scenario, _overrides(args))
        asm = Assembly(sc.model, redundant_constraints=sc.simulation.redundant_constraints)
    except FlexmbsError as exc:
        _error(_one_line(exc))
        return EXIT_BAD_INPUT
    print_info(sc, asm, sys.stdout)
    return EXIT_OK


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

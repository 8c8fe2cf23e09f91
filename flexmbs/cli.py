"""Command line: ``flexmbs run | info | render | plot | sweep | compile | paraview`` (the docs
site's "Command line" page, docs/cli.md), one module per command in :mod:`flexmbs.commands`
(its parser and its ``run``); here the parser they make up, the dispatch and the exit status.

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
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from .commands._common import (
    DOCS_URL,
    EXIT_BAD_INPUT,
    EXIT_FAILED,
    EXIT_INTERRUPTED,
    EXIT_OK,
    OneLineParser,
    error,
)

__all__ = ["EXIT_BAD_INPUT", "EXIT_FAILED", "EXIT_INTERRUPTED", "EXIT_OK", "build_parser",
           "console_main", "main"]

#: the commands: name -> the module of :mod:`flexmbs.commands` whose ``run(args)`` runs it;
#: imported by :func:`build_parser`, inside :func:`main` (a Ctrl-C while they load is one line)
COMMANDS = {"run": "run", "info": "info", "render": "postprocess", "plot": "postprocess",
            "sweep": "sweep", "compile": "compile", "paraview": "paraview"}


def build_parser() -> argparse.ArgumentParser:
    """The ``flexmbs`` parser: each command adds its own sub-parser."""
    from . import __version__
    from .commands import compile as compile_command
    from .commands import info as info_command
    from .commands import paraview as paraview_command
    from .commands import postprocess as postprocess_command
    from .commands import run as run_command
    from .commands import sweep as sweep_command

    parser = OneLineParser(
        prog="flexmbs", description="Flexible multibody dynamics: ANCF beams, rigid bodies, "
        "sliding joints with clearance. Every command has -q/--quiet. Documentation: "
        f"{DOCS_URL} (the command line: {DOCS_URL}cli/).")
    parser.add_argument("--version", action="version", version=f"flexmbs {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True,
                                parser_class=OneLineParser)
    overrides = OneLineParser(add_help=False)
    overrides.add_argument("--set", dest="overrides", action="append", default=[],
                           metavar="KEY=VALUE",
                           help="override a scenario value, e.g. simulation.dt=5e-4 or "
                                "beams.rod.elements=8 (repeatable)")
    run_command.add_parser(sub, [overrides])
    info_command.add_parser(sub, [overrides])
    postprocess_command.add_parsers(sub)
    compile_command.add_parser(sub, [overrides])
    sweep_command.add_parser(sub, [overrides])
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


class _InterruptWatch:
    """SIGINT handler for the length of a command: Python's (raise KeyboardInterrupt), which
    also remembers that it fired. A Ctrl-C that lands inside a C extension's import may come
    out as another error with the interrupt dropped from its chain (numpy's: "PyCapsule_Import
    could not import module datetime" while its C part loads); the flag still says why."""

    def __init__(self) -> None:
        self.fired = False
        self.previous: Any = None

    def __call__(self, signum: int, frame: Any) -> None:
        self.fired = True
        raise KeyboardInterrupt

    def __enter__(self) -> _InterruptWatch:
        import signal

        with contextlib.suppress(ValueError):      # not the main thread: leave it alone
            self.previous = signal.signal(signal.SIGINT, self)
        return self

    def __exit__(self, *exc: object) -> None:
        import signal

        if self.previous is not None:
            with contextlib.suppress(ValueError):
                signal.signal(signal.SIGINT, self.previous)


def main(argv: Sequence[str] | None = None) -> int:
    """The ``flexmbs`` command; returns the exit status. Ctrl-C at any moment (also while the
    libraries load) is one line and exit 130."""
    with _InterruptWatch() as watch:
        try:
            return _main(argv)
        except KeyboardInterrupt:
            error("interrupted")
            return EXIT_INTERRUPTED
        except Exception as exc:
            if not (watch.fired or _caused_by_interrupt(exc)):
                raise
            error("interrupted")    # e.g. Python wraps a Ctrl-C that lands in a class body
            return EXIT_INTERRUPTED  # being created (dataclass fields) in a RuntimeError


def _caused_by_interrupt(exc: BaseException) -> bool:
    """Whether a KeyboardInterrupt is in ``exc``'s chain of causes (``raise ... from``) or
    contexts (raised while handling it)."""
    seen: set[int] = set()
    cur: BaseException | None = exc
    while cur is not None and id(cur) not in seen:
        if isinstance(cur, KeyboardInterrupt):
            return True
        seen.add(id(cur))
        cur = cur.__cause__ or cur.__context__
    return False


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
    from .environment import check_environment
    from .errors import FlexmbsError

    try:                        # the FLEXMBS_* variables, before anything is read or written
        check_environment()
    except FlexmbsError as exc:
        error(str(exc))
        return EXIT_BAD_INPUT
    try:
        import importlib

        return int(importlib.import_module(f".commands.{COMMANDS[args.command]}",
                                           __package__).run(args))
    except BrokenPipeError:   # e.g. `flexmbs info ... | head`: the reader left, not an error
        import os

        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return EXIT_OK


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

"""What every ``flexmbs`` command shares: exit codes, one-line errors, the ``--set`` overrides,
signals that end a command like Ctrl-C, and the one report of a command's failure."""

from __future__ import annotations

import argparse
import contextlib
import math
import sys
from collections.abc import Callable
from typing import Any, NoReturn

from ..errors import ConvergenceError, FlexmbsError, Interrupted

#: the documentation site; help texts point to its pages (:func:`docs`), not to files of a clone
DOCS_URL = "https://flexmbs.readthedocs.io/en/latest/"

EXIT_OK = 0
EXIT_BAD_INPUT = 2
EXIT_FAILED = 3
EXIT_INTERRUPTED = 130

__all__ = ["DOCS_URL", "EXIT_BAD_INPUT", "EXIT_FAILED", "EXIT_INTERRUPTED", "EXIT_OK", "Number",
           "OneLineParser", "add_quiet", "docs", "error", "failure_status", "one_line", "overrides",
           "raise_pending", "terminate_like_ctrl_c"]


def docs(page: str, anchor: str = "") -> str:
    """The address of a page of the documentation site (``page``: its file name without
    ``.md``), for help texts: ``docs("cli", "flexmbs-compile")``."""
    return f"{DOCS_URL}{page}/" + (f"#{anchor}" if anchor else "")


def add_quiet(parser: argparse.ArgumentParser, what: str) -> None:
    """``-q/--quiet``, which every command has: ``what`` it leaves out (errors are always
    printed)."""
    parser.add_argument("--quiet", "-q", action="store_true",
                        help=f"{what} (errors are still printed)")


def one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split()) or type(exc).__name__


def error(message: str) -> None:
    print(f"flexmbs: error: {' '.join(message.split())}", file=sys.stderr)


class OneLineParser(argparse.ArgumentParser):
    """Usage errors in one line (``flexmbs run: error: ...; see flexmbs run -h``), exit 2,
    instead of argparse's usage block."""

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_BAD_INPUT, f"{self.prog}: error: {message}; see {self.prog} -h\n")


class Number:
    """The ``type`` of a numeric flag, and its declaration: an integer or a finite number in a
    range (``add_argument("--fps", type=Number(gt=0))``); a bad value is argparse's one-line
    usage error naming the flag (``argument --fps: expected a number > 0, got '0'``). The test
    of every flag (tests/io/test_every_key.py) generates its bad values from these."""

    def __init__(self, *, integer: bool = False, gt: float | None = None,
                 ge: float | None = None) -> None:
        self.integer, self.gt, self.ge = integer, gt, ge
        self.__name__ = "integer" if integer else "number"

    def expected(self) -> str:
        bound = (f" > {self.gt:g}" if self.gt is not None
                 else f" >= {self.ge:g}" if self.ge is not None else "")
        return ("an integer" if self.integer else "a finite number") + bound

    def __call__(self, text: str) -> float:
        try:
            v = int(text) if self.integer else float(text)
        except ValueError:
            v = math.nan
        if (not math.isfinite(v) or (self.gt is not None and not v > self.gt)
                or (self.ge is not None and not v >= self.ge)):
            raise argparse.ArgumentTypeError(f"expected {self.expected()}, got {text!r}")
        return v


def overrides(args: argparse.Namespace) -> list[str]:
    """The ``--set`` assignments of a command, with its shorthands (``--t-end``, ``--dt``,
    ``--output-frames``) appended."""
    sets = list(args.overrides)
    if getattr(args, "t_end", None) is not None:
        sets.append(f"simulation.t_end={args.t_end!r}")
    if getattr(args, "dt", None) is not None:
        sets.append(f"simulation.dt={args.dt!r}")
    if getattr(args, "output_frames", None) is not None:
        sets.append(f"simulation.output_frames={args.output_frames}")
    return sets


def failure_status(exc: BaseException, *, interrupted: str = "interrupted",
                   started: bool = False) -> int:
    """Report a command's failure in one line and return its exit status: Ctrl-C or a
    terminating signal (``interrupted``: the message) 130; a divergence 3; bad input (a
    :class:`~flexmbs.errors.FlexmbsError`) 2; a file that cannot be read or written 2, or 3 when
    the run had ``started`` (e.g. a full disk). Anything else is raised again (a traceback: an
    internal error to report)."""
    if isinstance(exc, KeyboardInterrupt):
        error(interrupted)
        return EXIT_INTERRUPTED
    if isinstance(exc, FlexmbsError):
        error(one_line(exc))
        return EXIT_FAILED if isinstance(exc, ConvergenceError) else EXIT_BAD_INPUT
    if isinstance(exc, OSError):
        where = f" {exc.filename}" if getattr(exc, "filename", None) else ""
        error(f"cannot write or read{where}: {exc.strerror or one_line(exc)}")
        return EXIT_FAILED if started else EXIT_BAD_INPUT
    raise exc


def terminate_like_ctrl_c() -> Callable[[], None]:
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
        if len(pending) == 1 and inside_compiler(frame):
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
    PENDING[:] = [pending]

    def restore() -> None:
        for sig, old in previous.items():
            signal.signal(sig, old)
        sys.unraisablehook = hook

    return restore


#: the signals received by the running command (see terminate_like_ctrl_c)
PENDING: list[list[str]] = []


def inside_compiler(frame: Any) -> bool:
    """Whether the interrupted Python code runs inside numba or llvmlite."""
    while frame is not None:
        module = frame.f_globals.get("__name__", "")
        if module.startswith(("numba.", "llvmlite.")) or module in ("numba", "llvmlite"):
            return True
        frame = frame.f_back
    return False


def raise_pending() -> None:
    """Raise a signal that numba swallowed (called from the progress report of every step)."""
    if PENDING and PENDING[0]:
        name = PENDING[0][-1]
        PENDING[0].clear()
        raise Interrupted("" if name == "SIGINT" else name)

"""Who may write an output folder (issue "nothing lost"): one run at a time, and never over
another scenario's results unless the user says so.

- :func:`claim` locks the folder for the run (``.flexmbs.lock`` holding the process id; a lock
  left by a process that no longer exists is taken over) and checks what the folder holds:
  an empty or new folder is taken; the folder of an earlier run of the same scenario is
  cleared of that run's files first (no stale frames survive); another scenario's output, or
  a non-empty folder that is not a flexmbs output folder, is refused with one line. With
  ``overwrite`` another scenario's output folder is cleared and taken; a folder that is not an
  output folder is never cleared (it may be the user's working directory).
- ``resume`` keeps the folder as it is (the resume logic checks it).
- A run killed at any moment (SIGKILL, a dead Dask worker) leaves a folder the next run of
  the scenario takes: a run writes ``summary.json`` (the mark, status ``running``) before any
  other file, :func:`claim` removes it after the other files, and a lock whose process is gone
  or a zombie is taken over.

A folder is flexmbs output only if its ``summary.json`` says so (issue "nothing lost, part
two"): :func:`output_summary`. Files with a run's names (``probes.csv``, ``summary.json``,
``vtu/``, ...) in a folder whose summary does not say so are the user's: the folder is refused
in one line naming them, with ``--overwrite`` too.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
from collections.abc import Iterator
from pathlib import Path

from ..errors import ScenarioError

__all__ = ["LOCK_NAME", "OUTPUT_FORMAT", "OUTPUT_FORMAT_VERSION", "claim", "lock_folder",
           "output_files", "output_summary",
           "refuse_user_files"]

LOCK_NAME = ".flexmbs.lock"
#: the mark of a flexmbs output folder: ``summary.json["format"]`` and ``["format_version"]``
OUTPUT_FORMAT = "flexmbs-output"
OUTPUT_FORMAT_VERSION = 1
#: what every summary.json written before the mark holds (flexmbs 0.x, since its first output
#: folder): a text ``scenario``, ``flexmbs_version`` and ``status``, ``dofs`` with
#: ``coordinates`` and ``multipliers``, and ``files``
_LEGACY_KEYS = ("scenario", "flexmbs_version", "status", "dofs", "files")

#: what a run writes at the top of its folder (everything else of an output folder is below
#: ``vtu/`` and ``figures/``)
_RUN_FILES = ("summary.json", "probes.csv", "contacts.csv", "sections.csv", "checkpoint.npz",
              ".checkpoint.npz.tmp", ".summary.json.tmp")


def output_files(folder: Path) -> list[Path]:
    """The files and folders of a flexmbs run in ``folder`` (what :func:`claim` clears)."""
    out = [folder / n for n in _RUN_FILES if (folder / n).exists()]
    out += sorted(folder.glob("*.pvd"))
    out += [folder / d for d in ("vtu", "figures") if (folder / d).is_dir()]
    return out


def _alive(pid: int) -> bool:
    """Whether process ``pid`` runs: a zombie (exited, not yet reaped by its parent, e.g. a
    killed Dask worker in a container whose init does not reap) does not."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:     # exists, another user's
        pass
    try:        # Linux: "pid (comm) STATE ..."; comm may hold spaces and parentheses
        stat = Path(f"/proc/{pid}/stat").read_text(encoding="utf-8", errors="replace")
    except OSError:             # no /proc (macOS), or gone meanwhile
        return True
    return stat.rpartition(")")[2].split()[:1] not in (["Z"], ["X"])


def _lock(folder: Path) -> Path:
    path = folder / LOCK_NAME
    for _ in range(2):
        try:
            fd = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
        except FileExistsError:
            try:
                pid = int(path.read_text().strip() or "0")
            except (OSError, ValueError):
                pid = 0
            if pid > 0 and pid != os.getpid() and _alive(pid):
                raise ScenarioError(
                    f"{folder}: another flexmbs run (process {pid}) is writing this folder; "
                    "wait for it or choose another --out") from None
            with contextlib.suppress(FileNotFoundError):
                path.unlink()       # left by a process that is gone
            continue
        with os.fdopen(fd, "w") as f:
            f.write(f"{os.getpid()}\n")
        return path
    raise ScenarioError(f"{folder}: cannot lock the folder ({LOCK_NAME} keeps reappearing)")


def output_summary(folder: str | os.PathLike[str]) -> dict | None:
    """``folder``'s ``summary.json`` if it marks flexmbs output, else None (no summary, not
    JSON, or not flexmbs's). Marked: ``format == "flexmbs-output"`` with an integer
    ``format_version`` and a text ``scenario``. A summary of flexmbs before the mark counts when
    it has no ``format`` key and all of ``_LEGACY_KEYS`` with their types (``{"mine": true}`` or
    another program's summary do not)."""
    try:
        summary = json.loads((Path(folder) / "summary.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):      # missing, unreadable, not UTF-8, not JSON
        return None
    if not isinstance(summary, dict) or not isinstance(summary.get("scenario"), str):
        return None
    if "format" in summary:
        version = summary.get("format_version")
        ok = (summary["format"] == OUTPUT_FORMAT and isinstance(version, int)
              and not isinstance(version, bool))
        return summary if ok else None
    dofs = summary.get("dofs")
    legacy = (all(k in summary for k in _LEGACY_KEYS)
              and isinstance(summary["flexmbs_version"], str)
              and isinstance(summary["status"], str) and isinstance(summary["files"], dict)
              and isinstance(dofs, dict) and "coordinates" in dofs and "multipliers" in dofs)
    return summary if legacy else None


def refuse_user_files(folder: str | os.PathLike[str], *, label: str = "--out ") -> None:
    """Raise :class:`ScenarioError` (one line naming them) if ``folder`` holds files or folders
    with a run's names (:func:`output_files`) but is not flexmbs output (:func:`output_summary`):
    they are the user's, and nothing may write over them, ``--overwrite`` included."""
    path = Path(folder)
    if not path.is_dir():
        return
    ours = output_files(path)
    if not ours or output_summary(path) is not None:
        return
    names = [p.name + ("/" if p.is_dir() else "") for p in ours]
    listed = ", ".join(names[:3]) + (", ..." if len(names) > 3 else "")
    why = ("its summary.json is not a flexmbs summary" if (path / "summary.json").exists()
           else "it has no flexmbs summary.json")
    raise ScenarioError(
        f"{label}{path}: {listed} {'is' if len(names) == 1 else 'are'} not flexmbs output "
        f"({why}); flexmbs does not write over them, not even with --overwrite; choose another "
        "folder")


def _previous_scenario(folder: Path) -> str | None:
    summary = output_summary(folder)
    return None if summary is None else str(summary["scenario"])


@contextlib.contextmanager
def lock_folder(folder: Path) -> Iterator[Path]:
    """Hold ``folder``'s lock (one writer at a time) for the ``with`` block."""
    lock = _lock(folder)
    try:
        yield folder
    finally:
        with contextlib.suppress(FileNotFoundError):
            lock.unlink()


@contextlib.contextmanager
def claim(folder: str | os.PathLike[str], *, scenario: str, overwrite: bool = False,
          resume: bool = False) -> Iterator[Path]:
    """Lock ``folder`` for a run of ``scenario`` and make sure it may be written (module
    docstring); the lock is released on exit. Raises :class:`ScenarioError` (one line) before
    anything is written when the folder is refused."""
    if str(folder).strip() == "":
        raise ScenarioError("--out: empty path; give the output folder")
    path = Path(folder)
    if path.exists() and not path.is_dir():
        raise ScenarioError(f"--out {path}: exists and is not a folder")
    if not resume and path.is_dir():
        entries = [p for p in path.iterdir() if p.name != LOCK_NAME]
        ours = output_files(path)
        previous = _previous_scenario(path)
        foreign = [p for p in entries if p not in ours]
        refuse_user_files(path)
        if entries and previous is None:
            raise ScenarioError(
                f"--out {path}: the folder is not empty and holds no flexmbs output; choose a new "
                "or empty folder")
        if previous is not None and previous != scenario and not overwrite:
            raise ScenarioError(
                f"--out {path}: holds the output of scenario '{previous}'; choose another folder "
                "or pass --overwrite to replace it")
        if foreign and not overwrite and previous is not None:
            raise ScenarioError(
                f"--out {path}: holds files that are not flexmbs output ({foreign[0].name}, ...); "
                "choose another folder")
    path.mkdir(parents=True, exist_ok=True)
    with lock_folder(path):
        if not resume:      # summary.json, the folder's mark, last: a run killed meanwhile
            marked = path / "summary.json"     # leaves a folder the next run still takes
            for p in sorted(output_files(path), key=lambda p: p == marked):
                if p.is_dir():
                    shutil.rmtree(p)
                else:
                    p.unlink()
        yield path

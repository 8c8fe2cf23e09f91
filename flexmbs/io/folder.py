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
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
from collections.abc import Iterator
from pathlib import Path

from ..errors import ScenarioError

__all__ = ["LOCK_NAME", "claim", "lock_folder", "output_files"]

LOCK_NAME = ".flexmbs.lock"

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
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:     # exists, another user's
        return True
    return True


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


def _previous_scenario(folder: Path) -> str | None:
    try:
        return str(json.loads((folder / "summary.json").read_text(encoding="utf-8"))["scenario"])
    except (OSError, ValueError, KeyError, TypeError):
        return None


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
        if entries and previous is None and not ours:
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
        if not resume:
            for p in output_files(path):
                if p.is_dir():
                    shutil.rmtree(p)
                else:
                    p.unlink()
        yield path

"""Checkpoints: the integrator state (and interaction state) in one ``.npz``, written atomically.

Layout of the archive (``allow_pickle=False`` throughout):

- ``t`` (0-d), ``q``, ``v``, ``qdd``, ``a``, ``lam``: the :class:`State`, bit-exact;
- ``extra__<key>``: every top-level entry of ``extra`` that is a numpy array (bit-exact);
- ``extra_json``: the other entries of ``extra`` as one JSON string (numbers, strings, lists,
  dicts; nested numpy arrays become lists);
- ``format``: ``"flexmbs-checkpoint-<N>"`` (:data:`FORMAT_VERSION`), ``flexmbs_version``.

A checkpoint of a newer format is refused naming both versions; one of an older format is
read when :data:`OLDER_FORMATS` says how (what it lacks is then filled as the interactions'
``set_state`` fill what older checkpoints did not hold), else refused in one line saying what
it lacks and how to continue (docs/design.md, "Output folder").
"""

from __future__ import annotations

import contextlib
import json
import os
import zipfile
from pathlib import Path
from typing import Any

import numpy as np

from .._version import __version__
from ..solvers.generalized_alpha import State

#: the checkpoint format this flexmbs writes; raise it when a resume needs an entry that older
#: checkpoints lack, and say in OLDER_FORMATS whether (and how) those still resume
FORMAT_VERSION = 1
_PREFIX = "flexmbs-checkpoint-"
FORMAT = f"{_PREFIX}{FORMAT_VERSION}"
#: older formats: None, read as they are (what they lack has a default); or a text naming what
#: they lack, refused with it (none yet: format 1 is the first)
OLDER_FORMATS: dict[int, str | None] = {}


class CheckpointVersionError(ValueError):
    """A checkpoint of a format this flexmbs does not resume (newer, or older without a way)."""


def format_version(tag: str) -> int | None:
    """The version of a format tag ``flexmbs-checkpoint-<N>``; None if it is not one."""
    if not tag.startswith(_PREFIX) or not tag[len(_PREFIX):].isdigit():
        return None
    return int(tag[len(_PREFIX):])


def _check_version(path: Path, version: int, written_by: str) -> None:
    if version > FORMAT_VERSION:
        raise CheckpointVersionError(
            f"{path} was written by a newer flexmbs ({written_by}, checkpoint format {version}); "
            f"this flexmbs {__version__} reads formats up to {FORMAT_VERSION}: resume it with "
            f"flexmbs {written_by} or later, or run again without --resume")
    if version < FORMAT_VERSION and OLDER_FORMATS.get(version, "its entries") is not None:
        lacks = OLDER_FORMATS.get(version) or "entries this flexmbs needs"
        raise CheckpointVersionError(
            f"{path} has checkpoint format {version} (flexmbs {written_by}), which lacks "
            f"{lacks}; this flexmbs {__version__} cannot resume it: run again without --resume "
            "(the frames written so far stay readable)")
_STATE_FIELDS = ("q", "v", "qdd", "a", "lam")


def _json_default(o: Any) -> Any:
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, np.generic):
        return o.item()
    raise TypeError(f"checkpoint extra: cannot store {type(o).__name__} (use arrays, numbers, "
                    "strings, lists or dicts)")


def save_checkpoint(path: str | os.PathLike, state: State, *, extra: dict | None = None) -> Path:
    """Write ``state`` (and ``extra``) to ``path`` atomically (temp file + rename)."""
    path = Path(path)
    arrays: dict[str, np.ndarray] = {"t": np.array(float(state.t))}
    for f in _STATE_FIELDS:
        arrays[f] = np.asarray(getattr(state, f), dtype=float)
    rest: dict[str, Any] = {}
    for k, val in (extra or {}).items():
        if isinstance(val, np.ndarray):
            arrays[f"extra__{k}"] = val
        else:
            rest[k] = val
    arrays["extra_json"] = np.array(json.dumps(rest, default=_json_default))
    arrays["format"] = np.array(FORMAT)
    arrays["flexmbs_version"] = np.array(__version__)
    tmp = path.with_name(f".{path.name}.tmp")
    try:
        with open(tmp, "wb") as fh:
            np.savez(fh, **arrays)  # type: ignore[arg-type]
        os.replace(tmp, path)
    except OSError as exc:          # e.g. a full disk: no temporary left, the file named
        with contextlib.suppress(OSError):
            tmp.unlink()
        if exc.filename is None:
            raise OSError(exc.errno, exc.strerror or str(exc), str(path)) from exc
        raise
    return path


def load_checkpoint(path: str | os.PathLike) -> tuple[State, dict]:
    """Read a checkpoint written by :func:`save_checkpoint`: ``(State, extra)``. A missing file
    raises OSError; a damaged one (cut off, overwritten, not ours) ValueError naming it."""
    try:
        with np.load(Path(path), allow_pickle=False) as z:
            version = format_version(str(z["format"])) if "format" in z.files else None
            if version is None:
                raise ValueError("no flexmbs checkpoint format tag")
            written_by = str(z["flexmbs_version"]) if "flexmbs_version" in z.files else "unknown"
            _check_version(Path(path), version, written_by)
            state = State(float(z["t"]), *(z[f].copy() for f in _STATE_FIELDS))
            extra: dict[str, Any] = json.loads(str(z["extra_json"]))
            for k in z.files:
                if k.startswith("extra__"):
                    extra[k[len("extra__"):]] = z[k].copy()
    except (FileNotFoundError, CheckpointVersionError):
        raise
    except (zipfile.BadZipFile, ValueError, EOFError, KeyError, TypeError, OSError) as exc:
        text = " ".join(str(exc).split())
        archive = isinstance(exc, (zipfile.BadZipFile, OSError)) or "pickle" in text
        reason = "not an .npz archive" if archive else (text[:80] or type(exc).__name__)
        raise ValueError(f"{path} is damaged or not a flexmbs checkpoint ({FORMAT}): "
                         f"{reason}") from None
    return state, extra

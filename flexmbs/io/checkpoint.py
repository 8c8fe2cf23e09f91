"""Checkpoints: the integrator state (and interaction state) in one ``.npz``, written atomically.

Layout of the archive (``allow_pickle=False`` throughout):

- ``t`` (0-d), ``q``, ``v``, ``qdd``, ``a``, ``lam``: the :class:`State`, bit-exact;
- ``extra__<key>``: every top-level entry of ``extra`` that is a numpy array (bit-exact);
- ``extra_json``: the other entries of ``extra`` as one JSON string (numbers, strings, lists,
  dicts; nested numpy arrays become lists);
- ``format``: ``"flexmbs-checkpoint-1"``, ``flexmbs_version``.
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

FORMAT = "flexmbs-checkpoint-1"
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
            if "format" not in z.files or str(z["format"]) != FORMAT:
                raise ValueError("no flexmbs checkpoint format tag")
            state = State(float(z["t"]), *(z[f].copy() for f in _STATE_FIELDS))
            extra: dict[str, Any] = json.loads(str(z["extra_json"]))
            for k in z.files:
                if k.startswith("extra__"):
                    extra[k[len("extra__"):]] = z[k].copy()
    except FileNotFoundError:
        raise
    except (zipfile.BadZipFile, ValueError, EOFError, KeyError, TypeError, OSError) as exc:
        text = " ".join(str(exc).split())
        archive = isinstance(exc, (zipfile.BadZipFile, OSError)) or "pickle" in text
        reason = "not an .npz archive" if archive else (text[:80] or type(exc).__name__)
        raise ValueError(f"{path} is damaged or not a flexmbs checkpoint ({FORMAT}): "
                         f"{reason}") from None
    return state, extra

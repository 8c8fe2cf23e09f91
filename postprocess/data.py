"""Readers of a flexmbs output folder (no pyvista, no matplotlib)."""

from __future__ import annotations

import csv
import json
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np


def _damaged(path: Path, what: str) -> ValueError:
    return ValueError(f"{path} is damaged or not written by flexmbs ({what})")


def _read_csv(path: Path) -> tuple[list[str], list[list[str]]]:
    """Header and rows of a CSV file of the folder ([] and [] when missing); a file that is not
    UTF-8 CSV is a one-line ValueError naming it."""
    if not path.is_file():
        return [], []
    try:
        with open(path, newline="", encoding="utf-8") as f:
            rows = list(csv.reader(f))
    except UnicodeDecodeError as exc:
        raise _damaged(path, f"not UTF-8 text: byte 0x{exc.object[exc.start]:02x} at "
                             f"position {exc.start}") from None
    except csv.Error as exc:
        raise _damaged(path, f"not CSV: {exc}") from None
    return (rows[0], rows[1:]) if rows else ([], [])


def _column(path: Path, header: list[str], rows: list[list[str]], i: int) -> np.ndarray:
    """Column ``i`` of a numeric CSV file as floats; a row that is not numbers names the file."""
    try:
        return np.array([float(r[i]) for r in rows if r])
    except (ValueError, IndexError):
        line = next(k for k, r in enumerate(rows, start=2) if r and not _numbers(r, i))
        raise _damaged(path, f"line {line}: column {header[i]!r} is not a number") from None


def _numbers(row: list[str], i: int) -> bool:
    try:
        float(row[i])
    except (ValueError, IndexError):
        return False
    return True


@dataclass
class Run:
    """Everything post-processing needs from one output folder."""

    directory: Path
    name: str
    summary: dict
    frames: list[tuple[float, Path]]            #: (time, .vtu path) from the .pvd
    probes: dict[str, np.ndarray]               #: column -> values ("t" included)
    contacts: list[dict] = field(default_factory=list)
    sections: list[dict] = field(default_factory=list)

    @property
    def label(self) -> str:
        return self.directory.name

    def probe_groups(self) -> dict[str, list[str]]:
        """Probe name -> its columns (vector probes: name_x, name_y, name_z; a reaction's
        force name_fx, _fy, _fz and moment name_mx, _my, _mz as ``name_force`` and
        ``name_moment``: one unit per figure)."""
        groups: dict[str, list[str]] = {}
        for c in self.probes:
            if c == "t":
                continue
            base = c
            for suffix in ("_x", "_y", "_z", "_w"):
                if c.endswith(suffix) and any(k != c and k.startswith(c[: -len(suffix)] + "_")
                                              for k in self.probes):
                    base = c[: -len(suffix)]
            for kind, name in (("f", "force"), ("m", "moment")):
                stem = c[:-3]
                if c[-3:] in (f"_{kind}x", f"_{kind}y", f"_{kind}z") and all(
                        f"{stem}_{k}{a}" in self.probes for k in "fm" for a in "xyz"):
                    base = f"{stem}_{name}"
            groups.setdefault(base, []).append(c)
        return groups


def read_run(directory: str | Path) -> Run:
    """Read an output folder; a missing or empty folder is a clear error."""
    d = Path(directory)
    if not d.is_dir():
        raise FileNotFoundError(f"output folder not found: {d}")
    pvds = sorted(d.glob("*.pvd"))
    summary = {}
    if (d / "summary.json").is_file():
        try:
            summary = json.loads((d / "summary.json").read_text(encoding="utf-8"))
        except UnicodeDecodeError as exc:
            raise _damaged(d / "summary.json", f"not UTF-8 text: byte "
                           f"0x{exc.object[exc.start]:02x} at position {exc.start}") from None
        except ValueError as exc:
            raise _damaged(d / "summary.json", f"not JSON: {exc}") from None
        if not isinstance(summary, dict):
            raise _damaged(d / "summary.json", "not a JSON object")
    name = summary.get("scenario") or (pvds[0].stem if pvds else d.name)
    frames: list[tuple[float, Path]] = []
    if pvds:
        try:
            root = ET.parse(pvds[0]).getroot()
        except ET.ParseError as exc:
            raise ValueError(f"{pvds[0]} is damaged ({exc}); flexmbs run --resume rewrites it "
                             "from the checkpoint and the frames in vtu/") from None
        for ds in root.iter("DataSet"):
            frames.append((float(ds.get("timestep", "0")), (d / ds.get("file", "")).resolve()))
    header, rows = _read_csv(d / "probes.csv")
    probes = {h: _column(d / "probes.csv", header, rows, i) for i, h in enumerate(header)}
    ch, crow = _read_csv(d / "contacts.csv")
    contacts = [dict(zip(ch, r, strict=False)) for r in crow if r]
    sh, srow = _read_csv(d / "sections.csv")
    sections = [dict(zip(sh, r, strict=False)) for r in srow if r]
    if not frames and not probes:
        raise FileNotFoundError(f"{d} is not a flexmbs output folder (no .pvd, no probes.csv)")
    return Run(d, name, summary, frames, probes, contacts, sections)

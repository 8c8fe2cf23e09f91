"""Readers of a flexmbs output folder (no pyvista, no matplotlib)."""

from __future__ import annotations

import csv
import json
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np


def _read_csv(path: Path) -> tuple[list[str], list[list[str]]]:
    if not path.is_file():
        return [], []
    with open(path, newline="", encoding="utf-8") as f:
        rows = list(csv.reader(f))
    return (rows[0], rows[1:]) if rows else ([], [])


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
        """Probe name -> its columns (vector probes: name_x, name_y, name_z)."""
        groups: dict[str, list[str]] = {}
        for c in self.probes:
            if c == "t":
                continue
            base = c
            for suffix in ("_x", "_y", "_z", "_w"):
                if c.endswith(suffix) and any(k != c and k.startswith(c[: -len(suffix)] + "_")
                                              for k in self.probes):
                    base = c[: -len(suffix)]
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
        summary = json.loads((d / "summary.json").read_text(encoding="utf-8"))
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
    probes = {h: np.array([float(r[i]) for r in rows if r]) for i, h in enumerate(header)}
    ch, crow = _read_csv(d / "contacts.csv")
    contacts = [dict(zip(ch, r, strict=False)) for r in crow if r]
    sh, srow = _read_csv(d / "sections.csv")
    sections = [dict(zip(sh, r, strict=False)) for r in srow if r]
    if not frames and not probes:
        raise FileNotFoundError(f"{d} is not a flexmbs output folder (no .pvd, no probes.csv)")
    return Run(d, name, summary, frames, probes, contacts, sections)

"""zlib-compressed VTK frames against uncompressed ones (issue 55, item 5).

1. Whole runs: ``flexmbs run SCENARIO --out DIR --set simulation.vtk_compression=...`` as a
   subprocess, the two settings alternating, ``--runs`` times each: wall time of the command,
   bytes and files of the frames (``vtu/``) and of the whole output folder.
2. Encoding alone: every data array of the uncompressed run's frames, decoded, then encoded
   again both ways in this process (``--repeat`` times, best): the CPU time a frame's arrays
   cost to encode, uncompressed (base64) and compressed (zlib blocks + base64), without the
   solver or the file system.

The output folders go to ``--dir`` (default /dev/shm when it exists: a RAM disk, so that the
disk's load does not enter the times).

    python benchmarks/vtk_compression.py [--scenario examples/solar_array_wing.toml] [--runs 2]
"""

from __future__ import annotations

import argparse
import base64
import shutil
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def folder_size(path: Path) -> tuple[int, int]:
    files = [p for p in path.rglob("*") if p.is_file()]
    return sum(p.stat().st_size for p in files), len(files)


def run(scenario: Path, out: Path, compressed: bool) -> float:
    if out.exists():
        shutil.rmtree(out)
    cmd = [sys.executable, "-m", "flexmbs", "run", str(scenario), "--out", str(out), "--quiet",
           "--set", f"simulation.vtk_compression={'true' if compressed else 'false'}"]
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True)
    return time.perf_counter() - t0


def raw_arrays(vtu_dir: Path) -> list[list[bytes]]:
    """The raw bytes of every binary DataArray, per frame piece file."""
    pieces = []
    for f in sorted(vtu_dir.glob("*.vt[pu]")):
        arrays = []
        for arr in ET.parse(f).getroot().iter("DataArray"):
            if arr.get("format") == "binary":
                arrays.append(base64.b64decode((arr.text or "").strip())[8:])
        pieces.append(arrays)
    return pieces


def encode_times(pieces: list[list[bytes]], repeat: int) -> tuple[float, float]:
    import numpy as np

    from flexmbs.io.vtu import _zlib_blocks

    def plain(raw: bytes) -> str:
        return base64.b64encode(np.uint64(len(raw)).tobytes() + raw).decode("ascii")

    best = []
    for encode in (plain, _zlib_blocks):
        times = []
        for _ in range(repeat):
            t0 = time.perf_counter()
            for arrays in pieces:
                for raw in arrays:
                    encode(raw)
            times.append(time.perf_counter() - t0)
        best.append(min(times))
    return best[0], best[1]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default=str(ROOT / "examples" / "solar_array_wing.toml"))
    ap.add_argument("--runs", type=int, default=2)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--dir", default="/dev/shm" if Path("/dev/shm").is_dir() else ".")
    args = ap.parse_args(argv)
    scenario = Path(args.scenario)
    base = Path(args.dir) / "flexmbs_vtk_compression"
    walls: dict[bool, list[float]] = {False: [], True: []}
    for _ in range(args.runs):
        for compressed in (False, True):
            walls[compressed].append(run(scenario, base / ("zlib" if compressed else "plain"),
                                         compressed))
    for compressed in (False, True):
        out = base / ("zlib" if compressed else "plain")
        frames, n_frames = folder_size(out / "vtu")
        total, _ = folder_size(out)
        name = "zlib" if compressed else "uncompressed"
        print(f"{name:>12}: wall {', '.join(f'{w:.2f}' for w in walls[compressed])} s; "
              f"frames {frames / 1e6:.1f} MB in {n_frames} files; folder {total / 1e6:.1f} MB")
    pieces = raw_arrays(base / "plain" / "vtu")
    n = len(list((base / "plain" / "vtu").glob("*.vt[mu]")))
    plain, packed = encode_times(pieces, args.repeat)
    print(f"encoding the {n} frames' arrays alone (best of {args.repeat}): uncompressed "
          f"{plain:.2f} s ({1e3 * plain / n:.2f} ms per frame), zlib {packed:.2f} s "
          f"({1e3 * packed / n:.2f} ms per frame)")
    shutil.rmtree(base)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

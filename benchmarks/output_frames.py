"""Frame writing: the multiblock frames (.vtm + .vtp pieces) against the merged ones (.vtu)
(issue 35, Measure and report).

1. Per frame: Example 1's states at its output rate (every 1e-2 s up to ``--t-end``, recorded
   once by an in-process run without an output folder, with their contact records) are written
   by ``OutputWriter``'s two paths, ``FrameBuilder.multiblock`` + ``VTUSeries.write`` and
   ``FrameBuilder.__call__`` + ``VTUSeries.write``, ``--repeat`` times each, alternating; the
   best and the median time per frame, and the bytes per frame (all files of a frame).
2. Whole runs (``--runs N``): ``flexmbs run examples/curved_beam_sleeve.toml --t-end T`` as a
   subprocess, alternating ``--output-frames merged`` / ``multiblock``, wall time of each.

The files go to a temporary folder in ``--dir`` (default: the current directory, where
``flexmbs run`` writes ``out/``; file creation costs differ between file systems).

    python benchmarks/output_frames.py [--t-end 0.5] [--repeat 5] [--runs 3] [--dir DIR]
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = ROOT / "examples" / "curved_beam_sleeve.toml"


def record_states(t_end: float) -> tuple[object, list]:
    """(assembly, [(state, contact rows)]) of Example 1 at its outputs up to ``t_end``."""
    import flexmbs as fm
    from flexmbs.assembly import Assembly
    from flexmbs.io.scenario import load_scenario
    from flexmbs.simulation import interaction_outputs

    sc = load_scenario(SCENARIO, [f"simulation.t_end={t_end!r}"])
    asm = Assembly(sc.model)
    kept: list = []
    fm.simulate(asm, t_end=t_end, dt=sc.simulation.dt, integrator=sc.integrator_options(),
                output_interval=sc.simulation.output_interval, record_energy=False,
                observer=lambda s: kept.append((s.copy(), interaction_outputs(asm, s))))
    return asm, kept


def time_frames(asm: object, kept: list, form: str, where: Path) -> tuple[float, int]:
    """Seconds per frame and bytes per frame of writing ``kept`` in ``form``."""
    from flexmbs.io.frames import FrameBuilder
    from flexmbs.io.vtu import VTUSeries

    frames = FrameBuilder(asm)
    build = frames.multiblock if form == "multiblock" else frames.__call__
    t0 = time.perf_counter()
    with VTUSeries(where / "run.pvd") as series:
        for state, contacts in kept:
            series.write(state.t, build(state, contacts=contacts))
    per_frame = (time.perf_counter() - t0) / len(kept)
    size = sum(p.stat().st_size for p in (where / "vtu").iterdir()) / len(kept)
    return per_frame, int(size)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--t-end", type=float, default=0.5)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--runs", type=int, default=3, help="whole runs per form (0: none)")
    ap.add_argument("--dir", default=".", help="where the temporary output folders go")
    a = ap.parse_args()
    asm, kept = record_states(a.t_end)
    print(f"Example 1 to t = {a.t_end} s: {len(kept)} frames, "
          f"{sum(len(c) for _, c in kept)} contact points in all")
    times: dict[str, list[float]] = {"merged": [], "multiblock": []}
    sizes: dict[str, int] = {}
    with tempfile.TemporaryDirectory(dir=a.dir) as tmp:
        for r in range(a.repeat):
            for form in ("merged", "multiblock") if r % 2 == 0 else ("multiblock", "merged"):
                where = Path(tmp) / f"{form}_{r}"
                where.mkdir()
                dt, sizes[form] = time_frames(asm, kept, form, where)
                times[form].append(dt)
    for form, ts in times.items():
        print(f"{form:10s} frame write: best {1e3 * min(ts):.3f} ms, median "
              f"{1e3 * statistics.median(ts):.3f} ms per frame; {sizes[form] / 1e3:.1f} kB per "
              "frame")
    if a.runs <= 0:
        return
    walls: dict[str, list[float]] = {"merged": [], "multiblock": []}
    with tempfile.TemporaryDirectory(dir=a.dir) as tmp:
        for r in range(a.runs):
            for form in ("merged", "multiblock") if r % 2 == 0 else ("multiblock", "merged"):
                out = Path(tmp) / form
                t0 = time.perf_counter()
                subprocess.run([sys.executable, "-m", "flexmbs", "run", str(SCENARIO), "--t-end",
                                repr(a.t_end), "--quiet", "--out", str(out), "--output-frames",
                                form], check=True)
                walls[form].append(time.perf_counter() - t0)
    for form, ws in walls.items():
        print(f"{form:10s} flexmbs run --t-end {a.t_end}: " + ", ".join(f"{w:.2f}" for w in ws)
              + f" s (median {statistics.median(ws):.2f} s)")


if __name__ == "__main__":
    main()

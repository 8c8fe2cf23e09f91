"""Speed-up of an 8-case sweep on 2 Dask workers against the same cases one after another.

    python benchmarks/sweep_speedup.py [--t-end 1.0] [--workers 2]

The cases are Example 1 (``examples/curved_beam_sleeve.toml``) with the hole radius (4 values)
x the contact stiffness (2 values), ``t_end`` shortened. "Serial" runs the cases in this process
one after another with :func:`flexmbs.sweeps.run_case` (warm numba cache, no Dask); "sweep" is
:func:`flexmbs.sweep` on a new LocalCluster, cluster start-up included. Both write the same
case folders (below a temporary folder).
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import flexmbs as fm
from flexmbs.sweeps import make_cases, run_case

SCENARIO = str(Path(__file__).resolve().parents[1] / "examples" / "curved_beam_sleeve.toml")
GRID = {"joints.sleeve.hole.radius": [2.3e-3, 2.5e-3, 2.8e-3, 3.0e-3],
        "joints.sleeve.contact.stiffness": [1e5, 1e6]}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t-end", type=float, default=1.0)
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    fixed = [f"simulation.t_end={args.t_end!r}"]
    cases = make_cases(GRID, overrides=fixed)
    with tempfile.TemporaryDirectory() as tmp:
        run_case(SCENARIO, cases[0].overrides, str(Path(tmp) / "warm"))   # numba cache loaded
        t0 = time.perf_counter()
        for c in cases:
            row = run_case(SCENARIO, c.overrides, str(Path(tmp) / "serial" / c.name))
            assert row["status"] == "completed", row["status"]
        serial = time.perf_counter() - t0
        t0 = time.perf_counter()
        rows = fm.sweep(SCENARIO, GRID, overrides=fixed, out=Path(tmp) / "sweep",
                        workers=args.workers)
        parallel = time.perf_counter() - t0
        assert all(r["status"] == "completed" for r in rows)
    print(f"{len(cases)} cases of Example 1, t_end = {args.t_end:g} s")
    print(f"one after another : {serial:7.2f} s")
    print(f"sweep, {args.workers} workers  : {parallel:7.2f} s (LocalCluster start included)")
    print(f"speed-up          : {serial / parallel:7.2f}")


if __name__ == "__main__":
    main()

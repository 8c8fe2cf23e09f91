"""``flexmbs sweep SCENARIO --grid ... --zip ...``: variants of a scenario on Dask, one output
folder per case and the table ``sweep.csv`` (docs/sweeps.md)."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

from ..errors import FlexmbsError
from ._common import (
    EXIT_BAD_INPUT,
    EXIT_FAILED,
    EXIT_OK,
    Number,
    add_quiet,
    docs,
    error,
    failure_status,
    terminate_like_ctrl_c,
)

__all__ = ["add_parser", "run"]


def add_parser(sub: Any, parents: list[argparse.ArgumentParser]) -> None:
    sweep = sub.add_parser(
        "sweep", parents=parents, help="run variants of a scenario on Dask (parameter study)",
        description="Run the Cartesian product of --grid lists (times the --zip lists taken side "
                    "by side) of --set overrides on Dask, one output folder per case, and write "
                    f"the table sweep.csv ({docs('sweeps')}). A case whose worker dies is run "
                    "again; a rerun of the command skips completed cases.")
    sweep.add_argument("scenario", metavar="SCENARIO", help="scenario file (.toml)")
    sweep.add_argument("--grid", action="append", default=[], metavar="KEY=V1,V2,...",
                       help="values of one --set key; several --grid give their product")
    sweep.add_argument("--zip", action="append", default=[], metavar="KEY=V1,V2,...",
                       help="values taken side by side with the other --zip lists (same length)")
    sweep.add_argument("--out", metavar="DIR",
                       help="sweep folder (default: out/<scenario name>_sweep)")
    sweep.add_argument("--scheduler", metavar="ADDRESS",
                       help="an existing Dask scheduler (tcp://host:8786 or a scheduler file); "
                            "default: a LocalCluster on this machine")
    sweep.add_argument("--workers", type=Number(integer=True, ge=1), metavar="N",
                       help="LocalCluster worker processes (default: one per core)")
    add_quiet(sweep, "no progress output")


def run(args: argparse.Namespace) -> int:
    """``flexmbs sweep``: :func:`flexmbs.sweeps.sweep` with a progress line per case; exit 0
    when every case completed, 3 when some failed (the table lists them), 2 on bad input."""
    import importlib.util

    from ..sweeps import Case, parse_values, sweep

    if importlib.util.find_spec("distributed") is None:
        error('sweep needs dask.distributed; install it with pip install "dask[distributed]"')
        return EXIT_BAD_INPUT
    quiet = bool(args.quiet)
    t0 = time.perf_counter()

    def report(case: Case, row: dict[str, Any], done: int, total: int, reused: bool) -> None:
        status = str(row.get("status"))
        if quiet:
            return
        if status != "completed":
            error(f"case {case.name} {status}")
        elif reused:
            print(f"[{done}/{total}] {case.name}: completed by an earlier run (kept)",
                  file=sys.stderr, flush=True)
        else:
            deaths = int(row.get("attempts") or 1) - 1
            again = (f", run again from the start after {deaths} worker death"
                     f"{'s' if deaths > 1 else ''}" if deaths > 0 else "")
            print(f"[{done}/{total}] {case.name}: completed in {row.get('wall_time', 0):.3g} s, "
                  f"{row.get('steps')} steps{again}", file=sys.stderr, flush=True)

    restore = terminate_like_ctrl_c()
    try:
        grid = dict(parse_values(g, "--grid") for g in args.grid)
        zipped = dict(parse_values(z, "--zip") for z in args.zip)
        if len(grid) != len(args.grid) or len(zipped) != len(args.zip):
            error("sweep: a key is given twice; give each --grid/--zip key once")
            return EXIT_BAD_INPUT
        rows = sweep(args.scenario, grid, zip=zipped, overrides=args.overrides, out=args.out,
                     scheduler=args.scheduler, workers=args.workers, report=report)
    except (KeyboardInterrupt, FlexmbsError, OSError) as exc:
        return failure_status(exc, interrupted="sweep interrupted (finished cases are in the "
                              "table; rerun to continue)")
    finally:
        restore()
    failed = [r for r in rows if r.get("status") != "completed"]
    if not quiet:
        from ..sweeps import TABLE_FILE

        table = Path(str(rows[0]["folder"])).parent / TABLE_FILE
        print(f"sweep: {len(rows) - len(failed)} of {len(rows)} cases completed, {len(failed)} "
              f"failed, wall time {time.perf_counter() - t0:.3g} s; table: {table}")
    return EXIT_FAILED if failed else EXIT_OK

"""Catheter figure (docs/examples.md): a catheter advanced over a guide wire in a vessel.

Runs ``flexmbs run examples/catheter.toml`` into ``--runs`` (unless the folder exists; use
``--rerun``), then draws into ``docs/figures/`` with postprocess/ (which only reads the output
folder):

- ``catheter.png``: the vessel, the catheter and the wire at the end of each push (from above),
  and the two feeders' forces against time.

    python examples/figures/catheter.py [--rerun]
"""

from __future__ import annotations

import argparse
import importlib
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]   # the checkout: its flexmbs, postprocess, examples
sys.path[:0] = [str(ROOT), str(ROOT / "examples")]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=Path, default=ROOT / "out" / "catheter",
                    help="output folder of the run")
    ap.add_argument("--figures", type=Path, default=ROOT / "docs" / "figures")
    ap.add_argument("--rerun", action="store_true")
    args = ap.parse_args(argv)
    # examples/catheter.py (this script shares its name: examples/ is first on the path)
    catheter = importlib.import_module("catheter")

    from flexmbs.cli import main as flexmbs
    from postprocess.catheter import catheter_figure
    from postprocess.data import read_run
    from postprocess.figures import save_figures

    if args.rerun or not (args.runs / "probes.csv").is_file():
        code = flexmbs(["run", str(ROOT / "examples" / "catheter.toml"), "--out",
                        str(args.runs), "-q", "--overwrite"])
        if code:
            return code
    figure = catheter_figure(read_run(args.runs),
                             pushes={"wire": catheter.WIRE_PUSHES,
                                     "catheter": catheter.CATHETER_PUSHES})
    for p in save_figures({"catheter": figure}, args.figures, ["png"]):
        print(p)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

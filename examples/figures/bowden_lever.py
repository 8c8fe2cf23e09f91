"""Bowden lever figure set (docs/examples.md): the lever's angle against the pull, with and
without friction.

Runs ``flexmbs run examples/bowden_lever.toml`` with μ = 0.2 and μ = 0 into ``--runs/mu_<μ>``
(unless the folder exists; use ``--rerun``), then draws into ``docs/figures/`` with
postprocess/ (which only reads the output folders):

- ``bowden_lever.png``: the lever's angle against the pull, on the capstan statics
  e^{−μΘ} (pulling) and e^{+μΘ} (letting back): the friction loop; and against the input's
  travel: the take-up of the clearance, cΘ, before the lever moves.

    python examples/figures/bowden_lever.py [--rerun]
"""

from __future__ import annotations

import argparse
import importlib
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]   # the checkout: its flexmbs, postprocess, examples
sys.path[:0] = [str(ROOT), str(ROOT / "examples")]
MUS = ("0.2", "0")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=Path, default=ROOT / "out" / "bowden_lever",
                    help="folder of the runs (one per friction coefficient)")
    ap.add_argument("--figures", type=Path, default=ROOT / "docs" / "figures")
    ap.add_argument("--rerun", action="store_true")
    args = ap.parse_args(argv)
    # examples/bowden_lever.py (this script shares its name: examples/ is first on the path)
    bowden_lever = importlib.import_module("bowden_lever")

    from flexmbs.cli import main as flexmbs
    from postprocess.bowden import lever_figure
    from postprocess.data import read_run
    from postprocess.figures import save_figures

    runs = {}
    for mu in MUS:
        out = args.runs / f"mu_{mu}"
        if args.rerun or not (out / "probes.csv").is_file():
            code = flexmbs(["run", str(ROOT / "examples" / "bowden_lever.toml"), "--out", str(out),
                            "-q", "--set", f"joints.tube.contact.friction={mu}"])
            if code:
                return code
        runs[f"μ = {mu}"] = read_run(out)
    figure = lever_figure(runs, stiffness=bowden_lever.SPRING, arm=bowden_lever.ARM,
                          wrap=bowden_lever.WRAP, mu={f"μ = {mu}": float(mu) for mu in MUS},
                          take_up=(bowden_lever.BORE - bowden_lever.WIRE_R) * bowden_lever.WRAP)
    paths = save_figures({"bowden_lever": figure}, args.figures, ["png"])
    for p in paths:
        print(p)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Tendon robot figure set (issue 52): the shape of every load case and the tensions along
the routes.

Runs examples/tendon_robot.py for each load case into ``--runs/<case>`` (unless the folder
exists; use ``--rerun``), then draws into ``docs/figures/`` with postprocess/ (which only reads
the output folders):

- ``robot_shapes.png``: the backbone through the disk centres, every case, three views;
- ``robot_tensions.png``: the tension in every span of each loaded tendon, per case;
- ``robot_loop.png``: the last disk's displacement against tendon 4's pull, up to 2 N and
  back, without friction and with μ = 0.1, as equilibria on 10 disks
  (``examples/tendon_robot.py --loop --static --disks 10``).

    python examples/figures/tendon_robot.py [--disks 20] [--mu 0] [--rerun]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]   # the checkout: its flexmbs, postprocess, examples
sys.path[:0] = [str(ROOT), str(ROOT / "examples")]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--disks", type=int, default=20)
    ap.add_argument("--mu", type=float, default=0.0)
    ap.add_argument("--runs", type=Path, default=ROOT / "out" / "tendon_robot",
                    help="folder of the runs (one per case)")
    ap.add_argument("--figures", type=Path, default=ROOT / "docs" / "figures")
    ap.add_argument("--rerun", action="store_true")
    args = ap.parse_args(argv)
    import tendon_robot

    from postprocess.data import read_run
    from postprocess.figures import save_figures
    from postprocess.robot import robot_loop, robot_shapes, robot_tensions

    runs = {}
    for case in tendon_robot.CASES:
        out = args.runs / case
        if args.rerun or not (out / "probes.csv").is_file():
            tendon_robot.main(["--case", case, "--disks", str(args.disks), "--mu", str(args.mu),
                               "--out", str(out)])
        runs[case] = read_run(out)
    loop = args.runs / "loop"
    if args.rerun or not (loop / "mu_0.1" / "probes.csv").is_file():
        # 10 disks: on 20 the quasi-static loop with friction stops just after the peak
        # (design notes, "Quasi-static paths")
        tendon_robot.main(["--loop", "--static", "--disks", "10", "--mu", "0.1",
                           "--out", str(loop)])
    loops = {f"mu = {mu}": read_run(loop / f"mu_{mu}") for mu in ("0", "0.1")}
    paths = save_figures({"robot_shapes": robot_shapes(runs),
                          "robot_tensions": robot_tensions(runs),
                          "robot_loop": robot_loop(loops)}, args.figures, ["png"])
    for p in paths:
        print(p)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

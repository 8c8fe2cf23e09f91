"""Example 2 figure set (docs/examples.md), the paper's Fig. 2(a)-(d), from the output folders
of ``flexmbs run examples/solar_array_wing.toml`` and ``..._ideal.toml``:

- ``ex2_wire_mid.png``: vertical (Z) displacement of the guide-wire midpoint, with and without
  clearance (Fig. 2(c));
- ``ex2_edge_CE.png``: Z deflection of the midpoint of the panel edge CE (Fig. 2(d));
- ``ex2_section.png``: the middle cross-section of the grommet at the last output (Fig. 2(b));
- ``ex2_render.png``: a view of wire, panels and grommet at the last output (Fig. 2(a));
- ``ex2_contacts.png``: grommet contact forces and active points.

    python examples/figures/example2.py [--clearance out/solar_array_wing]
        [--ideal out/solar_array_wing_ideal] [--sensitivity T_END]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]   # the checkout: its flexmbs, postprocess, examples
sys.path.insert(0, str(ROOT))


VARIANTS = {
    "baseline": [],
    "clearance 0.6 mm": ["joints.grommet.hole.radius=1.4e-3"],
    "clearance 0.3 mm": ["joints.grommet.hole.radius=1.1e-3"],
    "5 sections": ["joints.grommet.hole.sections=5"],
    "k = 3.2e5 N/m": ["joints.grommet.contact.stiffness=3.2e5"],
    "dt = 5e-5 s": ["simulation.dt=5e-5"],
    "dt = 2e-4 s": ["simulation.dt=2e-4"],
}


def sensitivity(t_end: float, out: Path) -> list[tuple[str, float, float, float]]:
    """Run the variants for ``t_end`` and compare the wire midpoint and M_CE with the baseline."""
    import numpy as np

    import postprocess
    from flexmbs.cli import main as flexmbs

    rows = []
    runs = {}
    for name, sets in VARIANTS.items():
        d = out / name.replace(" ", "_").replace("=", "").replace(".", "p")
        if not (d / "summary.json").is_file():
            args = ["run", str(ROOT / "examples" / "solar_array_wing.toml"), "--t-end", str(t_end),
                    "--quiet", "--out", str(d)]
            for s_ in sets:
                args += ["--set", s_]
            flexmbs(args)
        runs[name] = postprocess.read_run(d)
    base = runs["baseline"]
    for name, run in runs.items():
        n = min(len(run.probes["t"]), len(base.probes["t"]))
        dw = np.abs(run.probes["wire_mid_z"][:n] - base.probes["wire_mid_z"][:n]).max()
        dm = np.abs(run.probes["M_CE_z"][:n] - base.probes["M_CE_z"][:n]).max()
        fmax = np.abs(run.probes["grommet_force_y"]).max()
        rows.append((name, dw, dm, fmax))
        print(f"{name:18s} max|dw_mid| {dw:.3e} m  max|dM_CE| {dm:.3e} m  max|F_y| {fmax:.3f} N  "
              f"wall {run.summary.get('wall_time', float('nan')):.1f} s")
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--clearance", default=str(ROOT / "out" / "solar_array_wing"))
    ap.add_argument("--ideal", default=str(ROOT / "out" / "solar_array_wing_ideal"))
    ap.add_argument("--figures", default=str(ROOT / "docs" / "figures"))
    ap.add_argument("--sensitivity", type=float, metavar="T_END",
                    help="run the sensitivity variants for T_END seconds and print the table")
    args = ap.parse_args(argv)
    if args.sensitivity:
        sensitivity(args.sensitivity, ROOT / "out" / "example2_sensitivity")
        return 0
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    import postprocess
    from postprocess.plots import make_figures

    figs = Path(args.figures)
    figs.mkdir(parents=True, exist_ok=True)
    clr = postprocess.read_run(args.clearance)
    ide = postprocess.read_run(args.ideal)

    for col, name, title in (("wire_mid_z", "ex2_wire_mid.png",
                              "vertical displacement of the guide-wire midpoint"),
                             ("M_CE_z", "ex2_edge_CE.png",
                              "deflection of the midpoint of edge CE")):
        fig, ax = plt.subplots(figsize=(7, 3.2))
        ax.plot(ide.probes["t"], 1e3 * ide.probes[col], "k--", lw=1, label="without clearance")
        ax.plot(clr.probes["t"], 1e3 * clr.probes[col], "b-", lw=0.8, label="clearance 1.2 mm")
        ax.set(xlabel="t [s]", ylabel="Z [mm]", title=title)
        ax.legend()
        ax.grid(alpha=0.3)
        fig.tight_layout()
        fig.savefig(figs / name, dpi=110)
        plt.close(fig)
    f = make_figures(clr)["contacts"]
    f.set_size_inches(7, 5)
    f.tight_layout()
    f.savefig(figs / "ex2_contacts.png", dpi=110)
    plt.close(f)
    postprocess.section_view(clr.directory, joint="grommet", section=1,
                             path=figs / "ex2_section.png")
    files = postprocess.render(clr.directory, png_every=1, frames=[-1], window_size=(900, 500),
                               tube_scale=3, camera="iso", color_by="displacement", progress=False)
    if files:
        Path(files[0]).replace(figs / "ex2_render.png")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Example 2 figure set (docs/examples.md), the paper's Fig. 2(a)-(d), from the output folders
of ``flexmbs run examples/solar_array_wing.toml`` and ``..._ideal.toml``:

- ``ex2_wire_mid.png``: vertical (Z) displacement of the guide-wire midpoint, with and without
  clearance (Fig. 2(c));
- ``ex2_edge_CE.png``: Z deflection of the midpoint of the panel edge CE (Fig. 2(d));
- ``ex2_section.png``: the middle cross-section of the grommet at the last output (Fig. 2(b));
- ``ex2_render.png``: a view of wire, panels and grommet at the last output (Fig. 2(a));
- ``ex2_contacts.png``: grommet contact forces and active points.

    python postprocess/example2.py [--clearance out/solar_array_wing] [--ideal out/solar_array_wing_ideal]
"""

from __future__ import annotations

import argparse
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--clearance", default=str(ROOT / "out" / "solar_array_wing"))
    ap.add_argument("--ideal", default=str(ROOT / "out" / "solar_array_wing_ideal"))
    ap.add_argument("--figures", default=str(ROOT / "docs" / "figures"))
    args = ap.parse_args(argv)
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

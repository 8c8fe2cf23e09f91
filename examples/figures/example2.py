"""Example 2 figure set (docs/examples.md), the paper's Fig. 2(a)-(d), from the output folders
of ``flexmbs run examples/solar_array_wing.toml`` and ``..._ideal.toml`` (20 s):

- ``ex2_wire_mid.png``: vertical (Z) displacement of the guide-wire midpoint, with and without
  clearance (Fig. 2(c));
- ``ex2_edge_CE.png``: Z deflection of the midpoint of the panel edge CE (the middle panel's
  side edge, Fig. 2(d));
- ``ex2_section.png``: the middle cross-section of eyelet 1 at t = 20 s: bore, ellipse, the two
  contact points Q and their projections (Fig. 2(b));
- ``ex2_render.png``: wire, panels and eyelets at t = 20 s (Fig. 2(a));
- ``ex2_points.png``: the number of contact points (deepest points) per section over time;
- ``ex2_contacts.png``: eyelet contact forces and active points.

    python examples/figures/example2.py [--clearance out/solar_array_wing]
        [--ideal out/solar_array_wing_ideal] [--sensitivity T_END]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]   # the checkout: its flexmbs, postprocess, examples
sys.path.insert(0, str(ROOT))


GROMMETS = ("grommet1", "grommet2", "grommet3")


def _all(key: str, value: str) -> list[str]:
    """One override for every eyelet."""
    return [f"joints.{g}.{key}={value}" for g in GROMMETS]


VARIANTS = {
    "baseline": [],
    "clearance 0.9 mm": _all("hole.radius", "1.7e-3"),
    "clearance 1.6 mm": _all("hole.radius", "2.4e-3"),
    "5 sections": _all("hole.sections", "5"),
    "k = 1.6e5 N/m": _all("contact.stiffness", "1.6e5"),
    "step_tolerance = 1e-6": ["simulation.step_tolerance=1e-6"],
    "fixed h = 1e-4 s": ["simulation.dt=1e-4", "simulation.step_tolerance=0"],
}


def sensitivity(t_end: float, out: Path) -> list[tuple[str, float, float, float, float]]:
    """Run the variants for ``t_end`` and compare the wire midpoint and M_CE with the baseline;
    prints a Markdown table row per variant (max differences in mm, eyelet 1's largest force,
    share of outputs with two points in its middle section, Newton iterations per step,
    rejected steps, wall time)."""
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
        fmax = np.abs(run.probes["grommet1_force_y"]).max()
        two = _two_point_share(run)
        st = run.summary.get("stats", {})
        rows.append((name, dw, dm, fmax, two))
        print(f"| {name} | {1e3 * dw:.3f} | {1e3 * dm:.3f} | {fmax:.3f} | {100 * two:.0f} % | "
              f"{st.get('newton_iterations', 0) / max(st.get('steps', 1), 1):.2f} | "
              f"{st.get('rejected_steps', 0)} | {run.summary.get('wall_time', float('nan')):.1f} |")
    return rows


def _two_point_share(run) -> float:
    """Share of the outputs at which eyelet 1's middle section touches at two points."""
    middle = max(int(r["section"]) for r in run.sections if r["joint"] == "grommet1") // 2
    times = {}
    for r in run.contacts:
        if (r["joint"] == "grommet1" and int(r["section"]) == middle
                and float(r["normal_force"]) > 0):
            times[r["t"]] = times.get(r["t"], 0) + 1
    return sum(1 for c in times.values() if c == 2) / max(len(run.probes["t"]), 1)


def _sensitivity_figure(out: Path, path: Path) -> None:
    """M_CE of the clearance and penalty variants over the first 5 s."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    import postprocess

    fig, ax = plt.subplots(figsize=(7, 3.2))
    for name in ("baseline", "clearance 0.9 mm", "clearance 1.6 mm", "k = 1.6e5 N/m"):
        run = postprocess.read_run(out / name.replace(" ", "_").replace("=", "").replace(".", "p"))
        t = np.asarray(run.probes["t"])
        keep = t <= 5.0
        label = "clearance 1.2 mm, k = 4e4 N/m" if name == "baseline" else name
        ax.plot(t[keep], 1e3 * np.asarray(run.probes["M_CE_z"])[keep], lw=0.8, label=label)
    ax.set(xlabel="t [s]", ylabel="Z [mm]", title="edge CE: clearance and penalty variants")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _points_figure(run, path: Path) -> None:
    """Deepest contact points per section of eyelets 1 and 2 over time (contacts.csv)."""
    import matplotlib.pyplot as plt
    import numpy as np

    t = np.asarray(run.probes["t"])
    index = {round(float(x), 9): i for i, x in enumerate(t)}
    counts: dict[tuple[str, int], np.ndarray] = {}
    for r in run.contacts:
        if float(r["normal_force"]) <= 0:
            continue
        key = (r["joint"], int(r["section"]))
        counts.setdefault(key, np.zeros(t.size, int))[index[round(float(r["t"]), 9)]] += 1
    fig, axes = plt.subplots(2, 1, figsize=(7, 4), sharex=True)
    for ax, joint in zip(axes, GROMMETS[:2], strict=True):
        for k, style in ((0, "C0-"), (1, "C3-"), (2, "C2--")):
            c = counts.get((joint, k), np.zeros(t.size, int))
            ax.step(t, c + 0.04 * (k - 1), style, lw=0.8, where="post",
                    label=("end section 1", "middle section", "end section 2")[k])
        ax.set(ylabel="points", title=f"{joint}: contact points per section", ylim=(-0.3, 2.5))
        ax.grid(alpha=0.3)
    axes[0].legend(loc="center right", fontsize=8)
    axes[1].set_xlabel("t [s]")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--clearance", default=str(ROOT / "out" / "solar_array_wing"))
    ap.add_argument("--ideal", default=str(ROOT / "out" / "solar_array_wing_ideal"))
    ap.add_argument("--figures", default=str(ROOT / "docs" / "figures"))
    ap.add_argument("--sensitivity", type=float, metavar="T_END",
                    help="run the sensitivity variants for T_END seconds and print the table")
    args = ap.parse_args(argv)
    if args.sensitivity:
        out = ROOT / "out" / "example2_sensitivity"
        sensitivity(args.sensitivity, out)
        _sensitivity_figure(out, Path(args.figures) / "ex2_sensitivity.png")
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
    _points_figure(clr, figs / "ex2_points.png")
    f = make_figures(clr)["contacts"]
    f.set_size_inches(7, 5)
    f.tight_layout()
    f.savefig(figs / "ex2_contacts.png", dpi=110)
    plt.close(f)
    postprocess.section_view(clr.directory, joint="grommet1", section=1,
                             path=figs / "ex2_section.png")
    files = postprocess.render(clr.directory, png_every=1, frames=[-1], window_size=(900, 500),
                               tube_scale=3, camera="iso", color_by="displacement", progress=False)
    if files:
        Path(files[0]).replace(figs / "ex2_render.png")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

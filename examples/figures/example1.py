"""Example 1 figure set (docs/examples.md): with vs without clearance, clearance sensitivity.

Runs the models through examples/curved_beam_sleeve.py (unless the output folders exist; use
``--rerun``), then draws into ``docs/figures/`` with postprocess/ (which only reads the output
folders):

- ``ex1_slide.png``: slide coordinate s(t), with clearance vs the clearance-free joint;
- ``ex1_rail.png``: vertical displacement of the rail's lowest point;
- ``ex1_tilt.png``: angle between the sleeve axis and the undeformed rail tangent at s;
- ``ex1_contacts.png``: normal force per hole section and number of active contact points;
- ``ex1_sensitivity.png``: |s_c - s_ideal| for clearances 0.5, 0.1, 0.02 mm (10 mm long hole,
  see docs/examples.md for why);
- ``ex1_section.png`` and ``ex1_render.png``: section view and a rendered frame.

    python examples/figures/example1.py [--t-end 4.0] [--sensitivity-t-end 2.0] [--rerun]
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]   # the checkout: its flexmbs, postprocess, examples
sys.path[:0] = [str(ROOT), str(ROOT / "examples")]


def _run(out: Path, t_end: float, rerun: bool, **kw) -> Path:
    from curved_beam_sleeve import build  # examples/curved_beam_sleeve.py

    import flexmbs as fm
    from flexmbs.io.probes import BodyOrientationProbe

    if (out / "summary.json").is_file() and not rerun:
        return out
    model, rail, sleeve, joint, probes = build(**kw)
    probes.append(BodyOrientationProbe("sleeve_q", sleeve))
    fm.simulate(model, t_end=t_end, dt=1e-4, output_interval=1e-2, probes=probes, out=out,
                name=out.name)
    return out


def _tilt(run) -> np.ndarray:
    """Angle between the sleeve axis and the undeformed rail tangent at s (the arc
    phi = s - pi/4 with tangent (cos phi, 0, sin phi)); it includes the rail's own rotation
    under the moving sleeve, which is what the clearance-free curve shows."""
    from flexmbs.elements.rigid_body import normalize, rotation_matrix

    p = run.probes
    out = []
    for i in range(len(p["t"])):
        A = rotation_matrix(normalize(np.array([p["sleeve_q_w"][i], p["sleeve_q_x"][i],
                                                p["sleeve_q_y"][i], p["sleeve_q_z"][i]])))
        phi = p["sleeve_s"][i] - math.pi / 4
        t = np.array([math.cos(phi), 0.0, math.sin(phi)])
        out.append(math.atan2(np.linalg.norm(np.cross(A[:, 0], t)), A[:, 0] @ t))
    return np.array(out)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t-end", type=float, default=4.0)
    ap.add_argument("--sensitivity-t-end", type=float, default=2.0)
    ap.add_argument("--out", default=str(ROOT / "out" / "example1"))
    ap.add_argument("--figures", default=str(ROOT / "docs" / "figures"))
    ap.add_argument("--rerun", action="store_true")
    args = ap.parse_args(argv)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    import postprocess

    base = Path(args.out)
    figs = Path(args.figures)
    figs.mkdir(parents=True, exist_ok=True)
    clr = postprocess.read_run(_run(base / "clearance", args.t_end, args.rerun))
    ide = postprocess.read_run(_run(base / "ideal", args.t_end, args.rerun, ideal=True))
    sens = {c: postprocess.read_run(_run(base / f"hole10_c{c * 1e3:g}mm", args.sensitivity_t_end,
                                         args.rerun, clearance=c, hole_length=0.01))
            for c in (5e-4, 1e-4, 2e-5)}
    ide10 = postprocess.read_run(_run(base / "hole10_ideal", args.sensitivity_t_end, args.rerun,
                                      ideal=True, hole_length=0.01))

    def save(fig, name: str) -> None:
        fig.tight_layout()
        fig.savefig(figs / name, dpi=110)
        plt.close(fig)

    fig, ax = plt.subplots(figsize=(7, 3.2))
    ax.plot(ide.probes["t"], ide.probes["sleeve_s"], "k--", label="without clearance")
    ax.plot(clr.probes["t"], clr.probes["sleeve_s"], "b-", lw=1, label="clearance 0.5 mm")
    ax.set(xlabel="t [s]", ylabel="s [m]", title="slide coordinate (arc length from the first node)")
    ax.legend()
    ax.grid(alpha=0.3)
    save(fig, "ex1_slide.png")

    fig, ax = plt.subplots(figsize=(7, 3.2))
    ax.plot(ide.probes["t"], 1e3 * ide.probes["lowest_point_z"], "k--", label="without clearance")
    ax.plot(clr.probes["t"], 1e3 * clr.probes["lowest_point_z"], "b-", lw=1,
            label="clearance 0.5 mm")
    ax.set(xlabel="t [s]", ylabel="w [mm]", title="vertical displacement of the rail's lowest point")
    ax.legend()
    ax.grid(alpha=0.3)
    save(fig, "ex1_rail.png")

    fig, ax = plt.subplots(figsize=(7, 3.2))
    ax.plot(ide.probes["t"], 1e3 * _tilt(ide), "k--", label="without clearance")
    ax.plot(clr.probes["t"], 1e3 * _tilt(clr), "b-", lw=1, label="clearance 0.5 mm")
    ax.set(xlabel="t [s]", ylabel="angle [mrad]",
           title="sleeve axis vs the undeformed rail tangent (includes the rail's own rotation)")
    ax.legend()
    ax.grid(alpha=0.3)
    save(fig, "ex1_tilt.png")

    from postprocess.plots import make_figures

    f = make_figures(clr)["contacts"]
    f.set_size_inches(7, 5)
    save(f, "ex1_contacts.png")

    fig, ax = plt.subplots(figsize=(7, 3.2))
    for c, run in sens.items():
        n = min(len(run.probes["t"]), len(ide10.probes["t"]))
        d = np.abs(run.probes["sleeve_s"][:n] - ide10.probes["sleeve_s"][:n])
        ax.semilogy(run.probes["t"][:n], np.maximum(d, 1e-12), label=f"c = {c * 1e3:g} mm")
    ax.set(xlabel="t [s]", ylabel="|s_c - s_ideal| [m]",
           title="convergence to the clearance-free joint (hole 10 mm)")
    ax.legend()
    ax.grid(alpha=0.3, which="both")
    save(fig, "ex1_sensitivity.png")

    t_sec = float(clr.probes["t"][np.argmax(np.abs(clr.probes["contact_force_z"]))])
    postprocess.section_view(clr.directory, joint="sleeve", section=0, time=t_sec,
                             path=figs / "ex1_section.png")
    files = postprocess.render(clr.directory, png_every=1, frames=[len(clr.frames) // 8],
                               window_size=(900, 500), tube_scale=4, camera="xz", progress=False)
    if files:
        Path(files[0]).replace(figs / "ex1_render.png")
    for c, run in sens.items():
        n = min(len(run.probes["t"]), len(ide10.probes["t"]))
        d = np.abs(run.probes["sleeve_s"][:n] - ide10.probes["sleeve_s"][:n]).max()
        print(f"hole 10 mm, c = {c * 1e3:g} mm: max |s_c - s_ideal| = {d:.3e} m "
              f"(wall {run.summary.get('wall_time', float('nan')):.1f} s)")
    for r in (clr, ide):
        print(f"{r.label}: wall {r.summary.get('wall_time', float('nan')):.1f} s, "
              f"{r.summary.get('steps')} steps, {r.summary.get('newton_iterations')} Newton its")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

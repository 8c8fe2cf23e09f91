"""Time-history figures of an output folder (matplotlib, Agg): every probe, contact forces per
section, number of active contact points, energies; optionally a second run overlaid."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .data import Run, read_run


def _contact_series(run: Run) -> tuple[np.ndarray, dict[tuple[str, int], np.ndarray], np.ndarray]:
    """Output times, signed normal force per (joint, section) summed over points, and the number
    of active contact points per time (zero where a section is inactive)."""
    t = run.probes.get("t")
    if t is None or not len(t):
        t = np.array(sorted({float(c["t"]) for c in run.contacts}))
    index = {round(float(x), 12): i for i, x in enumerate(t)}
    forces: dict[tuple[str, int], np.ndarray] = {}
    count = np.zeros(len(t))
    for c in run.contacts:
        i = index.get(round(float(c["t"]), 12))
        if i is None:
            continue
        key = (c["joint"], int(c["section"]))
        forces.setdefault(key, np.zeros(len(t)))[i] += float(c["normal_force"] or 0.0)
        count[i] += 1
    return t, forces, count


def make_figures(run: Run, compare: Run | None = None) -> dict[str, object]:
    """matplotlib Figures by file stem (not saved)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figs: dict[str, object] = {}
    runs = [run] + ([compare] if compare is not None else [])
    styles = ["-", "--"]
    for name, cols in run.probe_groups().items():
        fig, ax = plt.subplots(figsize=(7, 3.5))
        for r, ls in zip(runs, styles, strict=False):
            for c in cols:
                if c in r.probes:
                    lab = c if compare is None else f"{c} ({r.label})"
                    ax.plot(r.probes["t"], r.probes[c], ls, label=lab)
        ax.set_xlabel("t [s]")
        ax.set_ylabel(name)
        ax.set_title(f"probe {name}")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        figs[f"probe_{name}"] = fig
    if run.contacts or (compare is not None and compare.contacts):
        fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
        for r, ls in zip(runs, styles, strict=False):
            if not r.contacts:
                continue
            t, forces, count = _contact_series(r)
            for (joint, sec), f in sorted(forces.items()):
                lab = f"{joint} s{sec}" + ("" if compare is None else f" ({r.label})")
                ax1.plot(t, f, ls, label=lab)
            ax2.plot(t, count, ls, drawstyle="steps-post", label=r.label)
        ax1.set_ylabel("normal force [N]")
        ax1.set_title("contact force per hole section")
        ax1.legend(fontsize=7, ncol=3)
        ax1.grid(True, alpha=0.3)
        ax2.set_ylabel("active contact points")
        ax2.set_xlabel("t [s]")
        ax2.legend(fontsize=8)
        ax2.grid(True, alpha=0.3)
        fig.tight_layout()
        figs["contacts"] = fig
    return figs


def plot(out_dir: str | Path, *, compare: str | Path | None = None,
         formats: Sequence[str] = ("png", "svg")) -> list[Path]:
    """Write the figures of :func:`make_figures` into ``out_dir/figures``; returns the paths."""
    import matplotlib.pyplot as plt

    for f in formats:
        if f not in ("png", "svg", "pdf"):
            raise ValueError(f"unknown figure format '{f}' (known: png, svg, pdf)")
    run = read_run(out_dir)
    other = read_run(compare) if compare is not None else None
    figs = make_figures(run, other)
    folder = run.directory / "figures"
    folder.mkdir(exist_ok=True)
    written = []
    for stem, fig in figs.items():
        for f in formats:
            p = folder / f"{stem}.{f}"
            fig.savefig(p, dpi=120)
            written.append(p)
        plt.close(fig)
    return written

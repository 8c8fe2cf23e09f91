"""Time-history figures of an output folder (matplotlib, Agg): every probe, contact forces per
section, number of active contact points, energies, and for a bore of many sections the contact
force along it; optionally a second run overlaid."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .data import Run, read_run
from .figures import save_figures


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


#: a clearance joint with more sections than this gets the figure of the contact force along
#: its bore (:func:`_along_bore`), and no per-section legend in the time-history figure
MANY_SECTIONS = 12

#: times drawn in the along-the-bore figure's upper panel
ALONG_TIMES = 6


def _bores(run: Run) -> dict[str, tuple[float, int]]:
    """Clearance joints of many sections (summary.json ``hole_sections``): name -> (bore
    length, number of sections); the sections are equally spaced along the bore."""
    out: dict[str, tuple[float, int]] = {}
    for name, rec in (run.summary.get("hole_sections") or {}).items():
        try:
            length, n = float(rec["length"]), int(rec["sections"])
        except (KeyError, TypeError, ValueError):
            continue
        if n > MANY_SECTIONS:
            out[name] = (length, n)
    return out


def _along_bore(run: Run, joint: str, length: float, n: int) -> Any:
    """The contact force along the bore of ``joint``: per section (summed over its points)
    against the distance from the bore's first section, at up to :data:`ALONG_TIMES` output
    times (the last included), and as a map over time and distance."""
    import matplotlib.pyplot as plt

    t, forces, _ = _contact_series(run)
    spacing = length / (n - 1)
    grid = np.zeros((len(t), n))
    for (name, k), f in forces.items():
        if name == joint and 0 <= k < n:
            grid[:, k] = f
    s = np.arange(n) * spacing
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(7, 6.5))
    touched = np.flatnonzero(np.any(grid != 0.0, axis=1))
    if touched.size:
        picks = np.unique(np.linspace(touched[0], len(t) - 1, ALONG_TIMES).round().astype(int))
        for i in picks:
            ax1.plot(s, grid[i], drawstyle="steps-mid", label=f"t = {t[i]:.4g} s")
        ax1.legend(fontsize=8)
    ax1.set(xlabel="distance along the bore [m]", ylabel="normal force [N]",
            title=f"{joint}: contact force per section ({n} sections, {spacing:.3g} m apart)")
    ax1.grid(True, alpha=0.3)
    if len(t) > 1:
        mesh = ax2.pcolormesh(s, t, grid, shading="nearest", cmap="viridis")
        fig.colorbar(mesh, ax=ax2, label="normal force [N]")
    ax2.set(xlabel="distance along the bore [m]", ylabel="t [s]")
    fig.tight_layout()
    return fig


def _labels(runs: list[Run]) -> list[str]:
    """Legend names of the runs: their folder names (with the parent when they coincide)."""
    names = [r.label for r in runs]
    if len(set(names)) < len(names):
        names = [f"{r.directory.parent.name}/{r.label}" for r in runs]
    if len(set(names)) < len(names):
        names = [f"{r.label} #{i + 1}" for i, r in enumerate(runs)]
    return names


def _is_energy(column: str) -> bool:
    return "energy" in column.lower()


def make_figures(run: Run, compare: Run | None = None, *,
                 against: str | None = None) -> dict[str, Any]:
    """matplotlib Figures by file stem (not saved): ``probe_<name>`` for every probe of
    probes.csv (vector probes: their components in one axes) except energies, ``energies``
    (all probe columns whose name contains "energy", in joules; probes.csv does not record
    probe types, hence the name rule), ``contacts`` (normal
    force per hole section summed over its points, and the number of active contact points)
    when either run has contacts, ``contact_along_<joint>`` (the contact force along the bore,
    :func:`_along_bore`) for each clearance joint of the run with more than
    :data:`MANY_SECTIONS` sections. With ``compare`` the second run is overlaid dashed, in the
    same colour per series; legends name the folders. ``against``: a probes.csv column (e.g.
    ``depth_x``) that the probe figures and energies take as abscissa instead of the time
    (an insertion force against the depth; their stems end in ``_vs_<column>``); a column
    missing from a run is a ValueError naming the known ones."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figs: dict[str, Any] = {}
    runs = [run] + ([compare] if compare is not None else [])
    names = _labels(runs)
    x_col = "t" if against is None else against
    for r in runs:
        if against is not None and against not in r.probes:
            known = ", ".join(c for c in r.probes if c != "t") or "none"
            raise ValueError(f"--against {against}: no such column in {r.directory / 'probes.csv'}"
                             f" (known: {known})")
    x_label = "t [s]" if against is None else against
    vs = "" if against is None else f"_vs_{against}"     # its own files beside the time plots
    styles = ["-", "--"]
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    groups = dict(run.probe_groups())
    if compare is not None:
        for name, cols in compare.probe_groups().items():
            groups.setdefault(name, cols)
    for name, cols in groups.items():
        if _is_energy(name):
            continue            # all energies share one figure
        fig, ax = plt.subplots(figsize=(7, 3.5))
        for r, lab_run, ls in zip(runs, names, styles, strict=False):
            for i, c in enumerate(cols):
                if c in r.probes and x_col in r.probes:
                    lab = c if compare is None else f"{c} ({lab_run})"
                    ax.plot(r.probes[x_col], r.probes[c], ls, color=colours[i % len(colours)],
                            label=lab)
        ax.set_xlabel(x_label)
        ax.set_ylabel(name)
        ax.set_title(f"probe {name}")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        figs[f"probe_{name}{vs}"] = fig
    energy_cols = [c for c in groups if _is_energy(c)]
    energy_cols = [c for name in energy_cols for c in groups[name]]
    if energy_cols:
        fig, ax = plt.subplots(figsize=(7, 3.5))
        for r, lab_run, ls in zip(runs, names, styles, strict=False):
            for i, c in enumerate(energy_cols):
                if c in r.probes and x_col in r.probes:
                    lab = c if compare is None else f"{c} ({lab_run})"
                    ax.plot(r.probes[x_col], r.probes[c], ls, color=colours[i % len(colours)],
                            label=lab)
        ax.set(xlabel=x_label, ylabel="energy [J]", title="energies")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        figs[f"energies{vs}"] = fig
    if any(r.contacts for r in runs):
        fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
        keys = sorted({(c["joint"], int(c["section"])) for r in runs for c in r.contacts})
        colour_of = {k: colours[i % len(colours)] for i, k in enumerate(keys)}
        many = len(keys) > MANY_SECTIONS
        for r, lab_run, ls in zip(runs, names, styles, strict=False):
            t, forces, count = _contact_series(r)
            for (joint, sec), f in sorted(forces.items()):
                lab = f"{joint} s{sec}" + ("" if compare is None else f" ({lab_run})")
                ax1.plot(t, f, ls, color=colour_of[(joint, sec)], label=lab)
            if len(t):
                ax2.plot(t, count, ls, drawstyle="steps-post", label=lab_run)
        ax1.set_ylabel("normal force [N]")
        ax1.set_title("contact normal force per hole section (sum over its points)"
                      + (f": {len(keys)} sections" if many else ""))
        if not many:
            ax1.legend(fontsize=7, ncol=3)
        ax1.grid(True, alpha=0.3)
        ax2.set_ylabel("active contact points")
        ax2.set_xlabel("t [s]")
        ax2.yaxis.get_major_locator().set_params(integer=True)
        ax2.legend(fontsize=8)
        ax2.grid(True, alpha=0.3)
        fig.tight_layout()
        figs["contacts"] = fig
    for joint, (length, n) in _bores(run).items():
        figs[f"contact_along_{joint}"] = _along_bore(run, joint, length, n)
    return figs


def plot(out_dir: str | Path, *, compare: str | Path | None = None,
         formats: Sequence[str] = ("png", "svg"), against: str | None = None) -> list[Path]:
    """Write the figures of :func:`make_figures` into ``out_dir/figures``; returns the paths.
    A sweep folder (``sweep.csv``) gets the sweep's figures (:mod:`postprocess.sweep`).
    ``against``: the probes.csv column the probe figures take as abscissa (default the time)."""

    from .sweep import is_sweep, plot_sweep

    for f in formats:
        if f not in ("png", "svg", "pdf"):
            raise ValueError(f"unknown figure format '{f}' (known: png, svg, pdf)")
    if is_sweep(out_dir):
        if compare is not None or against is not None:
            raise ValueError(f"{out_dir} is a sweep folder: --compare and --against apply to "
                             "run folders")
        return plot_sweep(out_dir, formats=formats)
    run = read_run(out_dir)
    other = read_run(compare) if compare is not None else None
    figs = make_figures(run, other, against=against)    # checked before anything is written
    return save_figures(figs, run.directory / "figures", formats)

"""Figures of a sweep folder (``flexmbs plot SWEEPDIR``): reads ``sweep.json``, ``sweep.csv``
and the cases' ``probes.csv``; runs nothing.

- ``sweep_<quantity>``: the quantity (a probe column's extreme, the largest contact force,
  Newton iterations, wall time) against each parameter, one line per combination of the other
  parameters;
- ``overlay_<probe column>``: the probe's time history of every completed case on one axis.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from .data import read_run

__all__ = ["is_sweep", "plot_sweep", "sweep_figures"]


def is_sweep(directory: str | Path) -> bool:
    from flexmbs.sweeps import SWEEP_FILE, TABLE_FILE

    d = Path(directory)
    return (d / TABLE_FILE).is_file() and (d / SWEEP_FILE).is_file()


def _extreme(row: dict[str, Any], column: str) -> float | None:
    lo, hi = row.get(f"{column}_min"), row.get(f"{column}_max")
    if not isinstance(lo, (int, float)) or not isinstance(hi, (int, float)):
        return None
    return hi if abs(hi) >= abs(lo) else lo


def _quantities(rows: Sequence[dict[str, Any]]) -> dict[str, str]:
    """Plotted quantity -> axis label."""
    out: dict[str, str] = {}
    if any(isinstance(r.get("max_contact_force"), (int, float)) for r in rows):
        out["max_contact_force"] = "largest contact force [N]"
    probe_cols = []
    for r in rows:
        for k in r:
            if k.endswith("_max") and k[:-4] not in probe_cols and f"{k[:-4]}_min" in r:
                probe_cols.append(k[:-4])
    for c in probe_cols:
        out[c] = f"{c}: extreme (largest |value|)"
    out["newton_iterations"] = "Newton iterations"
    out["wall_time"] = "wall time [s]"
    return out


def _value(row: dict[str, Any], quantity: str) -> float | None:
    v = row.get(quantity) if quantity in ("max_contact_force", "newton_iterations",
                                          "wall_time") else _extreme(row, quantity)
    return float(v) if isinstance(v, (int, float)) and math.isfinite(v) else None


def _axis_value(v: Any) -> float | str:
    return float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else str(v)


def sweep_figures(directory: str | Path) -> dict[str, Any]:
    """The figures of a sweep folder (module docstring), by file stem."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from flexmbs.sweeps import SWEEP_FILE, read_table

    d = Path(directory)
    meta = json.loads((d / SWEEP_FILE).read_text(encoding="utf-8"))
    params: list[str] = list(meta.get("parameters") or [])
    zipped = set(meta.get("zip") or {})
    rows = [r for r in read_table(d) if r.get("status") == "completed"]
    if not rows:
        raise FileNotFoundError(f"{d}: no completed case in the sweep table; nothing to plot")
    figs: dict[str, Any] = {}
    for quantity, label in _quantities(rows).items():
        fig, axes = plt.subplots(1, len(params), figsize=(4.2 * len(params), 3.6), squeeze=False)
        for ax, p in zip(axes[0], params, strict=True):
            # zipped keys vary together: the lines are the combinations of the other keys
            others = [o for o in params if o != p and not (p in zipped and o in zipped)]
            groups: dict[tuple, list[tuple[Any, float]]] = {}
            for r in rows:
                y = _value(r, quantity)
                if y is not None:
                    groups.setdefault(tuple(r.get(o) for o in others), []).append(
                        (_axis_value(r.get(p)), y))
            numeric = all(isinstance(x, float) for pts in groups.values() for x, _ in pts)
            for key, pts in groups.items():
                if numeric:
                    pts.sort()
                xs = [x for x, _ in pts]
                lab = ", ".join(f"{o.split('.')[-1]}={v}" for o, v in zip(others, key, strict=True))
                ax.plot(xs if numeric else [str(x) for x in xs], [y for _, y in pts], "o-",
                        label=lab or None)
            xs_all = [x for pts in groups.values() for x, _ in pts]
            if numeric and xs_all and min(xs_all) > 0 and max(xs_all) / min(xs_all) > 20:
                ax.set_xscale("log")
            ax.set_xlabel(p)
            ax.set_ylabel(label)
            ax.grid(True, alpha=0.3)
            if others and 1 < len(groups) <= 8:
                ax.legend(fontsize=6)
        fig.suptitle(f"{meta.get('scenario')}: {label}", fontsize=10)
        fig.tight_layout()
        figs[f"sweep_{quantity}"] = fig
    columns: list[str] = []
    runs = []
    for r in rows:
        try:
            run = read_run(r["folder"])
        except FileNotFoundError:
            continue
        runs.append((str(r["case"]), run))
        columns += [c for c in run.probes if c != "t" and c not in columns]
    for col in columns:
        fig, ax = plt.subplots(figsize=(7.5, 4.0))
        for case, run in runs:
            if col in run.probes:
                ax.plot(run.probes["t"], run.probes[col], lw=1.0, label=case)
        ax.set_xlabel("t [s]")
        ax.set_ylabel(col)
        ax.grid(True, alpha=0.3)
        if len(runs) <= 12:
            ax.legend(fontsize=6)
        ax.set_title(f"{meta.get('scenario')}: {col} of every case", fontsize=10)
        fig.tight_layout()
        figs[f"overlay_{col}"] = fig
    return figs


def plot_sweep(directory: str | Path, *, formats: Sequence[str] = ("png", "svg")) -> list[Path]:
    """Write :func:`sweep_figures` into ``directory/figures``; returns the paths."""
    from .figures import save_figures

    return save_figures(sweep_figures(directory), Path(directory) / "figures", formats)

"""Figures of a tendon-driven continuum robot (``examples/tendon_robot.py``), from its output
folders: the shape of the backbone through its disk centres, and the tension along each
tendon's route. Reads ``probes.csv`` only (probes ``disk<k>`` body positions, ``N_<tendon>``
tendon tensions)."""

from __future__ import annotations

import re
from typing import Any

import numpy as np

from .data import Run

__all__ = ["robot_loop", "robot_shapes", "robot_tensions"]


def _disks(run: Run, frame: int = -1) -> np.ndarray:
    """The disk centres (k, 3) at ``frame``, the base (the origin) first."""
    ks = sorted(int(m.group(1)) for c in run.probes
                if (m := re.fullmatch(r"disk(\d+)_x", c)))
    if not ks:
        raise ValueError(f"{run.directory}: probes.csv has no disk<k>_x columns (body_position "
                         "probes of the disks)")
    pts = [[run.probes[f"disk{k}_{a}"][frame] for a in "xyz"] for k in ks]
    return np.vstack([np.zeros((1, 3)), np.array(pts)])


def _tendons(run: Run) -> dict[str, list[str]]:
    """Tendon name -> its span tension columns ``N_<name>_0 ... N_<name>_<n>`` in route order."""
    out: dict[str, list[tuple[int, str]]] = {}
    for c in run.probes:
        m = re.fullmatch(r"N_(.+)_(\d+)", c)
        if m:
            out.setdefault(m.group(1), []).append((int(m.group(2)), c))
    return {k: [c for _, c in sorted(v)] for k, v in sorted(out.items())}


def robot_shapes(runs: dict[str, Run]) -> Any:
    """One figure: the disk centres of every run's last frame in the x-z and y-z planes and
    from above (x-y), one line per run labelled by its key [mm]."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(12, 4.5))
    for label, run in runs.items():
        p = 1e3 * _disks(run)
        for ax, (i, j) in zip(axes, ((0, 2), (1, 2), (0, 1)), strict=True):
            ax.plot(p[:, i], p[:, j], "o-", ms=3, label=label)
    for ax, (xl, yl) in zip(axes, (("x", "z"), ("y", "z"), ("x", "y")), strict=True):
        ax.set_xlabel(f"{xl} [mm]")
        ax.set_ylabel(f"{yl} [mm]")
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle("backbone through the disk centres (base at the origin)")
    fig.tight_layout()
    return fig


def robot_tensions(runs: dict[str, Run]) -> Any:
    """One panel per run: every loaded tendon's tension in its spans (0: the actuator's, then
    after each hole) at the last frame [N]."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(runs), figsize=(4 * len(runs), 3.6), squeeze=False)
    for ax, (label, run) in zip(axes[0], runs.items(), strict=True):
        for name, cols in _tendons(run).items():
            n = np.array([run.probes[c][-1] for c in cols])
            if np.abs(n).max() > 1e-3:
                ax.plot(np.arange(n.size), n, "o-", ms=3, label=name)
        ax.set_title(label)
        ax.set_xlabel("span (0: actuator, k: after hole k)")
        ax.set_ylabel("tension [N]")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def robot_loop(runs: dict[str, Run], tendon: str = "t4") -> Any:
    """One figure: the last disk's displacement [mm] against ``tendon``'s tension at its
    actuator (span 0) [N] over every run (a pull-release loop; one line per run)."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5.5, 4.2))
    for label, run in runs.items():
        column = f"N_{tendon}_0"
        if column not in run.probes:
            raise ValueError(f"{run.directory}: probes.csv has no {column} column (the "
                             f"tendon_tension probe of {tendon})")
        p = np.array([_disks(run, k)[-1] for k in range(run.probes["t"].size)])
        ax.plot(run.probes[column], 1e3 * np.linalg.norm(p - p[0], axis=1), "-", label=label)
    ax.set_xlabel(f"tension of {tendon} at its actuator [N]")
    ax.set_ylabel("displacement of the last disk [mm]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig

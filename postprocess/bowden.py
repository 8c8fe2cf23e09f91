"""Figures of the Bowden cable turning a lever (``examples/bowden_lever.toml``), from its
output folders: the lever's angle against the pull (the capstan loss e^{∓μΘ}: a friction
loop) and against the input's travel (the take-up of the clearance). Reads ``probes.csv``
only: ``pull_fx`` (the pull's reaction on the wire), ``lever_w``, ``lever_z`` (the lever's
Euler parameters), ``input_x`` (the pulled end's travel)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .data import Run

__all__ = ["lever_angle", "lever_figure"]


def lever_angle(run: Run) -> np.ndarray:
    """The lever's turn about z [rad]: 2 atan2(z, w) of probe ``lever``."""
    p = run.probes
    if "lever_w" not in p or "lever_z" not in p:
        raise ValueError(f"{run.directory}: probes.csv has no lever_w, lever_z columns (a "
                         "body_orientation probe 'lever')")
    return 2.0 * np.arctan2(p["lever_z"], p["lever_w"])


def lever_figure(runs: dict[str, Run], *, stiffness: float, arm: float, wrap: float,
                 mu: dict[str, float], take_up: float | None = None) -> Any:
    """One figure, two panels, one line per run labelled by its key (the first output, t = 0,
    left out): the lever's angle [deg] against the pull [N], with the capstan statics
    k φ = a cos φ F e^{∓μΘ} of each run's ``mu`` (pulling, letting back: the friction loop);
    and against the input's travel [mm] (the take-up of the clearance before the lever
    moves; ``take_up`` [m], e.g. cΘ, marked)."""
    import matplotlib.pyplot as plt

    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.5))
    top = 0.0
    for label, run in runs.items():
        phi = np.degrees(lever_angle(run))[1:]
        ax.plot(run.probes["pull_fx"][1:], phi, label=label)
        bx.plot(1e3 * run.probes["input_x"][1:], phi, label=label)
        top = max(top, float(run.probes["pull_fx"][1:].max()))
    f = np.linspace(0.0, top, 50)
    for m in sorted(set(mu.values())):
        for sign in ((-1, 1) if m > 0 else (0,)):
            # k φ = a cos φ F e^{sign μΘ}: φ by a few fixed-point sweeps (φ is small)
            load = arm * f * math.exp(sign * m * wrap) / stiffness
            phi = load.copy()
            for _ in range(5):
                phi = load * np.cos(phi)
            ax.plot(f, np.degrees(phi), "k:", lw=0.8)
            ax.annotate("no friction" if m == 0 else
                        f"e^({'−' if sign < 0 else '+'}{m:g}Θ): {'pulling' if sign < 0 else 'letting back'}",
                        (f[-1], np.degrees(phi[-1])), fontsize=8, ha="right", va="bottom")
    if take_up is not None:
        bx.axvline(1e3 * take_up, color="k", ls=":", lw=0.8)
        bx.annotate(f" cΘ = {1e3 * take_up:.2f} mm", (1e3 * take_up, 0.5), fontsize=8)
    ax.set_xlabel("pull on the wire's near end [N]")
    bx.set_xlabel("input: the wire's near end pulled out [mm]")
    for a in (ax, bx):
        a.set_ylabel("lever angle [deg]")
        a.grid(True, alpha=0.3)
        a.legend(loc="upper left")
    fig.suptitle("Bowden cable turning a lever: pulled out and let back")
    fig.tight_layout()
    return fig

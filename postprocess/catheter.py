"""Figure of a catheter advanced over a guide wire in a vessel (``examples/catheter.toml``),
from its output folder: the three levels at the end of each push, and the insertion forces.

Reads ``sections.csv`` (the vessel's sections each beam crosses: their origins draw the
vessel's centre-line, their crossings ``o + c_y e_y + c_z e_z`` each beam's centre-line at
the section stations; joints ``<beam>_in_vessel``) and ``probes.csv`` (``<beam>_feeder_fx``:
the feeders' forces on the beams)."""

from __future__ import annotations

from typing import Any

import numpy as np

from .data import Run

__all__ = ["catheter_figure", "crossings"]


def crossings(run: Run, joint: str, t: float) -> tuple[np.ndarray, np.ndarray]:
    """The sections of ``joint`` crossed at the output nearest ``t``, in station order: their
    origins (k, 3) and the beam's centre points there (k, 3) [m]."""
    rows = [r for r in run.sections if r["joint"] == joint]
    if not rows:
        raise ValueError(f"{run.directory}: sections.csv has no rows of joint {joint!r}")
    times = np.unique([float(r["t"]) for r in rows])
    near = times[np.argmin(abs(times - t))]
    at = sorted((r for r in rows if float(r["t"]) == near), key=lambda r: int(r["section"]))
    o = np.array([[float(r[f"o{a}"]) for a in "xyz"] for r in at])
    ey = np.array([[float(r[f"ey{a}"]) for a in "xyz"] for r in at])
    ez = np.array([[float(r[f"ez{a}"]) for a in "xyz"] for r in at])
    cy = np.array([float(r["cy"]) for r in at])[:, None]
    cz = np.array([float(r["cz"]) for r in at])[:, None]
    return o, o + cy * ey + cz * ez


def catheter_figure(run: Run, *, times: tuple[float, ...] = (0.4, 0.8, 1.2, 1.6),
                    pushes: dict[str, tuple[tuple[float, float, float], ...]] | None = None) -> Any:
    """One figure, two panels: the vessel's centre-line and, at each of ``times``, the
    catheter's and the wire's centre-lines where they cross the vessel's sections (from
    above, x–y [mm]); and the feeders' forces against time [N], each feeder's pushes
    (``pushes``: beam -> (start, end, distance) [s, s, m]) shaded."""
    import matplotlib.pyplot as plt

    fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 4.8))
    vessel = {}
    for r in run.sections:
        if r["joint"].endswith("_in_vessel"):
            vessel[int(r["section"])] = [float(r[f"o{a}"]) for a in "xyz"]
    path = 1e3 * np.array([vessel[k] for k in sorted(vessel)])
    ax.plot(path[:, 0], path[:, 1], color="0.6", lw=6, alpha=0.35, solid_capstyle="round",
            label="vessel (the sections crossed)")
    shades = np.linspace(0.35, 1.0, len(times))
    for t, alpha in zip(times, shades, strict=True):
        for beam, color in (("catheter", "tab:orange"), ("wire", "tab:blue")):
            _, centre = crossings(run, f"{beam}_in_vessel", t)
            p = 1e3 * centre
            ax.plot(p[:, 0], p[:, 1], color=color, alpha=alpha, lw=2.5 if beam == "catheter"
                    else 1.2, label=f"{beam}, t = {t:g} s")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    ax.set_title("the vessel, the catheter and the wire at the end of each push")
    time = run.probes["t"]
    for beam, color in (("wire", "tab:blue"), ("catheter", "tab:orange")):
        col = f"{beam}_feeder_fx"
        if col not in run.probes:
            raise ValueError(f"{run.directory}: probes.csv has no {col} column (a reaction "
                             f"probe '{beam}_feeder')")
        bx.plot(time, run.probes[col], color=color, label=f"{beam}'s feeder")
        for start, end, _ in (pushes or {}).get(beam, ()):
            bx.axvspan(start, end, color=color, alpha=0.08)
    bx.axhline(0.0, color="0.5", lw=0.8)
    bx.set_xlabel("t [s]")
    bx.set_ylabel("insertion force [N]")
    bx.grid(True, alpha=0.3)
    bx.legend(fontsize=8)
    bx.set_title("the feeders' forces (shaded: each one's pushes)")
    fig.tight_layout()
    return fig

"""The hole-section view of the paper's Fig. 2(b): in the plane of one hole section, the bore,
the beam's elliptical section, the contact points Q and their projections P, with the offsets
exaggerated so that a sub-millimetre clearance is visible (FORMULATION Part II §2-§4)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .data import read_run


def section_view(out_dir: str | Path, *, joint: str | None = None, section: int | None = None,
                 time: float | None = None, exaggeration: float | None = None,
                 path: str | Path | None = None):  # noqa: ANN201 - returns (Path, Figure)
    """Draw one section at the output time nearest to ``time`` (default: last); returns
    ``(path, figure)``. Needs ``sections.csv`` (written for clearance joints).

    Geometry in section coordinates (y, z) with the hole centre at the origin: bore circle of
    radius R, beam ellipse with centre (cy, cz), major axis (ey_a, ez_a), semi-axes a, b. The
    exaggeration factor f scales the ellipse centre offset and the gaps: the drawn centre is
    f (cy, cz) and the drawn bore radius r_b + f (R - r_b), so the clearance appears f times
    larger while the beam keeps its true size.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    run = read_run(out_dir)
    if not run.sections:
        raise FileNotFoundError(f"{out_dir}: no sections.csv (only clearance joints write it)")
    rows = run.sections
    joints = sorted({r["joint"] for r in rows})
    joint = joint or joints[0]
    if joint not in joints:
        raise ValueError(f"no clearance joint '{joint}' in {out_dir} (joints: {', '.join(joints)})")
    rows = [r for r in rows if r["joint"] == joint]
    times = np.array(sorted({float(r["t"]) for r in rows}))
    t = times[-1] if time is None else times[np.argmin(np.abs(times - time))]
    rows = [r for r in rows if float(r["t"]) == t]
    secs = sorted(int(r["section"]) for r in rows)
    section = secs[len(secs) // 2] if section is None else section
    match = [r for r in rows if int(r["section"]) == section]
    if not match:
        raise ValueError(f"section {section} of joint '{joint}' not found at t = {t} "
                         f"(sections: {secs})")
    s = {k: (float(v) if k not in ("joint",) else v) for k, v in match[0].items()}
    R, a, b = s["R"], s["a"], s["b"]
    c = np.array([s["cy"], s["cz"]])
    ea = np.array([s["ey_a"], s["ez_a"]])
    ea = ea / np.linalg.norm(ea) if np.linalg.norm(ea) > 0 else np.array([1.0, 0.0])
    eb = np.array([-ea[1], ea[0]])
    clearance = R - b
    f = exaggeration or max(1.0, 0.5 * R / max(clearance, 1e-12))
    origin = np.array([s["ox"], s["oy"], s["oz"]])
    ey = np.array([s["eyx"], s["eyy"], s["eyz"]])
    ez = np.array([s["ezx"], s["ezy"], s["ezz"]])

    def to2d(x: np.ndarray) -> np.ndarray:
        return np.array([(x - origin) @ ey, (x - origin) @ ez])

    phi = np.linspace(0, 2 * np.pi, 361)
    fig, ax = plt.subplots(figsize=(5.5, 5.5))
    Rd = b + f * clearance
    ax.plot(Rd * np.cos(phi), Rd * np.sin(phi), "k-", lw=1.5, label=f"bore R = {1e3 * R:.3g} mm")
    cd = f * c
    ell = cd[:, None] + a * np.cos(phi) * ea[:, None] + b * np.sin(phi) * eb[:, None]
    ax.plot(ell[0], ell[1], "b-", lw=1.2,
            label=f"beam section a = {1e3 * a:.4g} mm, b = {1e3 * b:.4g} mm")
    ax.plot(*cd, "b+", ms=10, label="ellipse centre r_I")
    pts = [r for r in run.contacts if r["joint"] == joint and float(r["t"]) == t
           and int(r["section"]) == section]
    for i, r in enumerate(pts):
        Q = to2d(np.array([float(r["qx"]), float(r["qy"]), float(r["qz"])]))
        P = to2d(np.array([float(r["px"]), float(r["py"]), float(r["pz"])]))
        u = Q / np.linalg.norm(Q)
        Qd = Rd * u                                   # Q on the drawn bore
        Pd = f * P
        ax.plot(*Qd, "ro", label="Q (hole point)" if i == 0 else None)
        ax.plot(*Pd, "gs", ms=4, label="P (projection on the axis)" if i == 0 else None)
        ax.plot([Pd[0], Qd[0]], [Pd[1], Qd[1]], "r:", lw=0.8)
        ax.annotate(f"g = {1e6 * float(r['gap']):.3g} µm\nF = {float(r['normal_force']):.3g} N",
                    Qd, textcoords="offset points", xytext=(8, 8), fontsize=8)
    ax.set_aspect("equal")
    ax.set_xlabel("y (section) [m]")
    ax.set_ylabel("z (section) [m]")
    ax.set_title(f"{joint}, section {section}, t = {t:.4g} s\n"
                 f"offsets and clearance exaggerated x{f:.3g}", fontsize=10)
    ax.legend(fontsize=7, loc="lower right")
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    out = Path(path) if path else run.directory / "figures" / f"section_{joint}_{section}.png"
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=130)
    return out, fig

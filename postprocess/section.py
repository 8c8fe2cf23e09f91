"""The hole-section view of the paper's Fig. 2(b): in the plane of one hole section, the bore
circle, the beam's elliptical section, the hole points Q and their projections P on the beam
axis, with the offsets exaggerated so that a sub-millimetre clearance is visible
(docs/theory.md §II.2-§II.4).

What the view needs and where it comes from:

- ``contacts.csv`` (docs/design.md) gives, per active contact point: ``gap``, ``normal_force``, the hole
  point Q (``qx, qy, qz``), its closest point P on the beam axis (``px, py, pz``) and the ellipse
  semi-axes ``a, b``. From these alone one can derive |Q - P| = b + gap (a consistency check,
  done here) and the beam's tilt to the hole axis, cos(theta) = b / a (§2), but **not** the
  picture: the section plane (origin O_k and axes e_y, e_z), the ellipse centre r_I and its
  major-axis direction e_a are missing, and so is the bore radius R.
- ``sections.csv`` (written by flexmbs.io for clearance joints, every section at every output)
  supplies exactly those: ``ox, oy, oz`` (O_k), ``eyx..ezz`` (e_y, e_z), ``cy, cz`` (r_I in
  section coordinates), ``ey_a, ez_a`` (e_a in section coordinates), ``a, b``, ``R``.
  Without it the view is refused with the list of these columns. ``radius=`` overrides R.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .data import read_run

#: the columns of sections.csv the view needs beyond contacts.csv
SECTION_VIEW_COLUMNS = ("t", "joint", "section", "ox", "oy", "oz", "eyx", "eyy", "eyz", "ezx",
                        "ezy", "ezz", "cy", "cz", "ey_a", "ez_a", "a", "b", "R")


@dataclass
class SectionState:
    """One hole section at one output time, in section coordinates (y, z) about the hole centre."""

    joint: str
    section: int
    t: float
    R: float                      #: bore radius
    a: float                      #: ellipse semi-axes (from contacts.csv when the section is in
    b: float                      #: contact, else sections.csv)
    centre: np.ndarray            #: ellipse centre r_I (2,)
    e_a: np.ndarray               #: unit major axis (2,)
    Q: list[np.ndarray] = field(default_factory=list)      #: hole points (2,)
    P: list[np.ndarray] = field(default_factory=list)      #: projections on the axis (2,)
    gaps: list[float] = field(default_factory=list)
    forces: list[float] = field(default_factory=list)
    distances: list[float] = field(default_factory=list)   #: |Q - P| in 3D
    ab_source: str = "sections.csv"
    hole: dict | None = None      #: the joint's non-circular section (summary.json), else a circle

    def wall(self, psi: np.ndarray) -> np.ndarray:
        """Wall points (len(psi), 2) of the bore: the registered section's own boundary (any
        shape) or the circle of radius R."""
        if self.hole is None:
            return self.R * np.stack([np.cos(psi), np.sin(psi)], axis=-1)
        from flexmbs.contact.bores import BORE_KEYS
        from flexmbs.contact.sections import get_section

        params = {k: v for k, v in self.hole.items() if k not in ("shape", *BORE_KEYS)}
        return get_section(self.hole["shape"], **params).boundary(psi)[0]

    @property
    def clearance(self) -> float:
        return self.R - self.b

    @property
    def tilt(self) -> float:
        """Angle between the beam tangent and the hole axis, arccos(b / a) (§2)."""
        return float(np.arccos(np.clip(self.b / self.a, -1.0, 1.0)))


def section_state(out_dir: str | Path, *, joint: str | None = None, section: int | None = None,
                  time: float | None = None, radius: float | None = None) -> SectionState:
    """Read one section at the output time nearest to ``time`` (default: the last output);
    ``joint`` defaults to the first clearance joint, ``section`` to its middle section."""
    run = read_run(out_dir)
    if not run.sections:
        raise FileNotFoundError(
            f"{out_dir}: no sections.csv; the section view needs the section frame and ellipse "
            f"({', '.join(SECTION_VIEW_COLUMNS)}), which contacts.csv does not have (it is "
            "written for clearance joints only)")
    missing = [c for c in SECTION_VIEW_COLUMNS if c not in run.sections[0]]
    if missing:
        raise ValueError(f"{out_dir}/sections.csv lacks the columns {', '.join(missing)}")
    joints = sorted({r["joint"] for r in run.sections})
    joint = joint or joints[0]
    if joint not in joints:
        raise ValueError(f"no clearance joint '{joint}' in {out_dir} (joints: {', '.join(joints)})")
    rows = [r for r in run.sections if r["joint"] == joint]
    times = np.array(sorted({float(r["t"]) for r in rows}))
    t = float(times[-1] if time is None else times[np.argmin(np.abs(times - time))])
    rows = [r for r in rows if float(r["t"]) == t]
    secs = sorted(int(r["section"]) for r in rows)
    section = secs[len(secs) // 2] if section is None else int(section)
    match = [r for r in rows if int(r["section"]) == section]
    if not match:
        raise ValueError(f"section {section} of joint '{joint}' not found at t = {t:g} "
                         f"(sections: {secs})")
    s = {k: float(v) for k, v in match[0].items() if k != "joint" and v != ""}
    origin = np.array([s["ox"], s["oy"], s["oz"]])
    ey = np.array([s["eyx"], s["eyy"], s["eyz"]])
    ez = np.array([s["ezx"], s["ezy"], s["ezz"]])
    ea = np.array([s["ey_a"], s["ez_a"]])
    ea = ea / np.linalg.norm(ea) if np.linalg.norm(ea) > 0 else np.array([1.0, 0.0])
    R = float(radius) if radius is not None else s["R"]
    if not R > 0:
        raise ValueError(f"bore radius must be > 0 (got {R})")
    st = SectionState(joint, section, t, R, s["a"], s["b"], np.array([s["cy"], s["cz"]]), ea)
    hole = (run.summary.get("hole_sections") or {}).get(joint)
    if hole and hole.get("shape") != "circle" and radius is None:
        st.hole = hole
    pts = [r for r in run.contacts if r["joint"] == joint and float(r["t"]) == t
           and int(r["section"]) == section]

    def to2d(x: np.ndarray) -> np.ndarray:
        return np.array([(x - origin) @ ey, (x - origin) @ ez])

    for r in pts:
        Q = np.array([float(r["qx"]), float(r["qy"]), float(r["qz"])])
        P = np.array([float(r["px"]), float(r["py"]), float(r["pz"])])
        st.Q.append(to2d(Q))
        st.P.append(to2d(P))
        st.gaps.append(float(r["gap"]))
        st.forces.append(float(r["normal_force"] or 0.0))
        st.distances.append(float(np.linalg.norm(Q - P)))
        if r.get("a") and r.get("b"):
            st.a, st.b, st.ab_source = float(r["a"]), float(r["b"]), "contacts.csv"
    return st


def default_exaggeration(st: SectionState) -> float:
    """Drawn clearance = half the bore radius (never < 1)."""
    return max(1.0, 0.5 * st.R / max(st.clearance, 1e-12 * st.R))


def section_figure(out_dir: str | Path, *, joint: str | None = None, section: int | None = None,
                   time: float | None = None, exaggeration: float | None = None,
                   radius: float | None = None) -> tuple[Any, SectionState]:
    """The matplotlib Figure of :func:`section_view` (not saved) and the data drawn.

    Drawn in millimetres. The exaggeration factor f scales the offsets relative to the hole
    centre: the ellipse is drawn at f r_I with its true semi-axes, the bore with radius
    b + f (R - b), Q on the drawn bore in its true direction and P at f P; so the clearance and
    the gaps appear f times larger while the beam keeps its size.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    st = section_state(out_dir, joint=joint, section=section, time=time, radius=radius)
    f = float(exaggeration) if exaggeration is not None else default_exaggeration(st)
    if not f > 0:
        raise ValueError(f"exaggeration must be > 0 (got {exaggeration})")
    a, b, R = st.a, st.b, st.R
    mm = 1e3                      # drawn in millimetres
    eb = np.array([-st.e_a[1], st.e_a[0]])
    phi = np.linspace(0.0, 2.0 * np.pi, 721)
    fig, ax = plt.subplots(figsize=(8.6, 5.6))
    Rd = b + f * (R - b)

    def drawn(x: np.ndarray) -> np.ndarray:
        """A wall point drawn at b + f(|x| − b) in its true direction (clearance ×f)."""
        r = np.linalg.norm(x, axis=-1, keepdims=True)
        return x / np.where(r > 0, r, 1.0) * (b + f * (r - b))

    wall = drawn(st.wall(phi))
    if st.hole is None:
        bore = f"bore, R = {1e3 * R:.4g} mm (drawn {1e3 * Rd:.3g} mm)"
    else:
        from flexmbs.contact.bores import BORE_KEYS

        shown = ", ".join(f"{k} = {v:.4g}" for k, v in st.hole.items()
                          if k not in ("shape", "samples", *BORE_KEYS))
        bore = f"bore: {st.hole['shape']} ({shown})"
    ax.plot(mm * wall[:, 0], mm * wall[:, 1], "k-", lw=1.5, label=bore)
    ax.plot([0.0], [0.0], "k+", ms=10, label="hole centre O")
    cd = f * st.centre
    ell = cd[:, None] + a * np.cos(phi) * st.e_a[:, None] + b * np.sin(phi) * eb[:, None]
    ax.plot(mm * ell[0], mm * ell[1], "b-", lw=1.2,
            label=f"beam section: a = {1e3 * a:.5g} mm, b = {1e3 * b:.5g} mm ({st.ab_source})")
    ax.plot([mm * cd[0]], [mm * cd[1]], "bx", ms=8, label="ellipse centre r_I")
    axis = np.array([cd - a * st.e_a, cd + a * st.e_a]).T
    ax.plot(mm * axis[0], mm * axis[1], "b--", lw=0.7,
            label=f"major axis e_a (tilt {np.degrees(st.tilt):.3g}°)")
    for i, (Q, P, g, F, ell3) in enumerate(zip(st.Q, st.P, st.gaps, st.forces, st.distances,
                                               strict=True)):
        u = Q / (np.linalg.norm(Q) or 1.0)
        Qd, Pd = mm * drawn(Q), mm * f * P
        ax.plot(*Qd, "ro", ms=6, label="Q (hole point)" if i == 0 else None)
        ax.plot(*Pd, "gs", ms=5, label="P (closest point on the beam axis)" if i == 0 else None)
        ax.plot([Pd[0], Qd[0]], [Pd[1], Qd[1]], "r:", lw=0.9)
        ax.annotate(f"g = {1e6 * g:.4g} µm\nF = {F:.3g} N\n|QP| = {1e3 * ell3:.5g} mm",
                    (float(Qd[0]), float(Qd[1])), textcoords="offset points",
                    xytext=(10, -40 if u[1] > 0 else 8), fontsize=8, color="darkred",
                    bbox={"boxstyle": "round", "fc": "white", "alpha": 0.8, "lw": 0})
    if not st.Q:
        ax.text(0.02, 0.98, "no contact in this section", transform=ax.transAxes, va="top",
                fontsize=9)
    lim = 1.2 * mm * max(float(np.abs(wall).max()), float(np.abs(ell).max()))
    ax.set_xlim(-lim, lim)
    ax.set_ylim(-lim, lim)
    ax.set_aspect("equal")
    ax.set_xlabel("y (section axis e_y) [mm]")
    ax.set_ylabel("z (section axis e_z) [mm]")
    ax.set_title(f"joint '{st.joint}', section {st.section}, t = {st.t:.4g} s\n"
                 f"offsets and clearance exaggerated ×{f:.3g} "
                 f"(clearance c = {1e3 * st.clearance:.3g} mm)", fontsize=10)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    return fig, st


def section_view(out_dir: str | Path, *, joint: str | None = None, section: int | None = None,
                 time: float | None = None, exaggeration: float | None = None,
                 radius: float | None = None, path: str | Path | None = None) -> Path:
    """Draw one hole section (the paper's Fig. 2(b)) at the output time nearest to ``time``
    (default: the last output) and save it to ``path`` (default
    ``out_dir/figures/section_<joint>_<section>.png``; the suffix selects the format). Returns
    the path. ``radius`` overrides the bore radius of sections.csv; ``exaggeration`` defaults
    to drawing the clearance as half the bore radius. See :func:`section_figure`."""
    import matplotlib.pyplot as plt

    fig, st = section_figure(out_dir, joint=joint, section=section, time=time,
                             exaggeration=exaggeration, radius=radius)
    out = (Path(path) if path is not None
           else Path(out_dir) / "figures" / f"section_{st.joint}_{st.section}.png")
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=130, bbox_inches="tight")
    plt.close(fig)
    return out


def contact_angles(out_dir: str | Path, joint: str | None = None
                   ) -> tuple[str, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Where the contacts of a clearance joint sit over time: ``(joint, t, section, angle,
    normal_force)`` per contacts.csv row, the angle of the hole point Q about the hole axis in
    the section's own axes (atan2(z, y), degrees), from contacts.csv and the section frames of
    sections.csv at the same output time."""
    run = read_run(out_dir)
    if not run.sections:
        raise FileNotFoundError(f"{out_dir}: no sections.csv (only clearance joints write it)")
    joints = sorted({r["joint"] for r in run.sections})
    joint = joint or joints[0]
    frames = {(float(r["t"]), int(r["section"])): r for r in run.sections if r["joint"] == joint}
    t, sec, ang, force = [], [], [], []
    for r in run.contacts:
        if r["joint"] != joint:
            continue
        key = (float(r["t"]), int(r["section"]))
        fr = frames.get(key)
        if fr is None:
            continue
        d = np.array([float(r["qx"]) - float(fr["ox"]), float(r["qy"]) - float(fr["oy"]),
                      float(r["qz"]) - float(fr["oz"])])
        y = d @ np.array([float(fr["eyx"]), float(fr["eyy"]), float(fr["eyz"])])
        z = d @ np.array([float(fr["ezx"]), float(fr["ezy"]), float(fr["ezz"])])
        t.append(key[0])
        sec.append(key[1])
        ang.append(np.degrees(np.arctan2(z, y)))
        force.append(float(r["normal_force"] or 0.0))
    return joint, np.array(t), np.array(sec, int), np.array(ang), np.array(force)


def contact_angles_view(out_dir: str | Path, joint: str | None = None,
                        path: str | Path | None = None) -> Path:
    """Figure of :func:`contact_angles`: the angle of every contact point about the hole axis
    over time, coloured by hole section, marker area by normal force; saved to ``path``
    (default ``out_dir/figures/contact_angles_<joint>.png``)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    joint, t, sec, ang, force = contact_angles(out_dir, joint)
    fig, ax = plt.subplots(figsize=(8.6, 4.4))
    if t.size:
        size = 6.0 + 40.0 * np.abs(force) / max(float(np.abs(force).max()), 1e-300)
        pts = ax.scatter(t, ang, c=sec, s=size, cmap="viridis", alpha=0.8)
        fig.colorbar(pts, ax=ax, label="hole section")
    else:
        ax.text(0.02, 0.95, "no contact", transform=ax.transAxes, va="top")
    ax.set_ylim(-180.0, 180.0)
    ax.set_yticks(np.arange(-180, 181, 45))
    ax.set_xlabel("t [s]")
    ax.set_ylabel("contact angle atan2(z, y) in the section [deg]")
    ax.set_title(f"joint '{joint}': where the contact points sit (marker area ~ normal force)",
                 fontsize=10)
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    out = Path(path) if path is not None else Path(out_dir) / "figures" / f"contact_angles_{joint}.png"
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=130, bbox_inches="tight")
    plt.close(fig)
    return out

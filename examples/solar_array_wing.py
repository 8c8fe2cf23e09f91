"""Example 2 through the Python API: the same model as examples/solar_array_wing.toml.

A partially deployed solar-array blanket in zero gravity, built after the paper's Example 2 (its
parameters are unknown): three rigid panels stand in a zig-zag at BETA = 35 deg to the guide
wire, hinged to the blanket box at x = 0, to each other at the fold lines and held at the top
edge by the mast tip (X and Z only). Torsion springs at the hinges stand for the folds'
stiffness. Each panel carries a thin eyelet (a 0.2 mm sheet, bore R = 2 mm) at the middle of its
side edge, its axis normal to the panel; the pretensioned guide wire (d = 1.6 mm, 20 N) runs
along X through the three eyelets, crossing each at 90 - BETA = 55 deg to its axis: the section
ellipse has a = 1.39 mm, a^2/b = 2.43 mm > R, the two-point regime (docs/theory.md §II.3). The wire's
anchors are moved 15 mm sideways in the initial static solve (routing misalignment), which
presses it on the eyelet walls along the ellipse's minor axis; the middle eyelet sits 0.5 mm
further out. A half-sine force on panel 2 then starts a free vibration. ``--ideal`` replaces the
clearance joints by rings without clearance (sliding joints, variant "ring").

    python examples/solar_array_wing.py [--t-end 20] [--dt 1e-3] [--step-tolerance 1e-5] [--ideal]
        [--clearance 1.2e-3] [--sections 3] [--stiffness 4e4] [--excitation 2.0] [--out DIR]
"""

from __future__ import annotations

import argparse
import math

import numpy as np

import flexmbs as fm
from flexmbs.io.probes import (
    BeamPointProbe,
    BodyPointProbe,
    ContactForceProbe,
    EnergyProbe,
    SlideCoordinateProbe,
)

H, W = 0.5, 1.0                   # panel height (fold line to fold line) and width (Y) [m]
BETA = math.radians(35.0)         # panel inclination to the guide wire (zig-zag)
N_PANELS = 3
E_TAB = 0.02                      # eyelet centres 20 mm beside the panels' side edge (y = -E_TAB)
DY = 15e-3                        # anchor misalignment (Y), applied in the initial static solve
SHIFT_MIDDLE = 0.5e-3             # the middle panel's eyelet sits this much further out (-Y)
EYELET_LENGTH = 0.2e-3            # eyelet sheet thickness [m]
WIRE_R, T_WIRE = 0.8e-3, 20.0     # wire radius [m], pretension before the misalignment [N]
WIRE_E, WIRE_RHO = 1e11, 7900.0
K_HINGE, C_HINGE = 50.0, 0.05     # hinge torsion springs [N m/rad], dampers [N m s/rad]
STATIC = fm.StaticOptions(load_steps=10, stabilizer=100.0)


def fold_points() -> list[np.ndarray]:
    """Fold lines (at y = 0) of the zig-zag: alternately at z = 0 and z = H sin(BETA)."""
    cb, sb = math.cos(BETA), math.sin(BETA)
    return [np.array([i * H * cb, 0.0, (i % 2) * H * sb]) for i in range(N_PANELS + 1)]


def build(*, ideal: bool = False, clearance: float = 1.2e-3, sections: int = 3,
          stiffness: float = 4e4, damping: float = 2.0, friction: float = 0.0,
          excitation: float = 2.0, hinge_damping: float = C_HINGE, wire_damping: float = 1e-4,
          elements: int = 15):
    """The model, its wire, panels, grommet joints and the paper's probes."""
    model = fm.Model(gravity=(0.0, 0.0, 0.0), name="solar_array_wing")
    m_p = 1.5 * H * W                                     # 1.5 kg/m^2
    # body axes: x = panel normal (the eyelet axis), y = along the fold lines, z = up the panel
    J_p = (m_p * (H**2 + W**2) / 12, m_p * H**2 / 12, m_p * W**2 / 12)
    folds = fold_points()
    half = np.array([0.0, W / 2, 0.0])
    panels = []
    for i in range(N_PANELS):
        u = (folds[i + 1] - folds[i]) / H
        y = np.array([0.0, 1.0, 0.0])
        R = np.column_stack([np.cross(y, u), y, u])
        panels.append(model.add_rigid_body(
            mass=m_p, inertia=J_p, pose=fm.Pose(0.5 * (folds[i] + folds[i + 1]) + half, R),
            name=f"panel{i + 1}", shape={"type": "box", "size": [0.004, W, H]}))
    y_axis = (0.0, 1.0, 0.0)
    hinges = [model.revolute(panels[0], fm.GROUND, point=folds[0] + half, axis=y_axis,
                             name="hinge_box")]
    for i in range(1, N_PANELS):
        hinges.append(model.revolute(panels[i], panels[i - 1], point=folds[i] + half,
                                     axis=y_axis, name=f"fold{i}"))
    # the mast tip holds the top edge in X and Z (rotation free): 18 - 5 - 5 - 5 - 2 = 1
    # degree of freedom, the zig-zag's fold mode
    model.joint(panels[-1], fm.GROUND, point=folds[-1] + half, translation=(1, 0, 1),
                name="mast_tip")
    for h in hinges:
        model.add_rotational_spring(h, stiffness=K_HINGE, damping=hinge_damping,
                                    name=f"{h.name}_spring")
    model.add_point_load(panels[1], (0.0, 0.0, excitation), name="excitation",
                         function=fm.HalfSine(duration=0.2))
    # the guide wire, straight along X at the eyelets' height; N = EA (eps - eps0), eps0 < 0
    zc = 0.5 * H * math.sin(BETA)
    ea = WIRE_E * math.pi * WIRE_R**2
    wire = model.add_beam(fm.line((-0.1, -E_TAB, zc), (folds[-1][0] + 0.1, -E_TAB, zc),
                                  elements=elements),
                          section=fm.CircularSection(WIRE_R),
                          material=fm.Material(E=WIRE_E, rho=WIRE_RHO),
                          reference_axial_strain=-T_WIRE / ea, damping=wire_damping,
                          name="guide_wire")
    for tag, node in (("G0", wire.first_node), ("G1", wire.last_node)):
        model.prescribe(node, [0, 2], 0.0, name=f"anchor_{tag}_xz")   # pinned in X and Z
        model.prescribe(node, [1], DY, name=f"anchor_{tag}_y")        # moved by DY in statics
    joints = []
    for i, p in enumerate(panels):
        out = SHIFT_MIDDLE if (i == 1 and not ideal) else 0.0   # a ring must sit on the wire
        eyelet = (0.0, -W / 2 - E_TAB - out, 0.0)               # panel coordinates
        if ideal:
            j = model.add_joint(fm.SlidingJoint(wire, p, hole_point=eyelet, variant="ring",
                                                name=f"grommet{i + 1}"))
        else:
            j = model.add_joint(fm.SlidingClearanceJoint(
                wire, p, hole=fm.CircleHole(WIRE_R + clearance, EYELET_LENGTH, sections),
                hole_point=eyelet, contact=fm.LinearPenalty(stiffness=stiffness, damping=damping),
                friction=friction, name=f"grommet{i + 1}"))
        joints.append(j)
    probes = [BeamPointProbe("wire_mid", wire, wire.length / 2, "displacement"),
              BodyPointProbe("M_CE", panels[1], (0.0, -W / 2, 0.0), "displacement"),
              SlideCoordinateProbe("grommet1_s", joints[0]), EnergyProbe("energy")]
    if not ideal:
        probes[2:2] = [ContactForceProbe(f"grommet{i + 1}_force", j) for i, j in enumerate(joints)]
    return model, wire, panels, joints, probes


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t-end", type=float, default=20.0)
    ap.add_argument("--dt", type=float, default=None,
                    help="largest step (default 1e-3 s; with --ideal the fixed step 1e-4 s)")
    ap.add_argument("--step-tolerance", type=float, default=None,
                    help="local error per step [m] (default 1e-5; 0 with --ideal: fixed steps)")
    ap.add_argument("--ideal", action="store_true")
    ap.add_argument("--clearance", type=float, default=1.2e-3)
    ap.add_argument("--sections", type=int, default=3)
    ap.add_argument("--stiffness", type=float, default=4e4)
    ap.add_argument("--excitation", type=float, default=2.0, help="half-sine amplitude F0 [N]")
    ap.add_argument("--out", default=None)
    args = ap.parse_args(argv)
    model, wire, panels, joints, probes = build(
        ideal=args.ideal, clearance=args.clearance, sections=args.sections,
        stiffness=args.stiffness, excitation=args.excitation)
    name = "solar_array_wing_ideal" if args.ideal else "solar_array_wing"
    out = args.out or f"out/{name}_py"
    # as the scenario files: step-error control with clearance, fixed steps for the rings
    dt = args.dt if args.dt is not None else 1e-4 if args.ideal else 2e-3
    tol = (args.step_tolerance if args.step_tolerance is not None
           else 0.0 if args.ideal else 1e-5)
    res = fm.simulate(model, t_end=args.t_end, dt=dt, output_interval=1e-2, probes=probes,
                      integrator=fm.GeneralizedAlpha(rho_inf=0.8, step_tolerance=tol), out=out,
                      name=name,
                      initial_static=True, static_options=STATIC)
    print(f"{name}: {res.stats.steps} steps, {res.stats.newton_iterations} Newton iterations, "
          f"wall {res.wall_time:.1f} s; output in {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Example 2, flat-panel variant, through the Python API: the same model as
examples/solar_array_wing_flat.toml (the default Example 2 is examples/solar_array_wing.py).

A pretensioned guide wire (ANCF cable) passes with clearance through a grommet on the fold line
of two rigid panels that fold like an accordion, held flat by a tension bar (docs/theory.md
§III.10; values proposed there, the paper's are unknown). The wire is meshed straight through the
grommet centre; its anchors are moved 5 mm sideways in the initial static solve, which presses
it on the bore wall. A half-sine force on panel 1 then starts a free vibration. ``--ideal``
replaces the clearance joint by a ring without clearance (sliding joint, variant "ring").

    python examples/solar_array_wing_flat.py [--t-end 20] [--dt 1e-4] [--ideal] [--clearance 1.2e-3]
        [--sections 3] [--stiffness 8e4] [--excitation 2.0] [--out DIR]
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import flexmbs as fm
from flexmbs.io.probes import (
    BeamPointProbe,
    BodyPointProbe,
    ContactForceProbe,
    EnergyProbe,
    SlideCoordinateProbe,
)

HERE = Path(__file__).resolve().parent
H, W = 0.5, 1.0                 # panel height (X) and width (Y) [m]
E_TAB, DY = 0.02, 5e-3          # grommet tab offset e, anchor misalignment [m]
WIRE_R, T_WIRE = 0.8e-3, 20.0   # wire radius [m], pretension before the misalignment [N]
WIRE_E, WIRE_RHO = 1e11, 7900.0
#: static solve: the anchors move in 10 load steps (0.5 mm each, less than the 1.2 mm clearance);
#: the fold mode is held only by the bar force, which also ramps from 0: stabilise it
STATIC = fm.StaticOptions(load_steps=10, stabilizer=100.0)


def build(*, ideal: bool = False, clearance: float = 1.2e-3, sections: int = 3,
          stiffness: float = 8e4, damping: float = 5.0, excitation: float = 2.0):
    model = fm.Model(gravity=(0.0, 0.0, 0.0), name="solar_array_wing_flat")
    m_p = 1.5 * H * W                                     # 1.5 kg/m^2
    J_p = (m_p * W**2 / 12, m_p * H**2 / 12, m_p * (H**2 + W**2) / 12)
    p1 = model.add_rigid_body(mass=m_p, inertia=J_p, position=(H / 2, W / 2, 0), name="panel1",
                              shape={"type": "box", "size": [H, W, 0.004]})
    p2 = model.add_rigid_body(mass=m_p, inertia=J_p, position=(1.5 * H, W / 2, 0), name="panel2",
                              shape={"type": "box", "size": [H, W, 0.004]})
    bar = model.add_rigid_body(mass=1.0, inertia=(1.0 / 12, 1e-4, 1.0 / 12),
                               position=(2 * H, W / 2, 0), name="tension_bar",
                               shape={"type": "box", "size": [0.02, W, 0.02]})
    y_axis = (0.0, 1.0, 0.0)
    model.revolute(p1, fm.GROUND, point=(0, W / 2, 0), axis=y_axis, name="hinge_AB")
    model.revolute(p2, p1, point=(H, W / 2, 0), axis=y_axis, name="hinge_CD")
    model.prismatic(bar, fm.GROUND, point=(2 * H, W / 2, 0), axis=(1, 0, 0), name="bar_slider")
    # tie the bar to panel 2 at the middle of EF in X and Z only: closes the loop without
    # redundant equations (18 coordinates - 5 - 5 - 5 - 2 = 1: the fold mode)
    model.joint(bar, p2, point=(2 * H, W / 2, 0), translation=(1, 0, 1), rotation=(0, 0, 0),
                name="tie_EF")
    model.add_point_load(bar, (40.0, 0.0, 0.0), name="blanket_tension")
    model.add_point_load(p1, (0.0, 0.0, excitation), name="excitation",
                         function=fm.HalfSine(duration=0.2))
    # guide wire meshed through the grommet centre (h, -e, 0); N = EA (eps - eps0), eps0 < 0
    ea = WIRE_E * math.pi * WIRE_R**2
    wire = model.add_beam(fm.read_curve(HERE.parent / "meshes" / "guide_wire.msh",
                                        group="guide_wire"),
                          section=fm.CircularSection(WIRE_R),
                          material=fm.Material(E=WIRE_E, rho=WIRE_RHO),
                          reference_axial_strain=-T_WIRE / ea, damping=1e-4, name="guide_wire")
    for tag, node in (("G0", wire.first_node), ("G1", wire.last_node)):
        model.prescribe(node, [0, 2], 0.0, name=f"anchor_{tag}_xz")   # pinned in X and Z
        model.prescribe(node, [1], DY, name=f"anchor_{tag}_y")        # moved by DY in statics
    grommet = (H - 1.5 * H, -E_TAB - W / 2, 0.0)           # (h, -e, 0) in panel-2 coordinates
    if ideal:
        joint = model.add_joint(fm.SlidingJoint(wire, p2, hole_point=grommet, variant="ring",
                                                name="grommet"))
    else:
        joint = model.add_joint(fm.SlidingClearanceJoint(
            wire, p2, hole=fm.CircleHole(WIRE_R + clearance, 3e-3, sections), hole_point=grommet,
            contact=fm.LinearPenalty(stiffness=stiffness, damping=damping),
            name="grommet"))
    probes = [BeamPointProbe("wire_mid", wire, 0.6, "displacement"),
              BodyPointProbe("M_CE", p2, (0.0, -W / 2, 0.0), "displacement"),
              SlideCoordinateProbe("grommet_s", joint), EnergyProbe("energy")]
    if not ideal:
        probes.insert(2, ContactForceProbe("grommet_force", joint))
    return model, wire, (p1, p2, bar), joint, probes


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t-end", type=float, default=20.0)
    ap.add_argument("--dt", type=float, default=1e-4)
    ap.add_argument("--ideal", action="store_true")
    ap.add_argument("--clearance", type=float, default=1.2e-3)
    ap.add_argument("--sections", type=int, default=3)
    ap.add_argument("--stiffness", type=float, default=8e4)
    ap.add_argument("--excitation", type=float, default=2.0, help="half-sine amplitude F0 [N]")
    ap.add_argument("--out", default=None)
    args = ap.parse_args(argv)
    model, wire, bodies, joint, probes = build(
        ideal=args.ideal, clearance=args.clearance, sections=args.sections,
        stiffness=args.stiffness, excitation=args.excitation)
    name = "solar_array_wing_flat_ideal" if args.ideal else "solar_array_wing_flat"
    out = args.out or f"out/{name}_py"
    res = fm.simulate(model, t_end=args.t_end, dt=args.dt, output_interval=1e-2, probes=probes,
                      integrator=fm.GeneralizedAlpha(rho_inf=0.8), out=out, name=name,
                      initial_static=True, static_options=STATIC)
    print(f"{name}: {res.stats.steps} steps, {res.stats.newton_iterations} Newton iterations, "
          f"wall {res.wall_time:.1f} s; output in {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

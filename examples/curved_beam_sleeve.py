"""Example 1 through the Python API: the same model as examples/curved_beam_sleeve.toml.

A hollow cylinder (sleeve) slides with clearance along an initially curved steel rail under
gravity (docs/theory.md §III.9). ``--ideal`` runs the clearance-free baseline instead.

    python examples/curved_beam_sleeve.py [--t-end 4.0] [--dt 1e-4] [--clearance 5e-4] [--ideal]
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

import flexmbs as fm
from flexmbs.io.probes import BeamPointProbe, ContactForceProbe, EnergyProbe, SlideCoordinateProbe

HERE = Path(__file__).resolve().parent
R_BEAM, RHO = 2e-3, 1.0             # rail radius, radius of curvature [m]
HOLE_LENGTH = 0.04


def build(*, clearance: float = 5e-4, ideal: bool = False, youngs_modulus: float = 2.1e11,
          hole_length: float = HOLE_LENGTH):
    model = fm.Model(gravity=(0.0, 0.0, -9.81), name="curved_beam_sleeve")
    rail = model.add_beam(fm.read_curve(HERE.parent / "meshes" / "arc_r1m_90deg.msh", group="rail"),
                          section=fm.CircularSection(R_BEAM),
                          material=fm.Material(E=youngs_modulus, rho=7800.0), name="rail")
    model.clamp(rail.first_node)
    model.clamp(rail.last_node)
    s0 = math.pi / 4 - math.pi / 6                       # 30 deg before the lowest point
    pose = rail.frame_at(s0)
    if not ideal:
        # the sleeve rests on its two end sections: centre below the rail axis by the clearance
        # minus the sagitta of the rail inside the sleeve, along the outward normal
        outward = np.array([-math.sin(math.pi / 6), 0.0, -math.cos(math.pi / 6)])
        pose = pose.shifted((clearance - hole_length**2 / (8 * RHO)) * outward)
    sleeve = model.add_rigid_body(mass=0.21441, inertia=(2.479e-5, 4.098e-5, 4.098e-5), pose=pose,
                                  name="sleeve", shape={"type": "cylinder", "radius": 0.015,
                                                        "inner_radius": R_BEAM + clearance,
                                                        "length": hole_length})
    if ideal:
        joint = model.add_joint(fm.SlidingJoint(rail, sleeve, name="sleeve"))
    else:
        joint = model.add_joint(fm.SlidingClearanceJoint(
            rail, sleeve, name="sleeve", hole=fm.CircleHole(R_BEAM + clearance, hole_length, 9),
            contact=fm.LinearPenalty(stiffness=1e6, damping=20.0)))
    probes = [SlideCoordinateProbe("sleeve_s", joint),
              BeamPointProbe("lowest_point", rail, math.pi / 4, "displacement"),
              EnergyProbe("energy")]
    if not ideal:
        probes.insert(2, ContactForceProbe("contact_force", joint))
    return model, rail, sleeve, joint, probes


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t-end", type=float, default=4.0)
    ap.add_argument("--dt", type=float, default=1e-4)
    ap.add_argument("--clearance", type=float, default=5e-4)
    ap.add_argument("--ideal", action="store_true")
    ap.add_argument("--out", default=None)
    args = ap.parse_args(argv)
    model, rail, sleeve, joint, probes = build(clearance=args.clearance, ideal=args.ideal)
    name = "curved_beam_sleeve_ideal" if args.ideal else "curved_beam_sleeve"
    res = fm.simulate(model, t_end=args.t_end, dt=args.dt, output_interval=1e-2, probes=probes,
                      out=args.out or f"out/{name}_py", name=name)
    print(f"{name}: {res.stats.steps} steps, {res.stats.newton_iterations} Newton iterations, "
          f"wall {res.wall_time:.1f} s; final slide coordinate "
          f"{joint.slide_coordinate(res.final_state.q):.6f} m; output in {args.out or 'out/'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

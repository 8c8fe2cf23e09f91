"""A guide wire pushed through a curved tube (issue "a rod or wire inside a curved tube").

A straight nitinol-like wire (r = 0.3 mm, E = 60 GPa) is held at its proximal end by a feeder
that pushes it along x at constant speed (a prescribed motion of the end's position and
slope: its reaction is the insertion force). Its tip starts 10 mm inside a rigid tube (bore
0.6 mm) that runs straight for 20 mm and then bends by ``--bend`` degrees with a 50 mm
radius, out of the x-y plane by ``--lift`` (a 3-D centre-line), with open ends: the wire
enters the bend, slides along the outer wall and comes out. Sections every mm; linear penalty
contact, friction that sticks (``--mu``). Prints the insertion force against the depth.

    python examples/guide_wire.py [--feed 0.06] [--bend 60] [--lift 10] [--mu 0.1]
"""

from __future__ import annotations

import argparse
import math
import warnings

import numpy as np

import flexmbs as fm

WIRE_R, BORE = 0.3e-3, 0.6e-3
NITINOL = fm.Material(E=6e10, rho=6500.0)
STRAIGHT, BEND_RADIUS = 0.02, 0.05


def vessel(bend_deg: float, lift_deg: float, ds: float = 1e-3) -> fm.Centerline:
    """Straight 20 mm along x from the origin, then a circular bend of ``bend_deg`` whose
    plane is turned by ``lift_deg`` about x out of the x-y plane."""
    bend, lift = math.radians(bend_deg), math.radians(lift_deg)
    side = np.array([0.0, math.cos(lift), math.sin(lift)])     # towards the bend's centre
    pts, tans = [], []
    n0 = max(2, round(STRAIGHT / ds))
    for k in range(n0):
        pts.append(np.array([STRAIGHT * k / n0, 0.0, 0.0]))
        tans.append(np.array([1.0, 0.0, 0.0]))
    n1 = max(4, round(BEND_RADIUS * bend / ds))
    centre = np.array([STRAIGHT, 0.0, 0.0]) + BEND_RADIUS * side
    for k in range(n1 + 1):
        a = bend * k / n1
        pts.append(centre + BEND_RADIUS * (math.sin(a) * np.array([1.0, 0.0, 0.0])
                                           - math.cos(a) * side))
        tans.append(math.cos(a) * np.array([1.0, 0.0, 0.0]) + math.sin(a) * side)
    return fm.polyline(np.array(pts), np.array(tans))


def build(feed: float, speed: float, bend: float, lift: float, mu: float
          ) -> tuple[fm.Model, fm.Beam, fm.SlidingClearanceJoint]:
    length = 0.08 + 0.01
    model = fm.Model(name="guide_wire", gravity=(0.0, 0.0, 0.0))
    wire = model.add_beam(fm.line((-0.08, 0, 0), (0.01, 0, 0), elements=round(length / 4e-3)),
                          section=fm.CircularSection(WIRE_R), material=NITINOL,
                          damping=2e-4, name="wire")
    duration = feed / speed
    model.prescribe(wire.first_node, [0], fm.Ramp(start=0.0, end=duration, value=feed,
                                                  smooth=True), name="feeder")
    model.prescribe(wire.first_node, [1, 2, 4, 5], name="feeder_hold")
    tube = model.add_rigid_body(mass=1.0, inertia=(1e-3, 1e-3, 1e-3), name="tube")
    model.fix_body(tube)
    joint = model.add_joint(fm.SlidingClearanceJoint(
        wire, tube, hole=fm.CurvedBore(vessel(bend, lift), radius=BORE, spacing=1e-3),
        contact=fm.LinearPenalty(stiffness=2e4), friction=fm.Friction(mu=mu) if mu else None,
        name="vessel"))
    return model, wire, joint


def push(feed: float = 0.06, speed: float = 0.1, bend: float = 60.0, lift: float = 10.0,
         mu: float = 0.1, dt: float = 2e-4) -> dict:
    """Feed the wire by ``feed``; returns times, depth, insertion force, the wire's tip and
    the result."""
    model, wire, joint = build(feed, speed, bend, lift, mu)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = fm.simulate(model, t_end=feed / speed, dt=dt, output_interval=feed / speed / 40,
                          integrator=fm.GeneralizedAlpha(rho_inf=0.8))
    F, _ = res.reaction("feeder", wire)
    tip = res.q[:, res.assembly.node_dofs(wire.last_node)[:3]]
    depth = res.q[:, res.assembly.node_dofs(wire.first_node)[0]] - res.assembly.q_ref[
        res.assembly.node_dofs(wire.first_node)[0]]
    return {"t": res.t, "depth": depth, "force": F[:, 0],
            "tip": tip, "result": res, "joint": joint, "wire": wire}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--feed", type=float, default=0.06, help="insertion depth [m]")
    ap.add_argument("--bend", type=float, default=60.0, help="bend of the tube [deg]")
    ap.add_argument("--lift", type=float, default=10.0, help="bend plane out of x-y [deg]")
    ap.add_argument("--mu", type=float, default=0.1)
    a = ap.parse_args()
    out = push(a.feed, bend=a.bend, lift=a.lift, mu=a.mu)
    for d, f, tip in zip(out["depth"][::4], out["force"][::4], out["tip"][::4], strict=False):
        print(f"depth {1e3 * d:6.2f} mm   insertion force {f:8.4f} N   tip "
              f"[{tip[0]:.4f}, {tip[1]:.4f}, {tip[2]:.4f}] m")


if __name__ == "__main__":
    main()

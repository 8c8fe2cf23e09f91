"""A wire pulled through a curved tube with friction: the capstan ratio T_pull / T_load = e^{μθ}.

A steel wire (r = 0.5 mm) runs straight into a rigid tube bent into a circular arc (centre-line
radius ρ = 0.1 m, wrap angle θ, bore radius 0.8 mm, a bore along a curve: ``fm.CurvedBore``)
and straight out of it. Its entry end carries a constant load T_load = 100 N pulling it back
along the entry line; its exit end is pulled along the exit line at a constant speed (a
prescribed motion, whose reaction is the pull force T_pull). The wire's reference is the
tube's shape, so it carries no bending moment there: the capstan (Euler–Eytelwein) law holds
when T ρ² ≫ EI (here ≈ 100). Contact: linear penalty and friction that sticks (μ = 0.2),
sections every 2 mm. Prints the pull force while the wire slides against the capstan law.

    python examples/capstan.py [--wrap 90] [--mu 0.2] [--t-end 0.2] [--housing]

``--housing``: the tube is a Bowden cable's housing, a beam clamped at every node, and the
wire runs through it by a ``fm.TubeJoint`` (the same law within 1 %).
"""

from __future__ import annotations

import argparse
import math
import warnings

import numpy as np

import flexmbs as fm

RHO, BORE, WIRE_R = 0.1, 0.8e-3, 0.5e-3
STEEL = fm.Material(E=2e11, rho=7800.0)
T_LOAD = 100.0
STRAIGHT = 0.03          # straight wire before and after the tube [m]
ELEMENT = 5e-3           # element length along the arc [m]
SPACING = 2e-3           # section spacing along the tube [m]


def wire_path(wrap: float, ds: float = ELEMENT) -> tuple[np.ndarray, np.ndarray]:
    """Nodes and unit tangents: straight along +y into the arc (centre at the origin, from
    (−ρ, 0, 0) clockwise through ``wrap``), straight out along the arc's exit tangent."""
    n_in = max(2, round(STRAIGHT / ds))
    n_arc = max(4, round(RHO * wrap / ds))
    pts, tans = [], []
    for k in range(n_in):
        pts.append((-RHO, -STRAIGHT + k * STRAIGHT / n_in, 0.0))
        tans.append((0.0, 1.0, 0.0))
    for k in range(n_arc + 1):
        phi = math.pi - wrap * k / n_arc
        pts.append((RHO * math.cos(phi), RHO * math.sin(phi), 0.0))
        tans.append((math.sin(phi), -math.cos(phi), 0.0))
    end, t_end = np.array(pts[-1]), np.array(tans[-1])
    for k in range(1, n_in + 1):
        pts.append(tuple(end + k * STRAIGHT / n_in * t_end))
        tans.append(tuple(t_end))
    return np.array(pts), np.array(tans)


def build(wrap: float, mu: float, *, speed: float = 0.02, ramp: float = 0.02,
          stiffness: float = 2e6, motion: fm.TimeFunction | None = None,
          damping: float = 1e-4, housing: bool = False) -> tuple[fm.Model, fm.Beam, str]:
    """The wire through the tube; returns (model, wire, name of the pull's prescribed motion).
    The exit end moves along the exit line by ``motion(t)`` (default: at ``speed`` from
    ``ramp``, when the load is in); ``damping``: the wire's material damping [s].
    ``housing``: the tube is a Bowden cable's housing, a steel beam along the arc (outer radius
    1.5 mm, one element per 5 mm) clamped at every node (``support0``, ``support1``, ...), the
    wire through it by a :class:`~flexmbs.TubeJoint`, instead of a fixed rigid body's curved
    bore."""
    pts, tans = wire_path(wrap)
    model = fm.Model(name="capstan", gravity=(0.0, 0.0, 0.0))
    wire = model.add_beam(fm.polyline(pts, tans), section=fm.CircularSection(WIRE_R),
                          material=STEEL, damping=damping, name="wire")
    contact, friction = fm.LinearPenalty(stiffness=stiffness), fm.Friction(mu=mu)
    if housing:
        arc = fm.arc((0.0, 0.0, 0.0), RHO, (-RHO, 0.0, 0.0), -wrap, normal=(0.0, 0.0, 1.0),
                     elements=max(4, round(RHO * wrap / ELEMENT)))
        tube_beam = model.add_beam(arc, section=fm.CircularSection(1.5e-3), material=STEEL,
                                   name="housing")
        for k in range(tube_beam.n_nodes):
            model.clamp(tube_beam.node(k), name=f"support{k}")
        model.add_joint(fm.TubeJoint(wire, tube_beam, inner_radius=BORE, spacing=SPACING,
                                     contact=contact, friction=friction, name="tube"))
    else:
        tube = model.add_rigid_body(mass=1.0, inertia=(1e-3, 1e-3, 1e-3), name="tube")
        model.fix_body(tube)
        arc = fm.arc((0.0, 0.0, 0.0), RHO, (-RHO, 0.0, 0.0), -wrap, normal=(0.0, 0.0, 1.0),
                     elements=64)
        model.add_joint(fm.SlidingClearanceJoint(
            wire, tube, hole=fm.CurvedBore(arc, radius=BORE, spacing=SPACING),
            contact=contact, friction=friction, name="tube"))
    # the load: T_LOAD back along the entry line, ramped in
    model.add_point_load(wire.first_node, (0.0, -T_LOAD, 0.0),
                         function=fm.Ramp(start=0.0, end=ramp, value=1.0, smooth=True))
    # the pull: the exit end moves along the exit line after the load is in
    t_out = tans[-1]
    axis = int(np.argmax(np.abs(t_out)))
    if not np.isclose(abs(t_out[axis]), 1.0):
        raise ValueError("the example pulls along a coordinate axis: wrap = 90 or 180 degrees")
    sign = float(np.sign(t_out[axis]))
    if motion is None:
        motion = fm.Ramp(start=ramp, end=ramp + 1.0, value=speed)
    along = motion if sign > 0 else fm.Function(lambda t: -motion(t))
    model.prescribe(wire.last_node, [axis], along, name="pull")
    model.prescribe(wire.last_node, [c for c in range(3) if c != axis], name="pull_line")
    return model, wire, "pull"


def pull_force(wrap: float, mu: float, t_end: float = 0.2, dt: float = 2e-4, *,
               housing: bool = False) -> dict:
    """Run and return the pull force history along the exit line and the capstan value
    (``housing``: :func:`build`'s)."""
    model, wire, pull = build(wrap, mu, housing=housing)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = fm.simulate(model, t_end=t_end, dt=dt, output_interval=5e-3,
                          integrator=fm.GeneralizedAlpha(rho_inf=0.8))
    F, _ = res.reaction(pull, wire)      # the prescribed motion's force on the wire
    t_out = wire_path(wrap)[1][-1]
    return {"t": res.t, "pull": F @ t_out, "capstan": T_LOAD * math.exp(mu * wrap),
            "result": res}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--wrap", type=float, default=90.0, help="wrap angle [deg] (90 or 180)")
    ap.add_argument("--mu", type=float, default=0.2)
    ap.add_argument("--t-end", type=float, default=0.2)
    ap.add_argument("--housing", action="store_true",
                    help="a Bowden cable: the tube is a beam clamped at every node (TubeJoint)")
    a = ap.parse_args()
    out = pull_force(math.radians(a.wrap), a.mu, a.t_end, housing=a.housing)
    for t, f in zip(out["t"][::4], out["pull"][::4], strict=False):
        print(f"t = {t:6.3f} s   pull = {f:8.3f} N")
    late = out["pull"][out["t"] > 0.5 * a.t_end + 0.01]
    print(f"sliding: pull {late.mean():.3f} N (min {late.min():.3f}, max {late.max():.3f}); "
          f"capstan T e^(mu theta) = {out['capstan']:.3f} N; ratio {late.mean() / T_LOAD:.4f} "
          f"vs {math.exp(a.mu * math.radians(a.wrap)):.4f}")


if __name__ == "__main__":
    main()

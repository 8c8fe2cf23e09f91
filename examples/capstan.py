"""A wire pulled through a curved tube with friction: the capstan ratio T_pull / T_load = e^{μθ}.

A steel wire (r = 0.5 mm) runs straight into a rigid tube bent into a circular arc (centre-line
radius ρ = 0.1 m, wrap angle θ, bore radius 0.8 mm, a bore along a curve: ``fm.CurvedBore``)
and straight out of it. Its entry end carries a constant load T_load = 100 N pulling it back
along the entry line; its exit end is pulled along the exit line at a constant speed (a
prescribed motion, whose reaction is the pull force T_pull). The wire's reference is the
tube's shape, so it carries no bending moment there: the capstan (Euler–Eytelwein) law holds
when T ρ² ≫ EI (here ≈ 100). Contact: linear penalty and friction that sticks (μ = 0.2),
sections every 2 mm. Prints the pull force while the wire slides against the capstan law.

    python examples/capstan.py [--wrap 90] [--mu 0.2] [--t-end 0.2] [--housing] [--backlash]

``--housing``: the tube is a Bowden cable's housing, a beam clamped at every node, and the
wire runs through it by a ``fm.TubeJoint`` (the same law within 1 %). ``--backlash``: the
Bowden cable pushed and pulled (:func:`build_backlash`): at each reversal the output stands
while the input travels 2cΘ, the difference of the wire's paths along the bend's inner and
outer walls (c = 0.3 mm: 942 µm at 90°).
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


def wire_path(wrap: float, ds: float = ELEMENT, straight: float = STRAIGHT,
              ) -> tuple[np.ndarray, np.ndarray]:
    """Nodes and unit tangents: ``straight`` along +y into the arc (centre at the origin, from
    (−ρ, 0, 0) clockwise through ``wrap``), ``straight`` out along the arc's exit tangent."""
    n_in = max(2, round(straight / ds))
    n_arc = max(4, round(RHO * wrap / ds))
    pts, tans = [], []
    for k in range(n_in):
        pts.append((-RHO, -straight + k * straight / n_in, 0.0))
        tans.append((0.0, 1.0, 0.0))
    for k in range(n_arc + 1):
        phi = math.pi - wrap * k / n_arc
        pts.append((RHO * math.cos(phi), RHO * math.sin(phi), 0.0))
        tans.append((math.sin(phi), -math.cos(phi), 0.0))
    end, t_end = np.array(pts[-1]), np.array(tans[-1])
    for k in range(1, n_in + 1):
        pts.append(tuple(end + k * straight / n_in * t_end))
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


HOUSING_STRAIGHT = 0.025  # the housing's straight ends; the wire sticks out 5 mm at each [m]
RETURN_SPRING = 2e4       # the output's spring to the ground [N/m]
SPRING_ARM = 1.0          # its ground point: this far back along the entry line [m]


class Stroke(fm.TimeFunction):
    """``amplitude sin(2π frequency t)`` started from rest: times 3x² − 2x³ (x = t / τ) over
    the first quarter period τ, where it reaches ``amplitude`` (no velocity jump at t = 0,
    which would strike the wire's damping)."""

    def __init__(self, *, amplitude: float, frequency: float) -> None:
        self.amplitude, self.frequency = float(amplitude), float(frequency)

    def _parts(self, t: float) -> tuple[float, float, float, float, float, float]:
        w, tau = 2.0 * math.pi * self.frequency, 0.25 / self.frequency
        x = min(max(t / tau, 0.0), 1.0)
        h, h1, h2 = (3 * x * x - 2 * x ** 3, 6 * x * (1 - x) / tau,
                     6 * (1 - 2 * x) / tau ** 2) if x < 1 else (1.0, 0.0, 0.0)
        return math.sin(w * t), math.cos(w * t), w, h, h1, h2

    def __call__(self, t: float) -> float:
        s, _, _, h, _, _ = self._parts(t)
        return self.amplitude * s * h

    def d1(self, t: float) -> float:
        s, c, w, h, h1, _ = self._parts(t)
        return self.amplitude * (w * c * h + s * h1)

    def d2(self, t: float) -> float:
        s, c, w, h, h1, h2 = self._parts(t)
        return self.amplitude * (-w * w * s * h + 2 * w * c * h1 + s * h2)


def build_backlash(wrap: float, *, bore: float = BORE, mu: float = 0.0,
                   amplitude: float = 0.7e-3, frequency: float = 5.0,
                   spring: float = RETURN_SPRING, spring_damping: float = 3.0,
                   stiffness: float = 2e6, damping: float = 1e-4) -> tuple[fm.Model, fm.Beam]:
    """A Bowden cable pushed and pulled: the wire (:func:`wire_path`) in a housing that runs
    straight for :data:`HOUSING_STRAIGHT`, round the bend and straight again (a steel beam
    clamped at every node, ``support0``, ...; the wire through it by a
    :class:`~flexmbs.TubeJoint` of radius ``bore``; ``mu`` = 0: frictionless). The input, the
    exit end, moves along the exit line by ``amplitude sin(2π frequency t)`` started from
    rest (:class:`Stroke`; prescribed ``"pull"``, positive out of the housing); the output,
    the entry end, is held back along the entry line by a spring of ``spring`` [N/m] (and
    ``spring_damping`` [N s/m], near critical for the wire's mass) to a ground point
    :data:`SPRING_ARM` behind it, unstressed as built.
    Pulled, the wire is in tension and lies against the bend's inner wall (path radius ρ − c,
    c = ``bore`` − r); pushed, in compression against the outer one (ρ + c). Neither end is
    held across its line, so the wire takes the wall's offset path; the housing's straights
    guide it there and keep the compressed wire from buckling. Contact: a linear penalty of
    ``stiffness`` per section with a C¹ onset over 1e-3 of the clearance (its penetration,
    0.2 µm at 2 N, widens the band by 2δΘ, 0.07 %). Returns (model, wire)."""
    pts, tans = wire_path(wrap)
    model = fm.Model(name="bowden_backlash", gravity=(0.0, 0.0, 0.0))
    wire = model.add_beam(fm.polyline(pts, tans), section=fm.CircularSection(WIRE_R),
                          material=STEEL, damping=damping, name="wire")
    hp, ht = wire_path(wrap, straight=HOUSING_STRAIGHT)
    housing = model.add_beam(fm.polyline(hp, ht), section=fm.CircularSection(1.5e-3),
                             material=STEEL, name="housing")
    for k in range(housing.n_nodes):
        model.clamp(housing.node(k), name=f"support{k}")
    contact = fm.LinearPenalty(stiffness=stiffness, onset=1e-3 * (bore - WIRE_R))
    model.add_joint(fm.TubeJoint(wire, housing, inner_radius=bore, spacing=SPACING,
                                 contact=contact, friction=fm.Friction(mu=mu) if mu > 0 else None,
                                 name="tube"))
    t_in, t_out = tans[0], tans[-1]
    model.add_spring_damper(wire.first_node, fm.GROUND, point_b=pts[0] - SPRING_ARM * t_in,
                            stiffness=spring, damping=spring_damping, name="return")
    axis = int(np.argmax(np.abs(t_out)))
    if not np.isclose(abs(t_out[axis]), 1.0):
        raise ValueError("the example pulls along a coordinate axis: wrap = 90 or 180 degrees")
    model.prescribe(wire.last_node, [axis],
                    Stroke(amplitude=float(np.sign(t_out[axis])) * amplitude,
                           frequency=frequency), name="pull")
    return model, wire


def backlash_loop(wrap: float, *, periods: float = 0.75, dt: float = 5e-4,
                  output_interval: float = 5e-4, rho_inf: float = 0.5, **kw: float) -> dict:
    """Run :func:`build_backlash` (``kw``) for ``periods`` of the stroke (0.75: pulled, pushed
    through the dead band, pushed to the end) and return, at the output times, the input's
    travel ``u_in`` (out of the housing), the output's ``u_out`` (into it) and the wire's
    tension at the output ``force`` (the spring's, its damping included), with the geometric
    backlash ``2 c Θ`` and the wire's axial compliance ``L / EA``."""
    model, wire = build_backlash(wrap, **kw)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = fm.simulate(model, t_end=periods / kw.get("frequency", 5.0), dt=dt,
                          output_interval=output_interval,
                          integrator=fm.GeneralizedAlpha(rho_inf=rho_inf))
    _, tans = wire_path(wrap)
    u_in = res.node_displacement(wire.last_node) @ tans[-1]
    u_out = res.node_displacement(wire.first_node) @ tans[0]
    v_out = res.v[:, res.assembly.node_dofs(wire.first_node)[:3]] @ tans[0]
    force = kw.get("spring", RETURN_SPRING) * u_out + kw.get("spring_damping", 3.0) * v_out
    c = kw.get("bore", BORE) - WIRE_R
    return {"t": res.t, "u_in": u_in, "u_out": u_out, "force": force,
            "backlash": 2.0 * c * wrap,
            "compliance": wire.length / (STEEL.E * math.pi * WIRE_R ** 2), "result": res}


def dead_band(out: dict, f_min: float = 0.2) -> float:
    """The backlash of a :func:`backlash_loop` history: on each branch, pulled (tension >
    ``f_min``) and pushed (< −``f_min``), ``u_in − u_out − C f`` (C = L/EA, the frictionless
    wire's stretch under its uniform tension f) is the shortening of the wire's path in the
    bend, ± c Θ; returns the pulled branch's mean less the pushed one's: the input's travel
    between the output stopping and restarting at a reversal."""
    slip = out["u_in"] - out["u_out"] - out["compliance"] * out["force"]
    pulled, pushed = out["force"] > f_min, out["force"] < -f_min
    return float(slip[pulled].mean() - slip[pushed].mean())


def stop_to_restart(out: dict, delta: float = 1e-5) -> float:
    """The dead band read off the output directly: after the input's farthest pull, the input's
    travel between the output coming back to within ``delta`` of rest (stopping) and leaving it
    on the other side (restarting), less the output's own 2 ``delta``."""
    u_in, u_out = out["u_in"], out["u_out"]
    k0 = int(np.argmax(u_in))

    def crossing(level: float, start: int) -> tuple[float, int]:
        k = start + int(np.argmax(u_out[start:] < level))
        w = (u_out[k - 1] - level) / (u_out[k - 1] - u_out[k])
        return float(u_in[k - 1] + w * (u_in[k] - u_in[k - 1])), k

    stop, k1 = crossing(delta, k0)
    restart, _ = crossing(-delta, k1)
    return stop - restart - 2.0 * delta


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--wrap", type=float, default=90.0, help="wrap angle [deg] (90 or 180)")
    ap.add_argument("--mu", type=float, default=0.2)
    ap.add_argument("--t-end", type=float, default=0.2)
    ap.add_argument("--housing", action="store_true",
                    help="a Bowden cable: the tube is a beam clamped at every node (TubeJoint)")
    ap.add_argument("--backlash", action="store_true",
                    help="the Bowden cable pushed and pulled (--mu 0: frictionless): its dead band")
    a = ap.parse_args()
    if a.backlash:
        out = backlash_loop(math.radians(a.wrap), mu=a.mu)
        for k in range(0, out["t"].size, 10):
            print(f"t = {out['t'][k]:6.3f} s   input {out['u_in'][k] * 1e3:7.3f} mm   "
                  f"output {out['u_out'][k] * 1e3:7.3f} mm   tension {out['force'][k]:6.2f} N")
        b = out["backlash"]
        for what, d in (("branches at |f| >= 2 N", dead_band(out, 2.0)),
                        ("output stop to restart", stop_to_restart(out))):
            print(f"dead band ({what}): {d * 1e6:.1f} um; 2 c Theta = {b * 1e6:.1f} um "
                  f"({d / b - 1:+.2%})")
        return
    out = pull_force(math.radians(a.wrap), a.mu, a.t_end, housing=a.housing)
    for t, f in zip(out["t"][::4], out["pull"][::4], strict=False):
        print(f"t = {t:6.3f} s   pull = {f:8.3f} N")
    late = out["pull"][out["t"] > 0.5 * a.t_end + 0.01]
    print(f"sliding: pull {late.mean():.3f} N (min {late.min():.3f}, max {late.max():.3f}); "
          f"capstan T e^(mu theta) = {out['capstan']:.3f} N; ratio {late.mean() / T_LOAD:.4f} "
          f"vs {math.exp(a.mu * math.radians(a.wrap)):.4f}")


if __name__ == "__main__":
    main()

"""A Bowden cable turning a lever through a bent housing: friction loss and backlash.

A steel wire (r = 0.5 mm) runs through a housing (a steel beam clamped at every node, a lumen of
0.8 mm: radial clearance c = 0.3 mm) that runs straight for 25 mm, round a bend of Θ = 90° (ρ =
0.1 m) and straight again, the wire through it by a ``fm.TubeJoint`` with friction that sticks
(μ = 0.2). The wire's far end is pinned to the arm (a = 20 mm) of a lever on a revolute joint
with a return spring (k = 23 N m/rad); its near end is pulled 2.5 mm out along the exit line
and let back (a half sine over 0.2 s, prescribed ``"pull"``, whose reaction is the pull force;
the run ends at 0.18 s, the input back to 0.77 mm and the wire still taut).

Statics of the lever: k φ = a cos φ T_out. While the wire slides out, the capstan law gives
T_out = T_pull e^{−μΘ} (0.73 of the pull reaches the lever: the friction loss); sliding back,
T_out = T_pull e^{+μΘ}, so the lever's angle against the pull is a loop. The wire starts on the
housing's centre-line; pulled, it lies against the bend's inner wall, and the input travels
cΘ = 0.47 mm before the lever moves (half the push–pull backlash 2cΘ of
``examples/capstan.py --backlash``: the lever's spring never pushes the wire).

Prints the pull, the lever's angle and the ratio k φ / (a cos φ T_pull) against e^{∓μΘ}.

    python examples/bowden_lever.py [--mu 0.2] [--t-end 0.2]
    python examples/bowden_lever.py --write-toml      # examples/bowden_lever.toml
    flexmbs run examples/bowden_lever.toml --out out/bowden_lever
"""

from __future__ import annotations

import argparse
import math
import warnings
from pathlib import Path

import numpy as np

import flexmbs as fm

RHO, WRAP, BORE, WIRE_R, HOUSING_R = 0.1, math.pi / 2, 0.8e-3, 0.5e-3, 1.5e-3
STEEL = fm.Material(E=2e11, rho=7800.0)
STRAIGHT, HOUSING_STRAIGHT = 0.03, 0.025     # the wire's and the housing's straights [m]
ELEMENT, SPACING = 5e-3, 2e-3                # element length, lumen section spacing [m]
ARM, SPRING = 0.02, 23.0                     # lever arm [m], return spring [N m/rad]
LEVER_MASS = 5e-3                            # [kg]
STROKE, DURATION = 2.5e-3, 0.2               # the pull: out and back, a half sine [m, s]
T_END = 0.18            # the input back to 0.77 mm: the wire still taut (the lever at 0.8 deg)
CONTACT = 2e6                                # penalty per section [N/m]
TOML = Path(__file__).with_suffix(".toml")


def path(straight: float, ds: float = ELEMENT) -> tuple[np.ndarray, np.ndarray]:
    """Nodes and unit tangents: ``straight`` along +y to (−ρ, 0, 0), the bend (centre at the
    origin) clockwise through Θ = 90° to (0, ρ, 0), ``straight`` along +x."""
    n_in, n_arc = max(2, round(straight / ds)), max(4, round(RHO * WRAP / ds))
    pts = [(-RHO, -straight + k * straight / n_in, 0.0) for k in range(n_in)]
    tans = [(0.0, 1.0, 0.0)] * n_in
    for k in range(n_arc + 1):
        phi = math.pi - WRAP * k / n_arc
        pts.append((RHO * math.cos(phi), RHO * math.sin(phi), 0.0))
        tans.append((math.sin(phi), -math.cos(phi), 0.0))
    pts += [(k * straight / n_in, RHO, 0.0) for k in range(1, n_in + 1)]
    tans += [(1.0, 0.0, 0.0)] * n_in
    return np.array(pts), np.array(tans)


def lever_geometry() -> tuple[np.ndarray, np.ndarray]:
    """The hinge (a distance ``ARM`` from the wire's far end, across the entry line) and the
    lever's centre of mass (half way)."""
    end = path(STRAIGHT)[0][0]
    hinge = end - np.array([ARM, 0.0, 0.0])
    return hinge, 0.5 * (hinge + end)


LEVER_INERTIA = (2e-8, LEVER_MASS * ARM**2 / 12, LEVER_MASS * ARM**2 / 12)


def build(mu: float = 0.2, stroke: float = STROKE, duration: float = DURATION
          ) -> tuple[fm.Model, fm.Beam, fm.RigidBody]:
    """The cable and the lever; returns (model, wire, lever)."""
    model = fm.Model(name="bowden_lever", gravity=(0.0, 0.0, 0.0))
    wire = model.add_beam(fm.polyline(*path(STRAIGHT)), section=fm.CircularSection(WIRE_R),
                          material=STEEL, damping=1e-4, name="wire")
    housing = model.add_beam(fm.polyline(*path(HOUSING_STRAIGHT)),
                             section=fm.CircularSection(HOUSING_R), material=STEEL,
                             name="housing")
    for k in range(housing.n_nodes):
        model.clamp(housing.node(k), name=f"support{k}")
    model.add_joint(fm.TubeJoint(
        wire, housing, inner_radius=BORE, spacing=SPACING,
        contact=fm.LinearPenalty(stiffness=CONTACT, onset=1e-3 * (BORE - WIRE_R)),
        friction=fm.Friction(mu=mu) if mu > 0 else None, name="tube"))
    hinge, centre = lever_geometry()
    lever = model.add_rigid_body(mass=LEVER_MASS, inertia=LEVER_INERTIA,
                                 pose=fm.Pose(centre), name="lever")
    joint = model.revolute(lever, point=hinge, axis=(0.0, 0.0, 1.0), name="hinge")
    model.add_rotational_spring(joint, stiffness=SPRING, damping=1e-3, name="return")
    model.spherical(wire.first_node, lever, name="link")
    model.prescribe(wire.last_node, [0], fm.HalfSine(duration=duration, amplitude=stroke),
                    name="pull")
    return model, wire, lever


def lever_angle(quaternion: np.ndarray) -> np.ndarray:
    """The lever's turn about z [rad] from its Euler parameters [w, x, y, z]."""
    return 2.0 * np.arctan2(quaternion[..., 3], quaternion[..., 0])


def run(mu: float = 0.2, t_end: float = T_END, dt: float = 5e-4) -> dict:
    """Simulate and return the histories: the input's travel ``u_in``, the pull force
    ``pull`` (the prescribed motion's force on the wire along the exit line: the hand's pull),
    the lever's angle ``phi`` and the wire's tension at the lever from the
    spring, ``t_out`` = k φ / (a cos φ)."""
    model, wire, lever = build(mu)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = fm.simulate(model, t_end=t_end, dt=dt, output_interval=2.5e-3,
                          integrator=fm.GeneralizedAlpha(rho_inf=0.5))
    phi = lever_angle(res.body_quaternion(lever))
    pull = res.reaction("pull", wire)[0][:, 0]
    return {"t": res.t, "u_in": res.node_displacement(wire.last_node)[:, 0], "pull": pull,
            "phi": phi, "t_out": SPRING * phi / (ARM * np.cos(phi)), "result": res}


def _vec(v: np.ndarray | tuple[float, ...]) -> str:
    return "[" + ", ".join(repr(float(x) if abs(x) > 1e-15 else 0.0) for x in v) + "]"


def scenario(mu: float = 0.2) -> str:
    """The model as a scenario file: ``examples/bowden_lever.toml`` is this text
    (``--write-toml``)."""
    hinge, centre = lever_geometry()
    lines = [
        "# Generated by `python examples/bowden_lever.py --write-toml` (edit the script, not this",
        "# file): a Bowden cable turning a lever through a housing bent by 90 degrees; the wire's",
        "# near end pulled 2.5 mm and let back, its far end on the lever's arm (return spring).",
        "#   flexmbs run examples/bowden_lever.toml --out out/bowden_lever",
        "#   flexmbs run examples/bowden_lever.toml --set joints.tube.contact.friction=0",
        "# The lever's angle from probe lever (Euler parameters): 2 atan2(lever_z, lever_w);",
        "# the pull force: pull_fx.",
        'name = "bowden_lever"',
        'description = "A Bowden cable turning a lever through a bent housing"',
        "",
        "[simulation]",
        f"t_end = {T_END!r}",
        "dt = 5e-4",
        "rho_inf = 0.5",
        "gravity = [0.0, 0.0, 0.0]",
        "output_interval = 2.5e-3",
    ]
    for name, straight, radius, damping in (("wire", STRAIGHT, WIRE_R, 1e-4),
                                             ("housing", HOUSING_STRAIGHT, HOUSING_R, 0.0)):
        pts, tans = path(straight)
        lines += ["", "[[beams]]", f'name = "{name}"', f"radius = {radius!r}",
                  f"youngs_modulus = {STEEL.E!r}", f"density = {STEEL.rho!r}"]
        if damping:
            lines.append(f"damping = {damping!r}")
        lines += ["[beams.geometry.polyline]",
                  "points = [" + ", ".join(_vec(p) for p in pts) + "]",
                  "tangents = [" + ", ".join(_vec(t) for t in tans) + "]"]
    lines += ["", "[[rigid_bodies]]", 'name = "lever"', f"mass = {LEVER_MASS!r}",
              f"inertia = {_vec(LEVER_INERTIA)}", f"pose = {{ position = {_vec(centre)} }}",
              f'shape = {{ type = "box", size = [{ARM!r}, 0.004, 0.002] }}']
    n_housing = len(path(HOUSING_STRAIGHT)[0])
    for k in range(n_housing):
        lines += ["", "[[constraints]]", 'type = "clamp"', f'name = "support{k}"',
                  'beam = "housing"', f"node = {k}"]
    lines += ["", "[[constraints]]", 'type = "revolute"', 'name = "hinge"', 'body = "lever"',
              f"point = {_vec(hinge)}", "axis = [0.0, 0.0, 1.0]",
              "", "[[constraints]]", 'type = "spherical"', 'name = "link"', 'beam = "wire"',
              'node = "first"', 'body2 = "lever"',
              f"point2 = {_vec(path(STRAIGHT)[0][0] - centre)}",
              "", "[[constraints]]", 'type = "prescribed"', 'name = "pull"', 'beam = "wire"',
              'node = "last"', "components = [0]",
              f'function = {{ type = "half_sine", duration = {DURATION!r}, '
              f"amplitude = {STROKE!r} }}",
              "", "[[joints]]", 'type = "tube"', 'name = "tube"', 'beam = "wire"',
              'tube = "housing"', f'lumen = {{ shape = "circle", radius = {BORE!r} }}',
              f"spacing = {SPACING!r}",
              f'contact = {{ law = "linear", stiffness = {CONTACT!r}, '
              f"onset = {1e-3 * (BORE - WIRE_R)!r}, friction = {mu!r} }}",
              "", "[[springs]]", 'type = "rotational"', 'name = "return"', 'joint = "hinge"',
              f"stiffness = {SPRING!r}", "damping = 1e-3",
              "", "[[probes]]", 'name = "pull"', 'type = "reaction"', 'constraint = "pull"',
              'part = "wire"',
              "", "[[probes]]", 'name = "lever"', 'type = "body_orientation"', 'body = "lever"',
              "", "[[probes]]", 'name = "input"', 'type = "beam_point"', 'beam = "wire"',
              f"s = {float(np.sum(np.linalg.norm(np.diff(path(STRAIGHT)[0], axis=0), axis=1)))!r}",
              'quantity = "displacement"']
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mu", type=float, default=0.2)
    ap.add_argument("--t-end", type=float, default=T_END)
    ap.add_argument("--write-toml", type=Path, nargs="?", const=TOML, default=None,
                    help=f"write the scenario file (default {TOML.name}) and stop")
    a = ap.parse_args(argv)
    if a.write_toml is not None:
        a.write_toml.write_text(scenario(a.mu), encoding="utf-8")
        print(a.write_toml)
        return 0
    out = run(a.mu, a.t_end)
    loss = math.exp(-a.mu * WRAP)
    for k in range(0, out["t"].size, 4):
        ratio = out["t_out"][k] / out["pull"][k] if out["pull"][k] > 1.0 else float("nan")
        print(f"t = {out['t'][k]:6.3f} s  input {out['u_in'][k] * 1e3:6.3f} mm  pull "
              f"{out['pull'][k]:7.2f} N  lever {math.degrees(out['phi'][k]):6.3f} deg  "
              f"k phi / (a cos phi pull) {ratio:6.4f}")
    print(f"capstan: e^(-mu Theta) = {loss:.4f} pulling, e^(mu Theta) = {1 / loss:.4f} "
          "letting back")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

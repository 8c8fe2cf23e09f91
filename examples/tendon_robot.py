"""A tendon-driven continuum robot: six tendons through 20 disks on a NiTi backbone (issue 52).

The robot of ``benchmarks/tendon_robot.py``, built as a user would, with
:meth:`flexmbs.Model.add_tendon`: a NiTi backbone (``ancf_rod14``, r = 0.7 mm, E = 54 GPa,
400 mm along z) clamped with its twist to a fixed base plate, ``--disks`` aluminium disks
(r = 15 mm, 2 mm) held rigidly by the backbone at equal spacing, six steel tendons (r = 0.08 mm)
10 mm from the backbone at 90°, -30° and 210°: tendons 1-3 anchored at the middle disk, 4-6
(the same holes) at the last. Every tendon passes a 1 mm hole (20 µm clearance, linear penalty
1e6 N/m, one contact section: the holes are shorter than the wire's elements) in the plate and
in every disk below its anchor, starts 20 mm below the plate and is pulled there by its tension.
The penalty rises smoothly over the first 0.2 µm of penetration (``LinearPenalty(onset=...)``).

The load cases (tensions of tendons 1..6 in N), by name:

- ``mixed``: (0, 2, 0, 1, 0, 1): the lower half bends towards 90°, the whole towards 150°;
- ``opposed``: (4, 0, 0, 0, 2, 0): the lower half towards 90°, the upper half back (an S);
- ``opposed_light``: (2, 0, 0, 0, 2, 0);
- ``tip_force``: (4, 0, 0, 0, 0, 1) and a 0.1 N force along +z at the tip.

The tensions ramp in over 0.1 s and the robot comes to rest under stiffness-proportional
damping (backbone 0.4 s: its first bending mode critically damped; wires 1 ms). ``--static``
solves the equilibrium with :func:`flexmbs.solve_static` instead. With slack tendons (a zero
tension) it converges for ``mixed`` (20 disks: 40 s) and ``opposed_light`` (10 disks: 104
s), not yet for the two cases with 4 N on tendon 1 (issue 52, item 3: ``docs/design-notes.md``,
"Statics of tendon-routed structures"). ``--mu`` adds stick friction at every hole.
``--loop`` pulls tendon 4 up to 2 N and releases it, without friction and with ``--mu``
(default 0.1): the tip's pull-release hysteresis.

Prints the tip's position and each tendon's tension in its spans (actuator to anchor); with
``--out`` writes the run (ParaView series with the disks, ``probes.csv`` with the disk centres,
the tip and the tensions) for ``examples/figures/tendon_robot.py``.

The same robot as a scenario file: ``examples/tendon_robot.toml`` (``--write-toml`` writes it).

    python examples/tendon_robot.py [--case mixed] [--disks 20] [--mu 0] [--out DIR] [--static]
    python examples/tendon_robot.py --loop [--mu 0.1] [--out DIR]   # the pull-release loop
    flexmbs run examples/tendon_robot.toml
"""

from __future__ import annotations

import argparse
import math
import time
import warnings
from pathlib import Path

import numpy as np

import flexmbs as fm
from flexmbs.assembly import Assembly

LENGTH, ROD_R = 0.4, 0.7e-3
NITI = fm.Material(E=54e9, rho=6450.0, nu=0.3)
STEEL = fm.Material(E=200e9, rho=7850.0, nu=0.3)
WIRE_R, CLEARANCE, PITCH_R, LEAD = 0.08e-3, 0.02e-3, 10e-3, 20e-3
ANGLES = (90.0, -30.0, 210.0)          # degrees about z: tendons 1-3, and 4-6
DISK_R, DISK_T, ALU = 15e-3, 2e-3, 2700.0
#: tensions of tendons 1..6 [N] and the tip force along +z [N] of each load case
CASES: dict[str, tuple[tuple[float, ...], float]] = {
    "mixed": ((0.0, 2.0, 0.0, 1.0, 0.0, 1.0), 0.0),
    "opposed": ((4.0, 0.0, 0.0, 0.0, 2.0, 0.0), 0.0),
    "opposed_light": ((2.0, 0.0, 0.0, 0.0, 2.0, 0.0), 0.0),
    "tip_force": ((4.0, 0.0, 0.0, 0.0, 0.0, 1.0), 0.1),
}
#: body x along global z: the disks' cylinders (drawn in ParaView) run along the backbone
AXIS_Z = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
RAMP, BACKBONE_DAMPING, WIRE_DAMPING = 0.1, 0.4, 1e-3
#: the wires' element length: 57 elements on the 420 mm tendons, as the issue's model
WIRE_ELEMENT = (LEAD + LENGTH) / 57
#: the holes' linear penalty rises smoothly over the first 1 % of the clearance (the Tendon's
#: default: ``flexmbs.tendons.ONSET``)
ONSET = 1e-2 * CLEARANCE
TOML = Path(__file__).with_suffix(".toml")


def build(case: str = "mixed", disks: int = 20, mu: float = 0.0,
          pull: fm.TimeFunction | None = None) -> tuple[fm.Model, dict]:
    """The robot under load case ``case``; returns the model and its parts (``backbone``,
    ``disks``, ``tendons``: :class:`flexmbs.TendonParts`). ``pull``: instead, tendon 4 alone
    pulled by this tension [N] (the others slack; the pull-release loop)."""
    if case not in CASES:
        raise SystemExit(f"--case: unknown load case {case!r} (known: {', '.join(CASES)})")
    if disks < 2:
        raise SystemExit(f"--disks: at least 2 (got {disks})")
    tensions, tip_force = CASES[case]
    model = fm.Model(name=f"tendon_robot_{case}", gravity=(0.0, 0.0, 0.0))
    backbone = model.add_beam(fm.line((0, 0, 0), (0, 0, LENGTH), elements=2 * disks),
                              section=fm.CircularSection(ROD_R), material=NITI,
                              element="ancf_rod14", damping=BACKBONE_DAMPING, name="backbone")
    mass = ALU * math.pi * DISK_R**2 * DISK_T
    inertia = (0.5 * mass * DISK_R**2, 0.25 * mass * DISK_R**2 + mass * DISK_T**2 / 12,
               0.25 * mass * DISK_R**2 + mass * DISK_T**2 / 12)

    def disk(z: float, name: str) -> fm.RigidBody:
        return model.add_rigid_body(mass=mass, inertia=inertia, pose=fm.Pose((0, 0, z), AXIS_Z),
                                    name=name, shape={"type": "cylinder", "radius": DISK_R,
                                                      "length": DISK_T})

    plate = disk(0.0, "plate")
    model.fix_body(plate, name="plate_fixed")
    model.rigid(backbone.first_node, plate, name="base_clamp")
    bodies = []
    for k in range(1, disks + 1):
        body = disk(k * LENGTH / disks, f"disk{k}")
        model.rigid(backbone.node(2 * k), body, name=f"mount{k}")
        bodies.append(body)
    def ramp(value: float) -> fm.Ramp:
        return fm.Ramp(start=0.0, end=RAMP, value=value, smooth=True)

    tendons = []
    for i, angle in enumerate(ANGLES + ANGLES):
        a = math.radians(angle)
        hole = AXIS_Z.T @ np.array([PITCH_R * math.cos(a), PITCH_R * math.sin(a), 0.0])
        end = disks // 2 if i < 3 else disks
        tension = ramp(tensions[i]) if tensions[i] else 0.0
        if pull is not None:
            tension = pull if i == 3 else 0.0
        tendons.append(model.add_tendon(fm.Tendon(
            name=f"t{i + 1}", route=[(plate, hole)] + [(b, hole) for b in bodies[:end - 1]],
            anchor=(bodies[end - 1], hole), lead=LEAD, radius=WIRE_R, material=STEEL,
            clearance=CLEARANCE, damping=WIRE_DAMPING, tension=tension,
            element_length=WIRE_ELEMENT,
            contact=fm.LinearPenalty(stiffness=1e6, onset=ONSET), friction=mu or None)))
    if tip_force and pull is None:
        model.add_point_load(backbone.last_node, (0.0, 0.0, 1.0), function=ramp(tip_force),
                             name="tip_force")
    return model, {"backbone": backbone, "disks": bodies, "tendons": tendons}


def _vec(v) -> str:
    return "[" + ", ".join(repr(float(x) if abs(x) > 1e-15 else 0.0) for x in v) + "]"


def scenario(case: str = "mixed", disks: int = 20, mu: float = 0.0) -> str:
    """The robot as a scenario file: ``examples/tendon_robot.toml`` is this text for the
    defaults (``--write-toml``); the other cases by ``--set tendons.t<i>.tension=...``."""
    tensions, tip_force = CASES[case]
    mass = ALU * math.pi * DISK_R**2 * DISK_T
    inertia = (0.5 * mass * DISK_R**2, 0.25 * mass * DISK_R**2 + mass * DISK_T**2 / 12,
               0.25 * mass * DISK_R**2 + mass * DISK_T**2 / 12)
    quaternion = fm.Pose((0.0, 0.0, 0.0), AXIS_Z).quaternion     # body x along global z
    lines = [
        "# Generated by `python examples/tendon_robot.py --write-toml` (edit the script, not this",
        "# file): the tendon-driven continuum robot of examples/tendon_robot.py, load case",
        f"# '{case}', {disks} disks. The other load cases, e.g. 'opposed' (4, 0, 0, 0, 2, 0 N):",
        "#   flexmbs run examples/tendon_robot.toml --set tendons.t1.tension.value=4 \\",
        "#       --set tendons.t2.tension=0 --set tendons.t4.tension=0 \\",
        "#       --set tendons.t5.tension.value=2 --set tendons.t6.tension=0",
        "# A damped run to rest (statics with slack tendons: docs/design-notes.md, \"Statics of",
        "# tendon-routed structures\").",
        f'name = "tendon_robot_{case}"',
        'description = "Six tendons through the disks of a NiTi continuum robot, damped to rest"',
        "",
        "[simulation]",
        "t_end = 2.0",
        "dt = 5e-3",
        "rho_inf = 0.5",
        "gravity = [0.0, 0.0, 0.0]",
        "output_interval = 0.1",
        "",
        "[[beams]]",
        'name = "backbone"',
        f"geometry = {{ line = {{ start = [0.0, 0.0, 0.0], end = [0.0, 0.0, {LENGTH!r}] }} }}",
        f"elements = {2 * disks}",
        'element = "ancf_rod14"',
        f"radius = {ROD_R!r}",
        f"youngs_modulus = {NITI.E!r}",
        f"density = {NITI.rho!r}",
        f"poisson_ratio = {NITI.nu!r}",
        f"damping = {BACKBONE_DAMPING!r}",
    ]
    names = ["plate"] + [f"disk{k}" for k in range(1, disks + 1)]
    for k, name in enumerate(names):
        lines += ["", "[[rigid_bodies]]", f'name = "{name}"', f"mass = {mass!r}",
                  f"inertia = {_vec(inertia)}",
                  f"pose = {{ position = [0.0, 0.0, {k * LENGTH / disks!r}], quaternion = "
                  f"{_vec(quaternion)} }}",
                  f'shape = {{ type = "cylinder", radius = {DISK_R!r}, length = {DISK_T!r} }}']
    lines += ["", "[[constraints]]", 'type = "fix_body"', 'name = "plate_fixed"', 'body = "plate"',
              "", "[[constraints]]", 'type = "rigid"', 'name = "base_clamp"', 'beam = "backbone"',
              'node = "first"', 'body = "plate"']
    for k in range(1, disks + 1):
        lines += ["", "[[constraints]]", 'type = "rigid"', f'name = "mount{k}"',
                  'beam = "backbone"', f"node = {2 * k}", f'body = "disk{k}"']
    for i, angle in enumerate(ANGLES + ANGLES):
        a = math.radians(angle)
        hole = AXIS_Z.T @ np.array([PITCH_R * math.cos(a), PITCH_R * math.sin(a), 0.0])
        end = disks // 2 if i < 3 else disks
        route = ", ".join(f'{{ body = "{b}", point = {_vec(hole)} }}' for b in names[:end])
        tension = (f"{{ type = \"ramp\", start = 0.0, end = {RAMP!r}, value = {tensions[i]!r}, "
                   "smooth = true }" if tensions[i] else "0.0")
        lines += ["", "[[tendons]]", f'name = "t{i + 1}"', f"route = [{route}]",
                  f'anchor = {{ body = "disk{end}", point = {_vec(hole)} }}', f"lead = {LEAD!r}",
                  f"radius = {WIRE_R!r}", f"youngs_modulus = {STEEL.E!r}",
                  f"density = {STEEL.rho!r}", f"poisson_ratio = {STEEL.nu!r}",
                  f"damping = {WIRE_DAMPING!r}", f"element_length = {WIRE_ELEMENT!r}",
                  f"clearance = {CLEARANCE!r}",
                  f"tension = {tension}",
                  f"contact = {{ law = \"linear\", stiffness = 1e6, onset = {ONSET!r}"
                  + (f", friction = {mu!r}" if mu else "") + " }"]
    if tip_force:
        lines += ["", "[[loads]]", 'type = "point"', 'name = "tip_force"', 'beam = "backbone"',
                  'node = "last"', f"force = [0.0, 0.0, {tip_force!r}]",
                  f'function = {{ type = "ramp", start = 0.0, end = {RAMP!r}, value = 1.0, '
                  'smooth = true }']
    lines += ["", "[[probes]]", 'type = "beam_point"', 'name = "tip"', 'beam = "backbone"',
              f"s = {LENGTH!r}"]
    for k in range(1, disks + 1):
        lines += ["", "[[probes]]", 'type = "body_position"', f'name = "disk{k}"',
                  f'body = "disk{k}"']
    for i in range(6):
        lines += ["", "[[probes]]", 'type = "tendon_tension"', f'name = "N_t{i + 1}"',
                  f'tendon = "t{i + 1}"', "", "[[probes]]", 'type = "tendon_displacement"',
                  f'name = "pulled_t{i + 1}"', f'tendon = "t{i + 1}"']
    return "\n".join(lines) + "\n"


def probes(parts: dict) -> list:
    """The disk centres, the tip and every tendon's span tensions and pulled length."""
    from flexmbs.io.probes import BodyPositionProbe, TendonDisplacementProbe, TendonTensionProbe

    out: list = [BodyPositionProbe(f"disk{k + 1}", d) for k, d in enumerate(parts["disks"])]
    for t in parts["tendons"]:
        out += [TendonTensionProbe(f"N_{t.name}", t), TendonDisplacementProbe(f"pulled_{t.name}", t)]
    return out


def report(asm, q: np.ndarray, parts: dict) -> None:
    """Print the tip's position and every tendon's span tensions and pulled length at ``q``."""
    tip = q[asm.node_dofs(parts["backbone"].last_node)[:3]]
    print(f"tip at ({1e3 * tip[0]:.2f}, {1e3 * tip[1]:.2f}, {1e3 * tip[2]:.2f}) mm")
    for t in parts["tendons"]:
        N = t.axial_forces(asm, q)
        print(f"  {t.name}: span tensions {np.array2string(N, precision=4, max_line_width=200)} N, "
              f"pulled {1e3 * t.pulled(asm, q):.3f} mm")


def static(model: fm.Model, parts: dict, args: argparse.Namespace) -> int:
    """The equilibrium under the full loads by load stepping (``--static``)."""
    asm = Assembly(model)
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            st = fm.solve_static(asm, fm.StaticOptions(load_steps=10), t=RAMP)
        except fm.FlexmbsError as exc:
            print(f"static solve failed after {time.perf_counter() - t0:.1f} s: {exc}")
            return 1
    print(f"case {args.case} (static): {st.load_increments} load increments, "
          f"{st.newton_iterations} Newton iterations, {time.perf_counter() - t0:.2f} s")
    report(asm, st.q, parts)
    return 0


#: the pull-release loop: tendon 4's tension [N] rises to this and falls back, each in ...
LOOP_PEAK = 2.0
#: ... this time [s] (about five times the backbone's damping time: nearly quasi-static)
LOOP_TIME = 2.0


def loop(args: argparse.Namespace) -> int:
    """``--loop``: tendon 4 pulled up to :data:`LOOP_PEAK` and released, without friction and
    with ``--mu`` (default 0.1), the tip's displacement against the actuator's tension; each
    run written to ``--out``/mu_<mu> for ``examples/figures/tendon_robot.py``. With
    ``--static`` the loop is a sequence of equilibria (:func:`flexmbs.solve_quasi_static`),
    without the damped run's lag."""
    pull = fm.Table(times=[0.0, LOOP_TIME, 2 * LOOP_TIME, 2.5 * LOOP_TIME],
                    values=[0.0, LOOP_PEAK, 0.0, 0.0])
    for mu in (0.0, args.mu or 0.1):
        model, parts = build(disks=args.disks, mu=mu, pull=pull)
        out = None if args.out is None else args.out / f"mu_{mu:g}"
        t0 = time.perf_counter()
        asm = Assembly(model)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            if args.static:     # equilibria every 0.1 s, the friction state carried along
                res = fm.solve_quasi_static(asm, np.linspace(0.0, 2.5 * LOOP_TIME, 51), out=out,
                                            probes=probes(parts) if out else ())
            else:
                res = fm.simulate(asm, t_end=2.5 * LOOP_TIME, dt=args.dt,
                                  output_interval=LOOP_TIME / 20,
                                  integrator=fm.GeneralizedAlpha(rho_inf=0.5),
                                  record_energy=False, out=out,
                                  probes=probes(parts) if out else ())
        t4 = parts["tendons"][3]
        tip = asm.node_dofs(parts["backbone"].last_node)[:3]
        print(f"mu = {mu:g} ({time.perf_counter() - t0:.0f} s): tension [N], tip displacement [mm]")
        for k in range(0, len(res.t), 5):  # every quarter of a ramp
            n = t4.axial_forces(asm, res.q[k])[0]
            u = np.linalg.norm(res.q[k][tip] - asm.q_ref[tip])
            print(f"  t = {res.t[k]:4.1f} s  {n:7.4f}  {1e3 * u:8.3f}")
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", default="mixed", help=f"load case: {', '.join(CASES)}")
    ap.add_argument("--disks", type=int, default=20)
    ap.add_argument("--mu", type=float, default=0.0, help="friction coefficient at the holes")
    ap.add_argument("--t-end", type=float, default=2.0, help="time to come to rest [s]")
    ap.add_argument("--dt", type=float, default=5e-3)
    ap.add_argument("--out", type=Path, default=None, help="output folder")
    ap.add_argument("--loop", action="store_true",
                    help="tendon 4 pulled to 2 N and released, with and without friction "
                         "(--mu, default 0.1): the tip's hysteresis")
    ap.add_argument("--static", action="store_true",
                    help="solve the equilibrium (solve_static) instead of the damped run; with "
                         "--loop, equilibria along the loop (solve_quasi_static)")
    ap.add_argument("--write-toml", type=Path, nargs="?", const=TOML, default=None,
                    metavar="FILE", help=f"write the scenario file (default {TOML.name}) and stop")
    args = ap.parse_args(argv)
    if args.write_toml is not None:
        args.write_toml.write_text(scenario(args.case, args.disks, args.mu), encoding="utf-8")
        print(args.write_toml)
        return 0
    if args.loop:
        return loop(args)
    model, parts = build(args.case, args.disks, args.mu)
    if args.static:
        return static(model, parts, args)
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = fm.simulate(model, t_end=args.t_end, dt=args.dt, output_interval=args.t_end / 20,
                          integrator=fm.GeneralizedAlpha(rho_inf=0.5), record_energy=False,
                          out=args.out, probes=probes(parts) if args.out else ())
    wall = time.perf_counter() - t0
    asm, q = res.assembly, res.final_state.q
    d = asm.node_dofs(parts["backbone"].last_node)[:3]
    moved = np.linalg.norm(q[d] - res.q[-2][d]) if len(res.q) > 1 else 0.0
    print(f"case {args.case}: tensions {CASES[args.case][0]} N, tip force "
          f"{CASES[args.case][1]} N, mu = {args.mu}; the tip moved {1e6 * moved:.2f} um over "
          "the last output interval")
    report(asm, q, parts)
    s = res.stats
    print(f"{s.steps} steps ({s.rejected_steps} rejected), {s.newton_iterations} Newton "
          f"iterations; wall {wall:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""A catheter advanced over a guide wire inside a 3-D vessel: a beam in a flexible tube in a
rigid bore, with clearance and friction at both levels (issue 53).

The vessel is that of ``examples/guide_wire.toml`` (``meshes/vessel.msh``: 20 mm straight, a
60° bend lifted 10° out of x-y, 10 mm straight, a 45° bend towards +z), here with a bore of
1.2 mm. A polymer catheter (outer radius 0.8 mm, lumen 0.45 mm, E = 3 GPa, 72 mm) starts with
its tip 12 mm into the vessel; a nitinol guide wire (r = 0.3 mm, 98 mm) runs through its lumen
and 6 mm beyond, its tip 2 mm before the first bend. Each is pushed at its proximal end, outside
the vessel, by a feeder (position along x, the other position components and slopes held) in
turns, each push a smooth move from rest to rest (``fm.Moves``):

- 0–0.4 s: the wire 25 mm, round the first bend (the catheter held);
- 0.4–0.8 s: the catheter 20 mm over it (the wire held);
- 0.8–1.2 s: the wire 20 mm, into the second bend;
- 1.2–1.6 s: the catheter 20 mm.

Contacts, each a linear penalty of 5e5 N/m per section:
- the catheter in the vessel (``SlidingClearanceJoint`` along the mesh's curve, a section per
  mm, μ = 0.1);
- the wire in the vessel (the same bore, μ = 0.1: it touches the vessel beyond the catheter's
  tip);
- the wire in the catheter's lumen (``TubeJoint``, a section every 2 mm, μ = 0.05).

The feeders' reactions are the insertion forces. Prints the tips and the forces.

    python examples/catheter.py [--t-end 1.6]
    python examples/catheter.py --write-toml            # examples/catheter.toml
    flexmbs run examples/catheter.toml --out out/catheter
    flexmbs render out/catheter --movie catheter.mp4    # the three levels drawn
"""

from __future__ import annotations

import argparse
import math
import warnings
from pathlib import Path

import numpy as np

import flexmbs as fm

ROOT = Path(__file__).resolve().parents[1]
VESSEL_MESH = ROOT / "meshes" / "vessel.msh"
TOML = Path(__file__).with_suffix(".toml")
VESSEL_R, VESSEL_SPACING = 1.2e-3, 1e-3
WIRE_R, WIRE_E, WIRE_RHO = 0.3e-3, 6e10, 6500.0                     # nitinol
WIRE_START, WIRE_TIP, WIRE_ELEMENTS = -0.08, 0.018, 24
CATHETER_R, LUMEN_R, CATHETER_E, CATHETER_RHO = 0.8e-3, 0.45e-3, 3e9, 1200.0   # a polymer
CATHETER_START, CATHETER_TIP, CATHETER_ELEMENTS = -0.06, 0.012, 18
LUMEN_SPACING = 2e-3
DAMPING = 2e-4                                  # stiffness-proportional [s]
CONTACT = 5e5                                   # penalty per section [N/m]
MU_VESSEL, MU_LUMEN = 0.1, 0.05
#: (start, end, distance) of each feeder's pushes [s, s, m]
WIRE_PUSHES = ((0.0, 0.4, 0.025), (0.8, 1.2, 0.02))
CATHETER_PUSHES = ((0.4, 0.8, 0.02), (1.2, 1.6, 0.02))
T_END, DT, OUTPUT = 1.6, 2e-4, 0.02


def catheter_section() -> fm.BeamStiffness:
    """The catheter's hollow section: EA, EI, ρA of a tube of radii 0.8 and 0.45 mm."""
    area = math.pi * (CATHETER_R**2 - LUMEN_R**2)
    inertia = math.pi / 4 * (CATHETER_R**4 - LUMEN_R**4)
    return fm.BeamStiffness(axial_stiffness=CATHETER_E * area,
                            bending_stiffness=CATHETER_E * inertia,
                            mass_per_length=CATHETER_RHO * area, radius=CATHETER_R)


def build(mu_vessel: float = MU_VESSEL, mu_lumen: float = MU_LUMEN
          ) -> tuple[fm.Model, fm.Beam, fm.Beam]:
    """The vessel, the catheter and the wire; returns (model, wire, catheter)."""
    model = fm.Model(name="catheter", gravity=(0.0, 0.0, 0.0))
    wire = model.add_beam(fm.line((WIRE_START, 0.0, 0.0), (WIRE_TIP, 0.0, 0.0),
                                  elements=WIRE_ELEMENTS),
                          section=fm.CircularSection(WIRE_R),
                          material=fm.Material(E=WIRE_E, rho=WIRE_RHO), damping=DAMPING,
                          name="wire")
    catheter = model.add_beam(fm.line((CATHETER_START, 0.0, 0.0), (CATHETER_TIP, 0.0, 0.0),
                                      elements=CATHETER_ELEMENTS),
                              section=catheter_section(), damping=DAMPING, name="catheter")
    for beam, pushes in ((wire, WIRE_PUSHES), (catheter, CATHETER_PUSHES)):
        model.prescribe(beam.first_node, [0], fm.Moves(pushes), name=f"{beam.name}_feeder")
        model.prescribe(beam.first_node, [1, 2, 4, 5], name=f"{beam.name}_feeder_hold")
    vessel = model.add_rigid_body(mass=1.0, inertia=(1e-3, 1e-3, 1e-3), name="vessel")
    model.fix_body(vessel, name="vessel_fixed")
    path = fm.read_curve(VESSEL_MESH, group="vessel")
    for beam in (catheter, wire):
        model.add_joint(fm.SlidingClearanceJoint(
            beam, vessel, hole=fm.CurvedBore(path, radius=VESSEL_R, spacing=VESSEL_SPACING),
            contact=fm.LinearPenalty(stiffness=CONTACT),
            friction=fm.Friction(mu=mu_vessel) if mu_vessel > 0 else None,
            name=f"{beam.name}_in_vessel"))
    model.add_joint(fm.TubeJoint(wire, catheter, inner_radius=LUMEN_R, spacing=LUMEN_SPACING,
                                 contact=fm.LinearPenalty(stiffness=CONTACT),
                                 friction=fm.Friction(mu=mu_lumen) if mu_lumen > 0 else None,
                                 name="wire_in_catheter"))
    return model, wire, catheter


def advance(t_end: float = T_END, out: str | Path | None = None) -> dict:
    """Run; returns the times, both tips' positions and both insertion forces (along x, the
    feeders' forces on the beams) and the result."""
    model, wire, catheter = build()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")        # the start's contact check: the tips are free
        res = fm.simulate(model, t_end=t_end, dt=DT, output_interval=OUTPUT, out=out,
                          integrator=fm.GeneralizedAlpha(rho_inf=0.8))
    asm = res.assembly
    run: dict = {"t": res.t, "result": res}
    for beam in (wire, catheter):
        run[f"{beam.name}_tip"] = res.q[:, asm.node_dofs(beam.last_node)[:3]]
        run[f"{beam.name}_force"] = res.reaction(f"{beam.name}_feeder", beam)[0][:, 0]
    return run


def _vec(v: tuple[float, ...] | np.ndarray) -> str:
    return "[" + ", ".join(repr(float(x)) for x in v) + "]"


def scenario() -> str:
    """The model as a scenario file: ``examples/catheter.toml`` is this text (``--write-toml``)."""
    area = math.pi * (CATHETER_R**2 - LUMEN_R**2)
    inertia = math.pi / 4 * (CATHETER_R**4 - LUMEN_R**4)
    lines = [
        "# Generated by `python examples/catheter.py --write-toml` (edit the script, not this",
        "# file): a catheter advanced over a guide wire inside the vessel of",
        "# examples/guide_wire.toml (bore 1.2 mm), the two pushed in turns at their proximal ends.",
        "#   flexmbs run examples/catheter.toml --out out/catheter",
        "#   flexmbs render out/catheter --movie catheter.mp4",
        "# The insertion forces: probes wire_feeder_fx, catheter_feeder_fx; the tips: wire_tip_*,",
        "# catheter_tip_*.",
        'name = "catheter"',
        'description = "A catheter advanced over a guide wire in a 3-D vessel"',
        "",
        "[simulation]",
        f"t_end = {T_END!r}",
        f"dt = {DT!r}",
        "rho_inf = 0.8",
        "gravity = [0.0, 0.0, 0.0]",
        f"output_interval = {OUTPUT!r}",
        "",
        "[[beams]]",
        'name = "wire"',
        f"geometry = {{ line = {{ start = {_vec((WIRE_START, 0.0, 0.0))}, "
        f"end = {_vec((WIRE_TIP, 0.0, 0.0))} }} }}",
        f"elements = {WIRE_ELEMENTS}",
        f"radius = {WIRE_R!r}",
        f"youngs_modulus = {WIRE_E!r}",
        f"density = {WIRE_RHO!r}",
        f"damping = {DAMPING!r}",
        "",
        "[[beams]]",
        'name = "catheter"',
        f"geometry = {{ line = {{ start = {_vec((CATHETER_START, 0.0, 0.0))}, "
        f"end = {_vec((CATHETER_TIP, 0.0, 0.0))} }} }}",
        f"elements = {CATHETER_ELEMENTS}",
        f"radius = {CATHETER_R!r}",
        f"axial_stiffness = {CATHETER_E * area!r}",
        f"bending_stiffness = {CATHETER_E * inertia!r}",
        f"mass_per_length = {CATHETER_RHO * area!r}",
        f"damping = {DAMPING!r}",
        "",
        "[[rigid_bodies]]",
        'name = "vessel"',
        "mass = 1.0",
        "inertia = [0.001, 0.001, 0.001]",
        'shape = { type = "box", size = [2e-3, 2e-3, 2e-3] }',
        "",
        "[[constraints]]",
        'type = "fix_body"',
        'name = "vessel_fixed"',
        'body = "vessel"',
    ]
    for beam, pushes in (("wire", WIRE_PUSHES), ("catheter", CATHETER_PUSHES)):
        moves = ", ".join(_vec(p) for p in pushes)
        lines += ["", "[[constraints]]", 'type = "prescribed"', f'name = "{beam}_feeder"',
                  f'beam = "{beam}"', 'node = "first"', "components = [0]",
                  f'function = {{ type = "moves", moves = [{moves}] }}',
                  "", "[[constraints]]", 'type = "prescribed"', f'name = "{beam}_feeder_hold"',
                  f'beam = "{beam}"', 'node = "first"', "components = [1, 2, 4, 5]"]
    for beam in ("catheter", "wire"):
        lines += ["", "[[joints]]", f'name = "{beam}_in_vessel"', 'type = "sliding_clearance"',
                  f'beam = "{beam}"', 'body = "vessel"',
                  f'hole = {{ shape = "circle", radius = {VESSEL_R!r}, spacing = '
                  f'{VESSEL_SPACING!r}, path = {{ mesh = "../meshes/vessel.msh", '
                  'group = "vessel" } }',
                  f'contact = {{ law = "linear", stiffness = {CONTACT!r}, '
                  f"friction = {MU_VESSEL!r} }}"]
    lines += ["", "[[joints]]", 'name = "wire_in_catheter"', 'type = "tube"', 'beam = "wire"',
              'tube = "catheter"', f'lumen = {{ shape = "circle", radius = {LUMEN_R!r} }}',
              f"spacing = {LUMEN_SPACING!r}",
              f'contact = {{ law = "linear", stiffness = {CONTACT!r}, '
              f"friction = {MU_LUMEN!r} }}"]
    for beam in ("wire", "catheter"):
        length = (WIRE_TIP - WIRE_START) if beam == "wire" else (CATHETER_TIP - CATHETER_START)
        lines += ["", "[[probes]]", f'name = "{beam}_feeder"', 'type = "reaction"',
                  f'constraint = "{beam}_feeder"', f'part = "{beam}"',
                  "", "[[probes]]", f'name = "{beam}_tip"', 'type = "beam_point"',
                  f'beam = "{beam}"', f"s = {length!r}", 'quantity = "position"']
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t-end", type=float, default=T_END)
    ap.add_argument("--write-toml", type=Path, nargs="?", const=TOML, default=None,
                    help=f"write the scenario file (default {TOML.name}) and stop")
    a = ap.parse_args(argv)
    if a.write_toml is not None:
        a.write_toml.write_text(scenario(), encoding="utf-8")
        print(a.write_toml)
        return 0
    run = advance(a.t_end)
    for k in range(0, len(run["t"]), 5):
        w, c = 1e3 * run["wire_tip"][k], 1e3 * run["catheter_tip"][k]
        print(f"t {run['t'][k]:5.2f} s  wire tip [{w[0]:6.2f} {w[1]:6.2f} {w[2]:6.2f}] mm "
              f"{run['wire_force'][k]:7.3f} N   catheter tip [{c[0]:6.2f} {c[1]:6.2f} "
              f"{c[2]:6.2f}] mm {run['catheter_force'][k]:7.3f} N")
    print(run["result"].stats)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

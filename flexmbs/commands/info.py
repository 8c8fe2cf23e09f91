"""``flexmbs info SCENARIO``: the model of a scenario, human readable."""

from __future__ import annotations

import argparse
import sys
from typing import Any, TextIO

from ..errors import FlexmbsError
from ._common import EXIT_BAD_INPUT, EXIT_OK, add_quiet, docs, error, one_line, overrides

__all__ = ["add_parser", "print_info", "run"]


def add_parser(sub: Any, parents: list[argparse.ArgumentParser]) -> None:
    info = sub.add_parser("info", parents=parents, help="print the model of a scenario",
                          description="Print the model: coordinates, beams, bodies, constraints, "
                                      "loads, joints, probes and solver settings "
                                      f"({docs('cli', 'flexmbs-info')}).")
    info.add_argument("scenario", metavar="SCENARIO", help="scenario file (.toml)")
    add_quiet(info, "print nothing: only check that the scenario loads and its model builds "
                    "(exit status 0 or 2)")



def _fmt(x: Any) -> str:
    import numpy as np

    if isinstance(x, (float, np.floating)):
        return f"{float(x):.6g}"
    if isinstance(x, np.ndarray):
        return "[" + ", ".join(_fmt(v) for v in x.reshape(-1)) + "]"
    if isinstance(x, (list, tuple)):
        return "[" + ", ".join(_fmt(v) for v in x) + "]"
    return str(x)


def _target(obj: Any) -> str:
    return str(getattr(obj, "name", obj))


def print_info(sc: Any, asm: Any, file: TextIO) -> None:
    """The model of a loaded scenario, human readable."""
    import numpy as np

    def p(*parts: Any) -> None:
        print(*parts, file=file)

    model = sc.model
    sim = sc.simulation
    p(f"scenario     {sc.name}  ({sc.path})")
    if sc.description:
        p(f"description  {' '.join(sc.description.split())}")
    p(f"coordinates  {asm.n_coords}")
    p(f"multipliers  {asm.n_mult}")
    p(f"gravity      {_fmt(model.gravity)} m/s^2")
    p(f"beams ({len(model.beams)})")
    for b in model.beams:
        k = b.stiffness
        opts = getattr(b, "options", None)
        p(f"  {b.name}: {b.n_elem} elements, {b.n_nodes} nodes, length {_fmt(b.length)} m"
          f"{', closed' if b.closed else ''} (element {b.element})")
        p(f"    EA {_fmt(k.axial_stiffness)} N, EI {_fmt(k.bending_stiffness)} N m^2, "
          f"rhoA {_fmt(k.mass_per_length)} kg/m"
          + (f", GJ {_fmt(k.torsional_stiffness)} N m^2" if k.torsional_stiffness else "")
          + (f", rhoJp {_fmt(k.polar_mass_moment)} kg m" if b.layout.twist is not None else "")
          + (f", radius {_fmt(k.radius)} m" if k.radius else ""))
        p(f"    damping {_fmt(b.damping)} s, reference axial strain "
          f"{_fmt(b.reference_axial_strain)}" + (f", options {opts}" if opts is not None else ""))
    p(f"rigid bodies ({len(model.bodies)})")
    for body in model.bodies:
        pose = body.pose
        p(f"  {body.name}: mass {_fmt(body.mass)} kg, inertia "
          f"{_fmt(np.asarray(body.inertia, float))} kg m^2")
        p(f"    position {_fmt(pose.position)} m, quaternion {_fmt(pose.quaternion)}")
    p(f"constraints ({len(model.constraints)}; {asm.n_mult} equations)")
    labels = list(asm.multiplier_labels)
    for c in model.constraints:
        eqs = [lab for lab in labels if f"'{c.name}'" in lab]
        target = _target(c.a) + (f" -> {_target(c.b)}" if c.kind not in ("clamp", "pin") and
                                 c.kind != "prescribed" else "")
        p(f"  {c.name}: {c.kind} {target}, {len(eqs)} equations")
        for lab in eqs:
            p(f"    {lab}")
    other = [lab for lab in labels if not any(f"'{c.name}'" in lab for c in model.constraints)]
    if other:
        p(f"  other equations ({len(other)})")
        for lab in other:
            p(f"    {lab}")
    dropped = list(getattr(asm, "dropped_equations", []))
    p(f"dropped redundant equations ({len(dropped)})" + (": " + "; ".join(dropped) if dropped else ""))
    p(f"loads ({len(model.loads)})")
    for ld in model.loads:
        tgt = ld.target
        where = (f"{tgt[0].name} at s = {_fmt(tgt[1])}" if isinstance(tgt, tuple) else _target(tgt))
        p(f"  {ld.name}: {ld.kind} on {where}, force {_fmt(ld.force)}"
          + (f", moment {_fmt(ld.moment)}" if ld.moment is not None else "")
          + f", function {ld.function!r}")
    joints = list(model.interactions)
    p(f"joints/interactions ({len(joints)})")
    for j in joints:
        p(f"  {j!r}")
    p(f"probes ({len(sc.probes)})")
    for pr in sc.probes:
        p(f"  {pr.name}: {type(pr).__name__} -> {', '.join(pr.columns())}")
    p("simulation")
    for k, v in vars(sim).items():
        if k == "newton":
            v = v or "{} (defaults)"
        p(f"  {k:22s} {_fmt(v)}")
    opts_i = sc.integrator_options()
    p(f"  solver                 {opts_i if opts_i is not None else sc.static_options()}")
    if opts_i is not None:
        reason = asm.compiled_reason()
        path = ("compiled (whole steps in numba)" if not reason and opts_i.compiled
                else "Python Newton loop (compiled = false)" if not reason
                else f"Python Newton loop: {reason}")
        p(f"  integrator path        {path}")


def run(args: argparse.Namespace) -> int:
    from ..assembly import Assembly
    from ..io.scenario import load_scenario

    try:
        sc = load_scenario(args.scenario, overrides(args))
        asm = Assembly(sc.model, redundant_constraints=sc.simulation.redundant_constraints)
    except FlexmbsError as exc:
        error(one_line(exc))
        return EXIT_BAD_INPUT
    if not args.quiet:
        print_info(sc, asm, sys.stdout)
    return EXIT_OK

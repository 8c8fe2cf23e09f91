"""A helical spring of torsion-capable rods (element ``ancf_rod14``) under an axial load.

A steel wire (d = 1 mm) coiled into 4 turns of radius 10 mm and pitch 2 mm is clamped at its
foot; its head is held by an end plate (a rigid body rigidly attached to the last node, its
section included) that slides along and turns about the coil axis (a cylindrical joint). The
static axial stiffness is compared with the closed form (docs/theory.md §I.7.7), then a step load
on the plate starts a lightly damped axial oscillation; the plate's travel and the wire's
torsional moment at mid-length are written to ``out/helical_spring`` (VTU frames, probes).
A cable (12-DOF, no torsion) cannot carry this load: its wire has no torsional stiffness.

    python examples/helical_spring.py [--per-coil 16] [--t-end 0.05] [--out out/helical_spring]
"""

from __future__ import annotations

import argparse
import math

import numpy as np

import flexmbs as fm
from flexmbs.assembly import Assembly
from flexmbs.io.probes import BeamPointProbe, BodyPositionProbe

R, PITCH, COILS, WIRE_RADIUS = 0.01, 2e-3, 4, 0.5e-3
STEEL = fm.Material(E=2e11, rho=7800.0, nu=0.3)


def build(per_coil: int = 16, force: float = 1.0) -> tuple[fm.Model, fm.Beam, fm.RigidBody]:
    n = COILS * per_coil
    s = np.linspace(0.0, 2 * math.pi * COILS, n + 1)
    c = PITCH / (2 * math.pi)
    points = np.column_stack([R * np.cos(s), R * np.sin(s), c * s])
    tangents = np.column_stack([-R * np.sin(s), R * np.cos(s), np.full_like(s, c)])
    model = fm.Model(name="helical_spring")
    wire = model.add_beam(fm.polyline(points, tangents), section=fm.CircularSection(WIRE_RADIUS),
                          material=STEEL, element="ancf_rod14", damping=2e-5, name="wire")
    model.clamp(wire.first_node)
    head = (0.0, 0.0, c * s[-1])
    plate = model.add_rigid_body(mass=5e-3, inertia=(1e-7, 1e-7, 2e-7), position=head,
                                 name="plate")
    model.rigid(wire.last_node, plate)
    model.joint(plate, point=head, axis=(0, 0, 1), translation=(0, 1, 1), rotation=(0, 1, 1),
                name="cylindrical")
    model.add_point_load(plate, (0.0, 0.0, force), name="pull")
    return model, wire, plate


def closed_form_stiffness(wire: fm.Beam) -> float:
    """k = 1/(ℓ [R² (cos²α/GJ + sin²α/EI) + sin²α/EA]) (docs/theory.md §I.7.7)."""
    st = wire.stiffness
    alpha = math.atan(PITCH / (2 * math.pi * R))
    assert st.torsional_stiffness is not None
    compliance = wire.length * (R**2 * (math.cos(alpha) ** 2 / st.torsional_stiffness
                                        + math.sin(alpha) ** 2 / st.bending_stiffness)
                                + math.sin(alpha) ** 2 / st.axial_stiffness)
    return 1.0 / compliance


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--per-coil", type=int, default=16, help="elements per coil")
    ap.add_argument("--t-end", type=float, default=0.05)
    ap.add_argument("--dt", type=float, default=5e-5)
    ap.add_argument("--out", default="out/helical_spring")
    args = ap.parse_args(argv)

    # the linear stiffness from a small load
    probe_force = 1e-3
    model, wire, plate = build(args.per_coil, probe_force)
    asm = Assembly(model)
    st = fm.solve_static(asm)
    z = asm.body_dofs(plate)[2]
    k = probe_force / (st.q[z] - asm.q_ref[z])
    k_formula = closed_form_stiffness(wire)
    G = STEEL.G
    k_classic = G * (2 * WIRE_RADIUS) ** 4 / (8 * (2 * R) ** 3 * COILS)
    print(f"axial stiffness {k:.2f} N/m; closed form {k_formula:.2f} N/m "
          f"({100 * (k / k_formula - 1):+.2f} %, the plates also hold the coil radius); "
          f"G d^4/(8 D^3 n) = {k_classic:.2f} N/m")

    # a step load from t = 0 on the unloaded spring: the plate oscillates about F/k
    force = 0.2
    model, wire, plate = build(args.per_coil, force)
    probes = [BodyPositionProbe("plate", plate),
              BeamPointProbe("torsion_mid", wire, 0.5 * wire.length, "torsional_moment")]
    res = fm.simulate(model, t_end=args.t_end, dt=args.dt, output_interval=args.t_end / 100,
                      out=args.out, probes=probes, integrator=fm.GeneralizedAlpha(rho_inf=0.9))
    z = res.assembly.body_dofs(plate)[2]
    travel = res.q[:, z] - res.assembly.q_ref[z]
    m_plate = 5e-3 + 0.33 * wire.stiffness.mass_per_length * wire.length   # + a third of the wire
    print(f"plate travel: max {1e3 * travel.max():.3f} mm (2 F/k = {2e3 * force / k:.3f} mm), final "
          f"{1e3 * travel[-1]:.3f} mm; estimated period 2 pi sqrt(m/k) = "
          f"{1e3 * 2 * math.pi * math.sqrt(m_plate / k):.2f} ms")
    s = res.stats
    print(f"{s.steps} steps, {s.newton_iterations / max(s.steps, 1):.2f} Newton iterations per "
          f"step, wall {res.wall_time:.2f} s; output in {args.out}")
    return 0 if np.all(np.isfinite(travel)) else 1


if __name__ == "__main__":
    raise SystemExit(main())

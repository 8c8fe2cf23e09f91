"""Cost of the torsion-capable rod (``ancf_rod14``) against the 12-DOF cable (issue "torsion rod":
our bound is 2x per element-step).

Two measures, both in one process run:

1. the element kernels alone (internal force; force + tangent) per element, on a deformed
   helix of 64 elements, best of 20 calls;
2. the dynamic cantilever of ``cantilever.py`` (generalized-alpha, h = 1e-3, modified Newton)
   built of either element, wall time per step and per element-step.

    python benchmarks/rod.py [--sizes 32 128] [--t-end 0.5]
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from exudyn_models import CANTILEVER  # noqa: E402

import flexmbs as fm  # noqa: E402
from flexmbs.assembly import Assembly  # noqa: E402
from flexmbs.elements import ancf_cable as cable  # noqa: E402
from flexmbs.elements import ancf_rod as rod  # noqa: E402


def _best(fn, repeats: int = 20) -> float:
    fn()
    best = float("inf")
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def kernel_costs(n: int = 64) -> dict[str, float]:
    """µs per element of the internal force and of force + tangent, cable and rod, on a helix
    deformed at random (same centreline for both)."""
    s = np.linspace(0.0, 4 * np.pi, n + 1)
    pts = np.column_stack([0.3 * np.cos(s), 0.3 * np.sin(s), 0.03 * s])
    model = fm.Model()
    out = {}
    rng = np.random.default_rng(0)
    for element in ("ancf_cable", "ancf_rod14"):
        model = fm.Model()
        model.add_beam(fm.polyline(pts), element=element,
                       section=fm.BeamStiffness(axial_stiffness=1e6, bending_stiffness=1.0,
                                                mass_per_length=1.0, torsional_stiffness=0.8))
        asm = Assembly(model)
        grp = asm.groups[0]
        q = asm.q_ref + 0.01 * rng.standard_normal(asm.n_coords)
        qe = np.ascontiguousarray(q[grp.dofs])
        ve = np.zeros_like(qe)
        f = np.empty_like(qe)
        k = np.empty(qe.shape + (qe.shape[1],))
        if element == "ancf_cable":
            def force(qe=qe, ve=ve, f=f, grp=grp) -> None:
                cable.internal_forces(qe, ve, grp.props, grp.rest, grp.options, f)

            def tangent(qe=qe, ve=ve, f=f, k=k, grp=grp) -> None:
                cable.internal_forces(qe, ve, grp.props, grp.rest, grp.options, f, k)
        else:
            def force(qe=qe, ve=ve, f=f, grp=grp) -> None:
                rod.internal_forces(qe, ve, grp.props, grp.rest, f)

            def tangent(qe=qe, ve=ve, f=f, k=k, grp=grp) -> None:
                rod.internal_forces(qe, ve, grp.props, grp.rest, f, k)
        out[f"{element} force"] = 1e6 * _best(force) / n
        out[f"{element} tangent"] = 1e6 * _best(tangent) / n
    return out


def cantilever(element: str, n_elem: int, t_end: float) -> dict:
    c = CANTILEVER
    model = fm.Model(gravity=c["gravity"])
    beam = model.add_beam(fm.line((0, 0, 0), (c["length"], 0, 0), elements=n_elem),
                          section=fm.BeamStiffness(axial_stiffness=c["axial_stiffness"],
                                                   bending_stiffness=c["bending_stiffness"],
                                                   mass_per_length=c["mass_per_length"],
                                                   torsional_stiffness=c["bending_stiffness"]),
                          element=element)
    model.clamp(beam.first_node)
    res = fm.simulate(model, t_end=t_end, dt=1e-3, output_interval=t_end, record_energy=False,
                      integrator=fm.GeneralizedAlpha(rho_inf=0.8, adaptive=False))
    steps = res.stats.steps
    return dict(us_step=1e6 * res.wall_time / steps, us_elem_step=1e6 * res.wall_time / steps / n_elem,
                iterations=res.stats.newton_iterations / steps,
                tip=float(res.node_displacement(beam.last_node)[-1, 2]))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[32, 128])
    ap.add_argument("--t-end", type=float, default=0.5)
    args = ap.parse_args(argv)
    k = kernel_costs()
    print("element kernels, µs per element (deformed helix, 64 elements):")
    for what in ("force", "tangent"):
        c, r = k[f"ancf_cable {what}"], k[f"ancf_rod14 {what}"]
        print(f"  {what:8s} cable {c:7.2f}   rod {r:7.2f}   rod/cable {r / c:5.2f}")
    print(f"dynamic cantilever (h = 1e-3, t_end = {args.t_end}):")
    for n in args.sizes:
        c = cantilever("ancf_cable", n, args.t_end)
        r = cantilever("ancf_rod14", n, args.t_end)
        print(f"  n = {n:4d}: cable {c['us_step']:8.1f} µs/step ({c['us_elem_step']:.2f} per element,"
              f" {c['iterations']:.2f} it/step)   rod {r['us_step']:8.1f} µs/step "
              f"({r['us_elem_step']:.2f}, {r['iterations']:.2f} it/step)   rod/cable "
              f"{r['us_step'] / c['us_step']:.2f}   tips {c['tip']:.6e} {r['tip']:.6e}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

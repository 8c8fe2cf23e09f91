"""Cost of the torsion-capable rod (``ancf_rod14``) against the 12-DOF cable (issue "torsion rod":
our bound is 2x per element-step).

Two measures, both in one process run:

1. an element group's compiled residual (internal force, M q̈, the rod's spin inertia) and
   matrix block per element, on a deformed helix of 64 elements in motion (timed in loops
   compiled without reference counting, like the compiled entry that runs the real step);
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

from exudyn_models import CANTILEVER

import flexmbs as fm
from flexmbs._jit import njit
from flexmbs.assembly import Assembly
from flexmbs.elements.group import element_jacobian, element_residual
from flexmbs.terms import dynamic_mode


@njit(refcount=False)
def _residuals(part, q, v, qdd, mode, r, repeats):
    for _ in range(repeats):
        element_residual(part, q, v, qdd, mode, r)


@njit(refcount=False)
def _jacobians(part, q, v, qdd, mode, data, repeats):
    for _ in range(repeats):
        element_jacobian(part, q, v, qdd, mode, 1.0, 0.5, 0.25, data)


def kernel_costs(n: int = 64, repeats: int = 200) -> dict[str, float]:
    """µs per element of an element group's residual (internal force, M q̈ and, for the rod, the
    spin inertia) and of its iteration-matrix block (the compiled functions the solvers call),
    cable and rod, on a helix deformed at random with random velocities and accelerations;
    best of 5 runs of ``repeats`` calls."""
    s = np.linspace(0.0, 4 * np.pi, n + 1)
    pts = np.column_stack([0.3 * np.cos(s), 0.3 * np.sin(s), 0.03 * s])
    out = {}
    rng = np.random.default_rng(0)
    for element in ("ancf_cable", "ancf_rod14"):
        model = fm.Model()
        model.add_beam(fm.polyline(pts), element=element,
                       section=fm.BeamStiffness(axial_stiffness=1e6, bending_stiffness=1.0,
                                                mass_per_length=1.0, torsional_stiffness=0.8))
        asm = Assembly(model)
        part = next(p for p in asm.system.beams if p.dofs.shape[0] == n)
        q = asm.q_ref + 0.01 * rng.standard_normal(asm.n_coords)
        v, qdd = rng.standard_normal((2, asm.n_coords))
        mode = dynamic_mode()
        r = np.zeros(asm.n_coords)
        data = np.zeros(asm.matrix.nnz)
        for what, fn, args in (("force", _residuals, (r,)), ("tangent", _jacobians, (data,))):
            fn(part, q, v, qdd, mode, *args, 1)
            best = min(_timed(fn, part, q, v, qdd, mode, *args, repeats) for _ in range(5))
            out[f"{element} {what}"] = 1e6 * best / repeats / n
    return out


def _timed(fn, *args) -> float:
    t = time.perf_counter()
    fn(*args)
    return time.perf_counter() - t


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
    print("element group residual and matrix block, µs per element (deformed helix, 64 elements):")
    for what in ("force", "tangent"):  # residual, matrix block
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

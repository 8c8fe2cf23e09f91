"""Side-by-side benchmark: dynamic 3D cantilever in flexmbs and in Exudyn, in one process run.

Same model (benchmarks/exudyn_models.CANTILEVER), same integrator (generalized-alpha,
rho_inf = 0.8, fixed h = 1e-3, index 3), same element integration (3-point Lobatto axial,
2-point Gauss bending), modified Newton in both. Prints wall time per step, the ratio
flexmbs/Exudyn and the tip deflection of both; then the scaling exponent of flexmbs'
cost per step from N = 16 to 1024.

    python benchmarks/cantilever.py [--t-end 0.5] [--sizes 8 32 128] [--no-scaling]
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from exudyn_models import CANTILEVER, exudyn_available, run_exudyn_cantilever

import flexmbs as fm


def build_flexmbs(n_elem: int) -> tuple[fm.Model, fm.Beam]:
    c = CANTILEVER
    model = fm.Model(gravity=c["gravity"])
    beam = model.add_beam(fm.line((0, 0, 0), (c["length"], 0, 0), elements=n_elem),
                          section=fm.BeamStiffness(axial_stiffness=c["axial_stiffness"],
                                                   bending_stiffness=c["bending_stiffness"],
                                                   mass_per_length=c["mass_per_length"]),
                          options=fm.CableOptions(axial_rule="lobatto3", bending_points=2))
    model.clamp(beam.first_node)
    return model, beam


def run_flexmbs(n_elem: int, *, h: float = 1e-3, t_end: float = 0.5, rho_inf: float = 0.8,
                repeats: int = 1) -> dict:
    best = None
    for _ in range(repeats):
        model, beam = build_flexmbs(n_elem)
        integ = fm.GeneralizedAlpha(rho_inf=rho_inf, adaptive=False)
        res = fm.simulate(model, t_end=t_end, dt=h, integrator=integ, output_interval=t_end,
                          record_energy=False)
        if best is None or res.wall_time < best[0].wall_time:
            best = (res, beam)
    best, beam = best
    s = best.stats
    return dict(n_elem=n_elem, steps=s.steps, wall_time=best.wall_time,
                us_per_step=1e6 * best.wall_time / s.steps,
                tip=best.node_displacement(beam.last_node)[-1],
                newton=s.newton_iterations, jac=s.factorizations)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t-end", type=float, default=0.5)
    ap.add_argument("--dt", type=float, default=1e-3)
    ap.add_argument("--sizes", type=int, nargs="+", default=[8, 32, 128])
    ap.add_argument("--no-scaling", action="store_true")
    args = ap.parse_args(argv)
    run_flexmbs(4, t_end=0.01)  # compile / load numba caches outside the timing
    have_exu = exudyn_available()
    if not have_exu:
        print("exudyn not installed (pip install exudyn): flexmbs column only")
    print(f"dynamic cantilever, h = {args.dt}, t_end = {args.t_end}, rho_inf = 0.8, "
          "modified Newton, rtol 1e-8")
    print(f"{'N':>5} {'flexmbs us/step':>16} {'Exudyn us/step':>15} {'ratio':>7} "
          f"{'flexmbs it/jac':>15} {'Exudyn it/jac':>14} {'tip z flexmbs':>15} {'tip z Exudyn':>14}")
    for n in args.sizes:
        f = run_flexmbs(n, h=args.dt, t_end=args.t_end, repeats=2)
        if have_exu:
            e = min((run_exudyn_cantilever(n, h=args.dt, t_end=args.t_end) for _ in range(2)),
                    key=lambda d: d["us_per_step"])
            ratio = f["us_per_step"] / e["us_per_step"]
            print(f"{n:5d} {f['us_per_step']:16.1f} {e['us_per_step']:15.1f} {ratio:7.2f} "
                  f"{f['newton']:>7d}/{f['jac']:<7d} {e['newton_iterations_total']!s:>6}/"
                  f"{e['jacobian_updates']!s:<7} {f['tip'][2]:15.8e} {e['tip_displacement'][2]:14.8e}")
        else:
            print(f"{n:5d} {f['us_per_step']:16.1f} {'-':>15} {'-':>7} {f['newton']:>7d}/{f['jac']:<7d}"
                  f" {'-':>14} {f['tip'][2]:15.8e}")
    if not args.no_scaling:
        Ns = [16, 64, 256, 1024]
        ts = []
        for n in Ns:
            r = run_flexmbs(n, h=args.dt, t_end=min(args.t_end, 0.1))
            ts.append(r["us_per_step"])
            print(f"scaling N = {n:5d}: {r['us_per_step']:9.1f} us/step "
                  f"({r['us_per_step'] / n:6.2f} us/element/step)")
        k = np.polyfit(np.log(Ns), np.log(ts), 1)[0]
        print(f"cost per step ~ N^{k:.2f} (N = {Ns[0]}..{Ns[-1]})")
    return 0


if __name__ == "__main__":
    t0 = time.perf_counter()
    rc = main()
    print(f"benchmark wall time {time.perf_counter() - t0:.1f} s")
    raise SystemExit(rc)

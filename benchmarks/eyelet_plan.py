"""The eyelet wire's factorisation with a plan of the matrix's current nonzeros (issue 37).

A ring's slide coordinate and multipliers reserve entries along the whole beam (the ring may
slide anywhere), so the plan puts them in the dense border: 4 unknowns per ring, a Schur
complement of 4 N_rings. At any moment only the ring's current element is coupled. This
script runs the wire of ``chain.build_eyelets`` for 0.02 s, takes its iteration matrix, drops
the reserved entries that are zero at that state (ring x beam outside the ring's element), plans
the rest (``plan_factorization``, which then chooses no border) and times the bordered banded
factorisation and one solve of both plans inside numba (best of 5), checking both against
SuperLU. It measures what a plan that follows the rings (re-planned when a ring leaves the
elements it was planned on) would gain; the run loop does not do that yet.

    python benchmarks/eyelet_plan.py [--eyelets 10 25 50 100]
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import flexmbs as fm
from flexmbs import driver
from flexmbs.linalg.bordered import BorderedBandedLU
from flexmbs.linalg.ordering import plan_factorization
from flexmbs.terms import dynamic_mode

ROOT = Path(__file__).resolve().parent
sys.path.insert(0, str(ROOT))
from unit_loops import best_of, loop_factorize, loop_solve  # noqa: E402


def measure(n_eyelets: int) -> dict:
    from chain import build_eyelets

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = fm.simulate(build_eyelets(n_eyelets), t_end=0.02, dt=1e-3, output_interval=0.02,
                          record_energy=False,
                          integrator=fm.GeneralizedAlpha(rho_inf=0.8, adaptive=False))
    asm, st = res.assembly, res.final_state
    h, beta, gamma = 1e-3, 0.3025, 0.6          # generalized-alpha's at rho_inf = 0.8 (about)
    data = np.zeros_like(asm.matrix.data)
    driver.jacobian(asm.kernel_system, st.q, st.v, st.qdd, st.lam,
                    asm.functions.table(st.t, h, 1)[0], dynamic_mode(), 1.0 / (beta * h * h),
                    gamma / (beta * h), 1.0, data)
    n, size = asm.n_coords, asm.n_total
    A = asm.matrix.copy()
    A.data[:] = data
    rhs = np.random.default_rng(0).standard_normal(size)
    ref = spla.splu(A.tocsc()).solve(rhs)
    x = np.zeros(size)
    out: dict = {"unknowns": size}
    plan = asm.factor_plan()
    lu = plan.factorization(asm.matrix)
    assert lu.factorize(data)
    out["now"] = (plan.border.size, plan.bandwidth, best_of(loop_factorize, (lu.factor, data), 50, 5),
                  best_of(loop_solve, (lu.factor, rhs, x), 50, 5),
                  float(np.abs(lu.solve(rhs) - ref).max() / np.abs(ref).max()))
    # the rings' unknowns (slide coordinates, multipliers) against the beam's coordinates
    coo = asm.matrix.tocoo()
    ring = np.zeros(size, bool)
    for obj in asm.model.interactions:
        ring[np.asarray(asm.extra_dofs(obj), np.int64)] = True
    for nl in asm.nonlinear:
        ring[n + np.asarray(nl.rows, np.int64)] = True
    beam = np.zeros(size, bool)
    beam[:n] = True
    beam[asm.body_dof_table.ravel()] = False
    reserved = (ring[coo.row] & beam[coo.col]) | (beam[coo.row] & ring[coo.col])
    keep = ~reserved | (data != 0.0)
    shape = (size, size)
    pattern = sp.csc_matrix((np.ones(int(keep.sum())), (coo.row[keep], coo.col[keep])), shape)
    values = sp.csc_matrix((data[keep], (coo.row[keep], coo.col[keep])), shape)
    pattern.sort_indices()
    values.sort_indices()
    plan2 = plan_factorization(pattern, asm.border_indices(), n, asm.coordinate_owners())
    lu2 = BorderedBandedLU(pattern, plan2.border, plan2.order)
    assert lu2.factorize(values.data)
    out["current"] = (plan2.border.size, plan2.bandwidth,
                      best_of(loop_factorize, (lu2.factor, values.data), 50, 5),
                      best_of(loop_solve, (lu2.factor, rhs, x), 50, 5),
                      float(np.abs(lu2.solve(rhs) - ref).max() / np.abs(ref).max()))
    out["dropped"] = int((~keep).sum())
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--eyelets", type=int, nargs="+", default=[10, 25, 50, 100])
    args = ap.parse_args(argv)
    print("eyelet wire (100 elements) at t = 0.02 s: factorisation and solve [us], best of 5;"
          " 'now' = the plan of the reserved pattern, 'current' = of the current nonzeros")
    print(f"{'rings':>5s} {'unknowns':>8s} | {'border':>6s} {'w':>3s} {'factor':>9s} "
          f"{'solve':>7s} {'err':>8s} | {'border':>6s} {'w':>3s} {'factor':>8s} {'solve':>6s} "
          f"{'err':>8s}")
    for k in args.eyelets:
        r = measure(k)
        a, b = r["now"], r["current"]
        print(f"{k:5d} {r['unknowns']:8d} | {a[0]:6d} {a[1]:3d} {a[2]:9.1f} {a[3]:7.1f} "
              f"{a[4]:8.1e} | {b[0]:6d} {b[1]:3d} {b[2]:8.1f} {b[3]:6.1f} {b[4]:8.1e}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

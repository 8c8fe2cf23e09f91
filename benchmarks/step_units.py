"""Unit costs of a compiled step: the dynamic cantilever (8 and 32 elements) and Example 1.

Each model integrates a few steps, then numba loops (compiled without reference counting, like
the compiled entry; best of 7 repeats of 1000 calls) time at that state: the element groups'
tangent alone (``groups``), the whole iteration matrix (``matrix``), the residual, the
bordered banded factorisation and one solve. The step costs about
``residuals x residual + solves x solve + refreshes x (matrix + factorisation)`` (counts per
step: ``cantilever.py``, ``contact.py``). ``--root DIR`` times another checkout (a worktree
of an earlier commit, for before/after runs alternating in one session).

    python benchmarks/step_units.py [--root DIR]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--root", type=Path, default=HERE.parent,
                    help="the checkout whose flexmbs is timed (default: this one)")
    args = ap.parse_args(argv)
    sys.path.insert(0, str(args.root))
    sys.path.insert(0, str(HERE))

    from cantilever import build_flexmbs
    from unit_loops import best_of, loop_factorize, loop_matrix, loop_residual, loop_solve

    import flexmbs as fm
    from flexmbs import driver as cm
    from flexmbs._jit import njit
    from flexmbs.assembly import Assembly
    from flexmbs.elements.group import groups_jacobian
    from flexmbs.io.scenario import load_scenario
    from flexmbs.terms import dynamic_mode

    @njit(refcount=False)
    def loop_groups(parts, q, v, qdd, mode, data, n):
        for _ in range(n):
            groups_jacobian(parts, q, v, qdd, mode, 1.0, 0.05, 1e-8, data)

    print(f"flexmbs from {Path(fm.__file__).parent}; unit costs [us], best of 7 x 1000 calls")
    print(f"{'model':14s} {'groups':>7s} {'matrix':>7s} {'residual':>9s} {'factor':>7s} "
          f"{'solve':>6s}   band")

    def units(name: str, model: fm.Model, t_end: float, dt: float, **kw: object) -> None:
        asm = Assembly(model)
        res = fm.simulate(asm, t_end=t_end, dt=dt, output_interval=t_end, record_energy=False,
                          **kw)
        st = res.final_state
        m = asm.kernel_system
        mode = dynamic_mode()
        fv = asm.functions.table(st.t, dt, 1)[0]
        r = np.zeros(asm.n_total)
        x = np.zeros_like(r)
        data = np.zeros_like(asm.matrix.data)
        cm.jacobian(m, st.q, st.v, st.qdd, st.lam, fv, mode, 1.0, 0.05, 1e-8, data)
        lu = asm.factor_plan().factorization(asm.matrix)
        lu.factorize(data)
        n = 1000
        cols = (best_of(loop_groups, (m.beams, st.q, st.v, st.qdd, mode, data), n),
                best_of(loop_matrix, (m, st.q, st.v, st.qdd, st.lam, fv, mode, data), n),
                best_of(loop_residual, (m, st.q, st.v, st.qdd, st.lam, fv, mode, r), n),
                best_of(loop_factorize, (lu.factor, data), n),
                best_of(loop_solve, (lu.factor, r, x), n))
        print(f"{name:14s} {cols[0]:7.2f} {cols[1]:7.2f} {cols[2]:9.2f} {cols[3]:7.2f} "
              f"{cols[4]:6.2f}   n_a = {lu.n_band}, kl = ku = {lu.kl}, border {lu.n_border}",
              flush=True)

    for n_elem in (8, 32):
        model, _ = build_flexmbs(n_elem)
        units(f"cantilever {n_elem}", model, 0.05, 1e-3)
    sc = load_scenario(args.root / "examples" / "curved_beam_sleeve.toml")
    units("Example 1", sc.model, 0.005, 1e-4, initial_static=sc.simulation.initial_static,
          static_options=sc.static_options())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

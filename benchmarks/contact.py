"""Where a step of Example 1 goes: unit costs of the compiled integrator, and the step model.

Loads examples/curved_beam_sleeve.toml (with clearance) and the clearance-free variant,
integrates 0.05 s, then times inside numba (no Python dispatch; best of 7 repeats of 300
calls) the pieces a compiled step is made of: the residual (and its clearance-joint part: the
detection of all hole sections and the forces of the penetrating points), the iteration matrix,
the bordered banded factorisation and one solve. A 0.5 s run then gives the counts per step
(residuals, iterations = solves, refreshes), and ``counts x unit costs`` is compared with the
measured time per step (the rest is the predictor, corrector, post-step and Python per chunk).
The timing loops compile without reference counting, like the compiled entry
(``kernel.kernel``) that runs the real step. With reference counting, every call passing the
system's tuples of arrays paid 6-10 µs per residual that the step itself does not pay.

    python benchmarks/contact.py [--t-end 0.5]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
from unit_loops import best_of, loop_factorize, loop_solve  # noqa: E402


def _best(fn, args, n: int = 300) -> float:
    """Best of 7 repeats, microseconds per call."""
    return best_of(fn, args, n)


def main(argv: list[str] | None = None) -> int:
    import flexmbs as fm
    from flexmbs import driver as cm
    from flexmbs._jit import FLAG, njit
    from flexmbs.assembly import Assembly
    from flexmbs.contact.clearance_term import _joint_forces
    from flexmbs.io.scenario import load_scenario
    from flexmbs.terms import dynamic_mode

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t-end", type=float, default=0.5)
    args = ap.parse_args(argv)

    @njit(refcount=False)
    def loop_residual(m, q, v, qdd, lam, fv, mode, r, n):
        for _ in range(n):
            cm.residual(m, q, v, qdd, lam, fv, mode, r)

    @njit(refcount=False)
    def loop_clearance(m, q, v, r, n):
        cl = m.clearance
        for _ in range(n):     # the clearance residual of joint 0, as the driver calls it
            _joint_forces(cl, 0, q, v, FLAG[0], r, cl.no_K, cl.no_C, cl.no_elem, cl.no_elem,
                          m.error)

    @njit(refcount=False)
    def loop_jacobian(m, q, v, qdd, lam, fv, mode, data, n):
        for _ in range(n):
            cm.jacobian(m, q, v, qdd, lam, fv, mode, 1.0, 0.05, 1e-8, data)

    print(f"Examples 1 (16 elements, 9 hole sections) and 2 (15 elements, 3 eyelets of 3 "
          f"sections; after its static solve): compiled unit costs [us], best of 7; "
          f"counts per step over {args.t_end} s at h = 1e-4")
    print("(joint) = the clearance joint's detection + forces with the default consistent "
          "detection, [paper] = with detection = \"paper\" (docs/theory.md §II.4b)")
    print(f"{'model':20s} {'residual':>9s} {'(joint)':>8s} {'[paper]':>8s} {'matrix':>8s} "
          f"{'factor':>8s} "
          f"{'solve':>7s} | {'res/st':>6s} {'it/st':>6s} {'ref/st':>7s} | {'model':>7s} "
          f"{'measured':>9s} us/step")
    for toml in ("curved_beam_sleeve.toml", "curved_beam_sleeve_ideal.toml",
                 "solar_array_wing.toml"):
        sc = load_scenario(ROOT / "examples" / toml)
        asm = Assembly(sc.model)
        res = fm.simulate(asm, t_end=0.05, dt=1e-4, output_interval=0.05, record_energy=False,
                          initial_static=sc.simulation.initial_static,
                          static_options=sc.static_options())
        st = res.final_state
        # the kernel's view (optional features it does not use are None and compiled out, as in
        # the real step); the paper's detection needs the Python view, which has every feature
        m = asm.kernel_system
        full = asm.system
        mode = dynamic_mode()
        fv = asm.functions.table(st.t, 1e-4, 1)[0]
        r = np.zeros(asm.n_total)
        x = np.zeros_like(r)
        data = np.zeros_like(asm.matrix.data)
        cm.jacobian(m, st.q, st.v, st.qdd, st.lam, fv, mode, 1.0, 0.05, 1e-8, data)
        lu = asm.factor_plan().factorization(asm.matrix)     # the plan the run uses
        lu.factorize(data)
        u_res = _best(loop_residual, (m, st.q, st.v, st.qdd, st.lam, fv, mode, r))
        u_joint = u_paper = u_res_paper = u_jac_paper = float("nan")
        if m.clearance is not None:
            u_joint = _best(loop_clearance, (m, st.q, st.v, r))
            full.clearance.consistent[:] = False
            u_paper = _best(loop_clearance, (full, st.q, st.v, r))
            u_res_paper = _best(loop_residual, (full, st.q, st.v, st.qdd, st.lam, fv, mode, r))
            u_jac_paper = _best(loop_jacobian, (full, st.q, st.v, st.qdd, st.lam, fv, mode, data))
            full.clearance.consistent[:] = True
        u_jac = _best(loop_jacobian, (m, st.q, st.v, st.qdd, st.lam, fv, mode, data))
        u_fac = _best(loop_factorize, (lu.factor, data))
        u_sol = _best(loop_solve, (lu.factor, r, x))
        run = fm.simulate(load_scenario(ROOT / "examples" / toml).model, t_end=args.t_end,
                          dt=1e-4, output_interval=args.t_end, record_energy=False,
                          initial_static=sc.simulation.initial_static,
                          static_options=sc.static_options())
        s = run.stats
        per = s.residual_evaluations / s.steps, s.newton_iterations / s.steps, \
            s.factorizations / s.steps
        model = per[0] * u_res + per[1] * u_sol + per[2] * (u_jac + u_fac)
        print(f"{sc.name:20s} {u_res:9.1f} {u_joint:8.1f} {u_paper:8.1f} {u_jac:8.1f} "
              f"{u_fac:8.1f} {u_sol:7.1f} "
              f"| {per[0]:6.2f} {per[1]:6.2f} {per[2]:7.3f} | {model:7.1f} "
              f"{1e6 * run.wall_time / s.steps:9.1f}")
        if m.clearance is not None:
            print(f"{'  paper detection':20s} {u_res_paper:9.1f} {u_paper:8.1f} {'':8s} "
                  f"{u_jac_paper:8.1f}")
    print(f"(band: n_a = {lu.n_band}, kl = ku = {lu.kl}, border n_b = {lu.n_border}; "
          "'measured' includes numba cache loading on the first run of a process)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

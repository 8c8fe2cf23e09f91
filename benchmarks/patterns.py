"""Reserved, planned and instantaneous non-zeros of the iteration matrix (issue 52, item 1).

For each model: the entries the pattern stores (*reserved*: every joint against its whole
beam), those a plan that follows the contacts reads (*planned*: each clearance joint's hole
body and each sliding joint's slide coordinate and multipliers held against its beam only on
the elements around where it is, :meth:`flexmbs.assembly.Assembly.contact_windows`), and
those that are non-zero in the iteration matrix at one state (*instantaneous*: after a few
steps). Also the plans' kinds and estimated costs, fixed and following.

    python benchmarks/patterns.py [--robot-disks 20]
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))

import flexmbs as fm  # noqa: E402
from flexmbs.assembly import Assembly  # noqa: E402
from flexmbs.io.scenario import load_scenario  # noqa: E402
from flexmbs.kernel import OP_JACOBIAN  # noqa: E402
from flexmbs.terms import dynamic_mode  # noqa: E402


def _kind(plan) -> str:
    if plan.sparse:
        return "sparse (KLU)"
    return f"band {plan.bandwidth}, border {plan.border.size}" + (
        f", tree {plan.tree.size}" if plan.tree is not None else "")


def measure(name: str, model: fm.Model, t_end: float, dt: float, **kw: object) -> None:
    asm = Assembly(model)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = fm.simulate(asm, t_end=t_end, dt=dt, output_interval=t_end, record_energy=False,
                          **kw)
    st = res.final_state
    fixed = asm.factor_plan()
    windows = asm.contact_windows(1)
    following = asm.factor_plan(windows=windows) if windows is not None else None
    asm.follow(windows)
    data = np.zeros_like(asm.matrix.data)
    asm._kernel(OP_JACOBIAN, st.q, st.v, st.qdd, st.lam, asm.functions.values(st.t),
                dynamic_mode(), data, (1.0, 0.05, 1e-8))
    asm.follow(None)
    planned = following.keep.sum() if following is not None and following.keep is not None \
        else asm.matrix.nnz
    print(f"{name:24s} {asm.n_total:6d} {asm.matrix.nnz:10d} {int(planned):9d} "
          f"{int(np.count_nonzero(data)):9d}   fixed: {_kind(fixed)} ({fixed.cost:.3g})"
          + ("" if following is None else
             f"; following: {_kind(following)} ({following.cost:.3g})"), flush=True)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--robot-disks", type=int, default=20)
    a = ap.parse_args(argv)
    from chain import build_eyelets
    from tendon_robot import build

    print(f"{'model':24s} {'unknowns':>6s} {'reserved':>10s} {'planned':>9s} {'instant':>9s}")
    model, _ = build(a.robot_disks)
    measure(f"tendon robot, {a.robot_disks} disks", model, 0.01, 1e-3,
            integrator=fm.GeneralizedAlpha(rho_inf=0.5))
    root = HERE.parent / "examples"
    for scenario, t_end, dt in (("solar_array_wing.toml", 0.01, 1e-3),
                                ("guide_wire.toml", 0.01, 2e-4)):
        sc = load_scenario(root / scenario)
        measure(scenario.replace(".toml", ""), sc.model, t_end, dt,
                integrator=sc.integrator_options(), initial_static=sc.simulation.initial_static,
                static_options=sc.static_options())
    model = build_eyelets(50)
    measure("50-ring wire", model, 0.01, 1e-3)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

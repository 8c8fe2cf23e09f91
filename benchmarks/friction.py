"""Example 1 with friction: the stick law against the regularised one (issue "friction that
sticks", Measure and report).

Runs examples/curved_beam_sleeve.toml with μ = 0.3 in-process (``fm.simulate`` on the loaded
scenario, no output folder) for each case and prints steps, rejected steps, Newton iterations
per step, wall time, where the sleeve stops and how far it moves afterwards:

- ``regularised``: the rate law (ε_v = 1e-3 m/s), the former behaviour;
- ``stick``: the stick law at the default tangential stiffness (the normal stiffness, 1e6 N/m),
  and at 1e5 and 1e7 N/m (the stiffness's effect on Newton and on the step);
- each on the rail as given (no structural damping: it rings after the sleeve stops) and with
  stiffness-proportional rail damping 1e-3 s (``--damped-only`` / ``--undamped-only``).

A warm-up run compiles first (not timed). The step size is the scenario's (1e-4 s) unless
``--dt`` is given: the integrator cuts a step only when Newton fails, so the stiffness shows in
the iterations and rejected steps at larger steps.

    python benchmarks/friction.py [--t-end 3] [--dt 1e-4 4e-4]
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = ROOT / "examples" / "curved_beam_sleeve.toml"


def run(law: str, stiffness: float | None, damped: bool, dt: float | None,
        t_end: float) -> dict:
    """One run; returns its statistics and the sleeve's stop and drift."""
    import flexmbs as fm
    from flexmbs.io.scenario import load_scenario

    over = ["joints.sleeve.contact.friction=0.3"]
    if law == "regularised":
        over.append("joints.sleeve.contact.friction_velocity=1e-3")
    elif stiffness is not None:
        over = [f"joints.sleeve.contact.friction={{ mu = 0.3, stiffness = {stiffness:g} }}"]
    if damped:
        over.append("beams.rail.damping=1e-3")
    sc = load_scenario(SCENARIO, overrides=over)
    (joint,) = sc.model.interactions
    step = dt if dt is not None else sc.simulation.dt
    t0 = time.perf_counter()
    res = fm.simulate(sc.model, t_end=t_end, dt=step, integrator=sc.integrator_options(),
                      output_interval=0.1, record_energy=False)
    wall = time.perf_counter() - t0
    s = np.array([joint.slide_coordinate(q) for q in res.q])
    late = s[res.t >= 1.5 - 1e-9]
    st = res.stats
    return {"wall": wall, "steps": st.steps, "rejected": st.rejected_steps,
            "newton": st.newton_iterations / max(st.steps, 1),
            "stop_deg": math.degrees(late[0] - math.pi / 4) if late.size else math.nan,
            "drift": float(np.abs(late - late[0]).max()) if late.size else math.nan,
            "k_t": joint.friction_stiffness()}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--t-end", type=float, default=3.0)
    ap.add_argument("--dt", type=float, nargs="*", default=[None])
    ap.add_argument("--damped-only", action="store_true")
    ap.add_argument("--undamped-only", action="store_true")
    a = ap.parse_args(argv)
    run("stick", None, True, None, 0.01)          # compile (not timed)
    rails = [True] if a.damped_only else [False] if a.undamped_only else [False, True]
    cases = [("regularised", None), ("stick", None), ("stick", 1e5), ("stick", 1e7)]
    print(f"Example 1, mu = 0.3, t_end = {a.t_end} s; drift = largest |s - s(1.5 s)| after 1.5 s")
    print(f"{'rail':9s} {'law':12s} {'k_t N/m':>8s} {'dt':>7s} {'steps':>6s} {'rej':>4s} "
          f"{'it/step':>7s} {'wall s':>7s} {'stop deg':>8s} {'drift m':>9s}")
    for damped in rails:
        for dt in a.dt:
            for law, k in cases:
                r = run(law, k, damped, dt, a.t_end)
                kt = "-" if law == "regularised" else f"{r['k_t']:.0e}"
                print(f"{'damped' if damped else 'as given':9s} {law:12s} {kt:>8s} "
                      f"{dt if dt is not None else 1e-4:7.0e} {r['steps']:6d} {r['rejected']:4d} "
                      f"{r['newton']:7.2f} {r['wall']:7.2f} {r['stop_deg']:8.2f} "
                      f"{r['drift']:9.2e}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

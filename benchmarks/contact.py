"""Cost of the clearance-joint narrow phase on a realistic state of Example 1.

Loads examples/curved_beam_sleeve.toml, integrates 0.05 s, then times (after warm-up):
the compiled detection of all 9 hole sections (crossing, ellipse, broad phase, stationary points,
closest-point projection), one contact-point evaluation (gap, force, consistent tangent), the
joint's residual contribution with and without the tangent, the whole assembled residual, and
the wall time per step of a 0.1 s run.

    python benchmarks/contact.py
"""

from __future__ import annotations

import sys
import timeit
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def _us(f, n: int = 2000) -> float:  # noqa: ANN001
    return 1e6 * min(timeit.repeat(f, number=n, repeat=3)) / n


def main() -> int:
    import flexmbs as fm  # noqa: I001
    from flexmbs.contact._detect import detect_circle
    from flexmbs.contact.pair import contact_point
    from flexmbs.io.scenario import load_scenario

    sc = load_scenario(ROOT / "examples" / "curved_beam_sleeve.toml")
    res = fm.simulate(sc.model, t_end=0.05, dt=1e-4, record_energy=False, output_interval=0.05)
    asm, st = res.assembly, res.final_state
    (j,) = sc.model.interactions
    n, m = asm.n_coords, asm.n_mult
    qb = st.q[j._body_dofs]
    A, centre, *_ = j._frames(qb)
    qe = np.ascontiguousarray(st.q[j._elem_dofs])
    R = float(j.hole.section.radius)

    def detect() -> int:
        return detect_circle(qe, j._lengths, centre, A, j.stations, j._elem, j._xi, j._elem_out,
                             j._xi_out, j.beam_radius, R, j._rows)

    n_active = detect()
    row = j._rows[0]
    eP = int(row[3])
    u_Q = A.T @ (row[5:8] - qb[:3])
    ed = j._elem_dofs[eP]

    def pair(consistent: bool) -> object:
        return contact_point(qb, st.v[j._body_dofs], u_Q, st.q[ed], st.v[ed], j._lengths[eP],
                             row[4], j.beam_radius, j.contact, None, 0.0, consistent)

    rq, rl = np.zeros(n), np.zeros(m)
    t_detect = _us(detect)
    t_pair = _us(lambda: pair(False))
    t_pair_c = _us(lambda: pair(True))
    t_joint = _us(lambda: j.evaluate(asm, st.q, st.v, st.lam, 0.05, rq, None))
    t_eval = _us(lambda: asm.evaluate(st.q, st.v, st.qdd, st.lam, 0.05, rq, rl))
    sc2 = load_scenario(ROOT / "examples" / "curved_beam_sleeve.toml")
    run = fm.simulate(sc2.model, t_end=0.1, dt=1e-4, record_energy=False, output_interval=0.1)
    s = run.stats
    print(f"Example 1 state at t = 0.05 s: {len(j.stations)} sections, {n_active} penetrating "
          "contact points")
    print(f"{'detection of all sections (compiled)':48s} {t_detect:8.2f} us "
          f"({t_detect / len(j.stations):.2f} us per section)")
    print(f"{'one contact point, Gauss-Newton tangent':48s} {t_pair:8.2f} us")
    print(f"{'one contact point, consistent tangent':48s} {t_pair_c:8.2f} us")
    print(f"{'joint residual (detection + active points)':48s} {t_joint:8.2f} us "
          f"({(t_joint - t_detect) / max(n_active, 1):.1f} us per active point)")
    print(f"{'assembled residual (beam, body, joint)':48s} {t_eval:8.2f} us")
    print(f"{'0.1 s run':48s} {1e6 * run.wall_time / s.steps:8.1f} us/step, "
          f"{s.newton_iterations / s.steps:.2f} Newton iterations/step, {s.factorizations} "
          "factorisations")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Cost of a bore with many sections (issue 30, "many sections, cheap").

1. Per step against the number of sections at a fixed contact count: a wire (r = 0.5 mm,
   20 elements, 120 mm, clamped) lies 20 mm deep in a straight open tube (R = 0.8 mm, one section
   per mm) under gravity, so 21 sections carry its contacts whatever the tube's length; the
   tube is 0.1, 1 and 10 m long (100, 1 000, 10 000 sections). Far sections should cost
   (almost) nothing: the section tree puts each element's bounding sphere to the sections.
2. A 200-element wire all through a 1 000-section curved tube (a quarter circle, radius
   0.2 m): steps per second, and the detection per crossed section.

    python benchmarks/tube.py [--steps 200]
"""

from __future__ import annotations

import argparse
import math
import time
import warnings

import numpy as np

import flexmbs as fm

STEEL = fm.Material(E=2e11, rho=7800.0)


def _run(model: fm.Model, steps: int, dt: float) -> tuple[float, float]:
    """Seconds per step and the run's fixed cost (set-up, packing), from runs of ``steps``
    and ``5 steps`` steps after a warm-up run of the same model."""
    times = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fm.simulate(model, t_end=5 * dt, dt=dt, output_interval=5 * dt, record_energy=False)
        for n in (steps, 5 * steps):
            t0 = time.perf_counter()
            fm.simulate(model, t_end=n * dt, dt=dt, output_interval=n * dt,
                        record_energy=False)
            times.append(time.perf_counter() - t0)
    per_step = (times[1] - times[0]) / (4 * steps)
    return per_step, times[0] - steps * per_step


def far_sections(length: float, steps: int) -> tuple[tuple[float, float], int]:
    model = fm.Model(name="tube", gravity=(0.0, 0.0, -9.81))
    wire = model.add_beam(fm.line((-0.1, 0, 0), (0.02, 0, 0), elements=20), name="wire",
                          section=fm.CircularSection(0.5e-3), material=STEEL)
    model.clamp(wire.first_node)
    tube = model.add_rigid_body(mass=1.0, inertia=(1, 1, 1), name="tube")
    model.fix_body(tube)
    n = round(length / 1e-3) + 1
    bore = fm.CurvedBore(fm.line((0, 0, 0), (length, 0, 0), elements=1), radius=0.8e-3,
                         sections=n)
    model.add_joint(fm.SlidingClearanceJoint(wire, tube, hole=bore,
                                             contact=fm.LinearPenalty(stiffness=1e5)))
    return _run(model, steps, 1e-4), n


def long_wire_model(n_el: int = 200, sections: int = 1000
                    ) -> tuple[fm.Model, fm.SlidingClearanceJoint]:
    """A wire of ``n_el`` elements lying all along a quarter-circle tube (radius 0.2 m) of
    ``sections`` sections under gravity (also ``step_profile.py``'s ``tube_wire``)."""
    rho = 0.2
    s = np.linspace(0.0, math.pi / 2, n_el + 1)
    pts = np.column_stack([rho * np.sin(s), rho * (1 - np.cos(s)), np.zeros_like(s)])
    tans = np.column_stack([np.cos(s), np.sin(s), np.zeros_like(s)])
    model = fm.Model(name="tube", gravity=(0.0, 0.0, -9.81))
    wire = model.add_beam(fm.polyline(pts, tans), name="wire",
                          section=fm.CircularSection(0.5e-3), material=STEEL)
    model.clamp(wire.first_node)
    tube = model.add_rigid_body(mass=1.0, inertia=(1, 1, 1), name="tube")
    model.fix_body(tube)
    arc = fm.arc((0, rho, 0), rho, (0.002, rho - math.sqrt(rho**2 - 0.002**2), 0),
                 math.pi / 2 - 0.02, normal=(0, 0, 1), elements=64)
    bore = fm.CurvedBore(arc, radius=0.8e-3, sections=sections)
    joint = model.add_joint(fm.SlidingClearanceJoint(wire, tube, hole=bore,
                                                     contact=fm.LinearPenalty(stiffness=1e5)))
    return model, joint


def long_wire(steps: int) -> tuple[tuple[float, float], int, int, tuple[float, int, int]]:
    model, joint = long_wire_model()
    n_el, bore = 200, joint.hole
    res = _run(model, steps, 1e-4)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        states = fm.simulate(model, t_end=0.03, dt=1e-4, output_interval=1e-3,
                             record_energy=False).q
    # the wire falls onto the wall and bounces: the state with the most contact candidates
    sagged = max((np.ascontiguousarray(x) for x in states), key=joint.detect_rows)
    return res, n_el, bore.sections, detection(joint, sagged)


def detection(joint: fm.SlidingClearanceJoint, q: np.ndarray, calls: int = 200,
              ) -> tuple[float, int, int]:
    """The compiled narrow phase of all sections alone (``joint.detect_rows``: broad phase,
    crossings, ellipses, stationary points; no forces) at ``q`` (the wire fallen onto the
    wall): µs per crossed section, crossed sections, candidate rows."""
    m = joint.detect_rows(q)
    crossed = int(np.count_nonzero(np.asarray(joint._elem_out)[:len(joint.stations)] >= 0))
    t0 = time.perf_counter()
    for _ in range(calls):
        joint.detect_rows(q)
    return (time.perf_counter() - t0) / calls / crossed, crossed, m


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=200)
    a = ap.parse_args()
    print("| tube length | sections | µs per step | set-up per run |")
    print("|---|---|---|---|")
    for length in (0.1, 1.0, 10.0):
        (dt, fixed), n = far_sections(length, a.steps)
        print(f"| {length:g} m | {n} | {1e6 * dt:.1f} | {1e3 * fixed:.1f} ms |")
    (dt, fixed), n_el, ns, (per, crossed, rows) = long_wire(max(10, a.steps // 10))
    print(f"\n{n_el}-element wire through a {ns}-section quarter circle: "
          f"{1e6 * dt:.0f} µs per step, {1 / dt:.0f} steps per second; detection "
          f"{1e6 * per:.2f} µs per crossed section ({crossed} crossed, {rows} candidates, "
          "called from Python)")


if __name__ == "__main__":
    main()

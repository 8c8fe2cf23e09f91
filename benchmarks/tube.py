"""Cost of a bore with many sections (issue 30, "many sections, cheap").

1. Per step against the number of sections at a fixed contact count: a wire (r = 0.5 mm,
   20 elements, 120 mm, clamped) lies 20 mm deep in a straight open tube (R = 0.8 mm, one section
   per mm) under gravity, so 21 sections carry its contacts whatever the tube's length; the
   tube is 0.1, 1 and 10 m long (100, 1 000, 10 000 sections). Far sections should cost
   (almost) nothing: the section tree puts each element's bounding sphere to the sections.
2. A 200-element wire all through a 1 000-section curved tube (a quarter circle, radius
   0.2 m): steps per second, and the detection per crossed section.
3. A flexible tube against the rigid bore (issue 53, item 5): a wire (r = 0.5 mm, 40
   elements, 0.4 m, clamped) lies under gravity in a straight tube of 201 sections (R = 0.8
   mm), once a fixed rigid bore, once a beam (`fm.TubeJoint`, 20 elements, clamped at every
   node, so the same contacts). The joint's cost per step is the step's time less that of
   the same model without the joint (the beams alone), divided by the sections the wire
   crosses; the same for one evaluation of the residual and Newton's matrix (the joint's own
   work, without the factorisation), and the matrix's reserved non-zeros.
4. A 200-element wire in a 100-element flexible tube of 1 000 sections (the same geometry as
   3): the reserved and the planned non-zeros, one evaluation with the plan that follows the
   contacts in force, and the step (a Jacobian clears only what that plan reads).

    python benchmarks/tube.py [--steps 200] [--parts 1234]
"""

from __future__ import annotations

import argparse
import math
import sys
import time
import warnings
from pathlib import Path

import numpy as np

if __package__ in (None, ""):      # run as a script: the checkout's flexmbs (a second
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # checkout compares)

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


def _straight_wire(model: fm.Model, length: float) -> fm.Beam:
    wire = model.add_beam(fm.line((-0.005, 0, 0), (length + 0.005, 0, 0), elements=40),
                          name="wire", section=fm.CircularSection(0.5e-3), material=STEEL)
    model.clamp(wire.first_node)
    model.clamp(wire.last_node)
    return wire


def flexible_against_rigid(steps: int, length: float = 0.4, sections: int = 201
                           ) -> dict[str, float]:
    """µs per step of the rigid bore, the flexible tube and each without its joint, and the
    joints' µs per crossed section (the contacts: every section, the wire sagging onto the
    wall between its clamped ends)."""
    law = fm.LinearPenalty(stiffness=1e5)
    out: dict[str, float] = {}
    for kind in ("rigid", "flexible"):
        for with_joint in (False, True):
            model = fm.Model(name="tube", gravity=(0.0, 0.0, -9.81))
            wire = _straight_wire(model, length)
            if kind == "rigid":
                body = model.add_rigid_body(mass=1.0, inertia=(1, 1, 1), name="tube")
                model.fix_body(body)
                if with_joint:
                    bore = fm.CurvedBore(fm.line((0, 0, 0), (length, 0, 0), elements=1),
                                         radius=0.8e-3, sections=sections)
                    model.add_joint(fm.SlidingClearanceJoint(wire, body, hole=bore, contact=law))
            else:
                tube = model.add_beam(fm.line((0, 0, 0), (length, 0, 0), elements=20),
                                      name="tube", section=fm.CircularSection(2e-3),
                                      material=fm.Material(E=2e9, rho=1200.0))
                for node in range(tube.n_nodes):
                    model.clamp(tube.node(node))
                if with_joint:
                    model.add_joint(fm.TubeJoint(wire, tube, inner_radius=0.8e-3,
                                                 sections=sections, contact=law))
            key = f"{kind}{'' if with_joint else '_alone'}"
            out[key] = 1e6 * _run(model, steps, 1e-4)[0]
            (out[key + "_evaluation"], out[key + "_nnz"],
             out[key + "_planned"]) = _evaluation(model)
    for kind in ("rigid", "flexible"):
        for what in ("", "_evaluation"):
            out[f"{kind}{what}_per_section"] = (out[kind + what]
                                                - out[f"{kind}_alone{what}"]) / sections
    return out


def _evaluation(model: fm.Model, calls: int = 200) -> tuple[float, int, int]:
    """µs per evaluation of the residual and Newton's matrix at the state after 5 ms, the
    matrix's reserved non-zeros, and those a plan that follows the contacts there reads."""
    from flexmbs.assembly import Assembly

    asm = Assembly(model)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = fm.simulate(asm, t_end=5e-3, dt=1e-4, output_interval=5e-3, record_energy=False)
    q, v = res.q[-1], res.v[-1]
    n, m = asm.n_coords, asm.n_mult
    a, lam, rq, rl = np.zeros(n), np.zeros(m), np.zeros(n), np.zeros(m)
    t0 = time.perf_counter()
    for _ in range(calls):
        asm.evaluate(q, v, a, lam, 0.0, rq, rl, matrix=(1.0, 1.0, 1.0))
    per = 1e6 * (time.perf_counter() - t0) / calls
    windows = asm.contact_windows(1)
    planned = (asm.matrix.nnz if windows is None
               else int(np.count_nonzero(asm.factor_plan(windows=windows).keep)))
    return per, int(asm.matrix.nnz), planned


def large_pair(n_tube: int = 100, n_wire: int = 200, sections: int = 1000, steps: int = 50
               ) -> dict[str, float]:
    """A wire of ``n_wire`` elements sagging in a flexible tube of ``n_tube`` elements held at
    every node (``sections`` sections): the reserved and the planned non-zeros, µs per
    evaluation of the residual and Newton's matrix with the plan that follows the contacts in
    force (as the integrator has it), and ms per step of a run of ``steps`` steps (after one
    to warm up)."""
    from flexmbs.assembly import Assembly

    length = 0.4
    model = fm.Model(name="tube", gravity=(0.0, 0.0, -9.81))
    wire = model.add_beam(fm.line((-0.005, 0, 0), (length + 0.005, 0, 0), elements=n_wire),
                          name="wire", section=fm.CircularSection(0.5e-3), material=STEEL)
    model.clamp(wire.first_node)
    model.clamp(wire.last_node)
    tube = model.add_beam(fm.line((0, 0, 0), (length, 0, 0), elements=n_tube), name="tube",
                          section=fm.CircularSection(2e-3),
                          material=fm.Material(E=2e9, rho=1200.0))
    for node in range(tube.n_nodes):
        model.clamp(tube.node(node))
    model.add_joint(fm.TubeJoint(wire, tube, inner_radius=0.8e-3, sections=sections,
                                 contact=fm.LinearPenalty(stiffness=1e5)))
    asm = Assembly(model)
    t_end = steps * 1e-4
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fm.simulate(asm, t_end=t_end, dt=1e-4, output_interval=t_end, record_energy=False)
        t0 = time.perf_counter()
        res = fm.simulate(asm, t_end=t_end, dt=1e-4, output_interval=t_end,
                          record_energy=False)
        step = (time.perf_counter() - t0) / steps
    q, v = res.q[-1], res.v[-1]
    n, m = asm.n_coords, asm.n_mult
    a, lam, rq, rl = np.zeros(n), np.zeros(m), np.zeros(n), np.zeros(m)
    windows = asm.contact_windows(1)
    asm.follow(windows)
    calls = 100
    asm.evaluate(q, v, a, lam, 0.0, rq, rl, matrix=(1.0, 1.0, 1.0))
    t0 = time.perf_counter()
    for _ in range(calls):
        asm.evaluate(q, v, a, lam, 0.0, rq, rl, matrix=(1.0, 1.0, 1.0))
    per = (time.perf_counter() - t0) / calls
    planned = int(np.count_nonzero(asm.factor_plan(windows=windows).keep))
    asm.follow(None)
    return {"nnz": float(asm.matrix.nnz), "planned": float(planned),
            "evaluation_us": 1e6 * per, "step_ms": 1e3 * step}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--parts", default="1234", help="the parts to run, e.g. 3")
    a = ap.parse_args()
    if "1" in a.parts:
        print("| tube length | sections | µs per step | set-up per run |")
        print("|---|---|---|---|")
        for length in (0.1, 1.0, 10.0):
            (dt, fixed), n = far_sections(length, a.steps)
            print(f"| {length:g} m | {n} | {1e6 * dt:.1f} | {1e3 * fixed:.1f} ms |")
    if "2" in a.parts:
        (dt, fixed), n_el, ns, (per, crossed, rows) = long_wire(max(10, a.steps // 10))
        print(f"\n{n_el}-element wire through a {ns}-section quarter circle: "
              f"{1e6 * dt:.0f} µs per step, {1 / dt:.0f} steps per second; detection "
              f"{1e6 * per:.2f} µs per crossed section ({crossed} crossed, {rows} candidates, "
              "called from Python)")
    if "4" in a.parts:
        p = large_pair(steps=max(10, a.steps // 4))
        print(f"\n200-element wire in a 100-element tube, 1000 sections: {p['nnz']:.0f} reserved, "
              f"{p['planned']:.0f} planned non-zeros; evaluation {p['evaluation_us']:.0f} µs "
              f"(the following plan in force); {p['step_ms']:.2f} ms per step")
    if "3" not in a.parts:
        return
    c = flexible_against_rigid(a.steps)
    print("\n| bore | µs per step (without the joint) | per crossed section | evaluation µs "
          "(without) | per crossed section | reserved non-zeros (without) | planned, following |")
    print("|---|---|---|---|---|---|---|")
    for k in ("rigid", "flexible"):
        print(f"| {k} | {c[k]:.0f} ({c[k + '_alone']:.0f}) | {c[k + '_per_section']:.2f} | "
              f"{c[k + '_evaluation']:.0f} ({c[k + '_alone_evaluation']:.0f}) | "
              f"{c[k + '_evaluation_per_section']:.2f} | {c[k + '_nnz']:.0f} "
              f"({c[k + '_alone_nnz']:.0f}) | {c[k + '_planned']:.0f} |")
    for what in ("", "_evaluation"):
        print(f"flexible / rigid per crossed section{what.replace('_', ', ')}: "
              f"{c['flexible' + what + '_per_section'] / c['rigid' + what + '_per_section']:.2f}")


if __name__ == "__main__":
    main()

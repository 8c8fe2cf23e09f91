"""A tendon-driven continuum robot: the baseline cost of many short clearance joints.

A NiTi backbone (``ancf_rod14``, r = 0.7 mm, E = 54 GPa, 400 mm along z) is held rigidly
(twist included) by a fixed base plate at z = 0 and carries ``n_disks`` rigid disks (r = 15
mm, 2 mm thick, aluminium), equally spaced up to its tip, each held rigidly by the backbone
node at its height. Six steel tendons (cables, r = 0.08 mm) run straight along z 10 mm from
the backbone, at 90°, -30° and 210°: tendons 1-3 end at disk ``n_disks // 2``, tendons 4-6
(the same hole positions) at the last disk. Each passes a 1 mm bore (radius r + 0.02 mm,
3 sections) in the base plate and in every disk below its end disk (a
:class:`~flexmbs.SlidingClearanceJoint` per tendon and body, so tendons 1 and 4 share one hole
point through two joints: there is no contact between tendons), is held at its end disk by a
spherical joint and pulled at its lower end (20 mm below the plate, x and y held) by its
tension, a point load along -z ramped in over 0.3 s. Linear penalty contact, 1e6 N/m: under
the largest tension (2 N) the contact forces of the bent backbone are a fraction of a newton,
so the penetration stays at or below 1 µm, 5 % of the 20 µm clearance; the tendon's own axial
stiffness per element (EA/h ~ 5e5 N/m) is of the same order, so the matrix is no stiffer than
the tendon already makes it. No friction unless ``--mu``; no gravity.

Prints the size of the problem (unknowns, clearance joints, reserved nonzeros, the bordered
banded factorisation's plan), then either a static solve with load steps (``--static``,
where it fails) or ``--steps`` dynamic steps (generalized-alpha, rho_inf = 0.5) after a 2-step
warm-up on a fresh build of the same model (the compiled kernels are then loaded: the timed
run excludes the first call's compile).

    python benchmarks/tendon_robot.py [--disks 20] [--steps 20] [--dt 1e-3] [--static]
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

if __package__ in (None, ""):      # run as a script: the checkout's flexmbs
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import flexmbs as fm
from flexmbs.assembly import Assembly
from flexmbs.solvers.generalized_alpha import IntegrationStats, State

LENGTH = 0.4                   # backbone length [m]
ROD_R = 0.7e-3
NITI = fm.Material(E=54e9, rho=6450.0, nu=0.3)
TENDON_R = 0.08e-3
STEEL = fm.Material(E=200e9, rho=7850.0, nu=0.3)
CLEARANCE = 0.02e-3            # bore radius - tendon radius
HOLE_LENGTH, HOLE_SECTIONS = 1e-3, 3
PITCH_R = 10e-3                # tendon holes from the backbone axis
ANGLES = (90.0, -30.0, 210.0)  # degrees about z, tendons 1-3 and 4-6
LEAD = 20e-3                   # tendon length below the base plate
DISK_R, DISK_T, ALU = 15e-3, 2e-3, 2700.0
T_RAMP = 0.3                   # the tensions are ramped in over this time [s]
STIFFNESS = 1e6                # contact penalty [N/m]
#: default tendon element length [m]: 57 elements on the 420 mm tendons (30 on the 220 mm
#: ones), which puts the 20-disk model at 2 219 unknowns, near the issue's 2 210
TENDON_ELEMENT = (LEAD + LENGTH) / 57
#: body x = global z: a :class:`~flexmbs.Hole` runs along body x, so every plate and disk is
#: turned so that its bores (and its cylinder shape) run along the backbone
AXIS_Z = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])


def _disk(model: fm.Model, z: float, name: str) -> fm.RigidBody:
    m = ALU * math.pi * DISK_R**2 * DISK_T
    axial = 0.5 * m * DISK_R**2
    transverse = 0.25 * m * DISK_R**2 + m * DISK_T**2 / 12.0
    return model.add_rigid_body(
        mass=m, inertia=(axial, transverse, transverse),
        pose=fm.Pose((0.0, 0.0, z), AXIS_Z), name=name,
        shape={"type": "cylinder", "radius": DISK_R, "length": DISK_T})


def hole_angles(shift_long: float = 0.0) -> list[float]:
    """Angles [deg] of tendons 1..6 (tendons 4-6 turned by ``shift_long``)."""
    return list(ANGLES) + [a + shift_long for a in ANGLES]


def build(n_disks: int = 20, tensions: tuple[float, ...] = (0, 2, 0, 1, 0, 1), mu: float = 0.0,
          tendon_elements: int | None = None, *, stiffness: float = STIFFNESS,
          shift_long: float = 0.0, t_ramp: float = T_RAMP, rod_damping: float = 0.0,
          tendon_damping: float = 0.0, only: tuple[int, ...] | None = None,
          sections: int = HOLE_SECTIONS, tip_force: float = 0.0, onset: float = 0.0
          ) -> tuple[fm.Model, dict]:
    """The robot with ``n_disks`` disks (spacing 400 mm / n_disks, 2 backbone elements per
    spacing, tendons 1-3 ending at disk ``n_disks // 2``) and tendon ``tensions`` [N] (1..6).

    ``tendon_elements``: elements of each of tendons 4-6 (420 mm); tendons 1-3 get the same
    element length; None: elements of about :data:`TENDON_ELEMENT`. ``mu``: friction
    coefficient of every bore (0: none); ``stiffness``: the linear penalty [N/m];
    ``shift_long``: turn tendons 4-6 by that many degrees (0: they share the holes of 1-3);
    ``t_ramp``: the tensions' smooth ramp [s]; ``only``: build only these tendons (1..6);
    ``sections``: contact sections per bore; ``tip_force``: a force along +z at the backbone's
    tip [N], ramped as the tensions; ``onset``: the penalty's smooth onset [m]. Returns
    (model, handles): ``backbone``,
    ``plate``, ``disks``, ``tendons``, ``bores`` (per tendon its clearance joints),
    ``tension_loads`` (per tendon its load or None), ``ends`` (spherical joints), ``holds``."""
    if n_disks < 2:
        raise ValueError(f"n_disks must be >= 2 (got {n_disks})")
    tensions = tuple(float(t) for t in tensions)
    if len(tensions) != 6:
        raise ValueError(f"tensions: 6 values, tendons 1..6 (got {len(tensions)})")
    spacing = LENGTH / n_disks
    mid = n_disks // 2
    h = (LEAD + LENGTH) / tendon_elements if tendon_elements else TENDON_ELEMENT

    model = fm.Model(name=f"tendon_robot_{n_disks}", gravity=(0.0, 0.0, 0.0))
    backbone = model.add_beam(fm.line((0.0, 0.0, 0.0), (0.0, 0.0, LENGTH), elements=2 * n_disks),
                              section=fm.CircularSection(ROD_R), material=NITI,
                              element="ancf_rod14", damping=rod_damping, name="backbone")
    plate = _disk(model, 0.0, "plate")
    model.fix_body(plate, name="plate_fixed")
    model.rigid(backbone.first_node, plate, name="base_clamp")   # position, slope and twist
    disks = []
    for k in range(1, n_disks + 1):
        disk = _disk(model, k * spacing, f"disk{k}")
        model.rigid(backbone.node(2 * k), disk, name=f"mount{k}")
        disks.append(disk)

    friction = fm.Friction(mu=mu) if mu else None
    law = fm.LinearPenalty(stiffness=stiffness, onset=onset)
    tendons, bores, loads, ends, holds = [], [], [], [], []
    for i, angle in enumerate(hole_angles(shift_long)):
        if only is not None and i + 1 not in only:
            continue
        end = mid if i < 3 else n_disks
        a = math.radians(angle)
        x, y = PITCH_R * math.cos(a), PITCH_R * math.sin(a)
        z_end = end * spacing
        n_el = max(1, round((z_end + LEAD) / h))
        tendon = model.add_beam(fm.line((x, y, -LEAD), (x, y, z_end), elements=n_el),
                                section=fm.CircularSection(TENDON_R), material=STEEL,
                                damping=tendon_damping, name=f"tendon{i + 1}")
        joints = []
        for body in [plate, *disks[:end - 1]]:
            point = AXIS_Z.T @ (np.array([x, y, body.pose.position[2]]) - body.pose.position)
            joints.append(model.add_joint(fm.SlidingClearanceJoint(
                tendon, body, hole=fm.CircleHole(radius=TENDON_R + CLEARANCE,
                                                 length=HOLE_LENGTH, sections=sections),
                hole_point=point, contact=law, friction=friction,
                name=f"bore_t{i + 1}_{body.name}")))
        ends.append(model.spherical(tendon.last_node, disks[end - 1], name=f"anchor_t{i + 1}"))
        holds.append(model.prescribe(tendon.first_node, [0, 1], name=f"guide_t{i + 1}"))
        load = None
        if tensions[i]:
            load = model.add_point_load(
                tendon.first_node, (0.0, 0.0, -tensions[i]),
                function=fm.Ramp(start=0.0, end=t_ramp, value=1.0, smooth=True),
                name=f"tension_t{i + 1}")
        tendons.append(tendon)
        bores.append(joints)
        loads.append(load)
    if tip_force:
        model.add_point_load(backbone.last_node, (0.0, 0.0, tip_force),
                             function=fm.Ramp(start=0.0, end=t_ramp, value=1.0, smooth=True),
                             name="tip_force")
    return model, {"backbone": backbone, "plate": plate, "disks": disks, "tendons": tendons,
                   "bores": bores, "tension_loads": loads, "ends": ends, "holds": holds}


def describe(model: fm.Model) -> tuple[Assembly, dict]:
    """The assembly and its size: unknowns (coordinates + multipliers), clearance joints, the
    reserved pattern's nonzeros and the factorisation plan (dynamic: with mass)."""
    t0 = time.perf_counter()
    asm = Assembly(model)
    t_asm = time.perf_counter() - t0
    t0 = time.perf_counter()
    plan = asm.factor_plan()
    t_plan = time.perf_counter() - t0
    clearance = sum(isinstance(j, fm.SlidingClearanceJoint) for j in model.interactions)
    info = {"unknowns": int(asm.n_total), "coordinates": int(asm.n_coords),
            "multipliers": int(asm.n_mult), "clearance_joints": clearance,
            "nnz": int(asm.matrix.nnz), "border": int(plan.border.size),
            "bandwidth": int(plan.bandwidth), "cost": float(plan.cost),
            "tree": 0 if plan.tree is None else int(plan.tree.size),
            "assembly_s": t_asm, "plan_s": t_plan}
    return asm, info


class _OutOfTime(Exception):
    """Raised by the progress callback when the run's wall-time budget is spent."""


def run_dynamic(n_disks: int, steps: int, dt: float, *, warmup: int = 2, every: int = 10,
                max_wall: float | None = None, log: bool = False, retreats: int | None = None,
                hold: bool = False, **kw) -> dict:
    """``warmup`` steps on one build (compiles or loads the kernels), then ``steps`` steps
    on a fresh build, timed from the integration's start (the initial accelerations solved,
    the first output) to the last step, counters from the integrator; outputs (and progress
    lines with ``log``) every ``every`` steps; stops after ``max_wall`` seconds of
    integration (None: no limit). Generalized-alpha, rho_inf = 0.5, adaptive steps;
    ``retreats``: Newton's halvings of a rejected iterate (None: the default); ``hold``:
    Newton holds the contacts' active set through a step (``NewtonOptions.hold_contacts``)."""
    nk: dict[str, Any] = {"hold_contacts": hold}
    if retreats is not None:
        nk["retreats"] = retreats
    opts = fm.GeneralizedAlpha(rho_inf=0.5, newton=fm.NewtonOptions(**nk))
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if warmup:
            model, _ = build(n_disks, **kw)
            fm.simulate(model, t_end=warmup * dt, dt=dt, output_interval=warmup * dt,
                        integrator=opts, record_energy=False)
    t_warm = time.perf_counter() - t0
    model, handles = build(n_disks, **kw)
    asm = Assembly(model)
    tip = asm.node_dofs(handles["backbone"].last_node)[:3]
    mark: dict = {"start": None, "last": None, "stats": None, "t": 0.0, "tip": np.zeros(3)}

    def observer(state: State) -> None:
        now = time.perf_counter()
        if mark["start"] is None:
            mark["start"] = mark["last"] = now
        mark["tip"] = state.q[tip] - asm.q_ref[tip]

    def progress(state: State, st: IntegrationStats) -> None:
        now = time.perf_counter()
        mark.update(last=now, t=state.t, stats=dataclasses.replace(st))
        if log:
            print(f"  t = {state.t:.4f} s: {st.steps} steps, {st.rejected_steps} rejected, "
                  f"{st.newton_iterations} Newton, {st.factorizations} factorisations, "
                  f"{now - mark['start']:.2f} s", flush=True)
        if max_wall is not None and now - mark["start"] > max_wall:
            raise _OutOfTime

    t1 = time.perf_counter()
    status = "completed"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            res = fm.simulate(asm, t_end=steps * dt, dt=dt, output_interval=every * dt,
                              integrator=opts, record_energy=False, observer=observer,
                              progress=progress)
            mark["stats"], mark["t"] = res.stats, float(res.t[-1])
        except _OutOfTime:
            status = f"stopped at the wall-time budget ({max_wall:g} s)"
        except fm.ConvergenceError as exc:
            status = f"failed: {exc}"
    total = time.perf_counter() - t1
    s = mark["stats"] or IntegrationStats()
    wall = (mark["last"] or t1) - (mark["start"] or t1)
    return {"warmup_s": t_warm, "wall_s": wall, "simulate_s": total,
            "per_step_ms": 1e3 * wall / max(s.steps, 1), "steps": s.steps,
            "rejected": s.rejected_steps, "newton": s.newton_iterations,
            "factorizations": s.factorizations, "residuals": s.residual_evaluations,
            "replans": s.replans, "t": mark["t"], "tip_displacement": mark["tip"],
            "status": status}


def unit_costs(n_disks: int, t_end: float = 0.03, **kw) -> dict:
    """Unit costs [us] of a compiled step at the state after ``t_end`` (contacts closed):
    the iteration matrix, the residual, the factorisation of the plan the run uses (the one
    that follows the contacts) and one solve, each the best of 3 repeats of compiled loops
    (benchmarks/unit_loops.py); with the plan's kind and the planned entries."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from unit_loops import best_of, loop_factorize, loop_matrix, loop_residual, loop_solve

    from flexmbs import driver
    from flexmbs.terms import dynamic_mode

    model, _ = build(n_disks, **kw)
    asm = Assembly(model)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = fm.simulate(asm, t_end=t_end, dt=1e-3, output_interval=t_end, record_energy=False,
                          integrator=fm.GeneralizedAlpha(rho_inf=0.5))
    st = res.final_state
    m, mode = asm.kernel_system, dynamic_mode()
    fv = asm.functions.table(st.t, 1e-3, 1)[0]
    r = np.zeros(asm.n_total)
    x = np.zeros_like(r)
    data = np.zeros_like(asm.matrix.data)
    windows = asm.contact_windows(1)
    asm.follow(windows)
    plan = asm.factor_plan(windows=windows)
    driver.jacobian(m, st.q, st.v, st.qdd, st.lam, fv, mode, 1.0, 0.05, 1e-8, data)
    lu = plan.factorization(asm.matrix)
    lu.factorize(data)
    out = {"unknowns": asm.n_total, "planned": int(plan.keep.sum()), "sparse": plan.sparse,
           "matrix_us": best_of(loop_matrix, (m, st.q, st.v, st.qdd, st.lam, fv, mode, data), 20, 3),
           "residual_us": best_of(loop_residual, (m, st.q, st.v, st.qdd, st.lam, fv, mode, r), 50, 3),
           "factor_us": best_of(loop_factorize, (lu.factor, data), 10, 3),
           "solve_us": best_of(loop_solve, (lu.factor, r, x), 50, 3)}
    asm.follow(None)
    return out


def contact_units(n_disks: int, refined: bool = False, **kw) -> dict:
    """The clearance joints' share of a residual [us] at the straight robot's start (best of 3
    compiled loops of 50 calls of ``clearance_terms``) beside the whole residual's; ``refined``:
    tendons of 3 elements per disk spacing (their elements grow with the disks)."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from unit_loops import best_of, loop_clearance, loop_residual

    from flexmbs.terms import dynamic_mode

    if refined:
        kw["tendon_elements"] = 3 * n_disks
    model, _ = build(n_disks, **kw)
    asm = Assembly(model)
    q, v = asm.initial_state()
    m = asm.kernel_system
    fv = asm.functions.table(0.0, 1e-3, 1)[0]
    r = np.zeros(asm.n_total)
    error = np.zeros(4, np.int64)
    zeros = np.zeros_like(q)
    lam = np.zeros(asm.n_total - q.size)
    return {"joints": int(m.clearance.r_b.size), "tendon_elements": int(m.clearance.n_elem.max()),
            "residual_us": best_of(loop_residual, (m, q, v, zeros, lam, fv, dynamic_mode(), r), 50, 3),
            "clearance_us": best_of(loop_clearance, (m.clearance, q, v, r, error), 50, 3)}


def run_static(n_disks: int, load_steps: int, hold: bool = False, **kw) -> dict:
    """Static equilibrium under the full tensions (time ``t_ramp``) by load stepping; where
    it fails if it does. ``hold``: ``NewtonOptions.hold_contacts``."""
    model, handles = build(n_disks, **kw)
    asm = Assembly(model)
    t_full = kw.get("t_ramp", T_RAMP)
    opts = fm.StaticOptions(load_steps=load_steps)
    opts = dataclasses.replace(opts, newton=dataclasses.replace(opts.newton, hold_contacts=hold))
    t0 = time.perf_counter()
    out: dict = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            st = fm.solve_static(asm, opts, t=t_full)
        except fm.FlexmbsError as exc:
            out.update(status="failed", error=f"{type(exc).__name__}: {exc}")
        else:
            d = asm.node_dofs(handles["backbone"].last_node)[:3]
            out.update(status="converged", increments=st.load_increments,
                       newton=st.newton_iterations, tip_displacement=st.q[d] - asm.q_ref[d])
    out["wall_s"] = time.perf_counter() - t0
    return out


#: the issue's four static load cases (tensions of tendons 1..6 [N], tip force [N]) and two
#: with taut tendons only
STATIC_CASES = {
    "(0,2,0,1,0,1)": ((0, 2, 0, 1, 0, 1), 0.0, None),
    "(4,0,0,0,2,0)": ((4, 0, 0, 0, 2, 0), 0.0, None),
    "(2,0,0,0,2,0)": ((2, 0, 0, 0, 2, 0), 0.0, None),
    "(4,0,0,0,0,1)+0.1N": ((4, 0, 0, 0, 0, 1), 0.1, None),
    "t4 only, 1 N": ((0, 0, 0, 1, 0, 0), 0.0, (4,)),
    "t2,t4,t6 only": ((0, 2, 0, 1, 0, 1), 0.0, (2, 4, 6)),
}


def static_cases(disks: int, sections: int, load_steps: int = 10, onset: float = 0.0,
                 hold: bool = False) -> None:
    """Print the static solve of every :data:`STATIC_CASES` entry (a fresh build each)."""
    for name, (tensions, tip, only) in STATIC_CASES.items():
        r = run_static(disks, load_steps, hold, tensions=tensions, tip_force=tip, only=only,
                       sections=sections, onset=onset)
        what = (f"{r['increments']} increments, {r['newton']} iterations" if r["status"] ==
                "converged" else r["error"][:110])
        print(f"{disks:3d} disks, {sections} section(s), onset {onset:g}, {name:>20s}: "
              f"{r['status']:9s} "
              f"{r['wall_s']:7.2f} s  {what}", flush=True)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--disks", type=int, default=20)
    ap.add_argument("--steps", type=int, default=20)
    ap.add_argument("--dt", type=float, default=1e-3)
    ap.add_argument("--static", action="store_true", help="static solve instead of dynamics")
    ap.add_argument("--load-steps", type=int, default=10, help="static load increments")
    ap.add_argument("--mu", type=float, default=0.0, help="friction coefficient of the bores")
    ap.add_argument("--units", type=int, nargs="*", default=None, metavar="DISKS",
                    help="unit costs of a compiled step at these disk counts instead of a run")
    ap.add_argument("--contact-units", type=int, nargs="*", default=None, metavar="DISKS",
                    help="the clearance joints' cost per residual at these disk counts (tendons "
                         "as built and refined with the disks)")
    ap.add_argument("--hold", action="store_true",
                    help="Newton holds the contacts' active set through a step or increment "
                         "(NewtonOptions(hold_contacts=True))")
    ap.add_argument("--retreats", type=int, default=None,
                    help="Newton's halvings of an iterate the model rejects (default: the "
                         "integrator's)")
    ap.add_argument("--stiffness", type=float, default=STIFFNESS, help="contact penalty [N/m]")
    ap.add_argument("--tendon-elements", type=int, default=None,
                    help="elements of the 420 mm tendons (default 57: 7.4 mm elements)")
    ap.add_argument("--tensions", type=float, nargs=6, default=(0, 2, 0, 1, 0, 1))
    ap.add_argument("--every", type=int, default=10, help="steps between outputs")
    ap.add_argument("--max-wall", type=float, default=240.0,
                    help="stop the timed run after this many seconds (0: no limit)")
    ap.add_argument("--progress", action="store_true", help="print a line per output")
    ap.add_argument("--sections", type=int, default=HOLE_SECTIONS,
                    help="contact sections per bore (the issue: 3)")
    ap.add_argument("--onset", type=float, default=0.0,
                    help="the penalty's smooth onset [m] (LinearPenalty(onset=...))")
    ap.add_argument("--static-cases", action="store_true",
                    help="static solves of the issue's four load cases and two taut ones")
    ap.add_argument("--shift", type=float, default=0.0,
                    help="turn tendons 4-6 by this angle [deg] (0: share the holes of 1-3)")
    a = ap.parse_args(argv)
    kw = {"tensions": tuple(a.tensions), "mu": a.mu, "tendon_elements": a.tendon_elements,
          "stiffness": a.stiffness, "shift_long": a.shift, "sections": a.sections,
          "onset": a.onset}
    if a.static_cases:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model, _ = build(2, sections=a.sections)      # compile or load the kernels
            fm.solve_static(Assembly(model), fm.StaticOptions(load_steps=2), t=0.0)
        static_cases(a.disks, a.sections, a.load_steps, a.onset, hold=a.hold)
        return 0

    if a.contact_units:
        print(f"{'disks':>5s} {'tendons':>8s} {'joints':>6s} {'elements':>8s} {'residual':>8s} "
              f"{'contacts':>8s}  [us]")
        for d in a.contact_units:
            for refined in (False, True):
                u = contact_units(d, refined, **kw)
                print(f"{d:5d} {'refined' if refined else 'as built':>8s} {u['joints']:6d} "
                      f"{u['tendon_elements']:8d} {u['residual_us']:8.0f} "
                      f"{u['clearance_us']:8.0f}", flush=True)
        return 0
    if a.units:
        print(f"{'disks':>5s} {'unknowns':>8s} {'planned':>8s} {'plan':>6s} {'matrix':>8s} "
              f"{'residual':>8s} {'factor':>8s} {'solve':>7s}  [us]")
        for d in a.units:
            u = unit_costs(d, **kw)
            print(f"{d:5d} {u['unknowns']:8d} {u['planned']:8d} "
                  f"{'KLU' if u['sparse'] else 'band':>6s} {u['matrix_us']:8.0f} "
                  f"{u['residual_us']:8.0f} {u['factor_us']:8.0f} {u['solve_us']:7.0f}", flush=True)
        return 0
    model, handles = build(a.disks, **kw)
    _, info = describe(model)
    elements = [t.n_elem for t in handles["tendons"]]
    print(f"tendon robot, {a.disks} disks: {info['unknowns']} unknowns ({info['coordinates']} "
          f"coordinates + {info['multipliers']} multipliers), {info['clearance_joints']} "
          f"clearance joints, tendon elements {elements}")
    print(f"reserved pattern nnz {info['nnz']}; plan: border {info['border']}, bandwidth "
          f"{info['bandwidth']}, cost {info['cost']:.4g}, tree {info['tree']} unknowns "
          f"(assembly {info['assembly_s']:.2f} s, plan {info['plan_s']:.2f} s)")
    sys.stdout.flush()
    if a.static:
        r = run_static(a.disks, a.load_steps, a.hold, **kw)
        if r["status"] == "converged":
            print(f"static: converged in {r['increments']} increments, {r['newton']} Newton "
                  f"iterations, {r['wall_s']:.2f} s; tip displacement "
                  f"{np.array2string(1e3 * r['tip_displacement'], precision=3)} mm")
        else:
            print(f"static: FAILED after {r['wall_s']:.2f} s: {r['error']}")
        return 0 if r["status"] == "converged" else 1
    r = run_dynamic(a.disks, a.steps, a.dt, every=a.every, max_wall=a.max_wall or None,
                    log=a.progress, retreats=a.retreats, hold=a.hold, **kw)
    print(f"warm-up (build + 2 steps, compile or cache load) {r['warmup_s']:.1f} s")
    print(f"dynamic ({r['status']}): {r['steps']} steps to t = {r['t']:.4g} s "
          f"({r['rejected']} rejected), "
          f"{r['newton']} Newton iterations, {r['factorizations']} factorisations, "
          f"{r['residuals']} residual evaluations, {r['replans']} re-plans")
    print(f"integration wall {r['wall_s']:.3f} s (simulate call {r['simulate_s']:.3f} s): "
          f"{r['per_step_ms']:.2f} ms per step; tip displacement "
          f"{np.array2string(1e6 * r['tip_displacement'], precision=3)} um")
    return 0 if r["status"] == "completed" else 1


if __name__ == "__main__":
    raise SystemExit(main())

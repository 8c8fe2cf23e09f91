"""Side-by-side benchmark: a hanging chain of N rigid bodies on spherical joints, flexmbs and
Exudyn in one process run (issue 37).

Links of 0.1 m, m = 0.1 kg, inertia of a slender rod (1e-6, m L^2/12, m L^2/12) about the
link's own axes, Euler parameters; the chain starts horizontal along x, its first link hinged
to the ground at the origin, gravity -z. Generalized-alpha rho_inf = 0.8, fixed h = 1e-3,
index 3, modified Newton on both sides, Exudyn with EigenSparse on one thread. Prints wall
time per step, the ratio flexmbs/Exudyn, the free end's z of both and the cost exponent of
flexmbs from N = 40 to 640; then a beam threaded through fixed eyelets (flexmbs only).

    python benchmarks/chain.py [--t-end 0.1] [--sizes 10 40 160 640] [--eyelets 50] [--fed 50]
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from exudyn_models import _quiet_settings, exudyn_available, solve_dynamic_timed

import flexmbs as fm
import flexmbs.solvers.generalized_alpha as ga

LINK = 0.1
MASS = 0.1
INERTIA = (1e-6, MASS * LINK**2 / 12, MASS * LINK**2 / 12)
G = (0.0, 0.0, -9.81)
PULL_RAMP = 0.01      # s: the eyelet wire's pull, cosine ramp from 0 (build_eyelets)


def chain_parents(n: int) -> list[int]:
    """The chain: link k hangs from link k - 1 (the first from the ground, -1)."""
    return list(range(-1, n - 1))


def tree_parents(n: int) -> list[int]:
    """A binary tree: link k hangs from link (k - 1) // 2 (siblings coincide and move alike)."""
    return [-1] + [(k - 1) // 2 for k in range(1, n)]


def _depths(parents: list[int]) -> list[int]:
    depth: list[int] = []
    for p in parents:
        depth.append(0 if p < 0 else depth[p] + 1)
    return depth


def build_chain(n: int, parents: list[int] | None = None) -> tuple[fm.Model, list]:
    """N links on spherical joints, each link's start on its parent's end (``parents``,
    default :func:`chain_parents`), along x."""
    parents = chain_parents(n) if parents is None else parents
    depth = _depths(parents)
    model = fm.Model(gravity=G)
    bodies: list = []
    for k in range(n):
        b = model.add_rigid_body(mass=MASS, inertia=INERTIA,
                                 pose=fm.Pose(((depth[k] + 0.5) * LINK, 0.0, 0.0), np.eye(3)))
        model.spherical(b, fm.GROUND if parents[k] < 0 else bodies[parents[k]],
                        point=(depth[k] * LINK, 0.0, 0.0))
        bodies.append(b)
    return model, bodies


def run_flexmbs_chain(n: int, *, h: float = 1e-3, t_end: float = 0.1, repeats: int = 1,
                      parents: list[int] | None = None) -> dict:
    best = None
    for _ in range(repeats):
        model, bodies = build_chain(n, parents)
        integ = fm.GeneralizedAlpha(rho_inf=0.8, adaptive=False)
        res = fm.simulate(model, t_end=t_end, dt=h, integrator=integ, output_interval=t_end,
                          record_energy=False)
        if best is None or res.wall_time < best[0].wall_time:
            best = (res, bodies)
    res, bodies = best
    s = res.stats
    return dict(n=n, steps=s.steps, wall_time=res.wall_time,
                us_per_step=1e6 * res.wall_time / s.steps,
                end_z=float(res.body_position(bodies[-1])[-1][2]),
                newton=s.newton_iterations, jac=s.factorizations,
                rejected=getattr(s, "rejected_steps", 0))


def run_exudyn_chain(n: int, *, h: float = 1e-3, t_end: float = 0.1,
                     parents: list[int] | None = None) -> dict:
    import exudyn as exu
    import exudyn.itemInterface as ei
    from exudyn.rigidBodyUtilities import RigidBodyInertia

    parents = chain_parents(n) if parents is None else parents
    depth = _depths(parents)
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddObject(ei.ObjectGround())
    inertia = RigidBodyInertia(mass=MASS, inertiaTensor=np.diag(INERTIA))
    ground_marker = mbs.AddMarker(ei.MarkerBodyRigid(bodyNumber=ground, localPosition=[0, 0, 0]))
    ends: list = []      # each link's end marker (its children's joint)
    last = None
    for k in range(n):
        node = mbs.AddNode(ei.NodeRigidBodyEP(
            referenceCoordinates=[(depth[k] + 0.5) * LINK, 0, 0, 1, 0, 0, 0],
            initialVelocities=[0] * 7))
        body = mbs.AddObject(ei.ObjectRigidBody(
            physicsMass=MASS, physicsInertia=inertia.GetInertia6D(), nodeNumber=node))
        mbs.AddLoad(ei.Force(markerNumber=mbs.AddMarker(ei.MarkerNodePosition(nodeNumber=node)),
                              loadVector=[MASS * g for g in G]))
        m_left = mbs.AddMarker(ei.MarkerBodyRigid(bodyNumber=body, localPosition=[-LINK / 2, 0, 0]))
        parent_marker = ground_marker if parents[k] < 0 else ends[parents[k]]
        mbs.AddObject(ei.ObjectJointSpherical(markerNumbers=[parent_marker, m_left],
                                               constrainedAxes=[1, 1, 1]))
        ends.append(mbs.AddMarker(ei.MarkerBodyRigid(bodyNumber=body,
                                                      localPosition=[LINK / 2, 0, 0])))
        last = node
    mbs.Assemble()
    s = _quiet_settings("EigenSparse")
    wall, solver, n_steps = solve_dynamic_timed(
        mbs, s, h=h, t_end=t_end, rho_inf=0.8, modified_newton=True, relative_tolerance=1e-8,
        residual_mode=1, absolute_tolerance=1e-8)
    it = solver.it
    z = mbs.GetNodeOutput(last, exu.OutputVariableType.Position)[2]
    return dict(n=n, steps=n_steps, wall_time=wall, us_per_step=1e6 * wall / n_steps,
                end_z=float(z), newton=int(it.newtonStepsCount), jac=int(it.newtonJacobiCount))


def _wire_through_rings(stations: np.ndarray, pull: float, *, clamped: bool, n_elem: int = 100
                        ) -> tuple[fm.Model, fm.Beam]:
    """A 1 m steel wire (r = 0.5 mm) along x under gravity through fixed rings at ``stations``
    (``SlidingJoint(variant="ring")`` on fixed bodies, a slide coordinate each), pulled by
    ``pull`` N along its axis at its end, ramped in over ``PULL_RAMP``; ``clamped``: at its
    start."""
    model = fm.Model(gravity=G)
    wire = model.add_beam(fm.line((0, 0, 0), (1.0, 0, 0), elements=n_elem),
                          section=fm.CircularSection(5e-4),
                          material=fm.Material(E=2.1e11, rho=7800.0))
    if clamped:
        model.clamp(wire.first_node)
    for k, x in enumerate(stations):
        ring = model.add_rigid_body(mass=1e-2, inertia=(1e-6, 1e-6, 1e-6),
                                    pose=fm.Pose((float(x), 0.0, 0.0), np.eye(3)), name=f"eyelet{k}")
        model.fix_body(ring)
        model.add_joint(fm.SlidingJoint(wire, ring, variant="ring", name=f"ring{k}"))
    model.add_point_load(wire.last_node, force=(pull, 0.0, 0.0),
                         function=fm.Ramp(end=PULL_RAMP, smooth=True))
    return model, wire


def build_eyelets(n_eyelets: int, n_elem: int = 100) -> fm.Model:
    """The wire clamped at its start, threaded through ``n_eyelets`` fixed eyelets evenly
    spaced along it, pulled by 1 N at the free end (:func:`_wire_through_rings`).

    The pull is ramped: applied at once, it gives the light tip node (consistent mass about
    2.3e-5 kg) an initial acceleration of about 4e4 m/s^2, which the constant-acceleration
    predictor turns into a tip displacement of centimetres in the first step, longer than the
    1 cm tip element; Newton then converges to the folded branch of that element (r' = -e_x,
    zero Green strain as for +e_x), and two steps later the rings' equations fail
    (benchmarks/README.md, "Eyelet wire")."""
    return _wire_through_rings(np.linspace(0.0, 1.0, n_eyelets + 2)[1:-1], 1.0, clamped=True,
                               n_elem=n_elem)[0]


def run_flexmbs_eyelets(n_eyelets: int, *, h: float = 1e-3, t_end: float = 0.05) -> dict:
    model = build_eyelets(n_eyelets)
    res = fm.simulate(model, t_end=t_end, dt=h, output_interval=t_end, record_energy=False,
                      integrator=fm.GeneralizedAlpha(rho_inf=0.8, adaptive=False))
    s = res.stats
    asm = res.assembly
    plan = asm.factor_plan()
    # the compiled loop's plan follows the rings where that is cheaper (generalized_alpha)
    following = asm.factor_plan(windows=asm.contact_windows(ga.FOLLOW_REACH))
    follows = following.cost < ga.FOLLOW_COST_RATIO * plan.cost
    used = following if follows else plan
    return dict(steps=s.steps, us_per_step=1e6 * res.wall_time / s.steps,
                newton=s.newton_iterations, jac=s.factorizations, border=used.border.size,
                unknowns=asm.n_total, follows=follows, replans=s.replans,
                fixed_border=plan.border.size)


def build_fed_wire(n_eyelets: int, n_elem: int = 100) -> tuple[fm.Model, fm.Beam]:
    """The wire free (no clamp) through ``n_eyelets`` fixed rings between 0.3 and 0.7 m,
    pulled by 0.05 N at its end (:func:`_wire_through_rings`): it is fed about 15 cm, 15
    elements, through the rings in 0.2 s, so a plan that follows the rings is made again as
    they pass element ends."""
    return _wire_through_rings(np.linspace(0.3, 0.7, n_eyelets), 0.05, clamped=False,
                               n_elem=n_elem)


def run_flexmbs_fed(n_eyelets: int, *, h: float = 1e-3, t_end: float = 0.2) -> dict:
    """The fed wire with full Newton (a factorisation at every iteration: the worst case for
    re-planning, each re-plan's Python included in the wall time)."""
    model, wire = build_fed_wire(n_eyelets)
    res = fm.simulate(model, t_end=t_end, dt=h, output_interval=t_end, record_energy=False,
                      integrator=fm.GeneralizedAlpha(rho_inf=0.8, adaptive=False,
                                                     newton=fm.NewtonOptions(modified=False)))
    s = res.stats
    return dict(steps=s.steps, us_per_step=1e6 * res.wall_time / s.steps, replans=s.replans,
                newton=s.newton_iterations, fed=float(res.node_displacement(wire.last_node)[-1][0]))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t-end", type=float, default=0.1)
    ap.add_argument("--dt", type=float, default=1e-3)
    ap.add_argument("--sizes", type=int, nargs="+", default=[10, 40, 160, 640])
    ap.add_argument("--eyelets", type=int, default=50)
    ap.add_argument("--fed", type=int, default=0, help="also a wire fed through this many rings")
    ap.add_argument("--tree", action="store_true",
                    help="binary trees of links instead of chains (eliminated in tree order)")
    args = ap.parse_args(argv)
    run_flexmbs_chain(3, t_end=0.005)   # compile / load numba caches outside the timing
    have_exu = exudyn_available()
    shape = tree_parents if args.tree else chain_parents
    print(f"hanging {'binary tree' if args.tree else 'chain'}, h = {args.dt}, t_end = "
          f"{args.t_end}, rho_inf = 0.8, modified Newton")
    print(f"{'N':>5} {'flexmbs us/step':>16} {'Exudyn us/step':>15} {'ratio':>7} "
          f"{'flexmbs it/jac':>15} {'Exudyn it/jac':>14} {'end z flexmbs':>14} {'end z Exudyn':>13}")
    ts = []
    for n in args.sizes:
        f = run_flexmbs_chain(n, h=args.dt, t_end=args.t_end, repeats=2, parents=shape(n))
        ts.append(f["us_per_step"])
        if have_exu:
            e = min((run_exudyn_chain(n, h=args.dt, t_end=args.t_end, parents=shape(n))
                     for _ in range(2)),
                    key=lambda d: d["us_per_step"])
            print(f"{n:5d} {f['us_per_step']:16.1f} {e['us_per_step']:15.1f} "
                  f"{f['us_per_step'] / e['us_per_step']:7.2f} {f['newton']:>7d}/{f['jac']:<7d} "
                  f"{e['newton']:>6d}/{e['jac']:<7d} {f['end_z']:14.8f} {e['end_z']:13.8f}")
        else:
            print(f"{n:5d} {f['us_per_step']:16.1f} {'-':>15} {'-':>7} "
                  f"{f['newton']:>7d}/{f['jac']:<7d}")
    big = [(n, t) for n, t in zip(args.sizes, ts, strict=True) if n >= 40]
    if len(big) >= 2:
        k = np.polyfit(np.log([n for n, _ in big]), np.log([t for _, t in big]), 1)[0]
        print(f"flexmbs cost per step ~ N^{k:.2f} (N = {big[0][0]}..{big[-1][0]})")
    if args.eyelets:
        r = run_flexmbs_eyelets(args.eyelets, h=args.dt)
        how = (f"plan following the rings ({r['replans']} replans; the fixed plan's border "
               f"{r['fixed_border']})" if r["follows"] else "fixed plan")
        print(f"wire through {args.eyelets} fixed eyelets (100 elements, {r['steps']} steps): "
              f"{r['us_per_step']:.1f} us/step, it/jac {r['newton']}/{r['jac']}, border "
              f"{r['border']} of {r['unknowns']} unknowns, {how} (no Exudyn counterpart)")
    if args.fed:
        r = run_flexmbs_fed(args.fed, h=args.dt)
        print(f"wire fed {100 * r['fed']:.1f} cm through {args.fed} fixed rings, full Newton "
              f"({r['steps']} steps): {r['us_per_step']:.1f} us/step, {r['replans']} re-plans, "
              f"{r['newton']} iterations (no Exudyn counterpart)")
    return 0


if __name__ == "__main__":
    t0 = time.perf_counter()
    rc = main()
    print(f"benchmark wall time {time.perf_counter() - t0:.1f} s")
    sys.exit(rc)

"""Example 1 with clearance (flexmbs) against Exudyn's clearance-free planar run: the speed goal.

The issue's Speed section asks for the wall time of the with-clearance run (4 s at h = 1e-4 s) next
to Exudyn's clearance-free planar run of the same model, measured by one run of one script on the
same machine. The goal is at most 2x Exudyn's time. This script times, in one process:

1. Exudyn planar, clearance-free (the reference of the goal). The rail and sleeve of docs/theory.md
   §III.9 in the x-y plane with gravity -y: 16 ``ObjectANCFCable2D`` elements with a
   curved stress-free reference (``strainIsRelativeToReference=1``), clamped ends, an
   ``ObjectRigidBody2D`` sleeve on an ``ObjectJointSliding2D`` (``constrainRotation=False``: the ring
   joint, the planar twin of the 3D model of ``sliding.py``).
2. Exudyn 3D ring joint, clearance-free: ``sliding.run_exudyn`` (``ObjectANCFCable`` +
   ``ObjectJointSliding``), for context.
3. flexmbs with clearance: what ``flexmbs run examples/curved_beam_sleeve.toml`` does
   (``flexmbs.cli.main`` in-process, output to a temporary folder).
4. flexmbs clearance-free: the same for ``examples/curved_beam_sleeve_ideal.toml`` (cylindrical joint).

Both Exudyn runs use the settings of ``sliding.py``: generalized-alpha rho_inf = 0.8, fixed step,
index 3, modified Newton, ``residualMode=1`` with tolerance 1e-8, EigenSparse on 1 thread, sensors
stored in memory every 1e-3 s, no file output, no graphics. Only ``exu.SolveDynamic`` is timed.
The flexmbs times are the whole ``flexmbs run`` call (scenario loading, assembly, simulation and
output folder), after a short warm-up run of each scenario so that numba compilation is not timed.

Physics checks (``--no-checks`` skips them): the planar slide coordinate against the 3D ring run;
the stiff rail (E x 1000) against the rigid-track pendulum period; the stress-free reference.

    python benchmarks/example1.py                      # 4 s at h = 1e-4 (a few minutes)
    python benchmarks/example1.py --t-end 0.2          # a short look
    python benchmarks/example1.py --t-end 1 --skip-flexmbs
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from exudyn_models import exudyn_available  # noqa: E402
from sliding import (  # noqa: E402
    ARC_LENGTH,
    CASE,
    LOW_NODE,
    S0,
    S_LOW,
    _section,
    analytic_period,
    exudyn_settings,
    passages,
    run_exudyn,
)

EXAMPLES = HERE.parent / "examples"
SCENARIO_CLEARANCE = EXAMPLES / "curved_beam_sleeve.toml"
SCENARIO_IDEAL = EXAMPLES / "curved_beam_sleeve_ideal.toml"
REPORT_TIMES = (0.5, 1.0, 2.0, 4.0)
WARMUP_T_END = 2e-3        # 20 steps of each flexmbs scenario before timing


# ------------------------------------------------------------------------------ Exudyn planar
def build_exudyn_planar(e_factor: float = 1.0, *, constrain_rotation: bool = False,
                        gravity: float | None = None, joint_active: bool = True):
    """The Example 1 rail and sleeve as a planar Exudyn model (x-y plane, gravity -y).

    The 3D model of ``sliding._build_exudyn`` lies in the X-Z plane; here its (X, Z) become (x, y).
    Returns ``(mbs, sensors, offsets, rail_nodes)`` after ``mbs.Assemble()``.
    """
    import exudyn as exu
    from exudyn.itemInterface import (
        CoordinateConstraint,
        Gravity,
        MarkerBodyCable2DCoordinates,
        MarkerBodyMass,
        MarkerBodyRigid,
        MarkerNodeCoordinate,
        NodeGenericData,
        NodePoint2DSlope1,
        NodePointGround,
        NodeRigidBody2D,
        ObjectANCFCable2D,
        ObjectJointSliding2D,
        ObjectRigidBody2D,
        SensorNode,
        SensorObject,
        VCoordinateConstraint,
        VNodePoint2DSlope1,
        VNodePointGround,
        VNodeRigidBody2D,
        VObjectANCFCable2D,
        VObjectJointSliding2D,
        VObjectRigidBody2D,
    )

    c = CASE
    n, rho = c["n_elem"], c["radius"]
    g = c["gravity"] if gravity is None else gravity
    A, I2 = _section()
    E = c["E"] * e_factor
    le = ARC_LENGTH / n
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    # nodes on the exact arc (centre (0, rho), lowest point at the origin) with unit tangents as
    # slopes; strainIsRelativeToReference = 1 subtracts the strain and curvature of this
    # interpolated reference, so the curved rail is stress-free
    phis = -np.pi / 4 + np.arange(n + 1) * (np.pi / 2 / n)
    nodes = [mbs.AddNode(NodePoint2DSlope1(
        referenceCoordinates=[rho * np.sin(p), rho - rho * np.cos(p), np.cos(p), np.sin(p)],
        visualization=VNodePoint2DSlope1(show=False))) for p in phis]
    cables = []
    for i in range(n):
        o = mbs.AddObject(ObjectANCFCable2D(
            length=le, massPerLength=c["density"] * A, axialStiffness=E * A, bendingStiffness=E * I2,
            strainIsRelativeToReference=1.0, nodeNumbers=[nodes[i], nodes[i + 1]],
            useReducedOrderIntegration=2,     # 3-point Lobatto axial, 2-point Gauss bending
            visualization=VObjectANCFCable2D(show=False)))
        cables.append(o)
        mbs.AddLoad(Gravity(markerNumber=mbs.AddMarker(MarkerBodyMass(bodyNumber=o)),
                            loadVector=[0.0, -g, 0.0]))
    # clamp as sliding.py / flexmbs model.clamp: position and the transverse slope component.
    # n = (-t_y, t_x): n . u' = 0  <=>  u'_x = (t_x / t_y) u'_y  (CoordinateConstraint factor1);
    # the axial slope stays free
    nG = mbs.AddNode(NodePointGround(visualization=VNodePointGround(show=False)))
    mG = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nG, coordinate=0))
    for k in (0, n):
        for j in (0, 1):
            m = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nodes[k], coordinate=j))
            mbs.AddObject(CoordinateConstraint(markerNumbers=[mG, m],
                                               visualization=VCoordinateConstraint(show=False)))
        tx, ty = np.cos(phis[k]), np.sin(phis[k])
        mx = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nodes[k], coordinate=2))
        my = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nodes[k], coordinate=3))
        mbs.AddObject(CoordinateConstraint(markerNumbers=[mx, my], factor1=tx / ty,
                                           visualization=VCoordinateConstraint(show=False)))
    # sleeve: planar rigid body, centre on the arc at s0, angle = tangent angle (body x = hole axis)
    p0 = c["phi0"]
    nB = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[rho * np.sin(p0), rho - rho * np.cos(p0), p0],
                                     visualization=VNodeRigidBody2D(show=False)))
    oB = mbs.AddObject(ObjectRigidBody2D(mass=c["mass"], inertia=c["inertia"][1], nodeNumber=nB,
                                         visualization=VObjectRigidBody2D(show=False)))
    mbs.AddLoad(Gravity(markerNumber=mbs.AddMarker(MarkerBodyMass(bodyNumber=oB)),
                        loadVector=[0.0, -g, 0.0]))
    mB = mbs.AddMarker(MarkerBodyRigid(bodyNumber=oB, localPosition=[0.0, 0.0, 0.0]))
    cable_markers = [mbs.AddMarker(MarkerBodyCable2DCoordinates(bodyNumber=o)) for o in cables]
    offsets = [i * le for i in range(n)]
    k0 = int(S0 // le)
    # data node: x[0] = element index, x[1] = global s at the start of the step (as in 3D)
    nData = mbs.AddNode(NodeGenericData(numberOfDataCoordinates=2, initialCoordinates=[k0, S0]))
    oJ = mbs.AddObject(ObjectJointSliding2D(
        markerNumbers=[mB, cable_markers[k0]], slidingMarkerNumbers=cable_markers,
        slidingMarkerOffsets=offsets, nodeNumber=nData,
        useClassicalFormulation=True,      # 2 position equations + zero force along the slope
        constrainRotation=bool(constrain_rotation), activeConnector=bool(joint_active),
        visualization=VObjectJointSliding2D(show=False)))
    OV = exu.OutputVariableType
    sensors = dict(
        s=mbs.AddSensor(SensorObject(objectNumber=oJ, outputVariableType=OV.SlidingCoordinate,
                                     storeInternal=True, writeToFile=False)),
        data=mbs.AddSensor(SensorNode(nodeNumber=nData, outputVariableType=OV.Coordinates,
                                      storeInternal=True, writeToFile=False)),
        low=mbs.AddSensor(SensorNode(nodeNumber=nodes[LOW_NODE], outputVariableType=OV.Displacement,
                                     storeInternal=True, writeToFile=False)),
        rot=mbs.AddSensor(SensorNode(nodeNumber=nB, outputVariableType=OV.Rotation,
                                     storeInternal=True, writeToFile=False)),
    )
    mbs.Assemble()
    return mbs, sensors, np.array(offsets), nodes


def run_exudyn_planar(e_factor: float, h: float, t_end: float, *, constrain_rotation: bool = False,
                      gravity: float | None = None, joint_active: bool = True,
                      tol: float = 1e-8) -> dict:
    import exudyn as exu
    mbs, sensors, offsets, nodes = build_exudyn_planar(
        e_factor, constrain_rotation=constrain_rotation, gravity=gravity, joint_active=joint_active)
    s, n_steps = exudyn_settings(h, t_end, True, tol)
    t0 = time.perf_counter()
    ok = exu.SolveDynamic(mbs, s, solverType=exu.DynamicSolverType.GeneralizedAlpha, storeSolver=True)
    wall = time.perf_counter() - t0
    if not ok:
        raise RuntimeError("Exudyn SolveDynamic failed (planar model)")
    it = mbs.sys["dynamicSolver"].it
    S = mbs.GetSensorStoredData(sensors["s"])
    D = mbs.GetSensorStoredData(sensors["data"])
    Z = mbs.GetSensorStoredData(sensors["low"])
    R = mbs.GetSensorStoredData(sensors["rot"])
    k = D[:, 1].astype(int)
    node_disp = max(float(np.abs(mbs.GetNodeOutput(nd, exu.OutputVariableType.Displacement)).max())
                    for nd in nodes)
    return dict(wall=wall, steps=n_steps, newton=int(it.newtonStepsCount), jac=int(it.newtonJacobiCount),
                t=S[:, 0], s=S[:, 1], s_data=D[:, 2], element=k,
                z_low=Z[:, 2], angle=R[:, 3], max_node_disp=node_disp)


# ------------------------------------------------------------------------------------- flexmbs
def run_flexmbs_cli(scenario: Path, t_end: float, dt: float, out: Path) -> dict:
    """``flexmbs run SCENARIO --quiet --out OUT --t-end T --dt H`` in-process, timed as a whole."""
    from flexmbs.cli import main as flexmbs_main
    argv = ["run", str(scenario), "--quiet", "--out", str(out), "--t-end", repr(float(t_end)),
            "--dt", repr(float(dt))]
    t0 = time.perf_counter()
    rc = flexmbs_main(argv)
    wall = time.perf_counter() - t0
    if rc != 0:
        raise RuntimeError(f"flexmbs {' '.join(argv)} exited with status {rc}")
    summary = json.loads((out / "summary.json").read_text())
    with open(out / "probes.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    st = summary["stats"]
    return dict(wall=wall, solver_wall=float(summary["wall_time"]), status=summary["status"],
                steps=int(st["steps"]), newton=int(st["newton_iterations"]),
                jac=int(st["factorizations"]), rejected=int(st["rejected_steps"]),
                t=np.array([float(r["t"]) for r in rows]),
                s=np.array([float(r["sleeve_s"]) for r in rows]),
                z_low=np.array([float(r["lowest_point_z"]) for r in rows]))


# ----------------------------------------------------------------------------------------- main
def _at(run: dict, t: float) -> float:
    return float(np.interp(t, run["t"], run["s"]))


def _checks(args, planar: dict, ring: dict) -> None:
    print("\nphysics checks (Exudyn planar)")
    T_cyl, T_ring = analytic_period(True), analytic_period(False)
    # 1. same motion as the 3D ring joint (same sensor times: every 1e-3 s)
    t1 = min(1.0, args.t_end)
    m1 = planar["t"] <= t1 + 1e-12
    se = np.interp(planar["t"], ring["t"], ring["s"])
    ze = np.interp(planar["t"], ring["t"], ring["z_low"])
    print(f"  planar vs 3D ring, E x 1, h = {args.dt:g}: max|s_planar - s_3D| = "
          f"{np.abs(planar['s'] - se)[m1].max():.2e} m over 0..{t1:g} s, "
          f"{np.abs(planar['s'] - se).max():.2e} m over 0..{args.t_end:g} s; "
          f"lowest node: max|y_planar - z_3D| = {np.abs(planar['z_low'] - ze).max():.2e} m "
          f"(min {planar['z_low'].min():.5e} / {ring['z_low'].min():.5e} m)")
    print(f"  planar SlidingCoordinate output vs data node: max diff "
          f"{np.abs(planar['s'] - planar['s_data']).max():.1e} m; elements visited "
          f"{planar['element'].min()}..{planar['element'].max()}")
    # 2. stiff rail against the rigid-track pendulum (two passages of the lowest point)
    t_stiff = 1.6
    print(f"  rigid track, 30 deg: T = {T_cyl:.5f} s with J_transv, {T_ring:.5f} s without; "
          f"T/4 = {T_cyl / 4:.6f} / {T_ring / 4:.6f} s")
    for label, cr, T in (("ring (constrainRotation=False)", False, T_ring),
                         ("constrainRotation=True", True, T_cyl)):
        r = run_exudyn_planar(1000.0, args.dt, t_stiff, constrain_rotation=cr)
        tc = passages(r["t"], r["s"])
        txt = (f"  E x 1000, {label:<31}: passages {', '.join(f'{x:.6f}' for x in tc[:2])} s; "
               f"t1 - T/4 = {tc[0] - T / 4:+.2e} s")
        if len(tc) >= 2:
            txt += f", (t2 - t1) - T/2 = {tc[1] - tc[0] - T / 2:+.2e} s"
        if cr:
            txt += f"; t1 - T_ring/4 = {tc[0] - T_ring / 4:+.2e} s"
        print(txt)
    # 3. stress-free reference: g = 0 and the joint switched off -> nothing may move
    r0 = run_exudyn_planar(1.0, args.dt, 0.01, gravity=0.0, joint_active=False)
    r1 = run_exudyn_planar(1.0, args.dt, 0.01, gravity=0.0)
    print(f"  stress-free reference, g = 0, 0.01 s: max nodal displacement {r0['max_node_disp']:.1e} m "
          f"(joint inactive), {r1['max_node_disp']:.1e} m (joint active: the sleeve starts on the "
          f"exact arc, not on the cubic interpolation)")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t-end", type=float, default=4.0, help="simulated time [s] (default 4)")
    ap.add_argument("--dt", type=float, default=1e-4, help="time step [s] (default 1e-4)")
    ap.add_argument("--no-checks", action="store_true", help="skip the physics checks")
    ap.add_argument("--skip-flexmbs", action="store_true", help="Exudyn runs only")
    args = ap.parse_args(argv)
    if not exudyn_available():
        print("exudyn not installed (pip install exudyn)")
        return 1
    import exudyn as exu

    import flexmbs
    print(f"Example 1, t_end = {args.t_end:g} s, h = {args.dt:g} s; exudyn {exu.__version__}, "
          f"flexmbs {flexmbs.__version__}, python {sys.version.split()[0]}, "
          f"{os.cpu_count()} cores, {time.strftime('%Y-%m-%d %H:%M')}")
    print(f"s0 = {S0:.6f} m, lowest point s = {S_LOW:.6f} m")

    # warm-up outside the timings: Exudyn once, flexmbs (numba) once per scenario
    run_exudyn_planar(1.0, args.dt, 10 * args.dt)
    runs: dict[str, dict] = {}
    with tempfile.TemporaryDirectory(prefix="flexmbs_example1_") as tmp:
        if not args.skip_flexmbs:
            for i, sc in enumerate((SCENARIO_CLEARANCE, SCENARIO_IDEAL)):
                run_flexmbs_cli(sc, WARMUP_T_END, args.dt, Path(tmp) / f"warmup{i}")
            print(f"warm-up: {WARMUP_T_END:g} s of each flexmbs scenario and 10 steps of Exudyn "
                  "before the timed runs (numba compilation and imports not timed)")
        print("running Exudyn planar ...", flush=True)
        runs["Exudyn planar (ring), no clearance"] = run_exudyn_planar(1.0, args.dt, args.t_end)
        print("running Exudyn 3D ring ...", flush=True)
        runs["Exudyn 3D ring, no clearance"] = run_exudyn(1.0, args.dt, args.t_end)
        if not args.skip_flexmbs:
            print("running flexmbs with clearance ...", flush=True)
            runs["flexmbs with clearance"] = run_flexmbs_cli(SCENARIO_CLEARANCE, args.t_end, args.dt,
                                                             Path(tmp) / "clearance")
            print("running flexmbs clearance-free ...", flush=True)
            runs["flexmbs cylindrical, no clearance"] = run_flexmbs_cli(SCENARIO_IDEAL, args.t_end,
                                                                        args.dt, Path(tmp) / "ideal")

    planar = runs["Exudyn planar (ring), no clearance"]
    ring = runs["Exudyn 3D ring, no clearance"]
    print(f"\nwall times for {args.t_end:g} s at h = {args.dt:g} s (one run each, same process; "
          "Exudyn: SolveDynamic only; flexmbs: the whole `flexmbs run` call, solver loop in brackets)")
    print(f"  {'run':<36} {'wall [s]':>9} {'steps':>7} {'rejected':>8} {'Newton it/step':>14} "
          f"{'Jacobians':>9} {'us/step':>8}")
    for name, r in runs.items():
        wall = f"{r['wall']:9.2f}"
        extra = f"  ({r['solver_wall']:.2f} s solver loop)" if "solver_wall" in r else ""
        print(f"  {name:<36} {wall} {r['steps']:7d} {r.get('rejected', 0):8d} "
              f"{r['newton'] / r['steps']:14.2f} {r['jac']:9d} {1e6 * r['wall'] / r['steps']:8.1f}{extra}")
    if "flexmbs with clearance" in runs:
        fc = runs["flexmbs with clearance"]
        fi = runs["flexmbs cylindrical, no clearance"]
        print(f"\n  flexmbs with clearance / Exudyn planar = {fc['wall'] / planar['wall']:.2f} "
              f"(goal <= 2)   / Exudyn 3D ring = {fc['wall'] / ring['wall']:.2f}")
        print(f"  flexmbs clearance-free / Exudyn planar = {fi['wall'] / planar['wall']:.2f}"
              f"   / Exudyn 3D ring = {fi['wall'] / ring['wall']:.2f}")
    print(f"  Exudyn 3D ring / Exudyn planar = {ring['wall'] / planar['wall']:.2f}")

    times = [t for t in REPORT_TIMES if t <= args.t_end + 1e-12] or [args.t_end]
    print("\nslide coordinate s [m] (arc length from the first node; lowest point "
          f"{S_LOW:.6f} m)")
    print(f"  {'run':<36} " + " ".join(f"{'t = ' + format(t, 'g') + ' s':>12}" for t in times)
          + f"  {'min lowest-node disp.':>22}")
    for name, r in runs.items():
        print(f"  {name:<36} " + " ".join(f"{_at(r, t):12.6f}" for t in times)
              + f"  {1e3 * r['z_low'].min():19.4f} mm")
    print("  (lowest-node vertical displacement sampled every 1e-3 s in Exudyn, every 1e-2 s in "
          "flexmbs' probes.csv)")

    if not args.no_checks:
        _checks(args, planar, ring)
    return 0


if __name__ == "__main__":
    t0 = time.perf_counter()
    rc = main()
    print(f"benchmark wall time {time.perf_counter() - t0:.1f} s")
    raise SystemExit(rc)

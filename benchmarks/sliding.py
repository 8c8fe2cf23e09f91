"""Side-by-side benchmark: sleeve on a sliding joint without clearance, flexmbs vs Exudyn.

Case: docs/theory.md §III.9, the clearance-free "rigid-ish" variant. A circular arc beam
(radius 1 m, 90 deg opening symmetric about its lowest point, vertical X-Z plane, centre
(0, 0, 1)) is made of 16 ANCF cable elements. The section is circular (r = 2 mm), steel
(E = 2.1e11, and E x 1000 for the rigid-track check), rho = 7800. Both ends are clamped.
Gravity is -9.81 z. A sleeve (rigid body, m = 0.21441 kg, principal inertia (2.479e-5,
4.098e-5, 4.098e-5), body x = hole axis) starts at rest at s0 = pi/4 - pi/6 (30 deg before
the lowest point) and slides without friction.

Both codes use generalized-alpha with rho_inf = 0.8, a fixed step h, index 3, modified
Newton and tolerance 1e-8. Exudyn uses EigenSparse on 1 thread with useReducedOrderIntegration=2.
flexmbs uses CableOptions(exudyn_compatible=True, axial_rule="lobatto3", bending_points=2),
which is the same element.

Exudyn 1.13.6 ``ObjectJointSliding`` only accepts ``constrainRotations=[0,0,0]``. Other values raise
``NotImplementedFeatureError: ... constrainRotations[i]!=0 not implemented``. So the Exudyn side is the
ring joint (3 position equations, sleeve free to rotate). flexmbs runs both the ring joint
(the like-for-like comparison) and the cylindrical joint (3 + 2 equations, the
case of docs/theory.md §II.7).

    python benchmarks/sliding.py [--dt 1e-3 1e-4] [--e-factors 1 1000] [--t-end 2.0]
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np
from scipy.special import ellipk

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from exudyn_models import _quiet_settings, alpha_settings, exudyn_available

import flexmbs as fm

CASE = dict(
    radius=1.0,                 # arc radius rho_0 [m]
    n_elem=16,
    section_radius=2e-3,        # r_b [m]
    E=2.1e11, density=7800.0,
    gravity=9.81,
    mass=0.21441,
    inertia=(2.479e-5, 4.098e-5, 4.098e-5),  # principal, body x = hole axis
    phi0=-np.pi / 6,            # release angle from the lowest point
)
ARC_LENGTH = CASE["radius"] * np.pi / 2
S_LOW = ARC_LENGTH / 2          # arc length of the lowest point from the first node
LOW_NODE = CASE["n_elem"] // 2  # node at the lowest point
S0 = S_LOW + CASE["radius"] * CASE["phi0"]   # = pi/4 - pi/6
REPORT_TIMES = (0.25, 0.5, 1.0, 1.5, 2.0)


def analytic_period(with_rotary_inertia: bool) -> float:
    """Rigid-track pendulum: (m rho^2 + J) phi'' + m g rho sin(phi) = 0, amplitude 30 deg.

    The cylindrical joint turns the sleeve with the tangent, so J = J_transverse counts. The ring
    joint leaves it free to rotate: gravity acts at the hole centre, so the sleeve does not
    turn and J = 0.
    """
    m, rho, g = CASE["mass"], CASE["radius"], CASE["gravity"]
    J = CASE["inertia"][1] if with_rotary_inertia else 0.0
    T0 = 2 * np.pi * np.sqrt((m * rho**2 + J) / (m * g * rho))
    return T0 * 2 / np.pi * ellipk(np.sin(abs(CASE["phi0"]) / 2) ** 2)


def passages(t: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Times at which s(t) crosses the lowest point (linear interpolation between samples)."""
    d = s - S_LOW
    i = np.flatnonzero(np.sign(d[:-1]) != np.sign(d[1:]))
    return t[i] - d[i] * (t[i + 1] - t[i]) / (d[i + 1] - d[i])


def _section():
    r = CASE["section_radius"]
    return np.pi * r**2, np.pi * r**4 / 4


# ----------------------------------------------------------------------------------- flexmbs
def run_flexmbs(e_factor: float, h: float, t_end: float, variant: str) -> dict:
    c = CASE
    E = c["E"] * e_factor
    model = fm.Model(gravity=(0, 0, -c["gravity"]))
    c45 = np.sqrt(0.5)
    rho = c["radius"]
    arc = fm.arc((0, 0, rho), rho, (-c45 * rho, 0, rho - c45 * rho), np.pi / 2, normal=(0, -1, 0),
                 elements=c["n_elem"])
    rail = model.add_beam(arc, section=fm.CircularSection(c["section_radius"]),
                          material=fm.Material(E=E, rho=c["density"]), name="rail",
                          options=fm.CableOptions(exudyn_compatible=True, axial_rule="lobatto3",
                                                  bending_points=2))
    model.clamp(rail.first_node)
    model.clamp(rail.last_node)
    sleeve = model.add_rigid_body(mass=c["mass"], inertia=c["inertia"], pose=rail.frame_at(S0),
                                  name="sleeve")
    joint = model.add_joint(fm.SlidingJoint(rail, sleeve, variant=variant))
    integ = fm.GeneralizedAlpha(rho_inf=0.8, adaptive=False)
    res = fm.simulate(model, t_end=t_end, dt=h, integrator=integ, output_interval=1e-3,
                      record_energy=False)
    st = res.stats
    return dict(t=res.t, s=res.q[:, res.assembly.extra_dofs(joint)[0]],
                z_low=res.node_displacement(rail.node(LOW_NODE))[:, 2],
                wall=res.wall_time, steps=st.steps, newton=st.newton_iterations,
                jac=st.factorizations, rejected=st.rejected_steps)


# ------------------------------------------------------------------------------------ Exudyn
def _build_exudyn(e_factor: float):
    import exudyn as exu
    from exudyn.itemInterface import (
        CoordinateConstraint,
        Gravity,
        MarkerBodyBeamShape,
        MarkerBodyMass,
        MarkerBodyRigid,
        MarkerNodeCoordinate,
        NodeGenericData,
        NodePointGround,
        NodePointSlope1,
        ObjectANCFCable,
        ObjectJointSliding,
        SensorBody,
        SensorNode,
        SensorObject,
        VCoordinateConstraint,
        VNodePointGround,
        VNodePointSlope1,
        VObjectANCFCable,
        VObjectJointSliding,
    )
    from exudyn.utilities import RigidBodyInertia

    c = CASE
    n, rho, g = c["n_elem"], c["radius"], c["gravity"]
    A, I2 = _section()
    E = c["E"] * e_factor
    le = ARC_LENGTH / n
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    phis = -np.pi / 4 + np.arange(n + 1) * (np.pi / 2 / n)
    # same reference as fm.arc: exact nodal positions, unit tangents
    nodes = [mbs.AddNode(NodePointSlope1(
        referenceCoordinates=[rho * np.sin(p), 0.0, rho - rho * np.cos(p), np.cos(p), 0.0, np.sin(p)],
        visualization=VNodePointSlope1(show=False))) for p in phis]
    cables = []
    for i in range(n):
        o = mbs.AddObject(ObjectANCFCable(
            length=le, massPerLength=c["density"] * A, axialStiffness=E * A, bendingStiffness=E * I2,
            strainIsRelativeToReference=1.0,        # curved reference = stress-free
            nodeNumbers=[nodes[i], nodes[i + 1]], useReducedOrderIntegration=2,
            visualization=VObjectANCFCable(show=False)))
        cables.append(o)
        mbs.AddLoad(Gravity(markerNumber=mbs.AddMarker(MarkerBodyMass(bodyNumber=o)),
                            loadVector=[0.0, 0.0, -g]))
    # clamp like flexmbs model.clamp: position + the two transverse slope components (the axial
    # slope stays free). The transverse directions are y (slope_y = 0) and the in-plane normal
    # n = (t_z, 0, -t_x): n . u' = 0  <=>  u'_x = (t_x / t_z) u'_z  (CoordinateConstraint factor1)
    nG = mbs.AddNode(NodePointGround(visualization=VNodePointGround(show=False)))
    mG = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nG, coordinate=0))
    for k in (0, n):
        for j in (0, 1, 2, 4):
            m = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nodes[k], coordinate=j))
            mbs.AddObject(CoordinateConstraint(markerNumbers=[mG, m],
                                               visualization=VCoordinateConstraint(show=False)))
        tx, tz = np.cos(phis[k]), np.sin(phis[k])
        mx = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nodes[k], coordinate=3))
        mz = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nodes[k], coordinate=5))
        mbs.AddObject(CoordinateConstraint(markerNumbers=[mx, mz], factor1=tx / tz,
                                           visualization=VCoordinateConstraint(show=False)))
    # sleeve: body x = tangent, body z = in-plane normal (upward), as fm Beam.frame_at
    p0 = c["phi0"]
    t0 = np.array([np.cos(p0), 0.0, np.sin(p0)])
    z0 = np.array([-np.sin(p0), 0.0, np.cos(p0)])
    R0 = np.column_stack([t0, np.cross(z0, t0), z0])
    oB = mbs.CreateRigidBody(inertia=RigidBodyInertia(mass=c["mass"], inertiaTensor=np.diag(c["inertia"])),
                             referencePosition=[rho * np.sin(p0), 0.0, rho - rho * np.cos(p0)],
                             referenceRotationMatrix=R0, gravity=[0.0, 0.0, -g], show=False)
    mB = mbs.AddMarker(MarkerBodyRigid(bodyNumber=oB))
    beam_markers = [mbs.AddMarker(MarkerBodyBeamShape(bodyNumber=o)) for o in cables]
    offsets = [i * le for i in range(n)]
    k0 = int(S0 // le)
    # data node: x[0] = index into beam_markers (element), x[1] = global s at the start of the step
    nData = mbs.AddNode(NodeGenericData(numberOfDataCoordinates=2, initialCoordinates=[k0, S0]))
    oJ = mbs.AddObject(ObjectJointSliding(markerNumbers=[mB, beam_markers[k0]],
                                          slidingMarkerNumbers=beam_markers,
                                          slidingMarkerOffsets=offsets, nodeNumber=nData,
                                          constrainRotations=[0, 0, 0],  # others: not implemented
                                          visualization=VObjectJointSliding(show=False)))
    OV = exu.OutputVariableType
    sensors = dict(
        s=mbs.AddSensor(SensorObject(objectNumber=oJ, outputVariableType=OV.SlidingCoordinate,
                                     storeInternal=True, writeToFile=False)),
        data=mbs.AddSensor(SensorNode(nodeNumber=nData, outputVariableType=OV.Coordinates,
                                      storeInternal=True, writeToFile=False)),
        pos=mbs.AddSensor(SensorBody(bodyNumber=oB, outputVariableType=OV.Position,
                                     storeInternal=True, writeToFile=False)),
        low=mbs.AddSensor(SensorNode(nodeNumber=nodes[LOW_NODE], outputVariableType=OV.Displacement,
                                     storeInternal=True, writeToFile=False)),
    )
    mbs.Assemble()
    return mbs, sensors, np.array(offsets)


def exudyn_settings(h: float, t_end: float, record: bool, tol: float,
                    modified_newton: bool = True) -> tuple:
    """Exudyn's solver settings of the comparison (generalized-alpha rho_inf = 0.8, fixed step,
    index 3, EigenSparse, increment test residualMode=1 with absTol = relTol): (settings, steps)."""
    s = _quiet_settings("EigenSparse")
    s.solution.sensors.active = bool(record)
    s.solution.sensors.writePeriod = 1e-3
    n_steps = alpha_settings(s, h=h, t_end=t_end, rho_inf=0.8, modified_newton=modified_newton,
                             relative_tolerance=tol, residual_mode=1)   # absTol = relTol
    return s, n_steps


def run_exudyn(e_factor: float, h: float, t_end: float, record: bool = True, *, tol: float = 1e-8,
               modified_newton: bool = True) -> dict:
    import exudyn as exu
    mbs, sensors, offsets = _build_exudyn(e_factor)
    s, n_steps = exudyn_settings(h, t_end, record, tol, modified_newton)
    t0 = time.perf_counter()
    ok = exu.SolveDynamic(mbs, s, solverType=exu.DynamicSolverType.GeneralizedAlpha, storeSolver=True)
    wall = time.perf_counter() - t0
    if not ok:
        raise RuntimeError("Exudyn SolveDynamic failed")
    it = mbs.sys["dynamicSolver"].it
    out = dict(wall=wall, steps=n_steps, newton=int(it.newtonStepsCount),
               jac=int(it.newtonJacobiCount), discontinuous=int(it.discontinuousIterationsCount))
    if record:
        S = mbs.GetSensorStoredData(sensors["s"])
        D = mbs.GetSensorStoredData(sensors["data"])
        P = mbs.GetSensorStoredData(sensors["pos"])
        Z = mbs.GetSensorStoredData(sensors["low"])
        k = D[:, 1].astype(int)                    # element index (data x[0])
        s_local = D[:, 2] - offsets[k]              # local s in that element (x[1] - offset[k])
        out.update(t=S[:, 0], s=offsets[k] + s_local, s_sensor=S[:, 1], element=k,
                   s_geom=S_LOW + CASE["radius"] * np.arctan2(P[:, 1], CASE["radius"] - P[:, 3]),
                   z_low=Z[:, 3])
    return out


# -------------------------------------------------------------------------------------- main
def _interp(t_ref, t, y):
    return np.interp(t_ref, t, y)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t-end", type=float, default=2.0)
    ap.add_argument("--dt", type=float, nargs="+", default=[1e-3, 1e-4])
    ap.add_argument("--e-factors", type=float, nargs="+", default=[1.0, 1000.0])
    args = ap.parse_args(argv)
    if not exudyn_available():
        print("exudyn not installed (pip install exudyn)")
        return 1
    import exudyn as exu
    T_cyl, T_ring = analytic_period(True), analytic_period(False)
    print(f"exudyn {exu.__version__}; t_end = {args.t_end}, gen.-alpha rho_inf = 0.8, modified Newton, "
          f"tol 1e-8, 16 elements, s0 = {S0:.6f} m, lowest point s = {S_LOW:.6f} m")
    print(f"analytic rigid track, 30 deg: T_cyl = {T_cyl:.5f} s (with J_transv), "
          f"T_ring = {T_ring:.5f} s (sleeve does not rotate)")
    run_flexmbs(1.0, 1e-3, 0.01, "ring")   # numba caches outside the timing
    run_exudyn(1.0, 1e-3, 0.01)

    summary = []
    for ef in args.e_factors:
        for h in args.dt:
            e = run_exudyn(ef, h, args.t_end)
            e_nr = run_exudyn(ef, h, args.t_end, record=False)
            e_t = run_exudyn(ef, h, args.t_end, tol=1e-10)   # tighter Newton test, see README
            fr = run_flexmbs(ef, h, args.t_end, "ring")
            fc = run_flexmbs(ef, h, args.t_end, "cylindrical")
            t = fr["t"]
            se = _interp(t, e["t"], e["s"])
            ze = _interp(t, e["t"], e["z_low"])
            set_ = _interp(t, e_t["t"], e_t["s"])
            print(f"\n=== E x {ef:g}, h = {h:g} ===")
            print(f"  Exudyn s check: max|SlidingCoordinate - s(data)| = "
                  f"{np.abs(e['s_sensor'] - e['s']).max():.2e}, max|s(data) - s(position)| = "
                  f"{np.abs(e['s'] - e['s_geom']).max():.2e} m (position projected on the "
                  f"reference arc), elements visited {e['element'].min()}..{e['element'].max()}")
            print(f"  {'t [s]':>6} {'s Exudyn ring':>14} {'s Exu 1e-10':>12} {'s flexmbs ring':>15}"
                  f" {'s flexmbs cyl':>14}"
                  f" {'z_low Exudyn':>13} {'z_low fm ring':>14} {'z_low fm cyl':>13}")
            for tr in REPORT_TIMES:
                if tr > args.t_end + 1e-12:
                    continue
                i = int(np.argmin(np.abs(t - tr)))
                print(f"  {t[i]:6.3f} {se[i]:14.8f} {set_[i]:12.8f} {fr['s'][i]:15.8f} {fc['s'][i]:14.8f}"
                      f" {ze[i]:13.5e} {fr['z_low'][i]:14.5e} {fc['z_low'][i]:13.5e}")
            d_ring = np.abs(fr["s"] - se).max()
            d_cyl = np.abs(fc["s"] - se).max()
            d_tight = np.abs(fr["s"] - set_).max()
            dz = np.abs(fr["z_low"] - ze).max()
            print(f"  max|s_fm_ring - s_exu| = {d_ring:.3e} m, max|s_fm_cyl - s_exu| = {d_cyl:.3e} m, "
                  f"max|s_fm_ring - s_exu(1e-10)| = {d_tight:.3e} m, "
                  f"max|z_low_fm_ring - z_low_exu| = {dz:.3e} m, "
                  f"min z_low: exu {e['z_low'].min():.5e}, fm ring {fr['z_low'].min():.5e}, "
                  f"fm cyl {fc['z_low'].min():.5e}")
            for name, tt, ss, T in (("Exudyn ring", e["t"], e["s"], T_ring),
                                    ("Exu 1e-10", e_t["t"], e_t["s"], T_ring),
                                    ("flexmbs ring", fr["t"], fr["s"], T_ring),
                                    ("flexmbs cyl", fc["t"], fc["s"], T_cyl)):
                tc = passages(tt, ss)
                txt = f"  {name:<13} passages of the lowest point: " + ", ".join(f"{x:.5f}" for x in tc[:3])
                if len(tc) >= 2:
                    txt += (f"  | t1 vs T/4: {tc[0] - T / 4:+.2e} s, t2-t1 vs T/2: "
                            f"{tc[1] - tc[0] - T / 2:+.2e} s (rel {(tc[1] - tc[0]) / (T / 2) - 1:+.1e})")
                print(txt)
            print(f"  {'':13} {'wall [s]':>9} {'us/step':>9} {'newton':>7} {'jac':>6} {'it/step':>7}")
            for name, r in (("Exudyn", e), ("Exudyn nosens", e_nr), ("Exu 1e-10", e_t),
                            ("flexmbs ring", fr),
                            ("flexmbs cyl", fc)):
                print(f"  {name:<13} {r['wall']:9.3f} {1e6 * r['wall'] / r['steps']:9.1f} "
                      f"{r['newton']:7d} {r['jac']:6d} {r['newton'] / r['steps']:7.2f}")
            print(f"  ratio flexmbs/Exudyn wall: ring {fr['wall'] / e['wall']:.2f}, "
                  f"cyl {fc['wall'] / e['wall']:.2f} (Exudyn with sensors; vs sensors off: ring "
                  f"{fr['wall'] / e_nr['wall']:.2f})")
            summary.append((ef, h, d_ring, d_tight, d_cyl, fr["wall"] / e["wall"],
                            fc["wall"] / e["wall"]))
    print("\nsummary (max|ds| = max over the run of |s_flexmbs - s_Exudyn|, Exudyn = ring joint)")
    print("  E-factor  h       ring       ring vs Exu 1e-10   cyl      wall ratio ring   cyl")
    for ef, h, dr, dt_, dc, rr, rc in summary:
        print(f"  {ef:8g}  {h:<6g} {dr:10.3e} {dt_:12.3e} {dc:14.3e} {rr:10.2f} {rc:9.2f}")
    return 0


if __name__ == "__main__":
    t0 = time.perf_counter()
    rc = main()
    print(f"benchmark wall time {time.perf_counter() - t0:.1f} s")
    raise SystemExit(rc)

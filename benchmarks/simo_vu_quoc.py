"""The Simo–Vu-Quoc right-angle cantilever (Simo & Vu-Quoc 1988, out-of-plane impulse), side by
side: flexmbs's 14-DOF rod against Exudyn's geometrically exact beam.

Model (the published one, with one deliberate change): two arms of length 10, the first along
global y from a clamp at the origin to the elbow (0, 10, 0), the second along global x from the
elbow to the tip (10, 10, 0); EA = GA = 1e6, EI = GJ = 1e3, ρA = 1, polar rotary inertia ρJ = 20;
an out-of-plane force F_z(t) at the elbow, 50 t for t ≤ 1, 50 (2 − t) for 1 ≤ t ≤ 2, zero after.
The change: the published bending rotary inertia ρI = 10 is replaced by a negligible one in
Exudyn, because the rod is an Euler–Bernoulli element without rotary inertia of bending (its
sections' only rotary inertia is the spin about the axis, docs/theory.md §I.2.3); with ρI = 10 the
published response is slower. The arms meet rigidly in a small rigid body at the elbow (mass
0.01, inertia 1e-4; a flexmbs beam cannot kink at a node); the Exudyn model has the same body.

``python benchmarks/simo_vu_quoc.py --write-reference`` runs Exudyn (80 linear elements per arm,
converged: 40 elements differ from 80 by 0.008 at most, 0.08 % of the tip amplitude) and writes the
elbow and tip out-of-plane displacements to ``tests/data/simo_vu_quoc_exudyn.csv``, which the test
``tests/physics/test_rod.py::test_simo_vu_quoc_right_angle_cantilever`` compares with flexmbs.
Without the flag it prints both histories' largest difference and the run times.
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

ARM = 10.0
SECTION = dict(EA=1e6, GA=1e6, EI=1e3, GJ=1e3, rhoA=1.0, rhoJ=20.0)
BENDING_ROTARY_INERTIA = 1e-3          # Exudyn only: ρI (published 10; the rod has none)
ELBOW = dict(mass=0.01, inertia=1e-4)
F_PEAK = 50.0
T_END = 15.0
DT = 0.01
RHO_INF = 0.9
REFERENCE = Path(__file__).resolve().parents[1] / "tests" / "data" / "simo_vu_quoc_exudyn.csv"


def elbow_force(t: float) -> float:
    """The published triangular pulse F_z(t)."""
    if t <= 1.0:
        return F_PEAK * max(t, 0.0)
    if t <= 2.0:
        return F_PEAK * (2.0 - t)
    return 0.0


def run_exudyn(elements_per_arm: int, *, dt: float = DT, t_end: float = T_END,
               rho_inf: float = RHO_INF) -> dict:
    """Exudyn 1.13: ``ObjectBeamGeometricallyExact`` on Euler-parameter nodes, implicit
    generalized-α; returns the times and the elbow and tip z displacements."""
    import exudyn as exu
    from exudyn.itemInterface import (
        GenericJoint,
        LoadForceVector,
        MarkerNodeRigid,
        NodePointGround,
        NodeRigidBodyEP,
        ObjectBeamGeometricallyExact,
        ObjectRigidBody,
        SensorNode,
    )
    from exudyn.rigidBodyUtilities import RotationMatrix2EulerParameters, RotationMatrixZ

    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    s = SECTION
    section = exu.BeamSection()
    section.stiffnessMatrix = np.diag([s["EA"], s["GA"], s["GA"], s["GJ"], s["EI"], s["EI"]])
    section.inertia = np.diag([s["rhoJ"], BENDING_ROTARY_INERTIA, BENDING_ROTARY_INERTIA])
    section.massPerLength = s["rhoA"]
    h = ARM / elements_per_arm
    turn = RotationMatrixZ(np.pi / 2)                 # arm 1: local x along global y
    ep1 = list(RotationMatrix2EulerParameters(turn))
    ep0 = [1.0, 0.0, 0.0, 0.0]
    arm1 = [mbs.AddNode(NodeRigidBodyEP(referenceCoordinates=[0, i * h, 0] + ep1))
            for i in range(elements_per_arm + 1)]
    arm2 = [mbs.AddNode(NodeRigidBodyEP(referenceCoordinates=[i * h, ARM, 0] + ep0))
            for i in range(elements_per_arm + 1)]
    for nodes in (arm1, arm2):
        for a, b in zip(nodes[:-1], nodes[1:], strict=True):
            mbs.AddObject(ObjectBeamGeometricallyExact(nodeNumbers=[a, b], length=h,
                                                       sectionData=section))
    body_node = mbs.AddNode(NodeRigidBodyEP(referenceCoordinates=[0, ARM, 0] + ep0))
    J = ELBOW["inertia"]
    mbs.AddObject(ObjectRigidBody(nodeNumber=body_node, mass=ELBOW["mass"], inertia=[J, J, J, 0, 0, 0]))
    # joint frames turned as arm 1's nodes, so that the clamp and the elbow start aligned
    ground = mbs.AddMarker(MarkerNodeRigid(nodeNumber=mbs.AddNode(NodePointGround()),
                                           localHT=exu.HT(rotation=turn)))
    body = mbs.AddMarker(MarkerNodeRigid(nodeNumber=body_node))
    body_turned = mbs.AddMarker(MarkerNodeRigid(nodeNumber=body_node, localHT=exu.HT(rotation=turn)))
    mbs.AddObject(GenericJoint(markerNumbers=[ground, mbs.AddMarker(MarkerNodeRigid(nodeNumber=arm1[0]))]))
    mbs.AddObject(GenericJoint(markerNumbers=[body_turned,
                                              mbs.AddMarker(MarkerNodeRigid(nodeNumber=arm1[-1]))]))
    mbs.AddObject(GenericJoint(markerNumbers=[body, mbs.AddMarker(MarkerNodeRigid(nodeNumber=arm2[0]))]))
    mbs.AddLoad(LoadForceVector(markerNumber=body, loadVector=[0, 0, 1.0],
                            loadVectorUserFunction=lambda mbs, t, load: [0, 0, elbow_force(t)]))
    sensors = [mbs.AddSensor(SensorNode(nodeNumber=n, storeInternal=True,
                                        outputVariableType=exu.OutputVariableType.Displacement))
               for n in (body_node, arm2[-1])]
    mbs.Assemble()

    st = exu.SimulationSettings()
    st.solution.file.write = False
    st.solution.sensors.writePeriod = dt
    st.linearSolver.solverType = exu.LinearSolverType.EigenSparse
    ti = st.timeIntegration
    ti.numberOfSteps = int(round(t_end / dt))
    ti.endTime = t_end
    ti.verboseMode = 0
    ti.adaptiveStep = False
    ti.generalizedAlpha.spectralRadius = rho_inf
    ti.newton.residualMode = 1                        # converged when the increment is small
    ti.newton.relativeTolerance = ti.newton.absoluteTolerance = 1e-9
    start = time.perf_counter()
    exu.SolveDynamic(mbs, st)
    wall = time.perf_counter() - start
    elbow, tip = (mbs.GetSensorStoredData(k) for k in sensors)
    return dict(t=elbow[:, 0], elbow=elbow[:, 3], tip=tip[:, 3], wall=wall)


def run_flexmbs(elements_per_arm: int, *, dt: float = DT, t_end: float = T_END,
                rho_inf: float = RHO_INF) -> dict:
    """The same model with two ``ancf_rod14`` beams rigidly joined to the elbow body."""
    import flexmbs as fm

    model = fm.Model()
    s = SECTION
    section = fm.BeamStiffness(axial_stiffness=s["EA"], bending_stiffness=s["EI"],
                               mass_per_length=s["rhoA"], torsional_stiffness=s["GJ"],
                               twist_inertia=s["rhoJ"])
    arm1 = model.add_beam(fm.line((0, 0, 0), (0, ARM, 0), elements=elements_per_arm),
                          section=section, element="ancf_rod14", name="arm1")
    arm2 = model.add_beam(fm.line((0, ARM, 0), (ARM, ARM, 0), elements=elements_per_arm),
                          section=section, element="ancf_rod14", name="arm2")
    J = ELBOW["inertia"]
    elbow = model.add_rigid_body(mass=ELBOW["mass"], inertia=(J, J, J), position=(0, ARM, 0),
                                 name="elbow")
    model.clamp(arm1.first_node)
    model.rigid(arm1.last_node, elbow)
    model.rigid(arm2.first_node, elbow)
    model.add_point_load(elbow, (0, 0, 1.0), function=elbow_force)
    start = time.perf_counter()
    res = fm.simulate(model, t_end=t_end, dt=dt, integrator=fm.GeneralizedAlpha(rho_inf=rho_inf))
    wall = time.perf_counter() - start
    return dict(t=res.t, elbow=res.body_position(elbow)[:, 2],
                tip=res.node_displacement(arm2.last_node)[:, 2], wall=wall)


def main() -> None:  # pragma: no cover - manual benchmark / reference generator
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write-reference", action="store_true",
                        help=f"run Exudyn and write {REFERENCE.relative_to(REFERENCE.parents[2])}")
    parser.add_argument("--exudyn-elements", type=int, default=80)
    parser.add_argument("--flexmbs-elements", type=int, default=8)
    args = parser.parse_args()
    ex = run_exudyn(args.exudyn_elements)
    print(f"Exudyn {args.exudyn_elements} el/arm: {ex['wall']:.2f} s; "
          f"max |tip z| {np.abs(ex['tip']).max():.4f}, max |elbow z| {np.abs(ex['elbow']).max():.4f}")
    if args.write_reference:
        import exudyn

        REFERENCE.parent.mkdir(parents=True, exist_ok=True)
        header = (f"Simo-Vu-Quoc right-angle cantilever, Exudyn {exudyn.__version__} "
                  f"ObjectBeamGeometricallyExact, {args.exudyn_elements} elements per arm, "
                  f"generalized-alpha rho_inf={RHO_INF}, dt={DT}; bending rotary inertia "
                  f"{BENDING_ROTARY_INERTIA} (see benchmarks/simo_vu_quoc.py)\n"
                  "t,elbow_z,tip_z")
        np.savetxt(REFERENCE, np.column_stack([ex["t"], ex["elbow"], ex["tip"]]),
                   delimiter=",", header=header, fmt="%.6e")
        print(f"wrote {REFERENCE}")
    fx = run_flexmbs(args.flexmbs_elements)
    tip = np.interp(fx["t"], ex["t"], ex["tip"])
    elbow = np.interp(fx["t"], ex["t"], ex["elbow"])
    print(f"flexmbs {args.flexmbs_elements} el/arm: {fx['wall']:.2f} s; "
          f"max |tip - Exudyn| {np.abs(fx['tip'] - tip).max():.4f}, "
          f"max |elbow - Exudyn| {np.abs(fx['elbow'] - elbow).max():.4f}")


if __name__ == "__main__":  # pragma: no cover
    main()

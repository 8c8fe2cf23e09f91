"""Exudyn reference models for the flexmbs side-by-side benchmark.

Model: straight 3D ANCF cable (``ObjectANCFCable``, 2 x ``NodePointSlope1`` =
12 DOF per element) along +x from (0,0,0) to (L,0,0), clamped at x=0 (node
position and the two transverse slope components fixed through
``CoordinateConstraint`` to ground, i.e. ``fixedConstraintsNode0=[1,1,1,0,1,1]``;
the axial slope stays free), released from rest in the straight configuration
under gravity (mass-proportional ``Gravity`` load on each element).

Only ``exu.SolveDynamic`` / ``exu.SolveStatic`` is timed (``time.perf_counter``);
``mbs.Assemble()`` is done beforehand and all file output, sensors, console
output and the renderer are switched off.

Run ``python benchmarks/exudyn_models.py`` for the table.
"""
from __future__ import annotations

import time
from typing import Any

import numpy as np

CANTILEVER = dict(
    length=1.0,
    mass_per_length=0.5,
    axial_stiffness=1e7,
    bending_stiffness=50.0,
    gravity=(0.0, 0.0, -9.81),
)

# ObjectANCFCable.useReducedOrderIntegration used for reduced_integration=True.
# In Exudyn 1.13.6 the 3D cable accepts 0, 1, 2 (3 raises "must be between 0 and 2"):
#   0: axial Gauss order 9 (5 pts), bending Gauss order 5 (3 pts)
#   1: axial Gauss order 7 (4 pts), bending Gauss order 3 (2 pts)
#   2: axial Lobatto order 3 (3 pts: 0, L/2, L), bending Gauss order 3 (2 pts)
REDUCED_INTEGRATION_FLAG = 2

# Linear solver: Exudyn's default is EXUdense; for a banded beam EigenSparse is the
# sensible choice (~9x faster at 128 elements here), so it is the default.
DEFAULT_LINEAR_SOLVER = "EigenSparse"

_exu = None


def exudyn_available() -> bool:
    """True if ``exudyn`` can be imported."""
    global _exu
    if _exu is not None:
        return True
    try:
        import exudyn
    except Exception:  # pragma: no cover - depends on environment
        return False
    _exu = exudyn
    return True


def _require_exudyn():
    if not exudyn_available():
        raise RuntimeError("exudyn is not installed (pip install exudyn)")
    return _exu


def _build_cantilever(n_elem: int, reduced_integration: bool):
    exu = _require_exudyn()
    from exudyn.itemInterface import (
        CoordinateConstraint,
        Gravity,
        MarkerBodyMass,
        MarkerNodeCoordinate,
        NodePointGround,
        NodePointSlope1,
        ObjectANCFCable,
        VCoordinateConstraint,
        VNodePointGround,
        VNodePointSlope1,
        VObjectANCFCable,
    )

    p = CANTILEVER
    L = float(p["length"])
    le = L / n_elem

    SC = exu.SystemContainer()
    mbs = SC.AddSystem()

    nodes = [mbs.AddNode(NodePointSlope1(referenceCoordinates=[i * le, 0.0, 0.0, 1.0, 0.0, 0.0],
                                         visualization=VNodePointSlope1(show=False)))
             for i in range(n_elem + 1)]
    flag = REDUCED_INTEGRATION_FLAG if reduced_integration else 0
    for i in range(n_elem):
        oCable = mbs.AddObject(ObjectANCFCable(
            length=le,
            massPerLength=p["mass_per_length"],
            axialStiffness=p["axial_stiffness"],
            bendingStiffness=p["bending_stiffness"],
            nodeNumbers=[nodes[i], nodes[i + 1]],
            useReducedOrderIntegration=flag,
            visualization=VObjectANCFCable(show=False),
        ))
        mMass = mbs.AddMarker(MarkerBodyMass(bodyNumber=oCable))
        mbs.AddLoad(Gravity(markerNumber=mMass, loadVector=list(p["gravity"])))

    # clamp: same pattern as exudyn.beams.GenerateStraightBeam(fixedConstraintsNode0=[1,1,1,0,1,1])
    nGround = mbs.AddNode(NodePointGround(referenceCoordinates=[0.0, 0.0, 0.0],
                                          visualization=VNodePointGround(show=False)))
    mGround = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nGround, coordinate=0))
    for j, fixed in enumerate((1, 1, 1, 0, 1, 1)):
        if fixed:
            m = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nodes[0], coordinate=j))
            mbs.AddObject(CoordinateConstraint(markerNumbers=[mGround, m],
                                               visualization=VCoordinateConstraint(show=False)))
    mbs.Assemble()
    return SC, mbs, nodes[-1]


def _quiet_settings(linear_solver: str):
    exu = _require_exudyn()
    s = exu.SimulationSettings()
    # no files, no sensors, no console output
    s.solution.file.write = False
    s.solution.sensors.active = False
    s.solution.restart.write = False
    s.solution.recordImagesInterval = -1
    s.show.statistics = False
    s.show.computationTime = False
    s.show.globalTimers = False
    s.timeIntegration.verboseMode = 0
    s.timeIntegration.verboseModeFile = 0
    s.staticSolver.verboseMode = 0
    s.staticSolver.verboseModeFile = 0
    s.linearSolver.solverType = getattr(exu.LinearSolverType, linear_solver)
    s.parallel.numberOfThreads = 1
    return s


def _tip_displacement(mbs, tip_node):
    exu = _require_exudyn()
    return np.array(mbs.GetNodeOutput(tip_node, exu.OutputVariableType.Displacement), dtype=float)


def run_exudyn_cantilever(n_elem: int, *, h: float = 1e-3, t_end: float = 0.5, rho_inf: float = 0.8,
                          reduced_integration: bool = True, modified_newton: bool = True,
                          relative_tolerance: float = 1e-8, static: bool = False,
                          linear_solver: str = DEFAULT_LINEAR_SOLVER,
                          residual_mode: int = 1, absolute_tolerance: float | None = None) -> dict:
    """Run the clamped ANCF-cable cantilever in Exudyn and return timing/accuracy data.

    Dynamic (default): generalized-alpha (index 3, no Newmark, no index-2 constraints),
    fixed step ``h`` up to ``t_end``, spectral radius ``rho_inf``; modified or full Newton.
    ``static=True``: ``exu.SolveStatic`` with full Newton, one load step (standard
    residual-based convergence test, ``relative_tolerance``).

    Newton convergence test (dynamic only), ``timeIntegration.newton.residualMode``:

    * ``residual_mode=1`` (default here): error = Newton *increment*; Exudyn's docs require
      ``absoluteTolerance == relativeTolerance`` for this mode, so ``absolute_tolerance``
      defaults to ``relative_tolerance``.
    * ``residual_mode=0`` (Exudyn's own default): error = L2 norm of the residual relative
      to the step's initial residual (``absoluteTolerance`` default 1e-10).  For this model
      the residual has a round-off floor of ~3e-8 (EA = 1e7 times machine epsilon), so
      ``relative_tolerance=1e-8`` cannot be met and the solve fails after 25 iterations.
      Smallest rtol that works for t_end=0.5: 1e-7 (8 elements), 1e-6 (32), 1e-5 (128).

    Extra result keys besides the requested ones: ``rejected_modified_newton_steps``,
    ``n_ode2``, ``linear_solver``, ``reduced_integration_flag``, ``residual_mode``.
    Newton statistics come from ``mbs.sys['dynamicSolver'].it`` (``SolverIterationData``,
    totals over the whole solve): ``newtonStepsCount`` and ``newtonJacobiCount``.
    """
    exu = _require_exudyn()
    SC, mbs, tip = _build_cantilever(n_elem, reduced_integration)
    s = _quiet_settings(linear_solver)

    if static:
        ss = s.staticSolver
        ss.numberOfLoadSteps = 1
        ss.adaptiveStep = False
        ss.newton.useModifiedNewton = False
        ss.newton.relativeTolerance = relative_tolerance
        t0 = time.perf_counter()
        ok = exu.SolveStatic(mbs, s, storeSolver=True)
        wall = time.perf_counter() - t0
        if not ok:
            raise RuntimeError("Exudyn SolveStatic failed")
        solver = mbs.sys["staticSolver"]
        steps = 1
    else:
        wall, solver, steps = solve_dynamic_timed(
            mbs, s, h=h, t_end=t_end, rho_inf=rho_inf, modified_newton=modified_newton,
            relative_tolerance=relative_tolerance, residual_mode=residual_mode,
            absolute_tolerance=absolute_tolerance)

    # solver statistics (SolverIterationData, cumulative over the whole solve)
    it = solver.it
    return dict(
        n_elem=n_elem,
        steps=steps,
        wall_time=wall,
        us_per_step=1e6 * wall / steps,
        us_per_element_step=1e6 * wall / (steps * n_elem),
        tip_displacement=_tip_displacement(mbs, tip),
        newton_iterations_total=int(it.newtonStepsCount),
        jacobian_updates=int(it.newtonJacobiCount),
        rejected_modified_newton_steps=int(it.rejectedModifiedNewtonSteps),
        n_ode2=int(mbs.systemData.ODE2Size()),
        linear_solver=linear_solver,
        reduced_integration_flag=REDUCED_INTEGRATION_FLAG if reduced_integration else 0,
        residual_mode=None if static else int(residual_mode),
    )


def alpha_settings(s: Any, *, h: float, t_end: float, rho_inf: float, modified_newton: bool,
                   relative_tolerance: float, residual_mode: int,
                   absolute_tolerance: float | None = None) -> int:
    """Exudyn's generalized-α settings of every comparison: the fixed step ``h`` to ``t_end``
    (no step control), index 3, initial accelerations computed, the Newton settings of
    :func:`run_exudyn_cantilever`'s docstring. Returns the number of steps."""
    n_steps = int(round(t_end / h))
    ti = s.timeIntegration
    ti.startTime = 0.0
    ti.endTime = n_steps * h
    ti.numberOfSteps = n_steps
    ti.initialStepSize = h
    ti.adaptiveStep = False          # no step reduction
    ti.automaticStepSize = False     # no error-controlled step size
    ga = ti.generalizedAlpha
    ga.spectralRadius = rho_inf
    ga.useIndex2Constraints = False
    ga.useNewmark = False
    ga.computeInitialAccelerations = True
    nw = ti.newton
    nw.useModifiedNewton = bool(modified_newton)
    nw.relativeTolerance = relative_tolerance
    nw.residualMode = int(residual_mode)
    if absolute_tolerance is None and residual_mode == 1:
        absolute_tolerance = relative_tolerance
    if absolute_tolerance is not None:
        nw.absoluteTolerance = absolute_tolerance
    return n_steps


def solve_dynamic_timed(mbs: Any, s: Any, **alpha: Any) -> tuple[float, Any, int]:
    """:func:`alpha_settings` (keyword arguments ``alpha``), then ``SolveDynamic`` timed alone.
    Returns (wall seconds, the stored solver, steps)."""
    exu = _require_exudyn()
    n_steps = alpha_settings(s, **alpha)
    t0 = time.perf_counter()
    ok = exu.SolveDynamic(mbs, s, solverType=exu.DynamicSolverType.GeneralizedAlpha,
                          storeSolver=True)
    wall = time.perf_counter() - t0
    if not ok:
        raise RuntimeError("Exudyn SolveDynamic failed")
    solver = mbs.sys["dynamicSolver"]
    if abs(solver.it.currentTime - s.timeIntegration.endTime) > 1e-9:
        raise RuntimeError(f"unexpected end time t={solver.it.currentTime}")
    return wall, solver, n_steps


def static_tip_closed_form() -> float:
    """Small-deflection cantilever under uniform load: w = q L^4 / (8 EI), q = rhoA*|g|."""
    p = CANTILEVER
    q = p["mass_per_length"] * abs(p["gravity"][2])
    return q * p["length"] ** 4 / (8.0 * p["bending_stiffness"])


def _row(rep, n, **kw):
    try:
        r = run_exudyn_cantilever(n, **kw)
    except Exception as e:  # Exudyn raises SolverError if Newton does not converge
        return f"{rep:>3} {n:>6} FAILED: {e}"
    return (f"{rep:>3} {n:>6} {r['n_ode2']:>6} {r['steps']:>5} {r['wall_time']:>8.4f} "
            f"{r['us_per_step']:>9.1f} {r['us_per_element_step']:>10.2f} "
            f"{r['newton_iterations_total']:>7} {r['jacobian_updates']:>5} "
            f"{r['tip_displacement'][2]:>16.10e}")


def _main():  # pragma: no cover - manual benchmark
    import platform
    import sys
    if not exudyn_available():
        print("exudyn not available")
        return
    exu = _require_exudyn()
    print(f"exudyn {exu.__version__} ({exu.__name__} compiled module: "
          f"{'exudynCPPfast' if getattr(sys, 'exudynFast', False) else 'default'}), "
          f"python {platform.python_version()}, {platform.machine()}")
    print(f"model: {CANTILEVER}")
    hdr = (f"{'rep':>3} {'n_elem':>6} {'nODE2':>6} {'steps':>5} {'wall[s]':>8} {'us/step':>9} "
           f"{'us/el/step':>10} {'newton':>7} {'jac':>5} {'tip_z[m]':>16}")
    run_exudyn_cantilever(8, t_end=0.05)  # warm-up

    cases = [
        ("A: modified Newton, residualMode=1 (increment), tol=1e-8  [default]",
         dict(), (1, 2)),
        ("B: full Newton, residualMode=1 (increment), tol=1e-8",
         dict(modified_newton=False), (1,)),
        ("C: modified Newton, residualMode=0 (Exudyn default, residual), rtol=1e-8",
         dict(residual_mode=0), (1,)),
        ("D: modified Newton, residualMode=0 (Exudyn default, residual), rtol=1e-5",
         dict(residual_mode=0, relative_tolerance=1e-5), (1, 2)),
        ("E: full Newton, residualMode=0 (Exudyn default, residual), rtol=1e-5",
         dict(residual_mode=0, relative_tolerance=1e-5, modified_newton=False), (1,)),
    ]
    for title, kw, reps in cases:
        print(f"\ndynamic, gen.-alpha rho_inf=0.8, index 3, h=1e-3, t_end=0.5, "
              f"useReducedOrderIntegration={REDUCED_INTEGRATION_FLAG}, {DEFAULT_LINEAR_SOLVER}, 1 thread")
        print(title)
        print(hdr)
        for rep in reps:
            for n in (8, 32, 128):
                print(_row(rep, n, **kw), flush=True)

    w_ref = static_tip_closed_form()
    print(f"\nstatic (SolveStatic, full Newton, 1 load step, rtol=1e-8); "
          f"closed form qL^4/(8EI) = {w_ref:.8e} m")
    for n in (8, 32):
        r = run_exudyn_cantilever(n, static=True)
        tip = r["tip_displacement"]
        rel = (abs(tip[2]) - w_ref) / w_ref
        print(f"  n_elem={n:>3}: tip = [{tip[0]:+.6e}, {tip[1]:+.6e}, {tip[2]:+.8e}]  "
              f"rel.diff(|w_z|) = {rel:+.3e}  newton={r['newton_iterations_total']} "
              f"jac={r['jacobian_updates']}  wall={1e3 * r['wall_time']:.2f} ms")


if __name__ == "__main__":
    _main()

"""High-level entry points: :func:`solve_static`, :func:`simulate`, :func:`modes`."""

from __future__ import annotations

import contextlib
import dataclasses
import json
import math
import os
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from . import driver
from .assembly import Assembly
from .budget import check_run
from .checks import RunChecks
from .elements import hermite
from .errors import ConvergenceError, FlexmbsWarning, ModelError, ScenarioError
from .io.checkpoint import CheckpointVersionError, load_checkpoint
from .io.output import OutputWriter, failure_reason
from .io.probes import Probe, probe_columns
from .model import Beam, Model, Node, RigidBody
from .solvers.eigen import Modes, eigenmodes
from .solvers.generalized_alpha import (
    GeneralizedAlpha,
    IntegrationStats,
    State,
    check_masses,
    consistent_initial_state,
    integrate,
)
from .solvers.static import QuasiStaticResult, StaticOptions, StaticResult
from .solvers.static import solve_quasi_static as _solve_quasi_static
from .solvers.static import solve_static as _solve_static


@dataclass
class Result:
    """Time histories at the output times, with accessors by model object.

    Returned by :func:`simulate`, not made by hand.

    Parameters
    ----------
    assembly : Assembly
        The assembled model (numbering of the coordinates).
    t : ndarray, shape (n_out,)
        Output times [s] (the last only after ``simulate(..., keep_history=False)``).
    q, v : ndarray, shape (n_out, n_coords)
        Coordinates and velocities at the output times.
    lam : ndarray, shape (n_out, n_mult)
        Constraint multipliers at the output times.
    energy : dict of str to ndarray
        Energy histories by kind (``"total"`` among them), when recorded.
    stats : IntegrationStats
        Steps, Newton iterations, factorisations, rejected steps.
    wall_time : float
        Wall time of the run [s].
    final_state : State
        The state at the end of the run.
    status : str, default "completed"
        How the run ended.
    extra : dict
        Further results, e.g. ``extra["probes"]``, the probe values.
    """

    assembly: Assembly
    t: np.ndarray
    q: np.ndarray                      # (n_out, n_coords)
    v: np.ndarray
    lam: np.ndarray
    energy: dict[str, np.ndarray]
    stats: IntegrationStats
    wall_time: float
    final_state: State
    status: str = "completed"
    extra: dict = field(default_factory=dict)

    def node_position(self, node: Node) -> np.ndarray:
        d = self.assembly.node_dofs(node)
        return self.q[:, d[:3]]

    def node_displacement(self, node: Node) -> np.ndarray:
        d = self.assembly.node_dofs(node)
        return self.q[:, d[:3]] - self.assembly.q_ref[d[:3]]

    def beam_point(self, beam: Beam, s: float, quantity: str = "position") -> np.ndarray:
        """Position, displacement or velocity history of the material point at arc length ``s``."""
        e, xi = beam.locate(s)
        S, dofs = hermite.centerline_interpolation(self.assembly.centerline_dofs(beam),
                                                 beam.centerline.lengths, np.array([e]),
                                                 np.array([xi]))

        def interp(X: np.ndarray) -> np.ndarray:
            return hermite.interpolate(S, dofs, X)[..., 0, :]
        if quantity == "position":
            return interp(self.q)
        if quantity == "displacement":
            return interp(self.q) - interp(self.assembly.q_ref[None, :])
        if quantity == "velocity":
            return interp(self.v)
        raise ModelError(f"quantity must be position, displacement or velocity (got {quantity!r})")

    def body_position(self, body: RigidBody) -> np.ndarray:
        return self.q[:, self.assembly.body_dofs(body)[:3]]

    def body_quaternion(self, body: RigidBody) -> np.ndarray:
        return self.q[:, self.assembly.body_dofs(body)[3:]]

    def reaction(self, constraint: str, part: Beam | RigidBody | str | None = None,
                 ) -> tuple[np.ndarray, np.ndarray]:
        """Force and moment histories, each (n_out, 3) in global components, of the constraint
        or joint named ``constraint`` on ``part`` (a beam or body, default the first it acts
        on); the moment is about the body's centre of mass or the beam's first node involved
        (:mod:`flexmbs.constraints.reactions`)."""
        from .io.probes import ReactionProbe

        probe = ReactionProbe("reaction", constraint,
                              None if part is None else str(getattr(part, "name", part)))
        probe.check(self.assembly)
        vals = np.array([probe.evaluate(self.assembly, State(float(t), q, v, v, v, lam))
                         for t, q, v, lam in zip(self.t, self.q, self.v, self.lam, strict=True)])
        return vals[:, :3], vals[:, 3:]


def beam_positions(asm: Assembly, beam: Beam, q: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Centreline positions (len(s), 3) of ``beam`` in configuration ``q`` at reference arc
    lengths ``s`` (measured from the first node)."""
    s = np.atleast_1d(np.asarray(s, float))
    loc = [beam.locate(float(x)) for x in s]
    return hermite.centerline_points(q, asm.centerline_dofs(beam), beam.centerline.lengths,
                                   np.array([a for a, _ in loc]), np.array([b for _, b in loc]))


def solve_static(model: Model | Assembly, options: StaticOptions | None = None, *,
                 t: float = 0.0, redundant_constraints: str = "error",
                 out: str | os.PathLike | None = None, probes: Sequence[Probe] = (),
                 name: str | None = None, metadata: dict | None = None,
                 write_vtu: bool = True, output_frames: str = "multiblock",
                 vtk_compression: bool = False) -> StaticResult:
    """Static equilibrium of ``model`` under its loads at time ``t`` (load stepping with
    ``options``).

    With ``out`` the equilibrium is written as the output folder (the docs' "Command line"
    page, "Output folder") with one frame at ``t`` (zero velocity): ``<name>.pvd`` +
    ``vtu/``, ``probes.csv`` with ``probes``, ``contacts.csv``, ``checkpoint.npz`` and
    ``summary.json`` (``name`` defaults to the model name; ``metadata`` is stored in the
    summary; ``output_frames``: ``"multiblock"`` or ``"merged"``, see
    :mod:`flexmbs.io.frames`). A solve that does not converge leaves the folder with
    ``status: "failed: ..."`` and raises :class:`ConvergenceError`.

    Parameters
    ----------
    model : Model or Assembly
        The model.
    options : StaticOptions, optional
        Load stepping and Newton options.
    t : float, default 0
        Time at which the loads' time functions are evaluated [s].
    redundant_constraints : {"error", "drop"}, default "error"
        What to do with redundant constraint equations.
    out : str or os.PathLike, optional
        Output folder (default: none written).
    probes : sequence of Probe, optional
        Probes written to ``probes.csv``.
    name : str, optional
        Name of the output files (default: the model's name).
    metadata : dict, optional
        Stored in ``summary.json``.
    write_vtu : bool, default True
        Write the VTK frame.
    output_frames : {"multiblock", "merged"}, default "multiblock"
        Form of the frame.
    vtk_compression : bool, default False
        zlib-compress the frame's data arrays.

    Returns
    -------
    StaticResult
        The equilibrium ``q``, the multipliers ``lam``, and the numbers of load increments and
        Newton iterations.
    """
    asm = model if isinstance(model, Assembly) else Assembly(
        model, redundant_constraints=redundant_constraints)
    if out is None:
        return _solve_static(asm, options, t=t)
    with _EquilibriumWriter(asm, out, name, probes, metadata, write_vtu, output_frames,
                            vtk_compression) as w:
        st = w.run(lambda: _solve_static(asm, options, t=t))
        w.frame(t, st.q, st.lam)
        w.done(st.newton_iterations, st.load_increments)
    return st


def solve_quasi_static(model: Model | Assembly, times: Sequence[float] | np.ndarray,
                       options: StaticOptions | None = None, *,
                       redundant_constraints: str = "error",
                       out: str | os.PathLike | None = None, probes: Sequence[Probe] = (),
                       name: str | None = None, metadata: dict | None = None,
                       write_vtu: bool = True, output_frames: str = "multiblock",
                       vtk_compression: bool = False) -> QuasiStaticResult:
    """Equilibria of ``model`` at the increasing ``times``, each continued from the last
    (:func:`flexmbs.solvers.static.solve_quasi_static`): a slow pull and release through
    holes with friction traces its hysteresis. With ``out`` every equilibrium is a frame of
    the output folder (as :func:`solve_static` writes one, with the same options); the frames
    written before a failure stay readable and the summary says where it stopped.

    Parameters
    ----------
    model : Model or Assembly
        The model.
    times : sequence of float
        Increasing times of the equilibria [s].
    options : StaticOptions, optional
        Load stepping of the first equilibrium and Newton settings of all.
    redundant_constraints : {"error", "drop"}, default "error"
        What to do with redundant constraint equations.
    out : str or os.PathLike, optional
        Output folder; one frame per equilibrium.
    probes : sequence of Probe, optional
        Probes written to ``probes.csv``, one row per equilibrium.
    name : str, optional
        Run name (default: the model's name).
    metadata : dict, optional
        Stored in ``summary.json``.
    write_vtu : bool, default True
        Write the VTU frames.
    output_frames : {"multiblock", "merged"}, default "multiblock"
        Form of the frames.
    vtk_compression : bool, default False
        zlib-compressed frame arrays.

    Returns
    -------
    QuasiStaticResult
        ``t``, ``q`` and ``lam`` (one row per time), ``load_increments``,
        ``newton_iterations`` and ``slope_search_from``.
    """
    asm = model if isinstance(model, Assembly) else Assembly(
        model, redundant_constraints=redundant_constraints)
    if out is None:
        return _solve_quasi_static(asm, times, options)
    with _EquilibriumWriter(asm, out, name, probes, metadata, write_vtu, output_frames,
                            vtk_compression) as w:
        res = w.run(lambda: _solve_quasi_static(asm, times, options, on_equilibrium=w.frame))
        w.done(res.newton_iterations, res.load_increments, steps=len(res.t))
    return res


class _EquilibriumWriter:
    """The output folder of a static or quasi-static solve: one frame per equilibrium (zero
    velocity), the summary's status and statistics."""

    def __init__(self, asm: Assembly, out: str | os.PathLike, name: str | None,
                 probes: Sequence[Probe], metadata: dict | None, write_vtu: bool,
                 output_frames: str, vtk_compression: bool) -> None:
        self.asm = asm
        self.run_name = str(name if name is not None else getattr(asm.model, "name", "model"))
        self.t0 = time.perf_counter()
        self.frames = 0
        self.writer = OutputWriter(out, self.run_name, asm, probes=probes, metadata=metadata,
                                   write_vtu=write_vtu, output_frames=output_frames,
                                   vtu_encoding="zlib" if vtk_compression else "binary")

    def __enter__(self) -> _EquilibriumWriter:
        self.writer.__enter__()
        return self

    def __exit__(self, *exc: Any) -> None:
        self.writer.__exit__(*exc)

    def run(self, solve: Callable[[], Any]) -> Any:
        try:
            return solve()
        except ConvergenceError as exc:
            self.writer.finish(f"failed: {failure_reason(exc)}", stats={"steps": self.frames},
                               wall_time=time.perf_counter() - self.t0)
            raise

    def frame(self, t: float, q: np.ndarray, lam: np.ndarray) -> None:
        zero = np.zeros_like(q)
        state = State(t, q.copy(), zero, zero.copy(), zero.copy(), lam.copy())
        self.asm.observe(state.q, state.v, state.lam, t)
        self.writer.write(state, contacts=interaction_outputs(self.asm, state),
                          sections=interaction_sections(self.asm, state),
                          checkpoint_extra={"scenario": self.run_name,
                                            "n_coords": int(self.asm.n_coords),
                                            "n_mult": int(self.asm.n_mult)})
        self.frames += 1

    def done(self, newton_iterations: int, load_increments: int, steps: int = 0) -> None:
        self.writer.finish("completed", stats={"steps": steps,
                                               "newton_iterations": newton_iterations,
                                               "rejected_steps": 0,
                                               "load_increments": load_increments},
                           wall_time=time.perf_counter() - self.t0)


def modes(model: Model | Assembly, *, n_modes: int | None = None, static: bool = False,
          redundant_constraints: str = "error") -> Modes:
    """Linearised modes about the reference (or, with ``static=True``, the loaded equilibrium).

    Parameters
    ----------
    model : Model or Assembly
        The model.
    n_modes : int, optional
        Number of modes, the lowest; only these are computed (default: all).
    static : bool, default False
        Linearise about the static equilibrium under the loads instead of the reference.
    redundant_constraints : {"error", "drop"}, default "error"
        What to do with redundant constraint equations.

    Returns
    -------
    Modes
        ``omega`` (angular frequencies [rad/s], ascending), ``frequencies`` [Hz] and
        ``shapes`` (n_coords, n_modes), mass-normalised.
    """
    if n_modes is not None and (isinstance(n_modes, bool) or not isinstance(n_modes, int)
                                or n_modes < 1):
        raise ModelError(f"modes: n_modes must be an integer >= 1 or None (got {n_modes!r})")
    asm = model if isinstance(model, Assembly) else Assembly(
        model, redundant_constraints=redundant_constraints)
    if static:
        st = _solve_static(asm)
        return eigenmodes(asm, st.q, st.lam, n_modes=n_modes)
    return eigenmodes(asm, n_modes=n_modes)


#: constraints whose Jacobian does not depend on the coordinates (nodal clamps and pins)
_LINEAR_CONSTRAINTS = ("clamp", "pin", "prescribed")


def _warn_undamped_constraints(model: Model, opts: GeneralizedAlpha) -> None:
    """rho_inf = 1 (no numerical damping) with nonlinear index-3 constraints: the period-2
    oscillation of the multipliers is not damped (a double root at -1 of the trapezoidal
    limit; Cardona & Geradin 1989), grows, and through the q-dependent constraint Jacobian
    feeds energy into the motion (issue "nothing lost": a heavy top gains 8 % of its energy in
    0.2 s). ``constraint_level = "position_velocity"`` removes the cause (the velocity
    corrector, docs/design-notes.md) except for drivers, whose ``Phi_t`` it leaves alone.
    Warned once per message."""
    if opts.rho_inf <= 0.99:
        return
    corrected = opts.constraint_level == "position_velocity"
    if corrected:
        nonlinear = [c.name for c in model.constraints if c.kind == "driver"]
    else:
        nonlinear = [c.name for c in model.constraints if c.kind not in _LINEAR_CONSTRAINTS]
        nonlinear += [j.name for j in model.interactions if j.constraints()]
    if not nonlinear:
        return
    names = f"{', '.join(nonlinear[:3])}{' ...' if len(nonlinear) > 3 else ''}"
    if corrected:
        warnings.warn(
            f"rho_inf = {opts.rho_inf:g} with the driver(s) {names}: the velocity corrector "
            "(constraint_level = \"position_velocity\") leaves equations with a time function "
            "at index 3, whose constraint forces oscillate from step to step with a growing "
            "amplitude; use rho_inf <= 0.95", FlexmbsWarning, stacklevel=1)
        return
    warnings.warn(
        f"rho_inf = {opts.rho_inf:g} with the nonlinear constraint(s) {names}: without "
        "numerical damping the constraint forces oscillate from step to step with a growing "
        "amplitude and energy drifts (index-3 constraints under the trapezoidal limit of "
        "generalized-alpha/HHT); set constraint_level = \"position_velocity\" (the velocity "
        "constraints held at every step: bounded forces, conserved energy), or use "
        "rho_inf <= 0.95, which damps only the unresolved high frequencies",
        FlexmbsWarning, stacklevel=1)


def _warn_motions_at_speed(model: Model, t_end: float) -> None:
    """A prescribed motion of a beam's node whose function moves at t = 0 while the beam starts
    at rest: the first step answers the velocity jump with an impulse (large reactions, the
    beam's damping force, a whipped tip), which is seldom meant. Only the start is checked:
    a rate of at least 1e-3 of the motion's range over the run per run length."""
    for c in model.constraints:
        if c.kind != "prescribed" or c.function is None or not isinstance(c.a, Node):
            continue
        rate = float(c.function.d1(0.0))
        times = np.linspace(0.0, t_end, 65)
        span = float(np.ptp([c.function(float(t)) for t in times]))
        if not (span > 0.0 and abs(rate) * t_end > 1e-3 * span):
            continue
        warnings.warn(
            f"prescribed motion '{c.name}' (beam '{c.a.beam.name}' node {c.a.index}) starts at "
            f"speed: its function's rate at t = 0 is {rate:.3g} per s while the beam starts at "
            "rest, a jump the first step answers with an impulse (large reactions and damping "
            "forces); start it from rest (a ramp with smooth = true) unless that is meant",
            FlexmbsWarning, stacklevel=3)


def simulate(model: Model | Assembly, *, t_end: float, dt: float,
             integrator: GeneralizedAlpha | None = None, output_interval: float | None = None,
             initial_static: bool = False, record_energy: bool = True,
             observer: Callable[[State], None] | None = None,
             progress: Callable[[State, IntegrationStats], None] | None = None,
             redundant_constraints: str = "error", out: str | os.PathLike | None = None,
             probes: Sequence[Probe] = (), name: str | None = None,
             static_options: StaticOptions | None = None, resume: bool = False,
             metadata: dict | None = None, write_vtu: bool = True,
             output_frames: str = "multiblock", vtk_compression: bool = False,
             keep_history: bool = True) -> Result:
    """Implicit dynamic simulation from the model's initial state (or its static equilibrium,
    ``initial_static=True``, solved with ``static_options``) to ``t_end`` with step ``dt``;
    results every ``output_interval``.

    With ``out`` the output folder (the docs' "Command line" page, "Output folder") is written
    as the run goes
    (``<name>.pvd`` + ``vtu/``, ``probes.csv`` with ``probes``, ``contacts.csv``,
    ``checkpoint.npz``, ``summary.json``; ``name`` defaults to the model name) and stays valid
    if the run fails (``status: "failed: ..."``) or is interrupted (``"interrupted"``);
    ``output_frames``: ``"multiblock"`` (a ``.vtm`` of named blocks per frame) or ``"merged"``
    (one ``.vtu`` grid per frame), see :mod:`flexmbs.io.frames`; ``vtk_compression``: the
    frames' data arrays zlib-compressed (default ``False``: uncompressed base64).
    ``resume=True`` continues the stopped run in ``out`` from its ``checkpoint.npz`` to
    ``t_end``, appending to its files (see :func:`resume_point`); the returned history then
    starts at the checkpoint. Probe values are also returned in ``Result.extra["probes"]``, and
    the run's checks of its energy balance and constraint drift in ``Result.extra["checks"]``
    (:mod:`flexmbs.checks`; one beyond its bound is also a :class:`FlexmbsWarning`).
    A :class:`ConvergenceError` carries the history so far as ``partial_result``.
    ``keep_history=False`` keeps only the last output in memory (the folder holds them all).

    Parameters
    ----------
    model : Model or Assembly
        The model.
    t_end : float
        End time [s].
    dt : float
        Time step [s] (the largest, with step-error control).
    integrator : GeneralizedAlpha, optional
        Integrator options (default ``GeneralizedAlpha()``).
    output_interval : float, optional
        Time between outputs [s] (default: every step).
    initial_static : bool, default False
        Start from the static equilibrium at t = 0.
    record_energy : bool, default True
        Record the energies at the outputs.
    observer : callable, optional
        ``observer(state)`` at every output.
    progress : callable, optional
        ``progress(state, stats)`` as the integrator goes.
    redundant_constraints : {"error", "drop"}, default "error"
        What to do with redundant constraint equations.
    out : str or os.PathLike, optional
        Output folder (default: none written).
    probes : sequence of Probe, optional
        Probes written to ``probes.csv``.
    name : str, optional
        Name of the output files (default: the model's name).
    static_options : StaticOptions, optional
        Options of the initial static solve.
    resume : bool, default False
        Continue the stopped run in ``out``.
    metadata : dict, optional
        Stored in ``summary.json``.
    write_vtu : bool, default True
        Write the VTK frames.
    output_frames : {"multiblock", "merged"}, default "multiblock"
        Form of the frames.
    vtk_compression : bool, default False
        zlib-compress the frames' data arrays (28 % smaller, the encoding about 12 times the
        CPU time).
    keep_history : bool, default True
        Keep every output in the returned :class:`Result`; ``False`` keeps the last only, so
        that memory stays flat however long the run (``flexmbs run`` does so: its outputs are
        in the folder).

    Returns
    -------
    Result
        Time histories at the output times, with accessors by model object.
    """
    check_run(model.model if isinstance(model, Assembly) else model, t_end=t_end, dt=dt,
              output_interval=output_interval, out=out)
    asm = model if isinstance(model, Assembly) else Assembly(
        model, redundant_constraints=redundant_constraints)
    opts = integrator or GeneralizedAlpha()
    _warn_undamped_constraints(asm.model, opts)
    run_name = str(name if name is not None else getattr(asm.model, "name", "model"))
    probes = list(probes)
    for p in probes:
        p.check(asm)
    resume_t: float | None = None
    previous: dict = {}
    solver_state: dict | None = None
    if resume:
        if out is None:
            raise ModelError("simulate(resume=True) needs out= (the folder of the stopped run)")
        state0, previous = resume_point(out, asm, run_name)
        resume_t = state0.t
        solver_state = _solver_state(out)
        # a run killed after its last output's checkpoint, before its summary said so, has
        # nothing left to integrate: resuming it ends the folder (the summary, its counters)
        at_end = abs(t_end - resume_t) <= 1e-9 * dt
        if at_end and previous.get("status") == "completed":
            raise ModelError(f"cannot resume: the run in {out} has already completed at "
                             f"t = {resume_t:.6g}; give a later t_end to continue it")
        if not (t_end > resume_t or at_end):
            raise ModelError(f"cannot resume: the checkpoint in {out} is at t = {resume_t:.6g} "
                             f"and t_end = {t_end:.6g}; give a later t_end")
    if not resume:
        check_masses(asm)        # bad input, before the folder is written
        _warn_motions_at_speed(asm.model, t_end)
    writer: OutputWriter | None = None
    if out is not None:
        meta = {"dt": dt, "t_end": t_end, "output_interval": output_interval,
                "integrator": dataclasses.asdict(opts), **(metadata or {})}
        if resume_t is not None:
            meta["resumed_from"] = resume_t
        writer = OutputWriter(out, run_name, asm, probes=probes, metadata=meta,
                              write_vtu=write_vtu, resume_at=resume_t,
                              output_frames=output_frames,
                              vtu_encoding="zlib" if vtk_compression else "binary",
                              expected_outputs=t_end / (output_interval or dt) + 1)
    checks = RunChecks(asm, rho_inf=opts.rho_inf, dt=dt, output_interval=output_interval,
                       previous=previous.get("checks"))
    run = _RunRecord(asm, probes, writer, record_energy=record_energy, resume_t=resume_t,
                     observer=observer, progress=progress, previous=previous, checks=checks,
                     keep_history=keep_history)
    # the writer ends the folder whatever ends the run (summary.json: "completed", "failed:
    # <reason>", "interrupted"), from the folder's creation on: an initial static solve that
    # does not converge still leaves a summary saying why
    with writer if writer is not None else contextlib.nullcontext():
        if writer is not None:
            writer.totals = run.totals
            writer.checks = checks.report
        if not resume:
            q0, v0 = asm.initial_state()
            if initial_static:
                q0 = _solve_static(asm, static_options).q
            state0 = consistent_initial_state(asm, q0, v0, 0.0)
        run.t0 = time.perf_counter()     # Result.wall_time: the integration's
        try:
            if resume_t is not None and abs(t_end - resume_t) <= 1e-9 * dt:
                run.record(state0)          # already on disk: the Result's final state only
                final, stats = state0, IntegrationStats()
            else:
                final, stats = integrate(asm, opts, t_end=t_end, dt=dt, state=state0,
                                         output_interval=output_interval, observer=run.record,
                                         progress=run.watch, solver_state=solver_state,
                                         snapshot=run.solver_now.update)
        except ConvergenceError as exc:
            # keep what was computed: the partial history travels with the exception
            exc.partial_result = run.result(  # type: ignore[attr-defined]
                run.last_state(), run.stats(), f"failed: {failure_reason(exc)}")
            raise
        run.stats_seen = stats
        result = run.result(final, stats, "completed")
        for message in result.extra["checks"]["warnings"]:
            warnings.warn(message, FlexmbsWarning, stacklevel=2)
    return result


class _RunRecord:
    """What :func:`simulate` keeps of a run: the histories at the output times (the
    :class:`Result`; the last output only without ``keep_history``), the probes, and each
    output written to ``writer`` with the checkpoint's extras; ``totals`` gives the writer the
    run's counters when it ends (added to those of the run it resumes)."""

    def __init__(self, asm: Assembly, probes: list[Probe], writer: OutputWriter | None, *,
                 record_energy: bool, resume_t: float | None,
                 observer: Callable[[State], None] | None,
                 progress: Callable[[State, IntegrationStats], None] | None,
                 previous: dict, checks: RunChecks, keep_history: bool = True) -> None:
        self.asm, self.probes, self.writer = asm, probes, writer
        self.keep_history = keep_history
        self.record_energy, self.resume_t = record_energy, resume_t
        self.observer, self.progress, self.previous = observer, progress, previous
        self.checks = checks
        self.columns = probe_columns(probes)
        self.ts: list[float] = []
        self.qs: list[np.ndarray] = []
        self.vs: list[np.ndarray] = []
        self.ls: list[np.ndarray] = []
        self.energies: dict[str, list[float]] = {}
        self.probe_rows: list[np.ndarray] = []
        self.stats_seen: IntegrationStats | None = None     # the integrator's own counters
        self.solver_now: dict[str, Any] = {}   # the integrator's own state at the output
        self.ckpt = {"scenario": writer.name if writer is not None else "",
                     "n_coords": int(asm.n_coords), "n_mult": int(asm.n_mult)}
        self.t0 = time.perf_counter()

    def record(self, s: State) -> None:
        """One output time: the histories, the probes, the folder."""
        asm, writer = self.asm, self.writer
        if not self.keep_history:
            for kept in (self.ts, self.qs, self.vs, self.ls, self.probe_rows):
                kept.clear()
            for history in self.energies.values():
                history.clear()
        self.ts.append(s.t)
        self.qs.append(s.q.copy())
        self.vs.append(s.v.copy())
        self.ls.append(s.lam.copy())
        energy = asm.energies(s.q, s.v) if self.record_energy or writer is not None else None
        if self.record_energy and energy is not None:
            for k, val in energy.items():
                self.energies.setdefault(k, []).append(val)
        values = np.concatenate([np.asarray(p.evaluate(asm, s), float).reshape(-1)
                                 for p in self.probes] + [np.zeros(0)])
        if self.probes:
            self.probe_rows.append(values)
        self.checks.observe(s.q, s.v, s.t, energy)
        # a resumed run starts at the checkpoint, which the folder already holds
        if writer is not None and (self.resume_t is None or s.t > self.resume_t):
            writer.write(s, contacts=interaction_outputs(asm, s),
                         sections=interaction_sections(asm, s), probe_values=values,
                         energy=energy,
                         checkpoint_extra={**self.ckpt, "interactions": interaction_states(asm),
                                           "node_bases": asm.node_bases(),
                                           "spring_angles": asm.system.springs.theta_ref.copy(),
                                           "run_totals": self.totals_at_output(),
                                           **{f"solver_{k}": v
                                              for k, v in self.solver_now.items()
                                              if k != "counters"}})
        if self.observer is not None:
            self.observer(s)

    def watch(self, s: State, st: IntegrationStats) -> None:
        if self.stats_seen is None:
            self.stats_seen = st     # the integrator's own (mutated) counters
        if self.progress is not None:
            self.progress(s, st)

    def stats(self) -> IntegrationStats:
        return self.stats_seen if self.stats_seen is not None else IntegrationStats()

    def totals_at_output(self) -> dict[str, Any]:
        """What a run resumed from this output's checkpoint continues from: the counters and
        wall time up to this output (with those of the runs this one resumes) and the checks'
        extremes; a summary's counters may run past the checkpoint, or be missing after a
        SIGKILL (:func:`resume_point`)."""
        counters = self.solver_now.get("counters") or {}
        now = IntegrationStats(**{f.name: int(counters.get(f.name, 0))
                                  for f in dataclasses.fields(IntegrationStats)})
        _, wall = self.totals()
        return {"stats": dataclasses.asdict(_add_stats(self.previous.get("stats"), now)),
                "wall_time": wall, "checks": dict(self.checks.running)}

    def totals(self) -> tuple[IntegrationStats, float]:
        """Counters and wall time so far, with those of the run this one resumes."""
        wall = time.perf_counter() - self.t0 + float(self.previous.get("wall_time") or 0.0)
        return _add_stats(self.previous.get("stats"), self.stats()), wall

    def last_state(self) -> State:
        q = self.qs[-1]
        return State(self.ts[-1], q, self.vs[-1], np.zeros_like(q), np.zeros_like(q),
                     self.ls[-1])

    def result(self, final: State, stats: IntegrationStats, status: str) -> Result:
        extra: dict[str, Any] = {}
        if self.probes:
            arr = np.array(self.probe_rows).reshape(len(self.probe_rows), len(self.columns))
            extra["probes"] = {c: arr[:, i] for i, c in enumerate(self.columns)}
        if self.writer is not None:
            extra["out"] = self.writer.directory
        extra["checks"] = self.checks.report()
        return Result(self.asm, np.array(self.ts), np.array(self.qs), np.array(self.vs),
                      np.array(self.ls), {k: np.array(v) for k, v in self.energies.items()},
                      stats, time.perf_counter() - self.t0, final, status, extra)


def _add_stats(previous: dict | None, stats: IntegrationStats) -> IntegrationStats:
    """Counters of a resumed run added to those of the run it continues."""
    total = dataclasses.replace(stats)
    for f in dataclasses.fields(IntegrationStats):
        old = (previous or {}).get(f.name)
        if isinstance(old, int):
            setattr(total, f.name, getattr(total, f.name) + old)
    return total


def interaction_outputs(asm: Assembly, state: State) -> list[dict]:
    """Contact records (contacts.csv columns) of every interaction of the model at ``state``."""
    rows: list[dict] = []
    for obj in asm.model.interactions:
        kind = driver.kind_of(obj)
        if kind is not None and kind.contacts is not None:
            rows.extend(kind.contacts(obj, asm, state.q, state.v, state.lam, state.t))
    return rows


def interaction_sections(asm: Assembly, state: State) -> list[dict]:
    """Hole-section records (sections.csv) of every clearance joint at ``state``."""
    rows: list[dict] = []
    for obj in asm.model.interactions:
        kind = driver.kind_of(obj)
        if kind is not None and kind.sections is not None:
            rows.extend(kind.sections(obj, state.q, state.v, state.t))
    return rows


def interaction_states(asm: Assembly) -> dict[str, Any]:
    """Internal state of the interactions (warm starts, active sets) by name, for checkpoints."""
    out: dict[str, Any] = {}
    for i, obj in enumerate(asm.model.interactions):
        fn = getattr(obj, "get_state", None)
        if fn is not None:
            out[str(getattr(obj, "name", i))] = fn()
    return out


def checkpoint_time(out: str | os.PathLike) -> float | None:
    """Time of the state in ``out/checkpoint.npz``, where ``simulate(..., resume=True)`` would
    start; ``None`` if there is no readable checkpoint (:func:`resume_point` says why)."""
    ckpt = Path(out) / "checkpoint.npz"
    if not ckpt.is_file():
        return None
    try:
        return float(load_checkpoint(ckpt)[0].t)
    except (OSError, ValueError, KeyError):
        return None


def _solver_state(out: str | os.PathLike) -> dict[str, Any] | None:
    """The integrator's own state saved with the checkpoint (``solver_*`` entries), if any."""
    try:
        _, extra = load_checkpoint(Path(out) / "checkpoint.npz")
    except (OSError, ValueError, KeyError):
        return None
    found = {k[len("solver_"):]: v for k, v in extra.items() if k.startswith("solver_")}
    return found or None


def resume_point(out: str | os.PathLike, asm: Assembly, name: str) -> tuple[State, dict]:
    """The state to continue a stopped run from: ``out/checkpoint.npz``, checked against this
    model (scenario name, coordinate and multiplier counts); interaction state is restored.
    Returns ``(state, previous summary)``; raises :class:`ScenarioError` if the folder does not
    belong to this run."""
    folder = Path(out)
    ckpt = folder / "checkpoint.npz"
    if not ckpt.is_file():
        raise ScenarioError(f"cannot resume: no checkpoint {ckpt} (run without --resume first)")
    try:
        state, extra = load_checkpoint(ckpt)
    except CheckpointVersionError as exc:
        raise ScenarioError(f"cannot resume: {exc}") from None
    except (OSError, ValueError, KeyError) as exc:
        raise ScenarioError(f"cannot resume: {exc}; the output written before it stays readable; "
                            "run again without --resume to start over") from None
    summary: dict = {}
    if (folder / "summary.json").is_file():
        try:
            summary = json.loads((folder / "summary.json").read_text(encoding="utf-8"))
        except ValueError as exc:
            raise ScenarioError(f"cannot resume: {folder / 'summary.json'} is not valid JSON "
                                f"({exc})") from None
    dofs = summary.get("dofs") or {}
    found = {"scenario": extra.get("scenario", summary.get("scenario")),
             "n_coords": extra.get("n_coords", dofs.get("coordinates")),
             "n_mult": extra.get("n_mult", dofs.get("multipliers"))}
    wanted = {"scenario": name, "n_coords": int(asm.n_coords), "n_mult": int(asm.n_mult)}
    bad = [f"{k} {found[k]!r} (this run: {wanted[k]!r})" for k in wanted if found[k] != wanted[k]]
    if bad:
        raise ScenarioError(f"cannot resume: {folder} belongs to another run: " + ", ".join(bad))
    if state.q.shape != (asm.n_coords,) or state.lam.shape != (asm.n_mult,):
        raise ScenarioError(f"cannot resume: {ckpt} has {state.q.size} coordinates and "
                            f"{state.lam.size} multipliers (this run: {asm.n_coords}, {asm.n_mult})")
    if not (math.isfinite(state.t) and np.all(np.isfinite(state.q))):
        raise ScenarioError(f"cannot resume: {ckpt} holds a non-finite state")
    bases = extra.get("node_bases")
    if bases is not None and np.size(bases):
        try:
            asm.set_node_bases(np.asarray(bases, dtype=float))
        except ValueError as exc:
            raise ScenarioError(f"cannot resume: {ckpt}: {exc}") from None
    angles = extra.get("spring_angles")     # the rotational springs' turns (older: none)
    theta_ref = asm.system.springs.theta_ref
    if angles is not None and np.shape(angles) == theta_ref.shape:
        theta_ref[:] = np.asarray(angles, dtype=float)
    saved = extra.get("interactions") or {}
    for i, obj in enumerate(asm.model.interactions):
        key = str(getattr(obj, "name", i))
        fn = getattr(obj, "set_state", None)
        if fn is not None and key in saved:
            try:
                fn(saved[key])
            except ModelError as exc:    # e.g. a changed friction law
                raise ScenarioError(f"cannot resume: {exc}") from None
    totals = extra.get("run_totals")     # the counters at the checkpoint (older: the summary's)
    if isinstance(totals, dict):
        summary = {**summary, "stats": totals.get("stats"), "wall_time": totals.get("wall_time"),
                   "checks": {"running": totals.get("checks") or {}}}
    return state, summary

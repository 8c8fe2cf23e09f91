"""Run a loaded scenario into its output folder: what ``flexmbs run`` and each case of
``flexmbs sweep`` do (docs/design.md, "CLI" and "Output folder").

:func:`run_scenario` claims the folder (lock, refusal of another run's folder, see
:mod:`flexmbs.io.folder`), records how the run was made (scenario file, its SHA-1, the
overrides) in ``summary.json["metadata"]`` and calls :func:`~flexmbs.simulation.solve_static`,
:func:`~flexmbs.simulation.solve_quasi_static` or :func:`~flexmbs.simulation.simulate`. Errors
propagate (the CLI and the sweep turn them into one line each).
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .assembly import Assembly
from .budget import check_run
from .io.folder import claim
from .io.output import check_output
from .io.scenario import Scenario
from .simulation import checkpoint_time, simulate, solve_quasi_static, solve_static
from .solvers.generalized_alpha import check_masses

__all__ = ["RunOutcome", "run_scenario", "scenario_digest"]

#: ``progress(start_time, t_end, name)`` -> a ``(state, stats)`` callback of the integrator
ProgressFactory = Callable[[float, float, str], Callable[[Any, Any], None]]


@dataclass(frozen=True)
class RunOutcome:
    """How a run ended (the same figures are in ``summary.json``)."""

    name: str
    out: Path
    status: str
    t_end: float
    steps: int
    newton_iterations: int
    rejected_steps: int


def scenario_digest(path: str | os.PathLike[str]) -> str:
    """SHA-1 of a scenario file's bytes (recorded by a run; a resumed or skipped run checks it)."""
    return hashlib.sha1(Path(path).read_bytes()).hexdigest()


def run_scenario(sc: Scenario, out: str | os.PathLike[str], *, overrides: Sequence[str] = (),
                 resume: bool = False, overwrite: bool = False,
                 progress: ProgressFactory | None = None) -> RunOutcome:
    """Run the loaded scenario ``sc`` (built with ``overrides``) into the folder ``out``;
    ``resume`` continues the stopped run there; ``overwrite`` replaces another scenario's
    output. ``progress`` makes the integrator's progress callback once the start time is known."""
    sim = sc.simulation
    folder = Path(out)
    metadata = {"scenario_file": os.path.abspath(sc.path), "overrides": list(overrides),
                "scenario_sha1": scenario_digest(sc.path),
                "integrator_name": sim.integrator, "initial_static": sim.initial_static}
    # everything that can be checked from the scenario, before the folder is claimed (created,
    # cleared): the run's size, the model's equations, the output's names, probes and shapes
    if sim.integrator != "static":
        check_run(sc.model, t_end=sim.t_end, dt=sim.dt, output_interval=sim.output_interval,
                  out=folder, prefix="simulation.")
    asm = Assembly(sc.model, redundant_constraints=sim.redundant_constraints)
    outputs = (None if sim.integrator == "static" else
               sim.t_end / (sim.output_interval or sim.dt) + 1)
    check_output(folder, sc.name, asm, probes=sc.probes, output_frames=sim.output_frames,
                 frames=outputs, prefix="simulation.")
    if sim.integrator not in ("static", "quasi_static") and not resume:
        check_masses(asm)
    with claim(folder, scenario=sc.name, overwrite=overwrite, resume=resume):
        if sim.integrator == "static":
            st = solve_static(asm, sc.static_options(), t=sim.t_end,
                              redundant_constraints=sim.redundant_constraints, out=folder,
                              probes=sc.probes, name=sc.name, metadata=metadata,
                              output_frames=sim.output_frames,
                              vtk_compression=sim.vtk_compression)
            return RunOutcome(sc.name, folder, "completed", sim.t_end, 0, st.newton_iterations, 0)
        if sim.integrator == "quasi_static":
            qs = solve_quasi_static(asm, sim.quasi_static_times(), sc.static_options(),
                                    redundant_constraints=sim.redundant_constraints, out=folder,
                                    probes=sc.probes, name=sc.name, metadata=metadata,
                                    output_frames=sim.output_frames,
                                    vtk_compression=sim.vtk_compression)
            return RunOutcome(sc.name, folder, "completed", sim.t_end, len(qs.t),
                              qs.newton_iterations, 0)
        # where a progress bar starts; simulate() reports a missing or unreadable checkpoint
        start = (checkpoint_time(folder) if resume else None) or 0.0
        callback = progress(start, sim.t_end, sc.name) if progress is not None else None
        # the outputs are in the folder: only the last is kept in memory (flat over long runs)
        res = simulate(asm, t_end=sim.t_end, dt=sim.dt, integrator=sc.integrator_options(),
                       output_interval=sim.output_interval, initial_static=sim.initial_static,
                       static_options=sc.static_options(),
                       redundant_constraints=sim.redundant_constraints, record_energy=False,
                       progress=callback, out=folder, probes=sc.probes, name=sc.name,
                       resume=resume, metadata=metadata, output_frames=sim.output_frames,
                       vtk_compression=sim.vtk_compression, keep_history=False)
        return RunOutcome(sc.name, folder, res.status, sim.t_end, res.stats.steps,
                          res.stats.newton_iterations, res.stats.rejected_steps)

"""The ``[simulation]`` table -> :class:`SimulationSettings` (how to run a scenario)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...solvers.generalized_alpha import CONSTRAINT_LEVELS
from ...solvers.newton import NewtonOptions
from ...solvers.static import StaticOptions
from ..frames import OUTPUT_FRAMES
from ..tables import MISSING, Table

__all__ = ["INTEGRATORS", "PREDICTORS", "SimulationSettings", "read_simulation"]

INTEGRATORS = ("generalized_alpha", "hht", "static", "quasi_static")
PREDICTORS = ("constant_acceleration", "zero_acceleration")

_NEWTON_KEYS = {"max_iterations": "int", "relative_tolerance": "pos", "constraint_tolerance": "pos",
                "modified": "bool", "line_search": "bool", "refresh_ratio": "ratio",
                "refresh_iterations": "pos", "refresh_cost": "pos", "retreats": "count",
                "slope_search": "bool", "hold_contacts": "bool"}


@dataclass(frozen=True, kw_only=True)
class SimulationSettings:
    """The ``[simulation]`` table (units SI). See docs/scenario.md for every key."""

    t_end: float
    dt: float
    integrator: str = "generalized_alpha"
    rho_inf: float = 0.8
    gravity: tuple[float, float, float] = (0.0, 0.0, 0.0)
    output_interval: float | None = None       #: None: every step
    output_frames: str = "multiblock"          #: "multiblock" (.vtm per frame) | "merged" (.vtu)
    vtk_compression: bool = False              #: frames' arrays zlib-compressed (VTK reads them)
    initial_static: bool = False               #: start from the static equilibrium at t = 0
    adaptive: bool = True                      #: halve the step on Newton failure
    min_step: float | None = None              #: None: dt / 1024
    redundant_constraints: str = "error"       #: "error" | "drop"
    load_steps: int = 1                        #: initial load increments of the static solver
    static_stabilizer: float = 0.0             #: mass-proportional stabiliser c_s [1/s^2]
    predictor: str = "constant_acceleration"   #: Newton start of each step
    compiled: bool = True                      #: compiled integrator when the model allows it
    constraint_level: str = "position"         #: "position" | "position_velocity"
    step_tolerance: float = 0.0                #: local error per step; 0: fixed steps
    newton: dict[str, Any] = field(default_factory=dict)  #: NewtonOptions overrides

    def quasi_static_times(self) -> np.ndarray:
        """The equilibria of ``integrator = "quasi_static"``: from 0 every ``output_interval``
        (default ``dt``) to ``t_end`` (the last interval shorter if it does not divide)."""
        every = self.output_interval or self.dt
        n = int(np.floor(self.t_end / every * (1 + 1e-12)))
        times = every * np.arange(n + 1)
        return times if times[-1] >= self.t_end * (1 - 1e-12) else np.append(times, self.t_end)

    def newton_options(self, *, static: bool = False) -> NewtonOptions:
        """NewtonOptions with the ``[simulation.newton]`` keys applied (static: full Newton)."""
        base = StaticOptions().newton if static else NewtonOptions()
        kw = {k: getattr(base, k) for k in base.__dataclass_fields__}
        kw.update(self.newton)
        return NewtonOptions(**kw)


def read_simulation(t: Table) -> SimulationSettings:
    """Validate the ``[simulation]`` table."""
    t.allow(("t_end", "dt", "integrator", "rho_inf", "gravity", "output_interval", "output_frames",
             "vtk_compression", "initial_static", "adaptive", "min_step", "redundant_constraints",
             "load_steps",
             "static_stabilizer", "predictor", "compiled", "constraint_level",
             "step_tolerance", "newton"))
    integrator = t.choice("integrator", INTEGRATORS, "generalized_alpha", what="integrator")
    static = integrator == "static"
    t_end = t.number("t_end", 1.0 if static else MISSING, gt=0, unit="s")
    dt = t.number("dt", t_end if static else MISSING, gt=0, unit="s")
    if dt > t_end:
        raise t.fail("dt", f"a time step <= t_end = {t_end:g}", dt)
    lo = 0.5 if integrator == "hht" else 0.0
    rho_inf = t.number("rho_inf", 0.8, ge=lo, le=1.0, unit="1")
    gravity = t.vector("gravity", np.zeros(3), unit="m/s^2")
    out = t.number("output_interval", None, gt=0, unit="s")
    if out is not None and out < dt * (1 - 1e-12):
        raise t.fail("output_interval", f"a number >= dt = {dt:g} (one output per step at most)", out)
    min_step = t.number("min_step", None, gt=0, unit="s")
    if min_step is not None and min_step > dt:
        raise t.fail("min_step", f"a number <= dt = {dt:g}", min_step)
    adaptive = t.boolean("adaptive", True)
    step_tolerance = t.number("step_tolerance", 0.0, ge=0.0, unit="1")
    if step_tolerance > 0.0 and not adaptive:
        raise t.fail("step_tolerance", "0 when adaptive = false (a step refused for its error is "
                     "retried with half the step), or adaptive = true", step_tolerance)
    newton: dict[str, Any] = {}
    nt = t.table("newton", None)
    if nt is not None:
        nt.allow(_NEWTON_KEYS)
        for k, kind in _NEWTON_KEYS.items():
            if not nt.has(k):
                continue
            newton[k] = (nt.integer(k, ge=1) if kind == "int" else nt.integer(k, ge=0)
                         if kind == "count" else nt.boolean(k) if kind == "bool"
                         else nt.number(k, gt=0, lt=1, unit="1") if kind == "ratio"
                         else nt.number(k, gt=0, unit="1"))
    gx, gy, gz = (float(x) for x in gravity)
    return SimulationSettings(
        t_end=t_end, dt=dt, integrator=integrator, rho_inf=rho_inf, gravity=(gx, gy, gz),
        output_interval=out, initial_static=t.boolean("initial_static", False),
        output_frames=t.choice("output_frames", OUTPUT_FRAMES, "multiblock", what="output form"),
        vtk_compression=t.boolean("vtk_compression", False),
        adaptive=adaptive, min_step=min_step,
        redundant_constraints=t.choice("redundant_constraints", ("error", "drop"), "error"),
        load_steps=t.integer("load_steps", 1, ge=1),
        static_stabilizer=t.number("static_stabilizer", 0.0, ge=0.0, unit="1/s^2"),
        predictor=t.choice("predictor", PREDICTORS, "constant_acceleration", what="predictor"),
        compiled=t.boolean("compiled", True),
        constraint_level=t.choice("constraint_level", CONSTRAINT_LEVELS, "position",
                                  what="constraint level"),
        step_tolerance=step_tolerance, newton=newton)

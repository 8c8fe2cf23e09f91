"""Numbers that cannot be trusted are not written as results (docs/design.md, "The checks of a
run"): a run checks its energy balance at every output and its constraint drift at outputs
at least :data:`DRIFT_STEPS` steps apart, against the bounds stated here. ``summary.json``
reports each check (``checks``); one beyond its bound is a warning there and on the terminal,
naming the quantity and what to change.

- **Energy.** In a model where nothing does work (no loads, drivers or prescribed motion with a
  time function, no interaction that declares it works) the total energy of
  :meth:`~flexmbs.assembly.Assembly.energies` may not grow: by more than
  :data:`ENERGY_BOUND` of the energy the run exchanges (the largest kinetic energy, plus the
  largest stored energy, plus the range of the gravitational one). If nothing dissipates either
  (no damping, friction, damped contact law, and ``rho_inf = 1``), it may not fall by more
  than that either. Otherwise (work done, or an interaction that does not declare its
  :meth:`~flexmbs.constraints.interaction.Interaction.energy_flow`) the energy is not checked,
  and the summary says why.
- **Position drift.** ``max |Phi|`` of the kept constraint equations, relative to the model's
  length scale L (the measure of Newton's ``constraint_tolerance``), at most
  :data:`POSITION_DRIFT_BOUND`.
- **Velocity drift.** ``max |Phi_q v + Phi_t|``, relative to the largest speed of a node or body
  (at least L × :data:`POSITION_DRIFT_BOUND` per step), at most :data:`VELOCITY_DRIFT_BOUND`.
  Index-3 generalized-alpha holds ``Phi = 0`` at every step, not its rate;
  ``constraint_level = "position_velocity"`` holds both.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from .loads import Constant

if TYPE_CHECKING:  # pragma: no cover
    from .assembly import Assembly
    from .model import Model

__all__ = ["DRIFT_STEPS", "ENERGY_BOUND", "POSITION_DRIFT_BOUND", "VELOCITY_DRIFT_BOUND", "EnergyFlows",
           "RunChecks", "energy_flows"]

#: energy a passive run may gain (and a conservative one may lose), as a fraction of the energy
#: it exchanges
ENERGY_BOUND = 1e-2
#: ``max |Phi|`` over the run, as a fraction of the model's length scale
POSITION_DRIFT_BOUND = 1e-6
#: ``max |Phi_q v + Phi_t|`` over the run, as a fraction of the largest speed of a node or body
VELOCITY_DRIFT_BOUND = 1e-2
#: the drift is measured at outputs at least this many steps apart (and at the first)
DRIFT_STEPS = 10


@dataclass(frozen=True)
class EnergyFlows:
    """What changes a model's energy, by name: ``works`` may put energy in, ``dissipates``
    only takes it out, ``undeclared`` are interactions that do not say."""

    works: tuple[str, ...]
    dissipates: tuple[str, ...]
    undeclared: tuple[str, ...]


def _driven(function: Any) -> bool:
    return function is not None and not isinstance(function, Constant)


def energy_flows(model: Model, rho_inf: float) -> EnergyFlows:
    """The model's sources and sinks of energy (module docstring), with generalized-alpha's
    numerical damping for ``rho_inf < 1``."""
    works = [f"load '{ld.name}'" for ld in model.loads]
    works += [f"{c.kind} '{c.name}'" for c in model.constraints
              if c.kind in ("driver", "prescribed") and _driven(c.function)]
    dissipates = [f"beam '{b.name}' damping" for b in model.beams if b.damping > 0.0]
    dissipates += [f"spring '{s.name}' damping" for s in model.springs if s.damping > 0.0]
    undeclared: list[str] = []
    for obj in model.interactions:
        flow = obj.energy_flow()
        label = f"joint '{obj.name}'"
        if flow == "works":
            works.append(label)
        elif flow == "dissipates":
            dissipates.append(label)
        elif flow is None:
            undeclared.append(label)
    if rho_inf < 1.0:
        dissipates.append(f"numerical damping (rho_inf = {rho_inf:g})")
    return EnergyFlows(tuple(works), tuple(dissipates), tuple(undeclared))


def _names(items: tuple[str, ...]) -> str:
    return ", ".join(items[:3]) + (f" and {len(items) - 3} more" if len(items) > 3 else "")


class RunChecks:
    """The checks of one run (module docstring), updated by :meth:`observe` at every output;
    ``previous``: the ``checks`` of the summary of the run this one resumes."""

    def __init__(self, asm: Assembly, *, rho_inf: float, dt: float,
                 output_interval: float | None = None,
                 previous: Mapping[str, Any] | None = None) -> None:
        self.asm = asm
        #: the drift is measured at the first output and then at every ``stride``-th: at most
        #: every DRIFT_STEPS steps (its Python evaluation of every constraint costs, e.g., 5 ms
        #: for 640 equations: a 160-body chain's step is 14 ms)
        self.output_interval = float(output_interval or dt)
        self.stride = max(1, math.ceil(DRIFT_STEPS * dt / self.output_interval - 1e-9))
        self.flows = energy_flows(asm.model, rho_inf)
        self.length = float(asm.length_scale)
        #: the speed below which a drift is measured against L x POSITION_DRIFT_BOUND per step
        self.speed_floor = self.length * POSITION_DRIFT_BOUND / float(dt)
        model = asm.model
        moving = [asm.node_dofs(b.node(i))[:3] for b in model.beams for i in range(b.n_nodes)]
        moving += [asm.body_dofs(b)[:3] for b in model.bodies]
        self.moving = np.concatenate(moving + [np.zeros(0, np.int64)]).astype(np.int64)
        #: the energy below which a change is rounding: the whole mass at the speed floor
        self.energy_floor = self._kinetic_at_unit_speed() * self.speed_floor**2
        state = dict((previous or {}).get("running") or {})
        #: extremes so far (kept in the summary for a resumed run)
        self.running: dict[str, float] = {k: float(v) for k, v in state.items()
                                          if isinstance(v, (int, float))}

    def _kinetic_at_unit_speed(self) -> float:
        """Kinetic energy of the model in its reference configuration translating at 1 m/s
        (half its mass) [J s²/m²]."""
        asm = self.asm
        q = asm.q_ref
        v = np.zeros_like(q)
        v[self.moving[::3]] = 1.0
        return float(asm.energies(q, v)["kinetic"])

    def _keep(self, key: str, value: float, t: float | None = None) -> None:
        """Keep the largest ``value`` of ``key`` (with its time ``t``, if given)."""
        old = self.running.get(key)
        if old is None or value > old:
            self.running[key] = value
            if t is not None:
                self.running[f"{key}_t"] = t

    def observe(self, q: np.ndarray, v: np.ndarray, t: float,
                energy: Mapping[str, float] | None) -> None:
        """One output's state and its energies (``None``: not evaluated)."""
        first = "t_first" not in self.running
        self.running.setdefault("t_first", float(t))
        self._keep("speed", float(np.abs(v[self.moving]).max(initial=0.0)))
        if first or round(t / self.output_interval) % self.stride == 0:
            phi, rate = self.asm.rows.drift(q, v, t)
            self._keep("position_drift", float(np.abs(phi).max(initial=0.0)), float(t))
            self._keep("velocity_drift", float(np.abs(rate).max(initial=0.0)), float(t))
        if energy is None:
            self.running["energy_missing"] = 1.0
            return
        total = float(energy["total"])
        kinetic = float(energy["kinetic"])
        gravity = float(energy.get("gravity", 0.0))
        self.running.setdefault("energy_initial", total)
        self._keep("energy_max", total)
        self._keep("minus_energy_min", -total)
        self._keep("kinetic_max", kinetic)
        self._keep("stored_max", abs(total - kinetic - gravity))
        self._keep("gravity_max", gravity)
        self._keep("minus_gravity_min", -gravity)

    # ------------------------------------------------------------------ report
    def _energy(self) -> dict[str, Any]:
        r, f = self.running, self.flows
        out: dict[str, Any] = {"bound": ENERGY_BOUND}
        if f.works:
            return {**out, "checked": False, "reason": f"work done by {_names(f.works)}"}
        if f.undeclared:
            return {**out, "checked": False,
                    "reason": f"{_names(f.undeclared)} do not declare their energy flow"}
        if "energy_initial" not in r or r.get("energy_missing"):
            return {**out, "checked": False, "reason": "energies not evaluated at every output"}
        scale = max(r["kinetic_max"] + r["stored_max"] + (r["gravity_max"] + r["minus_gravity_min"]),
                    self.energy_floor)
        gained = r["energy_max"] - r["energy_initial"]
        lost = r["energy_initial"] + r["minus_energy_min"]
        conserved = not f.dissipates
        change = max(gained, lost) if conserved else gained
        value = change / scale if scale > 0.0 else 0.0     # no mass, no energy: nothing moves
        out.update(checked=True, quantity="energy change" if conserved else "energy gained",
                   value=value, scale=scale, gained=gained, lost=lost, passed=value <= ENERGY_BOUND)
        if not conserved:
            out["dissipated_by"] = list(f.dissipates)
        return out

    def report(self) -> dict[str, Any]:
        """The summary's ``checks``: each check's value, bound and verdict, the warnings, and
        the extremes a resumed run continues from (``running``)."""
        r = self.running
        speed = max(r.get("speed", 0.0), self.speed_floor)
        checks: dict[str, Any] = {"energy": self._energy()}
        if "position_drift" in r:
            pos = r["position_drift"] / self.length
            vel = r["velocity_drift"] / speed
            checks["position_drift"] = {"value": pos, "bound": POSITION_DRIFT_BOUND,
                                        "length_scale": self.length,
                                        "time": r["position_drift_t"],
                                        "passed": pos <= POSITION_DRIFT_BOUND}
            checks["velocity_drift"] = {"value": vel, "bound": VELOCITY_DRIFT_BOUND,
                                        "speed_scale": speed, "time": r["velocity_drift_t"],
                                        "passed": vel <= VELOCITY_DRIFT_BOUND}
        checks["warnings"] = self.warnings(checks)
        checks["running"] = dict(r)
        return checks

    def warnings(self, checks: Mapping[str, Any] | None = None) -> list[str]:
        """One line per check beyond its bound, naming the quantity and what to change."""
        c = self.report() if checks is None else checks
        out: list[str] = []
        e = c["energy"]
        if e.get("checked") and not e["passed"]:
            conserved = e["quantity"] == "energy change"
            what = "changed" if conserved else "grew"
            where = "nothing does work or dissipates" if conserved else "nothing does work"
            out.append(f"results not trusted: the total energy {what} by {100 * e['value']:.3g} % "
                       f"of the energy exchanged ({e['scale']:.4g} J) in a model where {where} "
                       f"(bound {100 * ENERGY_BOUND:g} %); use a smaller dt, rho_inf < 1 or "
                       "constraint_level = \"position_velocity\"")
        first = self.running.get("t_first")
        p = c.get("position_drift")
        if p is not None and not p["passed"]:
            fix = ("the initial state violates the constraints: start from positions that "
                   "satisfy them (or initial_static = true)" if p["time"] == first else
                   "tighten simulation.newton.constraint_tolerance")
            out.append(f"results not trusted: the constraints are violated by {p['value']:.3g} "
                       f"of the length scale ({self.length:.3g} m; bound {POSITION_DRIFT_BOUND:g}) "
                       f"at t = {p['time']:.6g} s; {fix}")
        w = c.get("velocity_drift")
        if w is not None and not w["passed"]:
            fix = ("the initial velocities violate the constraints: give velocities the joints "
                   "allow" if w["time"] == first else
                   "use constraint_level = \"position_velocity\" or a smaller dt")
            out.append(f"results not trusted: the constraints' rates (Phi_q v + Phi_t) reach "
                       f"{w['value']:.3g} times the largest speed of a node or body "
                       f"({w['speed_scale']:.3g} m/s; bound {VELOCITY_DRIFT_BOUND:g}) at "
                       f"t = {w['time']:.6g} s; {fix}")
        return out

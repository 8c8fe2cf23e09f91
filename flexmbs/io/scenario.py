"""Scenario files: TOML -> :class:`~flexmbs.model.Model`, simulation settings and probes.

The file format is the contract of docs/design.md ("Scenario file"); every key is documented in
``docs/scenario.md``. Everything is validated while the model is built, before anything runs:
an invalid value raises :class:`~flexmbs.errors.ScenarioError` with a one-line message that starts
with the key path (``beams[rail].radius: expected a number > 0, got -0.002``).

This module is the facade; the work is done by

- :mod:`flexmbs.io.tables`: typed reading of TOML tables with key paths (:class:`Table`);
- :mod:`flexmbs.io.overrides`: ``--set KEY=VALUE`` (:func:`apply_override`);
- :mod:`flexmbs.io.builders`: one builder per entry kind, registered by name
  (``builder(table, ctx) -> object``), and the ``[simulation]`` table.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..model import Model
from ..solvers.generalized_alpha import GeneralizedAlpha
from ..solvers.static import StaticOptions
from .builders import (
    CONSTRAINTS,
    INTEGRATORS,
    JOINTS,
    LOADS,
    SPRINGS,
    BuildContext,
    SimulationSettings,
    build_beam,
    build_entry,
    build_probe,
    build_rigid_body,
    build_tendon,
    read_simulation,
)
from .overrides import ARRAY_KEYS, apply_override
from .tables import Table, at
from .tables import read_toml as read_scenario_file

__all__ = [
    "INTEGRATORS",
    "TOP_KEYS",
    "BuildContext",
    "Scenario",
    "SimulationSettings",
    "Table",
    "apply_override",
    "build_scenario",
    "load_scenario",
    "read_scenario_file",
]

#: keys of the top level of a scenario file
TOP_KEYS = ("name", "description", "simulation", *ARRAY_KEYS)


@dataclass
class Scenario:
    """A loaded scenario: the model, how to run it and what to record."""

    name: str
    path: Path
    model: Model
    simulation: SimulationSettings
    probes: list[Any]
    raw: dict[str, Any]                 #: the parsed file after the overrides
    description: str = ""
    joints: dict[str, Any] = field(default_factory=dict)   #: built ``[[joints]]`` by name

    def integrator_options(self) -> GeneralizedAlpha | None:
        """Options of the time integrator; ``None`` for ``integrator = "static"`` and
        ``"quasi_static"`` (equilibria only)."""
        sim = self.simulation
        if sim.integrator in ("static", "quasi_static"):
            return None
        return GeneralizedAlpha(rho_inf=sim.rho_inf, scheme=sim.integrator,  # type: ignore[arg-type]
                                newton=sim.newton_options(), adaptive=sim.adaptive,
                                min_step=sim.min_step or 0.0,
                                predictor=sim.predictor,  # type: ignore[arg-type]
                                compiled=sim.compiled,
                                constraint_level=sim.constraint_level,  # type: ignore[arg-type]
                                step_tolerance=sim.step_tolerance)

    def static_options(self) -> StaticOptions:
        """Options of the static solver (``integrator = "static"``, ``"quasi_static"`` or
        ``initial_static``)."""
        return StaticOptions(load_steps=self.simulation.load_steps,
                             stabilizer=self.simulation.static_stabilizer,
                             newton=self.simulation.newton_options(static=True))


def load_scenario(path: str | os.PathLike[str], overrides: Sequence[str] = ()) -> Scenario:
    """Read, override, validate and build a scenario file (nothing is run)."""
    p = Path(path)
    raw = read_scenario_file(p)
    for assignment in overrides:
        apply_override(raw, assignment)
    return build_scenario(raw, p)


def build_scenario(raw: dict[str, Any], path: str | os.PathLike[str]) -> Scenario:
    """Validate a parsed scenario and build its model; ``path`` anchors relative file paths."""
    p = Path(path)
    root = Table(raw, "")
    root.allow(TOP_KEYS)
    name = root.string("name", p.stem)
    if any(c in name for c in "/\\:") or name in (".", "..") or not name.isprintable():
        raise root.fail("name", "a name usable as a folder name (printable, no / \\ :)", name)
    description = root.get("description", "")
    if not isinstance(description, str):
        raise root.fail("description", "a string", description)
    sim = read_simulation(root.table("simulation"))
    model = Model(gravity=sim.gravity, name=name)
    ctx = BuildContext(model=model, base_dir=p.resolve().parent)
    for t in root.tables("beams", need_name=True):
        with at(t.path):
            ctx.beams[t.raw["name"]] = build_beam(t, ctx)
    for t in root.tables("rigid_bodies", need_name=True):
        with at(t.path):
            ctx.bodies[t.raw["name"]] = build_rigid_body(t, ctx)
    for t in root.tables("constraints", need_name=False):
        build_entry(CONSTRAINTS, t, ctx)
    for t in root.tables("joints", need_name=True):
        ctx.joints[t.raw["name"]] = build_entry(JOINTS, t, ctx)
    for t in root.tables("tendons", need_name=True):
        build_tendon(t, ctx)
    for t in root.tables("loads", need_name=False):
        build_entry(LOADS, t, ctx)
    for t in root.tables("springs", need_name=False):
        build_entry(SPRINGS, t, ctx)
    probes = [build_probe(t, ctx) for t in root.tables("probes", need_name=True)]
    if probes:
        from .probes import probe_columns

        with at("probes"):
            probe_columns(probes)
    return Scenario(name=name, path=p, model=model, simulation=sim, probes=probes, raw=raw,
                    description=description, joints=ctx.joints)

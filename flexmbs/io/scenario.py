"""Scenario files: TOML -> :class:`~flexmbs.model.Model`, simulation settings and probes.

The file format is the contract of DESIGN.md ("Scenario file"); every key is documented in
``docs/scenario.md``. Everything is validated while the model is built, before anything runs:
an invalid value raises :class:`~flexmbs.errors.ScenarioError` with a one-line message that starts
with the key path (``beams[rail].radius: expected a number > 0, got -0.002``). Arrays of tables
are addressed by the entry's ``name`` when it has one (``beams[rail]``), otherwise by index
(``constraints[0]``).

Joint types (``[[joints]]``) and probe types (``[[probes]]``) are registries keyed by the names
used in the file; a builder is ``builder(model, table, keypath, context)`` where ``table`` is a
:class:`Table` reader (typed getters that raise ScenarioError with the key path), ``keypath`` the
entry's path and ``context`` the :class:`BuildContext` (beams, bodies, base directory).
"""

from __future__ import annotations

import difflib
import math
import os
import sys
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..elements.ancf_cable import CableOptions
from ..errors import GeometryError, ModelError, ScenarioError
from ..geometry.curves import Centerline, arc, line, polyline
from ..loads import Constant, HalfSine, Ramp, Sine, TimeFunction
from ..loads import Table as TableFunction
from ..model import GROUND, Beam, Ground, Model, Node, Pose, RigidBody
from ..sections import BeamStiffness, CircularSection, Material
from ..solvers.generalized_alpha import GeneralizedAlpha
from ..solvers.newton import NewtonOptions
from ..solvers.static import StaticOptions

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - python 3.10
    import tomli as tomllib

__all__ = [
    "INTEGRATORS",
    "JOINT_TYPES",
    "PROBE_BUILDERS",
    "BuildContext",
    "Scenario",
    "SimulationSettings",
    "Table",
    "apply_override",
    "build_scenario",
    "load_scenario",
    "read_scenario_file",
]

INTEGRATORS = ("generalized_alpha", "hht", "static")
_MISSING: Any = object()


# ================================================================================================
# Result objects


@dataclass(frozen=True, kw_only=True)
class SimulationSettings:
    """The ``[simulation]`` table (units SI). See docs/scenario.md for every key."""

    t_end: float
    dt: float
    integrator: str = "generalized_alpha"
    rho_inf: float = 0.8
    gravity: tuple[float, float, float] = (0.0, 0.0, 0.0)
    output_interval: float | None = None       #: None: every step
    initial_static: bool = False               #: start from the static equilibrium at t = 0
    adaptive: bool = True                      #: halve the step on Newton failure
    min_step: float | None = None              #: None: dt / 1024
    redundant_constraints: str = "error"       #: "error" | "drop"
    load_steps: int = 1                        #: initial load increments of the static solver
    static_stabilizer: float = 0.0             #: mass-proportional stabiliser c_s [1/s^2]
    predictor: str = "constant_acceleration"   #: Newton start of each step
    compiled: bool = True                      #: compiled integrator when the model allows it
    newton: dict[str, Any] = field(default_factory=dict)  #: NewtonOptions overrides

    def newton_options(self, *, static: bool = False) -> NewtonOptions:
        """NewtonOptions with the ``[simulation.newton]`` keys applied (static: full Newton)."""
        base = StaticOptions().newton if static else NewtonOptions()
        kw = {k: getattr(base, k) for k in base.__dataclass_fields__}
        kw.update(self.newton)
        return NewtonOptions(**kw)


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
        """Options of the time integrator; ``None`` for ``integrator = "static"``."""
        sim = self.simulation
        if sim.integrator == "static":
            return None
        return GeneralizedAlpha(rho_inf=sim.rho_inf, scheme=sim.integrator,  # type: ignore[arg-type]
                                newton=sim.newton_options(), adaptive=sim.adaptive,
                                min_step=sim.min_step or 0.0,
                                predictor=sim.predictor,  # type: ignore[arg-type]
                                compiled=sim.compiled)

    def static_options(self) -> StaticOptions:
        """Options of the static solver (``integrator = "static"`` or ``initial_static``)."""
        return StaticOptions(load_steps=self.simulation.load_steps,
                             stabilizer=self.simulation.static_stabilizer,
                             newton=self.simulation.newton_options(static=True))


@dataclass
class BuildContext:
    """What builders may look up while the model is built."""

    model: Model
    base_dir: Path                       #: directory of the scenario file (relative paths)
    beams: dict[str, Beam] = field(default_factory=dict)
    bodies: dict[str, RigidBody] = field(default_factory=dict)
    joints: dict[str, Any] = field(default_factory=dict)

    def resolve(self, value: str) -> Path:
        p = Path(value).expanduser()
        return p if p.is_absolute() else (self.base_dir / p).resolve()

    def beam(self, t: Table, key: str = "beam") -> Beam:
        name = t.string(key)
        if name not in self.beams:
            known = ", ".join(self.beams) or "none"
            raise ScenarioError(f"{t.key(key)}: no beam named '{name}' (beams: {known})")
        return self.beams[name]

    def body(self, t: Table, key: str = "body") -> RigidBody:
        name = t.string(key)
        if name not in self.bodies:
            known = ", ".join(self.bodies) or "none"
            raise ScenarioError(f"{t.key(key)}: no rigid body named '{name}' (rigid bodies: {known})")
        return self.bodies[name]

    def node(self, t: Table, beam: Beam, key: str = "node") -> Node:
        v = t.get(key)
        n = beam.n_nodes
        if v in ("first", "last"):
            return beam.node(v)
        if isinstance(v, int) and not isinstance(v, bool) and -n <= v < n:
            return beam.node(v)
        raise ScenarioError(f"{t.key(key)}: expected 'first', 'last' or a node index of beam "
                            f"'{beam.name}' in 0..{n - 1}, got {_show(v)}")

    def arc_length(self, t: Table, beam: Beam, key: str = "s") -> float:
        s = t.number(key)
        if not -1e-12 * beam.length <= s <= beam.length * (1 + 1e-12):
            raise ScenarioError(f"{t.key(key)}: expected an arc length in [0, {beam.length:.6g}] "
                                f"(length of beam '{beam.name}'), got {_show(s)}")
        return min(max(s, 0.0), beam.length)


# ================================================================================================
# Reading tables with key paths


def _show(v: Any) -> str:
    """A value as the user wrote it (TOML spelling), shortened."""
    if isinstance(v, bool):
        s = "true" if v else "false"
    elif isinstance(v, str):
        s = repr(v)
    elif isinstance(v, Mapping):
        s = "a table {" + ", ".join(str(k) for k in v) + "}"
    elif isinstance(v, (list, tuple)):
        s = "[" + ", ".join(_show(x) for x in v) + "]"
    else:
        s = repr(v)
    return s if len(s) <= 80 else s[:77] + "..."


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _bounds_text(gt: float | None, ge: float | None, lt: float | None, le: float | None) -> str:
    lo = (f"> {gt:g}" if gt is not None else f">= {ge:g}" if ge is not None else None)
    hi = (f"< {lt:g}" if lt is not None else f"<= {le:g}" if le is not None else None)
    if lo and hi:
        a = "(" if gt is not None else "["
        b = ")" if lt is not None else "]"
        return f" in {a}{gt if gt is not None else ge:g}, {lt if lt is not None else le:g}{b}"
    return f" {lo or hi}" if (lo or hi) else ""


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split())


class Table:
    """Typed, path-aware access to one TOML table (raises ScenarioError naming the key path)."""

    def __init__(self, raw: Mapping[str, Any], path: str) -> None:
        self.raw = raw
        self.path = path

    def key(self, k: str) -> str:
        return f"{self.path}.{k}" if self.path else k

    def where(self) -> str:
        return self.path or "the top level"

    def has(self, k: str) -> bool:
        return k in self.raw

    def present(self, keys: Iterable[str]) -> list[str]:
        return [k for k in keys if k in self.raw]

    def allow(self, keys: Iterable[str]) -> None:
        """Reject keys not in ``keys`` (with a close-match suggestion)."""
        allowed = list(keys)
        for k in self.raw:
            if k not in allowed:
                close = difflib.get_close_matches(k, allowed, n=1, cutoff=0.6)
                hint = (f"; did you mean '{close[0]}'?" if close
                        else f" (allowed: {', '.join(sorted(allowed))})")
                raise ScenarioError(f"unknown key '{k}' in {self.where()}{hint}")

    def exclusive(self, *groups: str) -> str | None:
        """The one key of ``groups`` present (None if none); two or more is an error."""
        got = self.present(groups)
        if len(got) > 1:
            raise ScenarioError(f"{self.where()}: give only one of "
                                f"{', '.join(repr(g) for g in groups)} (got {', '.join(got)})")
        return got[0] if got else None

    def get(self, k: str, default: Any = _MISSING, expected: str = "a value") -> Any:
        if k in self.raw:
            return self.raw[k]
        if default is _MISSING:
            raise ScenarioError(f"{self.key(k)}: missing required key (expected {expected})")
        return default

    def fail(self, k: str, expected: str, got: Any) -> ScenarioError:
        return ScenarioError(f"{self.key(k)}: expected {expected}, got {_show(got)}")

    def number(self, k: str, default: Any = _MISSING, *, gt: float | None = None,
               ge: float | None = None, lt: float | None = None, le: float | None = None) -> Any:
        expected = "a number" + _bounds_text(gt, ge, lt, le)
        v = self.get(k, default, expected)
        if v is default and k not in self.raw:
            return v
        if not _is_number(v) or not math.isfinite(v):
            raise self.fail(k, expected.replace("a number", "a finite number")
                            if _is_number(v) else expected, v)
        if ((gt is not None and not v > gt) or (ge is not None and not v >= ge)
                or (lt is not None and not v < lt) or (le is not None and not v <= le)):
            raise self.fail(k, expected, v)
        return float(v)

    def integer(self, k: str, default: Any = _MISSING, *, ge: int | None = None,
                le: int | None = None) -> Any:
        expected = "an integer" + _bounds_text(None, ge, None, le)
        v = self.get(k, default, expected)
        if v is default and k not in self.raw:
            return v
        if not isinstance(v, int) or isinstance(v, bool):
            raise self.fail(k, expected, v)
        if (ge is not None and v < ge) or (le is not None and v > le):
            raise self.fail(k, expected, v)
        return int(v)

    def boolean(self, k: str, default: Any = _MISSING) -> Any:
        v = self.get(k, default, "true or false")
        if not isinstance(v, bool):
            raise self.fail(k, "true or false", v)
        return v

    def string(self, k: str, default: Any = _MISSING) -> Any:
        v = self.get(k, default, "a string")
        if v is default and k not in self.raw:
            return v
        if not isinstance(v, str) or not v:
            raise self.fail(k, "a non-empty string", v)
        return v

    def choice(self, k: str, choices: Sequence[str], default: Any = _MISSING,
               what: str = "value") -> Any:
        v = self.string(k, default)
        if v not in choices:
            raise ScenarioError(f"{self.key(k)}: unknown {what} {_show(v)} "
                                f"(known: {', '.join(choices)})")
        return v

    def vector(self, k: str, default: Any = _MISSING, *, n: int = 3,
               what: str | None = None) -> Any:
        expected = what or (f"{n} numbers [x, y, z]" if n == 3 else f"{n} numbers")
        v = self.get(k, default, expected)
        if v is default and k not in self.raw:
            return v
        if (not isinstance(v, list) or len(v) != n
                or not all(_is_number(x) and math.isfinite(x) for x in v)):
            raise self.fail(k, expected, v)
        return np.array(v, dtype=float)

    def table(self, k: str, default: Any = _MISSING) -> Any:
        v = self.get(k, default, "a table")
        if v is default and k not in self.raw:
            return v
        if not isinstance(v, Mapping):
            raise self.fail(k, "a table { ... }", v)
        return Table(v, self.key(k))

    def tables(self, k: str, *, need_name: bool) -> list[Table]:
        """An array of tables ``[[k]]``, each addressed as ``k[name]`` (or ``k[index]``)."""
        v = self.get(k, [], "an array of tables [[...]]")
        if isinstance(v, Mapping):
            raise ScenarioError(f"{self.key(k)}: expected an array of tables [[{k}]], got a single "
                                f"table [{k}]; write [[{k}]]")
        if not isinstance(v, list):
            raise self.fail(k, f"an array of tables [[{k}]]", v)
        out: list[Table] = []
        seen: dict[str, int] = {}
        for i, entry in enumerate(v):
            if not isinstance(entry, Mapping):
                raise ScenarioError(f"{self.key(k)}[{i}]: expected a table, got {_show(entry)}")
            name = entry.get("name")
            if "name" in entry and (not isinstance(name, str) or not name):
                raise ScenarioError(f"{self.key(k)}[{i}].name: expected a non-empty string, "
                                    f"got {_show(name)}")
            if need_name and name is None:
                raise ScenarioError(f"{self.key(k)}[{i}].name: missing required key "
                                    f"(expected a unique name string)")
            if name is not None:
                if name in seen:
                    raise ScenarioError(f"{self.key(k)}[{i}].name: duplicate name '{name}' "
                                        f"(also {self.key(k)}[{seen[name]}]); names must be unique")
                seen[name] = i
            out.append(Table(entry, f"{self.key(k)}[{name if name is not None else i}]"))
        return out


@contextmanager
def _at(path: str) -> Iterator[None]:
    """Re-raise model/geometry errors of the API as ScenarioError prefixed with ``path``."""
    try:
        yield
    except ScenarioError:
        raise
    except (ModelError, GeometryError, ValueError) as exc:
        raise ScenarioError(f"{path}: {_one_line(exc)}") from exc


def _display_path(p: Path) -> str:
    """``relative/to/cwd`` (resolved ``/abs/path``)."""
    try:
        rel = os.path.relpath(p)
    except ValueError:  # another drive on Windows
        rel = str(p)
    return f"{rel} (resolved: {p.resolve()})"


# ================================================================================================
# File reading and overrides


def read_scenario_file(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Parse a scenario TOML file (no validation)."""
    p = Path(path)
    if not p.is_file():
        what = "is a directory, not a file" if p.is_dir() else "not found"
        raise ScenarioError(f"scenario file {what}: {_display_path(p)}")
    try:
        with p.open("rb") as fh:
            return tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioError(f"{p}: invalid TOML: {_one_line(exc)}") from exc
    except UnicodeDecodeError as exc:
        raise ScenarioError(f"{p}: invalid TOML: the file is not UTF-8 text ({exc.reason})") from exc


def _parse_value(text: str) -> Any:
    text = text.strip()
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text   # a bare word: a string


def _split_key(key: str) -> list[str]:
    """``beams.rail.elements`` and ``beams[rail].elements`` -> ['beams', 'rail', 'elements']."""
    parts: list[str] = []
    for chunk in key.replace("[", ".").replace("]", "").split("."):
        chunk = chunk.strip()
        if not chunk:
            raise ValueError("empty key segment")
        parts.append(chunk.strip("\"'"))
    return parts


def apply_override(raw: dict[str, Any], assignment: str) -> None:
    """Apply ``KEY=VALUE`` (the CLI ``--set``) to a parsed scenario in place.

    ``KEY`` is a dotted path; entries of arrays of tables are addressed by their ``name`` (or
    by index): ``beams.rail.elements=8``, ``joints.sleeve.clearance=1e-3``,
    ``simulation.newton.max_iterations=40``. ``VALUE`` is parsed as a TOML value (numbers,
    booleans, strings, arrays, inline tables); a bare word is a string. Missing tables on the
    way are created; the loader then validates the result like the file itself.
    """
    if "=" not in assignment:
        raise ScenarioError(f"--set {assignment}: expected KEY=VALUE, e.g. simulation.dt=2e-4")
    key, _, text = assignment.partition("=")
    try:
        parts = _split_key(key)
    except ValueError:
        raise ScenarioError(f"--set {assignment}: invalid key {key.strip()!r}") from None
    value = _parse_value(text)
    node: Any = raw
    done: list[str] = []
    for part in parts[:-1]:
        where = ".".join(done) or "the top level"
        if isinstance(node, list):
            node = _array_entry(node, part, assignment, where)
        elif isinstance(node, dict):
            if part not in node:
                # a missing array of tables has no entries to address; anything else is a table
                node[part] = [] if (node is raw and part in _ARRAY_KEYS) else {}
            node = node[part]
        else:
            raise ScenarioError(f"--set {assignment}: {where} is {_show(node)}, not a table")
        done.append(part)
    last = parts[-1]
    where = ".".join(done) or "the top level"
    if isinstance(node, list):
        raise ScenarioError(f"--set {assignment}: {where} is an array of tables; name an entry "
                            f"and a key, e.g. {where}.<name>.<key>=...")
    if not isinstance(node, dict):
        raise ScenarioError(f"--set {assignment}: {where} is {_show(node)}, not a table")
    node[last] = value


def _array_entry(entries: list[Any], part: str, assignment: str, where: str) -> Any:
    for e in entries:
        if isinstance(e, dict) and e.get("name") == part:
            return e
    if part.lstrip("-").isdigit() and -len(entries) <= int(part) < len(entries):
        return entries[int(part)]
    names = [e["name"] for e in entries if isinstance(e, dict) and isinstance(e.get("name"), str)]
    known = ", ".join(names) if names else f"indices 0..{len(entries) - 1}" if entries else "none"
    raise ScenarioError(f"--set {assignment}: no entry '{part}' in {where} (entries: {known})")


# ================================================================================================
# Loading


_ARRAY_KEYS = ("beams", "rigid_bodies", "constraints", "joints", "loads", "probes")
TOP_KEYS = ("name", "description", "simulation", "beams", "rigid_bodies", "constraints",
            "joints", "loads", "probes")


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
    if any(c in name for c in "/\\:") or name in (".", ".."):
        raise root.fail("name", "a name usable as a folder name (no / \\ :)", name)
    description = root.get("description", "")
    if not isinstance(description, str):
        raise root.fail("description", "a string", description)
    sim = _simulation(root.table("simulation"))
    model = Model(gravity=sim.gravity, name=name)
    ctx = BuildContext(model=model, base_dir=p.resolve().parent)
    for t in root.tables("beams", need_name=True):
        with _at(t.path):
            ctx.beams[t.raw["name"]] = _beam(ctx, t)
    for t in root.tables("rigid_bodies", need_name=True):
        with _at(t.path):
            ctx.bodies[t.raw["name"]] = _rigid_body(ctx, t)
    for t in root.tables("constraints", need_name=False):
        keys, build = _CONSTRAINTS[_kind(t, _CONSTRAINTS, "constraint type")]
        t.allow(("type", "name", *keys))
        with _at(t.path):
            build(ctx, t)
    for t in root.tables("joints", need_name=True):
        kind = _kind(t, JOINT_TYPES, "joint type")
        with _at(t.path):
            ctx.joints[t.raw["name"]] = JOINT_TYPES[kind](model, t, t.path, ctx)
    for t in root.tables("loads", need_name=False):
        keys, build = _LOADS[_kind(t, _LOADS, "load type")]
        t.allow(("type", "name", *keys))
        with _at(t.path):
            build(ctx, t)
    probes = []
    for t in root.tables("probes", need_name=True):
        with _at(t.path):
            probes.append(_probe(ctx, t))
    if probes:
        from .probes import probe_columns

        with _at("probes"):
            probe_columns(probes)
    return Scenario(name=name, path=p, model=model, simulation=sim, probes=probes, raw=raw,
                    description=description, joints=ctx.joints)


def _kind(t: Table, registry: Mapping[str, Any], what: str) -> str:
    """The ``type`` of an entry; a misspelt ``type`` key is reported as such."""
    if not t.has("type"):
        close = difflib.get_close_matches("type", [str(k) for k in t.raw], n=1, cutoff=0.6)
        if close:
            raise ScenarioError(f"unknown key '{close[0]}' in {t.where()}; did you mean 'type'?")
    return t.choice("type", list(registry), what=what)


# ------------------------------------------------------------------------------------ simulation
_NEWTON_KEYS = {"max_iterations": "int", "relative_tolerance": "pos", "constraint_tolerance": "pos",
                "modified": "bool", "line_search": "bool", "refresh_ratio": "ratio",
                "refresh_iterations": "pos", "refresh_cost": "pos"}
PREDICTORS = ("constant_acceleration", "zero_acceleration")


def _simulation(t: Table) -> SimulationSettings:
    t.allow(("t_end", "dt", "integrator", "rho_inf", "gravity", "output_interval",
             "initial_static", "adaptive", "min_step", "redundant_constraints", "load_steps",
             "static_stabilizer", "predictor", "compiled",
             "newton"))
    integrator = t.choice("integrator", INTEGRATORS, "generalized_alpha", what="integrator")
    static = integrator == "static"
    t_end = t.number("t_end", 1.0 if static else _MISSING, gt=0)
    dt = t.number("dt", t_end if static else _MISSING, gt=0)
    if dt > t_end:
        raise t.fail("dt", f"a time step <= t_end = {t_end:g}", dt)
    lo = 0.5 if integrator == "hht" else 0.0
    rho_inf = t.number("rho_inf", 0.8, ge=lo, le=1.0)
    gravity = t.vector("gravity", np.zeros(3))
    out = t.number("output_interval", None, gt=0)
    if out is not None and out < dt * (1 - 1e-12):
        raise t.fail("output_interval", f"a number >= dt = {dt:g} (one output per step at most)", out)
    min_step = t.number("min_step", None, gt=0)
    if min_step is not None and min_step > dt:
        raise t.fail("min_step", f"a number <= dt = {dt:g}", min_step)
    newton: dict[str, Any] = {}
    nt = t.table("newton", None)
    if nt is not None:
        nt.allow(_NEWTON_KEYS)
        for k, kind in _NEWTON_KEYS.items():
            if not nt.has(k):
                continue
            newton[k] = (nt.integer(k, ge=1) if kind == "int" else nt.boolean(k) if kind == "bool"
                         else nt.number(k, gt=0, lt=1) if kind == "ratio" else nt.number(k, gt=0))
    return SimulationSettings(
        t_end=t_end, dt=dt, integrator=integrator, rho_inf=rho_inf,
        gravity=tuple(float(x) for x in gravity),  # type: ignore[arg-type]
        output_interval=out, initial_static=t.boolean("initial_static", False),
        adaptive=t.boolean("adaptive", True), min_step=min_step,
        redundant_constraints=t.choice("redundant_constraints", ("error", "drop"), "error"),
        load_steps=t.integer("load_steps", 1, ge=1),
        static_stabilizer=t.number("static_stabilizer", 0.0, ge=0.0),
        predictor=t.choice("predictor", PREDICTORS, "constant_acceleration", what="predictor"),
        compiled=t.boolean("compiled", True), newton=newton)


# ------------------------------------------------------------------------------------ beams
_ELEMENTS = ("ancf_cable", "ancf_rod14")
_MATERIAL_KEYS = ("youngs_modulus", "density", "poisson_ratio", "shear_modulus")
_EXPLICIT_KEYS = ("axial_stiffness", "bending_stiffness", "mass_per_length", "torsional_stiffness")
_BEAM_KEYS = ("name", "geometry", "elements", "element", "radius", *_MATERIAL_KEYS, *_EXPLICIT_KEYS,
              "damping", "reference_axial_strain", "bending", "axial_rule", "bending_points",
              "exudyn_compatible")


def _beam(ctx: BuildContext, t: Table) -> Beam:
    t.allow(_BEAM_KEYS)
    element = t.choice("element", _ELEMENTS, "ancf_cable", what="element")
    if element != "ancf_cable":
        raise ScenarioError(f"{t.key('element')}: element '{element}' is not available in this "
                            "version (available: ancf_cable)")
    elements = t.integer("elements", None, ge=1)
    centerline = _geometry(ctx, t.table("geometry"), elements, t)
    stiffness = _section(t)
    options = CableOptions(bending=t.choice("bending", ("vector", "scalar"), "vector"),
                           axial_rule=t.choice("axial_rule", ("lobatto3", "gauss5"), "lobatto3"),
                           bending_points=t.integer("bending_points", 3, ge=2, le=3),
                           exudyn_compatible=t.boolean("exudyn_compatible", False))
    return ctx.model.add_beam(centerline, section=stiffness, name=t.raw["name"], options=options,
                              damping=t.number("damping", 0.0, ge=0),
                              reference_axial_strain=t.number("reference_axial_strain", 0.0,
                                                              gt=-1, lt=1))


def _geometry(ctx: BuildContext, g: Table, elements: int | None, beam: Table) -> Centerline:
    g.allow(("line", "arc", "mesh", "group", "polyline"))
    kinds = g.present(("line", "arc", "mesh", "polyline"))
    if len(kinds) != 1:
        raise ScenarioError(f"{g.path}: expected exactly one of 'line', 'arc', 'mesh', 'polyline'"
                            f", got {', '.join(kinds) or 'none'}")
    kind = kinds[0]
    if g.has("group") and kind != "mesh":
        raise ScenarioError(f"{g.key('group')}: 'group' selects a curve of a mesh file; it needs "
                            "geometry.mesh")
    if kind in ("line", "arc") and elements is None:
        raise ScenarioError(f"{beam.key('elements')}: missing required key (expected an integer "
                            f">= 1; a {kind} geometry needs the number of elements)")
    if kind == "mesh":
        file = ctx.resolve(g.string("mesh"))
        group = g.string("group", None)
        if not file.is_file():
            raise ScenarioError(f"{g.key('mesh')}: mesh file not found: {_display_path(file)}")
        with _at(g.key("mesh")):
            from ..geometry.mesh_input import read_curve

            return read_curve(file, group=group, elements=elements)
    sub = g.table(kind)
    with _at(sub.path):
        if kind == "line":
            assert elements is not None  # checked above
            sub.allow(("start", "end"))
            return line(sub.vector("start"), sub.vector("end"), elements=elements)
        if kind == "arc":
            assert elements is not None
            sub.allow(("center", "radius", "start", "angle", "normal"))
            return arc(sub.vector("center"), sub.number("radius", gt=0), sub.vector("start"),
                       sub.number("angle"), sub.vector("normal", np.array([0.0, 0.0, 1.0])),
                       elements=elements)
        sub.allow(("points", "tangents", "closed"))
        pts = _points(sub, "points")
        tans = _points(sub, "tangents", len(pts)) if sub.has("tangents") else None
        return polyline(pts, tans, closed=sub.boolean("closed", False), elements=elements)


def _points(t: Table, k: str, n: int | None = None) -> np.ndarray:
    v = t.get(k, expected="an array of points [[x, y, z], ...]")
    ok = (isinstance(v, list) and len(v) >= (n or 2) and (n is None or len(v) == n)
          and all(isinstance(p, list) and len(p) == 3
                  and all(_is_number(x) and math.isfinite(x) for x in p) for p in v))
    if not ok:
        raise t.fail(k, f"an array of {n or 'at least 2'} points [[x, y, z], ...]", v)
    return np.array(v, dtype=float)


def _section(t: Table) -> BeamStiffness:
    explicit = t.present(_EXPLICIT_KEYS[:3])
    if explicit:
        mixed = t.present(_MATERIAL_KEYS)
        if mixed:
            raise ScenarioError(f"{t.path}: give the section either as radius + youngs_modulus + "
                                "density or as axial_stiffness + bending_stiffness + "
                                f"mass_per_length, not both (got {', '.join(explicit + mixed)})")
        return BeamStiffness(axial_stiffness=t.number("axial_stiffness", gt=0),
                             bending_stiffness=t.number("bending_stiffness", gt=0),
                             mass_per_length=t.number("mass_per_length", ge=0),
                             torsional_stiffness=t.number("torsional_stiffness", None, gt=0),
                             radius=t.number("radius", None, gt=0))
    if t.has("torsional_stiffness"):
        raise ScenarioError(f"{t.key('torsional_stiffness')}: only with an explicit section "
                            "(axial_stiffness, bending_stiffness, mass_per_length); with "
                            "radius + youngs_modulus it follows from shear_modulus/poisson_ratio")
    if not t.has("radius") and not t.has("youngs_modulus"):
        raise ScenarioError(f"{t.path}: missing section: give radius + youngs_modulus + density "
                            "or axial_stiffness + bending_stiffness + mass_per_length")
    radius = t.number("radius", gt=0)
    E = t.number("youngs_modulus", gt=0)
    rho = t.number("density", ge=0)
    t.exclusive("poisson_ratio", "shear_modulus")
    if t.has("shear_modulus"):
        G = t.number("shear_modulus", gt=0)
        nu = E / (2 * G) - 1
        if not -1 < nu < 0.5:
            raise t.fail("shear_modulus", f"a number > {E / 3:g} (youngs_modulus/3, so that the "
                         "Poisson ratio E/2G - 1 is in (-1, 0.5))", G)
    else:
        nu = t.number("poisson_ratio", 0.3, gt=-1, lt=0.5)
    return BeamStiffness.from_section(CircularSection(radius), Material(E=E, rho=rho, nu=nu))


# ------------------------------------------------------------------------------------ rigid bodies
def _rigid_body(ctx: BuildContext, t: Table) -> RigidBody:
    t.allow(("name", "mass", "inertia", "pose", "velocity", "angular_velocity", "shape"))
    mass = t.number("mass", gt=0)
    inertia = _inertia(t)
    pt = t.table("pose", None)
    pose = Pose(np.zeros(3)) if pt is None else _pose(ctx, pt)
    shape = _shape(ctx, t.table("shape")) if t.has("shape") else None
    return ctx.model.add_rigid_body(mass=mass, inertia=inertia, pose=pose, name=t.raw["name"],
                                    velocity=t.vector("velocity", np.zeros(3)),
                                    angular_velocity=t.vector("angular_velocity", np.zeros(3)),
                                    shape=shape)


def _inertia(t: Table) -> np.ndarray:
    expected = "3 principal moments > 0 or a symmetric positive definite 3x3 matrix [kg m^2]"
    v = t.get("inertia", expected=expected)
    J: np.ndarray | None = None
    if isinstance(v, list) and len(v) == 3 and all(_is_number(x) for x in v):
        J = np.diag(np.array(v, dtype=float))
    elif (isinstance(v, list) and len(v) == 3
          and all(isinstance(r, list) and len(r) == 3 and all(_is_number(x) for x in r) for r in v)):
        J = np.array(v, dtype=float)
    if J is None or not np.all(np.isfinite(J)) or not np.allclose(J, J.T, rtol=1e-10,
                                                                  atol=1e-14 * np.abs(J).max()):
        raise t.fail("inertia", expected, v)
    ev = np.linalg.eigvalsh(J)
    if ev.min() <= 0:
        raise t.fail("inertia", expected, v)
    if ev[2] > (ev[0] + ev[1]) * (1 + 1e-6):
        raise ScenarioError(f"{t.key('inertia')}: principal moments {_show(ev.tolist())} violate "
                            "the triangle inequality (each <= the sum of the other two); no rigid "
                            "body has them")
    return J


def _pose(ctx: BuildContext, p: Table) -> Pose:
    p.allow(("position", "quaternion", "on_beam", "s", "offset", "up"))
    if p.has("on_beam"):
        bad = p.present(("position", "quaternion"))
        if bad:
            raise ScenarioError(f"{p.path}: give either {{ position, quaternion }} or "
                                f"{{ on_beam, s, offset }}, not both (got on_beam and {bad[0]})")
        beam = ctx.beam(p, "on_beam")
        s = ctx.arc_length(p, beam)
        up = p.vector("up", None)
        with _at(p.path):
            frame = beam.frame_at(s, up=up)
        return frame.shifted(p.vector("offset", np.zeros(3)))
    bad = p.present(("s", "offset", "up"))
    if bad:
        raise ScenarioError(f"{p.key(bad[0])}: only with on_beam = \"<beam name>\"")
    position = p.vector("position")
    q = p.vector("quaternion", np.array([1.0, 0, 0, 0]), n=4,
                 what="a unit quaternion [w, x, y, z] (4 numbers)")
    if abs(np.linalg.norm(q) - 1.0) > 1e-3:
        raise p.fail("quaternion", f"a unit quaternion [w, x, y, z] (norm {np.linalg.norm(q):.6g})",
                     q.tolist())
    return Pose.from_quaternion(position, q)


_SHAPES = ("cylinder", "box", "mesh")


def _shape(ctx: BuildContext, s: Table) -> dict[str, Any]:
    kind = s.choice("type", _SHAPES, what="shape type")
    if kind == "cylinder":
        s.allow(("type", "radius", "length", "inner_radius"))
        r = s.number("radius", gt=0)
        out: dict[str, Any] = {"type": kind, "radius": r, "length": s.number("length", gt=0)}
        if s.has("inner_radius"):
            out["inner_radius"] = s.number("inner_radius", ge=0, lt=r)
        return out
    if kind == "box":
        s.allow(("type", "size"))
        size = s.vector("size", what="3 sizes [lx, ly, lz] > 0")
        if np.any(size <= 0):
            raise s.fail("size", "3 sizes [lx, ly, lz] > 0", size.tolist())
        return {"type": kind, "size": size.tolist()}
    s.allow(("type", "file", "scale"))
    file = ctx.resolve(s.string("file"))
    if not file.is_file():
        raise ScenarioError(f"{s.key('file')}: shape file not found: {_display_path(file)}")
    return {"type": kind, "file": str(file), "scale": s.number("scale", 1.0, gt=0)}


# ------------------------------------------------------------------------------------ constraints
def _clamp(ctx: BuildContext, t: Table) -> None:
    ctx.model.clamp(ctx.node(t, ctx.beam(t)), name=t.raw.get("name"))


def _pin(ctx: BuildContext, t: Table) -> None:
    ctx.model.pin(ctx.node(t, ctx.beam(t)), name=t.raw.get("name"))


def _fix_body(ctx: BuildContext, t: Table) -> None:
    ctx.model.fix_body(ctx.body(t), name=t.raw.get("name"))


def _first(ctx: BuildContext, t: Table, allow_node: bool = True) -> RigidBody | Node:
    """The first connected object: ``body`` or (``beam`` + ``node``)."""
    which = t.exclusive("body", "beam") if allow_node else ("body" if t.has("body") else None)
    if which is None:
        raise ScenarioError(f"{t.key('body')}: missing required key (expected the name of a "
                            f"rigid body{' or beam + node' if allow_node else ''})")
    if which == "body":
        if t.has("node"):
            raise ScenarioError(f"{t.key('node')}: only with beam = \"<beam name>\"")
        return ctx.body(t)
    return ctx.node(t, ctx.beam(t))


def _second(ctx: BuildContext, t: Table) -> RigidBody | Ground:
    return ctx.body(t, "body2") if t.has("body2") else GROUND


def _global_point(obj: RigidBody | Node, local: np.ndarray) -> np.ndarray:
    if isinstance(obj, Node):
        return obj.position.copy()
    return obj.pose.position + obj.pose.rotation @ local


def _spherical(ctx: BuildContext, t: Table) -> None:
    a = _first(ctx, t)
    if isinstance(a, Node) and t.has("point"):
        raise ScenarioError(f"{t.key('point')}: a beam node has no body frame; omit 'point'")
    x = _global_point(a, t.vector("point", np.zeros(3)))
    if t.has("body2"):
        if t.has("ground_point"):
            raise ScenarioError(f"{t.path}: give either body2 (+ point2) or ground_point, not both")
        b: RigidBody | Ground = ctx.body(t, "body2")
        other, key = _global_point(b, t.vector("point2", np.zeros(3))), "point2"  # type: ignore[arg-type]
    else:
        if t.has("point2"):
            raise ScenarioError(f"{t.key('point2')}: only with body2 = \"<body name>\"")
        b = GROUND
        other, key = (t.vector("ground_point"), "ground_point") if t.has("ground_point") else (x, "")
    gap = float(np.linalg.norm(other - x))
    if key and gap > 1e-9 * max(1.0, float(np.linalg.norm(x))):
        raise ScenarioError(f"{t.key(key)}: expected the same global point as the first object's "
                            f"point {_show(x.tolist())} in the initial configuration, "
                            f"got {_show(other.tolist())} ({gap:.3g} m apart)")
    ctx.model.spherical(a, b, point=x, name=t.raw.get("name"))


def _revolute(ctx: BuildContext, t: Table) -> None:
    a = _first(ctx, t, allow_node=False)
    ctx.model.revolute(a, _second(ctx, t), point=t.vector("point"), axis=_axis(t),  # type: ignore[arg-type]
                       name=t.raw.get("name"))


def _prismatic(ctx: BuildContext, t: Table) -> None:
    a = _first(ctx, t, allow_node=False)
    ctx.model.prismatic(a, _second(ctx, t), point=t.vector("point"), axis=_axis(t),  # type: ignore[arg-type]
                        name=t.raw.get("name"))


def _axis(t: Table, default: Any = _MISSING) -> Any:
    ax = t.vector("axis", default)
    if ax is not None and not np.linalg.norm(ax) > 0:
        raise t.fail("axis", "a non-zero direction [x, y, z]", ax.tolist())
    return ax


def _rigid(ctx: BuildContext, t: Table) -> None:
    node = ctx.node(t, ctx.beam(t))
    ctx.model.rigid(node, _second_named(ctx, t, "body"), name=t.raw.get("name"))


def _second_named(ctx: BuildContext, t: Table, key: str) -> RigidBody | Ground:
    return ctx.body(t, key) if t.has(key) else GROUND


def _prescribed(ctx: BuildContext, t: Table) -> None:
    target = _first(ctx, t)
    n = 6 if isinstance(target, Node) else 7
    comps = t.get("components", expected=f"a list of coordinate indices in 0..{n - 1}")
    if (not isinstance(comps, list) or not comps or len(set(map(str, comps))) != len(comps)
            or not all(isinstance(c, int) and not isinstance(c, bool) and 0 <= c < n for c in comps)):
        what = "node: 0-2 position, 3-5 slope" if n == 6 else "body: 0-2 position, 3-6 Euler parameters"
        raise t.fail("components", f"a list of distinct indices in 0..{n - 1} ({what})", comps)
    fn = _function(t, "function", Constant(0.0))
    ctx.model.prescribe(target, comps, fn, name=t.raw.get("name"))


def _joint(ctx: BuildContext, t: Table) -> None:
    a = _first(ctx, t)
    b = _second(ctx, t)
    frame = None
    if t.exclusive("axis", "frame") == "frame":
        v = t.get("frame")
        F = np.array(v, dtype=float) if (isinstance(v, list) and len(v) == 3 and all(
            isinstance(r, list) and len(r) == 3 and all(_is_number(x) for x in r) for r in v)) else None
        if F is None or not np.allclose(F.T @ F, np.eye(3), atol=1e-9) or np.linalg.det(F) < 0:
            raise t.fail("frame", "a 3x3 rotation matrix (columns = joint axes, global)", v)
        frame = F
    masks = {}
    for k, default in (("translation", [1, 1, 1]), ("rotation", [0, 0, 0])):
        m = t.get(k, default)
        if not (isinstance(m, list) and len(m) == 3 and all(x in (0, 1) for x in m)):
            raise t.fail(k, "3 flags [x, y, z], each 0 (free) or 1 (locked)", m)
        masks[k] = tuple(int(x) for x in m)
    if sum(masks["translation"]) + sum(masks["rotation"]) == 0:
        raise ScenarioError(f"{t.path}: translation and rotation lock nothing; set at least one 1")
    ctx.model.joint(a, b, point=t.vector("point"), axis=_axis(t, None), frame=frame,
                    translation=masks["translation"], rotation=masks["rotation"],
                    name=t.raw.get("name"))


_CONSTRAINTS: dict[str, tuple[tuple[str, ...], Callable[[BuildContext, Table], None]]] = {
    "clamp": (("beam", "node"), _clamp),
    "pin": (("beam", "node"), _pin),
    "fix_body": (("body",), _fix_body),
    "spherical": (("body", "beam", "node", "point", "body2", "point2", "ground_point"), _spherical),
    "revolute": (("body", "body2", "point", "axis"), _revolute),
    "prismatic": (("body", "body2", "point", "axis"), _prismatic),
    "rigid": (("beam", "node", "body"), _rigid),
    "prescribed": (("body", "beam", "node", "components", "function"), _prescribed),
    "joint": (("body", "beam", "node", "body2", "point", "axis", "frame", "translation",
               "rotation"), _joint),
}


# ------------------------------------------------------------------------------------ joints
def _sliding(model: Model, t: Table, keypath: str, ctx: BuildContext) -> Any:
    """``type = "sliding"``: SlidingJoint (no clearance), FORMULATION Part II §7."""
    from ..constraints.sliding import SlidingJoint

    t.allow(("name", "type", "beam", "body", "variant", "s0", "hole_point", "axis", "friction",
             "friction_velocity", "axial_force"))
    beam = ctx.beam(t)
    body = ctx.body(t)
    s0 = ctx.arc_length(t, beam, "s0") if t.has("s0") else None
    joint = SlidingJoint(
        beam, body, name=t.raw["name"],
        variant=t.choice("variant", ("cylindrical", "ring"), "cylindrical", what="variant"),
        s0=s0, hole_point=t.vector("hole_point", (0.0, 0.0, 0.0)),
        axis=t.vector("axis", (1.0, 0.0, 0.0)),
        friction=t.number("friction", 0.0, ge=0.0),
        friction_velocity=t.number("friction_velocity", 1e-3, gt=0.0),
        axial_force=_function(t, "axial_force", None) if t.has("axial_force") else None)
    return model.add_joint(joint)


_LAW_KEYS = {"linear": ("stiffness", "damping"), "hertz": ("stiffness", "exponent"),
             "hunt_crossley": ("stiffness", "exponent", "restitution"),
             "lankarani_nikravesh": ("stiffness", "exponent", "restitution")}


def _sliding_clearance(model: Model, t: Table, keypath: str, ctx: BuildContext) -> Any:
    """``type = "sliding_clearance"``: SlidingClearanceJoint, FORMULATION Part II §1-§8."""
    from ..contact.joint import Hole, SlidingClearanceJoint
    from ..contact.laws import RegularizedCoulomb, get_law
    from ..contact.sections import CircleSection, SuperellipseSection

    t.allow(("name", "type", "beam", "body", "hole", "contact", "beam_radius", "tangent"))
    beam = ctx.beam(t)
    body = ctx.body(t)
    h = t.table("hole")
    shape = h.choice("shape", ("circle", "superellipse"), "circle", what="hole shape")
    if shape == "circle":
        h.allow(("shape", "radius", "length", "sections", "point"))
        section: Any = CircleSection(h.number("radius", gt=0.0))
    else:
        h.allow(("shape", "semi_axes", "exponent", "length", "sections", "point"))
        A, B = h.vector("semi_axes", n=2, what="2 numbers [A, B] (semi-axes along body y, z)")
        if not (A > 0 and B > 0):
            raise h.fail("semi_axes", "2 numbers > 0", [A, B])
        section = SuperellipseSection(float(A), float(B), h.number("exponent", 2.0, ge=2.0))
    hole = Hole(section, h.number("length", gt=0.0), h.integer("sections", 9, ge=1))
    c = t.table("contact") if t.has("contact") else Table({}, t.key("contact"))
    law = c.choice("law", tuple(_LAW_KEYS), "linear", what="contact law")
    c.allow(("law", *_LAW_KEYS[law], "friction", "friction_velocity"))
    params = {k: c.number(k, ge=0.0) for k in _LAW_KEYS[law] if c.has(k)}
    try:
        contact_law = get_law(law, **params)
    except ModelError as exc:
        raise ScenarioError(f"{c.where()}: {exc}") from None
    mu = c.number("friction", 0.0, ge=0.0)
    friction = (RegularizedCoulomb(mu=mu, eps_v=c.number("friction_velocity", 1e-3, gt=0.0))
                if mu > 0 else None)
    tangent = t.choice("tangent", ("consistent", "gauss_newton"), "gauss_newton", what="tangent")
    joint = SlidingClearanceJoint(
        beam, body, hole=hole, contact=contact_law, friction=friction,
        hole_point=h.vector("point", (0.0, 0.0, 0.0)),
        beam_radius=t.number("beam_radius", gt=0.0) if t.has("beam_radius") else None,
        consistent=tangent == "consistent", name=t.raw["name"])
    return model.add_joint(joint)


#: ``[[joints]]`` types: builder(model, table, keypath, context) -> joint object
JOINT_TYPES: dict[str, Callable[[Model, Table, str, BuildContext], Any]] = {
    "sliding": _sliding,
    "sliding_clearance": _sliding_clearance,
}


# ------------------------------------------------------------------------------------ loads
def _function(t: Table, key: str, default: TimeFunction) -> TimeFunction:
    """A time function: a number (constant) or ``{ type = "ramp" | "half_sine" | ... }``."""
    if not t.has(key):
        return default
    v = t.raw[key]
    if _is_number(v):
        return Constant(float(t.number(key)))
    if not isinstance(v, Mapping):
        raise t.fail(key, "a number or a time function table { type = "
                     f"{' | '.join(repr(k) for k in _FUNCTIONS)}, ... }}", v)
    f = t.table(key)
    kind = f.choice("type", _FUNCTIONS, what="time function")
    if kind == "constant":
        f.allow(("type", "value"))
        return Constant(f.number("value"))
    if kind == "ramp":
        f.allow(("type", "start", "end", "value", "smooth"))
        start, end = f.number("start", 0.0), f.number("end")
        if not end > start:
            raise f.fail("end", f"a time > start = {start:g}", end)
        return Ramp(start=start, end=end, value=f.number("value", 1.0),
                    smooth=f.boolean("smooth", False))
    if kind == "half_sine":
        f.allow(("type", "duration", "start", "amplitude"))
        return HalfSine(duration=f.number("duration", gt=0), start=f.number("start", 0.0),
                        amplitude=f.number("amplitude", 1.0))
    if kind == "sine":
        f.allow(("type", "amplitude", "frequency", "phase"))
        return Sine(amplitude=f.number("amplitude", 1.0), frequency=f.number("frequency", gt=0),
                    phase=f.number("phase", 0.0))
    f.allow(("type", "times", "values"))
    times, values = f.get("times", expected="a list of times"), f.get("values",
                                                                       expected="a list of numbers")
    for k, arr in (("times", times), ("values", values)):
        if not (isinstance(arr, list) and arr and all(_is_number(x) and math.isfinite(x)
                                                       for x in arr)):
            raise f.fail(k, "a non-empty list of numbers", arr)
    if len(times) != len(values):
        raise f.fail("values", f"{len(times)} numbers (one per entry of times)", values)
    if any(b <= a for a, b in zip(times[:-1], times[1:], strict=True)):
        raise f.fail("times", "strictly increasing times", times)
    return TableFunction(times, values)


_FUNCTIONS = ("constant", "ramp", "half_sine", "sine", "table")


def _point_load(ctx: BuildContext, t: Table) -> None:
    which = t.exclusive("beam", "body")
    if which is None:
        raise ScenarioError(f"{t.path}: missing target: give beam (+ node or s) or body (+ point)")
    if not t.has("force") and not t.has("moment"):
        raise ScenarioError(f"{t.key('force')}: missing required key (expected 3 numbers [N]; "
                            "give force and/or moment)")
    force = t.vector("force", np.zeros(3))
    moment = t.vector("moment", None)
    fn = _function(t, "function", Constant(1.0))
    target: Any
    if which == "body":
        for k in ("node", "s"):
            if t.has(k):
                raise ScenarioError(f"{t.key(k)}: only with beam = \"<beam name>\"")
        target = ctx.body(t)
    else:
        if t.has("point"):
            raise ScenarioError(f"{t.key('point')}: only with body = \"<body name>\" (a beam load "
                                "acts at node or s)")
        beam = ctx.beam(t)
        at = t.exclusive("node", "s")
        if at is None:
            raise ScenarioError(f"{t.key('node')}: missing required key (expected 'first', 'last', "
                                "a node index, or s = arc length)")
        if at == "node":
            target = ctx.node(t, beam)
        else:
            if moment is not None:
                raise ScenarioError(f"{t.key('moment')}: moments on a beam act at nodes only; "
                                    "give node instead of s")
            target = (beam, ctx.arc_length(t, beam))
    ctx.model.add_point_load(target, force, moment=moment, point=t.vector("point", np.zeros(3)),
                             function=fn, name=t.raw.get("name"))


def _distributed_load(ctx: BuildContext, t: Table) -> None:
    beam = ctx.beam(t)
    ctx.model.add_distributed_load(beam, t.vector("force"),
                                   function=_function(t, "function", Constant(1.0)),
                                   name=t.raw.get("name"))


_LOADS: dict[str, tuple[tuple[str, ...], Callable[[BuildContext, Table], None]]] = {
    "point": (("beam", "node", "s", "body", "point", "force", "moment", "function"), _point_load),
    "distributed": (("beam", "force", "function"), _distributed_load),
}


# ------------------------------------------------------------------------------------ probes
def _probe_beam_point(model: Model, t: Table, keypath: str, ctx: BuildContext) -> Any:
    from . import probes

    t.allow(("name", "type", "beam", "s", "quantity"))
    beam = ctx.beam(t)
    s = ctx.arc_length(t, beam)
    quantity = t.choice("quantity", ("position", "displacement", "velocity"), "position",
                        what="quantity")
    return probes.BeamPointProbe(t.raw["name"], beam, s, quantity)


def _probe_body_position(model: Model, t: Table, keypath: str, ctx: BuildContext) -> Any:
    from . import probes

    t.allow(("name", "type", "body"))
    return probes.BodyPositionProbe(t.raw["name"], ctx.body(t))


def _probe_body_point(model: Model, t: Table, keypath: str, ctx: BuildContext) -> Any:
    from . import probes

    t.allow(("name", "type", "body", "point", "quantity"))
    quantity = t.choice("quantity", ("position", "displacement"), "position", what="quantity")
    return probes.BodyPointProbe(t.raw["name"], ctx.body(t), t.vector("point"), quantity)


def _probe_body_orientation(model: Model, t: Table, keypath: str, ctx: BuildContext) -> Any:
    from . import probes

    t.allow(("name", "type", "body"))
    return probes.BodyOrientationProbe(t.raw["name"], ctx.body(t))


def _probe_energy(model: Model, t: Table, keypath: str, ctx: BuildContext) -> Any:
    from . import probes

    t.allow(("name", "type", "quantity"))
    quantity = t.choice("quantity", ("total", "kinetic", "strain", "gravity"), "total",
                        what="quantity")
    return probes.EnergyProbe(t.raw["name"], quantity)


def _joint_probe(cls_name: str, needs: str, kind: str) -> Callable[..., Any]:
    """Builder of a probe on a joint that offers the method ``needs`` (``joint = "name"``)."""

    def build(model: Model, t: Table, keypath: str, ctx: BuildContext) -> Any:
        from . import probes

        t.allow(("name", "type", "joint"))
        name = t.string("joint")
        joint = ctx.joints.get(name)
        if joint is None or not hasattr(joint, needs):
            known = ", ".join(k for k, j in ctx.joints.items() if hasattr(j, needs))
            raise ScenarioError(f"{t.key('joint')}: no {kind} joint named '{name}' "
                                f"({kind} joints: {known or 'none'})")
        return getattr(probes, cls_name)(t.raw["name"], joint)

    return build


_probe_slide_coordinate = _joint_probe("SlideCoordinateProbe", "slide_coordinate", "sliding")
_probe_joint_reaction = _joint_probe("JointReactionProbe", "reaction_force", "sliding")
_probe_contact_force = _joint_probe("ContactForceProbe", "contact_force", "clearance")


#: ``[[probes]]`` types: builder(model, table, keypath, context) -> probe object
PROBE_BUILDERS: dict[str, Callable[[Model, Table, str, BuildContext], Any]] = {
    "beam_point": _probe_beam_point,
    "body_position": _probe_body_position,
    "body_orientation": _probe_body_orientation,
    "body_point": _probe_body_point,
    "energy": _probe_energy,
    "slide_coordinate": _probe_slide_coordinate,
    "contact_force": _probe_contact_force,
    "joint_reaction": _probe_joint_reaction,
}


def _probe(ctx: BuildContext, t: Table) -> Any:
    name = t.raw["name"]
    if any(c in name for c in ",\"\n\r") or name.strip() != name:
        raise t.fail("name", "a probe name usable as a CSV column (no commas, quotes or "
                     "surrounding spaces)", name)
    kind = _kind(t, PROBE_BUILDERS, "probe type")
    return PROBE_BUILDERS[kind](ctx.model, t, t.path, ctx)


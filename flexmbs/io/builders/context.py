"""What every scenario builder sees: the :class:`BuildContext` and the one builder signature.

A builder of any kind (element, constraint, joint, load, probe) is
``builder(table: Table, ctx: BuildContext) -> object``: it checks its own keys
(``table.allow(...)``), reads them through the typed :class:`~flexmbs.io.tables.Table` getters,
looks named objects up in ``ctx`` and adds what it builds to ``ctx.model``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ...errors import ScenarioError
from ...model import Beam, Model, Node, RigidBody
from ...registry import Registry
from ..tables import Table, at, show_value

__all__ = ["Builder", "BuildContext", "build_entry"]

#: the signature of every scenario builder
Builder = Callable[[Table, "BuildContext"], Any]


@dataclass
class BuildContext:
    """The model being built and the named objects builders may look up."""

    model: Model
    base_dir: Path                       #: directory of the scenario file (relative paths)
    beams: dict[str, Beam] = field(default_factory=dict)
    bodies: dict[str, RigidBody] = field(default_factory=dict)
    joints: dict[str, Any] = field(default_factory=dict)
    #: built ``[[tendons]]`` by name (:class:`~flexmbs.tendons.TendonParts`)
    tendons: dict[str, Any] = field(default_factory=dict)
    #: bodies placed with ``pose = { on_beam, s, rest = "bore" }``: name -> (rest direction or
    #: None for gravity, key path of the pose); their clearance joint moves them to rest
    resting: dict[str, tuple[Any, str]] = field(default_factory=dict)

    def resolve(self, value: str) -> Path:
        """A path of the scenario file, relative to its directory."""
        p = Path(value).expanduser()
        return p if p.is_absolute() else (self.base_dir / p).resolve()

    def beam(self, t: Table, key: str = "beam") -> Beam:
        """The beam named by ``t[key]``."""
        name = t.string(key)
        if name not in self.beams:
            known = ", ".join(self.beams) or "none"
            raise ScenarioError(f"{t.key(key)}: no beam named '{name}' (beams: {known})")
        return self.beams[name]

    def constraint(self, t: Table, key: str = "joint") -> Any:
        """The revolute, prismatic or generic joint of ``[[constraints]]`` named by ``t[key]``
        (defined before this entry)."""
        name = t.string(key)
        joints = [c for c in self.model.constraints if c.frame_a is not None and c.kind != "driver"]
        for c in joints:
            if c.name == name:
                return c
        known = ", ".join(c.name for c in joints) or "none"
        raise ScenarioError(f"{t.key(key)}: no joint named '{name}' among the [[constraints]] "
                            f"before this entry (joints: {known})")

    def body(self, t: Table, key: str = "body") -> RigidBody:
        """The rigid body named by ``t[key]``."""
        name = t.string(key)
        if name not in self.bodies:
            known = ", ".join(self.bodies) or "none"
            raise ScenarioError(f"{t.key(key)}: no rigid body named '{name}' (rigid bodies: {known})")
        return self.bodies[name]

    def node(self, t: Table, beam: Beam, key: str = "node") -> Node:
        """The node of ``beam`` given by ``t[key]``: ``"first"``, ``"last"`` or an index."""
        v = t.get(key)
        n = beam.n_nodes
        if v in ("first", "last"):
            return beam.node(v)
        if isinstance(v, int) and not isinstance(v, bool) and -n <= v < n:
            return beam.node(v)
        raise ScenarioError(f"{t.key(key)}: expected 'first', 'last' or a node index of beam "
                            f"'{beam.name}' in 0..{n - 1}, got {show_value(v)}")

    def arc_length(self, t: Table, beam: Beam, key: str = "s") -> float:
        """A reference arc length of ``beam`` (within its length)."""
        s = t.number(key, unit="m")
        tol = beam.length_tolerance
        if not -tol <= s <= beam.length + tol:
            raise ScenarioError(f"{t.key(key)}: expected an arc length in [0, {beam.length!r}] "
                                f"(length of beam '{beam.name}', tolerance {tol:.3g}), got "
                                f"{show_value(s)}")
        return beam.check_arc_length(s)


def build_entry(registry: Registry[Builder], t: Table, ctx: BuildContext) -> Any:
    """Build the entry ``t`` of an array of tables by its ``type`` (the registry's builder);
    errors of the Python API are reported with the entry's key path."""
    _, build = t.kind(registry)
    with at(t.path):
        return build(t, ctx)

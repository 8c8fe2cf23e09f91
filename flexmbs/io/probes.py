"""Probes: named scalar/vector quantities written to ``probes.csv`` at every output time.

A probe declares its CSV columns and evaluates them from the assembly and a solver state.
Vector probes write ``<name>_x, <name>_y, <name>_z`` (docs/design.md, "Output folder"). The names
used in scenario files (``[[probes]] type = ...``) are the registry
:data:`flexmbs.io.builders.probes.PROBES` of scenario builders; a new probe type is a class here
and a builder registered there.
"""

from __future__ import annotations

import weakref
from abc import ABC, abstractmethod
from typing import Any

import numpy as np

from ..elements import hermite
from ..errors import ModelError
from ..model import Beam, RigidBody

_XYZ = ("x", "y", "z")


class Probe(ABC):
    """A named output quantity; ``columns()`` and ``evaluate()`` have the same length."""

    name: str

    @abstractmethod
    def columns(self) -> list[str]:
        """CSV column names: ``[name]`` for scalars, ``[name_x, name_y, name_z]`` for vectors."""

    @abstractmethod
    def evaluate(self, asm: Any, state: Any) -> np.ndarray:
        """Values in the order of :meth:`columns`."""

    def check(self, asm: Any) -> None:  # noqa: B027 - optional hook, default accepts everything
        """Raise :class:`ModelError` if the probe does not belong to ``asm.model``."""


def _check_name(name: object) -> str:
    if not isinstance(name, str) or not name or "," in name:
        raise ModelError(f"probe name must be a non-empty string without commas (got {name!r})")
    return name


class BeamPointProbe(Probe):
    """Position, displacement or velocity of the material point at reference arc length ``s``,
    or one of its element's output fields there (the cable's ``axial_strain``, ``curvature``;
    the rod's also ``twist``, ``torsion``, ``torsional_moment``)."""

    QUANTITIES = ("position", "displacement", "velocity")

    @classmethod
    def quantities(cls, beam: Beam) -> tuple[str, ...]:
        """What a probe on ``beam`` can record."""
        return cls.QUANTITIES + beam.layout.output_fields

    def __init__(self, name: str, beam: Beam, s: float, quantity: str = "position") -> None:
        self.name = _check_name(name)
        if not isinstance(beam, Beam):
            raise ModelError(f"probe '{name}': beam must be a Beam (got {beam!r})")
        if quantity not in self.quantities(beam):
            raise ModelError(f"probe '{name}': quantity must be one of "
                             f"{list(self.quantities(beam))} (got {quantity!r})")
        s = float(s)
        if not (np.isfinite(s) and 0.0 <= s <= beam.length * (1 + 1e-12)):
            raise ModelError(f"probe '{name}': s = {s} is outside beam '{beam.name}'; valid range "
                             f"is 0 <= s <= {beam.length:.12g} (reference arc length)")
        self.beam, self.s, self.quantity = beam, s, quantity
        self._element, self._xi = beam.locate(min(s, beam.length))

    def columns(self) -> list[str]:
        if self.quantity in self.QUANTITIES or self.quantity in self.beam.layout.vector_fields:
            return [f"{self.name}_{c}" for c in _XYZ]
        return [self.name]

    def check(self, asm: Any) -> None:
        if not any(b is self.beam for b in asm.model.beams):
            raise ModelError(f"probe '{self.name}': beam '{self.beam.name}' is not part of the model")

    def _interp(self, asm: Any, x: np.ndarray) -> np.ndarray:
        return hermite.centerline_points(x, self._dofs(asm)[1], self.beam.centerline.lengths,
                                       np.array([self._element]), np.array([self._xi]))[0]

    def _dofs(self, asm: Any) -> tuple[Any, np.ndarray, dict[str, np.ndarray]]:
        """(the assembly, the beam's centreline coordinates in it, a place for values of its
        reference) kept for the assembly last asked about: every output asks again."""
        kept: tuple[Any, np.ndarray, dict[str, np.ndarray]] | None = getattr(self, "_kept", None)
        if kept is None or kept[0]() is not asm:
            kept = (weakref.ref(asm), asm.centerline_dofs(self.beam), {})
            self._kept = kept
        return kept

    def __getstate__(self) -> dict[str, Any]:
        state = dict(self.__dict__)
        state.pop("_kept", None)       # a weak reference: not pickled
        return state

    def evaluate(self, asm: Any, state: Any) -> np.ndarray:
        if self.quantity not in self.QUANTITIES:
            e = np.array([self._element])
            etype, rest, options = asm.beam_rest(self.beam, e)
            qe = np.asarray(state.q)[asm.element_dofs(self.beam)[e]]
            field = etype.output_fields(qe, rest, options, np.array([self._xi]))[self.quantity]
            return np.atleast_1d(np.asarray(field, dtype=float)[0, 0])
        if self.quantity == "velocity":
            return self._interp(asm, state.v)
        r = self._interp(asm, state.q)
        if self.quantity == "displacement":
            ref = self._dofs(asm)[2]
            if "q_ref" not in ref:
                ref["q_ref"] = self._interp(asm, asm.q_ref)
            r = r - ref["q_ref"]
        return r


class BodyPositionProbe(Probe):
    """Position of the body reference point (centre of mass)."""

    def __init__(self, name: str, body: RigidBody) -> None:
        self.name = _check_name(name)
        if not isinstance(body, RigidBody):
            raise ModelError(f"probe '{name}': body must be a RigidBody (got {body!r})")
        self.body = body

    def columns(self) -> list[str]:
        return [f"{self.name}_{c}" for c in _XYZ]

    def check(self, asm: Any) -> None:
        if not any(b is self.body for b in asm.model.bodies):
            raise ModelError(f"probe '{self.name}': body '{self.body.name}' is not part of the model")

    def evaluate(self, asm: Any, state: Any) -> np.ndarray:
        return np.asarray(state.q)[asm.body_dofs(self.body)[:3]].copy()


class BodyPointProbe(Probe):
    """Position or displacement of a body-fixed point (body coordinates ``point``)."""

    def __init__(self, name: str, body: RigidBody, point: Any, quantity: str = "position") -> None:
        self.name = _check_name(name)
        if not isinstance(body, RigidBody):
            raise ModelError(f"probe '{name}': body must be a RigidBody (got {body!r})")
        if quantity not in ("position", "displacement"):
            raise ModelError(f"probe '{name}': quantity must be 'position' or 'displacement' "
                             f"(got {quantity!r})")
        self.body = body
        self.point = np.asarray(point, dtype=float).reshape(3)
        self.quantity = quantity

    def columns(self) -> list[str]:
        return [f"{self.name}_{c}" for c in _XYZ]

    def _at(self, asm: Any, q: np.ndarray) -> np.ndarray:
        from ..elements.rigid_body import rotation_matrix

        qb = q[asm.body_dofs(self.body)]
        return qb[:3] + rotation_matrix(qb[3:7]) @ self.point

    def evaluate(self, asm: Any, state: Any) -> np.ndarray:
        x = self._at(asm, state.q)
        return x - self._at(asm, asm.q_ref) if self.quantity == "displacement" else x

    def check(self, asm: Any) -> None:
        if self.body not in asm.model.bodies:
            raise ModelError(f"probe '{self.name}': body '{self.body.name}' is not in the model")


class BodyOrientationProbe(BodyPositionProbe):
    """Euler parameters [w, x, y, z] of the body orientation."""

    def columns(self) -> list[str]:
        return [f"{self.name}_{c}" for c in ("w", "x", "y", "z")]

    def evaluate(self, asm: Any, state: Any) -> np.ndarray:
        return np.asarray(state.q)[asm.body_dofs(self.body)[3:]].copy()


class EnergyProbe(Probe):
    """An energy of ``Assembly.energies``: total, kinetic, strain, gravitational, spring, or
    the stored energy an interaction kind declares on its record (``contact``: clearance
    joints, ``rope``: ropes); 0 in a model without that kind (:meth:`quantities`)."""

    @staticmethod
    def quantities() -> tuple[str, ...]:
        """The energies by name (:data:`flexmbs.assembly.ENERGIES`)."""
        from ..assembly import ENERGIES

        return ENERGIES

    def __init__(self, name: str, quantity: str = "total") -> None:
        self.name = _check_name(name)
        if quantity not in self.quantities():
            raise ModelError(f"probe '{name}': quantity must be one of {list(self.quantities())} "
                             f"(got {quantity!r})")
        self.quantity = quantity

    def columns(self) -> list[str]:
        return [self.name]

    def evaluate(self, asm: Any, state: Any) -> np.ndarray:
        return np.array([asm.energies(state.q, state.v).get(self.quantity, 0.0)])


class SlideCoordinateProbe(Probe):
    """Arc length ``s`` (from the beam's first node) of a sliding joint's contact point."""

    def __init__(self, name: str, joint: Any) -> None:
        self.name = _check_name(name)
        if not hasattr(joint, "slide_coordinate"):
            raise ModelError(f"probe '{name}': joint {joint!r} has no slide coordinate")
        self.joint = joint

    def columns(self) -> list[str]:
        return [self.name]

    def evaluate(self, asm: Any, state: Any) -> np.ndarray:
        return np.array([self.joint.slide_coordinate(state.q)])

    def check(self, asm: Any) -> None:
        if self.joint not in asm.model.interactions:
            raise ModelError(f"probe '{self.name}': joint '{self.joint.name}' is not in the model")


class JointReactionProbe(Probe):
    """Reaction force of a (clearance-free) sliding joint on its body (global components)."""

    def __init__(self, name: str, joint: Any) -> None:
        self.name = _check_name(name)
        if not hasattr(joint, "reaction_force"):
            raise ModelError(f"probe '{name}': joint {joint!r} has no reaction force")
        self.joint = joint

    def columns(self) -> list[str]:
        return [f"{self.name}_{c}" for c in _XYZ]

    def evaluate(self, asm: Any, state: Any) -> np.ndarray:
        return self.joint.reaction_force(asm, state.lam)

    def check(self, asm: Any) -> None:
        if self.joint not in asm.model.interactions:
            raise ModelError(f"probe '{self.name}': joint '{self.joint.name}' is not in the model")


class ReactionProbe(Probe):
    """Force and moment of a constraint or joint on one attached part (global components;
    moment about the body's centre of mass or the beam's first node involved), from the
    multipliers (:mod:`flexmbs.constraints.reactions`). ``part`` defaults to the first part
    (a body before a beam; for a joint between two bodies, the first body in the model)."""

    def __init__(self, name: str, constraint: str, part: str | None = None) -> None:
        self.name = _check_name(name)
        self.constraint = str(constraint)
        self.part = part

    def columns(self) -> list[str]:
        return [f"{self.name}_{k}" for k in ("fx", "fy", "fz", "mx", "my", "mz")]

    def _pick(self, found: list[Any]) -> Any:
        for r in found:
            if self.part is None or r.part == self.part:
                return r
        parts = ", ".join(r.part for r in found) or "none"
        raise ModelError(f"probe '{self.name}': constraint '{self.constraint}' does not act on "
                         f"'{self.part}' (it acts on: {parts})")

    def evaluate(self, asm: Any, state: Any) -> np.ndarray:
        from ..constraints.reactions import reactions

        r = self._pick(reactions(asm, state.q, state.lam, self.constraint, float(state.t)))
        return np.concatenate([r.force, r.moment])

    def check(self, asm: Any) -> None:
        from ..constraints.reactions import reactions

        self._pick(reactions(asm, asm.q_ref, np.zeros(asm.n_mult), self.constraint))


class ContactForceProbe(Probe):
    """Total contact force on the hole body of a clearance joint (global components)."""

    def __init__(self, name: str, joint: Any) -> None:
        self.name = _check_name(name)
        if not hasattr(joint, "contact_force"):
            raise ModelError(f"probe '{name}': joint {joint!r} has no contact force")
        self.joint = joint

    def columns(self) -> list[str]:
        return [f"{self.name}_{c}" for c in _XYZ]

    def evaluate(self, asm: Any, state: Any) -> np.ndarray:
        return self.joint.contact_force(state.q, state.v)

    def check(self, asm: Any) -> None:
        if self.joint not in asm.model.interactions:
            raise ModelError(f"probe '{self.name}': joint '{self.joint.name}' is not in the model")


class RopeProbe(Probe):
    """A rope's length [m] and tension [N] (0 when slack), columns ``<name>_length`` and
    ``<name>_tension`` (:meth:`Rope.state_of <flexmbs.ropes.Rope.state_of>`)."""

    def __init__(self, name: str, rope: Any) -> None:
        from ..ropes import Rope

        self.name = _check_name(name)
        if not isinstance(rope, Rope):
            raise ModelError(f"probe '{name}': expected a rope (flexmbs.Rope), got {rope!r}")
        self.rope = rope

    def columns(self) -> list[str]:
        return [f"{self.name}_length", f"{self.name}_tension"]

    def evaluate(self, asm: Any, state: Any) -> np.ndarray:
        length, _rate, tension = self.rope.state_of(state.q, state.v)
        return np.array([length, tension])

    def check(self, asm: Any) -> None:
        if self.rope not in asm.model.interactions:
            raise ModelError(f"probe '{self.name}': rope '{self.rope.name}' is not in the model")


class TendonTensionProbe(Probe):
    """The tension along a tendon's route: the axial force N = EA(ε − ε0) [N] of its wire (the
    elastic part) in the middle of every free span, columns ``<name>_0`` (the actuator's span,
    start → hole 1) ... ``<name>_<n>`` (last hole → anchor):
    :meth:`TendonParts.axial_forces <flexmbs.tendons.TendonParts.axial_forces>`."""

    def __init__(self, name: str, tendon: Any) -> None:
        self.name = _check_name(name)
        if not hasattr(tendon, "axial_forces"):
            raise ModelError(f"probe '{name}': expected a tendon (what Model.add_tendon returns), "
                             f"got {tendon!r}")
        self.tendon = tendon

    def columns(self) -> list[str]:
        return [f"{self.name}_{k}" for k in range(len(self.tendon.holes) + 1)]

    def evaluate(self, asm: Any, state: Any) -> np.ndarray:
        return np.asarray(self.tendon.axial_forces(asm, state.q), dtype=float)

    def check(self, asm: Any) -> None:
        if not any(b is self.tendon.beam for b in asm.model.beams):
            raise ModelError(f"probe '{self.name}': tendon '{self.tendon.name}' is not part of "
                             "the model")


class TendonDisplacementProbe(TendonTensionProbe):
    """How far a tendon's start has moved back along the route's first direction [m] (positive:
    pulled): :meth:`TendonParts.pulled <flexmbs.tendons.TendonParts.pulled>`."""

    def columns(self) -> list[str]:
        return [self.name]

    def evaluate(self, asm: Any, state: Any) -> np.ndarray:
        return np.array([self.tendon.pulled(asm, state.q)])


def probe_columns(probes: list[Probe] | tuple[Probe, ...]) -> list[str]:
    """All columns of ``probes`` in order; duplicate names are a :class:`ModelError`."""
    cols: list[str] = []
    for p in probes:
        cols.extend(p.columns())
    seen: set[str] = set()
    dup = sorted({c for c in cols if c in seen or seen.add(c)})  # type: ignore[func-returns-value]
    if dup or "t" in cols:
        raise ModelError(f"probe columns must be unique and not 't' (duplicates: {dup or ['t']}); "
                         "give the probes distinct names")
    return cols

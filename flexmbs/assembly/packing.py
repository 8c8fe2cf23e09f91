"""The owners of the terms of the equations, each listed once with the blocks it writes in the
iteration matrix and the packer of its part, and the packed system the driver sums
(:mod:`flexmbs.terms`: every kind packs itself)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from .. import driver
from ..constraints.base import Constraint
from ..constraints.drivers import JointDriver, pack_drivers
from ..constraints.joints import EulerParameterNormalization, joint_pattern, pack_joints, pack_norms
from ..constraints.linear import linear_pattern, pack_linear
from ..elements import rigid_body as rb
from ..elements.group import MAX_GROUPS
from ..elements.layout import BASE_RECORD, ELEMENT_TYPES, ElementType
from ..errors import ModelError
from ..loads import moments_pattern, pack_loads
from ..model import Beam, Model
from ..springs import pack_springs, springs_pattern
from .external_loads import ExternalLoads
from .numbering import GroupSpec, Numbering
from .rows import ConstraintRows

if TYPE_CHECKING:  # pragma: no cover
    from ..constraints.interaction import InteractionKind
    from ..terms import PackContext

Blocks = list[tuple[np.ndarray, np.ndarray]]


@dataclass
class BeamGroup:
    """Beams sharing an element type and its options: one packed part, one kernel call."""

    element_type: ElementType
    options: Any                     # the element's options (CableOptions for the cable)
    beams: list[Beam]
    part: Any                        # the element's packed part (flexmbs.elements.group)

    @property
    def dofs(self) -> np.ndarray:
        return np.asarray(self.part.dofs)

    @property
    def props(self) -> Any:
        return self.part.props

    @property
    def rest(self) -> Any:
        return self.part.rest

    @property
    def mass(self) -> np.ndarray:
        return self.part.mass


class TermOwner(NamedTuple):
    """One owner of terms: the blocks ``(rows, cols)`` it writes in the iteration matrix and
    the packer of its part (called once the pattern of all blocks exists)."""

    field: str                                 # its part's field of driver.SystemPart
    blocks: Blocks
    pack: Callable[[PackContext], Any]
    present: bool = True                       # the model has terms of it (else not compiled)


class PackedSystem(NamedTuple):
    groups: list[BeamGroup]
    system: driver.SystemPart            # every part (Python's view)
    #: what the compiled kernel receives: the kinds the model lacks are None, so that their
    #: code is not compiled for it (driver.OPTIONAL_KINDS)
    kernel_system: driver.SystemPart
    #: what the complete kernel of its element types receives (every kind's part, every
    #: feature: driver.SystemPart.complete), the same arrays
    complete_system: driver.SystemPart
    joint_lists: dict[str, list[Any]]    # the interactions of every compiled kind


def interactions_by_kind(model: Model) -> dict[str, list[Any]]:
    """The model's interactions of every compiled kind (:data:`driver.INTERACTION_KINDS`)."""
    return {k.name: [obj for obj in model.interactions if obj.term_kind == k.name]
            for k in driver.INTERACTION_KINDS}


def term_owners(model: Model, numbering: Numbering, rows: ConstraintRows, loads: ExternalLoads,
                ctx: PackContext) -> list[TermOwner]:
    """Every owner of terms, once, in packing order (the order numbers the time functions:
    the linear rows' first, then the bodies', the loads', the interactions', the drivers')."""
    n = numbering.n_coords
    joints = [nl.constraint for nl in rows.nonlinear if id(nl.constraint) not in rows.interaction_constraints]
    coords = {id(nl.constraint): nl.coords for nl in rows.nonlinear}
    norms = [c for c in joints if isinstance(c, EulerParameterNormalization)]
    tables = [c for c in joints if hasattr(c, "table")]
    drivers = [c for c in joints if isinstance(c, JointDriver)]
    if len(norms) + len(tables) + len(drivers) != len(joints):
        raise ModelError("internal: a constraint that no term kind packs")

    def joint_blocks(kept: Sequence[Constraint]) -> Blocks:
        return [b for c in kept for b in joint_pattern(coords[id(c)], rows.multiplier_rows(c), n, c)]

    def pack_linear_rows(ctx: PackContext) -> Any:
        fn_rows = [row for row, _ in rows.lin_functions]
        fn_idx = [ctx.functions(fn) for _, fn in rows.lin_functions]
        return pack_linear(rows.lin_matrix, rows.lin_rhs0, fn_rows, fn_idx, ctx)

    by_kind = interactions_by_kind(model)
    owners = [
        TermOwner("beams", [(d, d) for spec in numbering.groups for d in spec.dofs],
                  lambda ctx: _pack_groups(numbering.groups, ctx)),
        TermOwner("linear", linear_pattern(rows.lin_matrix, n), pack_linear_rows),
        TermOwner("bodies", rb.bodies_pattern(model.bodies, ctx),
                  lambda ctx: rb.pack_bodies(model.bodies, loads.body_loads, ctx, ctx.functions),
                  bool(model.bodies)),
        TermOwner("loads", moments_pattern(loads.node_moments),
                  lambda ctx: pack_loads(loads.f_const, loads.timed, loads.node_moments,
                                         ctx.functions, ctx)),
        TermOwner("norms", joint_blocks(norms),
                  lambda ctx: pack_norms(norms, ctx), bool(norms)),
        TermOwner("joints", joint_blocks(tables),
                  lambda ctx: pack_joints(tables, ctx), bool(tables)),
    ]
    for kind in driver.INTERACTION_KINDS:
        objs = by_kind[kind.name]
        owners.append(TermOwner(kind.name, [b for obj in objs for b in kind.pattern(obj, ctx)],
                                _packer(kind, objs), bool(objs)))
    owners += [
        TermOwner("springs", springs_pattern(model.springs, ctx),
                  lambda ctx: pack_springs(model.springs, ctx), bool(model.springs)),
        TermOwner("drivers", joint_blocks(drivers),
                  lambda ctx: pack_drivers(drivers, ctx, ctx.functions),
                  bool(drivers)),
    ]
    return owners


def _packer(kind: InteractionKind, objs: list[Any]) -> Callable[[PackContext], Any]:
    """The packer of an interaction kind's part of ``objs``."""
    return lambda ctx: kind.pack(objs, ctx)


def pack_system(owners: list[TermOwner], model: Model, ctx: PackContext) -> PackedSystem:
    """Every owner's part (in the order of ``owners``) in the system the driver sums."""
    parts = {owner.field: owner.pack(ctx) for owner in owners}
    groups: list[BeamGroup] = parts.pop("beams")
    system = driver.SystemPart(
        n=ctx.n_coords, m=ctx.n_total - ctx.n_coords, beams=_element_parts(groups, ctx), **parts,
        error=np.zeros(4, np.int64),
        bases=np.zeros((sum(2 * g.dofs.shape[0] for g in groups
                            if g.element_type.rebase is not None), BASE_RECORD)),
        zero=_zero_list(owners, ctx))
    kernel_system = system.without_absent({owner.field: owner.present for owner in owners})
    return PackedSystem(groups, system, kernel_system, system.complete(), interactions_by_kind(model))


def _zero_list(owners: list[TermOwner], ctx: PackContext) -> np.ndarray:
    """:attr:`SystemPart.zero <flexmbs.driver.SystemPart>`: ``[-1]`` (a Jacobian zeroes every
    stored position), with room for every position when an interaction kind follows its
    members (:meth:`Assembly.follow <flexmbs.assembly.Assembly.follow>` lists the positions a
    following plan reads there)."""
    following = {kind.name for kind in driver.INTERACTION_KINDS if kind.follow is not None}
    room = any(owner.field in following and owner.present for owner in owners)
    zero = np.zeros(1 + (ctx.matrix_pattern()[1].size if room else 0), np.int64)
    zero[0] = -1
    return zero


def _pack_groups(specs: list[GroupSpec], ctx: PackContext) -> list[BeamGroup]:
    out = []
    for spec in specs:
        pos = np.array([ctx.positions(d, d).reshape(-1) for d in spec.dofs], np.int64)
        out.append(BeamGroup(spec.element_type, spec.options, spec.beams,
                             spec.element_type.pack(spec.dofs, spec.props, spec.options, ctx.q_free, pos)))
    return out


def _element_parts(groups: list[BeamGroup], ctx: PackContext) -> tuple[Any, ...]:
    """The groups' parts in registration order of their element types: the default element
    (the first registered, the cable) always has one (empty if the model has none of its
    elements), the others only when used: a cable-only model compiles no rod code (measured:
    its first run 177 s -> 116 s cold), and a model with rods compiles one signature, with or
    without cables."""
    parts = []
    for k, name in enumerate(ELEMENT_TYPES):
        et = ELEMENT_TYPES.get(name)
        mine = [g.part for g in groups if g.element_type is et]
        if not mine and k > 0:
            continue
        if not mine:
            size = et.layout.element_size
            mine = [et.pack(np.zeros((0, size), np.int64), et.section_properties([]),
                            et.default_options, ctx.q_ref, np.zeros((0, size * size), np.int64))]
        parts += mine
    if len(parts) > MAX_GROUPS:
        raise ModelError(f"{len(parts)} groups of beams (element type and options): at most "
                         f"{MAX_GROUPS}; give beams of one element type the same options")
    return tuple(parts)

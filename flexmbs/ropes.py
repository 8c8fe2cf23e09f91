"""Rope length limiters (issue 54, item 8): two points, each a rigid-body point, a beam node or
a fixed point of the ground, that may not separate beyond the rope's length L. Below L the rope
is slack (no force); taut, it pulls the ends together along the line between them with the
force of a contact law (:mod:`flexmbs.contact.laws`) whose penetration is the stretch:

    δ = l − L,    δ̇ = dl/dt = g · q',    f = law_force(law, δ, δ̇, v_a)    (tension, ≥ 0)

with the length l, ``g = dl/dq`` and ``H = d²l/dq²`` of a translational spring-damper (one
statement: :func:`flexmbs.springs.length_of`, :func:`flexmbs.springs.length_hessian`) and
``v_a`` the stretch rate at which the rope last became taut (state, checkpointed; it scales
the χ damping of the Hunt-Crossley and Lankarani-Nikravesh laws as a contact's approach
velocity does). Its generalized force ``f g`` enters ``r_q``; the tangent is exact,
``K = k_t g gᵀ + f H + c_t g (H q')ᵀ``, ``C = c_t g gᵀ`` with ``k_t = ∂f/∂δ``,
``c_t = ∂f/∂δ̇`` of the law (:func:`flexmbs.springs.add_measure_matrix`); its potential is
the law's ``Φ(δ)`` (:func:`~flexmbs.contact.laws.law_energy`), the energy ``"rope"`` of
:meth:`~flexmbs.assembly.Assembly.energies`. A damped :class:`~flexmbs.contact.laws.LinearPenalty`
without onsets ramps its viscous force in over ``DAMPING_ONSET`` of the rope's length (as a
clearance joint does over its clearance: without the ramp the force jumps at the instant the
rope goes taut, and an implicit step there may have no solution).

Why a kind of its own and not a spring-damper: an undamped linear rope *is* a spring-damper
with the force-elongation table ``[[-1, 0], [0, 0], [1, k]]`` about the rest length L (tested
against it), but a spring's damping acts when slack as well and pushes, and its table cannot
carry a stiffening law or the approach velocity, so a rope that snatches taut and dissipates
cannot be built from one.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from ._jit import njit
from .constraints.interaction import EnergyFlow, Interaction, InteractionKind, ModelParts
from .contact.laws import N_LAW, ForceLaw, LinearPenalty, law_dissipates, law_energy, law_force
from .errors import ModelError
from .model import GROUND, Node, RigidBody
from .springs import (
    END,
    add_measure_matrix,
    ends_pattern,
    length_hessian,
    length_of,
    pack_ends,
    reference_point,
)
from .terms import WITH_DAMPING

if TYPE_CHECKING:  # pragma: no cover
    from .terms import DofMap, PackContext

__all__ = ["ROPE", "Rope", "RopePart", "pack_ropes", "rope_pattern", "ropes_jacobian",
           "ropes_post_step", "ropes_residual"]


class Rope(Interaction):
    """A rope of ``length`` L [m] between ``a`` and ``b`` (module docstring): each a
    :class:`~flexmbs.model.RigidBody` (``point_a``/``point_b`` in its frame), a beam
    :class:`~flexmbs.model.Node` or ``GROUND`` (the point global). ``contact``: the force law
    of the taut rope, any law of :data:`~flexmbs.contact.laws.CONTACT_LAWS` with the stretch
    as its penetration (e.g. ``LinearPenalty(stiffness=EA/L, damping=...)``). Added with
    :meth:`Model.add_joint <flexmbs.model.Model.add_joint>`; scenario ``[[joints]] type =
    "rope"``."""

    term_kind = "rope"

    def __init__(self, a: Any, b: Any = GROUND, *, length: float, contact: ForceLaw,
                 point_a: Any = (0.0, 0.0, 0.0), point_b: Any = (0.0, 0.0, 0.0),
                 name: str | None = None) -> None:
        self.name = name or f"rope_{getattr(a, 'name', 'ground')}"
        who = f"rope '{self.name}'"
        ok = isinstance(length, (int, float, np.floating)) and not isinstance(length, bool) \
            and math.isfinite(float(length)) and float(length) > 0.0
        if not ok:
            raise ModelError(f"{who}: length must be a finite number > 0 [m] (got {length!r})")
        if not isinstance(contact, ForceLaw):
            raise ModelError(f"{who}: contact must be a force law such as LinearPenalty(stiffness="
                             f"...) (got {contact!r})")
        for obj, end in ((a, "a"), (b, "b")):
            if not isinstance(obj, (RigidBody, Node)) and obj is not GROUND:
                raise ModelError(f"{who}: {end} must be a RigidBody, a beam Node or GROUND "
                                 f"(got {obj!r})")
        if a is GROUND and b is GROUND:
            raise ModelError(f"{who}: both ends on the ground hold nothing; give a body or a node")
        self.a, self.b = a, b
        self.point_a = np.asarray(point_a, float)
        self.point_b = np.asarray(point_b, float)
        self.length = float(length)
        self.contact = contact
        #: the law's parameters as the kernels read them (a damped linear law without onsets
        #: ramps its damping in over DAMPING_ONSET of the length)
        self.law = (contact.for_clearance(self.length) if isinstance(contact, LinearPenalty)
                    else contact).parameters()
        #: state: the stretch rate when the rope last became taut (0 while slack); a view of
        #: the packed part once packed
        self.approach = np.zeros(1)

    # ------------------------------------------------------------------ set-up
    def validate(self, model: ModelParts) -> None:
        what = f"rope '{self.name}'"
        self.point_a = model.end_point(self.a, self.point_a, "a", what)
        self.point_b = model.end_point(self.b, self.point_b, "b", what)
        if not self.reference_length() > 0.0:
            raise ModelError(f"{what}: its ends coincide in the reference configuration; the "
                             "direction of its force is undefined")

    def reference_length(self) -> float:
        """The distance of the ends in the reference configuration [m]."""
        return float(np.linalg.norm(reference_point(self.b, self.point_b)
                                    - reference_point(self.a, self.point_a)))

    def energy_flow(self) -> EnergyFlow:
        """An elastic law stores energy; a damped one dissipates."""
        return "dissipates" if law_dissipates(self.contact) else "conserves"

    def bind(self, dofs: DofMap, extra_dofs: np.ndarray) -> None:
        """Keeps a part of this rope alone for its output (:meth:`state_of`)."""
        self._own = pack_ropes([self], _Positions(dofs))

    # ------------------------------------------------------------------ output
    def state_of(self, q: np.ndarray, v: np.ndarray) -> tuple[float, float, float]:
        """``(l, dl/dt, tension f)`` at ``(q, v)`` (dynamics: with its damping), from the
        kernels' statement (:func:`_rope_force`)."""
        part = self._own
        part.approach[0] = self.approach[0]
        length, rate, f, _kt, _ct = _rope_force(part, 0, np.ascontiguousarray(q, float),
                                                np.ascontiguousarray(v, float), 1.0)
        return float(length), float(rate), float(f)

    def tension(self, q: np.ndarray, v: np.ndarray) -> float:
        """The rope's tension [N] (0 when slack)."""
        return self.state_of(q, v)[2]

    def energy(self, q: np.ndarray, v: np.ndarray | None = None) -> float:
        """The potential ``Φ(l − L)`` of the law's elastic part [J] (``v`` unused)."""
        length = length_of(self._own, 0, np.ascontiguousarray(q, float))
        return float(law_energy(self.law, length - self.length))

    def get_state(self) -> dict[str, Any]:
        return {"approach": float(self.approach[0])}

    def set_state(self, state: dict[str, Any]) -> None:
        self.approach[0] = float(state.get("approach", 0.0))

    def __repr__(self) -> str:
        return (f"Rope({self.name!r}, {getattr(self.a, 'name', self.a)!r} - "
                f"{getattr(self.b, 'name', self.b)!r}, length={self.length!r}, "
                f"contact={self.contact!r})")


class _Positions:
    """A DofMap without a matrix pattern: packing a rope for its output needs no positions."""

    def __init__(self, dofs: DofMap) -> None:
        self.dofs = dofs

    def __getattr__(self, name: str) -> Any:
        return getattr(self.dofs, name)

    def positions(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        return np.full(len(rows) * len(cols), -1, np.int64)


# ---------------------------------------------------------------------------------------------
# the term of the assembler (flexmbs.terms)
class RopePart(NamedTuple):
    idx: np.ndarray          # (n, 2*END) coordinates of end a then end b, -1 unused
    kind: np.ndarray         # (n, 2) springs.GROUND_END | NODE_END | BODY_END
    point: np.ndarray        # (n, 2, 3) body-frame point (bodies), global point (ground)
    T: np.ndarray            # (n, 2, 3, 4, 4) point tensors of body ends
    pos: np.ndarray          # (n, (2*END)**2) CSC positions of the block idx x idx, -1 unused
    law: np.ndarray          # (n, N_LAW) ForceLaw.parameters
    length: np.ndarray       # (n,) L
    approach: np.ndarray     # (n,) state: the stretch rate when the rope last became taut
    D: np.ndarray            # work (3, 2*END)
    g: np.ndarray            # work (2*END,)
    H: np.ndarray            # work (2*END, 2*END)
    x: np.ndarray            # work (2, 3)
    hv: np.ndarray           # work (2*END,)


def rope_pattern(rope: Rope, dofs: DofMap) -> list[tuple[np.ndarray, np.ndarray]]:
    return ends_pattern(rope.a, rope.b, dofs)


def pack_ropes(ropes: list[Rope], ctx: PackContext | DofMap) -> RopePart:
    """All ropes; their state (``approach``) becomes a view of the packed array."""
    n = len(ropes)
    w = 2 * END
    idx, kind, point, T, pos = pack_ends([(r.a, r.point_a, r.b, r.point_b) for r in ropes], ctx)
    law = np.zeros((n, N_LAW))
    for i, r in enumerate(ropes):
        law[i] = r.law
    part = RopePart(
        idx=idx,
        kind=kind,
        point=point,
        T=T,
        pos=pos,
        law=law,
        length=np.array([r.length for r in ropes], float),
        approach=np.array([float(r.approach[0]) for r in ropes], float),
        D=np.zeros((3, w)),
        g=np.zeros(w),
        H=np.zeros((w, w)),
        x=np.zeros((2, 3)),
        hv=np.zeros(w))
    if not isinstance(ctx, _Positions):
        for i, r in enumerate(ropes):
            r.approach = part.approach[i:i + 1]
    return part


@njit
def _rope_force(rp, i, q, v, damping):
    """g into rp.g; returns ``(l, dl/dt, f, ∂f/∂δ, ∂f/∂δ̇)`` of rope i (the rate 0 without
    ``damping``: statics)."""
    length = length_of(rp, i, q)
    rate = 0.0
    if damping != 0.0:
        for a in range(rp.g.size):
            if rp.idx[i, a] >= 0:
                rate += rp.g[a] * v[rp.idx[i, a]]
    f, kt, ct = law_force(rp.law[i], length - rp.length[i], rate, rp.approach[i])
    return length, rate, f, kt, ct


@njit(internal=True)
def ropes_residual(rp, q, v, mode, r):
    """``r_q += f g`` for every rope; returns the largest tension (the force scale of the
    convergence test)."""
    if rp is None:   # none in the model: compiled to nothing (driver.OPTIONAL_KINDS)
        return 0.0
    scale = 0.0
    for i in range(rp.idx.shape[0]):
        _length, _rate, f, _kt, _ct = _rope_force(rp, i, q, v, mode[WITH_DAMPING])
        if f == 0.0:
            continue
        for a in range(rp.g.size):
            if rp.idx[i, a] >= 0:
                r[rp.idx[i, a]] += f * rp.g[a]
        scale = max(scale, f)
    return scale


@njit(internal=True)
def ropes_jacobian(rp, q, v, mode, cC, cK, data):
    """``cK K + cC C`` of every taut rope into ``data`` (module docstring); returns the
    largest ``∂f/∂δ``."""
    if rp is None:   # none in the model: compiled to nothing (driver.OPTIONAL_KINDS)
        return 0.0
    kscale = 0.0
    for i in range(rp.idx.shape[0]):
        _length, _rate, f, kt, ct = _rope_force(rp, i, q, v, mode[WITH_DAMPING])
        if f == 0.0 and kt == 0.0 and ct == 0.0:
            continue
        kscale = max(kscale, kt)
        length_hessian(rp, i, q)
        add_measure_matrix(rp, i, f, kt, ct, v, cC, cK, data, rp.hv)
    return kscale


@njit(internal=True)
def ropes_post_step(rp, q, v):
    """After a converged step: a rope that became taut keeps its stretch rate as its approach
    velocity, a slack one forgets it (``v`` empty: statics, no rate)."""
    if rp is None:   # none in the model: compiled to nothing (driver.OPTIONAL_KINDS)
        return
    for i in range(rp.idx.shape[0]):
        length = length_of(rp, i, q)
        if length - rp.length[i] <= 0.0:
            rp.approach[i] = 0.0
        elif rp.approach[i] == 0.0 and v.size > 0:
            rate = 0.0
            for a in range(rp.g.size):
                if rp.idx[i, a] >= 0:
                    rate += rp.g[a] * v[rp.idx[i, a]]
            rp.approach[i] = rate


#: the rope's term kind (:class:`~flexmbs.constraints.interaction.InteractionKind`): no error
#: codes; its stored energy is "rope"; its output the probe ``rope``
ROPE = InteractionKind(name="rope", pattern=rope_pattern, pack=pack_ropes,
                       energy=("rope", Rope.energy))

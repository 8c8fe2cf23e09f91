"""Interactions: joints and contacts that own state, extra coordinates or force terms.

An interaction (a sliding joint, a clearance joint) is attached to the model with
``model.add_joint(...)``, which calls :meth:`Interaction.validate`. The assembler numbers its
extra coordinates (e.g. the arc-length coordinate ``s`` of a sliding joint) after the rigid
bodies and tells it its numbering through :meth:`Interaction.bind` (a :class:`~flexmbs.terms.DofMap`,
never the concrete assembler). Its equations are a term kind of the assembler
(``term_kind``: the module that owns the kind packs all interactions of that kind and states
their residual and Jacobian as compiled kernels, :mod:`flexmbs.terms`). An interaction that has
no compiled form at the moment (:meth:`compiled_form` false) is evaluated through
:meth:`evaluate` and :meth:`post_step` instead.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar, Literal, Protocol

import numpy as np

from ..errors import FlexmbsError, ModelError
from .base import Constraint

if TYPE_CHECKING:  # pragma: no cover
    from ..terms import DofMap, PackContext

#: what an interaction does to the model's energy (:meth:`Interaction.energy_flow`)
EnergyFlow = Literal["conserves", "dissipates", "works"]


@dataclass(frozen=True, kw_only=True)
class Following:
    """How the factorisation's plan follows the members of a kind along their beams (the
    sliding joint's current element, the clearance joint's contacts): the plan holds a
    member's *own* unknowns against its beam only on the elements of a *window* ``[lo, hi)``,
    stored in the part's ``window`` array (n_rows, 2), and the member's Jacobian reports
    ``off_plan`` (member in ``error[1]``, element in ``error[2]``, window row in ``error[3]``)
    instead of writing an entry outside it; the step is then retried on a new plan
    (:meth:`flexmbs.assembly.Assembly.follow`).

    ``own(obj, dofs)``: the member's unknowns whose entries against its beam follow it, one
    array per window row of the member (the slide coordinate and multipliers; the hole body's
    coordinates; a flexible tube's coordinates per element, each with a window of its own);
    ``elements(obj)``: its beam's coordinates per element, (n_elem, k), −1 padded;
    ``current(part, reach)``: every row's window at the state the next step starts from,
    ``reach`` elements either side of the elements it is on, in the members' order."""

    off_plan: int
    own: Callable[[Any, DofMap], list[np.ndarray]]
    elements: Callable[[Any], np.ndarray]
    current: Callable[[Any, int], np.ndarray]


@dataclass(frozen=True, kw_only=True)
class InteractionKind:
    """The record of one compiled interaction kind, declared by the module that owns its
    physics and listed once in :data:`flexmbs.driver.INTERACTION_KINDS` (docs/extending.md):
    the assembler reserves its pattern and packs its part from it, the driver calls its
    kernels (numba needs those calls spelt out), and an error code of the driver listed in
    ``errors`` is turned into the exception of the interaction ``error[1]`` of this kind
    (:meth:`Interaction.error`).

    ``stops``: the codes of ``errors`` after which the converged step stands and the run stops
    (:class:`~flexmbs.errors.SimulationStopped`, e.g. a slide reaching the beam's end) instead
    of the step failing and being cut.

    ``compiled_view(part)``: the part as the compiled kernel receives it, with ``None`` for the
    kind's features no interaction of the model uses (their code is then not compiled for it:
    :meth:`~flexmbs.driver.SystemPart.without_absent`; the same arrays otherwise).

    ``begin(part, q)``: ``q`` is where the next step starts (a kind whose forces depend on the
    step's start: the clearance joint's sticking friction); ``energy``: the name of a stored
    energy of the kind's interactions in :meth:`~flexmbs.assembly.Assembly.energies` and the
    function ``energy(obj, q, v)`` giving one interaction's share.

    ``observe(part, objs, q, v, residual)``: an output's state (:meth:`~flexmbs.assembly.
    Assembly.observe`): the kind hands the by-products of the kernel's last residual, which
    was at ``(q, v)``, to its interactions for their output records (the clearance joints'
    contact points); ``residual()``, when given, evaluates that residual first (the state is
    not one a converged step just left), leaving the steps' state as it was.

    ``follow``: a kind whose members' entries the factorisation's plan may hold only near
    where they are on their beams (:class:`Following`).

    Output hooks, each called on one interaction of the kind (the writers ask the record,
    :func:`flexmbs.driver.kind_of`, never the object what it offers): ``contacts(obj, dofs,
    q, v, lam, t)``: its rows of ``contacts.csv`` (and the contact points of the frames);
    ``sections(obj, q, v, t)``: its rows of ``sections.csv``; ``outlines(obj, q, samples)``:
    its bore's section outlines in the frames ((n, samples, 3)); ``hole_record(obj)``: its
    entry of ``summary.json``'s ``hole_sections``. The energy (``energy``, above) is listed
    by the probe ``energy`` and ``Assembly.energies`` from the records.

    ``name``: the interactions' ``term_kind`` and the field of
    :class:`~flexmbs.driver.SystemPart` holding the part; ``pattern(obj, dofs)``: the blocks
    ``(rows, cols)`` one interaction writes; ``pack(objs, ctx)``: the part of all of them
    (:class:`~flexmbs.terms.PackContext`); ``enable(part, i, on)``: switches the compiled
    evaluation of interaction i (for kinds whose members can fall back to their Python path,
    :meth:`Interaction.compiled_form`)."""

    name: str
    pattern: Callable[[Any, DofMap], list[tuple[np.ndarray, np.ndarray]]]
    pack: Callable[[list[Any], PackContext], Any]
    errors: tuple[int, ...] = ()
    stops: tuple[int, ...] = ()
    enable: Callable[[Any, int, bool], None] | None = None
    begin: Callable[[Any, np.ndarray], None] | None = None
    compiled_view: Callable[[Any], Any] | None = None
    energy: tuple[str, Callable[[Any, np.ndarray, np.ndarray], float]] | None = None
    observe: Callable[[Any, list[Any], np.ndarray, np.ndarray, Callable[[], None] | None],
                      None] | None = None
    follow: Following | None = None
    contacts: Callable[..., list[dict[str, Any]]] | None = None
    sections: Callable[..., list[dict[str, Any]]] | None = None
    outlines: Callable[..., np.ndarray] | None = None
    hole_record: Callable[[Any], dict[str, Any]] | None = None


class ModelParts(Protocol):
    """What an interaction checks itself against when added to a model."""

    beams: list[Any]
    bodies: list[Any]

    def end_point(self, obj: Any, point: Any, end: str, what: str) -> np.ndarray:
        """The checked point of one end of a two-point element (:meth:`flexmbs.model.Model.end_point`)."""


class MatrixSink(Protocol):
    """Where a Python-path interaction adds its derivatives."""

    def add_to_matrix(self, rows: np.ndarray, cols: np.ndarray, block: np.ndarray) -> None:
        """Add a dense block to the iteration matrix being assembled (rows/cols global)."""


class Interaction:
    """Base class: every hook has a do-nothing default."""

    name: str = "interaction"
    #: the assembler term kind that evaluates it ("sliding", "clearance")
    term_kind: ClassVar[str] = ""

    def validate(self, model: ModelParts) -> None:
        """Check the definition against the model (called by ``model.add_joint``)."""

    def extra_labels(self) -> list[str]:
        """Names of extra coordinates (one per entry) appended to q by the assembly."""
        return []

    def bind(self, dofs: DofMap, extra_dofs: np.ndarray) -> None:
        """Learn the global indices (called once the DOF map exists)."""

    def initial_extra(self, q0: np.ndarray) -> np.ndarray:
        """Initial values of the extra coordinates given the initial coordinates."""
        return np.zeros(len(self.extra_labels()))

    def constraints(self) -> list[Constraint]:
        return []

    def energy_flow(self) -> EnergyFlow | None:
        """How the interaction changes the model's energy, for the run's energy check
        (:mod:`flexmbs.checks`): ``"conserves"`` (it stores energy or does no work),
        ``"dissipates"`` (friction, damping: it only takes energy out), ``"works"`` (it may
        put energy in, e.g. an actuator), ``None`` (not declared: the energy is not checked)."""
        return None

    def compiled_form(self) -> bool:
        """Whether the kernels of its term kind evaluate it now (else :meth:`evaluate`)."""
        return True

    def evaluate(self, sink: MatrixSink, q: np.ndarray, v: np.ndarray, lam: np.ndarray, t: float,
                 r_q: np.ndarray, matrix: tuple[float, float, float] | None) -> float:
        """Python path: add force terms to ``r_q`` (residual convention: minus external forces)
        and, with ``matrix = (cM, cC, cK)``, their derivatives through ``sink.add_to_matrix``.
        Returns the largest force entering the residual (for the convergence test)."""
        raise ModelError(f"interaction '{self.name}' has no Python evaluation")

    def post_step(self, q: np.ndarray, v: np.ndarray, t: float) -> None:
        """Python path: update internal state after a converged step."""

    def error(self, code: int, detail: int, q: np.ndarray, t: float) -> FlexmbsError:
        """The exception for an error code its kernels reported."""
        return FlexmbsError(f"joint '{self.name}': error {code} ({detail})")

    def get_state(self) -> dict[str, Any]:
        """Internal state for checkpoints (JSON-compatible)."""
        return {}

    def set_state(self, state: dict[str, Any]) -> None:
        """Restore :meth:`get_state`."""

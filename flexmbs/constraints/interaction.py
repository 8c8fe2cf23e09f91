"""Interactions: joints and contacts that own state, extra coordinates or force terms.

An interaction (a sliding joint, a clearance joint) is attached to the model with
``model.add_joint(...)``. The assembly numbers its extra coordinates (e.g. the arc-length
coordinate ``s`` of a sliding joint) after the rigid bodies, asks it for constraints and force
terms every Newton iteration, and calls :meth:`Interaction.post_step` after each converged step,
where detection state (element indices, warm starts, active sets) is updated.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from .base import Constraint

if TYPE_CHECKING:  # pragma: no cover
    from ..assembly import Assembly
    from ..model import Model


class Interaction:
    """Base class: every hook has a do-nothing default."""

    name: str = "interaction"

    def validate(self, model: Model) -> None:
        """Check the definition against the model (called by ``model.add_joint``)."""

    def extra_labels(self) -> list[str]:
        """Names of extra coordinates (one per entry) appended to q by the assembly."""
        return []

    def bind(self, asm: Assembly, extra_dofs: np.ndarray) -> None:
        """Learn the global indices (called once the DOF map exists)."""

    def initial_extra(self, q0: np.ndarray) -> np.ndarray:
        """Initial values of the extra coordinates given the initial coordinates."""
        return np.zeros(len(self.extra_labels()))

    def constraints(self) -> list[Constraint]:
        return []

    def pattern_blocks(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """(rows, cols) index sets whose couplings (both ways) the sparse pattern must reserve;
        the multipliers of :meth:`constraints` are coupled with every ``cols`` set."""
        return []

    def evaluate(self, asm: Assembly, q: np.ndarray, v: np.ndarray, lam: np.ndarray, t: float,
                 r_q: np.ndarray, matrix: tuple[float, float, float] | None) -> float:
        """Add force terms to ``r_q`` (residual convention: minus external forces) and, with
        ``matrix = (cM, cC, cK)``, their derivatives through ``asm.add_to_matrix``. Returns
        the largest force entering the residual (for the convergence test)."""
        return 0.0

    def post_step(self, asm: Assembly, q: np.ndarray, v: np.ndarray, t: float) -> None:
        """Update internal state after a converged step."""

    def get_state(self) -> dict[str, Any]:
        """Internal state for checkpoints (JSON-compatible)."""
        return {}

    def set_state(self, state: dict[str, Any]) -> None:
        """Restore :meth:`get_state`."""

    def output(self, asm: Assembly, q: np.ndarray, v: np.ndarray, lam: np.ndarray,
               t: float) -> list[dict[str, Any]]:
        """Contact points (dicts of the contacts.csv columns) for output."""
        return []

"""Algebraic constraints Φ(q, t) = 0: attachments and the constraint protocol.

A constraint owns a few scalar equations and the global indices of the coordinates it reads
(:meth:`Constraint.coordinates`). The assembler gathers ``q_local = q[c.coordinates()]``, calls
:meth:`Constraint.evaluate` (value and Jacobian) and :meth:`Constraint.hessian_lambda`
(``Σ_i λ_i ∂²Φ_i/∂q²``, the constraint part of the Newton matrix for ``Φ_qᵀλ``) and scatters.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import ClassVar, Literal

import numpy as np

from ..errors import ModelError

__all__ = ["Attachment", "Constraint", "AttachmentKind"]

AttachmentKind = Literal["ground", "rigid_body", "beam_node"]

_N_DOFS: dict[str, int] = {"ground": 0, "rigid_body": 7, "beam_node": 6}


def _readonly(a: np.ndarray) -> np.ndarray:
    a = np.array(a, copy=True)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class Attachment:
    """Where a constraint attaches: ground, a rigid body or a beam node.

    - ``dofs``: global coordinate indices, 7 for a rigid body (``[r, p]``), 6 for a beam node
      (``[r, r′]``) or 7 with a twist (``[r, r′, φ]``, ``twist`` True: declared by the
      element's layout), none for ground.
    - ``point``: body-frame point (rigid body) or global point (ground); unused for a beam node
      (its point is the node position).
    - ``frame``: joint frame, columns = axes, in body coordinates (rigid body) or global
      coordinates (ground); identity by default; unused for a beam node.
    """

    kind: AttachmentKind
    dofs: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    point: np.ndarray = field(default_factory=lambda: np.zeros(3))
    frame: np.ndarray = field(default_factory=lambda: np.eye(3))
    twist: bool = False     #: a beam node with a twist coordinate (the rod's φ, last of dofs)

    def __post_init__(self) -> None:
        if self.kind not in _N_DOFS:
            raise ModelError(f"Attachment kind must be one of {sorted(_N_DOFS)} "
                             f"(got {self.kind!r})")
        dofs = np.asarray(self.dofs, dtype=np.int64).reshape(-1)
        if self.twist and self.kind != "beam_node":
            raise ModelError(f"Attachment '{self.kind}' has no twist (only a beam node)")
        needed = _N_DOFS[self.kind] + int(self.twist)
        if dofs.size != needed:
            raise ModelError(f"Attachment '{self.kind}' needs {needed} dofs "
                             f"{'with its twist ' if self.twist else ''}(got {dofs.size})")
        point = np.asarray(self.point, dtype=float)
        frame = np.asarray(self.frame, dtype=float)
        if point.shape != (3,) or not np.all(np.isfinite(point)):
            raise ModelError(f"Attachment point must be 3 finite numbers (got {self.point!r})")
        if frame.shape != (3, 3) or not np.allclose(frame.T @ frame, np.eye(3), atol=1e-9) \
                or np.linalg.det(frame) < 0.0:
            raise ModelError("Attachment frame must be a 3x3 rotation matrix (orthonormal "
                             "columns, right-handed)")
        object.__setattr__(self, "dofs", _readonly(dofs))
        object.__setattr__(self, "point", _readonly(point))
        object.__setattr__(self, "frame", _readonly(frame))

    @classmethod
    def ground(cls, point: np.ndarray | tuple[float, float, float] = (0.0, 0.0, 0.0),
               frame: np.ndarray | None = None) -> Attachment:
        """Fixed global point and frame."""
        return cls("ground", np.zeros(0, dtype=np.int64), np.asarray(point, dtype=float),
                   np.eye(3) if frame is None else np.asarray(frame, dtype=float))

    @classmethod
    def rigid_body(cls, dofs: np.ndarray, point: np.ndarray | tuple[float, float, float],
                   frame: np.ndarray | None = None) -> Attachment:
        """Body point and joint frame in body coordinates; ``dofs`` = global indices of [r, p]."""
        return cls("rigid_body", np.asarray(dofs), np.asarray(point, dtype=float),
                   np.eye(3) if frame is None else np.asarray(frame, dtype=float))

    @classmethod
    def beam_node(cls, dofs: np.ndarray, *, twist: bool = False) -> Attachment:
        """Beam node; ``dofs`` = global indices of [r (3), r′ (3)], or with ``twist`` [r, r′, φ]
        (7) for a node with a twist angle (an element layout with ``twist``, the rod)."""
        return cls("beam_node", np.asarray(dofs), twist=twist)

    @property
    def is_ground(self) -> bool:
        return self.kind == "ground"


class Constraint(ABC):
    """A group of ``n_equations`` scalar equations Φ(q_local, t) = 0 of one named object.

    Subclasses set ``name``, ``n_equations`` and ``equation_labels`` in ``__init__``.
    All derivatives are exact; ``hessian_lambda`` is symmetric.
    """

    name: str
    n_equations: int
    equation_labels: list[str]
    rheonomic: ClassVar[bool] = False

    @abstractmethod
    def coordinates(self) -> np.ndarray:
        """Global indices of the coordinates Φ depends on (defines the order of ``q_local``)."""

    @abstractmethod
    def evaluate(self, q_local: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
        """``(Φ (m,), Φ_q (m, n_local))`` at ``q_local = q[self.coordinates()]``."""

    @abstractmethod
    def hessian_lambda(self, q_local: np.ndarray, lam: np.ndarray, t: float) -> np.ndarray:
        """``Σ_i λ_i ∂²Φ_i/∂q²`` (n_local, n_local), exact and symmetric."""

    def time_derivatives(self, q_local: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
        """``(Φ_t, Φ_tt)``, each (m,); zero for scleronomic constraints."""
        return np.zeros(self.n_equations), np.zeros(self.n_equations)

    def equation_name(self, i: int) -> str:
        """``"<name>.<label>"`` of equation i, for error messages."""
        return f"{self.name}.{self.equation_labels[i]}"

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.name!r}, equations={self.equation_labels})"

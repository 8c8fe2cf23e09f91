"""Reaction forces of constraints and joints from their multipliers (issue "multibody basics").

The equations of motion read ``M q'' + Phi_q^T lam = Q`` (FORMULATION Part I §5), so the
generalized force a constraint exerts on the coordinates is ``Q_c = -Phi_c,q^T lam_c`` (its own
rows only). On each part it acts on:

- a rigid body (position r, Euler parameters p): force ``F = Q_c[r]`` at the centre of mass and
  moment ``M = P(p)^T Q_c[p]`` about it, where ``p' = P(p) omega`` (global angular velocity), so
  that ``Q_p . dp = M . dtheta`` (virtual work);
- a beam: on each node, force ``Q_c[r_i]`` and, from the slope coordinates, the moment
  ``r'_i x Q_c[r'_i]`` (a virtual rotation turns the slope by ``dtheta x r'``); the part's
  reaction is their resultant, the moment taken about the first node involved.

Coordinates that are not positions or rotations (the slide coordinate of a sliding joint) carry
no physical force and are left out.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..elements.rigid_body import pdot_from_omega_global
from ..errors import ModelError

if TYPE_CHECKING:  # pragma: no cover
    from ..assembly import Assembly

__all__ = ["Reaction", "constraint_names", "reactions"]


@dataclass(frozen=True)
class Reaction:
    """Force and moment of a constraint on one part, global components; the moment is about
    ``point`` (the body's centre of mass, or the beam's first node involved)."""

    part: str
    force: np.ndarray
    moment: np.ndarray
    point: np.ndarray


def constraint_names(asm: Assembly) -> list[str]:
    """Names of the constraints and joints that have multipliers (in model order)."""
    seen: list[str] = []
    for name in asm.multiplier_owner:
        if name not in seen and not name.endswith(".normalization"):
            seen.append(name)
    return seen


def _rotation_map(p: np.ndarray) -> np.ndarray:
    """P(p) with p' = P(p) omega (global omega): columns are p' for unit omega."""
    return np.column_stack([pdot_from_omega_global(p, e) for e in np.eye(3)])


def reactions(asm: Assembly, q: np.ndarray, lam: np.ndarray, name: str,
              t: float = 0.0) -> list[Reaction]:
    """Reactions of the constraint or joint ``name`` on every part it acts on, at (q, lam)."""
    rows = np.flatnonzero(np.array([o == name for o in asm.multiplier_owner], dtype=bool))
    if rows.size == 0:
        known = ", ".join(constraint_names(asm)) or "none"
        raise ModelError(f"no constraint or joint named '{name}' with multipliers (known: {known})")
    G = asm.constraint_jacobian(q, t)[rows]
    Q = -(G.T @ lam[rows])
    touched = set(np.unique(G.indices).tolist())
    out: list[Reaction] = []
    for body in asm.model.bodies:
        d = asm.body_dofs(body)
        if not touched.intersection(d.tolist()):
            continue
        p = q[d[3:7]]
        out.append(Reaction(body.name, Q[d[:3]].copy(), _rotation_map(p).T @ Q[d[3:7]],
                            q[d[:3]].copy()))
    for beam in asm.model.beams:
        lay = beam.layout
        F = np.zeros(3)
        M = np.zeros(3)
        ref: np.ndarray | None = None
        for i in range(beam.n_nodes):
            node = beam.node(i)
            d = asm.node_dofs(node)
            if not touched.intersection(d.tolist()):
                continue
            pos = d[list(lay.position)]
            x = q[pos]
            if ref is None:
                ref = x.copy()
            f = Q[pos]
            s = d[list(lay.slope)]
            m = np.cross(q[s], Q[s])
            F += f
            M += m + np.cross(x - ref, f)
        if ref is not None:
            out.append(Reaction(beam.name, F, M, ref))
    return out

"""Reaction forces of constraints and joints from their multipliers (issue "multibody basics").

The equations of motion read ``M q'' + Phi_q^T lam = Q`` (docs/theory.md §I.5), so the
generalized force a constraint exerts on the coordinates is ``Q_c = -Phi_c,q^T lam_c`` (its own
rows only). On each part it acts on:

- a rigid body (position r, Euler parameters p): force ``F = Q_c[r]`` at the centre of mass and
  moment ``M = P(p)^T Q_c[p]`` about it, where ``p' = P(p) omega`` (global angular velocity), so
  that ``Q_p . dp = M . dtheta`` (virtual work);
- a beam: on each node, force ``Q_c[r_i]`` and the moment M whose generalized force on the
  node's slope (and twist, on a rod) is ``Q_c`` there: the inverse of the node's rotation map
  that :func:`flexmbs.loads.node_moment` states (``M = r'_i x Q_c[r'_i]`` on a cable; on a rod
  also the twist's ``Q_c[φ_i]`` about the tangent, with the chart's share); the part's reaction
  is their resultant, the moment taken about the first node involved.

Coordinates that are not positions or rotations (the slide coordinate of a sliding joint) carry
no physical force and are left out.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..elements.rigid_body import pdot_from_omega_global
from ..errors import ModelError
from ..loads import node_moment

if TYPE_CHECKING:  # pragma: no cover
    from ..assembly import Assembly

__all__ = ["Reaction", "constraint_names", "node_reaction_moment", "reactions"]


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


def node_reaction_moment(g: np.ndarray, Q_g: np.ndarray, Q_twist: float,
                         base: np.ndarray | None) -> np.ndarray:
    """The moment M on a beam node (slope g; ``base`` t̄ of a rod node's chart, None on a
    cable) whose generalized force is ``(Q_g, Q_twist)``: the least-squares inverse of
    ``Q = Gᵀ M`` with the columns of Gᵀ from :func:`flexmbs.loads.node_moment` (the one
    statement of the node's virtual rotation). A slope force along g (a stretch, no rotation)
    is left out; a cable's moment about its tangent is zero (no twist coordinate)."""
    twist = base is not None
    G = np.empty((4, 3))
    Q = np.empty(4)
    dQ = np.empty((4, 3))
    g = np.ascontiguousarray(g, dtype=float)
    b = np.ascontiguousarray(base if twist else np.zeros(3), dtype=float)
    for j, e in enumerate(np.eye(3)):
        node_moment(g, e, b, twist, Q, dQ)
        G[:, j] = Q
    rhs = np.append(np.asarray(Q_g, float), float(Q_twist) if twist else 0.0)
    return np.linalg.lstsq(G, rhs, rcond=1e-12)[0]


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
    bases = {int(r[0]): r[1:4] for r in asm.node_bases()}    # a rod node's chart by twist dof
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
            tw = None if lay.twist is None else int(d[lay.twist])
            m = node_reaction_moment(q[s], Q[s], 0.0 if tw is None else Q[tw],
                                     None if tw is None else bases[tw])
            F += f
            M += m + np.cross(x - ref, f)
        if ref is not None:
            out.append(Reaction(beam.name, F, M, ref))
    return out

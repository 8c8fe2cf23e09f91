"""Linearised eigenmodes about a (static) configuration, constraints by null-space projection."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from ..assembly import Assembly
from ..errors import ModelError


@dataclass
class Modes:
    omega: np.ndarray         # angular frequencies [rad/s], ascending (rigid modes ~ 0)
    shapes: np.ndarray        # (n_coords, n_modes) mass-normalised mode shapes

    @property
    def frequencies(self) -> np.ndarray:
        """Natural frequencies in Hz."""
        return self.omega / (2 * np.pi)


def eigenmodes(asm: Assembly, q: np.ndarray | None = None, lam: np.ndarray | None = None, *,
               n_modes: int | None = None, t: float = 0.0, max_dense: int = 6000) -> Modes:
    """Undamped modes of (K, M) linearised at ``q`` with multipliers ``lam`` (geometric stiffness
    of constraint reactions included), restricted to the null space of Phi_q; with ``n_modes``
    only the lowest ``n_modes`` are computed. ``scipy.linalg.eigh`` returns them in ascending
    order."""
    n = asm.n_coords
    if n > max_dense:
        raise ModelError(f"eigenmodes uses dense linear algebra; the model has {n} coordinates "
                         f"(> max_dense={max_dense})")
    q = asm.q_ref.copy() if q is None else np.asarray(q, float)
    lam = np.zeros(asm.n_mult) if lam is None else np.asarray(lam, float)
    r_q = np.zeros(n)
    r_lam = np.zeros(asm.n_mult)
    asm.evaluate(q, np.zeros(n), None, lam, t, r_q, r_lam, matrix=(0.0, 0.0, 1.0),
                 with_damping=False)
    K = asm.matrix[:n, :n].toarray()
    K = 0.5 * (K + K.T)
    M = asm.mass_matrix(q).toarray()
    if asm.n_mult:
        J = asm.constraint_jacobian(q, t).toarray()
        N = scipy.linalg.null_space(J)
    else:
        N = np.eye(n)
    Kr = N.T @ K @ N
    Mr = N.T @ M @ N
    m = Kr.shape[0]
    if n_modes is not None and 0 < n_modes < m:
        # only the lowest n_modes pairs (LAPACK's expert driver: bisection and inverse
        # iteration for the pairs asked for, not the whole spectrum)
        w2, V = scipy.linalg.eigh(Kr, Mr, subset_by_index=[0, n_modes - 1])
    else:
        w2, V = scipy.linalg.eigh(Kr, Mr)
        if n_modes is not None:
            w2, V = w2[:n_modes], V[:, :n_modes]
    omega = np.sqrt(np.clip(w2, 0.0, None))
    return Modes(omega, N @ V)

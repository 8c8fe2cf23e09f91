"""Compiled gather/scatter loops of the assembler (allocation-free, one call per element group)."""

from __future__ import annotations

import numpy as np

from ._jit import njit


@njit
def gather(x: np.ndarray, dofs: np.ndarray, out: np.ndarray) -> None:
    """out[e, k] = x[dofs[e, k]]."""
    ne, nk = dofs.shape
    for e in range(ne):
        for k in range(nk):
            out[e, k] = x[dofs[e, k]]


@njit
def scatter_add(out: np.ndarray, dofs: np.ndarray, vals: np.ndarray, sign: float) -> float:
    """out[dofs[e, k]] += sign * vals[e, k]; returns max |vals| (a force scale)."""
    ne, nk = dofs.shape
    m = 0.0
    for e in range(ne):
        for k in range(nk):
            v = vals[e, k]
            out[dofs[e, k]] += sign * v
            if abs(v) > m:
                m = abs(v)
    return m


@njit
def scatter_mass_times(out: np.ndarray, dofs: np.ndarray, mass: np.ndarray,
                       acc: np.ndarray) -> float:
    """out[dofs[e]] += mass[e] @ acc[dofs[e]]; returns max |mass[e] @ acc_e|."""
    ne, nk = dofs.shape
    m = 0.0
    for e in range(ne):
        for i in range(nk):
            s = 0.0
            for j in range(nk):
                s += mass[e, i, j] * acc[dofs[e, j]]
            out[dofs[e, i]] += s
            if abs(s) > m:
                m = abs(s)
    return m


@njit
def scatter_matrix(data: np.ndarray, pos: np.ndarray, K: np.ndarray, C: np.ndarray,
                   M: np.ndarray, cK: float, cC: float, cM: float) -> None:
    """data[pos[e, k]] += cK K[e].flat[k] + cC C[e].flat[k] + cM M[e].flat[k]."""
    ne, nk = pos.shape
    for e in range(ne):
        for k in range(nk):
            data[pos[e, k]] += cK * K[e, k] + cC * C[e, k] + cM * M[e, k]


@njit
def scatter_matrix_kc(data: np.ndarray, pos: np.ndarray, K: np.ndarray, C: np.ndarray,
                      cK: float, cC: float) -> None:
    """data[pos[e, k]] += cK K[e].flat[k] + cC C[e].flat[k] (no mass term)."""
    ne, nk = pos.shape
    for e in range(ne):
        for k in range(nk):
            data[pos[e, k]] += cK * K[e, k] + cC * C[e, k]

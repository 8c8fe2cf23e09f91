"""Timing loops shared by the unit-cost benchmarks (``contact.py``, ``eyelet_plan.py``,
``step_units.py``, ``tendon_robot.py``): the iteration matrix, the residual, the factorisation
and solve called ``n`` times inside numba (no Python
dispatch per call), compiled without reference counting like the compiled entry, and the best
of several repeats."""

from __future__ import annotations

import time

import numpy as np

from flexmbs import driver
from flexmbs._jit import njit
from flexmbs.contact.clearance_term import clearance_terms
from flexmbs.linalg.bordered import bordered_factorize, bordered_solve


@njit(refcount=False)
def loop_factorize(factor, data, n):
    for _ in range(n):
        bordered_factorize(factor, data)


@njit(refcount=False)
def loop_solve(factor, b, x, n):
    for _ in range(n):
        bordered_solve(factor, b, x)


@njit(refcount=False)
def loop_matrix(m, q, v, qdd, lam, fv, mode, data, n):
    """The whole iteration matrix (cM, cC, cK = 1, 0.05, 1e-8), ``n`` times."""
    for _ in range(n):
        driver.jacobian(m, q, v, qdd, lam, fv, mode, 1.0, 0.05, 1e-8, data)


@njit(refcount=False)
def loop_residual(m, q, v, qdd, lam, fv, mode, r, n):
    for _ in range(n):
        driver.residual(m, q, v, qdd, lam, fv, mode, r)


@njit(refcount=False)
def loop_clearance(cl, q, v, r, error, n):
    """The clearance joints' residual alone (``clearance_terms``), ``n`` times."""
    for _ in range(n):
        clearance_terms(cl, q, v, False, 0.0, 0.0, r, r, error)


def best_of(fn, args, n: int, repeats: int = 7) -> float:
    """Microseconds per call of ``fn(*args, n)``: the best of ``repeats`` runs after a warm-up."""
    fn(*args, 3)
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn(*args, n)
        best = min(best, (time.perf_counter() - t0) / n * 1e6)
    return best

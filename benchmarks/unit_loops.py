"""Timing loops shared by the unit-cost benchmarks (``contact.py``, ``eyelet_plan.py``): the
bordered banded LU's factorisation and solve called ``n`` times inside numba (no Python
dispatch per call), compiled without reference counting like the compiled entry, and the best
of several repeats."""

from __future__ import annotations

import time

import numpy as np

from flexmbs._jit import njit
from flexmbs.linalg.bordered import bordered_factorize, bordered_solve


@njit(refcount=False)
def loop_factorize(factor, data, n):  # noqa: ANN001, ANN201
    for _ in range(n):
        bordered_factorize(factor, data)


@njit(refcount=False)
def loop_solve(factor, b, x, n):  # noqa: ANN001, ANN201
    for _ in range(n):
        bordered_solve(factor, b, x)


def best_of(fn, args, n: int, repeats: int = 7) -> float:  # noqa: ANN001
    """Microseconds per call of ``fn(*args, n)``: the best of ``repeats`` runs after a warm-up."""
    fn(*args, 3)
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn(*args, n)
        best = min(best, (time.perf_counter() - t0) / n * 1e6)
    return best

"""The iteration matrix's factorisation, one for every solver (issue 37, item 2).

The compiled and the Python Newton loops, the velocity corrector and the initial accelerations
factorise the assembled saddle-point matrix with the bordered banded LU
(:mod:`flexmbs.linalg.bordered`) and the assembly's plan (:meth:`Assembly.factor_plan`:
border and band order chosen by cost, :mod:`flexmbs.linalg.ordering`). The plan's border is
safe for a matrix with mass on every band coordinate; a stiffness-only matrix (statics) is
planned with every coordinate labelled massless, which closes every nonempty border over the
whole matrix, and is factorised that way only when that costs no more than
:data:`STATIC_COST_RATIO` times the dynamic plan (SuperLU otherwise); see
``docs/design-notes.md``, "One factorisation for every solver".
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp

from ..errors import ConvergenceError
from .newton import SINGULAR, Factorization, SuperLUFactor

if TYPE_CHECKING:
    from ..assembly import Assembly

#: a stiffness-only plan is used while its estimated cost is at most this multiple of the
#: dynamic plan's (the same band: a chain, a beam); beyond it SuperLU
STATIC_COST_RATIO = 2.0


class PlannedLU:
    """:class:`~flexmbs.linalg.bordered.BorderedBandedLU` of the assembly's matrix pattern
    with :meth:`Assembly.factor_plan`; :meth:`factorize` raises :class:`ConvergenceError` on a
    zero or non-finite pivot."""

    def __init__(self, asm: Assembly, *, mass: bool = True) -> None:
        plan = asm.factor_plan(mass=mass)
        self.lu = plan.factorization(asm.matrix)

    def factorize(self, A: sp.csc_matrix) -> None:
        """Factor ``A`` (the assembly's pattern)."""
        if not self.lu.factorize(A.data):
            raise ConvergenceError(f"{SINGULAR} (zero pivot {self.lu.info - 1})")

    def solve(self, b: np.ndarray) -> np.ndarray:
        """x = A^-1 b with the last factorisation."""
        return self.lu.solve(b)


def static_factorization(asm: Assembly) -> Factorization:
    """The factorisation of the static (stiffness-only) iteration matrix: the planned LU with
    every coordinate massless when it costs at most :data:`STATIC_COST_RATIO` times the
    dynamic plan or when it is KLU's sparse LU, else SuperLU (a hub coupled to a whole beam
    leaves only a band as wide as the beam or one dense block, both cubic in the size; KLU
    plans it where installed)."""
    plan = asm.factor_plan(mass=False)
    if plan.sparse or plan.cost <= STATIC_COST_RATIO * asm.factor_plan(mass=True).cost:
        return PlannedLU(asm, mass=False)
    return SuperLUFactor()

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
#: a plan that follows the sliding and clearance joints (:meth:`Assembly.factor_plan` with
#: windows) holds each joint's entries on this many elements either side of where it is
FOLLOW_REACH = 1
#: ... and is used when its estimated cost is below this fraction of the plan of the whole
#: reserved pattern (a few joints on long beams keep the fixed plan: no re-planning)
FOLLOW_COST_RATIO = 0.25
#: new plans for one step (static increment) before it counts as failed (each adds the
#: elements where the solve found a joint outside its windows; a sliding joint's needs one)
MAX_REPLANS = 8


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


class FollowingStaticLU:
    """The static (stiffness-only) matrix's planned LU on a plan that follows the joints'
    contacts (windows around where they are, :meth:`Assembly.contact_windows`), as the
    integrator's: used where it costs below :data:`FOLLOW_COST_RATIO` of the whole reserved
    pattern's static plan. A solve whose Jacobian leaves the windows raises
    :class:`~flexmbs.errors.OffPlanError`; :meth:`replan` then adds where it went."""

    def __init__(self, asm: Assembly, windows: np.ndarray) -> None:
        self.asm = asm
        self.windows = np.asarray(windows, np.int64).copy()
        asm.follow(self.windows)
        self.lu = asm.factor_plan(mass=False, windows=self.windows).factorization(asm.matrix)
        self.replans = 0

    def factorize(self, A: sp.csc_matrix) -> None:
        if not self.lu.factorize(A.data):
            raise ConvergenceError(f"{SINGULAR} (zero pivot {self.lu.info - 1})")

    def solve(self, b: np.ndarray) -> np.ndarray:
        return self.lu.solve(b)

    def replan(self, widen: tuple[int, int, int], again: bool) -> None:
        """A joint left its windows (``widen``: the error's code, window row, element): a plan
        around where every joint is now and where the solve found it; ``again``: the last new
        plan failed too (its windows are kept: they only grow)."""
        windows = self.asm.contact_windows(FOLLOW_REACH, widen,
                                           keep=self.windows if again else None)
        assert windows is not None
        self.windows = windows
        self.asm.follow(self.windows)
        plan = self.asm.factor_plan(mass=False, windows=self.windows,
                                    border=self.lu.factor.border, sparse=self.lu.sparse)
        self.lu = plan.factorization(self.asm.matrix)
        self.replans += 1

    def release(self) -> None:
        """The solve is over: every plan holds the joints' whole beams again."""
        self.asm.follow(None)


def static_factorization(asm: Assembly) -> Factorization:
    """The factorisation of the static (stiffness-only) iteration matrix: the planned LU with
    every coordinate massless, following the joints' contacts (:class:`FollowingStaticLU`)
    where that is much cheaper, else on the whole pattern when it costs at most
    :data:`STATIC_COST_RATIO` times the dynamic plan or when it is KLU's sparse LU, else
    SuperLU (a hub coupled to a whole beam leaves only a band as wide as the beam or one dense
    block, both cubic in the size; KLU plans it where installed)."""
    plan = asm.factor_plan(mass=False)
    windows = asm.contact_windows(FOLLOW_REACH)
    if windows is not None and asm.factor_plan(mass=False, windows=windows).cost \
            < FOLLOW_COST_RATIO * plan.cost:
        return FollowingStaticLU(asm, windows)
    if plan.sparse or plan.cost <= STATIC_COST_RATIO * asm.factor_plan(mass=True).cost:
        return PlannedLU(asm, mass=False)
    return SuperLUFactor()

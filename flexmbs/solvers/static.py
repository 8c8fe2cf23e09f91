"""Static equilibrium by full Newton with adaptive load stepping (docs/theory.md §I.6.5)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..assembly import Assembly
from ..errors import ConvergenceError, FlexmbsError, ModelError, OffPlanError
from .factor import MAX_REPLANS, FollowingStaticLU, static_factorization
from .newton import Newton, NewtonOptions


@dataclass(frozen=True, kw_only=True)
class StaticOptions:
    """Load stepping: the external loads are scaled by a factor growing from 0 to 1.

    ``load_steps`` is the initial number of increments; a failed increment is halved (down to
    ``min_increment``), an easy one (``<= easy_iterations`` Newton iterations) grows by 1.5.
    Contacts that close and open within an increment cost a few iterations each, so "easy" is
    8, with 40 iterations at most: one tendon on the 20-disk robot (plain linear penalty)
    takes 11 increments (236 iterations, 1.2 s) where 4 and 30 took 376 (2 875, 11.5 s);
    design notes, "Statics of tendon-routed structures".
    ``stabilizer`` (docs/theory.md §I.6.5, Exudyn's stabilizerODE2term) adds the mass-proportional
    term ``c_s (1 - load^2) M`` to the Newton matrix only: it regularises slack cables and
    contacts that are not yet closed in the first increments, and vanishes at full load, so
    the equilibrium found is unchanged. Newton halves a step whose iterate the model rejects
    (``newton.retreats``, 10 here): the load factor does not scale a penetration the model
    starts with, so halving the increment would not help.
    """

    load_steps: int = 1
    min_increment: float = 1e-4
    stabilizer: float = 0.0       # c_s [1/s^2]: adds c_s (1 - load^2) M to the Newton matrix
    easy_iterations: int = 8
    newton: NewtonOptions = field(default_factory=lambda: NewtonOptions(
        modified=False, line_search=False, max_iterations=40, retreats=10))


@dataclass
class StaticResult:
    q: np.ndarray
    lam: np.ndarray
    load_increments: int
    newton_iterations: int


class _StaticStep:
    def __init__(self, asm: Assembly, q: np.ndarray, lam: np.ndarray, t: float) -> None:
        self.asm = asm
        self.q = q
        self.lam = lam
        self.v = np.zeros_like(q)
        self.t = t
        self.n = asm.n_total
        self.r_q = np.zeros(asm.n_coords)
        self.r_lam = np.zeros(asm.n_mult)
        self.load = 1.0
        self.stabilizer = 0.0

    def evaluate(self, want_matrix: bool):
        cs = self.stabilizer * (1.0 - self.load**2)
        scale = self.asm.evaluate(self.q, self.v, None, self.lam, self.t, self.r_q, self.r_lam,
                                  matrix=(cs, 0.0, 1.0) if want_matrix else None,
                                  load_factor=self.load, with_damping=False)
        return self.r_q, self.r_lam, scale

    def matrix(self):
        return self.asm.matrix

    def scaled_rhs(self, r_q, r_lam, out) -> None:
        n = r_q.size
        np.negative(r_q, out=out[:n])
        np.negative(r_lam, out=out[n:])

    def apply(self, dx, factor: float) -> None:
        n = self.r_q.size
        self.q += factor * dx[:n]
        self.lam += factor * dx[n:]

    def save(self):
        return self.q.copy(), self.lam.copy()

    def restore(self, saved) -> None:
        self.q[:] = saved[0]
        self.lam[:] = saved[1]

    def describe(self, index: int) -> str:
        return self.asm.describe_coordinate(index)

    def stiffness_scale(self) -> float:
        return self.asm.stiffness_scale


def solve_static(asm: Assembly, options: StaticOptions | None = None, *,
                 q0: np.ndarray | None = None, t: float = 0.0) -> StaticResult:
    """Static equilibrium under the loads at time ``t`` (inertia and damping ignored)."""
    o = options or StaticOptions()
    if o.load_steps < 1:
        raise ModelError(f"load_steps must be >= 1 (got {o.load_steps})")
    q = (asm.q_ref if q0 is None else q0).copy()
    lam = np.zeros(asm.n_mult)
    asm.begin(q)
    prob = _StaticStep(asm, q, lam, t)
    prob.stabilizer = o.stabilizer
    factor = static_factorization(asm)
    newton = Newton(o.newton, asm.length_scale, factor)
    try:
        n_inc = _load_steps(asm, prob, newton, factor, o, t)
    finally:
        if isinstance(factor, FollowingStaticLU):
            factor.release()
    return StaticResult(q, lam, n_inc, newton.total.iterations)


def _load_steps(asm: Assembly, prob: _StaticStep, newton: Newton, factor: object,
                o: StaticOptions, t: float) -> int:
    """The load factor from 0 to 1 in adaptive increments; returns their number. An increment
    whose Jacobian left the plan's windows (:class:`~flexmbs.errors.OffPlanError`) is solved
    again on a plan that holds where it went (at most ``MAX_REPLANS`` times), not halved."""
    q, lam = prob.q, prob.lam
    load, inc = 0.0, 1.0 / o.load_steps
    n_inc = replans = 0
    while load < 1.0:
        trial = min(1.0, load + inc)
        saved = prob.save()
        prob.load = trial
        try:
            st = newton.solve(prob, full=True)
        except OffPlanError as exc:
            prob.restore(saved)
            replans += 1
            if replans > MAX_REPLANS or not isinstance(factor, FollowingStaticLU):
                raise ConvergenceError(f"static solve failed at load factor {load:.4g}: "
                                       f"{exc}") from None
            factor.replan(exc.widen, again=replans > 1)
            continue
        except ConvergenceError as exc:
            prob.restore(saved)
            inc *= 0.5
            if inc < o.min_increment:
                raise ConvergenceError(
                    f"static solve failed at load factor {load:.4g} (increment below "
                    f"{o.min_increment:g}): {exc}") from None
            continue
        replans = 0
        try:
            asm.static_increment_done(q, lam, t, trial)   # joints' state, nodal charts (§2.4)
        except FlexmbsError as exc:    # a node turned past the frames' limit: smaller increment
            prob.restore(saved)
            inc *= 0.5
            if inc < o.min_increment:
                raise ConvergenceError(f"static solve failed at load factor {load:.4g}: "
                                       f"{exc}") from None
            continue
        load = trial
        n_inc += 1
        if st.iterations <= o.easy_iterations:
            inc *= 1.5
    return n_inc


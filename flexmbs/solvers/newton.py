"""Newton iteration on the assembled saddle-point system, shared by the static and dynamic solvers.

The solver sees only a *step problem*: an object that evaluates the residual (and on request
refills the iteration matrix) at its current iterate and applies a correction. It never sees
elements. Convergence is measured on the unscaled residual with tolerances scaled to the model's
own force and length scales (see :class:`NewtonOptions`).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol

import numpy as np
import scipy.sparse as sp

from ..contact.clearance_term import HOLD_KEEP, HOLD_OFF, HOLD_READ, HOLD_TRACKED
from ..errors import ConvergenceError, ModelError, OffPlanError
from ..steploop import hold_action, renew_jacobian

if TYPE_CHECKING:
    import scipy.sparse.linalg as spla


@dataclass(frozen=True, kw_only=True)
class NewtonOptions:
    """Newton settings.

    Converged when ``max|r_q| <= relative_tolerance * F`` and ``max|Phi| <= constraint_tolerance
    * L``, where ``F`` is the largest single force entering the residual in that evaluation (element
    forces, inertia, loads: it bounds the rounding floor, so the test works for a steel beam and a
    soft cable alike) and ``L`` the model's length scale (bounding box). The force test also
    passes below the rounding floor ``roundoff_factor * eps * k * L`` (``k`` the largest
    diagonal stiffness entry): there a residual corresponds to a displacement error of about
    ``roundoff_factor * eps * L`` and cannot be reduced further in double precision (a steel
    cable's floor grows from ~1e-8 N at 8 elements to ~1e-5 N at 512).

    Modified Newton refreshes the Jacobian within a solve when the contraction is poor
    (``refresh_ratio``, ``refresh_iterations``), and between solves by the renewal rule: when
    the last solve's iterations exceed the average cost per solve since the last refresh,
    ``(refresh_cost + iterations) / solves`` (``refresh_cost`` = cost of a refresh in
    iterations; ``inf`` disables the rule). The default 5 is the measured ratio of refresh to
    iteration cost of the compiled integrator (3.6-6.2 on the benchmarks).

    ``slope_search``: when an iterate's error grew, move back along the step to where the
    residual's work on the step, ``g(a) = dq . r_q(q + a dq)``, has fallen to half its
    magnitude at the start (:data:`SLOPE_ACCEPT`). For a problem that is the gradient of a
    potential (statics without friction) ``g`` is the potential's slope along the step and
    the search an inexact minimisation along it; it breaks the cycles of plain Newton between
    contact sets (a slack tendon in its holes: design notes, "Statics of tendon-routed
    structures"). The static solver switches it on itself when an increment fails without it.

    Parameters
    ----------
    max_iterations : int, default 25
        Iterations per solve.
    relative_tolerance : float, default 1e-8
        Residual tolerance relative to the largest force F.
    constraint_tolerance : float, default 1e-10
        Constraint tolerance relative to the model's length scale L.
    modified : bool, default True
        Reuse the factorisation while it contracts.
    refresh_ratio : float, default 0.7
        Refresh within a solve when an iteration contracts by less than this.
    refresh_iterations : float, default 10
        ... or when more further iterations are predicted at the current rate.
    refresh_cost : float, default 5
        Cost of a refresh in iterations, for the renewal rule between solves.
    line_search : bool, default False
        Backtracking line search on the residual's norm.
    slope_search : bool, default False
        The slope search above (static solves; exclusive with ``line_search``).
    retreats : int, default 0
        Halvings of a Newton step whose iterate the model rejects before the solve fails.
    divergence_limit : float, default 1e8
        Growth of the residual at which a solve is declared divergent.
    roundoff_factor : float, default 20
        Factor of the rounding floor ``roundoff_factor * eps * k * L`` of the force test.
    hold_contacts : bool, default False
        Each solve (a step, a static increment) holds the clearance joints' active set while
        Newton converges: the contacts tracked from the last step act (an opening one pulls by
        the linear law's extension), no other point does; once the held problem has nearly
        converged, a set at odds with the gaps is replaced by the iterate's contacts and Newton
        continues (:mod:`flexmbs.steploop`, :func:`~flexmbs.steploop.hold_action`). The
        accepted state solves the plain equations to the same tolerance. For contacts of the
        plain linear law that tap (tendons in their holes: 8.6× fewer steps; with the law's
        smooth onset, no gain); not for impacts, where the held step
        can settle on a deep-penetration solution that plain Newton's halving avoids (design
        notes, "A Newton that holds the contacts").
    """

    max_iterations: int = 25
    relative_tolerance: float = 1e-8
    constraint_tolerance: float = 1e-10
    modified: bool = True           # reuse the factorisation while it contracts well
    refresh_ratio: float = 0.7        # refresh when err_new / err_old exceeds this ...
    refresh_iterations: float = 10.0  # ... or more further iterations are predicted
    refresh_cost: float = 5.0         # renewal rule between steps (cost of a refresh, iterations)
    line_search: bool = False
    slope_search: bool = False
    retreats: int = 0                # halvings of a step whose iterate the model rejects
    divergence_limit: float = 1e8   # error growth factor that counts as divergence
    roundoff_factor: float = 20.0
    hold_contacts: bool = False      # hold the clearance contacts within a solve

    def __post_init__(self) -> None:
        # the one check of these values (the scenario reader builds this class)
        n = self.max_iterations
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
            raise ModelError(f"NewtonOptions: max_iterations must be an integer >= 1 (got {n!r})")
        for key in ("relative_tolerance", "constraint_tolerance", "refresh_ratio",
                    "refresh_iterations", "divergence_limit", "roundoff_factor"):
            v = getattr(self, key)
            if not (isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
                    and v > 0):
                raise ModelError(f"NewtonOptions: {key} must be a finite number > 0 (got {v!r})")
        r = self.retreats
        if isinstance(r, bool) or not isinstance(r, (int, np.integer)) or r < 0:
            raise ModelError(f"NewtonOptions: retreats must be an integer >= 0 (got {r!r})")
        if not isinstance(self.hold_contacts, (bool, np.bool_)):
            raise ModelError(f"NewtonOptions: hold_contacts must be true or false "
                             f"(got {self.hold_contacts!r})")
        if self.line_search and self.slope_search:
            raise ModelError("NewtonOptions: line_search and slope_search are exclusive; "
                             "set one of them")
        if not (isinstance(self.refresh_cost, (int, float)) and self.refresh_cost >= 0):
            raise ModelError(f"NewtonOptions: refresh_cost must be >= 0 or inf "
                             f"(got {self.refresh_cost!r})")


class StepProblem(Protocol):
    n: int

    def evaluate(self, want_matrix: bool) -> tuple[np.ndarray, np.ndarray, float]: ...
    def matrix(self) -> sp.csc_matrix: ...
    def scaled_rhs(self, r_q: np.ndarray, r_lam: np.ndarray, out: np.ndarray) -> None: ...
    def apply(self, dx: np.ndarray, factor: float) -> None: ...
    def save(self) -> object: ...
    def restore(self, saved: object) -> None: ...
    def describe(self, index: int) -> str: ...
    def stiffness_scale(self) -> float: ...
    def hold(self, action: int) -> int: ...


#: the slope search stops where ``|g(a)| <= SLOPE_ACCEPT * |g(0)|`` (a strong-Wolfe curvature
#: condition), after at most :data:`SLOPE_EVALUATIONS` residuals
SLOPE_ACCEPT = 0.5
SLOPE_EVALUATIONS = 10

#: the message of a singular iteration matrix (every factorisation)
SINGULAR = ("the iteration matrix is singular: the model has an unconstrained motion (a free "
            "rigid-body mode in statics, a body without mass or inertia) or redundant "
            "constraints")


class Factorization(Protocol):
    """A factorisation of the iteration matrix: :meth:`factorize` raises
    :class:`~flexmbs.errors.ConvergenceError` if the matrix is singular."""

    def factorize(self, A: sp.csc_matrix) -> None: ...
    def solve(self, b: np.ndarray) -> np.ndarray: ...


class SuperLUFactor:
    """SuperLU (COLAMD), for a matrix of any pattern."""

    def __init__(self) -> None:
        self.lu: spla.SuperLU | None = None

    def factorize(self, A: sp.csc_matrix) -> None:
        with warnings.catch_warnings():
            import scipy.sparse.linalg as spla  # here: its import costs 0.2 s of every start-up

            warnings.simplefilter("error", spla.MatrixRankWarning)
            try:
                self.lu = spla.splu(A, permc_spec="COLAMD", options={"SymmetricMode": False})
            except (RuntimeError, spla.MatrixRankWarning) as exc:
                self.lu = None
                raise ConvergenceError(f"{SINGULAR} ({exc})") from None

    def solve(self, b: np.ndarray) -> np.ndarray:
        assert self.lu is not None
        return self.lu.solve(b)


@dataclass
class NewtonStats:
    iterations: int = 0
    factorizations: int = 0
    residual_evaluations: int = 0
    history: list[float] = field(default_factory=list)


def _too_slow(err: float, err_prev: float, o: NewtonOptions) -> bool:
    """Modified Newton contracts too slowly: rate above ``refresh_ratio``, or more than
    ``refresh_iterations`` further iterations predicted at the current rate."""
    rho = err / err_prev
    return rho > o.refresh_ratio or np.log(err) > o.refresh_iterations * -np.log(rho)


class Newton:
    """Newton solver with optional modified-Newton factorisation reuse and line search."""

    def __init__(self, options: NewtonOptions, length_scale: float,
                 factorization: Factorization | None = None) -> None:
        """``factorization``: the iteration matrix's factorisation
        (:class:`flexmbs.solvers.factor.PlannedLU` on every path of the package; default
        SuperLU, for problems without an assembly's pattern)."""
        self.options = options
        self.length_scale = length_scale
        self.factorization = factorization if factorization is not None else SuperLUFactor()
        self.lu: Factorization | None = None
        self.total = NewtonStats()
        self._rhs: np.ndarray | None = None
        self._cycle = [0, 0]         # solves and iterations since the last factorisation
        self._renew = False

    def invalidate(self) -> None:
        """Forget the factorisation (matrix coefficients changed, e.g. a new step size)."""
        self.lu = None

    def _renewal(self, iterations: int) -> None:
        self._cycle[0] += 1
        self._cycle[1] += iterations
        self._renew = bool(renew_jacobian(float(iterations), float(self._cycle[0]),
                                          float(self._cycle[1]), float(self.options.refresh_cost)))

    def error(self, r_q: np.ndarray, r_lam: np.ndarray, scale: float,
              stiffness: float = 0.0) -> tuple[float, int]:
        """Scaled error (converged when <= 1) and the index of the worst equation."""
        o = self.options
        n = r_q.size
        tol = max(o.relative_tolerance * scale,
                  o.roundoff_factor * 2.2e-16 * stiffness * self.length_scale, 1e-300)
        eq = np.abs(r_q).max() / tol if n else 0.0
        ec = (np.abs(r_lam).max() / (o.constraint_tolerance * self.length_scale)
              if r_lam.size else 0.0)
        if eq >= ec:
            return float(eq), int(np.argmax(np.abs(r_q))) if n else 0
        return float(ec), n + int(np.argmax(np.abs(r_lam)))

    def _factorize(self, A: sp.csc_matrix) -> None:
        self.lu = None
        self.factorization.factorize(A)     # ConvergenceError if singular
        self.lu = self.factorization
        self.total.factorizations += 1

    def solve(self, problem: StepProblem, *, full: bool = False) -> NewtonStats:
        """Solve ``problem`` from its current iterate (``full``: a fresh matrix at every
        iteration); with ``hold_contacts`` the problem's clearance contacts are held through
        the solve (:class:`NewtonOptions`) and let go whatever its outcome."""
        if not self.options.hold_contacts:
            return self._solve(problem, full, holding=False)
        problem.hold(HOLD_TRACKED)
        try:
            return self._solve(problem, full, holding=True)
        finally:
            problem.hold(HOLD_OFF)

    def _solve(self, problem: StepProblem, full: bool, *, holding: bool) -> NewtonStats:
        o = self.options
        stats = NewtonStats()
        updates = 0     # of the held set (steploop.hold_action)
        modified = o.modified and not full
        need = self.lu is None or not modified or self._renew
        its_since = 0   # iterations with the current factorisation
        err_prev = np.inf
        if self._rhs is None or self._rhs.size != problem.n:
            self._rhs = np.zeros(problem.n)
        rhs = self._rhs
        retreat: tuple[object, np.ndarray] | None = None
        slope = 0.0
        for it in range(o.max_iterations + 1):
            r_q, r_lam, scale = self._evaluate(problem, need, stats, retreat, o.retreats)
            stats.residual_evaluations += 1
            err, worst = self.error(r_q, r_lam, scale, problem.stiffness_scale())
            if o.slope_search and retreat is not None and err > max(err_prev, 1.0) \
                    and self._slope_search(problem, retreat, slope, r_q, stats):
                r_q, r_lam, scale = problem.evaluate(need)
                stats.residual_evaluations += 1
                err, worst = self.error(r_q, r_lam, scale, problem.stiffness_scale())
            act = hold_action(err, updates, problem.hold(HOLD_READ)) if holding else HOLD_KEEP
            if act != HOLD_KEEP:   # the held problem nearly solved, at odds with the gaps
                updates += 1
                holding = act != HOLD_OFF
                problem.hold(act)
                r_q, r_lam, scale = problem.evaluate(need)
                stats.residual_evaluations += 1
                err, worst = self.error(r_q, r_lam, scale, problem.stiffness_scale())
            stats.history.append(err)
            if not np.isfinite(err):
                raise ConvergenceError(f"Newton produced a non-finite residual at iteration {it} "
                                       f"(worst: {problem.describe(worst)})")
            if err <= 1.0:
                stats.iterations = it
                self._accumulate(stats)
                self._renewal(its_since)
                return stats
            if it == o.max_iterations:
                break
            if it > 0 and err > o.divergence_limit * stats.history[0]:
                break
            if modified and not need and it > 0 and _too_slow(err, err_prev, o):
                # poor contraction with an old matrix: refresh it at the current iterate
                r_q, r_lam, scale = problem.evaluate(True)
                stats.residual_evaluations += 1
                need = True
            if need:
                self._factorize(problem.matrix())
                stats.factorizations += 1
                need = not modified
                self._cycle = [0, 0]
                self._renew = False
                its_since = 0
            problem.scaled_rhs(r_q, r_lam, rhs)
            dx = self.lu.solve(rhs)  # type: ignore[union-attr]
            slope = float(dx[:r_q.size] @ r_q)    # the step's work on the residual, g(0)
            if o.line_search:
                self._line_search(problem, dx, err)
                retreat = None
            else:
                retreat = (problem.save(), dx)
                problem.apply(dx, 1.0)
            its_since += 1
            err_prev = err
        stats.iterations = o.max_iterations
        self._accumulate(stats)
        self.lu = None
        raise ConvergenceError(
            f"Newton did not converge in {stats.iterations} iterations (scaled error "
            f"{stats.history[-1]:.3g}, 1 = tolerance; worst equation: {problem.describe(worst)})")

    @staticmethod
    def _evaluate(problem: StepProblem, need: bool, stats: NewtonStats,
                  retreat: tuple[object, np.ndarray] | None, retreats: int
                  ) -> tuple[np.ndarray, np.ndarray, float]:
        """``problem.evaluate``; an iterate the model rejects (a ConvergenceError of the
        evaluation, e.g. a beam axis pushed through a bore wall by a full step from a start in
        penetration) is retreated towards the last accepted one by halving the step, up to
        ``retreats`` times, before the solve fails (issue "the clearance contact as the exact
        gradient of a potential", item 6)."""
        alpha = 1.0
        while True:
            try:
                return problem.evaluate(need)
            except OffPlanError:     # not the iterate's fault: the caller plans again
                raise
            except ConvergenceError:
                if retreat is None or alpha <= 0.5 ** retreats:
                    raise
            saved, dx = retreat
            problem.restore(saved)
            alpha *= 0.5
            problem.apply(dx, alpha)
            stats.residual_evaluations += 1

    @staticmethod
    def _slope_search(problem: StepProblem, retreat: tuple[object, np.ndarray], g0: float,
                      r_q: np.ndarray, stats: NewtonStats) -> bool:
        """Move the iterate to ``saved + a dx``, ``0 < a < 1``, where ``|g(a)| <= SLOPE_ACCEPT
        |g(0)|`` (``g(a) = dq . r_q`` there; ``r_q`` is the residual at ``a = 1``), by regula
        falsi on the bracket ``g(0) < 0 < g(1)``, each trial kept a tenth of the bracket inside
        it (an iterate the model rejects bisects). False, and the iterate left at ``a = 1``,
        when there is no bracket: the step does not overshoot a minimum along it. See
        :class:`NewtonOptions`."""
        saved, dx = retreat
        dq = dx[:r_q.size]
        g1 = float(dq @ r_q)
        if not g0 < 0.0 < g1:
            return False
        lo, g_lo, hi, g_hi = 0.0, g0, 1.0, g1
        for _ in range(SLOPE_EVALUATIONS):
            if math.isfinite(g_hi):     # the secant's root, kept a tenth inside the bracket
                a = lo - g_lo * (hi - lo) / (g_hi - g_lo)
                a = min(max(a, lo + 0.1 * (hi - lo)), hi - 0.1 * (hi - lo))
            else:
                a = 0.5 * (lo + hi)
            problem.restore(saved)
            problem.apply(dx, a)
            stats.residual_evaluations += 1
            try:
                r, _, _ = problem.evaluate(False)
            except OffPlanError:
                raise
            except ConvergenceError:        # a rejected iterate: the bracket's far end
                hi, g_hi = a, math.inf
                continue
            g = float(dq @ r)
            if abs(g) <= SLOPE_ACCEPT * -g0:
                return True
            if g < 0.0:
                lo, g_lo = a, g
            else:
                hi, g_hi = a, g
        return True

    def _line_search(self, problem: StepProblem, dx: np.ndarray, err0: float) -> None:
        saved = problem.save()
        alpha = 1.0
        for _ in range(8):
            problem.apply(dx, alpha)
            try:
                r_q, r_lam, scale = problem.evaluate(False)
            except OffPlanError:
                raise
            except ConvergenceError:    # a rejected iterate: a shorter step
                problem.restore(saved)
                alpha *= 0.5
                continue
            err, _ = self.error(r_q, r_lam, scale, problem.stiffness_scale())
            if np.isfinite(err) and err < (1 - 1e-4 * alpha) * err0:
                return
            problem.restore(saved)
            alpha *= 0.5
        problem.apply(dx, alpha)

    def _accumulate(self, s: NewtonStats) -> None:
        self.total.iterations += s.iterations
        self.total.residual_evaluations += s.residual_evaluations

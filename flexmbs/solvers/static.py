"""Static equilibrium by full Newton with adaptive load stepping (docs/theory.md §I.6.5)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

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
    starts with, so halving the increment would not help. An increment that plain Newton
    cannot solve is solved again, and the rest of the path, with Newton's slope search
    (``NewtonOptions.slope_search``) before increments are halved: slack tendons among their
    holes make plain Newton cycle between contact sets (design notes, "Statics of
    tendon-routed structures").

    Parameters
    ----------
    load_steps : int, default 1
        Initial number of load increments.
    min_increment : float, default 1e-4
        Smallest load increment.
    stabilizer : float, default 0
        c_s [1/s^2] of the mass-proportional stabiliser.
    easy_iterations : int, default 8
        Newton iterations up to which an increment counts as easy (the next grows by 1.5).
    newton : NewtonOptions, optional
        Newton settings (default: full Newton, 40 iterations, 10 retreats; contacts not held:
        holding them through an increment cost the tendon robot's statics 3.6× the
        iterations and two of its load cases, design notes, "A Newton that holds the
        contacts").
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
    #: the load factor from which Newton's slope search was on (None: plain Newton throughout)
    slope_search_from: float | None = None


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

    def hold(self, action: int) -> int:
        return self.asm.hold_contacts(action)


def solve_static(asm: Assembly, options: StaticOptions | None = None, *,
                 q0: np.ndarray | None = None, t: float = 0.0) -> StaticResult:
    """Static equilibrium under the loads at time ``t`` (inertia and damping ignored)."""
    o = options or StaticOptions()
    q = (asm.q_ref if q0 is None else q0).copy()
    lam = np.zeros(asm.n_mult)
    with _Path(asm, q, lam, o) as path:
        n_inc = path.follow(t, t, 0.0, 1.0, 1.0 / o.load_steps)
    return StaticResult(q, lam, n_inc, path.newton.total.iterations, path.slope_search_from)


@dataclass
class QuasiStaticResult:
    """Equilibria at ``t[k]`` (rows of ``q`` and ``lam``), each continued from the last."""

    t: np.ndarray
    q: np.ndarray
    lam: np.ndarray
    load_increments: int
    newton_iterations: int
    #: the time from which Newton's slope search was on (None: plain Newton throughout)
    slope_search_from: float | None = None


def solve_quasi_static(asm: Assembly, times: Sequence[float] | np.ndarray,
                       options: StaticOptions | None = None,
                       *, q0: np.ndarray | None = None,
                       on_equilibrium: Callable[[float, np.ndarray, np.ndarray], None] | None = None
                       ) -> QuasiStaticResult:
    """A sequence of equilibria at the increasing ``times``: the first by load stepping from
    the reference (as :func:`solve_static`), each next one continued from the last with the
    time as the path parameter (loads, prescribed motions and drivers at the intermediate
    times; sub-steps halved where Newton fails and grown where it is easy). The joints' state
    (friction anchors, contact tracking) is carried from increment to increment, so a loop of
    loads shows the friction's hysteresis. ``on_equilibrium(t, q, lam)`` is called at each
    time (the arrays are the solver's own: copy what you keep)."""
    o = options or StaticOptions()
    ts = np.asarray(times, dtype=float)
    if ts.ndim != 1 or ts.size < 1 or not np.all(np.isfinite(ts)) or np.any(np.diff(ts) <= 0):
        raise ModelError("times: an increasing sequence of finite times (got "
                         f"{np.asarray(times).tolist()!r:.80})")
    q = (asm.q_ref if q0 is None else q0).copy()
    lam = np.zeros(asm.n_mult)
    qs, lams = np.empty((ts.size, q.size)), np.empty((ts.size, lam.size))
    n_inc = 0
    with _Path(asm, q, lam, o) as path:
        for k, tk in enumerate(ts):
            if k == 0:
                n_inc += path.follow(tk, tk, 0.0, 1.0, 1.0 / o.load_steps)
            else:
                n_inc += path.follow(ts[k - 1], tk, 1.0, 1.0, 1.0)
            qs[k], lams[k] = q, lam
            if on_equilibrium is not None:
                on_equilibrium(float(tk), q, lam)
    slope = path.slope_search_from
    return QuasiStaticResult(ts, qs, lams, n_inc, path.newton.total.iterations, slope)


class _Path:
    """Newton along a path of equilibria: each increment moves the time and the load factor
    by a share of a segment (:meth:`follow`), solved from the last equilibrium. The
    factorisation and Newton (with its slope search, once on) serve every segment."""

    def __init__(self, asm: Assembly, q: np.ndarray, lam: np.ndarray, o: StaticOptions) -> None:
        if o.load_steps < 1:
            raise ModelError(f"load_steps must be >= 1 (got {o.load_steps})")
        self.asm, self.o = asm, o
        asm.begin(q)
        self.prob = _StaticStep(asm, q, lam, 0.0)
        self.prob.stabilizer = o.stabilizer
        self.factor = static_factorization(asm)
        self.newton = Newton(o.newton, asm.length_scale, self.factor)
        self.slope_search_from: float | None = 0.0 if o.newton.slope_search else None

    def __enter__(self) -> _Path:
        return self

    def __exit__(self, *exc: object) -> None:
        if isinstance(self.factor, FollowingStaticLU):
            self.factor.release()
        self.asm.relax_towards_stress_free(1.0)

    def follow(self, t0: float, t1: float, load0: float, load1: float, first: float) -> int:
        """From the equilibrium at ``(t0, load0)`` to ``(t1, load1)`` in adaptive increments
        (the first a share ``first`` of the segment); returns their number. A failed increment
        is halved (down to ``min_increment``), an easy one (``<= easy_iterations``) grows by
        1.5. An increment that plain Newton cannot solve is solved again with the slope
        search, which stays on. An increment whose Jacobian left the plan's windows
        (:class:`~flexmbs.errors.OffPlanError`) is solved again on a plan that holds where it
        went (at most ``MAX_REPLANS`` times), not halved."""
        asm, prob, newton, factor, o = self.asm, self.prob, self.newton, self.factor, self.o
        q, lam = prob.q, prob.lam

        def where(s: float) -> str:
            return (f"load factor {load0 + s * (load1 - load0):.4g}" if t1 == t0 else
                    f"t = {t0 + s * (t1 - t0):.6g}")

        s, inc = 0.0, first
        n_inc = replans = 0
        while s < 1.0:
            trial = min(1.0, s + inc)
            saved = prob.save()
            prob.t = t0 + trial * (t1 - t0) if trial < 1.0 else t1
            prob.load = load0 + trial * (load1 - load0)
            # beams that start away from their stress-free shape: the prestress with the loads
            asm.relax_towards_stress_free(prob.load)
            try:
                st = newton.solve(prob, full=True)
            except OffPlanError as exc:
                prob.restore(saved)
                replans += 1
                if replans > MAX_REPLANS or not isinstance(factor, FollowingStaticLU):
                    raise ConvergenceError(f"static solve failed at {where(s)}: {exc}") from None
                factor.replan(exc.widen, again=replans > 1)
                continue
            except ConvergenceError as exc:
                prob.restore(saved)
                if not newton.options.slope_search and not newton.options.line_search:
                    # plain Newton failed: this increment and the rest with the slope search
                    newton.options = replace(newton.options, slope_search=True)
                    self.slope_search_from = (load0 + s * (load1 - load0) if t1 == t0
                                              else t0 + s * (t1 - t0))
                    continue
                inc *= 0.5
                if inc < o.min_increment:
                    raise ConvergenceError(
                        f"static solve failed at {where(s)} (increment below "
                        f"{o.min_increment:g}): {exc}") from None
                continue
            replans = 0
            try:    # joints' state, nodal charts (§2.4)
                asm.static_increment_done(q, lam, prob.t, prob.load)
            except FlexmbsError as exc:    # a node turned past the frames' limit: smaller increment
                prob.restore(saved)
                inc *= 0.5
                if inc < o.min_increment:
                    raise ConvergenceError(f"static solve failed at {where(s)}: {exc}") from None
                continue
            s = trial
            n_inc += 1
            if st.iterations <= o.easy_iterations:
                inc *= 1.5
        return n_inc

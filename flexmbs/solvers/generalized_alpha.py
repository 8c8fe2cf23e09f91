"""Generalized-alpha for the index-3 DAE  M q'' + Q_int + Phi_q^T lam = Q_ext,  Phi = 0.

Arnold & Brüls, Multibody Syst. Dyn. 18 (2007) 185-202, with the scaled iteration matrix of
Bottasso, Bauchau & Cardona (2007): dynamic rows times s = beta h^2, multiplier update divided by
s (docs/theory.md §I.6.1). HHT is the special case alpha_m = 0 (Chung & Hulbert 1993).

``constraint_level="position_velocity"`` adds a velocity corrector after each converged step:
q stays, (v, q'', lam) move along the Newmark direction (v += gamma' u, q'' += beta' u) until
``Phi_q v = 0`` holds with the equations of motion (:class:`_VelocityStep`; the index-2
velocity constraint of Gear-Gupta-Leimkuhler and Arnold, Brüls & Cardona, Numer. Math. 129
(2015) 149-179, in the projected form of ALI3-P, Cuadrado et al. 2004). It removes the
undamped period-2 mode of the multipliers at rho_inf = 1 (docs/design-notes.md).
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from ..assembly import Assembly
from ..budget import check_times
from ..driver import constraint_velocity
from ..errors import ConvergenceError, ModelError
from ..kernel import OP_STEPS, kernel
from ..linalg.sparse_lu import ST_HAVE, sparse_restore
from ..steploop import alpha_coefficients, alpha_correct, alpha_predict, step_error
from .factor import FOLLOW_COST_RATIO, FOLLOW_REACH, MAX_REPLANS, PlannedLU
from .newton import Newton, NewtonOptions

#: values of :attr:`GeneralizedAlpha.constraint_level` (the scenario key of the same name)
CONSTRAINT_LEVELS = ("position", "position_velocity")
#: with step-error control the step doubles only after steps whose error estimates were at most
#: this share of the tolerance (the estimate scales with h³: 8 × 0.1 leaves a margin of 0.8)
GROW_ERROR = 0.1


@dataclass(frozen=True, kw_only=True)
class GeneralizedAlpha:
    """Options of the generalized-alpha (or HHT) integrator.

    ``rho_inf`` is the spectral radius at infinite frequency (1: no numerical damping;
    0.8 default). ``scheme="hht"`` uses alpha_m = 0 and needs rho_inf in [0.5, 1].
    Newton defaults to modified Newton (factorisation reused while it contracts).
    ``predictor``: Newton starts from ``q''_{n+1} = 0`` (``"zero_acceleration"``, Arnold &
    Brüls) or from ``q''_{n+1} = q''_n`` (``"constant_acceleration"``), with q and v consistent
    with it. On Newton failure the step is halved (``adaptive``) down to ``min_step``, then
    grows back. ``compiled``: run the compiled path when the model allows it.
    ``constraint_level``: ``"position"`` holds ``Phi = 0`` at every step (index 3);
    ``"position_velocity"`` also ``Phi_q v = 0`` (velocity corrector, module docstring): with
    joints and ``rho_inf = 1`` the constraint forces then stay bounded and the energy is
    conserved (an extra factorisation per step; equations with ``Phi_t != 0``, prescribed
    motion and drivers, keep their velocity).
    ``step_tolerance`` (> 0, model units: m for positions, 1 for slopes and Euler parameters):
    step-error control: a converged step whose local error estimate
    (:func:`flexmbs.steploop.step_error`) exceeds it is retried with half the step, and the
    step grows back (by 2, up to ``dt``) only after ``grow_after`` steps whose estimates were at
    most :data:`GROW_ERROR` of it, so that the doubled step stays within it; ``dt`` is then
    the largest step. 0: steps are cut only when Newton fails (fixed ``dt`` otherwise).

    Parameters
    ----------
    rho_inf : float, default 0.8
        Spectral radius at infinite frequency, in [0, 1] (hht: [0.5, 1]).
    scheme : {"generalized_alpha", "hht"}, default "generalized_alpha"
        The integrator.
    newton : NewtonOptions, optional
        Newton settings (default: modified Newton).
    adaptive : bool, default True
        Halve the step when Newton fails.
    min_step : float, default 0
        Smallest step of the cut-back [s] (0: ``dt``/1024).
    grow_after : int, default 10
        Steps after a cut before the step doubles back.
    compiled : bool, default True
        Run whole steps compiled when the model allows it.
    predictor : {"constant_acceleration", "zero_acceleration"}, default "constant_acceleration"
        Newton's start in each step.
    constraint_level : {"position", "position_velocity"}, default "position"
        What holds at the end of each step.
    step_tolerance : float, default 0
        Largest local error of a step (0: no step-error control).
    """

    rho_inf: float = 0.8
    scheme: Literal["generalized_alpha", "hht"] = "generalized_alpha"
    newton: NewtonOptions = field(default_factory=NewtonOptions)
    adaptive: bool = True
    min_step: float = 0.0            # 0: dt / 1024
    grow_after: int = 10             # successful steps before the step is doubled back
    compiled: bool = True            # compiled Newton loop when the model allows it
    predictor: Literal["zero_acceleration", "constant_acceleration"] = "constant_acceleration"
    constraint_level: Literal["position", "position_velocity"] = "position"
    step_tolerance: float = 0.0      # 0: no step-error control

    def __post_init__(self) -> None:
        if not (self.step_tolerance >= 0.0 and math.isfinite(self.step_tolerance)):
            raise ModelError(f"step_tolerance must be a finite number >= 0 (got "
                             f"{self.step_tolerance}; 0 = fixed steps)")
        if self.step_tolerance > 0.0 and not self.adaptive:
            raise ModelError("step_tolerance needs adaptive steps (adaptive = true): a step "
                             "refused for its error is retried with half the step")
        if self.constraint_level not in CONSTRAINT_LEVELS:
            raise ModelError(f"unknown constraint_level {self.constraint_level!r} (known: "
                             f"{', '.join(CONSTRAINT_LEVELS)})")
        if self.predictor not in ("zero_acceleration", "constant_acceleration"):
            raise ModelError(f"unknown predictor '{self.predictor}' (known: zero_acceleration, "
                             "constant_acceleration)")
        if not 0.0 <= self.rho_inf <= 1.0:
            raise ModelError(f"rho_inf must be in [0, 1] (got {self.rho_inf})")
        if self.newton.slope_search:
            raise ModelError("newton.slope_search applies to static solves (integrator = "
                             "\"static\"), which switch it on themselves where plain Newton "
                             "fails; remove it from the time integrator's options")
        if self.scheme == "hht" and self.rho_inf < 0.5:
            raise ModelError(f"HHT needs rho_inf in [0.5, 1] (got {self.rho_inf})")
        if self.scheme not in ("generalized_alpha", "hht"):
            raise ModelError(f"unknown scheme '{self.scheme}' (known: generalized_alpha, hht)")

    def parameters(self) -> tuple[float, float, float, float]:
        """(alpha_m, alpha_f, gamma, beta) in the Arnold-Brüls convention."""
        r = self.rho_inf
        if self.scheme == "hht":
            am, af = 0.0, (1 - r) / (1 + r)
        else:
            am, af = (2 * r - 1) / (r + 1), r / (r + 1)
        gamma = 0.5 + af - am
        beta = 0.25 * (gamma + 0.5) ** 2
        return am, af, gamma, beta


@dataclass
class State:
    t: float
    q: np.ndarray
    v: np.ndarray
    qdd: np.ndarray
    a: np.ndarray      # algorithmic acceleration
    lam: np.ndarray

    def copy(self) -> State:
        return State(self.t, self.q.copy(), self.v.copy(), self.qdd.copy(), self.a.copy(),
                     self.lam.copy())

    def restore(self, saved: State) -> None:
        """The arrays of ``saved`` (a :meth:`copy`) back in place (a refused step)."""
        self.q[:], self.v[:], self.qdd[:], self.a[:], self.lam[:] = (
            saved.q, saved.v, saved.qdd, saved.a, saved.lam)


@dataclass
class IntegrationStats:
    steps: int = 0
    rejected_steps: int = 0
    newton_iterations: int = 0
    factorizations: int = 0
    residual_evaluations: int = 0
    velocity_iterations: int = 0    # of the velocity corrector (constraint_level)
    error_rejections: int = 0       # of rejected_steps: converged, refused for their error
    replans: int = 0                # plans made again as sliding joints moved on (FOLLOW_*)


class _AlphaStep:
    """The nonlinear problem of one step, seen by :class:`Newton`."""

    def __init__(self, asm: Assembly, state: State) -> None:
        self.asm = asm
        self.s = state
        self.n = asm.n_total
        self.r_q = np.zeros(asm.n_coords)
        self.r_lam = np.zeros(asm.n_mult)
        self.t = 0.0
        self.bp = self.gp = self.scale_s = 0.0

    def setup(self, t: float, beta_p: float, gamma_p: float, s: float) -> None:
        self.t, self.bp, self.gp, self.scale_s = t, beta_p, gamma_p, s

    def evaluate(self, want_matrix: bool):
        s = self.scale_s
        mat = (s * self.bp, s * self.gp, s) if want_matrix else None
        scale = self.asm.evaluate(self.s.q, self.s.v, self.s.qdd, self.s.lam, self.t, self.r_q,
                                  self.r_lam, matrix=mat)
        return self.r_q, self.r_lam, scale

    def matrix(self):
        return self.asm.matrix

    def scaled_rhs(self, r_q, r_lam, out) -> None:
        n = self.r_q.size
        np.multiply(r_q, -self.scale_s, out=out[:n])
        np.negative(r_lam, out=out[n:])

    def apply(self, dx, factor: float) -> None:
        n = self.r_q.size
        dq = dx[:n]
        st = self.s
        if factor == 1.0:
            st.q += dq
            st.v += self.gp * dq
            st.qdd += self.bp * dq
            st.lam += dx[n:] / self.scale_s
        else:
            st.q += factor * dq
            st.v += (factor * self.gp) * dq
            st.qdd += (factor * self.bp) * dq
            st.lam += (factor / self.scale_s) * dx[n:]

    def save(self):
        return self.s.copy()

    def restore(self, saved) -> None:
        self.s.q[:] = saved.q
        self.s.v[:] = saved.v
        self.s.qdd[:] = saved.qdd
        self.s.lam[:] = saved.lam

    def describe(self, index: int) -> str:
        return self.asm.describe_coordinate(index)

    def stiffness_scale(self) -> float:
        return self.asm.stiffness_scale

    def hold(self, action: int) -> int:
        return self.asm.hold_contacts(action)


class _VelocityStep(_AlphaStep):
    """The velocity corrector of one step, seen by :class:`Newton`: q fixed, unknowns ``u``
    (v += gamma' u, q'' += beta' u) and lam; residual ``[r_q; Phi_q v / gamma']`` with
    ``Phi_q`` from the constraint rows of the iteration matrix without stiffness
    (:func:`flexmbs.driver.constraint_velocity`), which is its exact Newton matrix. The same
    equations as the compiled corrector (:mod:`flexmbs.steploop`)."""

    def __init__(self, asm: Assembly, state: State) -> None:
        super().__init__(asm, state)
        self.rows = asm.velocity_rows()
        self.indptr, self.indices = asm.matrix_pattern()
        self.data: np.ndarray | None = None
        self._r = np.zeros(asm.n_total)

    def setup(self, t: float, beta_p: float, gamma_p: float, s: float) -> None:
        super().setup(t, beta_p, gamma_p, s)
        self.data = None            # Phi_q at this step's q: read at the first evaluation

    def evaluate(self, want_matrix: bool):
        s = self.scale_s
        mat = (s * self.bp, s * self.gp, 0.0) if want_matrix or self.data is None else None
        scale = self.asm.evaluate(self.s.q, self.s.v, self.s.qdd, self.s.lam, self.t, self.r_q,
                                  self.r_lam, matrix=mat)
        if mat is not None:
            self.data = self.asm.matrix.data.copy()
        n = self.r_q.size
        constraint_velocity(self.indptr, self.indices, n, self.data, self.s.v, self.rows,
                            1.0 / self.gp, self._r)
        self.r_lam[:] = self._r[n:]
        return self.r_q, self.r_lam, scale

    def hold(self, action: int) -> int:
        """Nothing held: q is fixed at the converged step's, whose contacts agree with their
        gaps (the compiled corrector holds nothing either)."""
        return 0

    def apply(self, dx, factor: float) -> None:
        n = self.r_q.size
        du = dx[:n]
        st = self.s
        st.v += (factor * self.gp) * du
        st.qdd += (factor * self.bp) * du
        st.lam += (factor / self.scale_s) * dx[n:]


def _massless(asm: Assembly) -> str:
    """The cause of a singular mass matrix a user can act on: the beams without mass (density
    0), named with their scenario key; '' when every beam has mass."""
    beams = [b.name for b in asm.model.beams if not b.stiffness.mass_per_length > 0.0]
    if not beams:
        return ""
    keys = ", ".join(f"beams[{name}].density" for name in beams[:3])
    return (f"beam{'s' if len(beams) > 1 else ''} {', '.join(repr(b) for b in beams[:3])}"
            f"{' ...' if len(beams) > 3 else ''} {'have' if len(beams) > 1 else 'has'} no mass "
            f"(density 0: {keys}); a beam that can move in a dynamic run needs a density > 0 "
            "(or integrator = \"static\")")


def check_masses(asm: Assembly) -> None:
    """Before a dynamic run writes anything: a beam without mass (density 0) that can move
    makes the initial accelerations singular; refuse it as bad input (:class:`ModelError`
    naming ``beams[<name>].density``) when the initial accelerations cannot be computed.
    Nothing to do, and nothing solved, when every beam has mass."""
    cause = _massless(asm)
    if not cause:
        return
    q0, v0 = asm.initial_state()
    try:
        consistent_initial_state(asm, q0, v0, 0.0)
    except ConvergenceError:
        raise ModelError(cause) from None


def consistent_initial_state(asm: Assembly, q0: np.ndarray, v0: np.ndarray, t0: float) -> State:
    """Solve [M Phi_q^T; Phi_q 0][q''; lam] = [Q_ext - Q_int; gamma] at (q0, v0, t0); forces
    that depend on lam (friction on a sliding joint's reaction) by Newton iterations from it.

    With prescribed motion or drivers moving at t0 (``Phi_t != 0``), v0 is first made
    consistent, ``Phi_q v = -Phi_t``, by the smallest change in the kinetic-energy norm:
    [M Phi_q^T; Phi_q 0][v; mu] = [M v0; -Phi_t] (a driven part starts at its function's speed).
    """
    n, m = asm.n_coords, asm.n_mult
    r_q = np.zeros(n)
    r_lam = np.zeros(m)
    zeros_acc = np.zeros(n)
    nu = asm.constraint_velocity_terms(q0, t0) if m else np.zeros(0)
    lu = PlannedLU(asm)     # [M Phi_q^T; Phi_q 0]: mass on every coordinate that has it
    if np.any(nu != 0.0) and np.all(np.isfinite(nu)):
        asm.evaluate(q0, v0, zeros_acc, np.zeros(m), t0, r_q, r_lam, matrix=(1.0, 0.0, 0.0))
        A = asm.matrix
        with contextlib.suppress(ConvergenceError):
            lu.factorize(A)
            v_new = lu.solve(np.concatenate([A[:n, :n] @ v0, nu]))[:n]
            if np.all(np.isfinite(v_new)):
                v0 = v_new
    asm.evaluate(q0, v0, zeros_acc, np.zeros(m), t0, r_q, r_lam, matrix=(1.0, 0.0, 0.0))
    rhs = np.concatenate([-r_q, asm.constraint_time_terms(q0, v0, t0)])
    bad = np.flatnonzero(~np.isfinite(rhs))
    if bad.size:
        i = int(bad[0])
        where = (asm.describe_coordinate(i) if i < n else f"constraint equation {i - n}")
        culprit = ""
        for ld in getattr(asm.model, "loads", ()):
            with contextlib.suppress(Exception):
                scale = float(ld.function(t0)) if ld.function is not None else 1.0
                if not np.isfinite(scale):
                    culprit = f"; load '{ld.name}': its time function gives {scale} at t = {t0:g}"
                    break
        raise ConvergenceError(
            f"the forces at t = {t0:g} are not finite ({float(rhs[i])} on {where}){culprit}; "
            "loads and their time functions must stay finite")
    try:
        lu.factorize(asm.matrix)
        x = lu.solve(rhs)
    except ConvergenceError as exc:
        raise ConvergenceError(
            f"cannot compute consistent initial accelerations: singular mass/constraint matrix "
            f"({exc}); {_massless(asm) or 'every coordinate needs mass or a constraint'}"
        ) from None
    if not np.all(np.isfinite(x)):
        i = int(np.flatnonzero(~np.isfinite(x))[0])
        where = asm.describe_coordinate(i) if i < n else f"multiplier {i - n}"
        raise ConvergenceError(
            f"initial accelerations are not finite (first at {where}): the mass/constraint "
            "matrix is singular or the forces overflow; "
            f"{_massless(asm) or 'every coordinate needs mass or a constraint'}, and forces must "
            "stay finite")
    for _ in range(MULTIPLIER_ITERATIONS):
        # forces that depend on the multipliers (the sliding joint's friction on its normal
        # reaction) were evaluated at λ = 0 above: Newton on [q''; λ] with the same matrix
        scale = asm.evaluate(q0, v0, x[:n], x[n:], t0, r_q, r_lam, matrix=(1.0, 0.0, 0.0))
        if not np.abs(r_q).max() > 1e-10 * max(scale, 1e-300):
            break
        A = asm.matrix
        try:
            lu.factorize(A)
        except ConvergenceError:
            break
        dx = lu.solve(np.concatenate([r_q, A[n:, :n] @ x[:n] - rhs[n:]]))
        if not np.all(np.isfinite(dx)):
            break
        x = x - dx
    qdd = x[:n].copy()
    return State(t0, q0.copy(), v0.copy(), qdd, qdd.copy(), x[n:].copy())


#: Newton iterations of :func:`consistent_initial_state` for multiplier-dependent forces
MULTIPLIER_ITERATIONS = 10


Observer = Callable[[State], None]


class _PythonStepper:
    """General path: Newton on :class:`_AlphaStep` (any model), one step per call."""

    def snapshot(self) -> dict[str, np.ndarray]:
        """Solver state a checkpoint carries (none here: SuperLU factors do not serialise; a
        resumed Python-path run refactorises, agreeing to the Newton tolerance)."""
        return {}

    def restore(self, saved: dict[str, np.ndarray]) -> None:
        """See :meth:`snapshot`."""

    def __init__(self, asm: Assembly, options: GeneralizedAlpha, state: State) -> None:
        self.am, self.af, self.gamma, self.beta = options.parameters()
        self.keep_acceleration = options.predictor == "constant_acceleration"
        self.newton = Newton(options.newton, asm.length_scale, PlannedLU(asm))
        self.step = _AlphaStep(asm, state)
        self.state = state
        self.velocity = options.constraint_level == "position_velocity" and asm.n_mult > 0
        self.corrector = Newton(options.newton, asm.length_scale, PlannedLU(asm))
        self.velocity_step = _VelocityStep(asm, state) if self.velocity else None
        self.error = 0.0

    replans = 0     # the Python loop's plan holds every entry (none follows the joints)

    def replan(self, again: bool = False) -> None:
        raise AssertionError("the Python loop's plan does not follow the joints")

    def release(self) -> None:
        return None

    def max_chunk(self) -> int:
        return 1

    def error_max(self) -> float:
        """The largest scaled step-error estimate of the last call's steps (0 without control)."""
        return self.error

    def invalidate(self) -> None:
        self.newton.invalidate()

    def advance(self, h: float, n_steps: int, t0: float, tolerance: float = 0.0) -> int:
        """One step from t0 (``n_steps`` is 1); on failure (or a step error estimate above
        ``tolerance`` > 0) the state is restored."""
        am, af, gamma, beta = self.am, self.af, self.gamma, self.beta
        st = self.state
        saved = st.copy()
        # the compiled loop's predictor and corrector (flexmbs.steploop)
        bp, gp, s = alpha_coefficients(h, am, af, gamma, beta)
        a_star = np.empty_like(st.a)
        alpha_predict(st.q, st.v, st.qdd, st.a, a_star, h, am, af, gamma, beta,
                      self.keep_acceleration)
        self.step.setup(t0 + h, bp, gp, s)
        try:
            self.newton.solve(self.step)
            if self.velocity_step is not None:
                self.velocity_step.setup(t0 + h, bp, gp, s)
                self.corrector.invalidate()     # its matrix: this step's q, no stiffness
                self.corrector.solve(self.velocity_step)
        except ConvergenceError as exc:
            st.restore(saved)
            raise _StepFailure(0, str(exc)) from None
        alpha_correct(st.a, a_star, st.qdd, am, af)
        self.error = 0.0
        if tolerance > 0.0:
            self.error = float(step_error(st.a, saved.a, h, beta, gamma, tolerance))
            if self.error > 1.0:
                st.restore(saved)
                raise _StepFailure(0, _step_error_reason(self.error, tolerance), error=True)
        return 1

    def finish_chunk(self) -> None:
        """Interaction state after the converged step (may stop the run), nodal frames
        re-based."""
        st = self.state
        self.step.asm.post_step(st.q, st.v, st.t, st.qdd, st.a, lam=st.lam)

    def totals(self) -> tuple[int, int, int]:
        t, c = self.newton.total, self.corrector.total
        return (t.iterations, t.factorizations + c.factorizations,
                t.residual_evaluations + c.residual_evaluations)

    def velocity_iterations(self) -> int:
        return self.corrector.total.iterations


def _step_error_reason(error: float, tolerance: float) -> str:
    return (f"its local error estimate {error * tolerance:.3g} exceeds step_tolerance = "
            f"{tolerance:g}")


class _StepFailure(Exception):
    def __init__(self, done: int, reason: str, error: bool = False, replan: bool = False
                 ) -> None:
        super().__init__(reason)
        self.done = done
        self.error = error          # converged, refused by step-error control
        self.replan = replan        # a sliding joint left the elements the plan follows




class _CompiledStepper:
    """Fast path: whole runs of steps (up to the next output) execute in numba
    (:func:`flexmbs.steploop.alpha_run` through :func:`flexmbs.kernel.kernel`: the
    driver's residual, Jacobian refresh,
    bordered banded LU, post-step update, all compiled); Python is re-entered only at output
    times and on failure. Applies when every term has a compiled form
    (:meth:`Assembly.compiled_reason` is empty)."""

    def __init__(self, asm: Assembly, options: GeneralizedAlpha, state: State) -> None:
        from .. import steploop as cc
        from ..linalg.bordered import BorderedBandedLU
        from ..terms import dynamic_mode

        self.cc = cc
        self.asm = asm
        self.o = options.newton
        self.am, self.af, self.gamma, self.beta = (float(x) for x in options.parameters())
        self.keep_acceleration = options.predictor == "constant_acceleration"
        self.state = state
        self.mode = dynamic_mode()
        self._coef = np.zeros(3)
        n, m = asm.n_coords, asm.n_mult
        self.r = np.zeros(n + m)
        self.rhs = np.zeros(n + m)
        self.dx = np.zeros(n + m)
        self.a_star = np.zeros(n)
        self.backup = np.zeros((5, n + m))
        self.info = np.zeros(cc.INFO_SIZE)
        self.info[cc.INFO_KSCALE] = asm.stiffness_scale
        self.data = np.zeros_like(asm.matrix.data)
        # the plan of the whole reserved pattern, or one that follows the sliding joints
        # where that is much cheaper (many rings on a beam: their slide coordinates and
        # multipliers then sit in the band beside their elements, not in a dense border)
        plan = asm.factor_plan()
        self.windows: np.ndarray | None = None
        self.replans = 0
        windows = asm.contact_windows(FOLLOW_REACH)
        if windows is not None:
            following = asm.factor_plan(windows=windows)
            if following.cost < FOLLOW_COST_RATIO * plan.cost:
                self.windows, plan = windows, following
        asm.follow(self.windows)
        self.lu: BorderedBandedLU = plan.factorization(asm.matrix)
        self.stopped: Exception | None = None
        self.tolerance = 0.0
        # the velocity corrector (constraint_level): its own factorisation, the matrix pattern
        # to read Phi_q from, the equations it holds
        self.velocity = options.constraint_level == "position_velocity" and m > 0
        if self.velocity:
            # the same plan: its matrix has the mass, not the stiffness (docs/design-notes.md,
            # "One factorisation for every solver")
            self.factor_v = self.lu.twin()
            self.pattern = asm.matrix_pattern()
            self.velocity_rows = asm.velocity_rows()
        else:
            self.factor_v = cc.idle_factor()
            self.pattern = (np.zeros(0, np.int64), np.zeros(0, np.int64))
            self.velocity_rows = np.zeros(0)

    def max_chunk(self) -> int:
        return 1_000_000

    def error_max(self) -> float:
        """The largest scaled step-error estimate of the last call's steps (0 without control)."""
        return float(self.info[self.cc.INFO_STEP_ERR_MAX])

    #: entries of ``info`` that steer the next steps (counters excluded: the summary adds them)
    _KEPT_INFO = ("INFO_HAVE", "INFO_KSCALE", "INFO_RENEW", "INFO_CYC_STEPS", "INFO_CYC_ITS")
    _FACTOR_ARRAYS = ("ab", "piv", "u_top", "u_inv", "xt", "a_ba", "s", "piv_s")

    def _factor_arrays(self) -> dict[str, np.ndarray]:
        """The factorisation's numeric arrays by name (the tree part's as ``tree_val`` and
        ``tree_piv``)."""
        f = self.lu.factor
        out = {k: getattr(f, k) for k in self._FACTOR_ARRAYS}
        out["tree_val"], out["tree_piv"] = f.tree.val, f.tree.piv
        sf = f.sparse      # KLU's factors are C memory: the values that give them again
        out["sparse_ax"], out["sparse_ax_full"] = sf.Ax, sf.Ax_full
        out["sparse_state"], out["sparse_values"] = sf.state, sf.values
        return out

    def snapshot(self) -> dict[str, np.ndarray]:
        """What the next steps depend on besides the state: whether a factorisation is held,
        its age in the renewal rule, the stiffness scale, the factors themselves and the
        windows of a plan that follows the sliding joints, so that a resumed run continues
        with the same factorisation (bit for bit, issue "nothing lost")."""
        cc = self.cc
        out = {"info": np.array([self.info[getattr(cc, k)] for k in self._KEPT_INFO])}
        for k, a in self._factor_arrays().items():
            out[k] = np.array(a, copy=True)
        if self.windows is not None:
            out["windows"] = self.windows.copy()
            out["plan_border"] = np.array(self.lu.factor.border, copy=True)
            out["plan_sparse"] = np.array(self.lu.sparse)
        return out

    def _plan_on(self, windows: np.ndarray, border: np.ndarray, sparse: bool) -> None:
        """Factorise with the plan that follows the joints on ``windows`` with the dense
        ``border`` (the first such plan's: a re-plan only orders the band again) or, with
        ``sparse``, KLU's (a re-plan analyses the new pattern)."""
        self.windows = np.asarray(windows, np.int64).copy()
        self.asm.follow(self.windows)
        plan = self.asm.factor_plan(windows=self.windows, border=border, sparse=sparse)
        self.lu = plan.factorization(self.asm.matrix)
        if self.velocity:
            self.factor_v = self.lu.twin()
        self.invalidate()

    def replan(self, again: bool = False) -> None:
        """A joint left the elements the plan follows it on: a new plan around where every
        joint is at the step's start, and around the element the failed step found it on
        (the next step refreshes the factorisation); ``again``: the step failed on the last
        new plan too (its windows are kept as well)."""
        err = self.asm.system.error
        windows = self.asm.contact_windows(
            FOLLOW_REACH, (int(self.info[self.cc.INFO_CODE]), int(err[3]), int(err[2])),
            keep=self.windows if again else None)
        assert windows is not None
        self._plan_on(windows, self.lu.factor.border, self.lu.sparse)
        self.replans += 1

    def release(self) -> None:
        """The run is over: every plan holds the sliding joints' whole beams again."""
        self.asm.follow(None)

    def restore(self, saved: dict[str, np.ndarray]) -> None:
        """Take over a :meth:`snapshot` (ignored unless every array fits this model)."""
        windows, border = saved.get("windows"), saved.get("plan_border")
        if self.windows is not None and windows is not None and border is not None \
                and np.shape(windows) == self.windows.shape:
            self._plan_on(windows, np.asarray(border, np.int64), bool(saved.get("plan_sparse", False)))
        arrays = self._factor_arrays()
        if "info" not in saved or any(k not in saved or np.shape(saved[k]) != a.shape
                                      for k, a in arrays.items()):
            return
        for k, a in arrays.items():
            a[...] = saved[k]
        for value, k in zip(np.asarray(saved["info"], float), self._KEPT_INFO, strict=True):
            self.info[getattr(self.cc, k)] = value
        sf = self.lu.factor.sparse
        if sf.n and sf.state[ST_HAVE] and sparse_restore(sf) != 0:
            self.invalidate()
        self.asm.stiffness_scale = float(self.info[self.cc.INFO_KSCALE])

    def invalidate(self) -> None:
        self.info[self.cc.INFO_HAVE] = 0.0

    def _failure_reason(self) -> str:
        cc, info = self.cc, self.info
        code = int(info[cc.INFO_CODE])
        if code == cc.ERR_STEP_ERROR:
            return _step_error_reason(float(info[cc.INFO_STEP_ERR]), self.tolerance)
        if code == cc.ERR_SINGULAR:
            return ("the iteration matrix is singular (a coordinate without mass or stiffness, "
                    f"or dependent constraints; zero pivot {int(info[cc.INFO_PIVOT])})")
        if code != 0:
            return str(self.asm.error_exception(code, self.state.q, self.state.t))
        return (f"Newton did not converge in {int(info[cc.INFO_IT])} iterations (scaled error "
                f"{info[cc.INFO_ERR]:.3g}, 1 = tolerance; worst equation: "
                f"{self.asm.describe_coordinate(int(info[cc.INFO_WORST]))})")

    def advance(self, h: float, n_steps: int, t0: float, tolerance: float = 0.0) -> int:
        asm, st, o, cc = self.asm, self.state, self.o, self.cc
        self.tolerance = tolerance
        fv = asm.functions.table(t0, h, n_steps)
        run = cc.AlphaRun(
            n_steps=int(n_steps), h=float(h), am=self.am, af=self.af, gamma=self.gamma,
            beta=self.beta, a=st.a, backup=self.backup, factor=self.lu.factor, rhs=self.rhs,
            dx=self.dx, a_star=self.a_star, max_it=int(o.max_iterations),
            full_newton=not o.modified, rtol=float(o.relative_tolerance),
            ctol=float(o.constraint_tolerance * asm.length_scale),
            floor_factor=float(o.roundoff_factor * 2.2e-16 * asm.length_scale),
            refresh_ratio=float(o.refresh_ratio), refresh_iterations=float(o.refresh_iterations),
            refresh_cost=float(o.refresh_cost), keep_acceleration=self.keep_acceleration,
            info=self.info, velocity=self.velocity, factor_v=self.factor_v,
            indptr=self.pattern[0], indices=self.pattern[1], velocity_rows=self.velocity_rows,
            step_tolerance=float(tolerance), retreats=int(o.retreats),
            hold_contacts=bool(o.hold_contacts))
        value, _ = kernel(OP_STEPS, asm.kernel_system, st.q, st.v, st.qdd, st.lam, fv, self.mode,
                          self._coef, self.r, self.data, run)
        status = int(value)
        asm.stiffness_scale = float(self.info[cc.INFO_KSCALE])
        done = int(self.info[cc.INFO_DONE])
        if status == cc.STATUS_CONVERGED:
            return done
        if status == cc.STATUS_STOPPED:
            self.stopped = asm.error_exception(int(self.info[cc.INFO_CODE]), st.q, t0 + done * h)
            return done
        self.invalidate()
        raise _StepFailure(done, self._failure_reason(),
                           error=int(self.info[cc.INFO_CODE]) == cc.ERR_STEP_ERROR,
                           replan=(self.windows is not None
                                   and asm.off_plan(int(self.info[cc.INFO_CODE]))))

    def finish_chunk(self) -> None:
        if self.stopped is not None:
            exc, self.stopped = self.stopped, None
            raise exc

    def totals(self) -> tuple[int, int, int]:
        cc, info = self.cc, self.info
        return int(info[cc.INFO_TOTAL]), int(info[cc.INFO_FACT]), int(info[cc.INFO_RES])

    def velocity_iterations(self) -> int:
        return int(self.info[self.cc.INFO_VEL_ITS])


def integrate(asm: Assembly, options: GeneralizedAlpha, *, t_end: float, dt: float,
              state: State | None = None, output_interval: float | None = None,
              observer: Observer | None = None,
              progress: Callable[[State, IntegrationStats], None] | None = None,
              solver_state: dict[str, Any] | None = None,
              snapshot: Callable[[dict[str, Any]], None] | None = None,
              ) -> tuple[State, IntegrationStats]:
    """Integrate from ``state`` (default: consistent initial state) to ``t_end``.

    ``observer(state)`` is called at t0 and at every multiple of ``output_interval`` (default:
    every step); just before, ``snapshot(d)`` receives the solver's own state (step size,
    cut-back count, the factorisation and its age), which ``solver_state=d`` restores, so that a
    run resumed from an output continues exactly as the uninterrupted one. Raises
    :class:`ConvergenceError` if a step cannot be completed even at ``min_step``; everything
    observed before stays valid.
    """
    check_times(t_end=t_end, dt=dt, output_interval=output_interval,
                t_start=0.0 if state is None else state.t)
    if state is None:
        q0, v0 = asm.initial_state()
        state = consistent_initial_state(asm, q0, v0, 0.0)
    asm.begin(state.q)
    out_dt = output_interval if output_interval is not None else dt
    compiled = options.compiled and not asm.compiled_reason()
    stepper: _PythonStepper | _CompiledStepper = (
        _CompiledStepper(asm, options, state) if compiled else _PythonStepper(asm, options, state))
    stats = IntegrationStats()
    h_nom = dt
    h = dt
    h_min = options.min_step or dt / 1024
    ok_since_cut = 0
    err_since_cut = 0.0     # largest step-error estimate since the last cut or growth
    t_eps = 1e-9 * dt
    k_out = int(math.floor(state.t / out_dt + 1e-9)) + 1
    h_matrix: float | None = None
    if solver_state:
        stepper.restore(solver_state)
        h = float(solver_state.get("h", h))
        ok_since_cut = int(solver_state.get("ok_since_cut", 0))
        err_since_cut = float(solver_state.get("err_since_cut", 0.0))
        hm = float(solver_state.get("h_matrix", -1.0))
        h_matrix = hm if hm > 0 else None

    def observe(after_step: bool) -> None:
        if snapshot is not None:
            _count(stats, stepper)
            snapshot({"h": h, "ok_since_cut": ok_since_cut, "err_since_cut": err_since_cut,
                      "h_matrix": -1.0 if h_matrix is None else h_matrix,
                      "counters": dataclasses.asdict(stats), **stepper.snapshot()})
        if observer is not None:
            # the interactions' records of the state: what its step's equations held
            asm.observe(state.q, state.v, state.lam, state.t, after_step=after_step)
            observer(state)

    observe(False)
    replans_here = 0
    try:
        while state.t < t_end - t_eps:
            t_out = min(k_out * out_dt, t_end)
            remaining = t_out - state.t
            n_full = int(math.floor(remaining / h + 1e-9))
            if n_full == 0 or remaining - h < t_eps:
                h_step, n_chunk = remaining, 1
            else:
                h_step = h
                n_chunk = n_full if remaining - n_full * h < t_eps else n_full
                if h < h_nom:   # after a cut-back: few steps, then try to grow again
                    n_chunk = min(n_chunk, options.grow_after - ok_since_cut)
            n_chunk = max(1, min(n_chunk, stepper.max_chunk()))
            if h_matrix is None or abs(h_step - h_matrix) > 1e-12 * h_step:
                stepper.invalidate()
                h_matrix = h_step
            t_start = state.t
            # at the smallest step no step is refused for its error (only Newton can fail there)
            tolerance = options.step_tolerance if h_step > h_min * (1 + 1e-12) else 0.0
            try:
                done = stepper.advance(h_step, n_chunk, t_start, tolerance)
                replans_here = 0
            except _StepFailure as exc:
                done = exc.done
                stats.steps += done
                state.t = t_start + done * h_step
                if exc.replan:
                    # a joint moved past its planned elements: plan anew (the new plan holds
                    # every joint where it starts the step and where the step found it; a
                    # step re-planned again keeps the last plan's elements too, so the
                    # windows only grow until the step converges)
                    again = replans_here > 0 and not done
                    replans_here = replans_here + 1 if again else 1
                    if replans_here > MAX_REPLANS:
                        raise ConvergenceError(f"step from t = {state.t:.6g}: {exc}") from None
                    stepper.replan(again)
                    h_matrix = None
                    continue
                stats.rejected_steps += 1
                stats.error_rejections += int(exc.error)
                if not options.adaptive or h_step <= h_min * (1 + 1e-12):
                    raise ConvergenceError(f"step from t = {state.t:.6g} failed at h = {h_step:.3g}: "
                                           f"{exc}") from None
                h = max(h_step / 2, h_min)
                ok_since_cut = 0
                err_since_cut = 0.0
                stepper.invalidate()
                h_matrix = None
                continue
            state.t = t_start + done * h_step
            if abs(state.t - t_out) <= t_eps:
                state.t = t_out
            stats.steps += done
            if h < h_nom:
                ok_since_cut += done
                err_since_cut = max(err_since_cut, stepper.error_max())
                if ok_since_cut >= options.grow_after:
                    if err_since_cut <= GROW_ERROR:
                        h = min(2 * h, h_nom)
                    ok_since_cut = 0
                    err_since_cut = 0.0
            stepper.finish_chunk()
            if state.t == t_out:
                k_out += 1
                observe(True)
            if progress is not None:
                _count(stats, stepper)
                progress(state, stats)
    finally:
        stepper.release()
    _count(stats, stepper)
    return state, stats


def _count(stats: IntegrationStats, stepper: _PythonStepper | _CompiledStepper) -> None:
    """The stepper's counters into ``stats`` (the driver counts steps and rejections)."""
    stats.newton_iterations, stats.factorizations, stats.residual_evaluations = stepper.totals()
    stats.replans = stepper.replans
    stats.velocity_iterations = stepper.velocity_iterations()

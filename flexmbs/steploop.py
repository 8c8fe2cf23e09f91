"""Compiled inner loop of generalized-alpha: runs of whole steps in numba.

One call of :func:`alpha_run` performs, for up to ``n_steps`` steps, the predictor, the
modified-Newton iterations (residual :func:`flexmbs.driver.residual`, convergence test,
Jacobian refresh :func:`flexmbs.driver.jacobian` + :func:`~flexmbs.linalg.bordered.bordered_factorize`
when modified Newton contracts too slowly, solve with the bordered banded LU factors), the
corrector, with ``velocity`` the velocity corrector (below), and the interactions' post-step
update (:func:`flexmbs.driver.post_step`). Python is
re-entered only at output times and on failure, so a step costs what compiled code costs. The
arithmetic and the convergence test are those of :mod:`flexmbs.solvers.newton` and
:mod:`flexmbs.solvers.generalized_alpha`; the tests run both paths on the same problems
(docs/theory.md §I.6.1).

Velocity corrector (``constraint_level = "position_velocity"``, docs/design-notes.md "rho_inf
= 1 with joints"): after the position step has converged, q stays and (v, q'', λ) move along
the Newmark direction (v += γ' u, q'' += β' u, λ += μ / s) until the velocity constraints
``Φ_q v = 0`` hold with the equations of motion: Newton on
``[[s(β' M + γ' C), Φ_qᵀ], [Φ_q, 0]] [u; μ] = -[s r_q; Φ_q v / γ']``, the iteration matrix
with no stiffness (q does not move), factorised once per step into its own ``factor_v``.
``Φ_q v`` is read from the constraint rows of that matrix (:func:`flexmbs.driver.constraint_velocity`).

Held active set (``hold_contacts``, :class:`~flexmbs.solvers.newton.NewtonOptions`): the
clearance joints' contacts are decided at the step's start (those tracked from the last step)
and held while Newton converges on the smooth problem they define (a held contact that opens
pulls by the linear law's extension, a point outside the set that penetrates acts not:
:func:`~flexmbs.contact.clearance_term.clearance_forces`). Once an iterate's error is within
:data:`HOLD_CHECK` tolerances and some point's gap disagrees with the set, the set becomes
that iterate's penetrating points, whose residual is then the plain one: converged, the step
is accepted; else Newton continues on the new set (after :data:`HOLD_UPDATES` updates, on the
plain problem); :func:`hold_action` decides, for this loop and the Python one. An accepted
step has every gap consistent with the set: its state solves the plain equations to the same
tolerance; only the iterates' path differs (without the hold a penalty's kink lets them make
and lose contacts and push a wire through a bore wall). Where a step carries a wire well into
a wall the held path can end on another solution of the penalty's step equations than plain
Newton's halving does: off by default (docs/design-notes.md, "A Newton that holds the
contacts"). Counted in ``info[INFO_HOLD]``.

Step-error control (``step_tolerance > 0``): after a converged step, :func:`step_error` estimates
its local error in q; a step whose estimate exceeds the tolerance is restored and reported
(ERR_STEP_ERROR), and the caller retries it with half the step.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ._jit import njit
from .codes import ERROR_CODES
from .contact.clearance_term import HOLD_CURRENT, HOLD_KEEP, HOLD_OFF, HOLD_READ, HOLD_TRACKED
from .driver import constraint_velocity, hold_contacts, jacobian, post_step, residual, stops_run
from .linalg.bordered import BorderedFactor, bordered_factorize, bordered_solve, empty_tree
from .linalg.sparse_lu import empty_sparse

STATUS_CONVERGED = 0   # all steps done
STATUS_FAILED = 2      # the current step failed and was restored to its start
STATUS_STOPPED = 3     # a step converged, then an interaction stopped the run (end of a beam)

#: error code of a singular iteration matrix (the others are flexmbs.driver.ERR_*)
ERR_SINGULAR = ERROR_CODES["singular"]
#: error code of a converged step whose local error estimate exceeds the tolerance
ERR_STEP_ERROR = ERROR_CODES["step_error"]

#: ``info`` entries
(INFO_IT, INFO_PREV, INFO_ERR, INFO_WORST, INFO_DONE, INFO_TOTAL, INFO_CODE, INFO_HAVE,
 INFO_KSCALE, INFO_FACT, INFO_RES, INFO_PIVOT, INFO_CYC_STEPS, INFO_CYC_ITS, INFO_STEP_ITS,
 INFO_RENEW, INFO_VEL_ITS, INFO_STEP_ERR, INFO_STEP_ERR_MAX, INFO_HOLD) = range(20)
INFO_SIZE = 20
#: updates of the held active set in one step before the step's Newton lets go of it
#: (``hold_contacts``; module docstring)
HOLD_UPDATES = 3
#: the held set is checked against the gaps at iterates whose error (in tolerances) is at most
#: this: the held problem nearly solved (1e3: 9 % fewer iterations than at 1 on the tendon
#: robot, 2.5 % on the guide wire; the same factorisations and steps)
HOLD_CHECK = 1e3


class AlphaRun(NamedTuple):
    """Settings and work arrays of one :func:`alpha_run` call (its caller's whole state)."""

    n_steps: int
    h: float
    am: float                   # generalized-alpha parameters (Arnold-Brüls convention)
    af: float
    gamma: float
    beta: float
    a: np.ndarray               # (n,) acceleration-like variable
    backup: np.ndarray          # (5, n + m) step start, restored on failure
    factor: BorderedFactor
    rhs: np.ndarray             # (n + m,)
    dx: np.ndarray              # (n + m,)
    a_star: np.ndarray          # (n,)
    max_it: int
    full_newton: bool
    rtol: float
    ctol: float
    floor_factor: float         # rounding floor of the force tolerance per unit stiffness
    refresh_ratio: float
    refresh_iterations: float
    refresh_cost: float
    keep_acceleration: bool
    info: np.ndarray            # (INFO_SIZE,) float
    velocity: bool              # the velocity corrector after each step (module docstring)
    factor_v: BorderedFactor    # its factorisation (the idle factor without it)
    indptr: np.ndarray          # int64 (N + 1,): CSC pattern of the iteration matrix ...
    indices: np.ndarray         # int64 (nnz,): ... (Φ_q v from its constraint rows)
    velocity_rows: np.ndarray   # (m,) 1.0: Φ_q v = 0 held; 0.0: a row with Φ_t, kept as is
    step_tolerance: float       # local error a step may have (step_error), 0: not checked
    retreats: int               # halvings of an iterate the model rejects (NewtonOptions)
    hold_contacts: bool         # the held active set (module docstring, NewtonOptions)


def idle_run() -> AlphaRun:
    """An :class:`AlphaRun` of no steps, with the types of a real one: what callers that only
    evaluate pass to :func:`flexmbs.kernel.kernel` (one signature, one compiled library)."""
    z = np.zeros(0)
    zi = np.zeros(0, np.int64)
    return AlphaRun(n_steps=0, h=0.0, am=0.0, af=0.0, gamma=0.0, beta=0.0, a=z,
                    backup=np.zeros((5, 0)), factor=idle_factor(), rhs=z, dx=z, a_star=z, max_it=0,
                    full_newton=False, rtol=0.0, ctol=0.0, floor_factor=0.0, refresh_ratio=0.0,
                    refresh_iterations=0.0, refresh_cost=0.0, keep_acceleration=False,
                    info=np.zeros(INFO_SIZE), velocity=False, factor_v=idle_factor(),
                    indptr=zi, indices=zi, velocity_rows=z, step_tolerance=0.0, retreats=0,
                    hold_contacts=False)


def idle_factor() -> BorderedFactor:
    """A :class:`BorderedFactor` of nothing, typed like a real one."""
    z = np.zeros(0)
    zi = np.zeros(0, np.int64)
    return BorderedFactor(
        n=0, n_band=0, n_border=0, kl=0, ku=0, perm=zi, border=zi, fill_pos=zi, fill_row=zi,
        fill_col=zi, fill_ptr=zi, ab=np.zeros((2, 2), order="F"),   # 2x2: typed F-contiguous
        piv=zi, u_top=zi, u_inv=z, xt=np.zeros((0, 0)), a_ba=np.zeros((0, 0)),
        s=np.zeros((0, 0)), piv_s=zi, work_a=z, work_b=z, tree=empty_tree(),
        sparse=empty_sparse())


@njit
def renew_jacobian(step_its, cycle_steps, cycle_its, refresh_cost):
    """Renewal rule for modified Newton: refresh the Jacobian at the next step when the last
    step's iterations exceed the average cost per step of the current cycle (the steps since
    the last refresh), ``(refresh_cost + cycle_its) / cycle_steps``, in iterations; this
    minimises the long-run cost per step when iterations grow as the Jacobian ages."""
    return step_its * cycle_steps > refresh_cost + cycle_its


@njit
def hold_action(err, updates, disagree):
    """What a Newton iteration that holds the contacts' active set does after an evaluation
    with error ``err`` (in tolerances) whose points disagree with the held set at ``disagree``
    places, the set updated ``updates`` times in this solve (module docstring): ``HOLD_KEEP``,
    or, once the held problem is nearly solved (``err <= HOLD_CHECK``) and the set disagrees,
    ``HOLD_CURRENT`` (the set becomes the iterate's contacts) or, after :data:`HOLD_UPDATES`
    updates, ``HOLD_OFF`` (the plain problem). Both Newton loops (this module's and
    :class:`flexmbs.solvers.newton.Newton`) decide by it."""
    if err <= HOLD_CHECK and disagree > 0:
        return HOLD_OFF if updates >= HOLD_UPDATES else HOLD_CURRENT
    return HOLD_KEEP


@njit
def _slow(err, err_prev, ratio, max_more):
    """Modified Newton contracts too slowly: rate above ``ratio`` or more than ``max_more``
    further iterations predicted at the current rate (same rule as newton.Newton)."""
    rho = err / err_prev
    if rho > ratio:
        return True
    return np.log(err) > max_more * -np.log(rho)


@njit
def step_error(a, a_old, h, beta, gamma, tolerance):
    """Local error estimate of a generalized-alpha step in q, scaled by ``tolerance``:
    ``max_i |(β − γ/2 + 1/12) h² (a_{n+1} − a_n)_i| / tolerance``; 1 = at the tolerance.

    The algorithmic acceleration approximates ``q̈(t_n + δh)``, ``δ = α_m − α_f = 1/2 − γ``
    (Arnold & Brüls 2007), so ``q_{n+1} = q_n + h v_n + h²(1/2 − β) a_n + h² β a_{n+1}``
    differs from the Taylor series through ``(q_n, v_n)`` by ``(β + δ/2 − 1/6) h³ q⃛`` and
    ``h q⃛ ≈ a_{n+1} − a_n`` (for γ = 1/2 the Newmark estimate ``(β − 1/6) h² Δq̈`` of
    Zienkiewicz & Xie 1991; tests/solvers/test_step_control.py checks it against the true local
    error of an oscillator). Coordinates in model units: metres for positions and slide
    coordinates, 1 for slopes and Euler parameters."""
    c = abs(beta - 0.5 * gamma + 1.0 / 12.0) * h * h / tolerance
    e = 0.0
    for i in range(a.size):
        d = abs(a[i] - a_old[i])
        if d > e:
            e = d
    return c * e


@njit
def _restore(backup, q, v, qdd, a, lam):
    n = q.size
    for i in range(n):
        q[i] = backup[0, i]
        v[i] = backup[1, i]
        qdd[i] = backup[2, i]
        a[i] = backup[3, i]
    for i in range(lam.size):
        lam[i] = backup[4, i]


@njit(inline="always")
def alpha_coefficients(h, am, af, gamma, beta):
    """``(β′, γ′, βh²)`` of a generalized-α step of size h (docs/theory.md §I.6): ``q̈ = β′ Δq``,
    ``q̇ = γ′ Δq`` for a Newton update Δq, and the iteration matrix's stiffness scale."""
    return (1 - am) / (h * h * beta * (1 - af)), gamma / (h * beta), beta * h * h


@njit(inline="always")
def alpha_predict(q, v, qdd, a, a_star, h, am, af, gamma, beta, keep_acceleration):
    """The step's predictor, in place: ``a* = (α_f q̈ − α_m a)/(1 − α_m)`` into ``a_star``,
    ``q += h q̇ + h²((½ − β) a + β a*)``, ``q̇ += h((1 − γ) a + γ a*)``; then Arnold & Brüls'
    ``q̈ = 0``, or (``keep_acceleration``) ``q̈`` kept and ``q``, ``q̇`` made consistent with
    it through β′, γ′. The multipliers keep their last values."""
    bp, gp, _ = alpha_coefficients(h, am, af, gamma, beta)
    for i in range(q.size):
        a_star[i] = (af * qdd[i] - am * a[i]) / (1 - am)
        q[i] += h * v[i] + h * h * ((0.5 - beta) * a[i] + beta * a_star[i])
        v[i] += h * ((1 - gamma) * a[i] + gamma * a_star[i])
        if keep_acceleration:
            q[i] += qdd[i] / bp
            v[i] += (gp / bp) * qdd[i]
        else:
            qdd[i] = 0.0


@njit(inline="always")
def alpha_correct(a, a_star, qdd, am, af):
    """The step's corrector: the algorithmic acceleration ``a = a* + (1 − α_f)/(1 − α_m) q̈``."""
    c_corr = (1 - af) / (1 - am)
    for i in range(a.size):
        a[i] = a_star[i] + c_corr * qdd[i]


@njit(inline="always")
def alpha_run(model, q, v, qdd, lam, fv, mode, r, data, run):
    """Up to ``run.n_steps`` gen-alpha steps of size ``run.h`` (settings and work arrays in
    ``run``, an :class:`AlphaRun`): predictor, modified-Newton iterations
    (Jacobian refreshed in place when needed), corrector, with ``run.velocity`` the velocity
    corrector (module docstring), post-step update; ``fv[k]`` holds
    the time-function values at the end of step k of this call. ``info`` (float, INFO_SIZE)
    carries between calls whether a factorisation is held (INFO_HAVE; set 0 when h changes),
    the stiffness scale of the rounding floor (INFO_KSCALE) and counters (factorisations,
    residual evaluations, iterations, velocity-corrector iterations); per call: iterations of
    the current step, errors, worst equation, steps completed, error code
    (``flexmbs.driver.ERR_*`` or ERR_SINGULAR).
    Refresh rules: within a step, when modified Newton contracts too slowly (:func:`_slow`);
    between steps, the renewal rule (:func:`flexmbs.steploop.renew_jacobian`).
    Returns a ``STATUS_*``.

    Inlined into :func:`flexmbs.kernel.kernel`, the one compiled entry (a call with more than
    30 arguments could not be inlined: Python passes them as ``*args``, hence ``run``). The
    position iterations and the velocity corrector share one call of the residual and one of
    the Jacobian (each inlines the whole model)."""
    (n_steps, h, am, af, gamma, beta, a, backup, factor, rhs, dx, a_star, max_it, full_newton,
     rtol, ctol, floor_factor, refresh_ratio, refresh_iterations, refresh_cost,
     keep_acceleration, info, velocity, factor_v, indptr, indices, velocity_rows,
     step_tolerance, retreats, hold) = run
    n = q.size
    m = lam.size
    bp, gp, s = alpha_coefficients(h, am, af, gamma, beta)
    info[INFO_DONE] = 0.0
    info[INFO_CODE] = 0.0
    info[INFO_STEP_ERR_MAX] = 0.0
    while info[INFO_DONE] < n_steps:
        fvk = fv[int(info[INFO_DONE])]
        for i in range(n):
            backup[0, i] = q[i]
            backup[1, i] = v[i]
            backup[2, i] = qdd[i]
            backup[3, i] = a[i]
        for i in range(m):
            backup[4, i] = lam[i]
        alpha_predict(q, v, qdd, a, a_star, h, am, af, gamma, beta, keep_acceleration)
        info[INFO_IT] = 0.0
        info[INFO_PREV] = np.inf
        info[INFO_STEP_ITS] = 0.0
        refreshes = 0
        holding = hold
        if hold:
            hold_contacts(model, HOLD_TRACKED)
        hold_updates = 0
        status = -1
        corrector = False       # the velocity corrector's iterations (q fixed)
        factored_v = False      # its matrix factorised at this step's q
        fac = factor
        err = np.inf
        alpha = 1.0             # the part of the last increment applied (retreats)
        while status < 0:
            scale, code = residual(model, q, v, qdd, lam, fvk, mode, r)
            info[INFO_RES] += 1.0
            if code != 0:
                if not corrector and info[INFO_IT] > 0 and alpha > 0.5 ** retreats:
                    # an iterate the model rejects (a beam axis through a bore wall): back
                    # towards the last accepted one by halving the increment, as
                    # solvers.newton.Newton._evaluate does
                    alpha *= 0.5
                    for i in range(n):
                        d = alpha * dx[i]
                        q[i] -= d
                        v[i] -= gp * d
                        qdd[i] -= bp * d
                    for i in range(m):
                        lam[i] -= alpha * dx[n + i] / s
                    continue
                info[INFO_CODE] = code
                status = STATUS_FAILED
                break
            alpha = 1.0
            if corrector and factored_v:
                constraint_velocity(indptr, indices, n, data, v, velocity_rows, 1.0 / gp, r)
            if not corrector or factored_v:
                tol = max(rtol * scale, floor_factor * info[INFO_KSCALE])
                eq = 0.0
                worst = 0
                for i in range(n):
                    e = abs(r[i]) / tol
                    if e > eq:
                        eq = e
                        worst = i
                ec = 0.0
                for i in range(m):
                    e = abs(r[n + i]) / ctol
                    if e > ec:
                        ec = e
                        if ec > eq:
                            worst = n + i
                err = max(eq, ec)
                info[INFO_ERR] = err
                info[INFO_WORST] = worst
                if not np.isfinite(err) or (err > 1.0 and info[INFO_IT] >= max_it):
                    status = STATUS_FAILED
                    break
                act = hold_action(err, hold_updates, hold_contacts(model, HOLD_READ)) \
                    if holding and not corrector else HOLD_KEEP
                if act != HOLD_KEEP:
                    # the held problem nearly solved, some gaps disagree with the set: the
                    # set becomes this iterate's contacts (its residual then the plain one)
                    hold_updates += 1
                    info[INFO_HOLD] += 1.0
                    holding = act != HOLD_OFF
                    hold_contacts(model, act)
                    continue
                if err <= 1.0:
                    if holding:
                        holding = False
                        hold_contacts(model, HOLD_OFF)
                    if velocity and not corrector:
                        # positions converged: the velocity corrector at this q
                        corrector = True
                        fac = factor_v
                        info[INFO_IT] = 0.0
                        continue
                    status = STATUS_CONVERGED
                    break
            if (corrector and not factored_v) or (not corrector and (
                    info[INFO_HAVE] == 0.0 or full_newton or (
                        info[INFO_IT] == 0 and info[INFO_RENEW] != 0.0) or (
                        info[INFO_IT] > 0 and _slow(err, info[INFO_PREV], refresh_ratio,
                                                    refresh_iterations)))):
                # Jacobian at the current iterate (poor contraction with the old one); the
                # corrector's: no stiffness (q fixed), its own factorisation, once per step
                if refreshes > 2 * max_it:
                    status = STATUS_FAILED
                    break
                kscale, code = jacobian(model, q, v, qdd, lam, fvk, mode, s * bp, s * gp,
                                        0.0 if corrector else s, data)
                if code != 0:
                    info[INFO_CODE] = code
                    status = STATUS_FAILED
                    break
                if kscale > 0.0:
                    info[INFO_KSCALE] = kscale
                pivot = bordered_factorize(fac, data)
                info[INFO_FACT] += 1.0
                refreshes += 1
                if pivot != 0:
                    if not corrector:
                        info[INFO_HAVE] = 0.0
                    info[INFO_PIVOT] = pivot
                    info[INFO_CODE] = ERR_SINGULAR
                    status = STATUS_FAILED
                    break
                if corrector:
                    factored_v = True
                    constraint_velocity(indptr, indices, n, data, v, velocity_rows, 1.0 / gp, r)
                else:
                    info[INFO_HAVE] = 1.0
                    info[INFO_RENEW] = 0.0
                    info[INFO_CYC_STEPS] = 0.0
                    info[INFO_CYC_ITS] = 0.0
                    info[INFO_STEP_ITS] = 0.0
            for i in range(n):
                rhs[i] = -s * r[i]
            for i in range(m):
                rhs[n + i] = -r[n + i]
            bordered_solve(fac, rhs, dx)
            for i in range(n):
                d = dx[i]
                if not corrector:
                    q[i] += d
                v[i] += gp * d
                qdd[i] += bp * d
            for i in range(m):
                lam[i] += dx[n + i] / s
            info[INFO_IT] += 1.0
            info[INFO_PREV] = err if not corrector or factored_v else np.inf
            if corrector:
                info[INFO_VEL_ITS] += 1.0
            else:
                info[INFO_STEP_ITS] += 1.0
                info[INFO_TOTAL] += 1.0
        if holding:
            hold_contacts(model, HOLD_OFF)
        if status == STATUS_FAILED:
            _restore(backup, q, v, qdd, a, lam)
            return STATUS_FAILED
        alpha_correct(a, a_star, qdd, am, af)
        if step_tolerance > 0.0:
            e = step_error(a, backup[3, :n], h, beta, gamma, step_tolerance)
            info[INFO_STEP_ERR] = e
            if e > 1.0:
                info[INFO_CODE] = ERR_STEP_ERROR
                _restore(backup, q, v, qdd, a, lam)
                return STATUS_FAILED
            info[INFO_STEP_ERR_MAX] = max(info[INFO_STEP_ERR_MAX], e)
        info[INFO_CYC_STEPS] += 1.0
        info[INFO_CYC_ITS] += info[INFO_STEP_ITS]
        if renew_jacobian(info[INFO_STEP_ITS], info[INFO_CYC_STEPS], info[INFO_CYC_ITS],
                          refresh_cost):
            info[INFO_RENEW] = 1.0
        code = post_step(model, q, v, qdd, a)
        if code == 0:
            info[INFO_DONE] += 1.0
            continue
        info[INFO_CODE] = code
        if stops_run(code):   # the step stands, the run stops (driver.STOPS_RUN)
            info[INFO_DONE] += 1.0
            return STATUS_STOPPED
        _restore(backup, q, v, qdd, a, lam)
        return STATUS_FAILED
    return STATUS_CONVERGED

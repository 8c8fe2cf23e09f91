"""Compiled inner loop of generalized-alpha for models made of beams and linear constraints.

One call runs the predictor and the modified-Newton iterations of a step entirely in numba:
residual evaluation (element kernel, scatter, linear constraints), the convergence test and the
banded triangular solves with the LU factors (LAPACK dgbtrf after a reverse Cuthill-McKee
reordering) computed at the last Jacobian refresh. Python
is re-entered only to refresh the Jacobian (assembly + SuperLU), so the per-iteration overhead is
that of compiled code. The arithmetic and the convergence test are those of
:mod:`flexmbs.solvers.newton` and :mod:`flexmbs.solvers.generalized_alpha`; the tests run both
paths on the same problems.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .._jit import njit
from ..elements.ancf_cable import _internal_kernel

STATUS_CONVERGED = 0
STATUS_REFRESH = 1
STATUS_FAILED = 2


class BandedLU:
    """LAPACK banded LU (dgbtrf, partial pivoting) of the iteration matrix after a reverse
    Cuthill-McKee reordering of its (fixed) pattern: beams with linear constraints give a
    narrow band, so factorisation and solves cost O(n) with tiny constants."""

    def __init__(self, A: sp.csc_matrix) -> None:
        from scipy.sparse.csgraph import reverse_cuthill_mckee

        n = A.shape[0]
        pattern = sp.csr_matrix((np.ones(A.nnz), A.indices, A.indptr), shape=A.shape).T.tocsr()
        pattern = pattern + pattern.T
        self.perm = np.ascontiguousarray(reverse_cuthill_mckee(pattern, symmetric_mode=True),
                                         dtype=np.int64)
        iperm = np.empty(n, np.int64)
        iperm[self.perm] = np.arange(n)
        cols = np.repeat(np.arange(n), np.diff(A.indptr))
        pi, pj = iperm[A.indices], iperm[cols]
        self.kl = int(max(0, (pi - pj).max()))
        self.ku = int(max(0, (pj - pi).max()))
        kv = self.kl + self.ku
        self.band_row = np.ascontiguousarray(kv + pi - pj, dtype=np.int64)
        self.band_col = np.ascontiguousarray(pj, dtype=np.int64)
        self.ab = np.zeros((2 * self.kl + self.ku + 1, n), order="F")
        self.piv = np.zeros(n, np.int32)
        self.work = np.zeros(n)
        self.n = n

    def factorize(self, data: np.ndarray) -> bool:
        """LU of the matrix with CSC ``data`` (pattern of construction). False if singular."""
        from scipy.linalg.lapack import dgbtrf

        fill_band(self.ab, self.band_row, self.band_col, data)
        lub, piv, info = dgbtrf(self.ab, self.kl, self.ku, overwrite_ab=1)
        if lub is not self.ab and not np.shares_memory(lub, self.ab):
            self.ab[:] = lub
        self.piv = np.ascontiguousarray(piv, dtype=np.int32)
        return info == 0

    def solve(self, b: np.ndarray) -> np.ndarray:
        x = np.empty_like(b)
        permuted_band_solve(self.ab, self.kl, self.ku, self.piv, self.perm, self.work, b, x)
        return x


@njit
def fill_band(ab, band_row, band_col, data):  # noqa: ANN001, ANN201
    ab[:, :] = 0.0
    for k in range(data.size):
        ab[band_row[k], band_col[k]] += data[k]


@njit
def band_solve(ab, kl, ku, piv, b):  # noqa: ANN001, ANN201
    """In-place solve with dgbtrf factors (LAPACK dgbtrs, no transpose; 0-based pivots)."""
    n = b.size
    kv = kl + ku
    if kl > 0:
        for j in range(n - 1):
            lm = min(kl, n - 1 - j)
            p = piv[j]
            if p != j:
                tmp = b[j]
                b[j] = b[p]
                b[p] = tmp
            bj = b[j]
            if bj != 0.0:
                for i in range(1, lm + 1):
                    b[j + i] -= ab[kv + i, j] * bj
    for j in range(n - 1, -1, -1):
        b[j] /= ab[kv, j]
        bj = b[j]
        if bj != 0.0:
            for i in range(max(0, j - kv), j):
                b[i] -= ab[kv + i - j, j] * bj


@njit
def permuted_band_solve(ab, kl, ku, piv, perm, work, b, x):  # noqa: ANN001, ANN201
    n = b.size
    for k in range(n):
        work[k] = b[perm[k]]
    band_solve(ab, kl, ku, piv, work)
    for k in range(n):
        x[perm[k]] = work[k]


@njit
def _residual(q, v, qdd, lam, f_ext, dofs, qe, ve, props, rest, scalar, force, mass,
              lin_p, lin_i, lin_x, lin_rhs, r, empty):  # noqa: ANN001, ANN201
    """r = [M q'' + Q_int - Q_ext + C^T lam ; C q - d]; returns the force scale (largest single
    force entering r_q), as Assembly.evaluate."""
    n = q.size
    scale = 0.0
    for i in range(n):
        r[i] = -f_ext[i]
        if abs(f_ext[i]) > scale:
            scale = abs(f_ext[i])
    ne = dofs.shape[0]
    for e in range(ne):
        for k in range(12):
            qe[e, k] = q[dofs[e, k]]
            ve[e, k] = v[dofs[e, k]]
    _internal_kernel(qe, ve, props, rest, scalar, False, False, force, empty, empty)
    for e in range(ne):
        for i in range(12):
            s = force[e, i]
            if abs(s) > scale:
                scale = abs(s)
            m = 0.0
            for j in range(12):
                m += mass[e, i, j] * qdd[dofs[e, j]]
            if abs(m) > scale:
                scale = abs(m)
            r[dofs[e, i]] += s + m
    m_lin = lin_rhs.size
    for row in range(m_lin):
        acc = -lin_rhs[row]
        lr = lam[row]
        for k in range(lin_p[row], lin_p[row + 1]):
            c = lin_i[k]
            acc += lin_x[k] * q[c]
            r[c] += lin_x[k] * lr
        r[n + row] = acc
    return scale


@njit
def _slow(err, err_prev, ratio, max_more):  # noqa: ANN001, ANN202
    """Modified Newton contracts too slowly: rate above ``ratio`` or more than ``max_more``
    further iterations predicted at the current rate (same rule as newton.Newton)."""
    rho = err / err_prev
    if rho > ratio:
        return True
    return np.log(err) > max_more * -np.log(rho)


@njit
def alpha_run(n_steps, resume, h, am, af, gamma, beta, q, v, qdd, a, lam, backup, f_ext, dofs,
              qe, ve, props, rest, scalar, force, mass, lin_p, lin_i, lin_x, lin_rhs,
              ab, kl, ku, piv, perm, have_factor, work,
              r, rhs, dx, a_star, max_it, full_newton, rtol, ctol, floor, refresh_ratio,
              refresh_iterations, info, empty):  # noqa: ANN001, ANN201
    """Up to ``n_steps`` gen-alpha steps of size ``h`` (constant loads and constraint values):
    predictor, modified-Newton iterations, corrector; FORMULATION Part I §6.1.

    ``info`` (float, 7): [iterations of the current step, previous error, last error, worst
    equation, steps completed in this call, total iterations, spare]. Returns
    STATUS_CONVERGED (all steps done), STATUS_REFRESH (the Jacobian must be refreshed at the
    current iterate of the current step; call again with ``resume``) or STATUS_FAILED (the
    current step was restored from ``backup`` (5, n_total) to its start).
    """
    n = q.size
    m = lam.size
    bp = (1 - am) / (h * h * beta * (1 - af))
    gp = gamma / (h * beta)
    s = beta * h * h
    c_corr = (1 - af) / (1 - am)
    info[4] = 0.0
    while info[4] < n_steps:
        if resume:
            fresh = True
            resume = False
        else:
            fresh = False
            for i in range(n):
                backup[0, i] = q[i]
                backup[1, i] = v[i]
                backup[2, i] = qdd[i]
                backup[3, i] = a[i]
            for i in range(m):
                backup[4, i] = lam[i]
            for i in range(n):
                # predictor of Arnold & Brüls: q''_{n+1} = 0, lam = lam_n. (q''_n as the
                # guess saves ~1 iteration per step but triggers more Jacobian refreshes.)
                a_star[i] = (af * qdd[i] - am * a[i]) / (1 - am)
                q[i] += h * v[i] + h * h * ((0.5 - beta) * a[i] + beta * a_star[i])
                v[i] += h * ((1 - gamma) * a[i] + gamma * a_star[i])
                qdd[i] = 0.0
            info[0] = 0.0
            info[1] = np.inf
        status = -1
        while status < 0:
            scale = _residual(q, v, qdd, lam, f_ext, dofs, qe, ve, props, rest, scalar, force,
                              mass, lin_p, lin_i, lin_x, lin_rhs, r, empty)
            tol = max(rtol * scale, floor)
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
            info[2] = err
            info[3] = worst
            if not np.isfinite(err) or (err > 1.0 and info[0] >= max_it):
                status = STATUS_FAILED
            elif err <= 1.0:
                status = STATUS_CONVERGED
            elif not have_factor:
                return STATUS_REFRESH
            elif (not fresh) and (full_newton or (info[0] > 0 and _slow(err, info[1], refresh_ratio,
                                                                        refresh_iterations))):
                return STATUS_REFRESH
            else:
                fresh = False
                for i in range(n):
                    rhs[i] = -s * r[i]
                for i in range(m):
                    rhs[n + i] = -r[n + i]
                for k in range(n + m):
                    work[k] = rhs[perm[k]]
                band_solve(ab, kl, ku, piv, work)
                for k in range(n + m):
                    dx[perm[k]] = work[k]
                for i in range(n):
                    d = dx[i]
                    q[i] += d
                    v[i] += gp * d
                    qdd[i] += bp * d
                for i in range(m):
                    lam[i] += dx[n + i] / s
                info[0] += 1.0
                info[5] += 1.0
                info[1] = err
        if status == STATUS_FAILED:
            for i in range(n):
                q[i] = backup[0, i]
                v[i] = backup[1, i]
                qdd[i] = backup[2, i]
                a[i] = backup[3, i]
            for i in range(m):
                lam[i] = backup[4, i]
            return STATUS_FAILED
        for i in range(n):
            a[i] = a_star[i] + c_corr * qdd[i]
        info[4] += 1.0
    return STATUS_CONVERGED

"""Rigid body in Cartesian coordinates with Euler parameters (Haug 1989 form; docs/theory.md §I.5).

Coordinates per body ``q_B = [r (3), p (4)]``: ``r`` is the centre of mass (global), and
``p = [e0, e1, e2, e3]`` the Euler parameters with ``pᵀp = 1`` (enforced by a constraint,
:class:`flexmbs.constraints.joints.EulerParameterNormalization`).

Conventions (docs/theory.md §I.5 / Haug; §II.0 calls the same matrices G and Ḡ):

- ``E(p) = [−e, ẽ + e0 I]`` (global angular velocity ``ω = 2Eṗ``),
  ``G(p) = [−e, −ẽ + e0 I]`` (body angular velocity ``ω′ = 2Gṗ``).
- ``A(p) = E Gᵀ = (e0² − eᵀe) I + 2(e eᵀ + e0 ẽ)``: the *homogeneous quadratic* form. It equals
  ``(2e0² − 1) I + 2(e eᵀ + e0 ẽ)`` on ``|p| = 1`` and makes ``A(p) s = pᵀ T(s) p`` an exact
  polynomial identity for any p, so ``∂(As)/∂p = 2 T(s) p`` is Haug's ``B(p, s)`` and
  ``∂²(As)_k/∂p² = 2 T_k(s)``.
- Residual convention ``M q̈ + Q_int + Φ_qᵀλ − Q_ext = 0``: :func:`inertial_residual` returns
  ``M q̈ − Q_v``; :func:`applied_force` / :func:`applied_torque_global` return ``Q_ext`` and its
  derivative (the assembler subtracts them).

All functions are stateless and batched: a leading axis ``nb`` over bodies (or any ``...``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from .._jit import njit
from ..terms import LOAD_FACTOR, WITH_INERTIA

if TYPE_CHECKING:  # pragma: no cover
    from ..terms import DofMap, FunctionTable

__all__ = [
    "skew",
    "normalize",
    "rotation_matrix",
    "rotation",
    "e_matrix",
    "g_matrix",
    "g_hat",
    "e_hat",
    "point_tensor",
    "point_tensor_of",
    "point_tensor_contract",
    "point_jacobian",
    "quaternion_from_matrix",
    "quaternion_from_axis_angle",
    "angular_velocity_global",
    "angular_velocity_body",
    "pdot_from_omega_global",
    "pdot_from_omega_body",
    "mass_matrix",
    "inertial_residual",
    "inertial_force_p",
    "inertial_derivatives",
    "kinetic_energy",
    "applied_force",
    "applied_torque_global",
    "applied_torque_body",
    "BodiesPart",
    "pack_bodies",
    "bodies_pattern",
    "bodies_residual",
    "bodies_jacobian",
]


# ---------------------------------------------------------------------------------------------
# matrix helpers
def inertia_tensor(inertia: object) -> np.ndarray:
    """The body-frame inertia tensor about the centre of mass from 3 principal moments or a
    3x3 matrix, checked: finite, symmetric, positive definite, and principal moments that a
    body can have (each <= the sum of the other two; a thin disc sits on the bound, so it is
    allowed a relative rounding of 1e-6). The one check of the API and the scenario reader;
    raises ValueError with the reason."""
    J = np.asarray(inertia, dtype=float)
    if J.shape == (3,):
        J = np.diag(J)
    if J.shape != (3, 3):
        raise ValueError(f"inertia must be 3 principal moments or a 3x3 matrix (got shape "
                         f"{J.shape})")
    if not np.all(np.isfinite(J)):
        raise ValueError("inertia must be finite numbers")
    if not np.allclose(J, J.T, rtol=1e-10, atol=1e-14 * np.abs(J).max()):
        raise ValueError("the inertia matrix must be symmetric")
    ev = np.linalg.eigvalsh(J)
    if not ev.min() > 0:
        raise ValueError(f"the inertia must be positive definite (principal moments "
                         f"{', '.join(f'{x:.6g}' for x in ev)})")
    if ev[2] > (ev[0] + ev[1]) * (1 + 1e-6):
        raise ValueError(f"principal moments {', '.join(f'{x:.6g}' for x in ev)} violate the "
                         "triangle inequality (each <= the sum of the other two): no rigid "
                         "body has them")
    return 0.5 * (J + J.T)


def skew(v: np.ndarray) -> np.ndarray:
    """(...,3) -> (...,3,3) with ``skew(a) @ b = a × b``."""
    v = np.asarray(v, dtype=float)
    out = np.zeros(v.shape + (3,))
    out[..., 0, 1] = -v[..., 2]
    out[..., 0, 2] = v[..., 1]
    out[..., 1, 0] = v[..., 2]
    out[..., 1, 2] = -v[..., 0]
    out[..., 2, 0] = -v[..., 1]
    out[..., 2, 1] = v[..., 0]
    return out


def normalize(p: np.ndarray) -> np.ndarray:
    """Project Euler parameters on the unit sphere, ``p / |p|`` (batched)."""
    p = np.asarray(p, dtype=float)
    return p / np.linalg.norm(p, axis=-1, keepdims=True)


def rotation_matrix(p: np.ndarray) -> np.ndarray:
    """docs/theory.md §I.5, homogeneous form ``A = E Gᵀ = (e0² − eᵀe)I + 2(eeᵀ + e0ẽ)`` (...,3,3);
    batched over the kernel :func:`rotation`."""
    p = np.asarray(p, dtype=float)
    if p.shape == (4,):
        return rotation(np.ascontiguousarray(p))
    flat = np.ascontiguousarray(p.reshape(-1, 4))
    out = np.empty((flat.shape[0], 3, 3))
    for i in range(flat.shape[0]):
        out[i] = rotation(flat[i])
    return out.reshape(p.shape[:-1] + (3, 3))


def e_matrix(p: np.ndarray) -> np.ndarray:
    """Haug 1989, docs/theory.md §I.5: ``E(p) = [−e, ẽ + e0 I]`` (...,3,4); global ``ω = 2Eṗ``."""
    p = np.asarray(p, dtype=float)
    out = np.empty(p.shape[:-1] + (3, 4))
    out[..., :, 0] = -p[..., 1:]
    out[..., :, 1:] = skew(p[..., 1:])
    for i in range(3):
        out[..., i, i + 1] += p[..., 0]
    return out


def g_matrix(p: np.ndarray) -> np.ndarray:
    """Haug 1989, docs/theory.md §I.5: ``G(p) = [−e, −ẽ + e0 I]`` (...,3,4); body ``ω′ = 2Gṗ``."""
    p = np.asarray(p, dtype=float)
    out = np.empty(p.shape[:-1] + (3, 4))
    out[..., :, 0] = -p[..., 1:]
    out[..., :, 1:] = -skew(p[..., 1:])
    for i in range(3):
        out[..., i, i + 1] += p[..., 0]
    return out


def g_hat(y: np.ndarray) -> np.ndarray:
    """docs/theory.md §I.5 ``Ĝ(y) = [[0, −yᵀ], [y, −ỹ]]`` (...,4,4), so that ``G(p)ᵀ y = Ĝ(y) p``."""
    y = np.asarray(y, dtype=float)
    out = np.zeros(y.shape[:-1] + (4, 4))
    out[..., 0, 1:] = -y
    out[..., 1:, 0] = y
    out[..., 1:, 1:] = -skew(y)
    return out


def e_hat(y: np.ndarray) -> np.ndarray:
    """``Ê(y) = [[0, −yᵀ], [y, ỹ]]`` (...,4,4), so that ``E(p)ᵀ y = Ê(y) p``."""
    y = np.asarray(y, dtype=float)
    out = np.zeros(y.shape[:-1] + (4, 4))
    out[..., 0, 1:] = -y
    out[..., 1:, 0] = y
    out[..., 1:, 1:] = skew(y)
    return out


@njit
def point_tensor_of(u):
    """Symmetric ``T_k(u)`` (3, 4, 4) with ``(A(p)u)_k = pᵀT_k(u)p`` for every p (A homogeneous)
    (:func:`point_tensor_into` a new array)."""
    T = np.empty((3, 4, 4))
    point_tensor_into(u, T)
    return T


@njit
def point_tensor_into(u, T):
    """:func:`point_tensor_of` written into ``T`` (3, 4, 4).

    Derivation [D]: ``Au = (e0² − eᵀe) u + 2e(eᵀu) + 2e0 (e × u)``, read off term by term.
    """
    for k in range(3):
        for i in range(4):
            for j in range(4):
                T[k, i, j] = 0.0
    for k in range(3):
        T[k, 0, 0] = u[k]
        for i in range(3):
            T[k, i + 1, i + 1] -= u[k]
            # 2 e_k (eᵀ u), split symmetrically
            T[k, k + 1, i + 1] += u[i]
            T[k, i + 1, k + 1] += u[i]
    # 2 e0 (e × u)_k: (e × u)_k = Σ_i (−ũ)_ki e_i
    for k, i, sgn, j in ((0, 1, 1.0, 2), (0, 2, -1.0, 1), (1, 0, -1.0, 2), (1, 2, 1.0, 0),
                         (2, 0, 1.0, 1), (2, 1, -1.0, 0)):
        T[k, 0, i + 1] = sgn * u[j]
        T[k, i + 1, 0] = sgn * u[j]


def point_tensor(s: np.ndarray) -> np.ndarray:
    """``T_k(s)`` (...,3,4,4) of :func:`point_tensor_of`, batched."""
    s = np.asarray(s, dtype=float)
    flat = np.ascontiguousarray(s.reshape(-1, 3))
    out = np.empty((flat.shape[0], 3, 4, 4))
    for i in range(flat.shape[0]):
        out[i] = point_tensor_of(flat[i])
    return out.reshape(s.shape[:-1] + (3, 4, 4))


def point_tensor_contract(s: np.ndarray, w: np.ndarray) -> np.ndarray:
    """``C(s, w) = Σ_k w_k T_k(s)`` (...,4,4), so that ``wᵀ A(p) s = pᵀ C p``."""
    return np.einsum("...k,...kij->...ij", np.asarray(w, dtype=float), point_tensor(s))


@njit(refcount=False)
def point_jacobian_of(T, p, B, Au):
    """Haug's ``B(p, u) = ∂(A(p)u)/∂p = 2T(u)p`` (3, 4) into ``B`` and ``A(p)u = pᵀT(u)p``
    (3,) into ``Au``, from the point tensor ``T = T(u)`` of :func:`point_tensor_of`; with a rate
    ``ṗ`` in place of p, ``B`` is ``2T(u)ṗ = ∂(B(p, u)ṗ)/∂p``. The one compiled statement of
    the rotated point's Euler-parameter derivative (the sliding joint, the contact pair and the
    exact contact tangent call it)."""
    for k in range(3):
        acc = 0.0
        for a in range(4):
            ta = 0.0
            for b in range(4):
                ta += T[k, a, b] * p[b]
            B[k, a] = 2.0 * ta
            acc += ta * p[a]
        Au[k] = acc


def point_jacobian(p: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Haug's ``B(p, s) = ∂(A(p)s)/∂p = 2 T(s) p`` (...,3,4), batched
    (:func:`point_jacobian_of`); equals ``−2A s̃ G + 2(As)pᵀ``."""
    p, s = np.asarray(p, dtype=float), np.asarray(s, dtype=float)
    batch = np.broadcast_shapes(p.shape[:-1], s.shape[:-1])
    pf = np.ascontiguousarray(np.broadcast_to(p, batch + (4,)).reshape(-1, 4))
    T = point_tensor(np.ascontiguousarray(np.broadcast_to(s, batch + (3,)).reshape(-1, 3)))
    out = np.empty((pf.shape[0], 3, 4))
    Au = np.empty(3)
    for i in range(pf.shape[0]):
        point_jacobian_of(T[i], pf[i], out[i], Au)
    return out.reshape(batch + (3, 4))


def quaternion_from_matrix(A: np.ndarray) -> np.ndarray:
    """Euler parameters (e0 ≥ 0) of rotation matrices (...,3,3) -> (...,4) (Shepperd 1978)."""
    A = np.asarray(A, dtype=float)
    batch = A.shape[:-2]
    R = A.reshape(-1, 3, 3)
    n = R.shape[0]
    tr = np.trace(R, axis1=1, axis2=2)
    cand = np.stack([tr, R[:, 0, 0], R[:, 1, 1], R[:, 2, 2]], axis=1)
    which = np.argmax(cand, axis=1)
    p = np.empty((n, 4))
    for b in range(n):
        Rb = R[b]
        i = which[b]
        if i == 0:
            e0 = 0.5 * np.sqrt(1.0 + tr[b])
            f = 0.25 / e0
            p[b] = (e0, (Rb[2, 1] - Rb[1, 2]) * f, (Rb[0, 2] - Rb[2, 0]) * f,
                    (Rb[1, 0] - Rb[0, 1]) * f)
        else:
            j, k = (i % 3), ((i + 1) % 3)  # cyclic successors of axis i-1
            a = i - 1
            ei = 0.5 * np.sqrt(max(1.0 + 2.0 * Rb[a, a] - tr[b], 0.0))
            f = 0.25 / ei
            q = np.empty(4)
            q[0] = (Rb[k, j] - Rb[j, k]) * f
            q[1 + a] = ei
            q[1 + j] = (Rb[a, j] + Rb[j, a]) * f
            q[1 + k] = (Rb[a, k] + Rb[k, a]) * f
            p[b] = q
    p *= np.where(p[:, :1] < 0.0, -1.0, 1.0)
    return p.reshape(batch + (4,))


def quaternion_from_axis_angle(axis: np.ndarray, angle: np.ndarray | float) -> np.ndarray:
    """``p = [cos(θ/2), sin(θ/2) u]`` for a rotation by θ about unit ``axis`` (...,3) -> (...,4)."""
    u = np.asarray(axis, dtype=float)
    u = u / np.linalg.norm(u, axis=-1, keepdims=True)
    h = 0.5 * np.asarray(angle, dtype=float)
    return np.concatenate([np.cos(h)[..., None] * np.ones(u.shape[:-1] + (1,)),
                           np.sin(h)[..., None] * u], axis=-1)


# ---------------------------------------------------------------------------------------------
# kinematics
def angular_velocity_global(p: np.ndarray, pd: np.ndarray) -> np.ndarray:
    """Haug 1989, docs/theory.md §I.5: ``ω = 2 E(p) ṗ`` (global components)."""
    return 2.0 * np.einsum("...ij,...j->...i", e_matrix(p), pd)


def angular_velocity_body(p: np.ndarray, pd: np.ndarray) -> np.ndarray:
    """Haug 1989, docs/theory.md §I.5: ``ω′ = 2 G(p) ṗ`` (body components)."""
    return 2.0 * np.einsum("...ij,...j->...i", g_matrix(p), pd)


def pdot_from_omega_global(p: np.ndarray, w: np.ndarray) -> np.ndarray:
    """``ṗ = ½ Eᵀ ω`` (satisfies ``pᵀṗ = 0``)."""
    return 0.5 * np.einsum("...ji,...j->...i", e_matrix(p), w)


def pdot_from_omega_body(p: np.ndarray, w_body: np.ndarray) -> np.ndarray:
    """``ṗ = ½ Gᵀ ω′`` (satisfies ``pᵀṗ = 0``)."""
    return 0.5 * np.einsum("...ji,...j->...i", g_matrix(p), w_body)


# ---------------------------------------------------------------------------------------------
# inertia
def mass_matrix(mass: np.ndarray, inertia: np.ndarray, p: np.ndarray) -> np.ndarray:
    """docs/theory.md §I.5: ``M = diag(m I3, 4 GᵀJ′G)`` (nb,7,7); singular along p (see Φ^p)."""
    mass = np.ascontiguousarray(mass, dtype=float)
    inertia = np.ascontiguousarray(inertia, dtype=float)
    p = np.ascontiguousarray(p, dtype=float)
    M = np.zeros((mass.shape[0], 7, 7))
    Mpp = np.empty((4, 4))
    for b in range(mass.shape[0]):
        for i in range(3):
            M[b, i, i] = mass[b]
        rotational_mass(inertia[b], p[b], Mpp)
        M[b, 3:, 3:] = Mpp
    return M


def inertial_residual(mass: np.ndarray, inertia: np.ndarray, p: np.ndarray, pd: np.ndarray,
                      qdd: np.ndarray, out_r: np.ndarray, out_dq: np.ndarray,
                      out_dv: np.ndarray) -> None:
    """docs/theory.md §I.5: ``r = [m r̈ ; 4GᵀJ′G p̈ − 8ĠᵀJ′Ġ p]`` (= M q̈ − Q_v), Ġ = G(ṗ).

    Writes (overwrites) ``out_r`` (nb,7), ``out_dq = ∂r/∂q`` (nb,7,7, only the p-p block is
    nonzero) and ``out_dv = ∂r/∂q̇`` (nb,7,7, p-p block). ``∂r/∂q̈`` is :func:`mass_matrix`.
    Batched wrapper of the kernels :func:`inertial_force_p` and :func:`inertial_derivatives`.
    """
    mass = np.asarray(mass, dtype=float)
    inertia = np.ascontiguousarray(inertia, dtype=float)
    p = np.ascontiguousarray(p, dtype=float)
    pd = np.ascontiguousarray(pd, dtype=float)
    qdd = np.ascontiguousarray(qdd, dtype=float)
    Q = np.empty(4)
    dq = np.empty((4, 4))
    dv = np.empty((4, 4))
    out_dq[...] = 0.0
    out_dv[...] = 0.0
    for b in range(mass.shape[0]):
        pdd = np.ascontiguousarray(qdd[b, 3:])
        inertial_force_p(inertia[b], p[b], pd[b], pdd, Q)
        inertial_derivatives(inertia[b], p[b], pd[b], pdd, dq, dv)
        out_r[b, :3] = mass[b] * qdd[b, :3]
        out_r[b, 3:] = Q
        out_dq[b, 3:, 3:] = dq
        out_dv[b, 3:, 3:] = dv


@njit
def rotation(p):
    """``A(p)`` (3, 3), the homogeneous rotation matrix of docs/theory.md §I.5 (:func:`rotation_into`)."""
    A = np.empty((3, 3))
    rotation_into(p, A)
    return A


@njit
def rotation_into(p, A):
    """``A(p)`` into ``A`` (3, 3), the homogeneous rotation matrix of docs/theory.md §I.5 (the one
    statement)."""
    e0, e1, e2, e3 = p[0], p[1], p[2], p[3]
    d = e0 * e0 - e1 * e1 - e2 * e2 - e3 * e3
    A[0, 0] = d + 2 * e1 * e1
    A[1, 1] = d + 2 * e2 * e2
    A[2, 2] = d + 2 * e3 * e3
    A[0, 1] = 2 * (e1 * e2 - e0 * e3)
    A[1, 0] = 2 * (e1 * e2 + e0 * e3)
    A[0, 2] = 2 * (e1 * e3 + e0 * e2)
    A[2, 0] = 2 * (e1 * e3 - e0 * e2)
    A[1, 2] = 2 * (e2 * e3 - e0 * e1)
    A[2, 1] = 2 * (e2 * e3 + e0 * e1)


@njit(refcount=False)
def _g_times(p, x):
    """``G(p) x`` (a 3-tuple), ``G(p) = [−e, −ẽ + e0 I]``; p, x 4-vectors (arrays or tuples).
    ``G(p) x = −G(x) p``."""
    return (-p[1] * x[0] + p[0] * x[1] + p[3] * x[2] - p[2] * x[3],
            -p[2] * x[0] - p[3] * x[1] + p[0] * x[2] + p[1] * x[3],
            -p[3] * x[0] + p[2] * x[1] - p[1] * x[2] + p[0] * x[3])


@njit(refcount=False)
def _gt_times(p, y):
    """``G(p)ᵀ y = Ĝ(y) p`` (a 4-tuple), ``Ĝ(y) = [[0, −yᵀ], [y, −ỹ]]`` (docs/theory.md §I.5)."""
    return (-p[1] * y[0] - p[2] * y[1] - p[3] * y[2],
            p[0] * y[0] - p[3] * y[1] + p[2] * y[2],
            p[3] * y[0] + p[0] * y[1] - p[1] * y[2],
            -p[2] * y[0] + p[1] * y[1] + p[0] * y[2])


@njit(refcount=False)
def _j_times(J, x):
    """``J x`` (a 3-tuple) for the 3 × 3 inertia J and a 3-vector (array or tuple)."""
    return (J[0, 0] * x[0] + J[0, 1] * x[1] + J[0, 2] * x[2],
            J[1, 0] * x[0] + J[1, 1] * x[1] + J[1, 2] * x[2],
            J[2, 0] * x[0] + J[2, 1] * x[1] + J[2, 2] * x[2])


@njit(refcount=False)
def _unit(j):
    """The j-th unit 4-vector (a tuple): column j of a 4-column product."""
    return (1.0 if j == 0 else 0.0, 1.0 if j == 1 else 0.0, 1.0 if j == 2 else 0.0,
            1.0 if j == 3 else 0.0)


@njit(refcount=False)
def inertial_force_p(J, p, pd, pdd, out):
    """docs/theory.md §I.5: the p rows of ``M q̈ − Q_v``, ``4GᵀJ′G p̈ − 8ĠᵀJ′Ġ p`` (Ġ = G(ṗ)),
    into ``out`` (4,); no scratch arrays."""
    a = _gt_times(p, _j_times(J, _g_times(p, pdd)))
    b = _gt_times(pd, _j_times(J, _g_times(pd, p)))
    out[0] = 4.0 * a[0] - 8.0 * b[0]
    out[1] = 4.0 * a[1] - 8.0 * b[1]
    out[2] = 4.0 * a[2] - 8.0 * b[2]
    out[3] = 4.0 * a[3] - 8.0 * b[3]


@njit(refcount=False)
def inertial_derivatives(J, p, pd, pdd, dq, dv):
    """∂/∂p and ∂/∂ṗ (4, 4) of :func:`inertial_force_p` into ``dq``, ``dv``, by the Ĝ identities
    of docs/theory.md §I.5: ``∂(4GᵀJ′Gp̈)/∂p = 4[Ĝ(J′Gp̈) − GᵀJ′G(p̈)]``,
    ``∂(8ĠᵀJ′Ġp)/∂p = 8ĠᵀJ′Ġ``, ``∂(8ĠᵀJ′Ġp)/∂ṗ = 8[Ĝ(J′Ġp) − ĠᵀJ′G]``; column by column."""
    y = _j_times(J, _g_times(p, pdd))
    u = _j_times(J, _g_times(pd, p))
    for j in range(4):
        e = _unit(j)
        gy = _gt_times(e, y)                                # Ĝ(y) e_j = G(e_j)ᵀ y
        gu = _gt_times(e, u)
        c1 = _gt_times(p, _j_times(J, _g_times(pdd, e)))    # GᵀJ′G(p̈) e_j
        c2 = _gt_times(pd, _j_times(J, _g_times(pd, e)))    # ĠᵀJ′Ġ e_j
        c3 = _gt_times(pd, _j_times(J, _g_times(p, e)))     # ĠᵀJ′G e_j
        for i in range(4):
            dq[i, j] = 4.0 * (gy[i] - c1[i]) - 8.0 * c2[i]
            dv[i, j] = -8.0 * (gu[i] - c3[i])


def kinetic_energy(mass: np.ndarray, inertia: np.ndarray, p: np.ndarray,
                   v: np.ndarray) -> np.ndarray:
    """Haug 1989, docs/theory.md §I.5: ``T = ½ m ṙᵀṙ + 2 ṗᵀGᵀJ′Gṗ`` (nb,)."""
    v = np.asarray(v, dtype=float)
    wb = np.einsum("bij,bj->bi", g_matrix(p), v[:, 3:])       # = ω′/2
    return (0.5 * np.asarray(mass, dtype=float) * np.einsum("bi,bi->b", v[:, :3], v[:, :3])
            + 2.0 * np.einsum("bi,bij,bj->b", wb, inertia, wb))


# ---------------------------------------------------------------------------------------------
# applied loads (Q_ext; forces and torques fixed in the global frame)
def applied_force(p: np.ndarray, s: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """docs/theory.md §I.5, force F (global) at body point s′: ``Q_r = F``, ``Q_p = BᵀF = 2C(s′,F)p``.

    ``B = ∂(As′)/∂p`` of the homogeneous A, so ``Q·δq = F·δx_P`` holds exactly to first order
    for every δq (not only tangent ones); it differs from ``2Gᵀ(s′ × AᵀF)`` by a multiple of p.
    Returns ``Q`` (nb,7) and ``dQ_dq`` (nb,7,7) with p-p block ``2 C(s′, F)`` (symmetric).
    Batched wrapper of the kernels :func:`point_force_p` / :func:`point_force_dp`.
    """
    F = np.ascontiguousarray(F, dtype=float)
    T = np.ascontiguousarray(point_tensor(np.broadcast_to(np.asarray(s, float), F.shape)))
    p = np.ascontiguousarray(p, dtype=float)
    nb = F.shape[0]
    Q = np.zeros((nb, 7))
    dQ = np.zeros((nb, 7, 7))
    Qp = np.empty(4)
    dQp = np.empty((4, 4))
    for b in range(nb):
        Q[b, :3] = F[b]
        point_force_p(T[b], F[b], 1.0, p[b], Qp)
        point_force_dp(T[b], F[b], 1.0, dQp)
        Q[b, 3:] = Qp
        dQ[b, 3:, 3:] = dQp
    return Q, dQ


def applied_torque_global(p: np.ndarray, n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Global torque n: ``Q_p = 2Eᵀn = 2Ê(n)p`` (docs/theory.md §I.5); returns (Q, dQ_dq).
    Batched wrapper of the kernels :func:`torque_p` / :func:`torque_dp`."""
    n = np.ascontiguousarray(n, dtype=float)
    p = np.ascontiguousarray(p, dtype=float)
    nb = n.shape[0]
    Q = np.zeros((nb, 7))
    dQ = np.zeros((nb, 7, 7))
    Qp = np.empty(4)
    dQp = np.empty((4, 4))
    for b in range(nb):
        torque_p(n[b], 1.0, p[b], Qp)
        torque_dp(n[b], 1.0, dQp)
        Q[b, 3:] = Qp
        dQ[b, 3:, 3:] = dQp
    return Q, dQ


def applied_torque_body(p: np.ndarray, n_body: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Body-fixed torque n′: ``Q_p = 2Gᵀn′ = 2Ĝ(n′)p`` (docs/theory.md §I.5); returns (Q, dQ_dq)."""
    n_body = np.asarray(n_body, dtype=float)
    Gh = g_hat(n_body)
    nb = n_body.shape[0]
    Q = np.zeros((nb, 7))
    Q[:, 3:] = 2.0 * np.einsum("bij,bj->bi", Gh, p)
    dQ = np.zeros((nb, 7, 7))
    dQ[:, 3:, 3:] = 2.0 * Gh
    return Q, dQ


# ---------------------------------------------------------------------------------------------
# kernels shared by every path (one statement of each equation)
@njit(refcount=False)
def rotational_mass(J, p, out):
    """``4 GᵀJ′G`` (4, 4), the Euler-parameter block of the body mass matrix (docs/theory.md §I.5),
    column by column."""
    for j in range(4):
        c = _gt_times(p, _j_times(J, _g_times(p, _unit(j))))
        for i in range(4):
            out[i, j] = 4.0 * c[i]


@njit(refcount=False)
def point_force_p(T, F, f, p, out):
    """``Q_p = 2 f C(s′, F) p`` with ``C = Σ_k F_k T_k(s′)`` (docs/theory.md §I.5, applied force)."""
    for a in range(4):
        acc = 0.0
        for b in range(4):
            cab = 0.0
            for c in range(3):
                cab += F[c] * T[c, a, b]
            acc += cab * p[b]
        out[a] = 2.0 * f * acc


@njit(refcount=False)
def point_force_dp(T, F, f, out):
    """``∂Q_p/∂p = 2 f C(s′, F)`` (4, 4) of :func:`point_force_p`."""
    for a in range(4):
        for b in range(4):
            cab = 0.0
            for c in range(3):
                cab += F[c] * T[c, a, b]
            out[a, b] = 2.0 * f * cab


@njit(refcount=False)
def torque_p(n, f, p, out):
    """Global torque f·n: ``Q_p = 2 f Eᵀn = 2 f Ê(n)p``, ``Ê(n) = [[0, −nᵀ], [n, ñ]]``
    (docs/theory.md §I.5)."""
    out[0] = -2.0 * f * (n[0] * p[1] + n[1] * p[2] + n[2] * p[3])
    out[1] = 2.0 * f * (n[0] * p[0] - n[2] * p[2] + n[1] * p[3])
    out[2] = 2.0 * f * (n[1] * p[0] + n[2] * p[1] - n[0] * p[3])
    out[3] = 2.0 * f * (n[2] * p[0] - n[1] * p[1] + n[0] * p[2])


@njit
def torque_dp(n, f, out):
    """``∂Q_p/∂p = 2 f Ê(n)`` (4, 4) of :func:`torque_p`."""
    e = np.zeros(4)
    col = np.empty(4)
    for b in range(4):
        e[:] = 0.0
        e[b] = 1.0
        torque_p(n, f, e, col)
        for a in range(4):
            out[a, b] = col[a]


# ---------------------------------------------------------------------------------------------
# the rigid-body term of the assembler (flexmbs.terms): inertia and body loads
class BodiesPart(NamedTuple):
    """All rigid bodies and the loads applied at body points, packed for the kernels."""

    dofs: np.ndarray                 # (nb, 7) [r, p]
    mass: np.ndarray                 # (nb,)
    inertia: np.ndarray              # (nb, 3, 3)
    pos: np.ndarray                  # (nb, 49) matrix positions of the body blocks
    load_body: np.ndarray            # (nl,) body of each load
    load_T: np.ndarray               # (nl, 3, 4, 4) point tensor of the load point
    load_force: np.ndarray           # (nl, 3) global force (per unit of its time function)
    load_moment: np.ndarray          # (nl, 3) global moment (zeros: none)
    load_fn: np.ndarray              # (nl,) time-function index
    p: np.ndarray                    # work (4,): one body's p, ṗ, p̈
    pd: np.ndarray
    pdd: np.ndarray
    dq: np.ndarray                   # work (4, 4): ∂/∂p, ∂/∂ṗ of the inertial force, M_pp
    dv: np.ndarray
    Mpp: np.ndarray
    Q: np.ndarray                    # work (4,): generalized force on p
    Q2: np.ndarray


def bodies_pattern(bodies: list, dofs: DofMap) -> list[tuple[np.ndarray, np.ndarray]]:
    """The 7×7 block of every body."""
    return [(dofs.body_dofs(b), dofs.body_dofs(b)) for b in bodies]


def pack_bodies(bodies: list, loads: list, dofs: DofMap, functions: FunctionTable) -> BodiesPart:
    """``loads``: (body, point (body frame), force, moment or None, time function) per load."""
    nb, nl = len(bodies), len(loads)
    index = {id(b): i for i, b in enumerate(bodies)}
    table = np.array([dofs.body_dofs(b) for b in bodies], dtype=np.int64).reshape(nb, 7)
    pos = np.array([dofs.positions(d, d) for d in table], dtype=np.int64).reshape(nb, 49)
    c = np.ascontiguousarray
    return BodiesPart(
        dofs=c(table),
        mass=np.array([b.mass for b in bodies], float),
        inertia=c(np.array([b.inertia for b in bodies], float).reshape(nb, 3, 3)),
        pos=c(pos),
        load_body=np.array([index[id(b)] for b, *_ in loads], dtype=np.int64),
        load_T=c(point_tensor(np.array([np.zeros(3) if pt is None else pt for _, pt, *_ in loads], float)
                                 .reshape(nl, 3))),
        load_force=c(np.array([f for _, _, f, _, _ in loads], float).reshape(nl, 3)),
        load_moment=c(np.array([np.zeros(3) if m is None else m for _, _, _, m, _ in loads], float)
                      .reshape(nl, 3)),
        load_fn=np.array([functions(fn) for *_, fn in loads], dtype=np.int64),
        p=np.zeros(4),
        pd=np.zeros(4),
        pdd=np.zeros(4),
        dq=np.zeros((4, 4)),
        dv=np.zeros((4, 4)),
        Mpp=np.zeros((4, 4)),
        Q=np.zeros(4),
        Q2=np.zeros(4))


@njit(inline="always")
def _gather(b, i, q, v, qdd, rates):
    """Body i's p (and with ``rates`` ṗ, p̈) into the part's work vectors."""
    for k in range(4):
        j = b.dofs[i, 3 + k]
        b.p[k] = q[j]
        if rates:
            b.pd[k] = v[j]
            b.pdd[k] = qdd[j]


@njit(refcount=False, internal=True)
def bodies_residual(b, q, v, qdd, fv, mode, r):
    """``r_q += M q̈ − Q_v`` (with inertia, :func:`inertial_force_p`) ``− Q_ext`` of the body
    loads (docs/theory.md §I.5); returns the largest single force."""
    if b is None:   # none in the model: compiled to nothing (driver.OPTIONAL_KINDS)
        return 0.0
    scale = 0.0
    if mode[WITH_INERTIA] != 0.0:
        for i in range(b.dofs.shape[0]):
            for c in range(3):
                j = b.dofs[i, c]
                f = b.mass[i] * qdd[j]
                r[j] += f
                scale = max(scale, abs(f))
            _gather(b, i, q, v, qdd, True)
            inertial_force_p(b.inertia[i], b.p, b.pd, b.pdd, b.Q)
            for k in range(4):
                r[b.dofs[i, 3 + k]] += b.Q[k]
                scale = max(scale, abs(b.Q[k]))
    for i in range(b.load_body.size):
        d = b.dofs[b.load_body[i]]
        f = mode[LOAD_FACTOR] * fv[b.load_fn[i]]
        for k in range(4):
            b.p[k] = q[d[3 + k]]
        for c in range(3):
            F = f * b.load_force[i, c]
            r[d[c]] -= F
            if abs(F) > scale:
                scale = abs(F)
        point_force_p(b.load_T[i], b.load_force[i], f, b.p, b.Q)
        mo = b.load_moment[i]
        if mo[0] != 0.0 or mo[1] != 0.0 or mo[2] != 0.0:
            torque_p(mo, f, b.p, b.Q2)
            for k in range(4):
                b.Q[k] += b.Q2[k]
        for k in range(4):
            r[d[3 + k]] -= b.Q[k]
            if abs(b.Q[k]) > scale:
                scale = abs(b.Q[k])
    return scale


@njit(refcount=False, internal=True)
def bodies_jacobian(b, q, v, qdd, fv, mode, cM, cC, cK, data):
    """``cM M + cC ∂r/∂q̇ + cK ∂r/∂q`` of :func:`bodies_residual` into the CSC ``data`` (without
    inertia, e.g. in statics, only ``cM M``: the optional mass-proportional stabiliser); only
    the nonzero entries (the r rows: ``cM m I``; the p-p block)."""
    if b is None:   # none in the model: compiled to nothing (driver.OPTIONAL_KINDS)
        return
    inertia = mode[WITH_INERTIA] != 0.0
    if inertia or cM != 0.0:
        for i in range(b.dofs.shape[0]):
            _gather(b, i, q, v, qdd, inertia)
            rotational_mass(b.inertia[i], b.p, b.Mpp)
            if inertia:
                inertial_derivatives(b.inertia[i], b.p, b.pd, b.pdd, b.dq, b.dv)
            pos = b.pos[i]
            for c in range(3):
                data[pos[8 * c]] += cM * b.mass[i]
            for a in range(4):
                for c in range(4):
                    val = 0.0
                    if inertia:
                        val = cC * b.dv[a, c] + cK * b.dq[a, c]
                    val += cM * b.Mpp[a, c]
                    data[pos[7 * (3 + a) + 3 + c]] += val
    for i in range(b.load_body.size):
        f = mode[LOAD_FACTOR] * fv[b.load_fn[i]]
        pos = b.pos[b.load_body[i]]
        point_force_dp(b.load_T[i], b.load_force[i], f, b.Mpp)
        for a in range(4):
            for c in range(4):
                data[pos[7 * (3 + a) + 3 + c]] -= cK * b.Mpp[a, c]
        mo = b.load_moment[i]
        if mo[0] != 0.0 or mo[1] != 0.0 or mo[2] != 0.0:
            torque_dp(mo, f, b.Mpp)
            for a in range(4):
                for c in range(4):
                    data[pos[7 * (3 + a) + 3 + c]] -= cK * b.Mpp[a, c]

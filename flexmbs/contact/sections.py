"""2D hole sections and the common-normal contact detector (FORMULATION II §3, §6).

Section coordinates are ``(y, z)`` with the hole centre at the origin. The beam cuts the section
plane in an ellipse (:class:`Ellipse2D`, FORMULATION II §2). A hole section reports every
stationary point of the penetration of that ellipse through its boundary (:meth:`candidates`):
local maxima (``kind=+1``) are contact points, local minima (``kind=-1``) enter the force with the
opposite sign (continuity rule, FORMULATION II §3).

Pluggable (DESIGN.md "Pluggable parts"): a :class:`HoleSection` provides ``boundary(psi)`` and the
generic detector of §6 (sample the common-normal residual F(ψ), bracket, safeguarded Newton). The
circle overrides it with the closed-form quartic of §3. :data:`HOLE_SECTIONS` (a
:class:`~flexmbs.registry.Registry`) maps the scenario names (``hole = { shape = ... }``) to
classes; :func:`get_section` builds one by name, and the scenario reader uses the same registry.
A new shape is a :class:`HoleSection` subclass registered with ``@HOLE_SECTIONS.register(name)``;
its dataclass fields are its parameters, in Python and as scenario keys.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass, field

import numpy as np

from .._jit import njit
from ..elements.centerline import bracketed_newton_step
from ..errors import ModelError
from ..registry import Registry

__all__ = [
    "Ellipse2D",
    "Candidate",
    "HoleSection",
    "CircleSection",
    "SuperellipseSection",
    "HOLE_SECTIONS",
    "SECTION_TYPES",
    "get_section",
    "two_point_possible",
    "inside_evolute",
    "jamming",
    "circle_stationary_points",
    "trig_quadratic_roots",
]


@dataclass(frozen=True)
class Ellipse2D:
    """Beam section ellipse ``X(φ) = c + a cos φ e_a + b sin φ e_b`` (FORMULATION II §2–§3)."""

    center: np.ndarray   #: (2,) centre c (beam centreline crossing) in section coordinates
    e_a: np.ndarray      #: (2,) unit major axis
    a: float             #: major semi-axis (a ≥ b)
    b: float             #: minor semi-axis (b > 0)

    def __post_init__(self) -> None:
        c = np.asarray(self.center, dtype=float).reshape(2)
        ea = np.asarray(self.e_a, dtype=float).reshape(2)
        nrm = math.hypot(ea[0], ea[1])
        if not nrm > 0.0:
            raise ModelError("Ellipse2D: e_a must be a nonzero vector")
        if not (self.b > 0.0 and self.a >= self.b * (1.0 - 1e-12)):
            raise ModelError(f"Ellipse2D: need a >= b > 0 (got a={self.a}, b={self.b})")
        object.__setattr__(self, "center", c)
        object.__setattr__(self, "e_a", ea / nrm)
        object.__setattr__(self, "a", float(self.a))
        object.__setattr__(self, "b", float(self.b))

    @property
    def e_b(self) -> np.ndarray:
        """Minor axis ``rot90(e_a)``."""
        return np.array([-self.e_a[1], self.e_a[0]])

    def point(self, phi: np.ndarray | float) -> np.ndarray:
        """``X(φ)`` (..., 2)."""
        phi = np.asarray(phi, dtype=float)
        return (self.center + (self.a * np.cos(phi))[..., None] * self.e_a
                + (self.b * np.sin(phi))[..., None] * self.e_b)

    def angle_of(self, X: np.ndarray) -> float:
        """Ellipse angle φ of a point X on the ellipse."""
        d = np.asarray(X, dtype=float) - self.center
        return math.atan2(float(d @ self.e_b) / self.b, float(d @ self.e_a) / self.a)

    def support(self, N: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Support point and map (FORMULATION II §6): ``X(N) = c + ΣN/√(NᵀΣN)`` and
        ``J_E = (Σ − ΣNNᵀΣ/NᵀΣN)/√(NᵀΣN)`` for unit normals ``N (..., 2)``."""
        N = np.asarray(N, dtype=float)
        ea, eb = self.e_a, self.e_b
        Sig = self.a**2 * np.outer(ea, ea) + self.b**2 * np.outer(eb, eb)
        SN = N @ Sig
        q = np.einsum("...i,...i->...", N, SN)
        sq = np.sqrt(q)
        X = self.center + SN / sq[..., None]
        J = (Sig - SN[..., :, None] * SN[..., None, :] / q[..., None, None]) / sq[..., None, None]
        return X, J


@dataclass(frozen=True)
class Candidate:
    """One stationary point of the section penetration (FORMULATION II §3/§6)."""

    phi: float           #: ellipse angle of X
    X: np.ndarray        #: (2,) beam-ellipse point
    Q: np.ndarray        #: (2,) hole boundary point (hole point of FORMULATION II §4)
    normal: np.ndarray   #: (2,) outward hole normal at Q (from the bore into the hole material)
    depth: float         #: penetration along the normal, > 0 = penetrating
    kind: int            #: +1 local max of penetration (contact point), −1 local min
    psi: float = field(default=math.nan)  #: boundary parameter of Q (generic detector only)


# ---------------------------------------------------------------------------------------------
class HoleSection(ABC):
    """Convex C¹ hole cross-section (DESIGN.md "Pluggable parts", FORMULATION II §6)."""

    #: number of samples of F(ψ) in the generic detector (≥ 64, FORMULATION II §6)
    samples: int = 128

    @abstractmethod
    def boundary(self, psi: np.ndarray | float
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(Y, N, T, speed, curvature)`` at parameter ψ ∈ [0, 2π): point, outward unit normal,
        CCW unit tangent, ``|Y_ψ|``, curvature κ ≥ 0 (shapes ``(..., 2)`` / ``(...)``)."""

    @abstractmethod
    def bounding_radius(self) -> float:
        """Radius of the smallest centred circle containing the section (broad phase)."""

    @abstractmethod
    def inscribed_radius(self) -> float:
        """Radius of the largest centred circle inside the section (broad phase)."""

    def compiled_shape(self) -> tuple[int, np.ndarray] | None:
        """``(kind, params)`` of the compiled boundary kernel (:func:`section_boundary`), or
        None: the joint then runs this section's Python detector."""
        return None

    def candidates(self, ellipse: Ellipse2D, margin: float = 0.0) -> list[Candidate]:
        """All stationary points of the penetration with ``depth > −margin`` (FORMULATION II §6).

        Generic detector: common-normal residual ``F(ψ) = T·(X(N(ψ)) − Y(ψ))`` sampled at
        ``self.samples`` points, sign changes bracketed, safeguarded Newton with
        ``F' = |Y_ψ|[κ(TᵀJ_E T − d) − 1]``; ``F' < 0`` is a maximum of ``d = N·(X − Y)``.
        """
        c = ellipse.center
        if math.hypot(c[0], c[1]) + ellipse.a < self.inscribed_radius() - margin:
            return []  # broad phase: the ellipse is strictly inside the inscribed circle
        m = max(int(self.samples), 64)
        psi = np.linspace(0.0, 2.0 * np.pi, m, endpoint=False)
        F, _, _ = self._residual(ellipse, psi)
        out: list[Candidate] = []
        for i in range(m):
            j = (i + 1) % m
            if F[i] == 0.0 or F[i] * F[j] < 0.0:
                lo = psi[i]
                hi = psi[i] + 2.0 * np.pi / m
                root = self._bracketed_root(ellipse, lo, hi, F[i])
                if root is not None:
                    cand = self._candidate(ellipse, root)
                    if cand.depth > -margin:
                        out.append(cand)
        return out

    # --- generic helpers -------------------------------------------------------------------
    def _residual(self, ellipse: Ellipse2D, psi: np.ndarray | float
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``F(ψ)``, ``F'(ψ)`` and ``d(ψ)`` (FORMULATION II §6)."""
        Y, N, T, speed, kappa = self.boundary(psi)
        X, J = ellipse.support(N)
        F = np.einsum("...i,...i->...", T, X - Y)
        d = np.einsum("...i,...i->...", N, X - Y)
        rho = np.einsum("...i,...ij,...j->...", T, J, T)
        dF = speed * (kappa * (rho - d) - 1.0)
        return F, dF, d

    def _bracketed_root(self, ellipse: Ellipse2D, lo: float, hi: float, flo: float
                        ) -> float | None:
        s = 0.5 * (lo + hi)
        tol = 1e-13 * max(1.0, self.bounding_radius())
        for _ in range(60):
            F, dF, _ = self._residual(ellipse, s)
            f = float(F)
            df = float(dF)
            if abs(f) <= tol:
                return s
            if (f < 0.0) == (flo < 0.0):
                lo, flo = s, f
            else:
                hi = s
            s_new = s - f / df if df != 0.0 else 0.5 * (lo + hi)
            if not (lo < s_new < hi):
                s_new = 0.5 * (lo + hi)
            if hi - lo < 1e-15:
                return s_new
            s = s_new
        return s

    def _candidate(self, ellipse: Ellipse2D, psi: float) -> Candidate:
        Y, N, T, speed, kappa = self.boundary(psi)
        X, J = ellipse.support(N)
        d = float(N @ (X - Y))
        dF = float(speed * (kappa * (T @ J @ T - d) - 1.0))
        return Candidate(phi=ellipse.angle_of(X) % (2.0 * np.pi), X=X, Q=np.asarray(Y, dtype=float),
                         normal=np.asarray(N, dtype=float), depth=d,
                         kind=1 if dF < 0.0 else -1, psi=float(psi % (2.0 * np.pi)))


# ---------------------------------------------------------------------------------------------
@njit
def _trig_f(phi, al, be, ga):  # noqa: ANN001, ANN202
    """``f = al sin φ cos φ + be sin φ + ga cos φ`` and ``f′`` (the stationarity condition of a
    quadratic trigonometric polynomial, FORMULATION II §3)."""
    s = math.sin(phi)
    c = math.cos(phi)
    f = al * s * c + be * s + ga * c
    df = al * (c * c - s * s) + be * c - ga * s
    return f, df


@njit
def _cubic_largest_root(b, c, d):  # noqa: ANN001, ANN202
    """Largest real root of ``m³ + b m² + c m + d`` (Cardano / trigonometric form), polished by
    two Newton steps."""
    p = c - b * b / 3.0
    q = 2.0 * b * b * b / 27.0 - b * c / 3.0 + d
    disc = 0.25 * q * q + p * p * p / 27.0
    if disc > 0.0:
        sq = math.sqrt(disc)
        u = -0.5 * q + sq
        w = -0.5 * q - sq
        m = math.copysign(abs(u) ** (1.0 / 3.0), u) + math.copysign(abs(w) ** (1.0 / 3.0), w)
    elif p < 0.0:
        r = 2.0 * math.sqrt(-p / 3.0)
        arg = 3.0 * q / (p * r)
        arg = max(-1.0, min(1.0, arg))
        m = r * math.cos(math.acos(arg) / 3.0)   # the largest of the three real roots
    else:
        m = 0.0
    m -= b / 3.0
    for _ in range(2):
        f = ((m + b) * m + c) * m + d
        df = (3.0 * m + 2.0 * b) * m + c
        if df == 0.0:
            break
        m -= f / df
    return m


@njit
def _quadratic_seeds(s1, s0, out, n):  # noqa: ANN001, ANN202
    """Real roots of ``y² + s1 y + s0``; complex ones with ``|imag| ≤ 1e-6(1 + |real|)`` count
    as real (near-double roots, polished by the caller)."""
    disc = s1 * s1 - 4.0 * s0
    if disc >= 0.0:
        sq = math.sqrt(disc)
        # stable pair: y1 = (-s1 - sign(s1) sq)/2, y2 = s0 / y1
        y1 = -0.5 * (s1 + math.copysign(sq, s1))
        out[n] = y1
        out[n + 1] = s0 / y1 if y1 != 0.0 else -s1 - y1
        return n + 2
    re = -0.5 * s1
    if 0.5 * math.sqrt(-disc) <= 1e-6 * (1.0 + abs(re)):
        out[n] = re
        return n + 1
    return n


@njit
def quartic_real_roots(c4, c3, c2, c1, c0, out):  # noqa: ANN001, ANN201
    """Real (and nearly real) roots of ``c4 t⁴ + c3 t³ + c2 t² + c1 t + c0`` into ``out`` (≥ 4),
    returns their number. Ferrari's factorisation through the largest root of the resolvent
    cubic; closed form, a few hundred flops (``np.roots`` costs an eigenvalue problem).
    Degree drops when leading coefficients are ≤ 1e-300, as in ``np.roots``."""
    if abs(c4) <= 1e-300:
        if abs(c3) <= 1e-300:
            if abs(c2) <= 1e-300:
                if abs(c1) <= 1e-300:
                    return 0
                out[0] = -c0 / c1
                return 1
            return _quadratic_seeds(c1 / c2, c0 / c2, out, np.int64(0))
        # cubic: one real root by the resolvent routine, then deflate
        b, c, d = c2 / c3, c1 / c3, c0 / c3
        t = _cubic_largest_root(b, c, d)
        out[0] = t
        return _quadratic_seeds(b + t, c + t * (b + t), out, np.int64(1))
    a, b, c, d = c3 / c4, c2 / c4, c1 / c4, c0 / c4
    sh = 0.25 * a
    a2 = a * a
    p = b - 0.375 * a2
    q = c - 0.5 * a * b + 0.125 * a2 * a
    r = d - 0.25 * a * c + a2 * b / 16.0 - 3.0 * a2 * a2 / 256.0
    scale = max(abs(p), math.sqrt(abs(r)), abs(q) ** (2.0 / 3.0), 1e-300)
    n = 0
    if abs(q) <= 1e-14 * scale ** 1.5:
        # biquadratic y⁴ + p y² + r: z = y²
        z = np.empty(2)
        nz = _quadratic_seeds(p, r, z, np.int64(0))
        for i in range(nz):
            if z[i] >= 0.0:
                y = math.sqrt(z[i])
                out[n] = y - sh
                out[n + 1] = -y - sh
                n += 2
            elif -z[i] <= 1e-12 * scale:
                out[n] = -sh
                n += 1
        return n
    m = _cubic_largest_root(p, 0.25 * p * p - r, -0.125 * q * q)
    if m <= 0.0:
        m = 1e-300
    w = math.sqrt(2.0 * m)
    tmp = np.empty(4)
    k = _quadratic_seeds(-w, 0.5 * p + m + q / (2.0 * w), tmp, np.int64(0))
    k = _quadratic_seeds(w, 0.5 * p + m - q / (2.0 * w), tmp, k)
    for i in range(k):
        out[i] = tmp[i] - sh
    return k


@njit
def circle_boundary(R, psi, Y, Yp, Ypp):  # noqa: ANN001, ANN201
    """Wall point ``Y(ψ) = R(cos ψ, sin ψ)`` of a circular section and its first and second
    ψ-derivatives into ``Y``, ``Yp``, ``Ypp`` (2,) (section coordinates; compiled boundary of
    :class:`CircleSection`, what the exact contact tangent reads)."""
    c = math.cos(psi)
    s = math.sin(psi)
    Y[0] = R * c
    Y[1] = R * s
    Yp[0] = -R * s
    Yp[1] = R * c
    Ypp[0] = -R * c
    Ypp[1] = -R * s


@njit
def superellipse_boundary(A, B, n, psi, Y, Yp, Ypp):  # noqa: ANN001, ANN201
    """Wall point of the superellipse ``|y/A|ⁿ + |z/B|ⁿ = 1`` in the radial parametrisation
    ``Y(ψ) = ρ(ψ)(cos ψ, sin ψ)``, ``ρ = g^(−1/n)``, ``g = |cos ψ/A|ⁿ + |sin ψ/B|ⁿ``, and its
    first and second ψ-derivatives into ``Y``, ``Yp``, ``Ypp`` (2,) (compiled boundary of
    :class:`SuperellipseSection`, FORMULATION II §6; n ≥ 2 keeps g twice differentiable)."""
    c = math.cos(psi)
    s = math.sin(psi)
    u = c / A
    w = s / B
    au = abs(u)
    aw = abs(w)
    su = 1.0 if u > 0.0 else (-1.0 if u < 0.0 else 0.0)
    sw = 1.0 if w > 0.0 else (-1.0 if w < 0.0 else 0.0)
    g = au**n + aw**n
    t1 = au ** (n - 1.0) * su * (-s / A)
    t2 = aw ** (n - 1.0) * sw * (c / B)
    dg = n * (t1 + t2)
    d2g = n * ((n - 1.0) * au ** (n - 2.0) * (s / A) ** 2 + au ** (n - 1.0) * su * (-c / A)
               + (n - 1.0) * aw ** (n - 2.0) * (c / B) ** 2 + aw ** (n - 1.0) * sw * (-s / B))
    rho = g ** (-1.0 / n)
    drho = -rho * dg / (n * g)
    d2rho = -(drho * dg + rho * d2g) / (n * g) + rho * dg * dg / (n * g * g)
    Y[0] = rho * c
    Y[1] = rho * s
    Yp[0] = drho * c - rho * s
    Yp[1] = drho * s + rho * c
    Ypp[0] = d2rho * c - 2.0 * drho * s - rho * c
    Ypp[1] = d2rho * s + 2.0 * drho * c - rho * s


#: compiled shapes: the kind codes of :meth:`HoleSection.compiled_shape`
SHAPE_CIRCLE = 0
SHAPE_SUPERELLIPSE = 1


@njit
def section_boundary(kind, params, psi, Y, Yp, Ypp):  # noqa: ANN001, ANN201
    """``Y(ψ), Y′, Y″`` of a compiled hole section (``kind``, ``params`` of
    :meth:`HoleSection.compiled_shape`): the only place that knows the shapes; the detector and
    the contact tangent read the wall through it."""
    if kind == SHAPE_CIRCLE:
        circle_boundary(params[0], psi, Y, Yp, Ypp)
        return
    beta = params[3]      # orientation of the section's a axis from e_y towards e_z
    superellipse_boundary(params[0], params[1], params[2], psi - beta, Y, Yp, Ypp)
    if beta != 0.0:
        cb = math.cos(beta)
        sb = math.sin(beta)
        for v in (Y, Yp, Ypp):
            v0 = v[0]
            v[0] = cb * v0 - sb * v[1]
            v[1] = sb * v0 + cb * v[1]


@njit
def section_contains(kind, params, y, z):  # noqa: ANN001, ANN201
    """Whether the point (y, z) lies inside the compiled hole section (on the wall counts)."""
    if kind == SHAPE_CIRCLE:
        return y * y + z * z <= params[0] * params[0]
    n = params[2]
    cb = math.cos(params[3])
    sb = math.sin(params[3])
    yl = cb * y + sb * z        # the point in the section's own axes
    zl = -sb * y + cb * z
    return abs(yl / params[0]) ** n + abs(zl / params[1]) ** n <= 1.0


@njit
def _support(cy, cz, eax, eay, a, b, N0, N1):  # noqa: ANN001, ANN202
    """Ellipse point with outward normal N: ``X = c + ΣN/√(NᵀΣN)``, and ``TᵀJ_E T`` for the
    tangent T = (−N1, N0) (FORMULATION II §6)."""
    na = N0 * eax + N1 * eay            # components of N along e_a, e_b
    nb = -N0 * eay + N1 * eax
    qq = a * a * na * na + b * b * nb * nb
    sq = math.sqrt(qq)
    xa = a * a * na / sq
    xb = b * b * nb / sq
    X0 = cy + xa * eax - xb * eay
    X1 = cz + xa * eay + xb * eax
    # T in (e_a, e_b): (−nb, na); TᵀΣT − (TᵀΣN)²/NᵀΣN over √(NᵀΣN)
    tst = a * a * nb * nb + b * b * na * na
    tsn = -a * a * na * nb + b * b * na * nb
    rho = (tst - tsn * tsn / qq) / sq
    return X0, X1, rho, xa / a, xb / b


@njit
def _common_normal_f(kind, params, cy, cz, eax, eay, a, b, psi, Y, Yp, Ypp):  # noqa: ANN001, ANN202
    """``F(ψ) = T·(X(N(ψ)) − Y(ψ))``, ``F′``, ``d = N·(X − Y)`` and the ellipse angle of X."""
    section_boundary(kind, params, psi, Y, Yp, Ypp)
    speed = math.hypot(Yp[0], Yp[1])
    T0 = Yp[0] / speed
    T1 = Yp[1] / speed
    N0 = T1
    N1 = -T0
    kappa = (Yp[0] * Ypp[1] - Yp[1] * Ypp[0]) / speed**3
    X0, X1, rho, ca, sb = _support(cy, cz, eax, eay, a, b, N0, N1)
    F = T0 * (X0 - Y[0]) + T1 * (X1 - Y[1])
    d = N0 * (X0 - Y[0]) + N1 * (X1 - Y[1])
    dF = speed * (kappa * (rho - d) - 1.0)
    return F, dF, d, math.atan2(sb, ca)


@njit
def common_normal_points(kind, params, cy, cz, eax, eay, a, b, samples, psi_out, phi_out,  # noqa: ANN001, ANN201
                         kind_out, depth_out):
    """Every stationary point of the penetration of the ellipse through a compiled section
    (generic detector of FORMULATION II §6, compiled): ``F(ψ)`` sampled at ``samples`` points,
    sign changes bracketed, safeguarded Newton; writes ψ (wall parameter), φ (ellipse angle),
    kind (+1 maximum of the penetration, −1 minimum) and depth ``N·(X − Y)``; returns their
    number (at most ``psi_out.size``)."""
    Y = np.empty(2)
    Yp = np.empty(2)
    Ypp = np.empty(2)
    h = 2.0 * np.pi / samples
    F0, _, _, _ = _common_normal_f(kind, params, cy, cz, eax, eay, a, b, 0.0, Y, Yp, Ypp)
    Fi = F0
    count = 0
    scale = max(a, params[0])
    for i in range(samples):
        lo = i * h
        hi = lo + h
        if i + 1 < samples:
            Fj, _, _, _ = _common_normal_f(kind, params, cy, cz, eax, eay, a, b, hi, Y, Yp, Ypp)
        else:
            Fj = F0
        if Fi == 0.0 or Fi * Fj < 0.0:
            flo = Fi
            s = 0.5 * (lo + hi) if Fi != 0.0 else lo
            for _ in range(60):
                f, df, _, _ = _common_normal_f(kind, params, cy, cz, eax, eay, a, b, s, Y, Yp, Ypp)
                if abs(f) <= 1e-13 * scale or hi - lo < 1e-15:
                    break
                s, lo, hi, flo = bracketed_newton_step(s, f, df, lo, hi, flo)
            f, df, d, phi = _common_normal_f(kind, params, cy, cz, eax, eay, a, b, s, Y, Yp, Ypp)
            if count < psi_out.size:
                psi_out[count] = s % (2.0 * np.pi)
                phi_out[count] = phi
                kind_out[count] = 1 if df < 0.0 else -1
                depth_out[count] = d
                count += 1
        Fi = Fj
    return count


@njit
def circle_stationary_points(cx, cy, eax, eay, a, b, R):  # noqa: ANN001, ANN201
    """Stationary angles of ``D(φ) = ½|X(φ)|²`` for an ellipse in a centred circle (FORMULATION II §3).

    ``f = D′ = (b² − a²) sin φ cos φ + a d_a sin φ − b d_b cos φ`` solved in closed form by
    :func:`trig_quadratic_roots`. Returns ``(phi (k,), kind (k,))`` with ``kind = +1`` for
    maxima (``f' < 0``), ``−1`` for minima. Degenerate a ≈ b centred (f ≡ 0): no points if
    ``a ≤ R``, else the four axis points as maxima (uniform penetration, net force 0).
    """
    da = -(cx * eax + cy * eay)          # d = O − c, O = 0
    db = -(cx * (-eay) + cy * eax)
    dist = math.hypot(cx, cy)
    scale = a * a + a * dist
    if a - b <= 1e-12 * a and dist <= 1e-12 * a:
        if a > R:
            return (np.array([0.0, 0.5 * np.pi, np.pi, 1.5 * np.pi]),
                    np.array([1, 1, 1, 1], dtype=np.int64))
        return np.empty(0), np.empty(0, dtype=np.int64)
    phis = np.empty(5)
    signs = np.empty(5, dtype=np.int64)
    nf = trig_quadratic_roots(b * b - a * a, a * da, -b * db, scale, phis, signs)
    return phis[:nf], -signs[:nf]


_H = math.sqrt(0.5)
#: sin(kπ/4), k = 0..7 (cos(kπ/4) = sin((k + 2)π/4))
_SIN_QUARTER = (0.0, _H, 1.0, _H, 0.0, -_H, -1.0, -_H)


@njit
def trig_quadratic_roots(al, be, ga, scale, phis, signs):  # noqa: ANN001, ANN201
    """Roots of ``f(φ) = al sin φ cos φ + be sin φ + ga cos φ`` on [0, 2π) into ``phis`` (≥ 5)
    with the sign of ``f′`` into ``signs``; returns their number (at most 4).

    Closed form (FORMULATION II §3): with ``t = tan((φ − φ0)/2)``, ``f (1 + t²)²`` is a quartic
    in t; φ0 ∈ {kπ/4} maximises the leading coefficient ``f(φ0 + π)`` (no root near t = ∞),
    real roots by :func:`quartic_real_roots` (nearly-real ones accepted), 4 Newton polishing
    steps on f, residual check against ``1e-10 scale``, duplicates removed."""
    phi0 = 0.0
    best = -1.0
    s0 = 0.0
    c0 = 1.0
    for k in range(8):    # f(kπ/4 + π) from the table of sin, cos at kπ/4 (no sincos)
        sk = _SIN_QUARTER[k]
        ck = _SIN_QUARTER[(k + 2) % 8]
        f_inf = abs(al * sk * ck - be * sk - ga * ck)
        if f_inf > best:
            best = f_inf
            phi0 = k * 0.25 * np.pi
            s0 = sk
            c0 = ck
    u0 = be * s0 + ga * c0
    u1 = 2.0 * (be * c0 - ga * s0)
    asc = al * s0 * c0
    acs = 2.0 * al * (c0 * c0 - s0 * s0)
    c4, c3, c2, c1, cc0 = asc - u0, u1 - acs, -6.0 * asc, acs + u1, asc + u0
    cmax = max(abs(c4), abs(c3), abs(c2), abs(c1), abs(cc0))
    seeds = np.empty(5)
    ns = quartic_real_roots(c4, c3, c2, c1, cc0, seeds)
    for i in range(ns):
        seeds[i] = phi0 + 2.0 * math.atan(seeds[i])
    if abs(c4) <= 1e-8 * cmax:
        seeds[ns] = phi0 + np.pi
        ns += 1
    nf = 0
    ftol = 1e-10 * scale
    for i in range(ns):
        phi = seeds[i]
        for _ in range(4):
            f, df = _trig_f(phi, al, be, ga)
            if df == 0.0:
                break
            step = -f / df
            if abs(step) > 0.3:
                step = 0.3 if step > 0 else -0.3
            phi += step
            if abs(step) <= 1e-15 * (1.0 + abs(phi)):
                break
        f, df = _trig_f(phi, al, be, ga)
        if abs(f) > ftol:
            continue
        phi = phi % (2.0 * np.pi)
        dup = False
        for j in range(nf):
            dd = abs(phi - phis[j])
            if min(dd, 2.0 * np.pi - dd) < 1e-9:
                dup = True
                break
        if dup:
            continue
        phis[nf] = phi
        signs[nf] = 1 if df > 0.0 else -1
        nf += 1
    return nf


#: scenario name -> hole section class (``hole = { shape = "circle", radius = ... }``)
HOLE_SECTIONS: Registry[type[HoleSection]] = Registry("hole section")


@HOLE_SECTIONS.register("circle")
@dataclass(frozen=True)
class CircleSection(HoleSection):
    """Circular bore of radius R (FORMULATION II §3): closed-form quartic detector."""

    radius: float

    def __post_init__(self) -> None:
        if not (isinstance(self.radius, (int, float)) and self.radius > 0.0):
            raise ModelError(f"CircleSection: radius must be > 0 (got {self.radius!r})")

    def boundary(self, psi: np.ndarray | float
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        psi = np.asarray(psi, dtype=float)
        N = np.stack([np.cos(psi), np.sin(psi)], axis=-1)
        T = np.stack([-N[..., 1], N[..., 0]], axis=-1)
        R = float(self.radius)
        return R * N, N, T, np.full(psi.shape, R), np.full(psi.shape, 1.0 / R)

    def bounding_radius(self) -> float:
        return float(self.radius)

    def compiled_shape(self) -> tuple[int, np.ndarray]:
        return SHAPE_CIRCLE, np.array([float(self.radius), 0.0, 0.0, 0.0])

    def inscribed_radius(self) -> float:
        return float(self.radius)

    def candidates(self, ellipse: Ellipse2D, margin: float = 0.0) -> list[Candidate]:
        """Stationary points of ``|X(φ)| − R`` with depth > −margin (FORMULATION II §3, §4):
        ``Q = R u``, ``u = X/|X|``."""
        R = float(self.radius)
        c = ellipse.center
        if math.hypot(c[0], c[1]) + ellipse.a < R - margin:
            return []  # broad phase
        phis, kinds = circle_stationary_points(float(c[0]), float(c[1]), float(ellipse.e_a[0]),
                                               float(ellipse.e_a[1]), ellipse.a, ellipse.b, R)
        out: list[Candidate] = []
        for phi, kind in zip(phis, kinds, strict=True):
            X = ellipse.point(phi)
            rho = math.hypot(X[0], X[1])
            if rho - R <= -margin or rho == 0.0:
                continue
            u = X / rho
            out.append(Candidate(phi=float(phi), X=X, Q=R * u, normal=u, depth=rho - R,
                                 kind=int(kind), psi=math.atan2(u[1], u[0]) % (2.0 * np.pi)))
        return out


@HOLE_SECTIONS.register("superellipse")
@dataclass(frozen=True)
class SuperellipseSection(HoleSection):
    """Superellipse bore ``|y/a|ⁿ + |z/b|ⁿ = 1``, semi-axes ``a`` (body y) and ``b`` (body z),
    ``n = exponent ≥ 2`` (FORMULATION II §6), radially parametrised ``Y(ψ) = ρ(ψ)(cos ψ, sin ψ)``;
    generic common-normal detector. ``angle`` turns the section in the hole body (its a axis
    from body y towards body z, radians). Parameter names as in the scenario: ``a``, ``b``,
    ``exponent``, ``angle``."""

    a: float
    b: float
    exponent: float = 2.0
    samples: int = 128
    angle: float = 0.0

    def __post_init__(self) -> None:
        for name in ("a", "b"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and not isinstance(v, bool) and v > 0.0):
                raise ModelError(f"SuperellipseSection: {name} must be > 0 (got {v!r})")
        n = self.exponent
        if not (isinstance(n, (int, float)) and not isinstance(n, bool) and n >= 2.0):
            raise ModelError(f"SuperellipseSection: exponent must be >= 2 (got {n!r})")
        if int(self.samples) < 64:
            raise ModelError(f"SuperellipseSection: samples must be >= 64 (got {self.samples!r})")
        ang = self.angle
        if not (isinstance(ang, (int, float)) and not isinstance(ang, bool) and math.isfinite(ang)):
            raise ModelError(f"SuperellipseSection: angle must be a finite number (got {ang!r})")

    def boundary(self, psi: np.ndarray | float
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        psi = np.asarray(psi, dtype=float)
        if self.angle == 0.0:
            return self._boundary_local(psi)
        Y, N, T, speed, kappa = self._boundary_local(psi - float(self.angle))
        c, s = math.cos(self.angle), math.sin(self.angle)
        rot = np.array([[c, -s], [s, c]])
        return Y @ rot.T, N @ rot.T, T @ rot.T, speed, kappa

    def _boundary_local(self, psi: np.ndarray
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`boundary` in the section's own axes (a along y)."""
        A, B, n = float(self.a), float(self.b), float(self.exponent)
        c, s = np.cos(psi), np.sin(psi)
        ac, as_ = np.abs(c / A), np.abs(s / B)
        g = ac**n + as_**n
        rho = g ** (-1.0 / n)
        # g' = n(|c/A|^(n-1) sgn(c)(-s)/A + |s/B|^(n-1) sgn(s) c/B)
        dg = n * (ac ** (n - 1.0) * np.sign(c) * (-s) / A + as_ ** (n - 1.0) * np.sign(s) * c / B)
        drho = -rho * dg / (n * g)
        y, z = rho * c, rho * s
        Yp = np.stack([drho * c - rho * s, drho * s + rho * c], axis=-1)
        speed = np.sqrt(np.einsum("...i,...i->...", Yp, Yp))
        ay, az = np.abs(y), np.abs(z)
        py = n * np.sign(y) * ay ** (n - 1.0) / A**n
        pz = n * np.sign(z) * az ** (n - 1.0) / B**n
        gn = np.sqrt(py * py + pz * pz)
        N = np.stack([py / gn, pz / gn], axis=-1)
        T = np.stack([-N[..., 1], N[..., 0]], axis=-1)
        pyy = n * (n - 1.0) * ay ** (n - 2.0) / A**n
        pzz = n * (n - 1.0) * az ** (n - 2.0) / B**n
        kappa = (pyy * pz * pz + pzz * py * py) / gn**3
        return np.stack([y, z], axis=-1), N, T, speed, kappa

    def bounding_radius(self) -> float:
        psi = np.linspace(0.0, 0.5 * np.pi, 2049)
        Y = self.boundary(psi)[0]
        return float(np.max(np.hypot(Y[:, 0], Y[:, 1]))) * (1.0 + 1e-6)

    def inscribed_radius(self) -> float:
        return float(min(self.a, self.b))  # ρ(ψ) ≥ min(a, b) for n ≥ 2

    def compiled_shape(self) -> tuple[int, np.ndarray]:
        return SHAPE_SUPERELLIPSE, np.array([float(self.a), float(self.b), float(self.exponent),
                                             float(self.angle)])


#: the former name of :data:`HOLE_SECTIONS` (same object)
SECTION_TYPES = HOLE_SECTIONS


def get_section(name: str, **params: float) -> HoleSection:
    """Hole section by scenario name, e.g. ``get_section("superellipse", a=2e-3, b=3e-3,
    exponent=4)``; an unknown name lists the known ones (:data:`HOLE_SECTIONS`)."""
    cls = HOLE_SECTIONS.get(name)
    try:
        return cls(**params)
    except TypeError as exc:
        raise ModelError(f"hole section {name!r}: {exc}") from None


def two_point_possible(ellipse: Ellipse2D, R: float) -> bool:
    """Two-point contact at the minor vertex is possible iff ``ρ_max = a²/b > R`` (FORMULATION II §3)."""
    return ellipse.a**2 / ellipse.b > R


def inside_evolute(ellipse: Ellipse2D, point: np.ndarray | None = None) -> bool:
    """Is ``point`` (default: hole centre) inside the ellipse's evolute (astroid)?  Then D(φ) has 4
    stationary points, else 2 (FORMULATION II §3)."""
    o = np.zeros(2) if point is None else np.asarray(point, dtype=float)
    d = o - ellipse.center
    da, db = float(d @ ellipse.e_a), float(d @ ellipse.e_b)
    a, b = ellipse.a, ellipse.b
    return abs(a * da) ** (2 / 3) + abs(b * db) ** (2 / 3) < (a * a - b * b) ** (2 / 3)


def jamming(ellipse: Ellipse2D, hole: HoleSection) -> bool:
    """True when the ellipse is wider than the hole's inscribed circle (``a > R_in``).

    Exact for the circle (the ellipse cannot fit anywhere: jamming, FORMULATION II §2); for other
    shapes a conservative flag (the ellipse may still fit along a wider direction).
    """
    return ellipse.a > hole.inscribed_radius()

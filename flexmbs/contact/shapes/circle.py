"""The circular bore (docs/theory.md §II.3): its compiled boundary and inside test, the closed-form
stationary points of an ellipse's penetration, and :class:`CircleSection` (scenario shape
``"circle"``)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..._jit import njit
from ...codes import SHAPE_CODES
from ...errors import ModelError
from ..roots import trig_quadratic_roots
from .base import HOLE_SECTIONS, Candidate, Ellipse2D, HoleSection

__all__ = ["SHAPE_CIRCLE", "CircleSection", "circle_boundary", "circle_contains",
           "circle_stationary_points"]

#: the compiled kind code of the circle (:meth:`HoleSection.compiled_shape`), params ``[R, 0, 0, 0]``
SHAPE_CIRCLE = SHAPE_CODES["circle"]


@njit
def circle_boundary(R, psi, Y, Yp, Ypp):
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
def circle_contains(params, y, z):
    """Whether (y, z) lies inside the circle of radius ``params[0]`` (on the wall counts)."""
    return y * y + z * z <= params[0] * params[0]


@njit
def circle_stationary_points(cx, cy, eax, eay, a, b, R):
    """Stationary angles of ``D(φ) = ½|X(φ)|²`` for an ellipse in a centred circle (docs/theory.md §II.3).

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
    nf = trig_quadratic_roots(b * b - a * a, a * da, -b * db, scale, phis, signs, np.empty(5))
    return phis[:nf], -signs[:nf]


@HOLE_SECTIONS.register("circle")
@dataclass(frozen=True)
class CircleSection(HoleSection):
    """Circular bore of radius R (docs/theory.md §II.3): closed-form quartic detector."""

    radius: float = field(metadata={"unit": "m", "gt": 0.0})

    def __post_init__(self) -> None:
        if not (isinstance(self.radius, (int, float)) and self.radius > 0.0):
            raise ModelError(f"CircleSection: radius must be > 0 (got {self.radius!r})")

    def bounding_radius(self) -> float:
        return float(self.radius)

    def compiled_shape(self) -> tuple[int, np.ndarray]:
        return SHAPE_CIRCLE, np.array([float(self.radius), 0.0, 0.0, 0.0])

    def inscribed_radius(self) -> float:
        return float(self.radius)

    def candidates(self, ellipse: Ellipse2D, margin: float = 0.0) -> list[Candidate]:
        """Stationary points of ``|X(φ)| − R`` with depth > −margin (docs/theory.md §II.3, §II.4):
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

"""The superellipse bore ``|y/a|ⁿ + |z/b|ⁿ = 1`` (docs/theory.md §II.6): its compiled boundary (radial
parametrisation, turned by the section's angle) and inside test, and
:class:`SuperellipseSection` (scenario shape ``"superellipse"``; the generic detector)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..._jit import njit
from ...codes import SHAPE_CODES
from ...errors import ModelError
from .base import HOLE_SECTIONS, HoleSection

__all__ = ["SHAPE_SUPERELLIPSE", "SuperellipseSection", "superellipse_boundary",
           "superellipse_contains", "superellipse_section_boundary"]

#: the compiled kind code of the superellipse, params ``[a, b, exponent, angle]``
SHAPE_SUPERELLIPSE = SHAPE_CODES["superellipse"]


@njit
def superellipse_boundary(A, B, n, psi, Y, Yp, Ypp):
    """Wall point of the superellipse ``|y/A|ⁿ + |z/B|ⁿ = 1`` in the radial parametrisation
    ``Y(ψ) = ρ(ψ)(cos ψ, sin ψ)``, ``ρ = g^(−1/n)``, ``g = |cos ψ/A|ⁿ + |sin ψ/B|ⁿ``, and its
    first and second ψ-derivatives into ``Y``, ``Yp``, ``Ypp`` (2,) (compiled boundary of
    :class:`SuperellipseSection`, docs/theory.md §II.6; n ≥ 2 keeps g twice differentiable)."""
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


@njit
def superellipse_section_boundary(params, psi, Y, Yp, Ypp):
    """:func:`superellipse_boundary` of the section ``params = [a, b, n, angle]``, its a axis
    turned by ``angle`` from e_y towards e_z."""
    beta = params[3]
    superellipse_boundary(params[0], params[1], params[2], psi - beta, Y, Yp, Ypp)
    if beta != 0.0:
        cb = math.cos(beta)
        sb = math.sin(beta)
        for v in (Y, Yp, Ypp):
            v0 = v[0]
            v[0] = cb * v0 - sb * v[1]
            v[1] = sb * v0 + cb * v[1]


@njit
def superellipse_contains(params, y, z):
    """Whether (y, z) lies inside the section ``params = [a, b, n, angle]`` (on the wall counts)."""
    n = params[2]
    cb = math.cos(params[3])
    sb = math.sin(params[3])
    yl = cb * y + sb * z        # the point in the section's own axes
    zl = -sb * y + cb * z
    return abs(yl / params[0]) ** n + abs(zl / params[1]) ** n <= 1.0


@HOLE_SECTIONS.register("superellipse")
@dataclass(frozen=True)
class SuperellipseSection(HoleSection):
    """Superellipse bore ``|y/a|ⁿ + |z/b|ⁿ = 1``, semi-axes ``a`` (body y) and ``b`` (body z),
    ``n = exponent ≥ 2`` (docs/theory.md §II.6), radially parametrised ``Y(ψ) = ρ(ψ)(cos ψ, sin ψ)``;
    generic common-normal detector. ``angle`` turns the section in the hole body (its a axis
    from body y towards body z, radians). Parameter names as in the scenario: ``a``, ``b``,
    ``exponent``, ``angle``."""

    a: float = field(metadata={"unit": "m", "gt": 0.0})
    b: float = field(metadata={"unit": "m", "gt": 0.0})
    exponent: float = field(default=2.0, metadata={"unit": "1", "ge": 2.0})
    samples: int = field(default=128, metadata={"ge": 64})
    angle: float = field(default=0.0, metadata={"unit": "rad"})

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

    def bounding_radius(self) -> float:
        psi = np.linspace(0.0, 0.5 * np.pi, 2049)
        Y = self.boundary(psi)[0]
        return float(np.max(np.hypot(Y[:, 0], Y[:, 1]))) * (1.0 + 1e-6)

    def inscribed_radius(self) -> float:
        return float(min(self.a, self.b))  # ρ(ψ) ≥ min(a, b) for n ≥ 2

    def compiled_shape(self) -> tuple[int, np.ndarray]:
        return SHAPE_SUPERELLIPSE, np.array([float(self.a), float(self.b), float(self.exponent),
                                             float(self.angle)])

"""What every hole section shares (docs/theory.md §II.2–§II.3, §II.6): the beam's section ellipse
:class:`Ellipse2D`, a detected :class:`Candidate`, the :class:`HoleSection` base with the generic
common-normal detector of §6 in numpy, and the registry :data:`HOLE_SECTIONS` of scenario shape
names. The shapes themselves are one module each in this package."""

from __future__ import annotations

import functools
import math
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..._jit import njit
from ...errors import ModelError
from ...registry import Registry

__all__ = ["Candidate", "Ellipse2D", "HOLE_SECTIONS", "HoleSection", "SHAPE_SAMPLES"]

#: wall samples of the compiled generic detector per section (``_detect.detect_section``: the
#: common-normal residual and the line-model seeds); what a shape's features must span (each
#: shape checks its own: the superellipse's exponent, the rounded rectangle's corner radius)
SHAPE_SAMPLES = 128


@dataclass(frozen=True)
class Ellipse2D:
    """Beam section ellipse ``X(φ) = c + a cos φ e_a + b sin φ e_b`` (docs/theory.md §II.2–§II.3)."""

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

    def support(self, N: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Support point and map (docs/theory.md §II.6): ``X(N) = c + ΣN/√(NᵀΣN)`` and
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
    """One stationary point of the section penetration (docs/theory.md §II.3/§II.6)."""

    phi: float           #: ellipse angle of X
    X: np.ndarray        #: (2,) beam-ellipse point
    Q: np.ndarray        #: (2,) hole boundary point (hole point of docs/theory.md §II.4)
    normal: np.ndarray   #: (2,) outward hole normal at Q (from the bore into the hole material)
    depth: float         #: penetration along the normal, > 0 = penetrating
    kind: int            #: +1 local max of penetration (contact point), −1 local min
    psi: float = field(default=math.nan)  #: boundary parameter of Q (generic detector only)


# ---------------------------------------------------------------------------------------------
class HoleSection(ABC):
    """Convex C¹ hole cross-section (docs/design.md "Pluggable parts", docs/theory.md §II.6)."""

    #: number of samples of F(ψ) in the generic detector (≥ 64, docs/theory.md §II.6)
    samples: int = 128

    #: the methods whose value a section computes once (sections are immutable: a frozen
    #: dataclass each); a superellipse's bounding radius samples its wall 2 049 times
    _ONCE = ("bounding_radius", "inscribed_radius")

    def __init_subclass__(cls, **kwargs: Any) -> None:
        """A subclass's :meth:`bounding_radius` and :meth:`inscribed_radius` are computed at
        their first call and kept (the detectors and the output ask for them per root and per
        output: Example "rounded slot" spent 10 s building its scenario in them)."""
        super().__init_subclass__(**kwargs)
        for name in HoleSection._ONCE:
            method = cls.__dict__.get(name)
            if method is not None and not getattr(method, "computed_once", False):
                setattr(cls, name, _once(name, method))

    def boundary(self, psi: np.ndarray | float
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(Y, N, T, speed, curvature)`` at parameter ψ ∈ [0, 2π): point, outward unit normal,
        CCW unit tangent, ``|Y_ψ|``, curvature κ ≥ 0 (shapes ``(..., 2)`` / ``(...)``).

        A section with a compiled boundary (:meth:`compiled_shape`) derives them from its kernel's
        ``Y, Y′, Y″`` (:func:`flexmbs.contact.shapes.section_boundary`): ``T = Y′/|Y′|``, ``N`` =
        T turned clockwise, ``κ = (Y′ × Y″)/|Y′|³``; a section defined in Python overrides it."""
        shape = self.compiled_shape()
        if shape is None:
            raise NotImplementedError(f"{type(self).__name__}: a hole section without a compiled "
                                      "boundary must define boundary(psi)")
        from . import section_boundary

        kind, params = shape
        psi_a = np.asarray(psi, dtype=float)
        flat = psi_a.reshape(-1)
        Y, Yp, Ypp = np.empty((flat.size, 2)), np.empty((flat.size, 2)), np.empty((flat.size, 2))
        for i in range(flat.size):
            section_boundary(kind, params, float(flat[i]), Y[i], Yp[i], Ypp[i])
        speed = np.hypot(Yp[:, 0], Yp[:, 1])
        T = Yp / speed[:, None]
        N = np.stack([T[:, 1], -T[:, 0]], axis=-1)
        kappa = (Yp[:, 0] * Ypp[:, 1] - Yp[:, 1] * Ypp[:, 0]) / speed**3
        shp = psi_a.shape
        return (Y.reshape(shp + (2,)), N.reshape(shp + (2,)), T.reshape(shp + (2,)),
                speed.reshape(shp), kappa.reshape(shp))

    @abstractmethod
    def bounding_radius(self) -> float:
        """Radius of the smallest centred circle containing the section (broad phase)."""

    @abstractmethod
    def inscribed_radius(self) -> float:
        """Radius of the largest centred circle inside the section (broad phase)."""

    def compiled_shape(self) -> tuple[int, np.ndarray] | None:
        """``(kind, params)`` of the compiled boundary kernel
        (:func:`flexmbs.contact.shapes.section_boundary`); a joint refuses a section without
        one (None)."""
        return None

    def candidates(self, ellipse: Ellipse2D, margin: float = 0.0) -> list[Candidate]:
        """All stationary points of the penetration with ``depth > −margin`` (docs/theory.md §II.6),
        by the compiled generic detector (:func:`flexmbs.contact.shapes.detector.common_normal_points`:
        the common-normal residual ``F(ψ) = T·(X(N(ψ)) − Y(ψ))`` sampled at ``self.samples``
        points, sign changes bracketed, safeguarded Newton) on the section's compiled boundary."""
        c = ellipse.center
        if math.hypot(c[0], c[1]) + ellipse.a < self.inscribed_radius() - margin:
            return []  # broad phase: the ellipse is strictly inside the inscribed circle
        shape = self.compiled_shape()
        if shape is None:
            raise NotImplementedError(f"{type(self).__name__}: a hole section without a compiled "
                                      "boundary has no detector")
        from .detector import common_normal_points

        kind, params = shape
        m = max(int(self.samples), 64)
        psi, phi, depth = np.empty(m), np.empty(m), np.empty(m)
        kinds = np.empty(m, dtype=np.int64)
        count = common_normal_points(int(kind), np.ascontiguousarray(params, dtype=float),
                                     float(c[0]), float(c[1]), float(ellipse.e_a[0]),
                                     float(ellipse.e_a[1]), float(ellipse.a), float(ellipse.b),
                                     m, psi, phi, kinds, depth)
        out: list[Candidate] = []
        for i in range(count):
            if not depth[i] > -margin:
                continue
            Y, N, _, _, _ = self.boundary(float(psi[i]))
            out.append(Candidate(phi=float(phi[i]) % (2.0 * np.pi), X=ellipse.point(float(phi[i])),
                                 Q=np.asarray(Y, dtype=float), normal=np.asarray(N, dtype=float),
                                 depth=float(depth[i]), kind=int(kinds[i]), psi=float(psi[i])))
        return out


def _once(name: str, method: Callable[[Any], float]) -> Callable[[Any], float]:
    """``method`` computed once per instance, its value kept in the instance's ``__dict__``
    (set through ``object.__setattr__``: the sections are frozen dataclasses)."""
    key = f"_{name}_value"

    @functools.wraps(method)
    def once(self: Any) -> float:
        value = self.__dict__.get(key)
        if value is None:
            value = method(self)
            object.__setattr__(self, key, value)
        return value

    once.computed_once = True  # type: ignore[attr-defined]
    return once


#: scenario name -> hole section class (``hole = { shape = "circle", radius = ... }``)
HOLE_SECTIONS: Registry[type[HoleSection]] = Registry("hole section")


@njit
def turned_wall(ang, k, y0, y1, t0, t1, c0, c1, Y, Yp, Ypp):
    """A wall point given in a frame turned by ``ang`` from the section's (a quadrant's or a
    sector's), into ``Y``, ``Yp``, ``Ypp`` (2,): the point ``y``, its unit tangent ``t`` and
    curvature vector ``c`` (per arc length) turned, the derivatives scaled by the
    parametrisation's speed ``k = ds/dψ`` (``Y′ = k R t``, ``Y″ = k² R c``). The one statement
    of it for the walls of flats and arcs (rounded rectangle, rounded polygon)."""
    ca = math.cos(ang)
    sa = math.sin(ang)
    Y[0] = ca * y0 - sa * y1
    Y[1] = sa * y0 + ca * y1
    Yp[0] = k * (ca * t0 - sa * t1)
    Yp[1] = k * (sa * t0 + ca * t1)
    Ypp[0] = k * k * (ca * c0 - sa * c1)
    Ypp[1] = k * k * (sa * c0 + ca * c1)

"""Normal contact force laws and regularised Coulomb friction (FORMULATION II §5).

Every law is a frozen keyword-only dataclass implementing :class:`ForceLaw`:
``force(delta, delta_dot, approach_velocity) -> (f, df_ddelta, df_ddelta_dot)`` with penetration
``δ = −g_N`` (> 0 in contact), its rate ``δ̇`` and the approach velocity ``δ̇⁽⁻⁾`` stored by the
caller at contact onset. ``f = 0`` for ``δ ≤ 0`` and ``f`` is clamped at 0 when damping would
pull (then both derivatives are 0). ``LAWS`` maps scenario names to classes; :func:`get_law`
builds one by name with errors naming the unknown law or the missing/invalid parameter.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from ..errors import ModelError

__all__ = [
    "ForceLaw",
    "LinearPenalty",
    "Hertz",
    "HuntCrossley",
    "LankaraniNikravesh",
    "RegularizedCoulomb",
    "LAWS",
    "get_law",
]


@runtime_checkable
class ForceLaw(Protocol):
    """Normal force law ``f_N(δ, δ̇; δ̇⁽⁻⁾)`` (FORMULATION II §5)."""

    def force(self, delta: float, delta_dot: float, approach_velocity: float = 0.0
              ) -> tuple[float, float, float]:
        """``(f, ∂f/∂δ, ∂f/∂δ̇)``; f ≥ 0, f = 0 for δ ≤ 0."""
        ...


def _positive(cls: str, name: str, value: object, *, allow_zero: bool = False) -> None:
    ok = isinstance(value, (int, float, np.floating)) and not isinstance(value, bool) \
        and math.isfinite(float(value)) and (float(value) >= 0.0 if allow_zero else float(value) > 0.0)
    if not ok:
        rel = ">= 0" if allow_zero else "> 0"
        raise ModelError(f"{cls}: {name} must be a finite number {rel} (got {value!r})")


def _exponent(cls: str, value: object) -> None:
    _positive(cls, "exponent", value)
    if float(value) < 1.0:  # type: ignore[arg-type]
        raise ModelError(f"{cls}: exponent must be >= 1 (a finite contact stiffness at δ → 0) "
                         f"(got {value!r})")


def _restitution(cls: str, value: object) -> None:
    _positive(cls, "restitution", value)
    if float(value) > 1.0:  # type: ignore[arg-type]
        raise ModelError(f"{cls}: restitution must be in (0, 1] (got {value!r})")


@dataclass(frozen=True, kw_only=True)
class LinearPenalty:
    """Linear penalty + viscous damping ``f = kδ + c_d δ̇`` (FORMULATION II §5, Exudyn's choice)."""

    stiffness: float
    damping: float = 0.0

    def __post_init__(self) -> None:
        _positive("LinearPenalty", "stiffness", self.stiffness)
        _positive("LinearPenalty", "damping", self.damping, allow_zero=True)

    def force(self, delta: float, delta_dot: float, approach_velocity: float = 0.0
              ) -> tuple[float, float, float]:
        if delta <= 0.0:
            return 0.0, 0.0, 0.0
        f = self.stiffness * delta + self.damping * delta_dot
        if f <= 0.0:
            return 0.0, 0.0, 0.0
        return f, float(self.stiffness), float(self.damping)


@dataclass(frozen=True, kw_only=True)
class Hertz:
    """Hertz-type ``f = Kδⁿ`` (n = 3/2 point contact, ≈ 1–1.1 line-like; FORMULATION II §5)."""

    stiffness: float
    exponent: float = 1.5

    def __post_init__(self) -> None:
        _positive("Hertz", "stiffness", self.stiffness)
        _exponent("Hertz", self.exponent)

    def force(self, delta: float, delta_dot: float, approach_velocity: float = 0.0
              ) -> tuple[float, float, float]:
        if delta <= 0.0:
            return 0.0, 0.0, 0.0
        n = float(self.exponent)
        fe = self.stiffness * delta**n
        return fe, n * fe / delta, 0.0


def _dissipative(K: float, n: float, chi: float, delta: float, delta_dot: float,
                 approach_velocity: float, v_min: float) -> tuple[float, float, float]:
    """``f = Kδⁿ [1 + χ δ̇/δ̇⁽⁻⁾]`` with ``|δ̇⁽⁻⁾|`` floored at ``v_min``, clamped at 0."""
    if delta <= 0.0:
        return 0.0, 0.0, 0.0
    v0 = max(abs(approach_velocity), v_min)
    fe = K * delta**n
    fac = 1.0 + chi * delta_dot / v0
    f = fe * fac
    if f <= 0.0:
        return 0.0, 0.0, 0.0
    return f, n * fe / delta * fac, fe * chi / v0


@dataclass(frozen=True, kw_only=True)
class HuntCrossley:
    """Hunt–Crossley ``f = Kδⁿ[1 + 3(1−e)/2 · δ̇/δ̇⁽⁻⁾]`` (FORMULATION II §5).

    ``min_approach_velocity`` guards ``δ̇⁽⁻⁾ → 0`` (resting contact): the approach velocity used is
    ``max(|δ̇⁽⁻⁾|, min_approach_velocity)``, so the damping coefficient stays bounded.
    """

    stiffness: float
    restitution: float
    exponent: float = 1.5
    min_approach_velocity: float = 1e-3

    def __post_init__(self) -> None:
        _positive("HuntCrossley", "stiffness", self.stiffness)
        _exponent("HuntCrossley", self.exponent)
        _restitution("HuntCrossley", self.restitution)
        _positive("HuntCrossley", "min_approach_velocity", self.min_approach_velocity)

    def force(self, delta: float, delta_dot: float, approach_velocity: float = 0.0
              ) -> tuple[float, float, float]:
        chi = 1.5 * (1.0 - self.restitution)
        return _dissipative(self.stiffness, float(self.exponent), chi, delta, delta_dot,
                            approach_velocity, self.min_approach_velocity)


@dataclass(frozen=True, kw_only=True)
class LankaraniNikravesh:
    """Lankarani–Nikravesh (1990) ``f = Kδⁿ[1 + 3(1−e²)/4 · δ̇/δ̇⁽⁻⁾]`` (FORMULATION II §5);
    same approach-velocity guard as :class:`HuntCrossley`."""

    stiffness: float
    restitution: float
    exponent: float = 1.5
    min_approach_velocity: float = 1e-3

    def __post_init__(self) -> None:
        _positive("LankaraniNikravesh", "stiffness", self.stiffness)
        _exponent("LankaraniNikravesh", self.exponent)
        _restitution("LankaraniNikravesh", self.restitution)
        _positive("LankaraniNikravesh", "min_approach_velocity", self.min_approach_velocity)

    def force(self, delta: float, delta_dot: float, approach_velocity: float = 0.0
              ) -> tuple[float, float, float]:
        chi = 0.75 * (1.0 - self.restitution**2)
        return _dissipative(self.stiffness, float(self.exponent), chi, delta, delta_dot,
                            approach_velocity, self.min_approach_velocity)


@dataclass(frozen=True, kw_only=True)
class RegularizedCoulomb:
    """Regularised Coulomb friction on the hole ``F_t = −μ f_n v_t/√(|v_t|² + ε_v²)``
    (FORMULATION II §5), ``v_t`` = tangential velocity of Q relative to P."""

    mu: float
    eps_v: float = 1e-4

    def __post_init__(self) -> None:
        _positive("RegularizedCoulomb", "mu", self.mu, allow_zero=True)
        _positive("RegularizedCoulomb", "eps_v", self.eps_v)

    def force(self, v_t: np.ndarray, f_n: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(F_t (3,), ∂F_t/∂v_t (3,3), ∂F_t/∂f_n (3,))``."""
        v = np.asarray(v_t, dtype=float)
        s = math.sqrt(float(v @ v) + self.eps_v**2)
        g = -self.mu * v / s
        F = f_n * g
        dF_dv = -self.mu * f_n * (np.eye(3) / s - np.outer(v, v) / s**3)
        return F, dF_dv, g


LAWS: dict[str, type] = {
    "linear": LinearPenalty,
    "hertz": Hertz,
    "hunt_crossley": HuntCrossley,
    "lankarani_nikravesh": LankaraniNikravesh,
}


def get_law(name: str, **params: float) -> ForceLaw:
    """Normal force law by scenario name, e.g. ``get_law("linear", stiffness=1e6, damping=20)``."""
    try:
        cls = LAWS[name]
    except KeyError:
        known = ", ".join(sorted(LAWS))
        raise ModelError(f"unknown contact law {name!r} (known: {known})") from None
    fields = {f.name: f for f in dataclasses.fields(cls)}
    unknown = sorted(set(params) - set(fields))
    if unknown:
        raise ModelError(f"contact law {name!r}: unknown parameter(s) {', '.join(unknown)} "
                         f"(accepted: {', '.join(fields)})")
    missing = [k for k, f in fields.items()
               if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
               and k not in params]
    if missing:
        raise ModelError(f"contact law {name!r}: missing required parameter(s) {', '.join(missing)}")
    return cls(**params)

"""Time functions for loads and prescribed motion.

A time function is a callable ``f(t) -> float`` with optional first and second derivatives
``f.d1(t)``, ``f.d2(t)`` (needed by prescribed-motion constraints, FORMULATION Part I §6.1).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from ._jit import njit
from .errors import ModelError
from .terms import LOAD_FACTOR

if TYPE_CHECKING:  # pragma: no cover
    from .terms import FunctionTable


class TimeFunction:
    """Base class: value and derivatives. The derivatives are right-sided (the motion after t:
    the initial acceleration of a run needs them at a start where a function is often only
    piecewise smooth); by default second-order forward differences."""

    def __call__(self, t: float) -> float:  # pragma: no cover - abstract
        raise NotImplementedError

    def d1(self, t: float) -> float:
        h = 1e-6
        return (-3.0 * self(t) + 4.0 * self(t + h) - self(t + 2 * h)) / (2 * h)

    def d2(self, t: float) -> float:
        h = 1e-4
        return (2.0 * self(t) - 5.0 * self(t + h) + 4.0 * self(t + 2 * h) - self(t + 3 * h)) / (h * h)


@dataclass(frozen=True)
class Constant(TimeFunction):
    value: float = 1.0

    def __call__(self, t: float) -> float:
        return self.value

    def d1(self, t: float) -> float:
        return 0.0

    def d2(self, t: float) -> float:
        return 0.0


@dataclass(frozen=True, kw_only=True)
class Ramp(TimeFunction):
    """0 before ``start``, linear to ``value`` at ``end``, constant after (smooth=True: cosine ramp)."""

    start: float = 0.0
    end: float = 1.0
    value: float = 1.0
    smooth: bool = False

    def __post_init__(self) -> None:
        if not self.end > self.start:
            raise ModelError(f"Ramp: end ({self.end}) must be > start ({self.start})")

    def __call__(self, t: float) -> float:
        x = min(max((t - self.start) / (self.end - self.start), 0.0), 1.0)
        if self.smooth:
            x = 0.5 - 0.5 * math.cos(math.pi * x)
        return self.value * x

    def _inside(self, t: float) -> float | None:
        """x in [0, 1) where the ramp moves right after t, else None."""
        return (t - self.start) / (self.end - self.start) if self.start <= t < self.end else None

    def d1(self, t: float) -> float:
        x = self._inside(t)
        if x is None:
            return 0.0
        rate = self.value / (self.end - self.start)
        return rate * 0.5 * math.pi * math.sin(math.pi * x) if self.smooth else rate

    def d2(self, t: float) -> float:
        x = self._inside(t)
        if x is None or not self.smooth:
            return 0.0
        w = math.pi / (self.end - self.start)
        return self.value * 0.5 * w * w * math.cos(math.pi * x)


@dataclass(frozen=True, kw_only=True)
class HalfSine(TimeFunction):
    """``amplitude * sin(pi (t - start)/duration)`` for start <= t <= start + duration, else 0."""

    duration: float
    start: float = 0.0
    amplitude: float = 1.0

    def __post_init__(self) -> None:
        if not self.duration > 0:
            raise ModelError(f"HalfSine: duration must be > 0 (got {self.duration})")

    def __call__(self, t: float) -> float:
        x = (t - self.start) / self.duration
        if x < 0.0 or x > 1.0:
            return 0.0
        return self.amplitude * math.sin(math.pi * x)


@dataclass(frozen=True, kw_only=True)
class Sine(TimeFunction):
    """``amplitude * sin(2 pi frequency t + phase)``."""

    amplitude: float = 1.0
    frequency: float = 1.0
    phase: float = 0.0

    def __call__(self, t: float) -> float:
        return self.amplitude * math.sin(2 * math.pi * self.frequency * t + self.phase)

    def d1(self, t: float) -> float:
        w = 2 * math.pi * self.frequency
        return self.amplitude * w * math.cos(w * t + self.phase)

    def d2(self, t: float) -> float:
        w = 2 * math.pi * self.frequency
        return -self.amplitude * w * w * math.sin(w * t + self.phase)


@dataclass(frozen=True)
class Table(TimeFunction):
    """Piecewise-linear interpolation of (times, values), constant outside."""

    times: Sequence[float]
    values: Sequence[float]
    _t: np.ndarray = field(init=False, repr=False)
    _v: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        t = np.asarray(self.times, float)
        v = np.asarray(self.values, float)
        if t.ndim != 1 or t.shape != v.shape or t.size < 1:
            raise ModelError("Table: times and values must be 1-D sequences of equal length >= 1")
        if np.any(np.diff(t) <= 0):
            raise ModelError("Table: times must be strictly increasing")
        object.__setattr__(self, "_t", t)
        object.__setattr__(self, "_v", v)

    def __call__(self, t: float) -> float:
        return float(np.interp(t, self._t, self._v))


@dataclass(frozen=True)
class Function(TimeFunction):
    """Wrap any Python callable ``f(t)``."""

    f: Callable[[float], float]

    def __call__(self, t: float) -> float:
        return float(self.f(t))


def as_time_function(f: TimeFunction | Callable[[float], float] | float | None) -> TimeFunction:
    if f is None:
        return Constant(1.0)
    if isinstance(f, TimeFunction):
        return f
    if isinstance(f, (int, float)):
        return Constant(float(f))
    if callable(f):
        return Function(f)
    raise ModelError(f"not a time function: {f!r} (give a number, a callable f(t) or a TimeFunction)")


# ---------------------------------------------------------------------------------------------
# the external-load term of the assembler (flexmbs.terms)
class LoadsPart(NamedTuple):
    """State-independent external forces: constant (gravity, constant loads) and timed."""

    f_const: np.ndarray              # (n,) constant generalized forces
    idx: np.ndarray                  # timed loads, flattened: coordinate, value, time function
    val: np.ndarray
    fn: np.ndarray


def pack_loads(f_const: np.ndarray, timed: list, functions: FunctionTable) -> LoadsPart:
    """``timed``: (coordinates, values, time function) per load."""
    idx = [np.asarray(i, np.int64).ravel() for i, _, _ in timed]
    val = [np.asarray(v, float).ravel() for _, v, _ in timed]
    fn = [np.full(i.size, functions(f), np.int64) for i, (_, _, f) in zip(idx, timed, strict=True)]
    cat = np.concatenate
    return LoadsPart(np.ascontiguousarray(f_const, dtype=float),
                     cat(idx) if idx else np.zeros(0, np.int64),
                     cat(val) if val else np.zeros(0), cat(fn) if fn else np.zeros(0, np.int64))


@njit
def loads_residual(ld, fv, mode, r):  # noqa: ANN001, ANN201
    """Initialises ``r_q = −λ Q_ext(t)`` (λ: load factor); returns max |r_q|."""
    lf = mode[LOAD_FACTOR]
    n = ld.f_const.size
    for i in range(n):
        r[i] = -lf * ld.f_const[i]
    for k in range(ld.idx.size):
        r[ld.idx[k]] -= lf * fv[ld.fn[k]] * ld.val[k]
    scale = 0.0
    for i in range(n):
        if abs(r[i]) > scale:
            scale = abs(r[i])
    return scale

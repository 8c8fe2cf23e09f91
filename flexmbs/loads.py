"""Time functions for loads and prescribed motion.

A time function is a callable ``f(t) -> float`` with optional first and second derivatives
``f.d1(t)``, ``f.d2(t)`` (needed by prescribed-motion constraints, docs/theory.md §I.6.1).
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
    from .terms import DofMap, FunctionTable


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
    """A time function that is ``value`` at every time.

    Parameters
    ----------
    value : float, default 1
        The value at every time.
    """

    value: float = 1.0

    def __call__(self, t: float) -> float:
        return self.value

    def d1(self, t: float) -> float:
        return 0.0

    def d2(self, t: float) -> float:
        return 0.0


@dataclass(frozen=True, kw_only=True)
class Ramp(TimeFunction):
    """0 before ``start``, linear to ``value`` at ``end``, constant after (smooth=True: cosine ramp).

    Parameters
    ----------
    start : float, default 0
        Time at which the ramp leaves 0 [s].
    end : float, default 1
        Time at which it reaches ``value`` [s].
    value : float, default 1
        Final value.
    smooth : bool, default False
        A cosine ramp instead of a linear one.
    """

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


@dataclass(frozen=True)
class Moves(TimeFunction):
    """A sequence of smooth moves: the sum of cosine :class:`Ramp` s, move i changing the value
    by ``change_i`` between ``start_i`` and ``end_i`` (a feeder that pushes, rests and pushes
    again, starting and stopping each time at rest: no jump in the rate, as a table's corners
    would give).

    Parameters
    ----------
    moves : sequence of (start, end, change)
        The moves [s, s, value]; ``end > start``; they may overlap (their changes add).
    """

    moves: Sequence[tuple[float, float, float]]
    _ramps: tuple[Ramp, ...] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        ramps = []
        for i, move in enumerate(self.moves):
            if len(move) != 3:
                raise ModelError(f"Moves: move {i} must be (start, end, change) (got {move!r})")
            start, end, change = (float(x) for x in move)
            if not end > start:
                raise ModelError(f"Moves: move {i} must end after it starts (start {start:g}, "
                                 f"end {end:g})")
            ramps.append(Ramp(start=start, end=end, value=change, smooth=True))
        if not ramps:
            raise ModelError("Moves: give at least one move (start, end, change)")
        object.__setattr__(self, "_ramps", tuple(ramps))

    def __call__(self, t: float) -> float:
        return sum(r(t) for r in self._ramps)

    def d1(self, t: float) -> float:
        return sum(r.d1(t) for r in self._ramps)

    def d2(self, t: float) -> float:
        return sum(r.d2(t) for r in self._ramps)


@dataclass(frozen=True, kw_only=True)
class HalfSine(TimeFunction):
    """``amplitude * sin(pi (t - start)/duration)`` for start <= t <= start + duration, else 0.

    Parameters
    ----------
    duration : float
        Length of the half wave [s].
    start : float, default 0
        Its start [s].
    amplitude : float, default 1
        Its peak value.
    """

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
    """``amplitude * sin(2 pi frequency t + phase)``.

    Parameters
    ----------
    amplitude : float, default 1
        Amplitude.
    frequency : float, default 1
        Frequency [Hz].
    phase : float, default 0
        Phase [rad].
    """

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
    """Piecewise-linear interpolation of (times, values), constant outside.

    Parameters
    ----------
    times : sequence of float
        Increasing times [s].
    values : sequence of float
        Values at those times.
    """

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
    """Wrap any Python callable ``f(t)``.

    Parameters
    ----------
    f : callable
        ``f(t) -> float``; its derivatives are taken by finite differences.
    """

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
    """External forces: constant (gravity, constant loads), timed, and moments on beam nodes
    (which depend on the node's current slope)."""

    f_const: np.ndarray              # (n,) constant generalized forces
    idx: np.ndarray                  # timed loads, flattened: coordinate, value, time function
    val: np.ndarray
    fn: np.ndarray
    m_slope: np.ndarray              # node moments: (k, 3) slope coordinates of the node
    m_twist: np.ndarray              # (k,) its twist coordinate, −1 without one (the cable)
    m_torque: np.ndarray             # (k, 3) the moment T (global, fixed direction)
    m_base: np.ndarray               # (k, 3) the unit base tangent t̄ of the node's twist
    m_fn: np.ndarray                 # (k,) time function
    m_pos: np.ndarray                # (k, 4, 3) matrix positions of rows [g, φ] × columns g


def pack_loads(f_const: np.ndarray, timed: list, moments: list, functions: FunctionTable,
               dofs: DofMap) -> LoadsPart:
    """``timed``: (coordinates, values, time function) per load; ``moments``: (slope
    coordinates (3,), twist coordinate or −1, T (3,), base tangent (3,), time function) per
    node moment."""
    idx = [np.asarray(i, np.int64).ravel() for i, _, _ in timed]
    val = [np.asarray(v, float).ravel() for _, v, _ in timed]
    fn = [np.full(i.size, functions(f), np.int64) for i, (_, _, f) in zip(idx, timed, strict=True)]
    cat = np.concatenate
    k = len(moments)
    slope = np.array([m[0] for m in moments], np.int64).reshape(k, 3)
    twist = np.array([m[1] for m in moments], np.int64).reshape(k)
    pos = np.full((k, 4, 3), -1, np.int64)
    for i in range(k):
        pos[i, :3] = dofs.positions(slope[i], slope[i]).reshape(3, 3)
        if twist[i] >= 0:
            pos[i, 3] = dofs.positions(twist[i:i + 1], slope[i]).reshape(3)
    return LoadsPart(
        f_const=np.ascontiguousarray(f_const, dtype=float),
        idx=cat(idx) if idx else np.zeros(0, np.int64),
        val=cat(val) if val else np.zeros(0),
        fn=cat(fn) if fn else np.zeros(0, np.int64),
        m_slope=slope,
        m_twist=twist,
        m_torque=np.array([m[2] for m in moments], float).reshape(k, 3),
        m_base=np.array([m[3] for m in moments], float).reshape(k, 3),
        m_fn=np.array([functions(m[4]) for m in moments], np.int64).reshape(k),
        m_pos=pos)


def moments_pattern(moments: list) -> list[tuple[np.ndarray, np.ndarray]]:
    """The blocks node moments write: rows [g, φ] of the node, columns g."""
    out = []
    for slope, twist, *_ in moments:
        rows = np.append(slope, twist) if twist >= 0 else np.asarray(slope)
        out.append((np.asarray(rows, np.int64), np.asarray(slope, np.int64)))
    return out


@njit
def node_moment(g, T, base, twist, Q, dQ):
    """Generalized force of a moment T on a beam node with slope g, and its derivative ∂Q/∂g
    (docs/theory.md §I.1.2, §I.2.3). With t = g/|g|, c = t̄·t:

        Q_g = [T × t − (T·t)(t̄ × t)/(1 + c)] / |g|,   Q_φ = T·t        (an element with a twist)
        Q_g = (T × t)/|g|                                               (the cable: no twist)

    (the virtual rotation of the section is t × δg/|g| about the normals and, with a twist
    coordinate, δφ plus the twist of the smallest rotation from t̄ about t). ``Q`` (4,),
    ``dQ`` (4, 3): rows g and φ."""
    n = math.sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2])
    t = g / n
    P = (np.eye(3) - np.outer(t, t)) / n                       # ∂t/∂g
    Txt = np.array([T[1] * t[2] - T[2] * t[1], T[2] * t[0] - T[0] * t[2],
                    T[0] * t[1] - T[1] * t[0]])
    TX = np.array([[0.0, -T[2], T[1]], [T[2], 0.0, -T[0]], [-T[1], T[0], 0.0]])
    for i in range(3):
        Q[i] = Txt[i] / n
        for j in range(3):
            TP_ij = TX[i, 0] * P[0, j] + TX[i, 1] * P[1, j] + TX[i, 2] * P[2, j]
            dQ[i, j] = TP_ij / n - Q[i] * t[j] / n
    for j in range(3):
        dQ[3, j] = 0.0
    Q[3] = 0.0
    if not twist:
        return
    Tt = T[0] * t[0] + T[1] * t[1] + T[2] * t[2]
    c = base[0] * t[0] + base[1] * t[1] + base[2] * t[2]
    bxt = np.array([base[1] * t[2] - base[2] * t[1], base[2] * t[0] - base[0] * t[2],
                    base[0] * t[1] - base[1] * t[0]])
    BX = np.array([[0.0, -base[2], base[1]], [base[2], 0.0, -base[0]],
                   [-base[1], base[0], 0.0]])
    TP = T @ P                                                  # ∂(T·t)/∂g
    bP = base @ P                                               # ∂c/∂g
    k = 1.0 / ((1.0 + c) * n)
    for i in range(3):
        B = Tt * bxt[i] * k
        Q[i] -= B
        for j in range(3):
            BP_ij = BX[i, 0] * P[0, j] + BX[i, 1] * P[1, j] + BX[i, 2] * P[2, j]
            dB = (bxt[i] * TP[j] + Tt * BP_ij) * k - B * bP[j] / (1.0 + c) - B * t[j] / n
            dQ[i, j] -= dB
    Q[3] = Tt
    for j in range(3):
        dQ[3, j] = TP[j]


@njit(inline="always")
def _moment_of(ld, k, q, g, Q, dQ):
    """``Q``, ``dQ`` of node moment k at ``q`` (``g``: scratch for the node's slope)."""
    for c in range(3):
        g[c] = q[ld.m_slope[k, c]]
    node_moment(g, ld.m_torque[k], ld.m_base[k], ld.m_twist[k] >= 0, Q, dQ)


@njit(internal=True)
def loads_set_bases(ld, log, stop):
    """Re-based nodes (``log[:stop]``, records ``[twist coordinate, t̄, D̄]``, docs/theory.md §I.2.4):
    moments on them read the new base tangent."""
    for k in range(ld.m_twist.size):
        for j in range(stop):
            if ld.m_twist[k] >= 0 and np.int64(log[j, 0]) == ld.m_twist[k]:
                for c in range(3):
                    ld.m_base[k, c] = log[j, 1 + c]


@njit(internal=True)
def loads_residual(ld, q, fv, mode, r):
    """Initialises ``r_q = −λ Q_ext(q, t)`` (λ: load factor); returns max |r_q|."""
    lf = mode[LOAD_FACTOR]
    n = ld.f_const.size
    for i in range(n):
        r[i] = -lf * ld.f_const[i]
    for k in range(ld.idx.size):
        r[ld.idx[k]] -= lf * fv[ld.fn[k]] * ld.val[k]
    if ld.m_fn.size:
        g = np.empty(3)
        Q = np.empty(4)
        dQ = np.empty((4, 3))
        for k in range(ld.m_fn.size):
            _moment_of(ld, k, q, g, Q, dQ)
            f = lf * fv[ld.m_fn[k]]
            for c in range(3):
                r[ld.m_slope[k, c]] -= f * Q[c]
            if ld.m_twist[k] >= 0:
                r[ld.m_twist[k]] -= f * Q[3]
    scale = 0.0
    for i in range(n):
        if abs(r[i]) > scale:
            scale = abs(r[i])
    return scale


@njit(internal=True)
def loads_jacobian(ld, q, fv, mode, cK, data):
    """``−cK λ ∂Q_ext/∂q`` of the node moments into ``data``."""
    if ld.m_fn.size == 0:
        return
    lf = mode[LOAD_FACTOR]
    g = np.empty(3)
    Q = np.empty(4)
    dQ = np.empty((4, 3))
    for k in range(ld.m_fn.size):
        _moment_of(ld, k, q, g, Q, dQ)
        f = cK * lf * fv[ld.m_fn[k]]
        for i in range(4):
            for j in range(3):
                p = ld.m_pos[k, i, j]
                if p >= 0:
                    data[p] -= f * dQ[i, j]

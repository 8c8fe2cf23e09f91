"""Normal contact force laws and regularised Coulomb friction (docs/theory.md §II.5).

Every law is a frozen keyword-only dataclass implementing :class:`ForceLaw`:
``force(delta, delta_dot, approach_velocity) -> (f, df_ddelta, df_ddelta_dot)`` with penetration
``δ = −g_N`` (> 0 in contact), its rate ``δ̇`` and the approach velocity ``δ̇⁽⁻⁾`` stored by the
caller at contact onset. ``f = 0`` for ``δ ≤ 0`` and ``f`` is clamped at 0 when damping would
pull (then both derivatives are 0). :data:`CONTACT_LAWS` (a :class:`~flexmbs.registry.Registry`)
maps scenario names to classes; :func:`get_law` builds one by name with errors naming the unknown
law or the missing/invalid parameter, and the scenario reader uses the same registry (a law's
dataclass fields are its scenario keys).

Every law is one special case of ``f = Kδⁿ(1 + χ δ̇/v₀) + c_d δ̇`` with ``v₀ = max(|δ̇⁽⁻⁾|, v_min)``;
:meth:`parameters` gives ``[K, n, χ, c_d, v_min]`` and :func:`law_force` (numba) evaluates it,
for the Python API and the compiled integrator alike. :func:`coulomb_force` is the numba kernel of
:class:`RegularizedCoulomb`.

Friction of a joint is a :class:`Friction` (scenario ``friction = { mu, mu_static, law, stiffness,
damping, velocity }``): ``law = "stick"`` (default) holds each contact by a tangential spring from
a sticking anchor and lets it slip by the Coulomb return mapping (:func:`coulomb_return_map`,
docs/design-notes.md "Friction that sticks"); ``law = "regularised"`` is the rate law
:func:`coulomb_force`. The kernels read it as the vector :meth:`Friction.parameters`
(``[law code, μ, μ_s, k_t, c_t, ε_v]``).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np

from .._jit import njit
from ..errors import ModelError
from ..registry import Registry

__all__ = [
    "ForceLaw",
    "LinearPenalty",
    "Hertz",
    "HuntCrossley",
    "LankaraniNikravesh",
    "RegularizedCoulomb",
    "Friction",
    "FRICTION_LAWS",
    "CONTACT_LAWS",
    "LAWS",
    "get_law",
    "law_force",
    "held_law_force",
    "mouth_weight",
    "mouth_radius",
    "MOUTH_FADE",
    "N_LAW",
    "DAMPING_ONSET",
    "law_energy",
    "law_dissipates",
    "coulomb_force",
    "coulomb_return_map",
    "tangential_force",
    "as_friction",
    "check_resumed_friction",
    "describe_friction",
]


@njit
def law_force(law, delta, delta_dot, approach_velocity):
    """``(f, ∂f/∂δ, ∂f/∂δ̇)`` of ``f = Kδⁿ(1 + χδ̇/v₀) + c_d s(δ) δ̇`` (docs/theory.md §II.5),
    ``law`` = ``[K, n, χ, c_d, v_min, onset, damping_onset]``, ``v₀ = max(|δ̇⁽⁻⁾|, v_min)``; 0
    for ``δ ≤ 0`` and clamped at 0. With n = 1 and ``onset`` δ₀ > 0 the elastic part is
    ``Kδ²/(2δ₀)`` below δ₀ and ``K(δ − δ₀/2)`` above: C¹, its stiffness grows from 0 instead of
    jumping to K at first touch (:class:`LinearPenalty`). The viscous part's factor ``s`` grows
    from 0 to 1 over the first ``damping_onset`` δ_c of penetration, ``s = x²(3 − 2x)``,
    ``x = δ/δ_c`` (1 beyond, and for δ_c = 0): without it the force jumps from 0 to ``c_d δ̇``
    at first touch, and an implicit step whose contact closes within it can have no solution
    (docs/design-notes.md "The damped penalty in a curved bore (issue 53 item 2)")."""
    if delta <= 0.0:
        return 0.0, 0.0, 0.0
    K, n, chi, c_d, onset = law[0], law[1], law[2], law[3], law[5]
    if n == 1.0:
        if delta < onset:        # the smooth onset: ke grows from 0 to K over the first ``onset``
            fe = 0.5 * K * delta * delta / onset
            ke = K * delta / onset
        else:
            fe = K * (delta - 0.5 * onset)
            ke = K
    else:
        fe = K * delta**n
        ke = n * fe / delta
    cs, dcs = c_d, 0.0           # the viscous coefficient c_d s(δ) and its δ-derivative
    if c_d != 0.0 and delta < law[6]:
        x = delta / law[6]
        cs = c_d * x * x * (3.0 - 2.0 * x)
        dcs = c_d * 6.0 * x * (1.0 - x) / law[6]
    if chi != 0.0:
        v0 = max(abs(approach_velocity), law[4])
        fac = 1.0 + chi * delta_dot / v0
        f = fe * fac + cs * delta_dot
        kt = ke * fac + dcs * delta_dot
        ct = fe * chi / v0 + cs
    else:
        f = fe + cs * delta_dot
        kt = ke + dcs * delta_dot
        ct = cs
    if f <= 0.0:
        return 0.0, 0.0, 0.0
    return f, kt, ct


#: the part of the beam radius over which an open bore's end section lets its contact go as the
#: beam's axis nears the mouth's rim (:func:`mouth_weight`)
MOUTH_FADE = 0.5

#: Gauss–Legendre nodes and weights on [0, 1] (five points: exact for polynomials of degree 9)
_GAUSS_X = (0.04691007703066800, 0.23076534494715845, 0.5, 0.76923465505284155,
            0.95308992296933200)
_GAUSS_W = (0.11846344252809454, 0.23931433524968324, 0.28444444444444444, 0.23931433524968324,
            0.11846344252809454)


@njit
def mouth_weight(delta, mouth):
    """``(w, dw/dδ)``: the weight of a contact at an end section of an open bore, whose law acts
    as ``w(δ) f(δ, δ̇)`` (docs/design-notes.md, "The mouth of an open bore"). ``mouth`` is the
    beam radius r_b there (0 elsewhere: w = 1); ``x = (r_b − δ)/ℓ`` is the distance of the beam's
    axis from the wall (``r_b − δ``) over ``ℓ = MOUTH_FADE r_b``, ``w = x²(3 − 2x)`` clipped to
    [0, 1]. The section ignores a beam whose axis crosses its plane outside the wall (the beam
    outside the mouth); without the weight, a beam whose axis slides in over the rim met a
    contact of a whole radius of penetration, a jump of k r_b. A penetration below
    ``(1 − MOUTH_FADE) r_b`` is not changed."""
    if mouth <= 0.0:
        return 1.0, 0.0
    ell = MOUTH_FADE * mouth
    x = (mouth - delta) / ell
    if x >= 1.0:
        return 1.0, 0.0
    if x <= 0.0:
        return 0.0, 0.0
    return x * x * (3.0 - 2.0 * x), -6.0 * x * (1.0 - x) / ell


@njit
def mouth_radius(open_ends, k, n_sections, r_b):
    """The ``mouth`` argument of :func:`held_law_force` for section ``k`` of a bore's
    ``n_sections`` (its tip sections not counted): the beam radius at an end section of an open
    bore, else 0 (:func:`mouth_weight`)."""
    if open_ends and (k == 0 or k == n_sections - 1):
        return r_b
    return 0.0


@njit
def held_law_force(law, delta, delta_dot, approach_velocity, held, mouth=0.0):
    """:func:`law_force`, and for a contact the Newton iterations hold in the active set
    (``held``, :class:`~flexmbs.solvers.newton.NewtonOptions` ``hold_contacts``) at ``δ ≤ 0``
    the elastic part's extension: ``(Kδ, K, 0)`` for a linear law without onset (the force
    pulls: the held problem has no kink at δ = 0), 0 otherwise (every other law is C¹ there
    with a zero slope, so its extension is 0). The held set is made consistent with the gaps
    before a step is accepted, so no converged state holds a pulling contact. ``mouth``: the
    beam radius at an end section of an open bore, whose force is weighted by
    :func:`mouth_weight` (its derivatives by the product rule), else 0."""
    if held and delta <= 0.0:
        if law[1] == 1.0 and law[5] == 0.0:
            return law[0] * delta, law[0], 0.0
        return 0.0, 0.0, 0.0
    f, kt, ct = law_force(law, delta, delta_dot, approach_velocity)
    if mouth > 0.0:
        w, dw = mouth_weight(delta, mouth)
        return w * f, w * kt + dw * f, w * ct
    return f, kt, ct


@njit
def law_energy(law, delta, mouth=0.0):
    """Potential ``Φ(δ) = Kδⁿ⁺¹/(n + 1)`` of the elastic part of :func:`law_force` (``Φ′ = Kδⁿ``;
    0 for ``δ ≤ 0``; with an onset δ₀: ``Kδ³/(6δ₀)``, then ``K(δ²/2 − δ₀δ/2 + δ₀²/6)``): the
    section potential of docs/theory.md §II.4b. The damping terms have none. ``mouth`` (the
    beam radius at an end section of an open bore, :func:`mouth_weight`): ``Φ′ = w f``, the
    part above ``(1 − MOUTH_FADE) r_b`` by five-point Gauss–Legendre (exact for the linear law
    past its onset; ``w f`` is a polynomial of degree 4 there)."""
    if delta <= 0.0:
        return 0.0
    if mouth > 0.0:
        start = (1.0 - MOUTH_FADE) * mouth
        if delta > start:
            top = min(delta, mouth)
            acc = 0.0
            for i in range(5):
                s = start + _GAUSS_X[i] * (top - start)
                w, _ = mouth_weight(s, mouth)
                acc += _GAUSS_W[i] * w * law_force(law, s, 0.0, 1.0)[0]
            return _elastic_energy(law, start) + acc * (top - start)
    return _elastic_energy(law, delta)


@njit
def _elastic_energy(law, delta):
    """:func:`law_energy` without a mouth (``delta`` > 0)."""
    n, onset = law[1], law[5]
    if n == 1.0 and onset > 0.0:
        if delta < onset:
            return law[0] * delta**3 / (6.0 * onset)
        return law[0] * (0.5 * delta * delta - 0.5 * onset * delta + onset * onset / 6.0)
    return law[0] * delta ** (n + 1.0) / (n + 1.0)


@njit
def coulomb_force(mu, eps_v, v_t, f_n, F, dF_dv, g):
    """Regularised Coulomb ``F = −μ f_n v_t/√(|v_t|² + ε²)`` into ``F`` (3,), ``dF_dv`` (3,3) and
    ``g = ∂F/∂f_n`` (3,) (docs/theory.md §II.5)."""
    s = math.sqrt(v_t[0] * v_t[0] + v_t[1] * v_t[1] + v_t[2] * v_t[2] + eps_v * eps_v)
    c = -mu * f_n
    for i in range(3):
        g[i] = -mu * v_t[i] / s
        F[i] = f_n * g[i]
        for j in range(3):
            dF_dv[i, j] = c * ((1.0 if i == j else 0.0) / s - v_t[i] * v_t[j] / s**3)


@njit
def coulomb_return_map(T, radius, F, dF_dT, t_hat):
    """Coulomb return mapping of a trial tangential force ``T`` (3,) onto the friction cone of
    radius ``ρ = μ f_N`` (docs/design-notes.md "Friction that sticks"). Stick, ``|T| ≤ ρ``:
    ``F = T``, ``∂F/∂T = I``, ``t̂ = 0``; slip: ``F = ρ T/|T|``, ``∂F/∂T = ρ/|T| (I − t̂t̂ᵀ)``,
    ``t̂ = T/|T| = ∂F/∂ρ``. Writes ``F``, ``dF_dT`` (3,3), ``t_hat``; returns True when sticking."""
    nT = math.sqrt(T[0] * T[0] + T[1] * T[1] + T[2] * T[2])
    if nT <= radius:
        for i in range(3):
            F[i] = T[i]
            t_hat[i] = 0.0
            for j in range(3):
                dF_dT[i, j] = 1.0 if i == j else 0.0
        return True
    c = radius / nT
    for i in range(3):
        t_hat[i] = T[i] / nT
    for i in range(3):
        F[i] = radius * t_hat[i]
        for j in range(3):
            dF_dT[i, j] = c * ((1.0 if i == j else 0.0) - t_hat[i] * t_hat[j])
    return False


@njit
def tangential_force(fric, stuck, f_n, d, v_t, F, dF_dd, dF_dv, dF_dfn, d_new):
    """Friction force of one contact from the parameter vector ``fric`` (:meth:`Friction.parameters`)
    with its derivatives (docs/design-notes.md "Friction that sticks").

    ``d`` (3): trial elastic tangential displacement from the sticking anchor, ``v_t`` (3):
    tangential slip velocity, both in the tangent plane; ``stuck``: the contact stuck at the end
    of the last step (its cone then has μ_s, else μ). Stick law: trial ``T = −k_t d − c_t v_t``,
    ``F`` = :func:`coulomb_return_map` of T on ``μ f_n``; ``d_new`` = the anchor's elastic
    displacement after the step (``d`` in stick, ``−F/k_t`` in slip). Regularised law:
    :func:`coulomb_force` of ``v_t`` (``dF_dd`` = 0, ``d_new`` = 0). Writes ``F``, ``dF_dd``,
    ``dF_dv`` (3, 3), ``dF_dfn``, ``d_new`` (3); returns 1.0 when sticking, else 0.0."""
    code = fric[0]
    if code == FRICTION_REGULARISED:
        coulomb_force(fric[1], fric[5], v_t, f_n, F, dF_dv, dF_dfn)
        for i in range(3):
            d_new[i] = 0.0
            for j in range(3):
                dF_dd[i, j] = 0.0
        return 0.0
    k_t, c_t = fric[3], fric[4]
    mu = fric[2] if stuck > 0.5 else fric[1]
    T = np.empty(3)
    for i in range(3):
        T[i] = -k_t * d[i] - c_t * v_t[i]
    dF_dT = np.empty((3, 3))
    sticking = coulomb_return_map(T, mu * f_n, F, dF_dT, dF_dfn)
    for i in range(3):
        dF_dfn[i] *= mu
        d_new[i] = d[i] if sticking else -F[i] / k_t
        for j in range(3):
            dF_dd[i, j] = -k_t * dF_dT[i, j]
            dF_dv[i, j] = -c_t * dF_dT[i, j]
    return 1.0 if sticking else 0.0


#: entries of a force law's parameters (:meth:`ForceLaw.parameters`)
N_LAW = 7
#: a damped :class:`LinearPenalty` without an onset ramps its viscous force in over this
#: fraction of a clearance joint's radial clearance (:meth:`LinearPenalty.for_clearance`)
DAMPING_ONSET = 1e-3


@runtime_checkable
class ForceLaw(Protocol):
    """Normal force law ``f_N(δ, δ̇; δ̇⁽⁻⁾)`` (docs/theory.md §II.5)."""

    def force(self, delta: float, delta_dot: float, approach_velocity: float = 0.0
              ) -> tuple[float, float, float]:
        """``(f, ∂f/∂δ, ∂f/∂δ̇)``; f ≥ 0, f = 0 for δ ≤ 0."""
        ...

    def parameters(self) -> np.ndarray:
        """``[K, n, χ, c_d, v_min, onset, damping_onset]`` (:data:`N_LAW`) of the common form evaluated by
        :func:`law_force`."""
        ...


def law_dissipates(law: ForceLaw) -> bool:
    """Whether a normal law takes energy out of the motion: a damping term (``χ`` or ``c_d`` of
    :meth:`ForceLaw.parameters`) that is not zero."""
    p = law.parameters()
    return bool(p[2] != 0.0 or p[3] != 0.0)


def _positive(cls: str, name: str, value: object, *, allow_zero: bool = False) -> None:
    ok = isinstance(value, (int, float, np.floating)) and not isinstance(value, bool) \
        and math.isfinite(float(value)) and (float(value) >= 0.0 if allow_zero else float(value) > 0.0)
    if not ok:
        need = ">= 0" if allow_zero else "> 0"
        raise ModelError(f"{cls}: {name} must be a finite number {need} (got {value!r})")


def _exponent(cls: str, value: object) -> None:
    _positive(cls, "exponent", value)
    if float(value) < 1.0:  # type: ignore[arg-type]
        raise ModelError(f"{cls}: exponent must be >= 1 for a stiffening contact (got {value!r})")


def _restitution(cls: str, value: object) -> None:
    _positive(cls, "restitution", value)
    if float(value) > 1.0:  # type: ignore[arg-type]
        raise ModelError(f"{cls}: restitution must be in (0, 1] (got {value!r})")


class _CommonForm:
    """``force`` through the compiled :func:`law_force` of :meth:`parameters`."""

    def parameters(self) -> np.ndarray:  # pragma: no cover - every law overrides it
        raise NotImplementedError

    def force(self, delta: float, delta_dot: float, approach_velocity: float = 0.0
              ) -> tuple[float, float, float]:
        return law_force(self.parameters(), float(delta), float(delta_dot),
                         float(approach_velocity))


@dataclass(frozen=True, kw_only=True)
class LinearPenalty(_CommonForm):
    """Linear penalty + viscous damping ``f = kδ + c_d δ̇`` (docs/theory.md §II.5, Exudyn's choice).

    ``onset`` δ₀ [m] (default 0): the force grows quadratically over the first δ₀ of
    penetration, ``kδ²/(2δ₀)``, then ``k(δ − δ₀/2)``: the law is C¹, so a contact that only
    grazes (a slack wire in its holes) does not throw Newton between "open, no stiffness" and
    "closed, stiffness k"; a loaded contact sits δ₀/2 deeper (design notes, "Statics of
    tendon-routed structures"). A small fraction of the clearance, e.g. 1e-3 of it.

    ``damping_onset`` δ_c [m]: the viscous part grows as ``c_d s(δ) δ̇``, ``s = x²(3 − 2x)``,
    ``x = δ/δ_c``, over the first δ_c of penetration (``s = 1`` beyond). Without it the force
    jumps from 0 to ``c_d δ̇`` at first touch, and an implicit step whose contact closes
    within that jump has no solution: Newton cycles between the contact open and closed at
    any step size (docs/design-notes.md "The damped penalty in a curved bore (issue 53 item
    2)"). ``None`` (default): ``onset`` when that is > 0, else a clearance joint takes
    :data:`DAMPING_ONSET` of its radial clearance; 0: no ramp (the law as written above).

    Parameters
    ----------
    stiffness : float
        k [N/m].
    damping : float, default 0
        c_d [N s/m].
    onset : float, default 0
        δ₀ [m]: the penetration over which the elastic force rises smoothly.
    damping_onset : float, optional
        δ_c [m]: the penetration over which the viscous force rises smoothly (default: above).
    """

    stiffness: float = field(metadata={"unit": "N/m", "gt": 0.0})
    damping: float = field(default=0.0, metadata={"unit": "N s/m", "ge": 0.0})
    onset: float = field(default=0.0, metadata={"unit": "m", "ge": 0.0})
    damping_onset: float | None = field(default=None, metadata={"unit": "m", "ge": 0.0})

    def __post_init__(self) -> None:
        _positive("LinearPenalty", "stiffness", self.stiffness)
        _positive("LinearPenalty", "damping", self.damping, allow_zero=True)
        _positive("LinearPenalty", "onset", self.onset, allow_zero=True)
        if self.damping_onset is not None:
            _positive("LinearPenalty", "damping_onset", self.damping_onset, allow_zero=True)

    def parameters(self) -> np.ndarray:
        ramp = self.onset if self.damping_onset is None else self.damping_onset
        return np.array([self.stiffness, 1.0, 0.0, self.damping, 0.0, self.onset, ramp],
                        dtype=float)

    def for_clearance(self, clearance: float) -> LinearPenalty:
        """The law a clearance joint of radial ``clearance`` [m] uses: with damping and
        neither ``onset`` nor ``damping_onset`` given, the viscous force ramps in over
        :data:`DAMPING_ONSET` of the clearance; otherwise the law itself."""
        if self.damping > 0.0 and self.damping_onset is None and self.onset == 0.0:
            return dataclasses.replace(self, damping_onset=DAMPING_ONSET * float(clearance))
        return self


@dataclass(frozen=True, kw_only=True)
class Hertz(_CommonForm):
    """Hertz-type ``f = Kδⁿ`` (n = 3/2 point contact, ≈ 1–1.1 line-like; docs/theory.md §II.5).

    Parameters
    ----------
    stiffness : float
        K [N/m^n].
    exponent : float, default 1.5
        n.
    """

    stiffness: float = field(metadata={"unit": "N/m^n", "gt": 0.0})
    exponent: float = field(default=1.5, metadata={"unit": "1", "ge": 1.0})

    def __post_init__(self) -> None:
        _positive("Hertz", "stiffness", self.stiffness)
        _exponent("Hertz", self.exponent)

    def parameters(self) -> np.ndarray:
        return np.array([self.stiffness, self.exponent, 0.0, 0.0, 0.0, 0.0, 0.0], dtype=float)


@dataclass(frozen=True, kw_only=True)
class HuntCrossley(_CommonForm):
    """Hunt–Crossley ``f = Kδⁿ[1 + 3(1−e)/2 · δ̇/δ̇⁽⁻⁾]`` (docs/theory.md §II.5).

    ``min_approach_velocity`` guards ``δ̇⁽⁻⁾ → 0`` (resting contact): the approach velocity used is
    ``max(|δ̇⁽⁻⁾|, min_approach_velocity)``, so the damping coefficient stays bounded.

    Parameters
    ----------
    stiffness : float
        K [N/m^n].
    restitution : float
        Coefficient of restitution e, in [0, 1].
    exponent : float, default 1.5
        n.
    min_approach_velocity : float, default 1e-3
        Lower bound of the approach velocity used in the damping term [m/s].
    """

    stiffness: float = field(metadata={"unit": "N/m^n", "gt": 0.0})
    restitution: float = field(metadata={"unit": "1", "gt": 0.0, "le": 1.0})
    exponent: float = field(default=1.5, metadata={"unit": "1", "ge": 1.0})
    min_approach_velocity: float = field(default=1e-3, metadata={"unit": "m/s", "gt": 0.0})

    def __post_init__(self) -> None:
        _positive("HuntCrossley", "stiffness", self.stiffness)
        _exponent("HuntCrossley", self.exponent)
        _restitution("HuntCrossley", self.restitution)
        _positive("HuntCrossley", "min_approach_velocity", self.min_approach_velocity)

    def parameters(self) -> np.ndarray:
        chi = 1.5 * (1.0 - self.restitution)
        return np.array([self.stiffness, self.exponent, chi, 0.0, self.min_approach_velocity,
                         0.0, 0.0], dtype=float)


@dataclass(frozen=True, kw_only=True)
class LankaraniNikravesh(_CommonForm):
    """Lankarani–Nikravesh (1990) ``f = Kδⁿ[1 + 3(1−e²)/4 · δ̇/δ̇⁽⁻⁾]`` (docs/theory.md §II.5);
    same approach-velocity guard as :class:`HuntCrossley`.

    Parameters
    ----------
    stiffness : float
        K [N/m^n].
    restitution : float
        Coefficient of restitution e, in [0, 1].
    exponent : float, default 1.5
        n.
    min_approach_velocity : float, default 1e-3
        Lower bound of the approach velocity used in the damping term [m/s].
    """

    stiffness: float = field(metadata={"unit": "N/m^n", "gt": 0.0})
    restitution: float = field(metadata={"unit": "1", "gt": 0.0, "le": 1.0})
    exponent: float = field(default=1.5, metadata={"unit": "1", "ge": 1.0})
    min_approach_velocity: float = field(default=1e-3, metadata={"unit": "m/s", "gt": 0.0})

    def __post_init__(self) -> None:
        _positive("LankaraniNikravesh", "stiffness", self.stiffness)
        _exponent("LankaraniNikravesh", self.exponent)
        _restitution("LankaraniNikravesh", self.restitution)
        _positive("LankaraniNikravesh", "min_approach_velocity", self.min_approach_velocity)

    def parameters(self) -> np.ndarray:
        chi = 0.75 * (1.0 - self.restitution**2)
        return np.array([self.stiffness, self.exponent, chi, 0.0, self.min_approach_velocity,
                         0.0, 0.0], dtype=float)


@dataclass(frozen=True, kw_only=True)
class RegularizedCoulomb:
    """Regularised Coulomb friction on the hole ``F_t = −μ f_n v_t/√(|v_t|² + ε_v²)``
    (docs/theory.md §II.5), ``v_t`` = tangential velocity of Q relative to P.

    Parameters
    ----------
    mu : float
        Friction coefficient μ.
    eps_v : float, default 1e-4
        Velocity scale ε_v [m/s].
    """

    mu: float
    eps_v: float = 1e-4

    def __post_init__(self) -> None:
        _positive("RegularizedCoulomb", "mu", self.mu, allow_zero=True)
        _positive("RegularizedCoulomb", "eps_v", self.eps_v)

    def force(self, v_t: np.ndarray, f_n: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(F_t (3,), ∂F_t/∂v_t (3,3), ∂F_t/∂f_n (3,))``."""
        F, dF_dv, g = np.empty(3), np.empty((3, 3)), np.empty(3)
        coulomb_force(float(self.mu), float(self.eps_v), np.ascontiguousarray(v_t, dtype=float),
                      float(f_n), F, dF_dv, g)
        return F, dF_dv, g


#: friction laws of :class:`Friction` (scenario ``friction = { law = ... }``)
FRICTION_LAWS = ("stick", "regularised")
#: law codes of :meth:`Friction.parameters` ``[code, μ, μ_s, k_t, c_t, ε_v]``
FRICTION_NONE, FRICTION_REGULARISED, FRICTION_STICK = 0.0, 1.0, 2.0
N_FRICTION = 6


@dataclass(frozen=True, kw_only=True)
class Friction:
    """Coulomb friction of a joint's contacts (issue "friction that sticks").

    ``law = "stick"`` (default): an elastic–plastic tangential law. Each contact is held by a
    tangential spring (``stiffness`` k_t [N/m], optional ``damping`` c_t [N s/m]) from a
    sticking anchor in the material coordinates of both parts; when the trial force leaves the
    cone μ f_N the contact slips and the anchor is returned onto the cone. The cone's
    coefficient is ``mu_static`` while the contact sticks and ``mu`` (kinetic) while it slips
    (``mu_static ≥ mu``, default equal). ``stiffness=None`` lets the joint choose (the
    clearance joint: the normal law's stiffness; the sliding joint: the axial stiffness EA/L of
    one beam element). ``law = "regularised"``: ``F = −μ f_N v_t/√(|v_t|² + velocity²)``, which
    cannot hold a contact still (it creeps at a speed ∝ ``velocity``).

    Parameters
    ----------
    mu : float
        Kinetic (sliding) friction coefficient.
    mu_static : float, optional
        Static coefficient of the stick law (default ``mu``; at least ``mu``).
    law : {"stick", "regularised"}, default "stick"
        The tangential law.
    stiffness : float, optional
        Tangential stiffness k_t of the stick law [N/m] (default: chosen by the joint).
    damping : float, default 0
        Tangential damping c_t of the stick law [N s/m].
    velocity : float, default 1e-3
        Velocity scale of the regularised law [m/s].
    """

    mu: float
    mu_static: float | None = None
    law: str = "stick"
    stiffness: float | None = None
    damping: float = 0.0
    velocity: float = 1e-3

    def __post_init__(self) -> None:
        _positive("Friction", "mu", self.mu, allow_zero=True)
        if self.law not in FRICTION_LAWS:
            raise ModelError(f"Friction: law must be one of {', '.join(map(repr, FRICTION_LAWS))} "
                             f"(got {self.law!r})")
        if self.mu_static is not None:
            _positive("Friction", "mu_static", self.mu_static, allow_zero=True)
            if float(self.mu_static) < float(self.mu):
                raise ModelError(f"Friction: mu_static ({self.mu_static}) must be >= mu "
                                 f"({self.mu}): the static coefficient is not below the kinetic one")
        if self.stiffness is not None:
            _positive("Friction", "stiffness", self.stiffness)
        _positive("Friction", "damping", self.damping, allow_zero=True)
        _positive("Friction", "velocity", self.velocity)
        if self.law == "regularised":
            if self.mu_static is not None and float(self.mu_static) != float(self.mu):
                raise ModelError("Friction: law \"regularised\" has one coefficient; mu_static "
                                 "needs law = \"stick\"")
            if self.stiffness is not None or self.damping:
                raise ModelError("Friction: stiffness and damping belong to law = \"stick\" "
                                 "(law \"regularised\" takes velocity)")

    @property
    def static_coefficient(self) -> float:
        return float(self.mu if self.mu_static is None else self.mu_static)

    def parameters(self, default_stiffness: float) -> np.ndarray:
        """``[law code, μ, μ_s, k_t, c_t, ε_v]`` (:data:`N_FRICTION`) for the kernels;
        ``default_stiffness`` is the joint's k_t when ``stiffness`` is not given."""
        code = FRICTION_STICK if self.law == "stick" else FRICTION_REGULARISED
        if float(self.mu) == 0.0 and self.static_coefficient == 0.0:
            code = FRICTION_NONE
        k_t = float(self.stiffness) if self.stiffness is not None else float(default_stiffness)
        return np.array([code, float(self.mu), self.static_coefficient, k_t, float(self.damping),
                         float(self.velocity)], dtype=float)


def no_friction() -> np.ndarray:
    """The parameter vector of a frictionless joint (law code :data:`FRICTION_NONE`)."""
    return np.array([FRICTION_NONE, 0.0, 0.0, 1.0, 0.0, 1.0], dtype=float)


def describe_friction(p: object) -> str:
    """A friction parameter vector (:meth:`Friction.parameters`) in words, as a scenario table."""
    v = [float(x) for x in np.asarray(p, dtype=float).ravel()]
    if len(v) != N_FRICTION:
        return f"parameters {v}"
    if v[0] == FRICTION_NONE:
        return "none"
    g = [f"{x:g}" if float(f"{x:g}") == x else repr(x) for x in v]
    if v[0] == FRICTION_STICK:
        return (f"{{law = \"stick\", mu = {g[1]}, mu_static = {g[2]}, stiffness = {g[3]}, "
                f"damping = {g[4]}}}")
    return f"{{law = \"regularised\", mu = {g[1]}, velocity = {g[5]}}}"


def check_resumed_friction(joint: str, saved: object, now: np.ndarray) -> None:
    """A checkpoint's friction parameters (``None``: an older checkpoint, accepted) must be the
    model's: the anchors were computed with them. Raises :class:`ModelError` naming both."""
    if saved is None:
        return
    old = np.asarray(saved, dtype=float)
    if old.shape != now.shape or np.any(old != now):
        raise ModelError(f"joint '{joint}': the checkpoint was written with friction "
                         f"{describe_friction(old)} and the model now has "
                         f"{describe_friction(now)}; a resumed run must keep the friction law "
                         "(run without --resume to start over)")


#: scenario name -> normal force law class (``contact = { law = ... }``), alphabetical
CONTACT_LAWS: Registry[type] = Registry("contact law")
CONTACT_LAWS.register("hertz", Hertz)
CONTACT_LAWS.register("hunt_crossley", HuntCrossley)
CONTACT_LAWS.register("lankarani_nikravesh", LankaraniNikravesh)
CONTACT_LAWS.register("linear", LinearPenalty)

#: the former name of :data:`CONTACT_LAWS` (same object)
LAWS = CONTACT_LAWS


def get_law(name: str, **params: float) -> ForceLaw:
    """Normal force law by scenario name, e.g. ``get_law("linear", stiffness=1e6, damping=20)``."""
    cls = CONTACT_LAWS.get(name)
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


def as_friction(friction: Friction | RegularizedCoulomb | float | None,
                friction_velocity: float | None = None) -> Friction | None:
    """Friction of a joint given as a :class:`Friction`, a :class:`RegularizedCoulomb` or a
    coefficient; a coefficient alone gets the stick law, with ``friction_velocity`` the
    regularised law (the form of earlier versions). ``None`` or 0: frictionless. Both joints
    take friction this way."""
    if friction is None:
        return None
    if isinstance(friction, RegularizedCoulomb):
        friction = Friction(mu=float(friction.mu), law="regularised", velocity=float(friction.eps_v))
    if isinstance(friction, Friction):
        return None if float(friction.mu) == 0.0 and friction.static_coefficient == 0.0 else friction
    if isinstance(friction, bool) or not isinstance(friction, (int, float, np.floating)):
        raise ModelError(f"friction must be a coefficient, a Friction or None (got {friction!r})")
    mu = float(friction)
    if mu == 0.0:
        return None
    if friction_velocity is not None:
        return Friction(mu=mu, law="regularised", velocity=float(friction_velocity))
    return Friction(mu=mu)

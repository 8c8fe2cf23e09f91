"""Sliding joint without clearance: a rigid body whose hole axis slides along an ANCF beam.

Sugiyama, Escalona & Shabana, Nonlinear Dyn. 31 (2003) 167-195: the arc-length parameter ``s``
of the contact point is an extra unknown without inertia (docs/theory.md §II.7)::

    Phi = [ r_H + A u_C - r(s) ;  (A y)·r'(s) ;  (A z)·r'(s) ] = 0     (cylindrical: 3 + 2)
    Phi = [ r_H + A u_C - r(s) ]                                       (ring: 3)
    Phi_s^T lam = Q_s                                                  (row of s)

``Q_s = |r'| (f_ax(t) + F)`` adds a prescribed axial force on the body along the beam tangent
and Coulomb friction F on the normal reaction N = |lam_pos,⊥| (:func:`sliding_axial_force`):
the stick law (an elastic–plastic tangential spring from a sticking anchor, Coulomb return
mapping) or the regularised law ``F = −μ N tanh(ṡ/ε_v)``. ``s`` is the reference arc length
from the beam's first node; within a step the current element's cubic is evaluated (also
slightly beyond its ends), and the element index and the friction anchor are updated after
each converged step.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, Literal, NamedTuple

import numpy as np

from .._jit import njit
from ..codes import ERROR_CODES
from ..contact.laws import (
    FRICTION_NONE,
    FRICTION_STICK,
    N_FRICTION,
    Friction,
    RegularizedCoulomb,
    as_friction,
    check_resumed_friction,
    coulomb_return_map,
    no_friction,
)
from ..elements import hermite
from ..elements.centerline import closest_point
from ..elements.hermite import CENTERLINE_SIZE, hermite_basis, shape_xi
from ..elements.rigid_body import point_jacobian_of, point_tensor, rotation_matrix
from ..errors import FlexmbsError, ModelError, SimulationStopped
from ..loads import TimeFunction, as_time_function
from ..terms import pad_stack
from .base import Constraint
from .interaction import EnergyFlow, Following, Interaction, InteractionKind, ModelParts

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Beam, RigidBody
    from ..terms import DofMap, PackContext


#: local coordinates of the joint ``[r_H (3), p (4), e_k (centreline), s]`` and the index of s
S_INDEX = 7 + CENTERLINE_SIZE
N_SLIDE = S_INDEX + 1


@njit
def _shape_x(xi, L):
    """Hermite S1..S4 and their x-derivatives (as :func:`flexmbs.elements.hermite.shape_functions`)."""
    S, dS, ddS = shape_xi(xi, L)
    return S, dS / L, ddS / (L * L)


@njit
def sliding_values(ql, L, start, T, n_eq, phi, jac):
    """Φ and Φ_q of the sliding joint on one element (Sugiyama et al. 2003, docs/theory.md §II.7).

    ``ql = [r_H, p, e_k (CENTERLINE_SIZE), s]`` (N_SLIDE); ``T`` (3, 3, 4, 4) = point tensors of
    the hole point u_C and the body axes y, z (``(A w)_k = pᵀT_k(w)p``); ``n_eq`` = 3 (ring) or 5
    (cylindrical). Writes ``phi`` (n_eq,) and ``jac`` (n_eq, N_SLIDE)."""
    p = ql[3:7]
    S, dS, ddS = _shape_x((ql[S_INDEX] - start) / L, L)
    for i in range(n_eq):
        for j in range(N_SLIDE):
            jac[i, j] = 0.0
    Bw = np.empty((3, 3, 4))        # ∂(A w)/∂p = 2T(w)p and A w for w = u, y, z
    Aw = np.empty((3, 3))
    for w in range(3):
        point_jacobian_of(T[w], p, Bw[w], Aw[w])
    r = np.zeros(3)
    r1 = np.zeros(3)
    r2 = np.zeros(3)
    for m in range(4):
        for c in range(3):
            e = ql[7 + 3 * m + c]
            r[c] += S[m] * e
            r1[c] += dS[m] * e
            r2[c] += ddS[m] * e
    for c in range(3):
        phi[c] = ql[c] + Aw[0, c] - r[c]
        jac[c, c] = 1.0
        for a in range(4):
            jac[c, 3 + a] = Bw[0, c, a]
        for m in range(4):
            jac[c, 7 + 3 * m + c] = -S[m]
        jac[c, S_INDEX] = -r1[c]
    if n_eq == 5:
        for i in range(2):
            w = 1 + i
            phi[3 + i] = Aw[w, 0] * r1[0] + Aw[w, 1] * r1[1] + Aw[w, 2] * r1[2]
            for a in range(4):
                jac[3 + i, 3 + a] = (r1[0] * Bw[w, 0, a] + r1[1] * Bw[w, 1, a]
                                     + r1[2] * Bw[w, 2, a])
            for m in range(4):
                for c in range(3):
                    jac[3 + i, 7 + 3 * m + c] = dS[m] * Aw[w, c]
            jac[3 + i, S_INDEX] = Aw[w, 0] * r2[0] + Aw[w, 1] * r2[1] + Aw[w, 2] * r2[2]


@njit
def sliding_hessian(ql, L, start, T, n_eq, lam, H):
    """``H = Σ_i λ_i ∂²Φ_i/∂q²`` (N_SLIDE, N_SLIDE) of :func:`sliding_values` (exact, symmetric)."""
    p = ql[3:7]
    S, dS, ddS = _shape_x((ql[S_INDEX] - start) / L, L)
    _, _, _, t3 = hermite_basis((ql[S_INDEX] - start) / L, L)
    d3 = np.empty(4)             # d³S/dx³
    for m in range(4):
        d3[m] = t3[m] / (L * L * L)
    r1 = np.zeros(3)
    r2 = np.zeros(3)
    r3 = np.zeros(3)
    for m in range(4):
        for c in range(3):
            e = ql[7 + 3 * m + c]
            r1[c] += dS[m] * e
            r2[c] += ddS[m] * e
            r3[c] += d3[m] * e
    for i in range(N_SLIDE):
        for j in range(N_SLIDE):
            H[i, j] = 0.0
    for a in range(4):
        for b in range(4):
            acc = 0.0
            for k in range(3):
                acc += lam[k] * T[0, k, a, b]
            H[3 + a, 3 + b] = 2.0 * acc
    for m in range(4):
        for c in range(3):
            H[7 + 3 * m + c, S_INDEX] = -dS[m] * lam[c]
    H[S_INDEX, S_INDEX] = -(lam[0] * r2[0] + lam[1] * r2[1] + lam[2] * r2[2])
    if n_eq == 5:
        for i in range(2):
            mu = lam[3 + i]
            if mu == 0.0:
                continue
            Tw = T[1 + i]
            Bw = np.empty((3, 4))        # ∂(A w)/∂p = 2 T(w) p and A w
            aw = np.empty(3)
            point_jacobian_of(Tw, p, Bw, aw)
            for a in range(4):
                for b in range(4):
                    H[3 + a, 3 + b] += mu * 2.0 * (r1[0] * Tw[0, a, b] + r1[1] * Tw[1, a, b]
                                                   + r1[2] * Tw[2, a, b])
                for m in range(4):
                    for c in range(3):
                        H[3 + a, 7 + 3 * m + c] += mu * Bw[c, a] * dS[m]
                H[3 + a, S_INDEX] += mu * (Bw[0, a] * r2[0] + Bw[1, a] * r2[1] + Bw[2, a] * r2[2])
            for m in range(4):
                for c in range(3):
                    H[7 + 3 * m + c, S_INDEX] += mu * ddS[m] * aw[c]
            H[S_INDEX, S_INDEX] += mu * (aw[0] * r3[0] + aw[1] * r3[1] + aw[2] * r3[2])
    for a in range(4):          # symmetric off-diagonal blocks
        for j in range(7, N_SLIDE):
            H[j, 3 + a] = H[3 + a, j]
    for j in range(7, S_INDEX):
        H[S_INDEX, j] = H[j, S_INDEX]


@njit
def sliding_axial_force(q_elem, L, start, s, s_rate, lam_pos, fr, anchor, stuck, f_axial):
    """Generalized force on s, ``Q_s = |r′|(f_ax + F)`` (docs/theory.md §II.7), and its exact
    derivatives. ``fr`` = :meth:`~flexmbs.contact.laws.Friction.parameters` ``[law, μ, μ_s, k_t,
    c_t, ε_v]``; N = |λ_⊥|, ``λ_⊥ = λ_pos − (λ_pos·t)t``.

    Stick law (docs/design-notes.md "Friction that sticks: the sliding joint"): trial force
    ``T = −k_t|r′|(s − s_A) − c_t|r′|ṡ`` from the anchor ``s_A`` (the beam's material
    coordinate where the body sticks), returned onto the cone ``ρ = μ_eff N`` (μ_eff = μ_s if
    ``stuck`` else μ) by :func:`~flexmbs.contact.laws.coulomb_return_map`. Regularised law:
    ``F = −μ N tanh(ṡ/ε_v)``. With ``dN = n̂·dλ − (λ·t)/|r′| n̂·dr′`` (n̂ = λ_⊥/N: the turn of t
    included) and ``dr′ = Σ S′_m de_m + r″ ds``, ``d|r′| = t·dr′``.

    Returns ``(Q_s, ∂Q_s/∂e (CENTERLINE_SIZE,), ∂Q_s/∂s, ∂Q_s/∂λ_pos (3,), ∂Q_s/∂ṡ, F,
    sticking, anchor after the step)``; the anchor moves onto the cone when slipping,
    ``s_A = s + F/(k_t|r′|)``."""
    _, dS, ddS = _shape_x((s - start) / L, L)
    r1 = np.zeros(3)
    r2 = np.zeros(3)
    for m in range(4):
        for c in range(3):
            r1[c] += dS[m] * q_elem[3 * m + c]
            r2[c] += ddS[m] * q_elem[3 * m + c]
    nr = math.sqrt(r1[0] * r1[0] + r1[1] * r1[1] + r1[2] * r1[2])
    t = r1 / nr
    code = fr[0]
    F = 0.0
    dQ_dnr = f_axial                 # ∂Q_s/∂|r′|
    g = np.zeros(3)                  # ∂Q_s/∂r′ through the direction of t in N
    dQ_ds = 0.0                      # ∂Q_s/∂s besides r′(s)
    dQ_dlam = np.zeros(3)
    dQ_dsd = 0.0
    sticking = True
    new_anchor = anchor
    if code != FRICTION_NONE:
        lt = lam_pos[0] * t[0] + lam_pos[1] * t[1] + lam_pos[2] * t[2]
        lperp = lam_pos - lt * t
        N = math.sqrt(lperp[0] * lperp[0] + lperp[1] * lperp[1] + lperp[2] * lperp[2])
        n_hat = lperp / N if N > 0.0 else np.zeros(3)
        if code == FRICTION_STICK:
            mu_eff = fr[2] if stuck else fr[1]
            k_t, c_t = fr[3], fr[4]
            T = -k_t * nr * (s - anchor) - c_t * nr * s_rate
            Tv = np.zeros(3)
            Tv[0] = T
            Fv = np.empty(3)
            dF_dT = np.empty((3, 3))
            t_hat = np.empty(3)
            sticking = coulomb_return_map(Tv, mu_eff * N, Fv, dF_dT, t_hat)
            F = Fv[0]
            a = dF_dT[0, 0]          # ∂F/∂T: 1 sticking, 0 slipping (scalar case)
            dF_dN = t_hat[0] * mu_eff
            dQ_dnr += F + a * T
            dQ_ds = -a * k_t * nr * nr
            dQ_dsd = -a * c_t * nr * nr
            if not sticking:
                new_anchor = s + F / (k_t * nr)
        else:
            th = math.tanh(s_rate / fr[5])
            F = -fr[1] * N * th
            dF_dN = -fr[1] * th
            dQ_dnr += F
            dQ_dsd = -nr * fr[1] * N * (1.0 - th * th) / fr[5]
            sticking = False
        dQ_dlam = nr * dF_dN * n_hat
        g = -dF_dN * lt * n_hat
    Qs = nr * (f_axial + F)
    h = dQ_dnr * t + g               # ∂Q_s/∂r′
    dQ_de = np.empty(CENTERLINE_SIZE)
    for m in range(4):
        for c in range(3):
            dQ_de[3 * m + c] = dS[m] * h[c]
    dQ_ds += h[0] * r2[0] + h[1] * r2[1] + h[2] * r2[2]
    return Qs, dQ_de, dQ_ds, dQ_dlam, dQ_dsd, F, sticking, new_anchor


class _SlidingConstraint(Constraint):
    """Equations of the sliding joint on the current element (coordinates change with it)."""

    def __init__(self, joint: SlidingJoint) -> None:
        self.joint = joint
        self.name = joint.name
        self.n_equations = 3 if joint.variant == "ring" else 5
        self.equation_labels = ["x", "y", "z", "align_1", "align_2"][: self.n_equations]

    def coordinates(self) -> np.ndarray:
        j = self.joint
        g = j.geometry
        return np.concatenate([g.body_dofs, g.elem_dofs[j.element], [g.s_dof]])

    def evaluate(self, q_local: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
        j = self.joint
        k = j.element
        m = self.n_equations
        phi = np.empty(m)
        jac = np.empty((m, N_SLIDE))
        sliding_values(np.ascontiguousarray(q_local, dtype=float), float(j.geometry.lengths[k]),
                       float(j.geometry.starts[k]), j.geometry.point_tensors, m, phi, jac)
        return phi, jac

    def hessian_lambda(self, q_local: np.ndarray, lam: np.ndarray, t: float) -> np.ndarray:
        j = self.joint
        k = j.element
        H = np.empty((N_SLIDE, N_SLIDE))
        sliding_hessian(np.ascontiguousarray(q_local, dtype=float), float(j.geometry.lengths[k]),
                        float(j.geometry.starts[k]), j.geometry.point_tensors, self.n_equations,
                        np.ascontiguousarray(lam, dtype=float), H)
        return H


class SlideFriction(NamedTuple):
    """Friction of a sliding joint at a state (:meth:`SlidingJoint.friction_force`)."""

    force: float          #: F [N] on the body along the beam tangent t = r′/|r′|
    sticking: bool        #: inside the cone (stick law)
    anchor: float         #: the anchor s_A after a step ending at this state


class SlidingGeometry(NamedTuple):
    """Where a sliding joint's coordinates are and its beam's arc length, built when the joint
    is bound (:meth:`SlidingJoint.bind`); read by the joint, its constraint and its pack
    (:func:`pack_sliding`)."""

    body_dofs: np.ndarray     # (7,) the body's coordinates
    elem_dofs: np.ndarray     # (n_elem, CENTERLINE_SIZE) every element's centreline coordinates
    s_dof: int                # the slide coordinate s (arc length)
    beam_dofs: np.ndarray     # every coordinate of the beam (the pattern)
    lengths: np.ndarray       # (n_elem,) element lengths
    starts: np.ndarray        # (n_elem,) arc length at each element's start
    total: float              # the beam's length
    point_tensors: np.ndarray  # (3, 3, 4, 4) T_k of the hole point, e_y, e_z (body coordinates)


class SlidingState(NamedTuple):
    """What a sliding joint carries from step to step (one-element arrays: built by the joint,
    then views of its packed part's arrays, updated in place by the compiled steps)."""

    element: np.ndarray   # the beam element holding the slide point
    anchor: np.ndarray    # friction anchor s_A (the beam's reference arc length)
    stuck: np.ndarray     # 1: the body stuck at the end of the last step


class SlidingJoint(Interaction):
    """Rigid body sliding along a beam without clearance (the paper's baseline joint).

    ``hole_point``: hole centre in body coordinates; ``axis``: hole axis in body coordinates
    (default body x). ``variant="cylindrical"`` keeps the axis along the beam tangent (3 + 2
    equations); ``"ring"`` only the position (3), for a short ring or grommet. ``s0``: initial
    arc length (default: projection of the hole centre onto the beam). ``axial_force`` (N on
    the body along the tangent, number or time function) is optional.

    ``friction`` (:func:`~flexmbs.contact.laws.as_friction`): a
    :class:`~flexmbs.contact.laws.Friction`, a :class:`~flexmbs.contact.laws.RegularizedCoulomb`
    or a Coulomb coefficient (the stick law; with ``friction_velocity``, the regularised law).
    The stick law holds the body by a tangential spring k_t from an anchor in the beam's
    material coordinate (the initial s) and lets it slip on the cone of the normal reaction
    (:func:`sliding_axial_force`); its default stiffness (``stiffness=None``) is the axial
    stiffness of one beam element, ``k_t = EA/L_e`` (L_e the mean element length), stiff enough
    that the elastic stick displacement μN/k_t is the beam's own strain under that force.

    Parameters
    ----------
    beam : Beam
        The beam along which the body slides.
    body : RigidBody
        The sliding body.
    name : str, optional
        The joint's name.
    hole_point : array_like of 3 floats, default (0, 0, 0)
        The hole's centre in body coordinates [m].
    axis : array_like of 3 floats, default (1, 0, 0)
        The hole's axis in body coordinates.
    variant : {"cylindrical", "ring"}, default "cylindrical"
        Axis along the tangent (5 equations) or the position only (3).
    s0 : float, optional
        Initial arc length on the beam [m] (default: the hole centre's projection).
    friction : Friction, RegularizedCoulomb or float, optional
        Friction; a number is a Coulomb coefficient (the stick law).
    friction_velocity : float, optional
        With a number ``friction``: the regularised law with this velocity scale [m/s].
    axial_force : float or TimeFunction, optional
        Force on the body along the beam's tangent [N].
    """

    term_kind = "sliding"

    def __init__(self, beam: Beam, body: RigidBody, *, name: str | None = None,
                 hole_point=(0.0, 0.0, 0.0), axis=(1.0, 0.0, 0.0),
                 variant: Literal["cylindrical", "ring"] = "cylindrical", s0: float | None = None,
                 friction: Friction | RegularizedCoulomb | float | None = None,
                 friction_velocity: float | None = None,
                 axial_force: TimeFunction | float | None = None) -> None:
        if variant not in ("cylindrical", "ring"):
            raise ModelError(f"SlidingJoint: variant must be 'cylindrical' or 'ring' (got {variant!r})")
        self.beam = beam
        self.body = body
        self.name = name or f"sliding_{body.name}"
        self.variant = variant
        self.hole_point = np.asarray(hole_point, float).reshape(3)
        ax = np.asarray(axis, float).reshape(3)
        if not np.linalg.norm(ax) > 0:
            raise ModelError("SlidingJoint: axis must not be zero")
        self.axis = ax / np.linalg.norm(ax)
        helper = np.array([0.0, 0.0, 1.0]) if abs(self.axis[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
        y = np.cross(helper, self.axis)
        self._y_body = y / np.linalg.norm(y)
        self._z_body = np.cross(self.axis, self._y_body)
        # point tensors of the constant body vectors: (A(p) w)_k = p^T T_k(w) p
        self._T_u = point_tensor(self.hole_point)
        self._T_y = point_tensor(self._y_body)
        self._T_z = point_tensor(self._z_body)
        self._T_all = np.ascontiguousarray(np.stack([self._T_u, self._T_y, self._T_z]))
        self.s0 = s0
        self.friction = as_friction(friction, friction_velocity)
        self.axial_force = None if axial_force is None else as_time_function(axial_force)
        # state, updated in place (also by the compiled integrator): current element, friction
        # anchor s_A and whether the body stuck at the end of the last step
        self.state = SlidingState(element=np.zeros(1, np.int64), anchor=np.zeros(1),
                                  stuck=np.ones(1, np.int64))
        self._constraint = _SlidingConstraint(self)

    @property
    def friction(self) -> Friction | None:
        """The friction law (None: frictionless); set through
        :func:`~flexmbs.contact.laws.as_friction`."""
        return self._friction

    @friction.setter
    def friction(self, value: Friction | RegularizedCoulomb | float | None) -> None:
        self._friction = as_friction(value)

    def default_stiffness(self) -> float:
        """k_t of the stick law when not given: the axial stiffness of one element, EA/L_e."""
        return float(self.beam.stiffness.axial_stiffness) * self.beam.n_elem / self.beam.length

    def friction_parameters(self) -> np.ndarray:
        """``[law code, μ, μ_s, k_t, c_t, ε_v]`` of the kernels
        (:meth:`~flexmbs.contact.laws.Friction.parameters`)."""
        f = self.friction
        return no_friction() if f is None else f.parameters(self.default_stiffness())

    # ------------------------------------------------------------------ set-up
    def validate(self, model: ModelParts) -> None:
        if self.beam not in model.beams:
            raise ModelError(f"joint '{self.name}': the beam is not part of the model")
        if self.body not in model.bodies:
            raise ModelError(f"joint '{self.name}': the body is not part of the model")
        if self.beam.closed:
            raise ModelError(f"joint '{self.name}': sliding on closed beams is not supported")

    def extra_labels(self) -> list[str]:
        return ["s"]

    def bind(self, dofs: DofMap, extra_dofs: np.ndarray) -> None:
        """Builds :attr:`geometry` (:class:`SlidingGeometry`)."""
        lengths = np.array(self.beam.centerline.lengths, dtype=float)
        self.geometry = SlidingGeometry(
            body_dofs=dofs.body_dofs(self.body),
            # the Hermite centreline coordinates of every element (the element's declared layout)
            elem_dofs=dofs.element_dofs(self.beam)[:, self.beam.layout.centerline],
            s_dof=int(extra_dofs[0]), beam_dofs=dofs.beam_dofs(self.beam), lengths=lengths,
            starts=np.concatenate([[0.0], np.cumsum(lengths)[:-1]]),
            total=float(np.sum(lengths)), point_tensors=self._T_all)

    def _hole_centre(self, q: np.ndarray) -> np.ndarray:
        qb = q[self.geometry.body_dofs]
        return qb[:3] + rotation_matrix(qb[3:7]) @ self.hole_point

    def initial_extra(self, q0: np.ndarray) -> np.ndarray:
        if self.s0 is not None:
            s = float(self.s0)
            if not 0.0 <= s <= self.geometry.total:
                raise ModelError(f"joint '{self.name}': s0 = {s} is outside the beam "
                                 f"(0 <= s <= {self.geometry.total:.6g})")
        else:
            s = self._project(q0, self._hole_centre(q0))
        self.element = self._locate(s)
        self.anchor = s
        self.stuck = True
        return np.array([s])

    def _locate(self, s: float) -> int:
        g = self.geometry
        return int(np.clip(np.searchsorted(g.starts, s, side="right") - 1, 0, len(g.lengths) - 1))

    def _project(self, q: np.ndarray, x: np.ndarray) -> float:
        """Arc length of the point of the beam nearest to x: the best of 9 samples per element
        starts the closest-point projection (:func:`flexmbs.elements.centerline.closest_point`)."""
        g = self.geometry
        n = len(g.lengths)
        xi = np.linspace(0.0, 1.0, 9)
        e_all = np.repeat(np.arange(n), xi.size)
        pts = hermite.centerline_points(q, g.elem_dofs, g.lengths, e_all, np.tile(xi, n))
        i = int(np.argmin(np.linalg.norm(pts - x, axis=1)))
        qe = np.ascontiguousarray(q[g.elem_dofs])
        e, xi_p, *_ = closest_point(qe, g.lengths, np.asarray(x, float), int(e_all[i]),
                                    float(xi[i % xi.size]))
        return float(np.clip(g.starts[e] + xi_p * g.lengths[e], 0.0, g.total))

    def constraints(self) -> list[Constraint]:
        return [self._constraint]

    def energy_flow(self) -> EnergyFlow:
        """An ideal joint does no work; its friction dissipates; its ``axial_force`` works."""
        if self.axial_force is not None:
            return "works"
        return "conserves" if self.friction is None else "dissipates"

    def error(self, code: int, detail: int, q: np.ndarray, t: float) -> FlexmbsError:
        """The exception for an error code of :func:`sliding_post_step` (or, should it ever
        leave the integrator, :data:`ERR_OFF_PLAN` of :func:`sliding_jacobian`)."""
        if code == ERR_OFF_PLAN:
            return FlexmbsError(
                f"joint '{self.name}': on element {detail} of beam '{self.beam.name}', outside "
                "the elements the factorisation was planned for (internal: the integrator "
                "plans again)")
        s = float(q[self.geometry.s_dof])
        return SimulationStopped(
            f"joint '{self.name}': body '{self.body.name}' reached the end of beam "
            f"'{self.beam.name}' at t = {t:.6g} s (s = {s:.6g}, beam length {self.geometry.total:.6g})")

    def slide_coordinate(self, q: np.ndarray) -> float:
        return float(q[self.geometry.s_dof])

    def reaction_force(self, dofs: DofMap, lam: np.ndarray) -> np.ndarray:
        """Constraint force of the joint on the body at the hole centre (global components):
        ``-lam_pos`` (the body equation reads ``m r'' + lam_pos = F``)."""
        rows = dofs.multiplier_rows(self._constraint)
        return -lam[rows[:3]]

    @property
    def element(self) -> int:
        """Index of the beam element holding the slide point (updated after each step)."""
        return int(self.state.element[0])

    @element.setter
    def element(self, k: int) -> None:
        self.state.element[0] = k

    @property
    def anchor(self) -> float:
        """Friction anchor s_A: the beam's material coordinate (reference arc length) where
        the body sticks (stick law; updated after each step)."""
        return float(self.state.anchor[0])

    @anchor.setter
    def anchor(self, s: float) -> None:
        self.state.anchor[0] = s

    @property
    def stuck(self) -> bool:
        """Whether the body stuck at the end of the last step (its cone then has μ_s)."""
        return bool(self.state.stuck[0])

    @stuck.setter
    def stuck(self, value: bool) -> None:
        self.state.stuck[0] = 1 if value else 0

    def friction_force(self, dofs: DofMap, q: np.ndarray, v: np.ndarray,
                       lam: np.ndarray) -> SlideFriction:
        """Friction at state ``(q, v, lam)`` from the current anchor (:func:`sliding_axial_force`)."""
        k = self.element
        rows = dofs.multiplier_rows(self._constraint)[:3]
        lp = np.where(rows >= 0, lam[np.maximum(rows, 0)], 0.0)
        g = self.geometry
        out = sliding_axial_force(
            np.ascontiguousarray(q[g.elem_dofs[k]], dtype=float), float(g.lengths[k]),
            float(g.starts[k]), float(q[g.s_dof]), float(v[g.s_dof]),
            np.ascontiguousarray(lp, dtype=float), self.friction_parameters(), self.anchor,
            int(self.stuck), 0.0)
        return SlideFriction(float(out[5]), bool(out[6]), float(out[7]))

    def get_state(self) -> dict[str, Any]:
        return {"element": int(self.element), "anchor": self.anchor, "stuck": self.stuck,
                "friction": [float(x) for x in self.friction_parameters()]}

    def set_state(self, state: dict[str, Any]) -> None:
        check_resumed_friction(self.name, state.get("friction"), self.friction_parameters())
        self.element = int(state["element"])
        if "anchor" in state:
            self.anchor = float(state["anchor"])
            self.stuck = bool(state["stuck"])

    def __repr__(self) -> str:
        return (f"SlidingJoint({self.name!r}, beam={self.beam.name!r}, body={self.body.name!r}, "
                f"variant={self.variant!r}, friction={self.friction!r})")


# ---------------------------------------------------------------------------------------------
# the sliding-joint term of the assembler (flexmbs.terms)
#: error code of :func:`sliding_post_step`: the slide coordinate left the beam
ERR_END_OF_BEAM = ERROR_CODES["end_of_beam"]
#: error code of :func:`sliding_jacobian`: a joint's element lies outside the elements the
#: factorisation's plan follows it on (``window``); the step is retried after a new plan
ERR_OFF_PLAN = ERROR_CODES["off_plan"]


class SlidingPart(NamedTuple):
    body: np.ndarray                 # (nj, 7)
    elem_dofs: np.ndarray            # (nj, max_ne, CENTERLINE_SIZE)
    lengths: np.ndarray              # (nj, max_ne)
    starts: np.ndarray               # (nj, max_ne)
    n_elem: np.ndarray               # (nj,)
    total: np.ndarray                # (nj,) beam length
    s_dof: np.ndarray                # (nj,)
    T: np.ndarray                    # (nj, 3, 3, 4, 4) point tensors of u_C, y, z
    n_eq: np.ndarray                 # (nj,) 3 ring, 5 cylindrical
    rows: np.ndarray                 # (nj, 5) multipliers, −1 dropped
    friction: np.ndarray             # (nj, N_FRICTION) Friction.parameters
    fn: np.ndarray                   # (nj,) axial-force time function, −1 none
    element: np.ndarray              # (nj,) state: current element
    anchor: np.ndarray               # (nj,) state: friction anchor s_A
    stuck: np.ndarray                # (nj,) state: stuck at the end of the last step (0/1)
    trial_anchor: np.ndarray         # (nj,) the last residual's anchor and stick flag, which
    trial_stuck: np.ndarray          # (nj,) sliding_post_step takes over
    pos_jac: np.ndarray              # (nj, max_ne, 5, N_SLIDE) per element; −1 for dropped rows
    pos_jacT: np.ndarray
    pos_hess: np.ndarray             # (nj, max_ne, N_SLIDE * N_SLIDE)
    pos_s_elem: np.ndarray           # (nj, max_ne, CENTERLINE_SIZE): friction / axial force row of s
    pos_ss: np.ndarray               # (nj,)
    pos_s_lam: np.ndarray            # (nj, 3)
    window: np.ndarray               # (nj, 2) state: the elements [lo, hi) the factorisation's
                                     # plan holds the joint's entries on (the whole beam unless
                                     # Assembly.follow set it)
    ql: np.ndarray                   # work (N_SLIDE,)
    phi: np.ndarray
    jac: np.ndarray
    H: np.ndarray
    lam: np.ndarray


def sliding_pattern(joint: SlidingJoint, dofs: DofMap) -> list[tuple[np.ndarray, np.ndarray]]:
    """The joint's multipliers couple with the body, s and every beam coordinate (the current
    element moves along the beam), both ways; so do s and, on a cylindrical joint, the body
    (its alignment rows ``(A y)·r′(s)`` mix p with the element and s). A ring's equations
    ``r_H + A u_C − r(s)`` are a sum of a body term and a beam term: its Hessian couples
    the body only with itself, which keeps a fixed eyelet's body out of the factorisation's
    border (issue 37)."""
    g = joint.geometry
    body, s = g.body_dofs, np.array([g.s_dof])
    cols = np.concatenate([body, s, g.beam_dofs])
    rows = dofs.multiplier_rows(joint.constraints()[0])
    mult = dofs.n_coords + rows[rows >= 0]
    if joint.variant == "ring":
        beam_s = np.concatenate([s, g.beam_dofs])
        blocks = [(body, body), (s, beam_s), (beam_s, s)]
    else:
        own = np.concatenate([body, s])
        blocks = [(own, cols), (cols, own)]
    return [*blocks, (mult, cols), (cols, mult)]


def pack_sliding(joints: list[SlidingJoint], ctx: PackContext) -> SlidingPart:
    """All sliding joints; their state arrays become views of the packed ones."""
    dofs, functions = ctx, ctx.functions
    nj = len(joints)
    n = dofs.n_coords
    rows = np.full((nj, 5), -1, np.int64)
    max_el = max((len(j.geometry.lengths) for j in joints), default=0)
    pj = np.full((nj, max_el, 5, N_SLIDE), -1, np.int64)
    pt = np.full((nj, max_el, 5, N_SLIDE), -1, np.int64)
    ph = np.zeros((nj, max_el, N_SLIDE * N_SLIDE), np.int64)
    pse = np.zeros((nj, max_el, CENTERLINE_SIZE), np.int64)
    pss = np.zeros(nj, np.int64)
    psl = np.zeros((nj, 3), np.int64)
    for i, j in enumerate(joints):
        constraint, = j.constraints()
        r = dofs.multiplier_rows(constraint)
        rows[i, :r.size] = r
        kept = np.flatnonzero(r >= 0)
        sd = np.array([j.geometry.s_dof])
        for k in range(len(j.geometry.lengths)):
            cc = np.concatenate([j.geometry.body_dofs, j.geometry.elem_dofs[k], sd])
            if kept.size:
                rr = n + r[kept]
                pj[i, k, kept] = dofs.positions(rr, cc).reshape(kept.size, N_SLIDE)
                pt[i, k, kept] = dofs.positions(cc, rr).reshape(N_SLIDE, kept.size).T
            ph[i, k] = dofs.positions_present(cc, cc)   # −1: outside a ring's Hessian pattern
            pse[i, k] = dofs.positions(sd, j.geometry.elem_dofs[k])
        pss[i] = dofs.positions(sd, sd)[0]
        if (j.friction is not None or j.axial_force is not None) and np.all(r[:3] >= 0):
            psl[i] = dofs.positions(sd, n + r[:3])
    i64, c = np.int64, np.ascontiguousarray
    part = SlidingPart(
        body=c(np.array([j.geometry.body_dofs for j in joints], i64).reshape(nj, 7)),
        elem_dofs=pad_stack([j.geometry.elem_dofs for j in joints], (CENTERLINE_SIZE,), 0, np.int64),
        lengths=pad_stack([j.geometry.lengths for j in joints], (), 1.0, float),
        starts=pad_stack([j.geometry.starts for j in joints], (), 0.0, float),
        n_elem=np.array([len(j.geometry.lengths) for j in joints], i64),
        total=np.array([j.geometry.total for j in joints], float),
        s_dof=np.array([j.geometry.s_dof for j in joints], i64),
        T=c(np.array([j.geometry.point_tensors for j in joints], float).reshape(nj, 3, 3, 4, 4)),
        n_eq=np.array([j.constraints()[0].n_equations for j in joints], i64),
        rows=rows,
        friction=c(np.array([j.friction_parameters() for j in joints], float).reshape(nj, N_FRICTION)),
        fn=np.array([-1 if j.axial_force is None else functions(j.axial_force) for j in joints], i64),
        element=np.array([j.element for j in joints], i64),
        anchor=np.array([j.anchor for j in joints], float),
        stuck=np.array([j.stuck for j in joints], i64),
        trial_anchor=np.array([j.anchor for j in joints], float),
        trial_stuck=np.array([j.stuck for j in joints], i64),
        pos_jac=pj,
        pos_jacT=pt,
        pos_hess=ph,
        pos_s_elem=pse,
        pos_ss=pss,
        pos_s_lam=psl,
        window=c(np.array([[0, len(j.geometry.lengths)] for j in joints], i64).reshape(nj, 2)),
        ql=np.zeros(N_SLIDE),
        phi=np.zeros(5),
        jac=np.zeros((5, N_SLIDE)),
        H=np.zeros((N_SLIDE, N_SLIDE)),
        lam=np.zeros(5))
    for i, j in enumerate(joints):     # the joint's state lives in the packed arrays
        j.state = SlidingState(element=part.element[i:i + 1], anchor=part.anchor[i:i + 1],
                               stuck=part.stuck[i:i + 1])
    return part


@njit(inline="always")
def _joint_values(sl, j, q):
    """Φ, Φ_q of sliding joint j on its current element; returns (element, its dofs, s dof,
    equations)."""
    k = sl.element[j]
    ed = sl.elem_dofs[j, k]
    for a in range(7):
        sl.ql[a] = q[sl.body[j, a]]
    for a in range(CENTERLINE_SIZE):
        sl.ql[7 + a] = q[ed[a]]
    sd = sl.s_dof[j]
    sl.ql[S_INDEX] = q[sd]
    ne_j = sl.n_eq[j]
    sliding_values(sl.ql, sl.lengths[j, k], sl.starts[j, k], sl.T[j], ne_j, sl.phi, sl.jac)
    return k, ed, sd, ne_j


@njit(inline="always")
def _joint_force(sl, j, k, sd, q, v, lam, fv):
    """Axial and friction force on s of sliding joint j (:func:`sliding_axial_force`)."""
    lp = np.zeros(3)
    for a in range(3):
        if sl.rows[j, a] >= 0:
            lp[a] = lam[sl.rows[j, a]]
    f_ax = fv[sl.fn[j]] if sl.fn[j] >= 0 else 0.0
    return sliding_axial_force(sl.ql[7:S_INDEX], sl.lengths[j, k], sl.starts[j, k], q[sd], v[sd], lp,
                               sl.friction[j], sl.anchor[j], sl.stuck[j], f_ax)


@njit(internal=True)
def sliding_residual(sl, n, q, v, lam, fv, r):
    """``r_λ = Φ``, ``r_q += Φ_qᵀλ``, ``r_s −= Q_s`` of every sliding joint; keeps the stick
    law's anchor and stick flag of this state for :func:`sliding_post_step`; returns max |Q_s|."""
    if sl is None:   # none in the model: compiled to nothing (driver.OPTIONAL_KINDS)
        return 0.0
    scale = 0.0
    for j in range(sl.s_dof.size):
        k, ed, sd, ne_j = _joint_values(sl, j, q)
        for i in range(ne_j):
            row = sl.rows[j, i]
            if row < 0:
                continue
            r[n + row] = sl.phi[i]
            lr = lam[row]
            for a in range(7):
                r[sl.body[j, a]] += sl.jac[i, a] * lr
            for a in range(CENTERLINE_SIZE):
                r[ed[a]] += sl.jac[i, 7 + a] * lr
            r[sd] += sl.jac[i, S_INDEX] * lr
        if sl.friction[j, 0] != FRICTION_NONE or sl.fn[j] >= 0:
            Qs, _, _, _, _, _, sticking, anchor = _joint_force(sl, j, k, sd, q, v, lam, fv)
            r[sd] -= Qs
            sl.trial_anchor[j] = anchor
            sl.trial_stuck[j] = 1 if sticking else 0
            if abs(Qs) > scale:
                scale = abs(Qs)
    return scale


@njit(internal=True)
def sliding_jacobian(sl, q, v, lam, fv, cC, cK, data, error):
    """Φ_q, Φ_qᵀ, ``cK Σλ_i ∂²Φ_i/∂q²`` and the exact derivatives of −Q_s in the element
    coordinates, s, ṡ and λ_pos (:func:`sliding_axial_force`); returns 0, or
    ``ERR_OFF_PLAN`` (joint in ``error[1]`` and ``error[3]``, element in ``error[2]``) when a
    joint's element
    lies outside its ``window``: its entries there are not in the factorisation's plan."""
    if sl is None:   # none in the model: compiled to nothing (driver.OPTIONAL_KINDS)
        return 0
    for j in range(sl.s_dof.size):
        if sl.element[j] < sl.window[j, 0] or sl.element[j] >= sl.window[j, 1]:
            error[0] = ERR_OFF_PLAN
            error[1] = j
            error[2] = sl.element[j]
            error[3] = j          # its window's row
            return ERR_OFF_PLAN
    for j in range(sl.s_dof.size):
        k, ed, sd, ne_j = _joint_values(sl, j, q)
        for i in range(ne_j):
            row = sl.rows[j, i]
            sl.lam[i] = lam[row] if row >= 0 else 0.0
            if row < 0:
                continue
            for a in range(N_SLIDE):
                data[sl.pos_jac[j, k, i, a]] += sl.jac[i, a]
                data[sl.pos_jacT[j, k, i, a]] += sl.jac[i, a]
        sliding_hessian(sl.ql, sl.lengths[j, k], sl.starts[j, k], sl.T[j], ne_j, sl.lam[:ne_j], sl.H)
        for a in range(N_SLIDE):
            for c in range(N_SLIDE):
                pos = sl.pos_hess[j, k, N_SLIDE * a + c]
                if pos >= 0:      # a ring's body-beam entries are zero and not in the pattern
                    data[pos] += cK * sl.H[a, c]
        if sl.friction[j, 0] != FRICTION_NONE or sl.fn[j] >= 0:
            _, dQ_de, dQ_ds, dQ_dlam, dQ_dsd, _, _, _ = _joint_force(sl, j, k, sd, q, v, lam, fv)
            for a in range(CENTERLINE_SIZE):
                data[sl.pos_s_elem[j, k, a]] -= cK * dQ_de[a]
            data[sl.pos_ss[j]] -= cK * dQ_ds + cC * dQ_dsd
            if sl.rows[j, 0] >= 0 and sl.rows[j, 1] >= 0 and sl.rows[j, 2] >= 0:
                for a in range(3):
                    data[sl.pos_s_lam[j, a]] -= dQ_dlam[a]
    return 0


@njit(internal=True)
def sliding_post_step(sl, q, error):
    """After a converged step (and a :func:`sliding_residual` at its state): the current
    element of every slide coordinate, and the stick law's anchor and stick flag of that
    residual; ``ERR_END_OF_BEAM`` (joint in ``error[1]``, nothing changed) when s left its
    beam."""
    if sl is None:   # none in the model: compiled to nothing (driver.OPTIONAL_KINDS)
        return 0
    for j in range(sl.s_dof.size):
        s = q[sl.s_dof[j]]
        if s < 0.0 or s > sl.total[j] or math.isnan(s):
            error[0] = ERR_END_OF_BEAM
            error[1] = j
            return ERR_END_OF_BEAM
    for j in range(sl.s_dof.size):
        s = q[sl.s_dof[j]]
        ne_j = sl.n_elem[j]
        k = np.searchsorted(sl.starts[j, :ne_j], s, side="right") - 1
        sl.element[j] = min(max(k, 0), ne_j - 1)
        if sl.friction[j, 0] == FRICTION_STICK:
            sl.anchor[j] = sl.trial_anchor[j]
            sl.stuck[j] = sl.trial_stuck[j]
    return 0


def _own_unknowns(joint: SlidingJoint, dofs: DofMap) -> list[np.ndarray]:
    """The slide coordinate and the kept multipliers: what couples with the joint's beam (one
    window row)."""
    rows = dofs.multiplier_rows(joint.constraints()[0])
    return [np.concatenate([[joint.geometry.s_dof], dofs.n_coords + rows[rows >= 0]]).astype(np.int64)]


def _current_windows(part: SlidingPart, reach: int) -> np.ndarray:
    """``reach`` elements either side of every joint's current element, clipped to its beam."""
    k = part.element.astype(np.int64)
    return np.stack([np.maximum(k - reach, 0), np.minimum(k + reach + 1, part.n_elem)],
                    axis=1).astype(np.int64)


#: the sliding joint's term kind (:class:`~flexmbs.constraints.interaction.InteractionKind`);
#: the plan may follow its current element (:class:`~flexmbs.constraints.interaction.Following`)
SLIDING = InteractionKind(name="sliding", pattern=sliding_pattern, pack=pack_sliding,
                          errors=(ERR_END_OF_BEAM, ERR_OFF_PLAN), stops=(ERR_END_OF_BEAM,),
                          follow=Following(off_plan=ERR_OFF_PLAN, own=_own_unknowns,
                                           elements=lambda joint: joint.geometry.elem_dofs,
                                           current=_current_windows))

"""Sliding joint without clearance: a rigid body whose hole axis slides along an ANCF beam.

Sugiyama, Escalona & Shabana, Nonlinear Dyn. 31 (2003) 167-195: the arc-length parameter ``s``
of the contact point is an extra unknown without inertia (FORMULATION Part II §7)::

    Phi = [ r_H + A u_C - r(s) ;  (A y)·r'(s) ;  (A z)·r'(s) ] = 0     (cylindrical: 3 + 2)
    Phi = [ r_H + A u_C - r(s) ]                                       (ring: 3)
    Phi_s^T lam = Q_s                                                  (row of s)

``Q_s = |r'| (f_ax(t) - mu N tanh(s_dot/eps_v))`` adds a prescribed axial force on the body
along the beam tangent and regularised Coulomb friction on the normal reaction N = |lam_pos,⊥|.
``s`` is the reference arc length from the beam's first node; within a step the current
element's cubic is evaluated (also slightly beyond its ends), and the element index is updated
after each converged step.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from ..elements import ancf_cable as cable
from ..elements.rigid_body import point_tensor, rotation_matrix
from ..errors import FlexmbsError, ModelError
from ..loads import TimeFunction, as_time_function
from .base import Constraint
from .interaction import Interaction

if TYPE_CHECKING:  # pragma: no cover
    from ..assembly import Assembly
    from ..model import Beam, Model, RigidBody


class SimulationStopped(FlexmbsError):
    """The simulation cannot continue (e.g. a sliding body reached the end of its beam)."""


def _third_derivatives(L: float) -> np.ndarray:
    return np.array([12.0 / L**3, 6.0 / L**2, -12.0 / L**3, 6.0 / L**2])


class _SlidingConstraint(Constraint):
    """Equations of the sliding joint on the current element (coordinates change with it)."""

    def __init__(self, joint: SlidingJoint) -> None:
        self.joint = joint
        self.name = joint.name
        self.n_equations = 3 if joint.variant == "ring" else 5
        self.equation_labels = ["x", "y", "z", "align_1", "align_2"][: self.n_equations]
        self.version = 0

    def coordinates(self) -> np.ndarray:
        j = self.joint
        return np.concatenate([j._body_dofs, j._elem_dofs[j.element], [j._s_dof]])

    def _kinematics(self, ql: np.ndarray):  # noqa: ANN202
        j = self.joint
        rH, p, e, s = ql[:3], ql[3:7], ql[7:19].reshape(4, 3), ql[19]
        k = j.element
        L = j._lengths[k]
        xi = (s - j._starts[k]) / L
        S, dS, ddS = (np.asarray(x).reshape(4) for x in cable.shape_functions(np.array(xi), np.array(L)))
        d3 = _third_derivatives(L)
        return rH, p, e, S, dS, ddS, d3

    def evaluate(self, q_local: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
        j = self.joint
        rH, p, e, S, dS, ddS, _ = self._kinematics(q_local)
        A = rotation_matrix(p)
        r = S @ e
        r1 = dS @ e
        r2 = ddS @ e
        m = self.n_equations
        phi = np.zeros(m)
        jac = np.zeros((m, 20))
        phi[:3] = rH + A @ j.hole_point - r
        jac[:3, :3] = np.eye(3)
        jac[:3, 3:7] = 2.0 * (j._T_u @ p)
        jac[:3, 7:19] = -np.kron(S, np.eye(3))
        jac[:3, 19] = -r1
        if m == 5:
            for i, (w, Tw) in enumerate(((j._y_body, j._T_y), (j._z_body, j._T_z))):
                aw = A @ w
                phi[3 + i] = aw @ r1
                jac[3 + i, 3:7] = r1 @ (2.0 * (Tw @ p))
                jac[3 + i, 7:19] = np.kron(dS, aw)
                jac[3 + i, 19] = aw @ r2
        return phi, jac

    def hessian_lambda(self, q_local: np.ndarray, lam: np.ndarray, t: float) -> np.ndarray:
        j = self.joint
        rH, p, e, S, dS, ddS, d3 = self._kinematics(q_local)
        H = np.zeros((20, 20))
        lp = lam[:3]
        r1 = dS @ e
        r2 = ddS @ e
        r3 = d3 @ e
        H[3:7, 3:7] += 2.0 * np.einsum("k,kij->ij", lp, j._T_u)
        H[7:19, 19] += -np.kron(dS, lp)
        H[19, 19] += -lp @ r2
        if self.n_equations == 5:
            A = rotation_matrix(p)
            for mu, w, Tw in zip(lam[3:5], (j._y_body, j._z_body), (j._T_y, j._T_z), strict=True):
                if mu == 0.0:
                    continue
                Bw = 2.0 * (Tw @ p)                           # d(A w)/dp, 3x4
                aw = A @ w
                H[3:7, 3:7] += mu * 2.0 * np.einsum("k,kij->ij", r1, Tw)
                H[3:7, 7:19] += mu * Bw.T @ np.kron(dS, np.eye(3))
                H[3:7, 19] += mu * Bw.T @ r2
                H[7:19, 19] += mu * np.kron(ddS, aw)
                H[19, 19] += mu * aw @ r3
        # symmetrise the off-diagonal blocks written once above
        H[7:19, 3:7] = H[3:7, 7:19].T
        H[19, 3:7] = H[3:7, 19]
        H[19, 7:19] = H[7:19, 19]
        return H


class SlidingJoint(Interaction):
    """Rigid body sliding along a beam without clearance (the paper's baseline joint).

    ``hole_point``: hole centre in body coordinates; ``axis``: hole axis in body coordinates
    (default body x). ``variant="cylindrical"`` keeps the axis along the beam tangent (3 + 2
    equations); ``"ring"`` only the position (3), for a short ring or grommet. ``s0``: initial
    arc length (default: projection of the hole centre onto the beam). ``friction`` (Coulomb
    coefficient, regularised with ``friction_velocity``) and ``axial_force`` (N on the body
    along the tangent, number or time function) are optional.
    """

    def __init__(self, beam: Beam, body: RigidBody, *, name: str | None = None,
                 hole_point=(0.0, 0.0, 0.0), axis=(1.0, 0.0, 0.0),
                 variant: Literal["cylindrical", "ring"] = "cylindrical", s0: float | None = None,
                 friction: float = 0.0, friction_velocity: float = 1e-3,
                 axial_force: TimeFunction | float | None = None) -> None:
        if variant not in ("cylindrical", "ring"):
            raise ModelError(f"SlidingJoint: variant must be 'cylindrical' or 'ring' (got {variant!r})")
        if friction < 0 or not friction_velocity > 0:
            raise ModelError("SlidingJoint: friction must be >= 0 and friction_velocity > 0")
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
        self.s0 = s0
        self.friction = float(friction)
        self.friction_velocity = float(friction_velocity)
        self.axial_force = None if axial_force is None else as_time_function(axial_force)
        self.element = 0
        self._constraint = _SlidingConstraint(self)

    # ------------------------------------------------------------------ set-up
    def validate(self, model: Model) -> None:
        if self.beam not in model.beams:
            raise ModelError(f"joint '{self.name}': the beam is not part of the model")
        if self.body not in model.bodies:
            raise ModelError(f"joint '{self.name}': the body is not part of the model")
        if self.beam.closed:
            raise ModelError(f"joint '{self.name}': sliding on closed beams is not supported")

    def extra_labels(self) -> list[str]:
        return ["s"]

    def bind(self, asm: Assembly, extra_dofs: np.ndarray) -> None:
        self._body_dofs = asm.body_dofs(self.body)
        self._elem_dofs = asm.element_dofs(self.beam)
        self._s_dof = int(extra_dofs[0])
        self._lengths = np.asarray(self.beam.centerline.lengths, float)
        self._starts = np.concatenate([[0.0], np.cumsum(self._lengths)[:-1]])
        self._total = float(np.sum(self._lengths))
        self._beam_dofs = asm.beam_dofs(self.beam)

    def _hole_centre(self, q: np.ndarray) -> np.ndarray:
        qb = q[self._body_dofs]
        return qb[:3] + rotation_matrix(qb[3:7]) @ self.hole_point

    def initial_extra(self, q0: np.ndarray) -> np.ndarray:
        if self.s0 is not None:
            s = float(self.s0)
            if not 0.0 <= s <= self._total:
                raise ModelError(f"joint '{self.name}': s0 = {s} is outside the beam "
                                 f"(0 <= s <= {self._total:.6g})")
        else:
            s = self._project(q0, self._hole_centre(q0))
        self.element = self._locate(s)
        return np.array([s])

    def _locate(self, s: float) -> int:
        return int(np.clip(np.searchsorted(self._starts, s, side="right") - 1, 0, len(self._lengths) - 1))

    def _project(self, q: np.ndarray, x: np.ndarray) -> float:
        """Arc length of the point of the beam nearest to x (sampling + Newton)."""
        n = len(self._lengths)
        xi = np.linspace(0.0, 1.0, 9)
        best = (np.inf, 0.0)
        for k in range(n):
            S, _, _ = cable.shape_functions(xi, np.full(xi.shape, self._lengths[k]))
            pts = np.asarray(S) @ q[self._elem_dofs[k]].reshape(4, 3)
            d = np.linalg.norm(pts - x, axis=1)
            i = int(np.argmin(d))
            if d[i] < best[0]:
                best = (d[i], self._starts[k] + xi[i] * self._lengths[k])
        s = best[1]
        for _ in range(20):
            k = self._locate(s)
            L = self._lengths[k]
            xi_k = np.array((s - self._starts[k]) / L)
            S, dS, ddS = (np.asarray(a).reshape(4) for a in cable.shape_functions(xi_k, np.array(L)))
            e = q[self._elem_dofs[k]].reshape(4, 3)
            r, r1, r2 = S @ e, dS @ e, ddS @ e
            h = (r - x) @ r1
            dh = r1 @ r1 + (r - x) @ r2
            step = -h / dh if dh > 0 else 0.0
            s = float(np.clip(s + step, 0.0, self._total))
            if abs(step) < 1e-14 * max(self._total, 1.0):
                break
        return s

    def constraints(self) -> list[Constraint]:
        return [self._constraint]

    def pattern_blocks(self) -> list[tuple[np.ndarray, np.ndarray]]:
        # body and s couple with every beam coordinate (the current element moves along the
        # beam); element-element blocks are already in the pattern, so no beam x beam block
        own = np.concatenate([self._body_dofs, [self._s_dof]])
        return [(own, np.concatenate([own, self._beam_dofs]))]

    # ------------------------------------------------------------------ forces on s
    def evaluate(self, asm: Assembly, q: np.ndarray, v: np.ndarray, lam: np.ndarray, t: float,
                 r_q: np.ndarray, matrix: tuple[float, float, float] | None) -> float:
        if self.friction == 0.0 and self.axial_force is None:
            return 0.0
        k = self.element
        L = self._lengths[k]
        s = q[self._s_dof]
        xi = np.array((s - self._starts[k]) / L)
        _, dS, _ = (np.asarray(a).reshape(4) for a in cable.shape_functions(xi, np.array(L)))
        r1 = dS @ q[self._elem_dofs[k]].reshape(4, 3)
        nr = float(np.linalg.norm(r1))
        tvec = r1 / nr
        rows = asm.multiplier_rows(self._constraint)
        lp = lam[rows[:3]]
        f_ax = self.axial_force(t) if self.axial_force is not None else 0.0
        Qs = nr * f_ax
        dQ_dlam = np.zeros(3)
        dQ_dsd = 0.0
        if self.friction > 0.0:
            lperp = lp - (lp @ tvec) * tvec
            N = float(np.linalg.norm(lperp))
            sd = v[self._s_dof]
            th = np.tanh(sd / self.friction_velocity)
            Qs -= nr * self.friction * N * th
            if N > 0:
                dQ_dlam = -nr * self.friction * th * (lperp / N)
            dQ_dsd = -nr * self.friction * N * (1 - th * th) / self.friction_velocity
        r_q[self._s_dof] -= Qs
        if matrix is not None:
            cM, cC, cK = matrix
            sd = np.array([self._s_dof])
            # Q_s = |r'| F_t: exact derivative of |r'| (element coordinates and s); the
            # friction part neglects the change of direction of the tangent in N = |lam_perp|
            e = q[self._elem_dofs[k]].reshape(4, 3)
            _, _, ddS = (np.asarray(a).reshape(4) for a in cable.shape_functions(xi, np.array(L)))
            r2 = ddS @ e
            Ft = Qs / nr
            asm.add_to_matrix(sd, self._elem_dofs[k], (-cK * Ft * np.kron(dS, tvec))[None, :])
            asm.add_to_matrix(sd, sd, np.array([[-cK * Ft * (tvec @ r2) - cC * dQ_dsd]]))
            asm.add_to_matrix(sd, asm.n_coords + rows[:3], -dQ_dlam[None, :])
        return abs(Qs)

    # ------------------------------------------------------------------ state
    def post_step(self, asm: Assembly, q: np.ndarray, v: np.ndarray, t: float) -> None:
        s = float(q[self._s_dof])
        if s < 0.0 or s > self._total:
            raise SimulationStopped(
                f"joint '{self.name}': body '{self.body.name}' reached the end of beam "
                f"'{self.beam.name}' at t = {t:.6g} s (s = {s:.6g}, beam length {self._total:.6g})")
        k = self._locate(s)
        if k != self.element:
            self.element = k
            self._constraint.version += 1

    def slide_coordinate(self, q: np.ndarray) -> float:
        return float(q[self._s_dof])

    def reaction_force(self, asm: Assembly, lam: np.ndarray) -> np.ndarray:
        """Constraint force of the joint on the body at the hole centre (global components):
        ``-lam_pos`` (the body equation reads ``m r'' + lam_pos = F``)."""
        rows = asm.multiplier_rows(self._constraint)
        return -lam[rows[:3]]

    def get_state(self) -> dict[str, Any]:
        return {"element": int(self.element)}

    def set_state(self, state: dict[str, Any]) -> None:
        self.element = int(state["element"])
        self._constraint.version += 1

    def __repr__(self) -> str:
        return (f"SlidingJoint({self.name!r}, beam={self.beam.name!r}, body={self.body.name!r}, "
                f"variant={self.variant!r}, friction={self.friction})")

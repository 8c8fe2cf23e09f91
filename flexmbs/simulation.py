"""High-level entry points: :func:`solve_static`, :func:`simulate`, :func:`modes`."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from .assembly import Assembly
from .elements import ancf_cable as cable
from .errors import ConvergenceError, ModelError
from .model import Beam, Model, Node, RigidBody
from .solvers.eigen import Modes, eigenmodes
from .solvers.generalized_alpha import (
    GeneralizedAlpha,
    IntegrationStats,
    State,
    consistent_initial_state,
    integrate,
)
from .solvers.static import StaticOptions, StaticResult
from .solvers.static import solve_static as _solve_static


@dataclass
class Result:
    """Time histories at the output times, with accessors by model object."""

    assembly: Assembly
    t: np.ndarray
    q: np.ndarray                      # (n_out, n_coords)
    v: np.ndarray
    lam: np.ndarray
    energy: dict[str, np.ndarray]
    stats: IntegrationStats
    wall_time: float
    final_state: State
    status: str = "completed"
    extra: dict = field(default_factory=dict)

    def node_position(self, node: Node) -> np.ndarray:
        d = self.assembly.node_dofs(node)
        return self.q[:, d[:3]]

    def node_displacement(self, node: Node) -> np.ndarray:
        d = self.assembly.node_dofs(node)
        return self.q[:, d[:3]] - self.assembly.q_ref[d[:3]]

    def beam_point(self, beam: Beam, s: float, quantity: str = "position") -> np.ndarray:
        """Position, displacement or velocity history of the material point at arc length ``s``."""
        e, xi = beam.locate(s)
        dofs = self.assembly.element_dofs(beam)[e]
        L = beam.centerline.lengths[e]
        S, _, _ = cable.shape_functions(np.array([xi]), np.array([L]))
        Sx = np.asarray(S).reshape(-1)[:4]
        def interp(X: np.ndarray) -> np.ndarray:
            Xe = X[..., dofs].reshape(X.shape[:-1] + (4, 3))
            return np.einsum("k,...kc->...c", Sx, Xe)
        if quantity == "position":
            return interp(self.q)
        if quantity == "displacement":
            return interp(self.q) - interp(self.assembly.q_ref[None, :])
        if quantity == "velocity":
            return interp(self.v)
        raise ModelError(f"quantity must be position, displacement or velocity (got {quantity!r})")

    def body_position(self, body: RigidBody) -> np.ndarray:
        return self.q[:, self.assembly.body_dofs(body)[:3]]

    def body_quaternion(self, body: RigidBody) -> np.ndarray:
        return self.q[:, self.assembly.body_dofs(body)[3:]]


def beam_positions(asm: Assembly, beam: Beam, q: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Centreline positions (len(s), 3) of ``beam`` in configuration ``q`` at reference arc
    lengths ``s`` (measured from the first node)."""
    s = np.atleast_1d(np.asarray(s, float))
    loc = [beam.locate(float(x)) for x in s]
    e = np.array([a for a, _ in loc])
    xi = np.array([b for _, b in loc])
    L = np.asarray(beam.centerline.lengths)[e]
    S, _, _ = cable.shape_functions(xi, L)
    S = np.asarray(S).reshape(len(s), 4)
    qe = q[asm.element_dofs(beam)[e]].reshape(len(s), 4, 3)
    return np.einsum("pk,pkc->pc", S, qe)


def solve_static(model: Model | Assembly, options: StaticOptions | None = None, *,
                 t: float = 0.0, redundant_constraints: str = "error") -> StaticResult:
    """Static equilibrium of ``model`` under its loads at time ``t``."""
    asm = model if isinstance(model, Assembly) else Assembly(
        model, redundant_constraints=redundant_constraints)
    return _solve_static(asm, options, t=t)


def modes(model: Model | Assembly, *, n_modes: int | None = None, static: bool = False,
          redundant_constraints: str = "error") -> Modes:
    """Linearised modes about the reference (or, with ``static=True``, the loaded equilibrium)."""
    asm = model if isinstance(model, Assembly) else Assembly(
        model, redundant_constraints=redundant_constraints)
    if static:
        st = _solve_static(asm)
        return eigenmodes(asm, st.q, st.lam, n_modes=n_modes)
    return eigenmodes(asm, n_modes=n_modes)


def simulate(model: Model | Assembly, *, t_end: float, dt: float,
             integrator: GeneralizedAlpha | None = None, output_interval: float | None = None,
             initial_static: bool = False, record_energy: bool = True,
             observer: Callable[[State], None] | None = None,
             progress: Callable[[State, IntegrationStats], None] | None = None,
             redundant_constraints: str = "error") -> Result:
    """Implicit dynamic simulation from the model's initial state (or its static equilibrium,
    ``initial_static=True``) to ``t_end`` with step ``dt``; results every ``output_interval``.
    """
    asm = model if isinstance(model, Assembly) else Assembly(
        model, redundant_constraints=redundant_constraints)
    opts = integrator or GeneralizedAlpha()
    q0, v0 = asm.initial_state()
    if initial_static:
        st = _solve_static(asm)
        q0 = st.q
    state0 = consistent_initial_state(asm, q0, v0, 0.0)
    ts, qs, vs, ls = [], [], [], []
    energies: dict[str, list[float]] = {}

    def record(s: State) -> None:
        ts.append(s.t)
        qs.append(s.q.copy())
        vs.append(s.v.copy())
        ls.append(s.lam.copy())
        if record_energy:
            for k, val in asm.energies(s.q, s.v).items():
                energies.setdefault(k, []).append(val)
        if observer is not None:
            observer(s)

    t0 = time.perf_counter()

    def result(final: State, stats: IntegrationStats, status: str) -> Result:
        return Result(asm, np.array(ts), np.array(qs), np.array(vs), np.array(ls),
                      {k: np.array(v) for k, v in energies.items()}, stats,
                      time.perf_counter() - t0, final, status)

    try:
        final, stats = integrate(asm, opts, t_end=t_end, dt=dt, state=state0,
                                 output_interval=output_interval, observer=record,
                                 progress=progress)
    except ConvergenceError as exc:
        # keep what was computed: the partial history travels with the exception
        last = State(ts[-1], qs[-1], vs[-1], np.zeros_like(qs[-1]), np.zeros_like(qs[-1]), ls[-1])
        exc.partial_result = result(last, IntegrationStats(), f"failed: {exc}")  # type: ignore[attr-defined]
        raise
    return result(final, stats, "completed")

"""Newton's slope search (``NewtonOptions.slope_search``) against a problem whose plain Newton
iteration is known to diverge: the gradient ``r(x) = atan(x)`` of the convex potential
``x atan(x) - ln(1 + x^2) / 2``, from ``|x0| > 1.3917`` (the classical counter-example: each
full step lands farther out on the other side)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.sparse as sp

import flexmbs as fm
from flexmbs.solvers.newton import Newton


class Atan:
    """``r(x) = atan(x) + c x`` per coordinate (``c`` a small convex term), no constraints."""

    def __init__(self, x0: np.ndarray, c: float = 0.0) -> None:
        self.x = np.asarray(x0, dtype=float).copy()
        self.c = c
        self.n = self.x.size
        self.residuals = 0

    def evaluate(self, want_matrix: bool):
        self.residuals += 1
        return np.arctan(self.x) + self.c * self.x, np.zeros(0), 1.0

    def matrix(self):
        return sp.csc_matrix(sp.diags(1.0 / (1.0 + self.x**2) + self.c))

    def scaled_rhs(self, r_q, r_lam, out) -> None:
        np.negative(r_q, out=out)

    def apply(self, dx, factor: float) -> None:
        self.x += factor * dx

    def save(self):
        return self.x.copy()

    def restore(self, saved) -> None:
        self.x[:] = saved

    def describe(self, index: int) -> str:
        return f"x{index}"

    def stiffness_scale(self) -> float:
        return 0.0

    def hold(self, action: int) -> int:   # no contacts to hold
        return 0


def _newton(**kw) -> Newton:
    return Newton(fm.NewtonOptions(modified=False, max_iterations=30, **kw), 1.0)


def test_plain_newton_diverges_on_the_arctangent():
    with pytest.raises(fm.ConvergenceError), np.errstate(over="ignore", invalid="ignore"):
        _newton().solve(Atan([1.5, -2.0, 3.0]), full=True)


@pytest.mark.parametrize("x0", [1.5, -2.0, 3.0, 10.0])
def test_the_slope_search_converges_and_ends_quadratically(x0):
    """From any start the search brings the iterate into Newton's basin; from there the full
    step is taken again, and the errors fall as plain Newton's do at this root:
    ``e' = (2/3) e^3`` (``atan`` has no curvature at 0 and third derivative -2)."""
    problem = Atan([x0])
    st = _newton(slope_search=True).solve(problem, full=True)
    assert abs(problem.x[0]) <= 1e-8
    assert st.iterations <= 6
    e = np.array(st.history) * 1e-8      # |atan(x)|: the scaled error times the tolerance
    near = [(a, b) for a, b in zip(e[:-1], e[1:], strict=True) if a < 0.2]
    assert len(near) >= 2
    for a, b in near:
        assert b == pytest.approx(2.0 / 3.0 * a**3, rel=0.05, abs=1e-15)


def test_the_search_is_not_run_where_newton_contracts():
    """Near the root plain Newton contracts; the slope search takes exactly its iterates."""
    plain, searching = Atan([0.5, -0.3]), Atan([0.5, -0.3])
    a = _newton().solve(plain, full=True)
    b = _newton(slope_search=True).solve(searching, full=True)
    assert a.history == b.history
    assert np.array_equal(plain.x, searching.x)
    assert plain.residuals == searching.residuals


def test_line_search_and_slope_search_are_exclusive():
    with pytest.raises(fm.ModelError, match="slope_search"):
        fm.NewtonOptions(line_search=True, slope_search=True)


def test_the_potential_falls_along_the_searched_iterates():
    """For a gradient problem the iterates steps are taken from lower the potential (the search's
    purpose); plain Newton's first step from 2.0 raises it."""
    def potential(x: float) -> float:
        return x * math.atan(x) - 0.5 * math.log1p(x * x)

    xs: list[float] = []

    class Recording(Atan):
        def matrix(self):        # factorised at each iterate a step is taken from
            xs.append(float(self.x[0]))
            return super().matrix()

    _newton(slope_search=True).solve(Recording([2.0]), full=True)
    assert len(xs) >= 3
    values = [potential(x) for x in xs]
    assert all(b <= a + 1e-15 for a, b in zip(values[:-1], values[1:], strict=True))
    assert potential(2.0 - math.atan(2.0) * 5.0) > potential(2.0)


def test_the_scenario_key_reaches_the_static_solver_and_the_integrator_refuses_it():
    from pathlib import Path

    from flexmbs.io.scenario import load_scenario

    example = Path(__file__).resolve().parents[2] / "examples" / "cantilever.toml"
    sc = load_scenario(example, ["simulation.integrator=static",
                                 "simulation.newton.slope_search=true"])
    assert sc.static_options().newton.slope_search
    with pytest.raises(fm.ModelError, match="slope_search applies to static solves"):
        load_scenario(example, ["simulation.newton.slope_search=true"]).integrator_options()

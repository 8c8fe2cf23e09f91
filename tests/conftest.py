"""Shared fixtures and tolerances for the flexmbs test suite."""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
import threading
import time
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest

import flexmbs as fm

#: run long validations in full only when asked (CI runs their fast form)
FULL = os.environ.get("FLEXMBS_FULL", "") == "1"
EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def pytest_sessionstart(session: pytest.Session) -> None:
    """The whole suite (no test paths named) first makes the complete kernels of cable and rod
    models ready (``flexmbs compile --complete``, flexmbs.kernel.prepare), in two processes at
    once: the tests' models then run on them instead of compiling one kernel per kind of model
    (19 kinds: most of the suite's time from an empty cache). After them, the own kernels of
    the cantilever and of Example 1 (the README's), which tests compare with them. Done by the
    controller of ``pytest -n``, before its workers start; ``FLEXMBS_KERNEL`` other than
    ``auto`` leaves it out, as does a run of chosen test files or ``-k`` (their models compile
    their own kinds)."""
    config = session.config
    if hasattr(config, "workerinput") or os.environ.get("FLEXMBS_KERNEL", "auto") != "auto":
        return
    here = Path(__file__).resolve().parent
    named = [a for a in config.args if Path(str(a).split("::")[0]).resolve() not in (here, here.parent)]
    if named or getattr(config.option, "keyword", "") or os.environ.get("FLEXMBS_DISABLE_JIT", "") == "1":
        return
    start = time.perf_counter()
    compile_ = [sys.executable, "-m", "flexmbs", "compile", "--quiet"]
    codes: list[int] = []

    def chain(*commands: list[str]) -> None:
        codes.extend(subprocess.call(cmd) for cmd in commands)

    # two chains of about the same length (the rod kernel takes longest)
    rod = threading.Thread(target=chain, args=([*compile_, "--complete", "rod"],
                                               [*compile_, "cable"]))
    rod.start()
    chain([*compile_, "--complete", "cable"], [*compile_, str(EXAMPLES / "curved_beam_sleeve.toml")])
    rod.join()
    reporter = config.pluginmanager.get_plugin("terminalreporter")
    if reporter is not None:
        reporter.write_line(f"flexmbs: the complete kernels and two own kernels ready in "
                            f"{time.perf_counter() - start:.0f} s (exit {codes})")


def assert_iteration_matrix_exact(asm, q: np.ndarray, v: np.ndarray, columns, *,
                                  rtol: float = 1e-6, h: float = 1e-9) -> None:
    """The assembled stiffness part of Newton's matrix at ``(q, v)`` (accelerations and
    multipliers zero) against central differences of the compiled residual in the coordinates
    ``columns``: each column within ``rtol`` of the matrix's largest entry."""
    n, m = asm.n_coords, asm.n_mult
    a, lam = np.zeros(n), np.zeros(m)

    def residual(q_: np.ndarray) -> np.ndarray:
        rq, rl = np.zeros(n), np.zeros(m)
        asm.evaluate(q_, v, a, lam, 0.0, rq, rl)
        return rq

    rq, rl = np.zeros(n), np.zeros(m)
    asm.evaluate(q, v, a, lam, 0.0, rq, rl, matrix=(0.0, 0.0, 1.0))
    K = asm.matrix.toarray()[:n, :n]
    scale = np.abs(K).max()
    for j in columns:
        e = np.zeros(n)
        e[j] = h
        column = (residual(q + e) - residual(q - e)) / (2 * h)
        assert np.abs(K[:, j] - column).max() <= rtol * scale, j


def load_module(path: Path, name: str) -> ModuleType:
    """The script ``path`` as a module named ``name`` (an example's or a figure script's
    functions)."""
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def assert_scenario_is_the_script_s(toml: Path, example: ModuleType) -> None:
    """An example's scenario file is what its script writes (``example.scenario()``: one
    source) and builds the model its ``build()`` does (sizes and reference coordinates)."""
    from flexmbs.assembly import Assembly
    from flexmbs.io.scenario import load_scenario

    assert toml.read_text(encoding="utf-8") == example.scenario()
    from_file = Assembly(load_scenario(toml).model)
    built = Assembly(example.build()[0])
    assert (from_file.n_coords, from_file.n_mult) == (built.n_coords, built.n_mult)
    np.testing.assert_allclose(from_file.q_ref, built.q_ref, rtol=0, atol=1e-15)


def load_example(name: str) -> ModuleType:
    """The example script ``examples/<name>.py`` as a module (its model builders)."""
    return load_module(EXAMPLES / f"{name}.py", f"example_{name}")


def straight_beam(model: fm.Model, n_elem: int, *, length: float = 1.0, EA: float = 1e7,
                  EI: float = 50.0, rhoA: float = 0.5, name: str = "beam",
                  options: fm.CableOptions | None = None, damping: float = 0.0) -> fm.Beam:
    """Straight beam along +x from the origin with explicit section resultants."""
    return model.add_beam(fm.line((0, 0, 0), (length, 0, 0), elements=n_elem),
                          section=fm.BeamStiffness(axial_stiffness=EA, bending_stiffness=EI,
                                                   mass_per_length=rhoA),
                          name=name, options=options, damping=damping)


def quarter_arc_beam(model: fm.Model, n_elem: int, *, R: float = 1.0, EA: float = 1e6,
                     EI: float = 1.0, rhoA: float = 1.0,
                     options: fm.CableOptions | None = None) -> fm.Beam:
    """Quarter circle of docs/theory.md §I.7.4: clamped end at the origin with tangent +y, centre
    (R, 0, 0), tip at (R, R, 0) with tangent +x."""
    return model.add_beam(fm.arc((R, 0, 0), R, (0, 0, 0), -np.pi / 2, normal=(0, 0, 1),
                                 elements=n_elem),
                          section=fm.BeamStiffness(axial_stiffness=EA, bending_stiffness=EI,
                                                   mass_per_length=rhoA), options=options)


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(1234)

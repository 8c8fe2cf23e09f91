"""``flexmbs compile [--complete] [cable | rod | SCENARIO ...]``: compile (or load from numba's
cache) the kernels of the named kinds of model ahead of a first run (with ``--complete``: the
complete kernel of their element groups, which serves every model with those groups), and the
one line a run prints while its kernels compile (issue "a first run in seconds")."""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ..errors import FlexmbsError
from ._common import (
    EXIT_BAD_INPUT,
    EXIT_OK,
    add_quiet,
    docs,
    error,
    failure_status,
    overrides,
    terminate_like_ctrl_c,
)

__all__ = ["add_parser", "announce_compiles", "compile_notice", "run"]


def add_parser(sub: Any, parents: list[argparse.ArgumentParser]) -> None:
    comp = sub.add_parser(
        "compile", parents=parents, help="compile the numba kernels ahead of a first run",
        description="Compile (or load from the cache) the numba kernels for the named kinds of "
                    "model (cable, rod: a clamped beam of these elements) or for the models of "
                    "scenario files, so that the first run starts at once "
                    f"({docs('cli', 'flexmbs-compile')}).")
    comp.add_argument("targets", nargs="*", metavar="KIND_OR_SCENARIO",
                      help="cable, rod, or a scenario file (.toml); default: cable")
    comp.add_argument("--complete", action="store_true",
                      help="compile the complete kernel of each target's element groups instead, "
                           "which serves every model with those groups, so that none compiles "
                           "(somewhat slower per step than a model's own kernel)")
    add_quiet(comp, "no output")



def compile_notice(estimate: float | None, same_kind: bool = True) -> str:
    """The one line printed while the kernels compile for a new kind of model."""
    if estimate is None:
        about = "a minute or two on a 2-core machine"
    elif same_kind:
        about = f"about {estimate:.0f} s, as its last compile here"
    else:
        about = f"the longest compile here so far took {estimate:.0f} s"
    return (f"flexmbs: compiling the numba kernels for this kind of model (once; {about}; "
            "cached for later runs)")


def announce_compiles() -> None:
    """Print :func:`compile_notice` on stderr whenever the kernel compiles in this process."""
    from .. import kernel

    def announce(estimate: float | None, kind: str, same_kind: bool) -> None:
        print(compile_notice(estimate, same_kind), file=sys.stderr, flush=True)

    kernel.announce_compile = announce


def run(args: argparse.Namespace) -> int:
    """``flexmbs compile``: compile (or load) the kernels of the named kinds of model or
    scenario files ahead of a run; one line per kind."""
    from ..io.scenario import load_scenario

    targets = list(args.targets) or ["cable"]
    restore = terminate_like_ctrl_c()
    choice = os.environ.get("FLEXMBS_KERNEL")     # the kernels asked for, whatever it says
    os.environ["FLEXMBS_KERNEL"] = "complete" if args.complete else "own"
    if not args.quiet:
        announce_compiles()
    try:
        for target in targets:
            start = time.perf_counter()
            if target in _COMPILE_KINDS:
                model = _COMPILE_KINDS[target]()
                name = target
            else:
                if not target.endswith(".toml") and not Path(target).exists():
                    error(f"compile: {target!r} is neither a kind of model "
                           f"({', '.join(_COMPILE_KINDS)}) nor a scenario file")
                    return EXIT_BAD_INPUT
                sc = load_scenario(target, overrides(args))
                model, name = sc.model, target
            from ..assembly import Assembly
            from ..kernel import model_kind

            asm = Assembly(model)
            _compile_python_paths(asm)
            kind = model_kind(asm.kernel_system, complete=asm.kernel_system is asm.complete_system)
            if not args.quiet:
                print(f"flexmbs: {name}: kernels ready ({kind}, "
                      f"{time.perf_counter() - start:.1f} s)", flush=True)
    except (KeyboardInterrupt, FlexmbsError, OSError) as exc:
        return failure_status(exc)
    finally:
        restore()
        if choice is None:
            os.environ.pop("FLEXMBS_KERNEL", None)
        else:
            os.environ["FLEXMBS_KERNEL"] = choice
    return EXIT_OK


def _compile_python_paths(asm: Any) -> None:
    """The compiled functions a run calls from Python besides the kernel (the banded
    factorisation's set-up, the output's beam fields), by one small dynamic step."""
    from ..simulation import simulate
    from ..solvers.generalized_alpha import GeneralizedAlpha

    with contextlib.suppress(FlexmbsError):   # a model that cannot step still has its kernel
        simulate(asm, t_end=2e-6, dt=1e-6, integrator=GeneralizedAlpha(adaptive=False),
                 output_interval=1e-6, record_energy=False)


def _cantilever(element: str) -> Any:
    """A clamped beam under gravity: the kernels of every model of this element's beams with
    clamps, pins, prescribed motion and loads."""
    import flexmbs as fm

    model = fm.Model(gravity=(0.0, 0.0, -9.81))
    beam = model.add_beam(fm.line((0, 0, 0), (1, 0, 0), elements=2),
                          section=fm.CircularSection(5e-3),
                          material=fm.Material(E=2.1e11, rho=7800.0), element=element)
    model.clamp(beam.first_node)
    return model


#: kinds of model ``flexmbs compile`` knows by name (scenario files name any other)
_COMPILE_KINDS: dict[str, Callable[[], Any]] = {
    "cable": lambda: _cantilever("ancf_cable"),
    "rod": lambda: _cantilever("ancf_rod14"),
}

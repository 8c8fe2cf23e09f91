"""``flexmbs run SCENARIO``: run a scenario into its output folder (the docs site's "Command
line" page), with a progress bar (or, with ``--verbose``, a line of solver statistics per
stretch of steps), ``--resume`` of a stopped run and one line at the end."""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path
from typing import Any

from ..errors import FlexmbsError
from ._common import (
    EXIT_BAD_INPUT,
    EXIT_OK,
    Number,
    add_quiet,
    docs,
    error,
    failure_status,
    overrides,
    raise_pending,
    terminate_like_ctrl_c,
)
from .compile import announce_compiles

__all__ = ["Progress", "add_parser", "run"]


def add_parser(sub: Any, parents: list[argparse.ArgumentParser]) -> None:
    run = sub.add_parser("run", parents=parents, help="run a scenario",
                         description="Run a scenario and write its output folder "
                                     f"({docs('cli', 'flexmbs-run')}).")
    run.add_argument("scenario", metavar="SCENARIO", help="scenario file (.toml)")
    run.add_argument("--out", metavar="DIR",
                     help="output folder (default: out/<scenario name> in the current directory)")
    run.add_argument("--t-end", type=Number(gt=0), metavar="T", help="end time (= --set simulation.t_end=T)")
    run.add_argument("--dt", type=Number(gt=0), metavar="H", help="time step (= --set simulation.dt=H)")
    talk = run.add_mutually_exclusive_group()
    add_quiet(talk, "no progress bar and no final summary")
    talk.add_argument("--verbose", "-v", action="store_true",
                      help="instead of the progress bar, one line on stderr per stretch of "
                           "steps the integrator reports (up to each output time): time, step "
                           "size, steps, Newton iterations (in all and per step), "
                           "factorisations and rejected steps")
    run.add_argument("--resume", metavar="OUT_DIR",
                     help="continue the stopped run in OUT_DIR from its checkpoint.npz to t_end, "
                          "appending to its files")
    run.add_argument("--overwrite", action="store_true",
                     help="replace the output of another scenario in the output folder")
    run.add_argument("--output-frames", choices=("multiblock", "merged"),
                     help="frames as VTK multiblocks of named blocks (.vtm, default) or one "
                          "merged grid each (.vtu) (= --set simulation.output_frames=...)")



class Progress:
    """tqdm bar over simulated time with steps/s and Newton iterations in the postfix; with
    ``verbose`` no bar but one line of the solver's counters per report instead."""

    def __init__(self, t0: float, t_end: float, *, disable: bool, name: str,
                 verbose: bool = False) -> None:
        self.bar: Any = None
        self.t0 = t0
        self.wall0 = time.perf_counter()
        self.last = 0.0
        self.verbose = verbose
        self.name = name
        self.seen: tuple[float, int, int, int, int] = (t0, 0, 0, 0, 0)
        if verbose:
            print(f"{name}: {'t [s]':>12} {'h [s]':>10} {'steps':>7} {'newton':>7} "
                  f"{'per step':>8} {'factor.':>7} {'rejected':>8}", file=sys.stderr, flush=True)
        if disable or verbose:
            return
        from tqdm import tqdm

        self.bar = tqdm(total=t_end, initial=t0, desc=name, unit="s", file=sys.stderr,
                        dynamic_ncols=True, leave=True,
                        bar_format="{desc}: {percentage:3.0f}%|{bar}| t = {n:.4g}/{total:.4g} s "
                                   "[{elapsed}<{remaining}{postfix}]")

    def __call__(self, state: Any, stats: Any) -> None:
        raise_pending()
        if self.verbose:
            self._line(state, stats)
        if self.bar is None:
            return
        self.stats = stats
        self.bar.n = float(state.t)
        now = time.perf_counter()
        if now - self.last >= 0.1:
            self.last = now
            self._postfix(now)
            self.bar.refresh()

    def _line(self, state: Any, stats: Any) -> None:
        """One line of what the integrator did since its last report (the counters' growth;
        ``h``: the mean step size over the stretch)."""
        now = (float(state.t), int(stats.steps), int(stats.newton_iterations),
               int(stats.factorizations), int(stats.rejected_steps))
        t0, steps0, newton0, fact0, rej0 = self.seen
        steps = now[1] - steps0
        if steps <= 0 and now[4] == rej0:
            return
        self.seen = now
        h = (now[0] - t0) / steps if steps > 0 else float("nan")
        per = (now[2] - newton0) / steps if steps > 0 else float("nan")
        print(f"{self.name}: {now[0]:12.6g} {h:10.3g} {steps:7d} {now[2] - newton0:7d} "
              f"{per:8.2f} {now[3] - fact0:7d} {now[4] - rej0:8d}",
              file=sys.stderr, flush=True)

    def _postfix(self, now: float) -> None:
        stats = getattr(self, "stats", None)
        if stats is None:
            return
        rate = stats.steps / max(now - self.wall0, 1e-9)
        post = {"steps": stats.steps, "steps/s": f"{rate:.3g}"}
        # the integrator totals Newton iterations at the end of a run; show them once known
        if stats.newton_iterations:
            post["newton"] = stats.newton_iterations
        if stats.rejected_steps:
            post["rejected"] = stats.rejected_steps
        self.bar.set_postfix(post, refresh=False)

    def close(self) -> None:
        if self.bar is not None:
            self._postfix(time.perf_counter())   # final counts (same stats object, now totalled)
            self.bar.close()
            self.bar = None


def _is_end_time(assignment: str) -> bool:
    return assignment.replace(" ", "").startswith("simulation.t_end=")


def _is_output_form(assignment: str) -> bool:
    return assignment.replace(" ", "").startswith("simulation.output_frames=")


def _resume_overrides(args: argparse.Namespace) -> list[str]:
    """The overrides of a resumed run: the first run's (from ``summary.json``, without its end
    time) unless the same are given again; a different model is refused with one line naming
    the difference (issue "nothing lost", item 5). The scenario file and its content must be
    those of the first run."""
    from ..errors import ScenarioError
    from ..runs import scenario_digest

    given = overrides(args)
    try:
        meta = json.loads((Path(args.resume) / "summary.json").read_text(encoding="utf-8"))
        meta = meta.get("metadata") or {}
    except (OSError, ValueError):
        return given                     # resume_point reports what is missing
    where = f"--resume {args.resume}"
    first_file = meta.get("scenario_file")
    if first_file and os.path.abspath(args.scenario) != first_file:
        raise ScenarioError(f"{where}: that run was made from {first_file}, not "
                            f"{os.path.abspath(args.scenario)}")
    digest = meta.get("scenario_sha1")
    if digest and Path(args.scenario).is_file() and scenario_digest(args.scenario) != digest:
        raise ScenarioError(f"{where}: {args.scenario} has changed since that run started; a "
                            "resumed run must be the same model (only the end time may change)")
    first = [o for o in meta.get("overrides") or [] if not _is_end_time(o)]
    # the form of the frames is not the model's: a resume continues the series in its form
    model = [o for o in first if not _is_output_form(o)]
    now = [o for o in given if not _is_end_time(o) and not _is_output_form(o)]
    if now and now != model:
        extra = [o for o in now if o not in model] or [o for o in model if o not in now] or now
        raise ScenarioError(f"{where}: that run used --set {' '.join(model) or '(none)'}; this "
                            f"one differs ({extra[0]}); a resumed run must be the same model "
                            "(only the end time may change)")
    return first + [o for o in given if _is_end_time(o)]


def run(args: argparse.Namespace) -> int:
    """``flexmbs run``: load the scenario, resolve the output folder and call
    :func:`flexmbs.runs.run_scenario`, which claims the folder and runs the scenario
    (:func:`~flexmbs.simulation.solve_static` or :func:`~flexmbs.simulation.simulate`); print
    one line."""
    from ..io.scenario import load_scenario
    from ..kernel import kernel_choice
    from ..runs import run_scenario

    quiet = bool(args.quiet)
    verbose = bool(getattr(args, "verbose", False))
    out: Path | None = None
    t_wall = time.perf_counter()
    bars: list[Progress] = []

    def progress(start: float, t_end: float, name: str) -> Progress:
        bars.append(Progress(start, t_end, name=name, disable=quiet or not sys.stderr.isatty(),
                             verbose=verbose))
        return bars[-1]

    def close_bars() -> None:
        for bar in bars:
            bar.close()

    restore = terminate_like_ctrl_c()
    try:
        kernel_choice()     # a bad FLEXMBS_KERNEL is bad input, before anything is written
        sets = _resume_overrides(args) if args.resume is not None else overrides(args)
        sc = load_scenario(args.scenario, sets)
        sim = sc.simulation
        if args.resume is not None:
            if args.out is not None and Path(args.out).resolve() != Path(args.resume).resolve():
                error(f"--out {args.out} and --resume {args.resume} name different folders")
                return EXIT_BAD_INPUT
            out = Path(args.resume)
            if not out.is_dir():
                error(f"cannot resume: {out} is not a folder")
                return EXIT_BAD_INPUT
            if sim.integrator in ("static", "quasi_static"):
                error(f"--resume: a {sim.integrator} scenario has nothing to resume (its "
                      "equilibria are solved again from the start)")
                return EXIT_BAD_INPUT
        else:
            if args.out is not None and not args.out.strip():
                error("--out: empty path; give the output folder")
                return EXIT_BAD_INPUT
            out = Path(args.out) if args.out is not None else Path("out") / sc.name
        if not quiet:
            announce_compiles()
        outcome = run_scenario(sc, out, overrides=sets, resume=args.resume is not None,
                               overwrite=bool(getattr(args, "overwrite", False)),
                               progress=progress)
        close_bars()
    except (KeyboardInterrupt, FlexmbsError, OSError) as exc:
        close_bars()
        # a run that had started (its summary exists) failed, e.g. on a full disk; before
        # that a bad path is bad input
        return failure_status(
            exc, interrupted="interrupted" + (f" (output so far in {out})" if out else ""),
            started=out is not None and (out / "summary.json").is_file())
    finally:
        restore()
    if not quiet:
        wall = time.perf_counter() - t_wall
        print(f"{sc.name}: {outcome.status} at t = {sim.t_end:.6g} s: {outcome.steps} steps, "
              f"{outcome.newton_iterations} Newton iterations, {outcome.rejected_steps} rejected, "
              f"wall time {wall:.3g} s; output: {out}")
    return EXIT_OK

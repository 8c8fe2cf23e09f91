"""Soak: long runs of Example 2 and the guide wire, and whether memory, open files and step
time stay flat (issue 57, item 3).

Each model runs through the path ``flexmbs run`` takes (:func:`flexmbs.io.scenario.load_scenario`
+ :func:`flexmbs.runs.run_scenario`), its output folder written to a temporary folder in
``--dir`` with the scenario's output settings (frames, probes, contact records, checkpoints,
the writer's thread); ``--model both`` runs each model in a fresh process (memory freed by
the first would hide growth in the second: the allocator reuses it before the resident size
grows). The integrator's progress callback (called after each stretch of steps, at least at
every output time) takes a sample at every ``t_end / --windows`` of simulated time: resident
set size (``VmRSS`` of /proc/self/status), open file descriptors (/proc/self/fd), threads,
files in the output folder's ``vtu/``, the machine's load, and over the window the wall time,
the process's CPU time (all threads) and the Newton iterations per step (the sampling's own
time left out).

Printed per model: the samples, and the least-squares slopes (± standard error) over the
windows after the first (the first holds the start: cache loading, the first outputs, the
excitation): RSS in MB per 1000 steps and per simulated second, open files per 1000 steps,
wall and CPU time per step in % of their mean per 1000 steps, Newton iterations per step
likewise (a change of the physics, not of the software); then the output folder's size and
file count.

An output folder of more than ``MAX_FILES`` files is refused (issue 57, item 3); a run whose
multiblock frames would pass it (Example 2 beyond 125 s: 8 files per frame) is run with
merged frames instead (``simulation.output_frames = "merged"``, the remedy the refusal names;
the same outputs, one file each), and the report says so.

    python benchmarks/soak.py [--model example2|guide_wire|both] [--t-end T] [--windows 40]
                              [--quick] [--dir DIR] [--csv FILE] [--json FILE] [--trace]

``--trace`` runs tracemalloc throughout (slow) and prints the allocation sites that grew most
between the end of the first window and the end of the run.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import subprocess
import sys
import tempfile
import time
import tracemalloc
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

#: model -> (scenario, simulated seconds of the soak: the issue's lengths)
MODELS = {"example2": (ROOT / "examples" / "solar_array_wing.toml", 200.0),
          "guide_wire": (ROOT / "examples" / "guide_wire.toml", 20.0)}
#: simulated seconds of ``--quick`` (a smoke test of a few seconds)
QUICK = {"example2": 0.5, "guide_wire": 0.05}


def process_status() -> tuple[float, int]:
    """(resident set size in MB, threads) of this process, from /proc/self/status."""
    rss_kb, threads = 0, 0
    with open("/proc/self/status", encoding="ascii") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                rss_kb = int(line.split()[1])
            elif line.startswith("Threads:"):
                threads = int(line.split()[1])
    return rss_kb / 1024, threads


def process_cpu() -> float:
    """CPU time of this process, all its threads, user + system [s]."""
    return time.process_time()


def open_files() -> int:
    """Open file descriptors of this process."""
    return len(os.listdir("/proc/self/fd"))


def folder_files(path: Path) -> tuple[int, int]:
    """(files, bytes) under ``path``."""
    files = size = 0
    for dirpath, _, names in os.walk(path):
        for n in names:
            files += 1
            size += os.stat(os.path.join(dirpath, n)).st_size
    return files, size


@dataclass
class Sample:
    """The process at the end of a window of simulated time."""

    t: float                 # simulated time [s]
    steps: int               # steps so far
    wall: float              # wall time since the first progress report, sampling excluded [s]
    step_us: float           # wall per step over the window [µs]
    cpu_us: float            # CPU time (all threads, user + system) per step over the window [µs]
    newton_per_step: float   # Newton iterations per step over the window
    rss_mb: float
    open_files: int
    threads: int
    output_files: int        # files in the output folder's vtu/
    load: float = math.nan        # the machine's 1-minute load average
    traced_mb: float = math.nan   # tracemalloc's current size (--trace only)


@dataclass
class Slope:
    """Least-squares slope and its standard error."""

    value: float
    error: float


@dataclass
class Soak:
    """One model's soak: samples, slopes and the output folder."""

    model: str
    scenario: str
    t_end: float
    overrides: list[str]
    samples: list[Sample]
    slopes: dict[str, Slope] = field(default_factory=dict)
    wall: float = 0.0                  # the whole run_scenario call [s]
    rss_start_mb: float = 0.0          # before the scenario is loaded
    output_files: int = 0
    output_mb: float = 0.0
    status: str = ""
    notes: list[str] = field(default_factory=list)


class Sampler:
    """The integrator's progress callback: a :class:`Sample` at every ``window`` of simulated
    time; the time spent sampling is left out of the step times."""

    def __init__(self, t_end: float, windows: int, folder: Path, trace: bool) -> None:
        self.t_end, self.window, self.folder, self.trace = t_end, t_end / windows, folder, trace
        self.samples: list[Sample] = []
        self.next_t = 0.0
        self.wall0 = 0.0
        self.overhead = 0.0           # sampling time so far
        self.last = (0.0, 0.0, 0, 0)  # (wall, CPU, steps, Newton iterations) of the last sample
        self.snapshots: list[Any] = []

    def __call__(self, state: Any, stats: Any) -> None:
        now = time.perf_counter()
        t = float(state.t)
        if self.samples and t < self.next_t - 1e-9 * self.window:
            return
        if not self.samples:
            self.wall0 = now
        wall = now - self.wall0 - self.overhead
        cpu = process_cpu()
        steps, newton = int(stats.steps), int(stats.newton_iterations)
        wall_last, cpu_last, steps_last, newton_last = self.last
        n = steps - steps_last if self.samples else 0     # the first report: no window
        rss, threads = process_status()
        files = sum(1 for _ in os.scandir(self.folder / "vtu")) if (self.folder / "vtu").is_dir() else 0
        traced = tracemalloc.get_traced_memory()[0] / 2**20 if self.trace else math.nan
        self.samples.append(Sample(
            t=t, steps=steps, wall=wall,
            step_us=1e6 * (wall - wall_last) / n if n > 0 else math.nan,
            cpu_us=1e6 * (cpu - cpu_last) / n if n > 0 else math.nan,
            newton_per_step=(newton - newton_last) / n if n > 0 else math.nan,
            rss_mb=rss, open_files=open_files(), threads=threads, output_files=files,
            load=os.getloadavg()[0], traced_mb=traced))
        if self.trace and (len(self.samples) == 2 or t >= self.t_end - 1e-9 * self.window):
            self.snapshots.append(tracemalloc.take_snapshot())   # first window's end, the run's
        self.next_t = (math.floor(t / self.window + 1e-9) + 1) * self.window
        self.overhead += time.perf_counter() - now
        self.last = (wall, process_cpu(), steps, newton)     # the next window starts here


def least_squares(x: np.ndarray, y: np.ndarray) -> Slope:
    """Slope of the straight line fitted to (x, y), with its standard error."""
    keep = np.isfinite(x) & np.isfinite(y)
    x, y = x[keep], y[keep]
    if x.size < 2 or np.ptp(x) == 0:
        return Slope(math.nan, math.nan)
    a = np.vstack([x, np.ones_like(x)]).T
    (slope, icpt), *_ = np.linalg.lstsq(a, y, rcond=None)
    if x.size < 3:
        return Slope(float(slope), math.nan)
    resid = y - (slope * x + icpt)
    se = math.sqrt(float(resid @ resid) / (x.size - 2) / float(((x - x.mean()) ** 2).sum()))
    return Slope(float(slope), se)


def fit_slopes(samples: list[Sample]) -> dict[str, Slope]:
    """The slopes over the windows after the first (samples[2:]; samples[0] is the first
    progress report, samples[1] ends the first window)."""
    kept = samples[2:]
    steps = np.array([s.steps for s in kept], float) / 1000
    # a window's step time and Newton count belong to its middle
    mid = np.array([(a.steps + b.steps) / 2 for a, b in zip(samples[1:-1], kept, strict=True)],
                   float) / 1000

    def column(name: str) -> np.ndarray:
        return np.array([getattr(s, name) for s in kept], float)

    def percent(name: str) -> Slope:
        y = column(name)
        fit, mean = least_squares(mid, y), float(np.nanmean(y)) if y.size else math.nan
        return Slope(100 * fit.value / mean, 100 * fit.error / mean)

    out = {"rss_mb_per_1000_steps": least_squares(steps, column("rss_mb")),
           "rss_mb_per_simulated_s": least_squares(column("t"), column("rss_mb")),
           "open_files_per_1000_steps": least_squares(steps, column("open_files")),
           "step_time_percent_per_1000_steps": percent("step_us"),
           "cpu_per_step_percent_per_1000_steps": percent("cpu_us"),
           "newton_per_step_percent_per_1000_steps": percent("newton_per_step")}
    if kept and not math.isnan(kept[0].traced_mb):
        out["traced_mb_per_1000_steps"] = least_squares(steps, column("traced_mb"))
    return out


def soak(model: str, t_end: float, *, windows: int = 40, directory: str | None = None,
         trace: bool = False) -> Soak:
    """Run ``model`` (a key of :data:`MODELS`) to ``t_end`` into a temporary output folder in
    ``directory`` and sample it ``windows`` times."""
    from flexmbs.errors import ModelError
    from flexmbs.io.output import MAX_FILES
    from flexmbs.io.scenario import load_scenario
    from flexmbs.runs import run_scenario

    scenario = MODELS[model][0]
    sets = [f"simulation.t_end={t_end!r}"]
    notes: list[str] = []
    rss_start = process_status()[0]
    if trace:
        tracemalloc.start()
    with tempfile.TemporaryDirectory(prefix=f"flexmbs_soak_{model}_", dir=directory) as tmp:
        out = Path(tmp) / model
        sampler = Sampler(t_end, windows, out, trace)
        t0 = time.perf_counter()
        try:
            outcome = run_scenario(load_scenario(scenario, sets), out, overrides=sets,
                                   progress=lambda *_: sampler)
        except ModelError as exc:
            if f"{MAX_FILES:.0e}" not in str(exc):
                raise
            notes.append(f"refused with default frames ({exc}); run with merged frames")
            sets.append('simulation.output_frames="merged"')
            sampler = Sampler(t_end, windows, out, trace)
            t0 = time.perf_counter()
            outcome = run_scenario(load_scenario(scenario, sets), out, overrides=sets,
                                   progress=lambda *_: sampler)
        wall = time.perf_counter() - t0
        files, size = folder_files(out)
    result = Soak(model=model, scenario=str(scenario.relative_to(ROOT)), t_end=t_end,
                  overrides=sets, samples=sampler.samples, wall=wall, rss_start_mb=rss_start,
                  output_files=files, output_mb=size / 1e6, status=outcome.status, notes=notes)
    result.slopes = fit_slopes(sampler.samples)
    if trace:
        if len(sampler.snapshots) >= 2:
            stats = sampler.snapshots[-1].compare_to(sampler.snapshots[0], "lineno")
            result.notes += ["tracemalloc, growth from the end of the first window to the end:"]
            result.notes += [f"  {s}" for s in stats[:15]]
        tracemalloc.stop()
    return result


UNITS = {"rss_mb_per_1000_steps": "MB RSS per 1000 steps",
         "rss_mb_per_simulated_s": "MB RSS per simulated s",
         "open_files_per_1000_steps": "open files per 1000 steps",
         "step_time_percent_per_1000_steps": "% wall time per step, per 1000 steps",
         "cpu_per_step_percent_per_1000_steps": "% CPU time per step, per 1000 steps",
         "newton_per_step_percent_per_1000_steps": "% Newton iterations per step, per 1000 steps",
         "traced_mb_per_1000_steps": "MB traced by tracemalloc per 1000 steps"}


def print_report(r: Soak) -> None:
    print(f"\n{r.model}: {r.scenario}, t_end = {r.t_end:g} s ({' '.join(r.overrides)}), "
          f"{r.status}; whole run {r.wall:.1f} s wall, {r.samples[-1].steps if r.samples else 0} "
          f"steps; RSS before loading the scenario {r.rss_start_mb:.1f} MB")
    for note in r.notes:
        print(note)
    print(f"{'t [s]':>9} {'steps':>9} {'wall [s]':>9} {'µs/step':>9} {'CPU µs/step':>11} "
          f"{'Newton/step':>11} {'RSS [MB]':>9} {'fds':>4} {'threads':>7} {'vtu files':>9} "
          f"{'load':>5}")
    for i, s in enumerate(r.samples):
        mark = "  first report" if i == 0 else "  first window: not fitted" if i == 1 else ""
        traced = f"  traced {s.traced_mb:.1f} MB" if not math.isnan(s.traced_mb) else ""
        print(f"{s.t:9.4g} {s.steps:9d} {s.wall:9.2f} {s.step_us:9.1f} {s.cpu_us:11.1f} "
              f"{s.newton_per_step:11.3f} {s.rss_mb:9.1f} {s.open_files:4d} {s.threads:7d} "
              f"{s.output_files:9d} {s.load:5.2f}{traced}{mark}")
    print(f"slopes over the {max(len(r.samples) - 2, 0)} samples after the first window "
          "(least squares ± standard error):")
    for key, fit in r.slopes.items():
        print(f"  {fit.value:+.4g} ± {fit.error:.2g} {UNITS[key]}")
    print(f"output folder: {r.output_files} files, {r.output_mb:.1f} MB")


def from_json(d: dict[str, Any]) -> Soak:
    """A :class:`Soak` back from its JSON form."""
    return Soak(**{**d, "samples": [Sample(**s) for s in d["samples"]],
                   "slopes": {k: Slope(**v) for k, v in d["slopes"].items()}})


def in_child(argv: list[str], model: str) -> Soak:
    """``model`` soaked in a fresh process (memory a previous model freed would hide growth:
    the allocator reuses it before the resident size grows); its report printed here."""
    with tempfile.TemporaryDirectory(prefix="flexmbs_soak_report_") as tmp:
        report = Path(tmp) / "report.json"
        # the child imports the flexmbs this process imported
        import flexmbs
        path = [str(Path(flexmbs.__file__).resolve().parents[1]), os.environ.get("PYTHONPATH", "")]
        done = subprocess.run([sys.executable, __file__, *argv, f"--model={model}",
                               f"--json={report}", "--no-header"],
                              env={**os.environ, "PYTHONPATH": os.pathsep.join(p for p in path if p)},
                              capture_output=True, text=True, check=False)
        sys.stdout.write(done.stdout)
        if done.returncode != 0:
            sys.stdout.write(done.stderr)
            raise RuntimeError(f"soak of {model} failed (exit {done.returncode})")
        return from_json(json.loads(report.read_text(encoding="utf-8"))[0])


def write_csv(path: str, reports: list[Soak]) -> None:
    names = list(Sample.__dataclass_fields__)
    with open(path, "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(["model", *names])
        for r in reports:
            for s in r.samples:
                w.writerow([r.model, *(getattr(s, n) for n in names)])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", choices=(*MODELS, "both"), default="both",
                    help="both: each in a fresh process, one after the other (default)")
    ap.add_argument("--t-end", type=float, help="simulated time [s] (default: 200 for example2, "
                                                "20 for guide_wire)")
    ap.add_argument("--quick", action="store_true",
                    help=f"a smoke test: {QUICK['example2']:g} s of example2, "
                         f"{QUICK['guide_wire']:g} s of guide_wire, 5 windows")
    ap.add_argument("--windows", type=int, help="samples after the first report (default 40)")
    ap.add_argument("--dir", help="where the temporary output folder goes (default: the "
                                  "system's temporary folder)")
    ap.add_argument("--csv", help="write the samples to this CSV file")
    ap.add_argument("--json", help="write the whole report to this JSON file")
    ap.add_argument("--trace", action="store_true",
                    help="tracemalloc throughout (slow): the allocation sites that grew most")
    ap.add_argument("--no-header", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    import flexmbs

    windows = args.windows or (5 if args.quick else 40)
    if not args.no_header:
        print(f"soak: flexmbs {flexmbs.__version__}, python {sys.version.split()[0]}, "
              f"{os.cpu_count()} cores, load {os.getloadavg()[0]:.2f}, "
              f"{time.strftime('%Y-%m-%d %H:%M')}", flush=True)
    reports = []
    if args.model == "both":
        passed = [f"--windows={windows}"]
        passed += [f"--t-end={args.t_end!r}"] if args.t_end else []
        passed += ["--quick"] if args.quick else []
        passed += [f"--dir={args.dir}"] if args.dir else []
        passed += ["--trace"] if args.trace else []
        reports = [in_child(passed, name) for name in MODELS]
    else:
        t_end = args.t_end or (QUICK[args.model] if args.quick else MODELS[args.model][1])
        reports.append(soak(args.model, t_end, windows=windows, directory=args.dir,
                            trace=args.trace))
        print_report(reports[-1])
    if not args.no_header:
        print(f"load at the end {os.getloadavg()[0]:.2f}")
    sys.stdout.flush()
    if args.csv:
        write_csv(args.csv, reports)
    if args.json:
        Path(args.json).write_text(json.dumps([asdict(r) for r in reports], indent=1),
                                   encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Issue 57, item 4: a sweep whose Dask worker process is killed (SIGKILL) mid-case finishes with
every row, the killed case run again from the start (the same files, bit for bit, as an
uninterrupted run); a case that kills its worker every time ends as one failed row after a
bounded number of attempts; a sweep interrupted (Ctrl-C, or its process killed) and run again
runs no finished case again and the unfinished ones from the start.

The kills are real: the pid is the one the case's worker wrote in the case's start log
(``.attempts/<case>``) and in the case folder's lock, and the kill waits until that attempt's
``probes.csv`` shows progress, so it lands mid-case whatever the machine's speed.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path

import pytest

import flexmbs as fm
from flexmbs.cli import main
from flexmbs.io.folder import LOCK_NAME, output_summary
from flexmbs.sweeps import ATTEMPTS_DIR

distributed = pytest.importorskip("distributed")

ROOT = Path(__file__).resolve().parents[1]
CANTILEVER = str(ROOT / "examples" / "cantilever.toml")
#: a case of about 2 s on a quiet core (300 outputs), long enough to be killed mid-run
LONG = ("simulation.t_end=3.0", "simulation.output_interval=0.01")


def _status(folder: Path) -> str | None:
    try:
        return json.loads((folder / "summary.json").read_text())["status"]
    except (OSError, ValueError, KeyError):
        return None


def _rows(folder: Path) -> int:
    """Rows of the folder's probes.csv (written after summary.json: maybe not there yet)."""
    try:
        return (folder / "probes.csv").read_bytes().count(b"\n") - 1
    except OSError:
        return 0


def _starts(sweep_dir: Path, case: str) -> list[int]:
    """The pids of the case's starts in this sweep run, oldest first."""
    try:
        text = (sweep_dir / ATTEMPTS_DIR / case).read_text()
    except OSError:
        return []
    return [int(p) for p in re.findall(r"pid=(\d+)", text)]


class WorkerKiller(threading.Thread):
    """SIGKILL the worker process that runs a case, mid-case: the case is ``target()`` (a name,
    or None while there is none); the pid is the last in its start log and must hold the case
    folder's lock; the kill waits until this attempt's ``probes.csv`` (written after the last
    kill) has more than ``rows`` rows. At most ``kills`` kills."""

    def __init__(self, sweep_dir: Path, target: Callable[[], str | None], *, kills: int,
                 rows: int = 30) -> None:
        super().__init__(daemon=True)
        self.sweep_dir, self.target, self.kills, self.rows = sweep_dir, target, kills, rows
        self.killed: list[tuple[str, int, int]] = []     # (case, pid, rows on disk)
        self.done = threading.Event()

    def run(self) -> None:
        last_kill = 0.0
        while len(self.killed) < self.kills and not self.done.wait(0.01):
            case = self.target()
            if case is None:
                continue
            folder = self.sweep_dir / case
            pids = _starts(self.sweep_dir, case)
            try:
                holder = int((folder / LOCK_NAME).read_text())
                fresh = (folder / "probes.csv").stat().st_mtime > last_kill
            except (OSError, ValueError):
                continue
            rows = _rows(folder)
            if not pids or holder != pids[-1] or not fresh or rows <= self.rows:
                continue
            if _status(folder) != "running" or pids[-1] in {p for _, p, _ in self.killed}:
                continue
            os.kill(pids[-1], signal.SIGKILL)
            last_kill = time.time()
            self.killed.append((case, pids[-1], rows))


def _same_run(folder: Path, reference: Path) -> None:
    """The files of an uninterrupted run, bit for bit (the frames too)."""
    names = ["probes.csv", "contacts.csv", "cantilever.pvd"]
    names += sorted(str(p.relative_to(reference)) for p in (reference / "vtu").iterdir())
    for name in names:
        assert (folder / name).read_bytes() == (reference / name).read_bytes(), name
    ours, theirs = (json.loads((d / "summary.json").read_text()) for d in (folder, reference))
    for key in ("status", "final_time", "steps", "newton_iterations", "rejected_steps"):
        assert ours[key] == theirs[key], key


def _reference(tmp_path: Path, overrides: tuple[str, ...]) -> Path:
    ref = tmp_path / "reference"
    argv = ["run", CANTILEVER, "--out", str(ref), "-q"]
    for o in overrides:
        argv += ["--set", o]
    assert main(argv) == 0
    return ref


def test_a_worker_killed_mid_case_runs_the_case_again_and_no_finished_case(tmp_path):
    """One worker: the second case runs on the worker that holds the first case's result; the
    worker is killed mid-case. Dask would recompute the lost result of the first case (its
    folder rewritten behind its row) if the sweep still held it."""
    out = tmp_path / "sweep"
    names = ["elements=4", "elements=6"]

    def after_the_first() -> str | None:       # the case that runs once the other completed
        for name in names:
            other = next(n for n in names if n != name)
            if _status(out / name) == "running" and _status(out / other) == "completed":
                return name
        return None

    killer = WorkerKiller(out, after_the_first, kills=1)
    reported: dict[str, tuple[dict, int]] = {}

    def report(case, row, done, total, reused):
        reported[case.name] = (row, (out / case.name / "summary.json").stat().st_mtime_ns)

    killer.start()
    try:
        rows = fm.sweep(CANTILEVER, {"beams.rod.elements": [4, 6]}, overrides=LONG, out=out,
                        workers=1, report=report)
    finally:
        killer.done.set()
        killer.join()
    assert len(killer.killed) == 1, "the worker was not killed mid-case"
    killed_case, killed_pid, _ = killer.killed[0]
    first = next(n for n in names if n != killed_case)
    by_case = {r["case"]: r for r in rows}
    assert [r["status"] for r in rows] == ["completed", "completed"]
    assert by_case[killed_case]["attempts"] == 2 and by_case[first]["attempts"] == 1
    starts = _starts(out, killed_case)
    assert starts[0] == killed_pid and starts[1] != killed_pid     # a new worker process
    # the finished case ran once: its folder is the one its row was made from
    assert len(_starts(out, first)) == 1
    assert (out / first / "summary.json").stat().st_mtime_ns == reported[first][1]
    # the killed case ran again from the start: an uninterrupted run's files and counters
    overrides = (*LONG, f"beams.rod.elements={by_case[killed_case]['beams.rod.elements']}")
    reference = _reference(tmp_path, overrides)
    _same_run(out / killed_case, reference)
    summary = json.loads((reference / "summary.json").read_text())
    assert by_case[killed_case]["steps"] == summary["steps"]
    assert by_case[killed_case]["newton_iterations"] == summary["newton_iterations"]


def test_a_case_that_kills_its_worker_every_time_fails_after_bounded_attempts(tmp_path):
    """Dask's ``allowed-failures`` (here 1: two attempts) bounds the attempts; the case's row
    says so and names it, the other case completes, the sweep returns."""
    import dask

    out = tmp_path / "sweep"
    killer = WorkerKiller(out, lambda: "elements=6", kills=5)
    killer.start()
    try:
        with dask.config.set({"distributed.scheduler.allowed-failures": 1}):
            rows = fm.sweep(CANTILEVER, {"beams.rod.elements": [4, 6]}, overrides=LONG, out=out,
                            workers=2)
    finally:
        killer.done.set()
        killer.join()
    by_case = {r["case"]: r for r in rows}
    assert len(killer.killed) == 2
    status = by_case["elements=6"]["status"]
    assert status.startswith("failed: worker died 2 times running case elements=6 ("), status
    assert "\n" not in status and f"{ATTEMPTS_DIR}/elements=6" in status
    assert by_case["elements=6"]["attempts"] == 2
    assert by_case["elements=6"]["final_time"] is None
    assert _starts(out, "elements=6") == [pid for _, pid, _ in killer.killed]
    assert by_case["elements=4"]["status"] == "completed"
    assert by_case["elements=4"]["attempts"] == 1 and len(_starts(out, "elements=4")) == 1
    # the last attempt's folder is an output folder that the next run of the sweep takes
    assert output_summary(out / "elements=6")["status"] == "running"


@pytest.mark.parametrize("how", ["ctrl-c", "sigkill"])
def test_an_interrupted_sweep_runs_again_only_its_unfinished_cases(tmp_path, how):
    """``flexmbs sweep`` in a real process, interrupted while one case is done and the other
    runs: Ctrl-C at a terminal (SIGINT to the process group: the sweep and its workers) or
    SIGKILL of the sweep's process alone (its workers then exit)."""
    out = tmp_path / "sweep"
    # the long case runs for about 7 s on a quiet core: it cannot end in the moments the
    # interrupted sweep takes to stop it, even on a loaded machine (3 s could, 2026-12-07)
    zipped = {"beams.rod.elements": [4, 6], "simulation.t_end": [0.3, 10.0]}
    short, long_ = "elements=4,t_end=0.3", "elements=6,t_end=10.0"
    argv = [sys.executable, "-m", "flexmbs", "sweep", CANTILEVER, "--zip",
            "beams.rod.elements=4,6", "--zip", "simulation.t_end=0.3,10.0", "--set", LONG[1],
            "--out", str(out), "--workers", "2"]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH",
                                                                                    "")])}
    proc = subprocess.Popen(argv, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, start_new_session=True)
    try:
        deadline = time.monotonic() + 240
        while not (_status(out / short) == "completed" and _status(out / long_) == "running"
                   and _rows(out / long_) > 20):
            assert proc.poll() is None, proc.communicate()
            assert time.monotonic() < deadline
            time.sleep(0.02)
        if how == "ctrl-c":
            os.killpg(proc.pid, signal.SIGINT)
        else:
            proc.kill()
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    if how == "ctrl-c":       # one line; the workers, which got the SIGINT too, say nothing
        assert proc.returncode == 130
        lines = [line for line in err.strip().splitlines() if not line.startswith("[")]
        assert lines == ["flexmbs: error: sweep interrupted (finished cases are in the table; "
                         "rerun to continue)"], err
    else:
        assert proc.returncode == -signal.SIGKILL
    # Ctrl-C stops the running case at once (Dask's 4 s of grace would let this one complete)
    assert _status(out / short) == "completed" and _status(out / long_) == "running"
    stamp = (out / short / "summary.json").stat().st_mtime_ns
    reused, ran = [], []
    rows = fm.sweep(CANTILEVER, zip=zipped, overrides=LONG[1:], out=out, workers=1,
                    report=lambda case, row, d, t, was_reused:
                    (reused if was_reused else ran).append(case.name))
    assert (reused, ran) == ([short], [long_])
    assert (out / short / "summary.json").stat().st_mtime_ns == stamp       # not run again
    assert [(r["case"], r["status"], r["attempts"]) for r in rows] == [
        (short, "completed", 0), (long_, "completed", 1)]
    _same_run(out / long_, _reference(tmp_path, (*LONG[1:], "beams.rod.elements=6",
                                                 "simulation.t_end=10.0")))

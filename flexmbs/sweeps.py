"""Parameter studies on Dask: ``flexmbs sweep`` and :func:`sweep` (docs/sweeps.md).

A sweep runs one scenario with overrides (the key paths of ``--set``): the Cartesian product of
the ``grid`` lists times the ``zip`` lists taken side by side. Each case is an ordinary run
(:func:`flexmbs.runs.run_scenario`) into its own folder below the sweep folder, named by its
parameters (``radius=0.0021,stiffness=1000000000.0``); ``sweep.csv`` tabulates every case
(parameters, status, wall time, steps, Newton iterations, rejected steps, largest contact force,
energy change, attempts, final/min/max of every probe column) and is rewritten as cases finish,
so an interrupted sweep leaves a valid table. A rerun skips cases whose folder holds a completed
run of the same scenario file and overrides (resumable); failed cases are run again.

A case whose worker process dies (killed, out of memory, a segfault) is run again from the
start by Dask on another or the restarted worker, up to the scheduler's
``distributed.scheduler.allowed-failures`` more times (Dask's default 3), then recorded as
``failed: worker died N times ...``; each start of a case appends a line to
``.attempts/<case>`` in the sweep folder, which the ``attempts`` column counts.

The cases run on a Dask ``LocalCluster`` of single-threaded worker processes (BLAS, OpenMP and
numba threads pinned to 1) or on an existing scheduler (``scheduler=`` address or scheduler
file), which must see the same file system. numba's kernels are compiled once (the first case
runs alone when the on-disk cache is empty) and loaded once per worker process.
"""

from __future__ import annotations

import builtins
import contextlib
import csv
import itertools
import json
import math
import os
import re
import socket
import sys
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .errors import FlexmbsError, ScenarioError

__all__ = ["ATTEMPTS_DIR", "SWEEP_FILE", "TABLE_FILE", "Case", "make_cases", "parse_values",
           "read_case", "sweep"]

TABLE_FILE = "sweep.csv"
SWEEP_FILE = "sweep.json"
#: the sweep folder's record of case starts: ``.attempts/<case>``, one line per start
ATTEMPTS_DIR = ".attempts"

#: environment of every worker process: one thread each (cases run side by side)
WORKER_ENV = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
              "NUMBA_NUM_THREADS": "1", "VECLIB_MAXIMUM_THREADS": "1"}

#: the table's fixed columns after ``case`` and the parameters
RESULT_COLUMNS = ("status", "final_time", "wall_time", "steps", "newton_iterations",
                  "rejected_steps", "max_contact_force", "energy_change", "attempts")


# ================================================================================ cases
@dataclass(frozen=True)
class Case:
    """One run of a sweep: its folder name, parameter values and ``--set`` overrides."""

    index: int
    name: str
    params: tuple[tuple[str, Any], ...]
    overrides: tuple[str, ...]


def toml_text(value: Any) -> str:
    """A Python value as a TOML value (the right-hand side of ``--set KEY=...``)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ScenarioError(f"sweep value {value!r}: not a finite number")
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, Mapping):
        return "{" + ", ".join(f"{json.dumps(str(k))} = {toml_text(v)}" for k, v in value.items()) + "}"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(toml_text(v) for v in value) + "]"
    if hasattr(value, "item"):            # numpy scalar
        return toml_text(value.item())
    raise ScenarioError(f"sweep value {value!r}: expected a number, boolean, string, array or table")


def parse_values(spec: str, flag: str = "--grid") -> tuple[str, list[Any]]:
    """``KEY=V1,V2,...`` (the CLI's ``--grid``/``--zip``) -> (KEY, values). Values are TOML
    values (a bare word is a string); commas inside ``[...]``, ``{...}`` or quotes do not split."""
    from .io.overrides import parse_value

    key, eq, text = spec.partition("=")
    key = key.strip()
    if not eq or not key:
        raise ScenarioError(f"{flag} {spec}: expected KEY=V1,V2,..., e.g. "
                            "joints.sleeve.hole.radius=2.0e-3,2.5e-3")
    items: list[str] = []
    depth, quote, current = 0, "", ""
    for ch in text:
        if quote:
            quote = "" if ch == quote else quote
        elif ch in "\"'":
            quote = ch
        elif ch in "[{":
            depth += 1
        elif ch in "]}":
            depth -= 1
        elif ch == "," and depth == 0:
            items.append(current)
            current = ""
            continue
        current += ch
    items.append(current)
    if any(not i.strip() for i in items):
        raise ScenarioError(f"{flag} {spec}: an empty value; separate values by single commas")
    return key, [parse_value(i) for i in items]


def _slug(value: Any) -> str:
    text = value if isinstance(value, str) else toml_text(value)
    slug = re.sub(r"[^A-Za-z0-9._+-]+", "_", text).strip("_")
    return slug or "_"


def _short_keys(keys: Sequence[str]) -> dict[str, str]:
    """The shortest dotted suffix of each key that tells the keys apart (folder names)."""
    parts = {k: k.split(".") for k in keys}
    out: dict[str, str] = {}
    for k in keys:
        for n in range(1, len(parts[k]) + 1):
            short = ".".join(parts[k][-n:])
            if all(".".join(parts[o][-n:]) != short for o in keys if o != k):
                break
        out[k] = short
    return out


def make_cases(grid: Mapping[str, Sequence[Any]] | None = None,
               zip: Mapping[str, Sequence[Any]] | None = None,
               overrides: Sequence[str] = ()) -> list[Case]:
    """The cases of a sweep: the Cartesian product of the ``grid`` lists, times the ``zip``
    lists taken side by side (all of one length). Keys are ``--set`` key paths; ``overrides``
    (``KEY=VALUE``) apply to every case before its parameters."""
    grid = dict(grid or {})
    zipped = dict(zip or {})
    for what, table in (("grid", grid), ("zip", zipped)):
        for key, values in table.items():
            if isinstance(values, (str, bytes)) or not isinstance(values, Sequence) or not values:
                raise ScenarioError(f"sweep {what} {key}: expected a non-empty list of values")
    both = set(grid) & set(zipped)
    if both:
        raise ScenarioError(f"sweep: key {sorted(both)[0]} is in both grid and zip; give it once")
    if not grid and not zipped:
        raise ScenarioError("sweep: no parameters; give --grid KEY=V1,V2,... (or --zip)")
    lengths = {len(v) for v in zipped.values()}
    if len(lengths) > 1:
        raise ScenarioError("sweep --zip: the zipped lists differ in length "
                            f"({', '.join(f'{k}: {len(v)}' for k, v in zipped.items())})")
    keys = list(grid) + list(zipped)
    short = _short_keys(keys)
    zip_rows = list(builtins.zip(*zipped.values(), strict=True)) if zipped else [()]
    cases: list[Case] = []
    seen: set[str] = set()
    for combo in itertools.product(*grid.values()):
        for zrow in zip_rows:
            values = list(combo) + list(zrow)
            params = tuple(builtins.zip(keys, values, strict=True))
            case_overrides = (*overrides, *(f"{k}={toml_text(v)}" for k, v in params))
            name = ",".join(f"{short[k]}={_slug(v)}" for k, v in params)
            if len(name) > 120:
                name = f"case{len(cases):04d}"
            if name in seen:
                name = f"{name}~{len(cases)}"
            seen.add(name)
            cases.append(Case(len(cases), name, params, case_overrides))
    return cases


# ================================================================================ one case
def read_case(folder: str | os.PathLike[str]) -> dict[str, Any]:
    """The results of one run folder as a table row: ``summary.json`` (status, time, steps,
    Newton iterations, rejected steps, wall time, energy change), the largest ``normal_force``
    of ``contacts.csv`` and final/min/max of every ``probes.csv`` column."""
    path = Path(folder)
    row: dict[str, Any] = {}
    try:
        summary = json.loads((path / "summary.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return row
    row["status"] = summary.get("status")
    row["final_time"] = summary.get("final_time")
    row["wall_time"] = summary.get("wall_time")
    for key in ("steps", "newton_iterations", "rejected_steps"):
        row[key] = summary.get(key)
    row["energy_change"] = (summary.get("energy_balance") or {}).get("change")
    if summary.get("hole_sections"):          # the model has clearance joints
        row["max_contact_force"] = _max_contact_force(path / "contacts.csv")
    row.update(_probe_extremes(path / "probes.csv"))
    return row


def _max_contact_force(path: Path) -> float | None:
    try:
        with open(path, newline="", encoding="utf-8") as f:
            reader = csv.reader(f)
            header = next(reader, None)
            if not header or "normal_force" not in header:
                return None
            col = header.index("normal_force")
            best = 0.0
            for rec in reader:
                with contextlib.suppress(ValueError, IndexError):
                    best = max(best, float(rec[col]))
            return best
    except OSError:
        return None


def _probe_extremes(path: Path) -> dict[str, float]:
    try:
        with open(path, newline="", encoding="utf-8") as f:
            reader = csv.reader(f)
            header = next(reader, None)
            if not header:
                return {}
            names = header[1:]
            lo = [math.inf] * len(names)
            hi = [-math.inf] * len(names)
            last: list[float] = []
            for rec in reader:
                try:
                    vals = [float(x) for x in rec[1:]]
                except ValueError:
                    continue                  # a line cut by a crash
                if len(vals) != len(names):
                    continue
                last = vals
                lo = [min(a, b) for a, b in builtins.zip(lo, vals, strict=True)]
                hi = [max(a, b) for a, b in builtins.zip(hi, vals, strict=True)]
    except OSError:
        return {}
    if not last:
        return {}
    out: dict[str, float] = {}
    for n, f_, a, b in builtins.zip(names, last, lo, hi, strict=True):
        out[f"{n}_final"], out[f"{n}_min"], out[f"{n}_max"] = f_, a, b
    return out


def run_case(scenario: str, overrides: Sequence[str], folder: str,
             attempts_log: str | None = None) -> dict[str, Any]:
    """Run one case into ``folder`` (on a Dask worker), from the start: the folder of an
    attempt whose worker died is cleared (:func:`flexmbs.io.folder.claim`). Never raises for a
    failing case: the row's ``status`` is ``failed: <one-line reason>``. The start is first
    appended to ``attempts_log`` (:func:`record_start`)."""
    from .io.scenario import load_scenario
    from .runs import run_scenario

    if attempts_log is not None:
        record_start(attempts_log)
    t0 = time.perf_counter()
    status = "completed"
    try:
        sc = load_scenario(scenario, overrides)
        status = run_scenario(sc, folder, overrides=overrides).status
    except (FlexmbsError, OSError) as exc:
        status = f"failed: {_one_line(exc)}"
    except Exception as exc:
        status = f"failed: internal error {type(exc).__name__}: {_one_line(exc)}"
    row = read_case(folder)
    if status != "completed" or not row:
        row["status"] = status
    row.setdefault("wall_time", time.perf_counter() - t0)
    return row


def record_start(log: str | os.PathLike[str]) -> None:
    """Append ``<UTC time> host=<host> pid=<process id>`` to ``log``: this process starts the
    case (a sweep counts the lines; the pid is the worker's, for its logs). A log that cannot be
    written does not stop the case."""
    line = (f"{time.strftime('%Y-%m-%dT%H:%M:%SZ', time.gmtime())} host={socket.gethostname()} "
            f"pid={os.getpid()}\n")
    with contextlib.suppress(OSError):
        Path(log).parent.mkdir(parents=True, exist_ok=True)
        with open(log, "a", encoding="utf-8") as f:
            f.write(line)


def count_starts(log: str | os.PathLike[str]) -> int:
    """How many times the case of ``log`` was started (:func:`record_start`)."""
    try:
        return Path(log).read_text(encoding="utf-8").count("\n")
    except OSError:
        return 0


def _prepare_kernel(scenario: str, overrides: Sequence[str]) -> None:
    """Compile the kernel of a case's model in this process (or load it from numba's cache),
    so that the local workers all load it instead of compiling it side by side (each kind of
    model has its own, see :func:`flexmbs.kernel.prepare`). A case that cannot be built is left
    to its worker, which records why."""
    from . import kernel
    from .assembly import Assembly
    from .io.scenario import load_scenario

    def announce(estimate: float | None, kind: str, same_kind: bool) -> None:
        about = "about a minute" if estimate is None else f"about {estimate:.0f} s"
        print(f"flexmbs sweep: compiling the numba kernels for this model (once, {about})",
              file=sys.stderr, flush=True)

    previous, kernel.announce_compile = kernel.announce_compile, announce
    try:
        Assembly(load_scenario(scenario, overrides).model)
    except Exception:
        pass
    finally:
        kernel.announce_compile = previous


def _one_line(exc: BaseException) -> str:
    if isinstance(exc, OSError) and exc.filename:
        return f"cannot write or read {exc.filename}: {exc.strerror or exc}"
    return " ".join(str(exc).split()) or type(exc).__name__


# ================================================================================ the sweep
def _finished(folder: Path, case: Case, digest: str) -> dict[str, Any] | None:
    """The row of a case whose folder holds a completed run of this scenario and overrides."""
    try:
        summary = json.loads((folder / "summary.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    meta = summary.get("metadata") or {}
    if (summary.get("status") != "completed" or meta.get("scenario_sha1") != digest
            or list(meta.get("overrides") or []) != list(case.overrides)):
        return None
    return read_case(folder)


def _write_table(path: Path, cases: Sequence[Case], rows: Mapping[int, dict[str, Any]]) -> None:
    keys = [k for k, _ in cases[0].params] if cases else []
    extra: list[str] = []
    for c in cases:
        for k in rows.get(c.index, {}):
            if k not in RESULT_COLUMNS and k not in extra:
                extra.append(k)
    header = ["case", *keys, *RESULT_COLUMNS, *extra]
    tmp = path.with_name(f".{path.name}.tmp")
    with open(tmp, "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(header)
        for c in cases:
            row = rows.get(c.index, {"status": "pending"})
            values = [c.name, *(v if not isinstance(v, (list, dict)) else toml_text(v)
                                for _, v in c.params)]
            values += ["" if row.get(h) is None else row.get(h) for h in (*RESULT_COLUMNS, *extra)]
            w.writerow(values)
    os.replace(tmp, path)


def read_table(folder: str | os.PathLike[str]) -> list[dict[str, Any]]:
    """``sweep.csv`` of a sweep folder as records (numbers as int or float, empty cells as
    None), each with ``folder``: the path of the case's output folder."""
    path = Path(folder) / TABLE_FILE
    with open(path, newline="", encoding="utf-8") as f:
        rows = [{k: _number(v) for k, v in rec.items()} for rec in csv.DictReader(f)]
    for row in rows:
        row["folder"] = str(Path(folder) / str(row["case"]))
    return rows


def _number(text: str | None) -> Any:
    if text is None or text == "":
        return None
    with contextlib.suppress(ValueError):
        return int(text)
    with contextlib.suppress(ValueError):
        return float(text)
    return text


@contextlib.contextmanager
def _sweep_folder(path: Path, scenario_name: str) -> Iterator[Path]:
    """Lock the sweep folder; refuse one that holds something else than this scenario's sweep."""
    from .io.folder import LOCK_NAME, lock_folder

    if path.exists() and not path.is_dir():
        raise ScenarioError(f"--out {path}: exists and is not a folder")
    if path.is_dir():
        entries = [p for p in path.iterdir() if p.name != LOCK_NAME]
        try:
            previous = json.loads((path / SWEEP_FILE).read_text(encoding="utf-8"))["scenario"]
        except (OSError, ValueError, KeyError, TypeError):
            previous = None
        if entries and previous is None:
            raise ScenarioError(f"--out {path}: the folder is not empty and holds no flexmbs "
                                "sweep; choose a new or empty folder")
        if previous is not None and previous != scenario_name:
            raise ScenarioError(f"--out {path}: holds a sweep of scenario '{previous}'; choose "
                                "another folder")
    path.mkdir(parents=True, exist_ok=True)
    with lock_folder(path):
        yield path


def _local_client(n_workers: int) -> tuple[Any, Callable[[bool], None]]:
    """A ``LocalCluster`` of ``n_workers`` single-threaded processes, its client, and its
    ``close(abandon)``: ``abandon`` (Ctrl-C) stops the running cases within 0.5 s instead of
    Dask's 4 s of grace to a running task (their folders say ``running``; a rerun of the sweep
    runs them again from the start)."""
    import asyncio
    import logging

    import dask
    from dask.distributed import Client, LocalCluster

    # one case per worker at a time: none waits queued behind a running case (a worker that
    # dies then takes only the case it runs, and idle workers take the queued cases); workers
    # ignore Ctrl-C (flexmbs._sweep_worker); the scheduler's log of a case given up is
    # silenced: the case's row and line say it
    preload = [*dask.config.get("distributed.worker.preload", []), "flexmbs._sweep_worker"]
    with dask.config.set({"distributed.worker.daemon": False,
                          "distributed.scheduler.worker-saturation": 1.0,
                          "distributed.worker.preload": preload}):
        cluster = LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                               dashboard_address=":0", silence_logs=logging.CRITICAL,
                               env=dict(WORKER_ENV))
    client = Client(cluster)

    async def stop_workers() -> None:
        await asyncio.gather(*(nanny.close(timeout=0.5) for nanny in list(cluster.workers.values())))

    def close(abandon: bool) -> None:
        if abandon:
            with contextlib.suppress(Exception):
                cluster.sync(stop_workers)
        client.close()
        cluster.close()
    return client, close


def _remote_client(scheduler: str) -> tuple[Any, Callable[[], None]]:
    from dask.distributed import Client

    try:
        if scheduler.endswith(".json") or Path(scheduler).is_file():
            client = Client(scheduler_file=scheduler, timeout="20s")
        else:
            client = Client(scheduler, timeout="20s")
    except (OSError, TimeoutError) as exc:
        raise ScenarioError(f"--scheduler {scheduler}: cannot connect ({_one_line(exc)}); start "
                            "a scheduler (dask scheduler) or give its address") from None
    return client, client.close


def sweep(scenario: str | os.PathLike[str], grid: Mapping[str, Sequence[Any]] | None = None, *,
          zip: Mapping[str, Sequence[Any]] | None = None,
          overrides: Sequence[str] = (), out: str | os.PathLike[str] | None = None, client: Any = None,
          scheduler: str | None = None, workers: int | None = None,
          report: Callable[[Case, dict[str, Any], int, int, bool], None] | None = None,
          ) -> list[dict[str, Any]]:
    """Run the cases of ``grid`` x ``zip`` (``--set`` key paths to lists of values) of the
    scenario file on Dask and return ``sweep.csv`` as records (module docstring).

    ``overrides`` (``KEY=VALUE``, the CLI's ``--set``) apply to every case.
    ``client``: a ``dask.distributed.Client`` to use; else ``scheduler`` (an address such as
    ``tcp://host:8786`` or a scheduler file) or a new ``LocalCluster`` of ``workers`` processes
    (default: one per core, at most one per case). ``out``: the sweep folder (default
    ``out/<scenario name>_sweep``). ``report(case, row, done, total, reused)`` is called for
    each case as it ends (``reused``: completed by an earlier run of the sweep, not run again;
    those and the cases that cannot be built are reported first). Cases whose parameters cannot
    be built are recorded as failed without running; if no case can be built the first reason
    is raised (:class:`ScenarioError`). A case whose worker dies is run again from the start
    (module docstring); the row's ``attempts`` says how many times this call started it.

    Parameters
    ----------
    scenario : str or os.PathLike
        The scenario file.
    grid : mapping of str to sequence, optional
        Key paths to lists of values; the cases are their Cartesian product.
    zip : mapping of str to sequence, optional
        Key paths to lists of equal length, taken side by side.
    overrides : sequence of str, optional
        ``KEY=VALUE`` assignments applied to every case.
    out : str or os.PathLike, optional
        The sweep folder.
    client : dask.distributed.Client, optional
        The client to use.
    scheduler : str, optional
        A scheduler's address or scheduler file.
    workers : int, optional
        Processes of a new local cluster.
    report : callable, optional
        ``report(case, row, done, total, reused)`` as each case ends.

    Returns
    -------
    list of dict
        The rows of ``sweep.csv``, one per case.
    """
    from .io.scenario import load_scenario
    from .runs import scenario_digest

    path = Path(scenario).resolve()
    cases = make_cases(grid, zip, overrides)
    if workers is not None and workers < 1:
        raise ScenarioError(f"--workers {workers}: expected a number >= 1")
    rows: dict[int, dict[str, Any]] = {}
    loaded: list[Case] = []
    name = None
    for case in cases:                      # every case is checked before anything runs
        try:
            sc = load_scenario(path, case.overrides)
        except FlexmbsError as exc:
            rows[case.index] = {"status": f"failed: {_one_line(exc)}", "attempts": 0}
            continue
        name = sc.name
        loaded.append(case)
    if not loaded:
        raise ScenarioError(rows[cases[0].index]["status"].removeprefix("failed: "))
    assert name is not None
    folder = Path(out) if out is not None else Path("out") / f"{name}_sweep"
    digest = scenario_digest(path)
    with _sweep_folder(folder, name):
        (folder / SWEEP_FILE).write_text(json.dumps({
            "scenario": name, "scenario_file": str(path), "scenario_sha1": digest,
            "parameters": [k for k, _ in cases[0].params], "overrides": list(overrides),
            "grid": {k: list(v) for k, v in (grid or {}).items()},
            "zip": {k: list(v) for k, v in (zip or {}).items()},
            "cases": [{"case": c.name, "overrides": list(c.overrides)} for c in cases],
        }, indent=2, default=str) + "\n", encoding="utf-8")
        todo = []
        reused: set[int] = set()
        for case in loaded:
            row = _finished(folder / case.name, case, digest)
            if row is not None:
                rows[case.index] = {**row, "attempts": 0}
                reused.add(case.index)
            else:
                todo.append(case)
        table = folder / TABLE_FILE
        _write_table(table, cases, rows)
        if report is not None:
            for done, case in enumerate((c for c in cases if c.index in rows), start=1):
                report(case, rows[case.index], done, len(cases), case.index in reused)
        if todo:
            _run_cases(todo, path, folder, cases, rows, table, client=client,
                       scheduler=scheduler, workers=workers, report=report)
        return read_table(folder)


def _run_cases(todo: Sequence[Case], path: Path, folder: Path, cases: Sequence[Case],
               rows: dict[int, dict[str, Any]], table: Path, *, client: Any, scheduler: str | None,
               workers: int | None, report: Callable[..., None] | None) -> None:
    from .kernel import kernels_cached

    close: Callable[[bool], None] = lambda abandon: None  # noqa: E731
    local = client is None and not scheduler
    if client is None:
        if scheduler:
            client, close_remote = _remote_client(scheduler)
            close = lambda abandon: close_remote()  # noqa: E731 - tasks running there finish
        else:
            n = workers or os.cpu_count() or 1
            client, close = _local_client(max(1, min(n, len(todo))))
    interrupted = False
    attempts = (folder / ATTEMPTS_DIR).resolve()
    attempts.mkdir(exist_ok=True)
    for case in todo:                       # the attempts column counts this sweep's starts
        (attempts / case.name).unlink(missing_ok=True)
    try:
        def submit(case: Case) -> Any:
            return client.submit(run_case, str(path), list(case.overrides),
                                 str((folder / case.name).resolve()), str(attempts / case.name),
                                 pure=False, key=f"flexmbs-{case.name}-{time.time_ns()}")

        pending = list(todo)
        futures: dict[Any, Case] = {}
        if pending and local:               # compile once here, then every worker loads it
            _prepare_kernel(str(path), pending[0].overrides)
        elif not kernels_cached():          # remote workers: the first case compiles alone
            print("flexmbs sweep: compiling the numba kernels in the first case (once, about a "
                  "minute)", file=sys.stderr, flush=True)
            first = pending.pop(0)
            futures[submit(first)] = first
            _collect(futures, rows, cases, table, attempts, report)
        for case in pending:
            futures[submit(case)] = case
        _collect(futures, rows, cases, table, attempts, report)
    except KeyboardInterrupt:
        interrupted = True
        with contextlib.suppress(Exception):
            client.cancel(list(futures))
        raise
    finally:
        _write_table(table, cases, rows)
        close(interrupted)


def _collect(futures: dict[Any, Case], rows: dict[int, dict[str, Any]], cases: Sequence[Case],
             table: Path, attempts: Path, report: Callable[..., None] | None) -> None:
    """Record each case's row as its future ends; the ``attempts`` column counts its starts.
    Dask has already run a case again whose worker died, up to ``allowed-failures`` times.
    Each future is released once read (and dropped from ``futures``): Dask would otherwise
    compute a finished case again when the worker holding its row dies, rewriting its folder
    behind its row."""
    from dask.distributed import KilledWorker, as_completed

    for fut in as_completed(list(futures)):
        case = futures.pop(fut)
        try:
            row = dict(fut.result())
        except KilledWorker as exc:
            row = {"status": f"failed: worker died {exc.allowed_failures + 1} times running case "
                             f"{case.name} (killed, out of memory or a crash such as a segfault; "
                             f"its starts are in {ATTEMPTS_DIR}/{case.name})"}
        except Exception as exc:
            row = {"status": f"failed: worker error {type(exc).__name__}: {_one_line(exc)}"}
        finally:
            fut.release()
        row["attempts"] = count_starts(attempts / case.name)
        rows[case.index] = row
        _write_table(table, cases, rows)
        if report is not None:
            report(case, row, len(rows), len(cases), False)

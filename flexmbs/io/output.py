"""The output folder of a run (docs/design.md, "Output folder"), written as the run goes::

    with OutputWriter(out_dir, "run", asm, probes=[...]) as out:
        final, stats = integrate(asm, opts, ..., observer=out.write)
        out.finish("completed", stats=stats)

Files (every one valid after every output written, so a run that stops early leaves readable
results; the writer's thread writes them, following the run by at most :data:`QUEUE_SIZE`
outputs and :data:`MAX_LAG` seconds of wall time, so that a run killed outright (SIGKILL, a
power cut) loses at most the outputs of its last second; whatever else ends the run, everything
queued is written before the summary):

- ``<name>.pvd`` + ``vtu/<name>_NNNNNN.vtm`` with its pieces ``vtu/<name>_NNNNNN_<block>.vtp``
  (``output_frames="multiblock"``, the default), or ``vtu/<name>_NNNNNN.vtu`` (``"merged"``)
  (:mod:`flexmbs.io.vtu`, frames by :mod:`flexmbs.io.frames`);
- ``probes.csv``: ``t,<probe columns>``, one row per output, flushed after each row;
- ``contacts.csv``: ``t,joint,section,point,gap,normal_force,qx,qy,qz,px,py,pz,a,b``, one row
  per active contact (header written even if there is none; missing keys are empty fields);
- ``checkpoint.npz``: the state of an output time (:mod:`flexmbs.io.checkpoint`): of the last
  output when the run ends (any status), and during the run at most every
  ``checkpoint_interval`` seconds of wall time (a checkpoint costs a few milliseconds; the
  outputs after it are dropped by ``--resume``);
- ``summary.json``: written at start, before any other file (``status: "running"``), and at
  the end (``completed``, ``failed: <reason>`` or ``interrupted``); ``format:
  "flexmbs-output"`` and ``format_version`` mark the folder as flexmbs output
  (:func:`flexmbs.io.folder.output_summary`): files with these names in a folder without the
  mark are the user's and are not written over.

``OutputWriter(..., resume_at=t)`` continues the folder of a stopped run (``flexmbs run
--resume``): rows and frames at times ``<= t`` are kept, later ones removed, new ones appended;
the frames continue in the form the series has (``.vtm`` or ``.vtu``), whatever
``output_frames`` says, so that one ``.pvd`` never mixes the two.
"""

from __future__ import annotations

import collections
import contextlib
import csv
import dataclasses
import errno
import json
import math
import os
import queue
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from types import TracebackType
from typing import Any, NamedTuple, TextIO

import numpy as np

from .._version import __version__
from ..errors import FlexmbsError, ModelError
from .checkpoint import save_checkpoint
from .folder import OUTPUT_FORMAT, OUTPUT_FORMAT_VERSION, refuse_user_files
from .frames import BLOCK_NAMES, OUTPUT_FRAMES, FrameBuilder
from .probes import Probe, probe_columns
from .vtu import VTUSeries

CONTACT_COLUMNS = ("t", "joint", "section", "point", "gap", "normal_force", "qx", "qy", "qz",
                   "px", "py", "pz", "a", "b")
#: ``sections.csv`` (clearance joints only; an addition to docs/design.md's folder): the state of every
#: hole section for the section view: origin and axes of the section plane (global), the beam's
#: ellipse in section coordinates (centre cy, cz; major axis ey_a, ez_a; semi-axes a, b), the
#: bore's bounding radius R and the number of contact points
SECTION_COLUMNS = ("t", "joint", "section", "ox", "oy", "oz", "eyx", "eyy", "eyz", "ezx", "ezy",
                   "ezz", "cy", "cz", "ey_a", "ez_a", "a", "b", "R", "contacts")


def _fmt(x: Any) -> str:
    """CSV field: floats with the shortest exact representation, others as text."""
    if type(x) is float:     # the common case first (a numpy float is a subclass: below)
        return repr(x)
    if x is None:
        return ""
    if isinstance(x, (float, np.floating)):
        return repr(float(x))
    if isinstance(x, (int, np.integer)):
        return str(int(x))
    return str(x)


def _jsonable(o: Any) -> Any:
    if isinstance(o, dict):
        return {str(k): _jsonable(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [_jsonable(v) for v in o]
    if isinstance(o, np.ndarray):
        return _jsonable(o.tolist())
    if isinstance(o, np.generic):
        o = o.item()
    if isinstance(o, float) and not math.isfinite(o):
        return str(o)           # JSON has no NaN/inf
    if isinstance(o, (str, int, float, bool)) or o is None:
        return o
    if isinstance(o, os.PathLike):
        return os.fspath(o)
    return str(o)


def failure_reason(exc: BaseException) -> str:
    """One line describing ``exc`` for ``status: "failed: <reason>"``."""
    if isinstance(exc, OSError) and exc.strerror:
        where = f" {exc.filename}" if exc.filename else ""
        return f"cannot write or read{where}: {exc.strerror}"
    msg = str(exc).strip().splitlines()
    text = msg[0] if msg else ""
    if not isinstance(exc, FlexmbsError) or not text:
        text = f"{type(exc).__name__}: {text}" if text else type(exc).__name__
    return text


class _Output(NamedTuple):
    """One output time as the writer's thread gets it: copies of what it reads of the run
    (nothing of the live model; the springs' turns in ``springs``)."""

    state: Any                     # a copy of the state (State.copy())
    contacts: list[dict]
    sections: list[dict]
    probe_values: np.ndarray
    springs: Any                   # FrameBuilder.springs_now() or None
    checkpoint_extra: dict | None  # None: no checkpoint
    written: tuple[int, float, dict]   # the summary's outputs, final time and energy after it


class _Flush(NamedTuple):
    """A marker in the writer's queue: set ``done`` when the thread takes it."""

    done: threading.Event


def _rows(t: str, records: Sequence[dict], columns: Sequence[str]) -> list[list[str]]:
    """CSV rows of ``records`` (dicts by column; missing keys are empty fields) at time ``t``."""
    keys = columns[1:]
    return [[t, *[_fmt(c.get(k)) for k in keys]] for c in records]


#: outputs queued for the writer's thread at most (the solver waits when the disk is slower)
QUEUE_SIZE = 16
#: seconds of wall time an output may wait for the disk: an output is not handed over while
#: one handed over longer ago than this is not written (docs/design.md, "Output folder")
MAX_LAG = 1.0

#: trailing blanks of summary.json: room for the final status on a full disk
SUMMARY_RESERVE = 4096


@contextlib.contextmanager
def _naming(path: Path) -> Iterator[None]:
    """Give an OSError without a file name (a write that fails, e.g. on a full disk) the path
    being written, so the one-line error and the summary say which file."""
    try:
        yield
    except OSError as exc:
        if exc.filename is None:
            raise OSError(exc.errno, exc.strerror or str(exc), str(path)) from exc
        raise


#: the longest ending flexmbs gives a file of a run named ``<name>``: the temporary file of a
#: multiblock piece, ``.<name>_NNNNNNN_hole_sections_K_K.vtp.tmp`` (frame numbers have 6 digits,
#: 7 at the budget's limit of 1e6 frames; K up to 4 and 5 digits: joints, sections per hole)
NAME_ENDING_MAX = len("._0000000_hole_sections_9999_99999.vtp.tmp")


def name_max(directory: str | os.PathLike) -> int:
    """The longest file name (bytes) the file system of ``directory`` (or of its nearest
    existing parent) allows: ``pathconf(PC_NAME_MAX)``, 255 where it cannot be asked."""
    d = Path(directory).absolute()
    while not d.exists() and d != d.parent:
        d = d.parent
    try:
        return int(os.pathconf(d, "PC_NAME_MAX"))
    except (OSError, ValueError, AttributeError):   # no pathconf (Windows), unknown name
        return 255


#: files an output folder may hold: a run that would write more is refused before its folder is
#: touched (file systems and ParaView's series readers slow down by the 10⁵; issue 57)
MAX_FILES = 100_000


def check_output(directory: str | os.PathLike, name: str, asm: Any, *,
                 probes: Sequence[Probe] = (), write_vtu: bool = True,
                 output_frames: str = "multiblock", samples_per_element: int = 8,
                 frames: float | None = None, prefix: str = "") -> FrameBuilder | None:
    """Everything the output of a run can be refused for, checked before its folder is touched
    (issue "nothing lost, part two"): the form of the frames, the run name against the file
    system's limit on file names (with :data:`NAME_ENDING_MAX`), the probes against the model,
    the frames' body shapes (mesh files are read here) and, given the run's number of
    ``frames``, the files they make against :data:`MAX_FILES` (``prefix`` before the keys the
    message names, ``"simulation."`` for scenarios). Returns the frame builder (None without
    VTU frames). Raises :class:`ModelError` (one line)."""
    if output_frames not in OUTPUT_FRAMES:
        raise ModelError(f"output_frames must be one of {', '.join(OUTPUT_FRAMES)} "
                         f"(got {output_frames!r})")
    limit = name_max(directory)
    size = len(str(name).encode("utf-8", "surrogateescape"))
    if size + NAME_ENDING_MAX > limit:
        short = str(name) if len(str(name)) <= 24 else f"{str(name)[:20]}..."
        raise ModelError(
            f"name: the run name '{short}' ({size} bytes) is too long for the file names of its "
            f"output (e.g. <name>_000000_hole_sections_0_0.vtp): the file system of {directory} "
            f"allows {limit} bytes per name; give a name of at most {limit - NAME_ENDING_MAX} "
            "bytes")
    for p in probes:
        p.check(asm)
    if not write_vtu:
        return None
    builder = FrameBuilder(asm, samples_per_element=samples_per_element)
    if frames is not None:
        per = 1 if output_frames == "merged" else 1 + len(builder.block_tree())
        if frames * per > MAX_FILES:
            fix = (f"a larger {prefix}output_interval" if output_frames == "merged" else
                   f"a larger {prefix}output_interval or {prefix}output_frames = \"merged\" "
                   "(one file per frame)")
            raise ModelError(f"{prefix}output_interval: {frames:.6g} output frames of {per} "
                             f"file{'s' if per > 1 else ''} each would put {frames * per:.3g} "
                             f"files in {directory}, more than {MAX_FILES:.0e}; give {fix}")
    return builder


class OutputWriter:
    """Writes the output folder of one run (context manager; see the module docstring).

    ``asm`` is the :class:`~flexmbs.assembly.Assembly`; ``metadata`` (scenario path, solver
    settings, ...) is stored under ``summary.json["metadata"]``. ``write_vtu=False`` skips the
    VTU series, ``checkpoints=False`` the checkpoint (written at most every
    ``checkpoint_interval`` s of wall time, and for the last output at the end). Each
    :meth:`write` is one output time. ``output_frames``: ``"multiblock"`` (a ``.vtm`` of named
    blocks per frame) or ``"merged"`` (one ``.vtu`` grid per frame), see
    :mod:`flexmbs.io.frames`.
    ``resume_at=t`` appends to the folder of an earlier run whose outputs up to ``t`` are kept
    (the CSV headers must match; the initial energy is taken from its ``summary.json``).

    ``background=True`` (the default): :meth:`write` takes copies of what the output reads of
    the run (state, rows, probe values, the springs' turns) and a thread of the writer builds
    the frame, formats the rows and writes the files, in order, while the caller goes on (the
    compiled integrator releases the GIL). At most :data:`QUEUE_SIZE` outputs wait; an error
    of the thread is raised by the next :meth:`write`, :meth:`flush` or :meth:`finish`, with
    its message; :meth:`finish` (also through ``with``, whatever ends the run) writes every
    output queued before, then the checkpoint and the summary. ``background=False`` writes
    each output in :meth:`write` itself (the same files).
    """

    def __init__(self, directory: str | os.PathLike, name: str, asm: Any, *,
                 probes: Sequence[Probe] = (), write_vtu: bool = True, checkpoints: bool = True,
                 metadata: dict | None = None, samples_per_element: int = 8,
                 vtu_encoding: str = "binary", resume_at: float | None = None,
                 checkpoint_interval: float = 10.0, output_frames: str = "multiblock",
                 background: bool = True, max_lag: float = MAX_LAG,
                 expected_outputs: float | None = None) -> None:
        # before the folder is touched: what can refuse the output
        frames = check_output(directory, name, asm, probes=probes, write_vtu=write_vtu,
                              output_frames=output_frames, frames=expected_outputs,
                              samples_per_element=samples_per_element)
        self.output_frames = output_frames
        self.directory = Path(directory)
        self.name = str(name)
        self.asm = asm
        self.probes = list(probes)
        self.metadata = dict(metadata or {})
        self.checkpoints = bool(checkpoints)
        self.checkpoint_interval = float(checkpoint_interval)
        self._pending_checkpoint: tuple[Any, dict] | None = None
        self._last_checkpoint = -math.inf
        self.probe_columns = probe_columns(self.probes)
        if resume_at is None:       # a user's own probes.csv, summary.json, ... are not written over
            refuse_user_files(self.directory, label="")
        self.directory.mkdir(parents=True, exist_ok=True)
        self._t_start = time.perf_counter()
        self.n_outputs = 0
        self.final_time: float | None = None
        self.initial_energy: dict[str, float] | None = None
        self.final_energy: dict[str, float] | None = None
        self.finished = False
        self.status = "running"
        #: what the summary reports when the run ends through ``with`` (``__exit__``): a
        #: callable returning ``(stats, wall_time)`` (the run's counters so far), set by the run
        self.totals: Callable[[], tuple[Any, float | None]] | None = None
        #: the run's checks for the summary (:meth:`flexmbs.checks.RunChecks.report`)
        self.checks: Callable[[], dict] | None = None
        self._files: list[Any] = []
        self.background = bool(background)
        self._queue: queue.Queue[_Output | _Flush | None] | None = None
        self.max_lag = float(max_lag)
        #: wall times at which the outputs not written yet were handed over, oldest first
        self._pending: collections.deque[float] = collections.deque()
        self._stored = threading.Condition()
        self._thread: threading.Thread | None = None
        self._failure: BaseException | None = None   # the writer thread's error
        self._failure_raised = False
        self._written: tuple[int, float, dict] | None = None   # the last output on disk
        self.series: VTUSeries | None = None
        self.frames: FrameBuilder | None = None
        self.resume_at = None if resume_at is None else float(resume_at)
        self.previous_summary: dict | None = None
        if self.resume_at is not None and self.summary_path.is_file():
            with open(self.summary_path, encoding="utf-8") as f:
                self.previous_summary = json.load(f)
            initial = (self.previous_summary.get("energy_balance") or {}).get("initial")
            if isinstance(initial, dict):
                self.initial_energy = initial
        try:
            if self.resume_at is None:    # the mark before any other file: a run killed while
                self._write_summary()     # it starts leaves a folder that says it is flexmbs's
            if frames is not None:
                self.frames = frames
                # without the writer's thread the series stores the files in one of its own
                self.series = VTUSeries(self.pvd_path, encoding=vtu_encoding,
                                        resume_at=self.resume_at, background=not self.background)
                if self.series.entries:     # a resumed series keeps its form
                    last = self.series.entries[-1][1]
                    self.output_frames = "multiblock" if last.endswith(".vtm") else "merged"
            self._probe_file, kept = self._open_csv("probes.csv", ["t", *self.probe_columns])
            self._contact_file, _ = self._open_csv("contacts.csv", list(CONTACT_COLUMNS))
            self._section_file: TextIO | None = None   # opened at the first section row
            self.n_outputs = kept
            self._write_summary()
        except BaseException:
            self._close_files()
            raise
        if self.background:
            self._queue = queue.Queue(maxsize=QUEUE_SIZE)
            self._thread = threading.Thread(target=self._run, name="flexmbs-output", daemon=True)
            self._thread.start()

    # ------------------------------------------------------------------ paths
    @property
    def pvd_path(self) -> Path:
        return self.directory / f"{self.name}.pvd"

    @property
    def checkpoint_path(self) -> Path:
        return self.directory / "checkpoint.npz"

    @property
    def summary_path(self) -> Path:
        return self.directory / "summary.json"

    def _open_csv(self, fname: str, header: list[str]) -> tuple[Any, int]:
        """Open ``fname`` for writing rows; returns (file, number of data rows kept)."""
        path = self.directory / fname
        rows: list[list[str]] = []
        if self.resume_at is not None and path.is_file():
            with open(path, newline="", encoding="utf-8") as f:
                old = list(csv.reader(f))
            if not old or old[0] != header:
                raise ModelError(f"cannot resume into {self.directory}: the columns of {fname} "
                                 f"differ from this run's ({','.join(header)})")
            rows = [r for r in old[1:] if r and float(r[0]) <= self.resume_at]
        tmp = path.with_name(f".{fname}.tmp")
        with open(tmp, "w", newline="", encoding="utf-8") as f:
            w = csv.writer(f)
            w.writerow(header)
            w.writerows(rows)
        os.replace(tmp, path)
        f = open(path, "a", newline="", encoding="utf-8")  # noqa: SIM115
        self._files.append(f)
        return f, len(rows)

    def _write_checkpoint(self) -> None:
        """The checkpoint of the last output, if not written yet."""
        if self._pending_checkpoint is not None:
            if self.series is not None:   # the frames of the checkpointed outputs are on disk
                self.series.flush()
            state, extra = self._pending_checkpoint
            save_checkpoint(self.checkpoint_path, state, extra=extra)
            self._pending_checkpoint = None

    def _close_files(self) -> None:
        for f in self._files:
            f.close()
        self._files = []
        if self.series is not None:
            self.series.close()

    # ------------------------------------------------------------------ per output
    def write(self, state: Any, *, contacts: Sequence[dict] | None = None,
              checkpoint_extra: dict | None = None, sections: Sequence[dict] | None = None,
              probe_values: np.ndarray | None = None, energy: dict | None = None) -> None:
        """Record one output time: VTU frame, probe row, contact rows, checkpoint.
        ``probe_values`` (the probes' columns) and ``energy`` (:meth:`Assembly.energies`) may
        be passed when the caller has them already. What the output reads of the live model is
        evaluated here; with ``background`` the files are written by the writer's thread."""
        if self.finished:
            raise ValueError("OutputWriter.write after finish()")
        self._raise_failure()
        t = float(state.t)
        if probe_values is None:
            probe_values = np.concatenate(
                [np.asarray(p.evaluate(self.asm, state), float).reshape(-1) for p in self.probes]
                + [np.zeros(0)])
        if energy is None:
            energy = self.asm.energies(state.q, state.v)
        extra = None
        if self.checkpoints:
            extra = {"output_step": self.n_outputs, **(checkpoint_extra or {})}
        if self.initial_energy is None:
            self.initial_energy = energy
        self.n_outputs += 1
        job = _Output(state.copy(), list(contacts or []), list(sections or []),
                      np.array(probe_values, dtype=float).reshape(-1),
                      self.frames.springs_now() if self.frames is not None else None, extra,
                      (self.n_outputs, t, energy))
        if self._queue is None:
            self._store(job)
            self._written = job.written
            return
        self._wait_for_lag()
        with self._stored:
            self._pending.append(time.perf_counter())
        while True:     # the queue is bounded; a thread that stopped on an error takes no more
            self._raise_failure()
            try:
                self._queue.put(job, timeout=0.1)
                return
            except queue.Full:
                if self._thread is None or not self._thread.is_alive():
                    self._raise_failure()
                    raise RuntimeError("flexmbs output thread ended") from None

    def _wait_for_lag(self) -> None:
        """Wait while an output handed over more than :attr:`max_lag` seconds ago is not on
        disk (the bound on what a SIGKILL loses)."""
        with self._stored:
            while self._pending and time.perf_counter() - self._pending[0] > self.max_lag:
                self._raise_failure()
                if self._thread is None or not self._thread.is_alive():
                    return
                self._stored.wait(0.05)

    def _store(self, job: _Output) -> None:
        """Write the files of one output (the writer's thread, or :meth:`write` without it)."""
        state = job.state
        t = float(state.t)
        if self.series is not None and self.frames is not None:
            frame = (self.frames.multiblock(state, contacts=job.contacts, springs=job.springs)
                     if self.output_frames == "multiblock"
                     else self.frames(state, contacts=job.contacts, springs=job.springs))
            with _naming(self.series.next_path(frame)):
                self.series.write(t, frame)
        ft = _fmt(t)
        with _naming(self.directory / "probes.csv"):
            csv.writer(self._probe_file).writerow([ft, *map(repr, job.probe_values.tolist())])
            self._probe_file.flush()
        if job.contacts:
            with _naming(self.directory / "contacts.csv"):
                csv.writer(self._contact_file).writerows(_rows(ft, job.contacts, CONTACT_COLUMNS))
                self._contact_file.flush()
        if job.sections:
            with _naming(self.directory / "sections.csv"):
                if self._section_file is None:
                    self._section_file, _ = self._open_csv("sections.csv", list(SECTION_COLUMNS))
                csv.writer(self._section_file).writerows(_rows(ft, job.sections, SECTION_COLUMNS))
                self._section_file.flush()
        if job.checkpoint_extra is not None:
            self._pending_checkpoint = (state, job.checkpoint_extra)
            now = time.perf_counter()
            if now - self._last_checkpoint >= self.checkpoint_interval:
                self._write_checkpoint()
                self._last_checkpoint = now

    def _run(self) -> None:
        """The writer's thread: the queued outputs in order until ``None``; after an error the
        rest is taken and dropped (the series stops at the last output written whole)."""
        assert self._queue is not None
        while True:
            job = self._queue.get()
            if job is None:
                return
            if isinstance(job, _Flush):
                job.done.set()
                continue
            if self._failure is None:
                try:
                    self._store(job)
                    self._written = job.written
                except BaseException as exc:
                    self._failure = exc
            with self._stored:
                if self._pending:
                    self._pending.popleft()
                self._stored.notify_all()

    def _raise_failure(self, again: bool = True) -> None:
        """Raise the writer thread's error in the caller's thread (the output is broken: at
        every call; ``again=False``: only if the caller has not had it, as ``finish`` does)."""
        if self._failure is not None and (again or not self._failure_raised):
            self._failure_raised = True
            raise self._failure

    def _stop_thread(self) -> None:
        """Let the writer's thread write every queued output and end. An interrupt (Ctrl-C)
        while waiting does not abandon the queued outputs: it is raised after them."""
        if self._thread is None or self._queue is None:
            return
        thread, q = self._thread, self._queue
        interrupted: KeyboardInterrupt | None = None
        while True:
            try:
                if thread.is_alive():
                    q.put(None)
                break
            except KeyboardInterrupt as exc:
                interrupted = exc
        while thread.is_alive():
            try:
                thread.join()
            except KeyboardInterrupt as exc:  # noqa: PERF203 - waited for again
                interrupted = exc
        self._thread = None
        if interrupted is not None:
            raise interrupted

    def flush(self) -> None:
        """Wait until every output given to :meth:`write` is written (files flushed; the
        checkpoint still follows its interval); raises the writer thread's error, if any."""
        if self._queue is not None and self._thread is not None:
            done = threading.Event()
            # the thread is idle once it takes this marker: every earlier output is written
            self._queue.put(_Flush(done))
            while not done.wait(0.1):
                if not self._thread.is_alive():
                    break
        self._raise_failure()

    # ------------------------------------------------------------------ summary
    def _summary(self, *, stats: Any = None, wall_time: float | None = None,
                 energy_balance: dict | None = None) -> dict:
        from ..driver import kind_of  # the records declare the output hooks

        if dataclasses.is_dataclass(stats) and not isinstance(stats, type):
            st = dataclasses.asdict(stats)
        else:
            st = dict(stats or {})
        energy: dict[str, Any] = {}
        if self.initial_energy is not None and self.final_energy is not None:
            energy = {"initial_total": self.initial_energy["total"],
                      "final_total": self.final_energy["total"],
                      "change": self.final_energy["total"] - self.initial_energy["total"],
                      "initial": self.initial_energy, "final": self.final_energy}
        energy.update(energy_balance or {})
        model = self.asm.model
        return _jsonable({
            "format": OUTPUT_FORMAT,
            "format_version": OUTPUT_FORMAT_VERSION,
            "scenario": self.name,
            "flexmbs_version": __version__,
            "status": self.status,
            "final_time": self.final_time,
            "outputs": self.n_outputs,
            "steps": st.get("steps"),
            "newton_iterations": st.get("newton_iterations"),
            "rejected_steps": st.get("rejected_steps"),
            "wall_time": time.perf_counter() - self._t_start if wall_time is None else wall_time,
            "dofs": {"coordinates": int(self.asm.n_coords), "multipliers": int(self.asm.n_mult)},
            "energy_balance": energy,
            "checks": self.checks() if self.checks is not None else None,
            "stats": st,
            "files": {"pvd": self.pvd_path.name if self.series else None,
                      "frames": self.output_frames if self.series else None,
                      "probes": "probes.csv", "contacts": "contacts.csv",
                      "checkpoint": self.checkpoint_path.name if self.checkpoints else None},
            "vtu_blocks": {"block_id": {str(k): v for k, v in BLOCK_NAMES.items()},
                           "beam_id": [b.name for b in model.beams],
                           "beam_radius": [None if b.radius is None else float(b.radius)
                                           for b in model.beams],
                           "body_id": [b.name for b in model.bodies],
                           "spring_id": [s.name for s in model.springs],
                           "joint_id": [str(getattr(j, "name", i))
                                        for i, j in enumerate(model.interactions)]},
            "vtm_blocks": (self.frames.block_tree() if self.frames is not None
                           and self.output_frames == "multiblock" else None),
            "hole_sections": {j.name: k.hole_record(j) for j, k in
                              ((j, kind_of(j)) for j in model.interactions)
                              if k is not None and k.hole_record is not None},
            "metadata": self.metadata,
        })

    def _write_summary(self, **kwargs: Any) -> None:
        """Write ``summary.json`` atomically (temporary file, rename). The file carries
        ``SUMMARY_RESERVE`` bytes of trailing blanks (valid JSON), so that on a full disk the
        final status can still be written in place, into blocks the file already holds."""
        text = json.dumps(self._summary(**kwargs), indent=2) + "\n"
        data = (text + " " * SUMMARY_RESERVE).encode("utf-8")
        tmp = self.summary_path.with_name(f".{self.summary_path.name}.tmp")
        with _naming(self.summary_path):
            try:
                with open(tmp, "wb") as f:
                    f.write(data)
                os.replace(tmp, self.summary_path)
            except OSError as exc:
                with contextlib.suppress(OSError):
                    tmp.unlink()
                if exc.errno != errno.ENOSPC or not self._overwrite_summary(text.encode()):
                    raise

    def _overwrite_summary(self, data: bytes) -> bool:
        """On a full disk: rewrite the existing summary in place if ``data`` fits in it."""
        try:
            size = self.summary_path.stat().st_size
            if len(data) > size:
                return False
            with open(self.summary_path, "r+b") as f:
                f.write(data + b" " * (size - len(data)))
            return True
        except OSError:
            return False

    def finish(self, status: str = "completed", *, stats: Any = None, wall_time: float | None = None,
               energy_balance: dict | None = None) -> None:
        """Close the files and write the final ``summary.json`` (``status``: ``"completed"``,
        ``"failed: <reason>"`` or ``"interrupted"``); ``stats`` is an ``IntegrationStats``."""
        if self.finished:
            return
        self.status = " ".join(str(status).split())   # one line
        self.finished = True
        interrupted: KeyboardInterrupt | None = None
        try:
            self._stop_thread()        # every output queued before is written
        except KeyboardInterrupt as exc:    # raised once the folder is complete
            interrupted = exc
        if self._written is not None:      # the summary counts the outputs on disk
            self.n_outputs, self.final_time, self.final_energy = self._written
        try:
            try:
                self._write_checkpoint()    # of the last output written whole
            finally:
                self._close_files()
        except OSError as exc:    # e.g. the disk is full: the summary still says so if it can
            self.status = f"failed: {failure_reason(exc)}"
            self._remove_temporaries()
            with contextlib.suppress(OSError):
                self._write_summary(stats=stats, wall_time=wall_time,
                                    energy_balance=energy_balance)
            self._remove_temporaries()
            raise
        if self._failure is not None:     # the writer thread's error is the run's end
            self.status = f"failed: {failure_reason(self._failure)}"
            self._remove_temporaries()
        try:
            self._write_summary(stats=stats, wall_time=wall_time, energy_balance=energy_balance)
        except OSError:
            self._remove_temporaries()
            raise
        self._raise_failure(again=False)      # unless the caller had it already
        if interrupted is not None:
            raise interrupted

    def _remove_temporaries(self) -> None:
        for p in self.directory.glob(".*.tmp"):
            with contextlib.suppress(OSError):
                p.unlink()

    def __enter__(self) -> OutputWriter:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        if self.finished:
            return
        stats, wall = self.totals() if self.totals is not None else (None, None)
        if exc is None:
            status = "completed"
        elif isinstance(exc, KeyboardInterrupt):
            status = "interrupted" + (f": {exc}" if str(exc) else "")
        else:
            status = f"failed: {failure_reason(exc)}"
        self.finish(status, stats=stats, wall_time=wall)

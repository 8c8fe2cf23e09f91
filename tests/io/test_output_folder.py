"""Who may write an output folder (issue "nothing lost", items 3, 4, 6): one run at a time,
no silent take-over of another scenario's results, ``--out ""`` refused, a terminated run
finishes like Ctrl-C. Real runs through the CLI; the concurrency and signal cases in real
subprocesses."""

from __future__ import annotations

import contextlib
import errno
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from flexmbs.cli import main
from flexmbs.io.folder import LOCK_NAME

ROOT = Path(__file__).resolve().parents[2]
CANTILEVER = str(ROOT / "examples" / "cantilever.toml")
PENDULUM = str(ROOT / "examples" / "flexible_pendulum.toml")


def _run(scenario: str, out: Path, *extra: str) -> int:
    return main(["run", scenario, "--t-end", "0.002", "--quiet", "--out", str(out), *extra])


def test_rerun_of_the_same_scenario_replaces_its_own_files(tmp_path):
    out = tmp_path / "o"
    assert _run(CANTILEVER, out) == 0
    stale = out / "vtu" / "stale_999.vtu"
    stale.write_text("old")
    assert _run(CANTILEVER, out) == 0
    assert not stale.exists()                    # the earlier run's frames are gone
    assert json.loads((out / "summary.json").read_text())["status"] == "completed"
    assert not (out / LOCK_NAME).exists()        # the lock is released


def test_another_scenarios_folder_is_refused_without_overwrite(tmp_path, capsys):
    out = tmp_path / "o"
    assert _run(CANTILEVER, out) == 0
    before = (out / "summary.json").read_text()
    assert _run(PENDULUM, out) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "holds the output of scenario 'cantilever'" in err[0]
    assert "--overwrite" in err[0]
    assert (out / "summary.json").read_text() == before          # nothing written
    assert _run(PENDULUM, out, "--overwrite") == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["scenario"] == "flexible_pendulum"
    assert not list((out / "vtu").glob("cantilever_*.vtu"))      # the old frames are cleared
    assert not (out / "cantilever.pvd").exists()


def test_foreign_folders_and_empty_out_are_refused(tmp_path, capsys, monkeypatch):
    mine = tmp_path / "notes"
    mine.mkdir()
    (mine / "thesis.tex").write_text("keep me")
    for extra in ((), ("--overwrite",)):
        assert _run(CANTILEVER, mine, *extra) == 2
        assert "holds no flexmbs output" in capsys.readouterr().err
    assert (mine / "thesis.tex").read_text() == "keep me"
    assert sorted(p.name for p in mine.iterdir()) == ["thesis.tex"]
    monkeypatch.chdir(tmp_path)
    assert main(["run", CANTILEVER, "--t-end", "0.002", "--quiet", "--out", ""]) == 2
    assert "--out: empty path" in capsys.readouterr().err


def _spawn(out: Path, t_end: str) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.Popen([sys.executable, "-m", "flexmbs", "run", CANTILEVER, "--t-end", t_end,
                             "--quiet", "--out", str(out)], cwd=ROOT, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _wait_for(path: Path, seconds: float = 60.0) -> None:
    end = time.time() + seconds
    while not path.exists():
        assert time.time() < end, f"{path} did not appear"
        time.sleep(0.05)


def test_a_second_run_into_a_busy_folder_is_refused(tmp_path):
    out = tmp_path / "o"
    first = _spawn(out, "200")
    try:
        _wait_for(out / "probes.csv")
        second = _spawn(out, "0.002")
        _, err = second.communicate(timeout=120)
        assert second.returncode == 2
        assert "another flexmbs run (process" in err and len(err.strip().splitlines()) == 1
    finally:
        first.send_signal(signal.SIGINT)
        first.communicate(timeout=120)


class _Killed(BaseException):
    """The process dies here: nothing after it runs (no ``except Exception`` catches it)."""


@pytest.mark.parametrize("where", ["while the writer opens its files",
                                   "while the rerun clears the folder"])
def test_a_run_killed_as_it_starts_leaves_a_folder_the_next_run_takes(tmp_path, monkeypatch,
                                                                       where):
    """Issue 57, item 4: a Dask worker killed mid-case; its rerun must not find a folder
    with a run's files and no summary (the mark), which would be refused as the user's."""
    from flexmbs.io import folder as folder_module
    from flexmbs.io.output import OutputWriter

    out = tmp_path / "o"
    if where == "while the rerun clears the folder":
        assert _run(CANTILEVER, out) == 0

        def die(path, *args, **kwargs):      # the first folder removed: vtu/
            raise _Killed
        monkeypatch.setattr(folder_module.shutil, "rmtree", die)
    else:
        real = OutputWriter._open_csv

        def die(self, fname, header):      # probes.csv is written, contacts.csv not yet
            if fname == "contacts.csv":
                raise _Killed
            return real(self, fname, header)
        monkeypatch.setattr(OutputWriter, "_open_csv", die)
    with pytest.raises(_Killed):
        _run(CANTILEVER, out)
    monkeypatch.undo()
    assert (out / "vtu").is_dir()                   # a half-written (or half-cleared) folder
    assert json.loads((out / "summary.json").read_text())["scenario"] == "cantilever"
    assert _run(CANTILEVER, out) == 0
    assert json.loads((out / "summary.json").read_text())["status"] == "completed"


@pytest.mark.skipif(not Path("/proc/self/stat").is_file(), reason="needs Linux /proc")
def test_a_lock_held_by_a_zombie_process_is_taken_over(tmp_path):
    """A killed worker not yet reaped by its parent (a container's init that does not reap)
    answers ``kill(pid, 0)`` but runs nothing: its lock is stale."""
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    stat = Path(f"/proc/{child.pid}/stat")
    try:
        end = time.time() + 30
        while stat.read_text().rpartition(")")[2].split()[0] != "Z":   # exited, not reaped
            assert time.time() < end
            time.sleep(0.02)
        out = tmp_path / "o"
        out.mkdir()
        (out / LOCK_NAME).write_text(f"{child.pid}\n")
        assert _run(CANTILEVER, out) == 0
    finally:
        child.wait()


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP])
def test_terminate_and_hangup_finish_like_ctrl_c(tmp_path, sig):
    out = tmp_path / "o"
    proc = _spawn(out, "200")
    _wait_for(out / "probes.csv")
    time.sleep(0.5)
    proc.send_signal(sig)
    proc.communicate(timeout=120)
    assert proc.returncode == 130
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == f"interrupted: {sig.name}"
    assert (out / "checkpoint.npz").is_file()
    assert summary["final_time"] > 0
    assert not (out / LOCK_NAME).exists()


def test_a_failure_before_the_first_output_leaves_the_summary(tmp_path, capsys, monkeypatch):
    """Item 8: the initial accelerations fail (made to, here: a model whose mass matrix is
    singular is refused before anything is written); the run fails before its first output
    but the folder holds summary.json saying why."""
    import flexmbs.simulation as simulation
    from flexmbs.errors import ConvergenceError

    def singular(*args, **kwargs):
        raise ConvergenceError("cannot compute consistent initial accelerations: singular "
                                  "mass/constraint matrix")

    monkeypatch.setattr(simulation, "consistent_initial_state", singular)
    out = tmp_path / "o"
    code = main(["run", CANTILEVER, "--t-end", "0.002", "--quiet", "--out", str(out)])
    assert code == 3
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "singular mass" in err[0]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"].startswith("failed: cannot compute consistent initial accelerations")
    assert not (out / LOCK_NAME).exists()


def test_a_full_disk_names_the_file_sets_the_status_and_leaves_no_temporaries(tmp_path, capsys,
                                                                              monkeypatch):
    """Item 7: writing a frame fails with ENOSPC (simulated: the write raises as a full disk
    does, with no file name). The error line names the file, summary.json says failed with the
    reason, no temporary file is left, the exit status is the failure code (3)."""
    import errno

    from flexmbs.io import vtu

    real = vtu.write_vtp        # each piece of a multiblock frame
    calls = []

    def full_disk(path, mesh, **kw):
        calls.append(path)
        if len(calls) > 2:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real(path, mesh, **kw)

    monkeypatch.setattr(vtu, "write_vtp", full_disk)
    out = tmp_path / "o"
    code = main(["run", CANTILEVER, "--t-end", "0.05", "--quiet", "--out", str(out)])
    assert code == 3
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "cantilever_000002.vtm" in err[0] and "No space left" in err[0]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"].startswith("failed: cannot write or read")
    assert "cantilever_000002.vtm" in summary["status"]
    assert not list(out.glob(".*.tmp")) and not list(out.glob("*.tmp"))
    assert not (out / LOCK_NAME).exists()


@pytest.fixture
def tiny_filesystem(tmp_path):
    """A 400 kB tmpfs (needs the right to mount: root on Linux; skipped elsewhere)."""
    import subprocess
    import sys

    where = tmp_path / "tiny"
    where.mkdir()
    if not sys.platform.startswith("linux"):
        pytest.skip("tmpfs mounts are Linux only")
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=400k", "tmpfs", str(where)],
                          capture_output=True, text=True)
    if done.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here ({done.stderr.strip() or done.returncode})")
    try:
        yield where
    finally:
        subprocess.run(["umount", str(where)], check=False)


def test_a_real_full_disk_mid_run(tiny_filesystem, capsys):
    """Item 7 on a real file system: the run fits the disk when it starts (the up-front
    estimate passes), then another file takes the space; the frame that no longer fits fails
    with the file's name, summary.json says so, no temporaries remain, exit 3; the frames
    written before stay readable."""
    out = tiny_filesystem / "o"
    filler = tiny_filesystem / "filler"

    def fill(state, stats):      # progress callback: after 0.02 s, the disk fills up
        if state.t > 0.02 and not filler.exists():
            # once the writer's thread has the first three frames on disk (the fourth begun;
            # the thread follows the solver by up to output.QUEUE_SIZE outputs)
            deadline = time.monotonic() + 30
            while len(list((out / "vtu").glob("*.vtm"))) < 4 and time.monotonic() < deadline:
                time.sleep(0.01)
            with open(filler, "wb") as f, contextlib.suppress(OSError):
                while True:
                    f.write(b"x" * 4096)
                    f.flush()

    from flexmbs.io.scenario import load_scenario
    from flexmbs.runs import run_scenario

    sc = load_scenario(CANTILEVER, ["simulation.t_end=0.08"])
    with pytest.raises(OSError) as info:
        run_scenario(sc, out, progress=lambda start, t_end, name: fill)
    assert info.value.errno == errno.ENOSPC
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"].startswith("failed: cannot write or read")
    assert not list(out.glob(".*.tmp")) and not list(out.glob("*.tmp"))
    import postprocess

    run = postprocess.read_run(out)
    assert len(run.frames) >= 3 and all(p.stat().st_size > 0 for _, p in run.frames)


EXAMPLE1 = ROOT / "examples" / "curved_beam_sleeve.toml"


@pytest.mark.parametrize("radius", [2.3e-3, 2.5e-3, 3.0e-3])
def test_rest_on_the_bore_follows_the_clearance(radius):
    """Item 9: Example 1 places its sleeve with pose = { on_beam, s, rest = "bore" }; whatever
    the hole radius, the bore starts touching the rail (deepest section point within 1 nm of
    the wall), never inside it (the issue's 1275 N at t = 0 with radius 2.1 mm and a fixed
    offset)."""
    import numpy as np

    from flexmbs.assembly import Assembly
    from flexmbs.io.scenario import load_scenario

    sc = load_scenario(EXAMPLE1, [f"joints.sleeve.hole.radius={radius}"])
    asm = Assembly(sc.model)
    (joint,) = sc.model.interactions
    q = asm.q_ref
    rows = joint.output(asm, q, np.zeros_like(q), np.zeros(asm.n_mult), 0.0)
    assert all(-1e-9 < r["gap"] <= 0.0 for r in rows)
    assert sum(abs(r["normal_force"]) for r in rows) < 1e-2          # N (k = 1e6 N/m)


def test_rest_on_the_bore_refuses_what_cannot_fit_and_needs_a_direction(capsys):
    """Below a clearance of the rail's sagitta over the sleeve (0.2 mm) the straight sleeve
    cannot sit on the curved rail; without gravity a rest direction must be given: one line
    each, naming the key."""
    code = main(["run", str(EXAMPLE1), "--t-end", "0.001", "--quiet", "--out", "/nonexistent/x",
                 "--set", "joints.sleeve.hole.radius=2.1e-3"])
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "rigid_bodies[sleeve].pose.rest" in err[0]
    assert "cuts the beam wherever it is placed" in err[0]
    code = main(["info", str(EXAMPLE1), "--set", "simulation.gravity=[0.0, 0.0, 0.0]"])
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "rest_direction" in err[0]
    assert main(["info", str(EXAMPLE1), "--set", "simulation.gravity=[0.0, 0.0, 0.0]",
                 "--set", "rigid_bodies.sleeve.pose.rest_direction=[0.0, 0.0, -1.0]"]) == 0


def test_a_start_inside_the_bore_wall_is_warned_in_one_line(tmp_path, capsys):
    """Item 9: the issue's case, Example 1 with the sleeve at a fixed offset chosen for 0.5 mm
    of clearance and the hole made 2.3 mm: the rail starts 0.2 mm inside the wall; one warning
    line names the joint, the depth and the fix."""
    text = EXAMPLE1.read_text().replace(
        'pose = { on_beam = "rail", s = 0.2617993877991494, rest = "bore" }',
        'pose = { on_beam = "rail", s = 0.2617993877991494, offset = [-1.5e-4, 0.0, -2.598076e-4] }')
    text = text.replace('mesh = "../meshes/', f'mesh = "{ROOT / "meshes"}/')
    scen = tmp_path / "fixed_offset.toml"
    scen.write_text(text)
    assert main(["info", str(scen), "--set", "joints.sleeve.hole.radius=2.3e-3"]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("flexmbs: warning: joint 'sleeve'")
    assert "into the bore wall" in err[0] and 'rest = "bore"' in err[0]
    assert main(["info", str(EXAMPLE1)]) == 0                      # placed at rest: no warning
    assert "warning" not in capsys.readouterr().err

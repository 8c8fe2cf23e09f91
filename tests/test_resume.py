"""``flexmbs run --resume``: a run stopped at t1 and continued to t2 equals an uninterrupted run
to t2, its folder holds each output once, and a folder of another run is refused.

Both with full Newton (``simulation.newton.modified=false``) and with modified Newton (the
default: the checkpoint carries the factorisation, its age and the step size) the resumed run
is bit-identical (files compared byte for byte).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from flexmbs.cli import EXIT_BAD_INPUT, EXIT_OK, main
from flexmbs.io.checkpoint import load_checkpoint
from flexmbs.io.vtu import frame_files, read_pvd

ROOT = Path(__file__).resolve().parents[1]
CANTILEVER = str(ROOT / "examples" / "cantilever.toml")
PENDULUM = str(ROOT / "examples" / "flexible_pendulum.toml")
FULL_NEWTON = ["--set", "simulation.newton.modified=false"]
T1, T2 = "0.03", "0.06"


def run(*args: str) -> int:
    return main(["run", *args, "--quiet"])


def assert_same_frame(a: Path, b: Path) -> None:
    """Frame ``b`` equals ``a`` byte for byte, and so do the pieces of a ``.vtm``."""
    assert b.read_bytes() == a.read_bytes(), b.name
    if a.suffix == ".vtm":
        pieces = frame_files(a)
        assert pieces
        for p in pieces:
            assert (b.parent / p.name).read_bytes() == p.read_bytes(), p.name


def stopped_and_resumed(tmp_path: Path, extra: list[str]) -> tuple[Path, Path]:
    """(uninterrupted run to T2, run to T1 resumed to T2)."""
    full, part = tmp_path / "full", tmp_path / "part"
    assert run(CANTILEVER, "--t-end", T2, "--out", str(full), *extra) == EXIT_OK
    assert run(CANTILEVER, "--t-end", T1, "--out", str(part), *extra) == EXIT_OK
    assert run(CANTILEVER, "--t-end", T2, "--resume", str(part), *extra) == EXIT_OK
    return full, part


def test_resume_bit_identical_with_full_newton(tmp_path):
    full, part = stopped_and_resumed(tmp_path, FULL_NEWTON)
    for f in ("probes.csv", "contacts.csv"):
        assert (part / f).read_bytes() == (full / f).read_bytes()
    assert read_pvd(part / "cantilever.pvd") == read_pvd(full / "cantilever.pvd")
    for _, f in read_pvd(full / "cantilever.pvd"):
        assert_same_frame(full / f, part / f)
    sa, _ = load_checkpoint(full / "checkpoint.npz")
    sb, _ = load_checkpoint(part / "checkpoint.npz")
    assert sa.t == sb.t == 0.06
    for k in ("q", "v", "qdd", "a", "lam"):
        np.testing.assert_array_equal(getattr(sb, k), getattr(sa, k))
    a, b = (json.loads((d / "summary.json").read_text()) for d in (full, part))
    assert b["status"] == "completed" and b["metadata"]["resumed_from"] == 0.03
    for k in ("steps", "newton_iterations", "outputs", "final_time"):
        assert b[k] == a[k], k
    assert b["energy_balance"]["final_total"] == a["energy_balance"]["final_total"]


def test_resume_default_modified_newton_is_bit_identical(tmp_path):
    """Item 2 of issue 18: with modified Newton (the default) the checkpoint carries the
    integrator's own state (the factorisation, its age, the step size), so the resumed run
    equals the uninterrupted one bit for bit: every file and the final state."""
    full, part = stopped_and_resumed(tmp_path, [])
    for f in ("probes.csv", "contacts.csv"):
        assert (part / f).read_bytes() == (full / f).read_bytes()
    for _, f in read_pvd(full / "cantilever.pvd"):
        assert_same_frame(full / f, part / f)
    sa, _ = load_checkpoint(full / "checkpoint.npz")
    sb, _ = load_checkpoint(part / "checkpoint.npz")
    for k in ("q", "v", "qdd", "a", "lam"):
        np.testing.assert_array_equal(getattr(sb, k), getattr(sa, k))


def test_resume_of_the_clearance_example_is_bit_identical(tmp_path):
    """The issue's case: Example 1 (clearance joint, modified Newton, contact tracking) stopped
    at 0.05 s and resumed to 0.1 s equals the uninterrupted run in every file."""
    ex1 = str(ROOT / "examples" / "curved_beam_sleeve.toml")
    full, part = tmp_path / "full", tmp_path / "part"
    assert run(ex1, "--t-end", "0.1", "--out", str(full)) == EXIT_OK
    assert run(ex1, "--t-end", "0.05", "--out", str(part)) == EXIT_OK
    assert run(ex1, "--t-end", "0.1", "--resume", str(part)) == EXIT_OK
    for f in ("probes.csv", "contacts.csv", "sections.csv"):
        assert (part / f).read_bytes() == (full / f).read_bytes(), f
    frames = read_pvd(full / "curved_beam_sleeve.pvd")
    assert read_pvd(part / "curved_beam_sleeve.pvd") == frames
    for _, f in frames:
        assert_same_frame(full / f, part / f)


def test_resume_drops_outputs_after_checkpoint(tmp_path):
    """Rows or frames after the checkpoint (a crash between writes) are not duplicated."""
    part = tmp_path / "part"
    assert run(CANTILEVER, "--t-end", T1, "--out", str(part), *FULL_NEWTON) == EXIT_OK
    with (part / "probes.csv").open("a") as f:
        f.write("0.035,1,2,3,4\n")
    assert run(CANTILEVER, "--t-end", T2, "--resume", str(part), *FULL_NEWTON) == EXIT_OK
    t = np.loadtxt(part / "probes.csv", delimiter=",", skiprows=1)[:, 0]
    np.testing.assert_allclose(t, np.arange(7) * 0.01, rtol=0, atol=1e-15)


@pytest.mark.parametrize("what", ["missing", "other_scenario", "other_size", "not_later",
                                  "no_folder"])
def test_resume_refuses(tmp_path, capsys, what):
    folder = tmp_path / "run"
    folder.mkdir()
    args = [CANTILEVER, "--t-end", T2]
    if what == "other_scenario":
        assert run(PENDULUM, "--t-end", T1, "--out", str(folder)) == EXIT_OK
    elif what in ("other_size", "not_later"):
        assert run(CANTILEVER, "--t-end", T1, "--out", str(folder)) == EXIT_OK
        if what == "other_size":
            args += ["--set", "beams.rod.elements=8"]
        else:
            args = [CANTILEVER, "--t-end", T1]
    elif what == "no_folder":
        folder = tmp_path / "nothing"
    capsys.readouterr()
    before = {p: p.read_bytes() for p in folder.glob("*.csv")}
    assert run(*args, "--resume", str(folder)) == EXIT_BAD_INPUT
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("flexmbs: error: ")
    expected = {"missing": "no checkpoint", "other_scenario": "that run was made from",
                "other_size": "differs (beams.rod.elements=8)", "not_later": "give a later t_end",
                "no_folder": "is not a folder"}[what]
    assert expected in lines[0]
    assert {p: p.read_bytes() for p in folder.glob("*.csv")} == before   # left untouched


def test_a_run_killed_after_its_last_checkpoint_is_ended_by_resume(tmp_path):
    """A run killed between its last output's checkpoint (at t_end) and its summary's
    "completed" has nothing left to integrate: --resume with the same t_end ends the folder
    (status, counters) and leaves every output as the uninterrupted run wrote it."""
    full, part = tmp_path / "full", tmp_path / "part"
    assert run(CANTILEVER, "--t-end", T1, "--out", str(full), *FULL_NEWTON) == EXIT_OK
    assert run(CANTILEVER, "--t-end", T1, "--out", str(part), *FULL_NEWTON) == EXIT_OK
    summary = json.loads((part / "summary.json").read_text())
    killed = {k: v for k, v in summary.items() if k not in ("stats", "checks", "wall_time")}
    (part / "summary.json").write_text(json.dumps({**killed, "status": "running"}))
    outputs = {p.relative_to(part): p.read_bytes() for p in part.rglob("*")
               if p.is_file() and p.name != "summary.json"}
    assert run(CANTILEVER, "--t-end", T1, "--resume", str(part), *FULL_NEWTON) == EXIT_OK
    ended, ref = (json.loads((d / "summary.json").read_text()) for d in (part, full))
    assert ended["status"] == "completed" and ended["stats"] == ref["stats"]
    assert ended["stats"]["steps"] > 0
    assert {p.relative_to(part): p.read_bytes() for p in part.rglob("*")
            if p.is_file() and p.name != "summary.json"} == outputs
    # once ended, the same t_end is refused: nothing to continue
    assert run(CANTILEVER, "--t-end", T1, "--resume", str(part), *FULL_NEWTON) == EXIT_BAD_INPUT


def test_resume_keeps_frames_the_index_had_not_listed_yet(tmp_path):
    """Item 1 of issue 18: the .pvd index lags the frames (rewritten at most once a second), so
    a kill can leave frames on disk that the index does not list although the checkpoint is
    later. --resume lists them again instead of deleting them as stale: every output time of
    probes.csv has its frame, each once, and a frame cut short by the kill is rewritten."""
    part = tmp_path / "part"
    assert run(CANTILEVER, "--t-end", T1, "--out", str(part), *FULL_NEWTON) == EXIT_OK
    pvd = part / "cantilever.pvd"
    entries = read_pvd(pvd)
    assert len(entries) == 4
    text = pvd.read_text().splitlines()
    pvd.write_text("\n".join(line for line in text if "_000002.vtm" not in line
                             and "_000003.vtm" not in line) + "\n")   # the lagging index
    assert len(read_pvd(pvd)) == 2
    assert run(CANTILEVER, "--t-end", T2, "--resume", str(part), *FULL_NEWTON) == EXIT_OK
    entries = read_pvd(pvd)
    t = np.loadtxt(part / "probes.csv", delimiter=",", skiprows=1)[:, 0]
    np.testing.assert_allclose([e[0] for e in entries], t, rtol=0, atol=1e-15)
    assert [Path(f).name for _, f in entries] == [f"cantilever_{k:06d}.vtm" for k in range(7)]
    assert all((part / f).is_file() for _, f in entries)
    assert all(p.is_file() for _, f in entries for p in frame_files(part / f) or [None])


def test_a_resumed_series_keeps_its_form(tmp_path):
    """A series of merged .vtu frames (an earlier flexmbs, or --output-frames merged) is
    continued in .vtu by a resume, whatever the default: one .pvd never mixes .vtu and .vtm."""
    part = tmp_path / "part"
    assert run(CANTILEVER, "--t-end", T1, "--out", str(part), "--output-frames", "merged",
               *FULL_NEWTON) == EXIT_OK
    assert run(CANTILEVER, "--t-end", T2, "--resume", str(part), *FULL_NEWTON) == EXIT_OK
    names = [Path(f).name for _, f in read_pvd(part / "cantilever.pvd")]
    assert names == [f"cantilever_{k:06d}.vtu" for k in range(7)]
    assert not list((part / "vtu").glob("*.vt[mp]"))
    summary = json.loads((part / "summary.json").read_text())
    assert summary["files"]["frames"] == "merged" and summary["vtm_blocks"] is None


@pytest.mark.parametrize("change", ["set", "dt", "edited"])
def test_resume_refuses_a_different_model_and_keeps_the_first_runs_overrides(tmp_path, capsys,
                                                                           change):
    """Item 5 of issue 18: a resumed run is the first run's model. Without --set it re-applies
    the first run's overrides (a resume that forgot them gives the same trajectory as the
    uninterrupted run); a different override, time step or an edited scenario file is refused
    in one line before anything is written."""
    scen = tmp_path / "c.toml"
    scen.write_text(Path(CANTILEVER).read_text())
    stiff = ["--set", "beams.rod.youngs_modulus=3e11"]
    full, part = tmp_path / "full", tmp_path / "part"
    assert run(str(scen), "--t-end", T2, "--out", str(full), *stiff, *FULL_NEWTON) == EXIT_OK
    assert run(str(scen), "--t-end", T1, "--out", str(part), *stiff, *FULL_NEWTON) == EXIT_OK
    before = {p: p.read_bytes() for p in part.glob("*.csv")}
    capsys.readouterr()
    if change == "set":
        bad = ["--set", "beams.rod.youngs_modulus=1e9"]
    elif change == "dt":
        bad = [*stiff, *FULL_NEWTON, "--dt", "5e-4"]
    else:
        scen.write_text(scen.read_text() + "\n# edited\n")
        bad = []
    assert run(str(scen), "--t-end", T2, "--resume", str(part), *bad) == EXIT_BAD_INPUT
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "a resumed run must be the same model" in lines[0]
    assert {p: p.read_bytes() for p in part.glob("*.csv")} == before
    if change == "edited":
        return
    assert run(str(scen), "--t-end", T2, "--resume", str(part)) == EXIT_OK   # overrides kept
    assert (part / "probes.csv").read_bytes() == (full / "probes.csv").read_bytes()


def test_resume_under_step_error_control_is_bit_identical(tmp_path):
    """Example 2 runs with step-error control (step_tolerance): the checkpoint carries the step
    size, the steps since the last cut and their largest error estimate, so a run stopped while
    its steps are cut (after the excitation's end) and resumed equals the uninterrupted one in
    every file."""
    ex2 = str(ROOT / "examples" / "solar_array_wing.toml")
    full, part = tmp_path / "full", tmp_path / "part"
    # the half-sine ends at 0.2 s: steps are cut at 0.21-0.22 s and grow back until 0.25 s
    assert run(ex2, "--t-end", "0.3", "--out", str(full)) == EXIT_OK
    assert run(ex2, "--t-end", "0.22", "--out", str(part)) == EXIT_OK
    assert run(ex2, "--t-end", "0.3", "--resume", str(part)) == EXIT_OK
    a, b = (json.loads((d / "summary.json").read_text()) for d in (full, part))
    assert a["stats"]["error_rejections"] > 0              # the control did cut steps
    for k in ("steps", "rejected_steps", "error_rejections", "newton_iterations"):
        assert b["stats"][k] == a["stats"][k], k
    for f in ("probes.csv", "contacts.csv", "sections.csv"):
        assert (part / f).read_bytes() == (full / f).read_bytes(), f
    sa, _ = load_checkpoint(full / "checkpoint.npz")
    sb, _ = load_checkpoint(part / "checkpoint.npz")
    for k in ("q", "v", "qdd", "a", "lam"):
        np.testing.assert_array_equal(getattr(sb, k), getattr(sa, k))


#: the tube pendulum's tube as a rod with a rounded-rectangle lumen, which turns with its twist
ROD_TUBE = ["--set", "beams.tube.element=ancf_rod14", "--set",
            'joints.lumen.lumen={ shape = "rounded_rectangle", w = 1.6e-3, h = 1.4e-3, r = 1e-3 }']


@pytest.mark.parametrize("tube", ["cable", "rod"])
def test_resume_of_a_wire_in_a_flexible_tube_is_bit_identical(tmp_path, tube):
    """A tube joint (issue 53): the falling tube pendulum with its wire, stick friction and the
    sections' frames renewed after the checkpoint (the tube turns by more than 60° after
    0.2 s), stopped at 0.2 s and resumed to 0.4 s, equals the uninterrupted run in every file
    and in the final state (the frames' bases included). ``rod``: the tube a rod whose
    rounded-rectangle lumen turns with its twist (the rod's nodal bases restored too)."""
    scenario = str(ROOT / "tests" / "data" / "tube_pendulum.toml")
    full, part = tmp_path / "full", tmp_path / "part"
    extra = ROD_TUBE if tube == "rod" else []
    assert run(scenario, *extra, "--out", str(full)) == EXIT_OK
    assert run(scenario, *extra, "--t-end", "0.2", "--out", str(part)) == EXIT_OK
    assert run(scenario, "--resume", str(part)) == EXIT_OK
    for f in ("probes.csv", "contacts.csv", "sections.csv"):
        assert (part / f).read_bytes() == (full / f).read_bytes(), f
    frames = read_pvd(full / "tube_pendulum.pvd")
    assert read_pvd(part / "tube_pendulum.pvd") == frames
    for _, f in frames:
        assert_same_frame(full / f, part / f)
    sa, ja = load_checkpoint(full / "checkpoint.npz")
    sb, jb = load_checkpoint(part / "checkpoint.npz")
    for k in ("q", "v", "qdd", "a", "lam"):
        np.testing.assert_array_equal(getattr(sb, k), getattr(sa, k))
    ba, bb = (np.array(j["interactions"]["lumen"]["tube_bases"]) for j in (ja, jb))
    np.testing.assert_array_equal(bb, ba)
    assert ba[:, 0].max() < 0.5          # renewed: every base tangent turned from x by > 60°
    assert len((full / "contacts.csv").read_text().splitlines()) > 1
    record = json.loads((full / "summary.json").read_text())["hole_sections"]["lumen"]
    assert record["tube"] == "tube" and record["sections"] == 31

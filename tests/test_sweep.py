"""Parameter sweeps on Dask (``flexmbs sweep``, :func:`flexmbs.sweep`)."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.cli import main
from flexmbs.errors import ScenarioError
from flexmbs.sweeps import make_cases, parse_values, read_table

distributed = pytest.importorskip("distributed")

CANTILEVER = str(Path(__file__).resolve().parents[1] / "examples" / "cantilever.toml")
SHORT = ("simulation.t_end=0.05", "simulation.output_interval=0.01")


@pytest.fixture(scope="module")
def client():
    from dask.distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=":0") as cluster, Client(cluster) as c:
        yield c


# ---------------------------------------------------------------------------- cases
def test_cases_are_the_product_of_grids_times_the_zipped_lists():
    cases = make_cases({"simulation.dt": [1e-3, 5e-4], "beams.rod.radius": [1e-3, 2e-3]},
                       zip={"beams.rod.elements": [4, 8, 16], "simulation.rho_inf": [0.8, 0.9, 1.0]},
                       overrides=["simulation.t_end=0.1"])
    assert len(cases) == 2 * 2 * 3
    names = [c.name for c in cases]
    assert len(set(names)) == len(names)
    assert names[0] == "dt=0.001,radius=0.001,elements=4,rho_inf=0.8"
    assert cases[-1].overrides == ("simulation.t_end=0.1", "simulation.dt=0.0005",
                                   "beams.rod.radius=0.002", "beams.rod.elements=16",
                                   "simulation.rho_inf=1.0")
    # zipped values stay side by side
    assert {(dict(c.params)["beams.rod.elements"], dict(c.params)["simulation.rho_inf"])
            for c in cases} == {(4, 0.8), (8, 0.9), (16, 1.0)}


def test_folder_names_tell_equal_last_segments_apart_and_keep_signs():
    cases = make_cases({"loads.a.force": [[0, 0, -1.5]], "loads.b.force": [[1, 0, 0]],
                        "simulation.gravity": [[0, 0, -9.81]]})
    assert cases[0].name == "a.force=0_0_-1.5,b.force=1_0_0,gravity=0_0_-9.81"


def test_value_lists_parse_like_set_values():
    assert parse_values("simulation.gravity=[0,0,-9.81],[0, 0, -1]") == (
        "simulation.gravity", [[0, 0, -9.81], [0, 0, -1]])
    assert parse_values('joints.j.contact.law="linear",hertz') == (
        "joints.j.contact.law", ["linear", "hertz"])
    assert parse_values("beams.rod.elements=4,8") == ("beams.rod.elements", [4, 8])


@pytest.mark.parametrize("kwargs, message", [
    (dict(grid={}), "no parameters"),
    (dict(grid={"a.b": []}), "non-empty list"),
    (dict(grid={"a.b": 3}), "non-empty list"),
    (dict(zip={"a": [1, 2], "b": [1]}), "differ in length"),
    (dict(grid={"a": [1]}, zip={"a": [1]}), "both grid and zip"),
    (dict(grid={"a": [float("nan")]}), "not a finite number"),
])
def test_bad_sweep_definitions_are_one_line_errors(kwargs, message):
    with pytest.raises(ScenarioError, match=message):
        make_cases(**kwargs)


# ---------------------------------------------------------------------------- runs
def _probes(folder: str | Path) -> np.ndarray:
    return np.loadtxt(Path(folder) / "probes.csv", delimiter=",", skiprows=1)


def test_three_cases_resume_and_a_failing_case(client, tmp_path):
    out = tmp_path / "sweep"
    grid = {"beams.rod.elements": [4, 6, 8]}
    rows = fm.sweep(CANTILEVER, grid, overrides=SHORT, out=out, client=client)
    assert [r["status"] for r in rows] == ["completed"] * 3
    assert [r["beams.rod.elements"] for r in rows] == [4, 6, 8]
    # a case is an ordinary run: the same files as `flexmbs run` of its overrides
    ref = tmp_path / "ref"
    assert main(["run", CANTILEVER, "--out", str(ref), "-q", "--set", SHORT[0], "--set", SHORT[1],
                 "--set", "beams.rod.elements=6"]) == 0
    assert np.array_equal(_probes(ref), _probes(rows[1]["folder"]))
    summary = json.loads((ref / "summary.json").read_text())
    assert rows[1]["steps"] == summary["steps"]
    assert rows[1]["newton_iterations"] == summary["newton_iterations"]
    assert rows[1]["tip_z_final"] == pytest.approx(_probes(ref)[-1, 3], rel=1e-15)
    assert rows[1]["tip_z_min"] == pytest.approx(_probes(ref)[:, 3].min(), rel=1e-15)
    assert rows[1]["energy_change"] == pytest.approx(summary["energy_balance"]["change"])
    assert rows[1]["max_contact_force"] is None          # no clearance joint

    # resume: only the deleted case runs again
    stamps = {r["case"]: (Path(r["folder"]) / "summary.json").stat().st_mtime_ns for r in rows}
    shutil.rmtree(rows[0]["folder"])
    ran: list[str] = []
    again = fm.sweep(CANTILEVER, grid, overrides=SHORT, out=out, client=client,
                     report=lambda case, row, done, total, reused: None if reused else ran.append(case.name))
    assert [r["status"] for r in again] == ["completed"] * 3
    for r in again[1:]:
        assert (Path(r["folder"]) / "summary.json").stat().st_mtime_ns == stamps[r["case"]]
    assert ran == [rows[0]["case"]]
    assert np.array_equal(_probes(again[0]["folder"]), _probes(rows[0]["folder"]))

    # an impossible parameter (at build time) and a failing run (at run time) fail alone
    bad = fm.sweep(CANTILEVER, {"beams.rod.radius": [-1.0, 5e-3],
                                "simulation.newton.max_iterations": [1, 25]},
                   overrides=(*SHORT, "simulation.min_step=1e-3"), out=tmp_path / "bad",
                   client=client)
    status = {(r["beams.rod.radius"], r["simulation.newton.max_iterations"]): r["status"]
              for r in bad}
    assert status[(5e-3, 25)] == "completed"
    assert status[(-1.0, 25)].startswith("failed: beams[rod].radius: expected a number > 0")
    assert status[(5e-3, 1)].startswith("failed: step from t = 0 failed")
    table = (tmp_path / "bad" / "sweep.csv").read_text()
    assert table.count("\n") == 5 and "\n" not in status[(5e-3, 1)]


def test_a_sweep_whose_every_case_is_invalid_is_refused_before_anything_is_written(tmp_path):
    with pytest.raises(ScenarioError, match="unknown key"):
        fm.sweep(CANTILEVER, {"simulation.no_such_key": [1, 2]}, out=tmp_path / "s")
    assert not (tmp_path / "s").exists()


def test_cli_sweep_local_cluster_plot_and_errors(tmp_path, capsys):
    out = tmp_path / "cli"
    argv = ["sweep", CANTILEVER, "--grid", "beams.rod.elements=4,6", "--zip",
            "simulation.rho_inf=0.8,0.9", "--set", SHORT[0], "--out", str(out), "--workers", "1"]
    assert main(argv) == 0
    err = capsys.readouterr()
    assert "4 of 4 cases completed" in err.out
    rows = read_table(out)
    assert [(r["beams.rod.elements"], r["simulation.rho_inf"]) for r in rows] == [
        (4, 0.8), (4, 0.9), (6, 0.8), (6, 0.9)]
    assert main(["plot", str(out), "--format", "png"]) == 0
    assert (out / "figures" / "sweep_tip_z.png").is_file()
    assert (out / "figures" / "overlay_tip_z.png").is_file()
    # one-line errors, exit 2
    for bad, text in [(["--grid", "beams.rod.elements"], "expected KEY=V1,V2"),
                      (["--grid", "beams.rod.elements=4,,6"], "an empty value"),
                      (["--grid", "beams.rod.elements=4", "--workers", "0"],
                       "--workers: expected an integer >= 1"),
                      (["--grid", "simulation.t_endd=1,2"], "unknown key 't_endd' in simulation")]:
        assert main(["sweep", CANTILEVER, "--out", str(tmp_path / "x"), *bad]) == 2
        lines = capsys.readouterr().err.strip().splitlines()
        assert len(lines) == 1 and text in lines[0], lines
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "notes.txt").write_text("mine")
    assert main(["sweep", CANTILEVER, "--grid", "beams.rod.elements=4", "--out",
                 str(tmp_path / "other")]) == 2
    assert "holds no flexmbs sweep" in capsys.readouterr().err


def test_same_table_on_a_scheduler_started_by_hand(tmp_path, client):
    """`dask scheduler` + `dask worker` processes on localhost, reached by a scheduler file."""
    grid = {"beams.rod.elements": [4, 6, 8]}
    local = fm.sweep(CANTILEVER, grid, overrides=SHORT, out=tmp_path / "local", client=client)
    sched_file = tmp_path / "scheduler.json"
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[1]))
    dask_cmd = [sys.executable, "-m", "dask"]
    procs = [subprocess.Popen([*dask_cmd, "scheduler", "--scheduler-file", str(sched_file),
                               "--port", "0", "--no-dashboard"], env=env,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        for _ in range(200):
            if sched_file.is_file() and sched_file.stat().st_size:
                break
            time.sleep(0.1)
        procs.append(subprocess.Popen([*dask_cmd, "worker", "--scheduler-file", str(sched_file),
                                       "--nthreads", "1", "--nworkers", "2", "--no-dashboard"],
                                      env=env, stdout=subprocess.DEVNULL,
                                      stderr=subprocess.DEVNULL))
        assert main(["sweep", CANTILEVER, "--grid", "beams.rod.elements=4,6,8", "--set",
                     SHORT[0], "--set", SHORT[1], "--out", str(tmp_path / "remote"),
                     "--scheduler", str(sched_file), "-q"]) == 0
    finally:
        for p in reversed(procs):
            p.terminate()
        for p in procs:
            p.wait(timeout=30)
    remote = read_table(tmp_path / "remote")
    for a, b in zip(local, remote, strict=True):
        for key in a:
            if key not in ("wall_time", "folder"):
                assert a[key] == b[key], key

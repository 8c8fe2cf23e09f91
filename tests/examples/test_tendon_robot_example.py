"""examples/tendon_robot.py (issue 52, item 5): the load cases by name, the run's output
(disk centres, span tensions, pulled lengths) and the figures postprocess/ draws from it."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import load_module

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def example():
    return load_module(ROOT / "examples" / "tendon_robot.py", "tendon_robot_example")


def test_the_load_cases_build_the_issue_robot(example):
    model, parts = example.build("tip_force", disks=4)
    tendons = parts["tendons"]
    assert [t.name for t in tendons] == [f"t{i}" for i in range(1, 7)]
    # tendons 1-3 end at the middle disk, 4-6 at the last: holes in the plate and every disk below
    assert [len(t.holes) for t in tendons] == [2, 2, 2, 4, 4, 4]
    assert {j.hole.sections for t in tendons for j in t.holes} == {1}
    assert "tip_force" in {ld.name for ld in model.loads}
    with pytest.raises(SystemExit, match="unknown load case 'bend'"):
        example.build("bend")


def test_a_short_run_writes_what_the_figures_read(example, tmp_path, capsys):
    out = tmp_path / "mixed"
    assert example.main(["--disks", "2", "--t-end", "0.05", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "case mixed" in printed and "t2: span tensions" in printed
    sys.path.insert(0, str(ROOT))
    try:
        from postprocess.data import read_run
        from postprocess.robot import robot_loop, robot_shapes, robot_tensions
    finally:
        sys.path.remove(str(ROOT))
    run = read_run(out)
    assert {"disk1_x", "disk2_z", "N_t2_0", "N_t2_1", "pulled_t2"} <= set(run.probes)
    assert run.probes["N_t2_0"][-1] > 0.1            # the ramp has begun to pull tendon 2
    assert np.abs(run.probes["N_t1_0"]).max() < 0.05      # tendon 1 is not pulled: slack
    import matplotlib.pyplot as plt

    for fig in (robot_shapes({"mixed": run}), robot_tensions({"mixed": run}),
                robot_loop({"mixed": run})):
        assert fig.axes
        plt.close(fig)


def test_the_scenario_file_is_the_script_s_robot(example, tmp_path):
    """examples/tendon_robot.toml is what the script writes (edit one source), and a scenario
    file written for 4 disks builds the model the Python builder does and runs on the CLI."""
    from flexmbs.assembly import Assembly
    from flexmbs.cli import main
    from flexmbs.io.scenario import load_scenario

    committed = (ROOT / "examples" / "tendon_robot.toml").read_text(encoding="utf-8")
    assert committed == example.scenario()
    path = tmp_path / "robot4.toml"
    assert example.main(["--write-toml", str(path), "--disks", "4", "--case", "tip_force"]) == 0
    from_file = Assembly(load_scenario(path).model)
    model, _ = example.build("tip_force", disks=4)
    built = Assembly(model)
    assert (from_file.n_coords, from_file.n_mult) == (built.n_coords, built.n_mult)
    np.testing.assert_allclose(from_file.q_ref, built.q_ref, rtol=0, atol=1e-15)
    out = tmp_path / "out"
    assert main(["run", str(path), "--out", str(out), "-q", "--set", "simulation.t_end=0.02",
                 "--set", "simulation.output_interval=0.01"]) == 0
    header = (out / "probes.csv").read_text(encoding="utf-8").splitlines()[0].split(",")
    assert {"tip_x", "disk4_z", "N_t4_4", "pulled_t6"} <= set(header)


def test_the_static_solve_of_the_mixed_case(example, capsys):
    """--static: the 'mixed' case (slack tendons 1, 3, 5) by solve_static on 4 disks; without
    friction tendon 2 (2 N) and tendons 4, 6 (1 N) keep their tensions in every span within
    1e-3 (measured 3e-4), the slack ones carry less than 1 mN."""
    assert example.main(["--disks", "4", "--static", "--case", "mixed"]) == 0
    out = capsys.readouterr().out
    assert "case mixed (static)" in out
    lines = {ln.split(":")[0].strip(): ln for ln in out.splitlines() if "span tensions" in ln}
    for name, T in (("t2", 2.0), ("t4", 1.0), ("t6", 1.0), ("t1", 0.0), ("t5", 0.0)):
        values = np.array(lines[name].split("[")[1].split("]")[0].split(), float)
        np.testing.assert_allclose(values, T, rtol=0, atol=1e-3 * max(T, 1.0))


def test_the_pull_release_loop_runs_both_frictions(example, tmp_path, capsys, monkeypatch):
    """--loop (shortened): tendon 4 pulled and released without friction and with μ = 0.1,
    each run in its folder with the actuator's tension rising and falling."""
    monkeypatch.setattr(example, "LOOP_TIME", 0.02)
    assert example.main(["--loop", "--disks", "2", "--out", str(tmp_path), "--dt", "2e-3"]) == 0
    assert "mu = 0.1" in capsys.readouterr().out
    sys.path.insert(0, str(ROOT))
    try:
        from postprocess.data import read_run
    finally:
        sys.path.remove(str(ROOT))
    for mu in ("0", "0.1"):
        n = read_run(tmp_path / f"mu_{mu}").probes["N_t4_0"]
        assert n.max() > 1.0 and abs(n[-1]) < 0.1 * n.max()

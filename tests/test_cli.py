"""The ``flexmbs`` command line (docs/design.md "CLI" and "Output folder"): run, info, exit codes,
one-line errors, the output folder of completed, failed and interrupted runs, and the same
folder from the Python API (``simulate(..., out=...)``)."""

from __future__ import annotations

import csv
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.cli import EXIT_BAD_INPUT, EXIT_FAILED, EXIT_INTERRUPTED, EXIT_OK, main
from flexmbs.io.probes import BeamPointProbe, EnergyProbe
from flexmbs.io.vtu import read_pvd

ROOT = Path(__file__).resolve().parents[1]
CANTILEVER = str(ROOT / "examples" / "cantilever.toml")
PENDULUM = str(ROOT / "examples" / "flexible_pendulum.toml")
CONTACT_HEADER = "t,joint,section,point,gap,normal_force,qx,qy,qz,px,py,pz,a,b"
#: makes the pendulum fail at t = 0.012 (frames at 0 and 0.01 written before)
DIVERGE = ["--set", "simulation.newton.max_iterations=2", "--set", "simulation.adaptive=false"]


def summary(folder: Path) -> dict:
    return json.loads((folder / "summary.json").read_text())


def one_error_line(err: str) -> str:
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1, err
    assert lines[0].startswith("flexmbs: error: ")
    return lines[0]


def test_quasi_static_integrator_writes_an_equilibrium_per_output_time(tmp_path, capsys):
    """Equilibria at 0, 0.25, ..., 1 (output_interval), each from the last: under constant
    gravity every one is the static deflection q L^4 / (8 EI) (within 1 %); the folder has
    one frame and one probes row per equilibrium; a quasi-static run has nothing to resume."""
    out = tmp_path / "qs"
    assert main(["run", CANTILEVER, "--set", "simulation.integrator=quasi_static", "--set",
                 "simulation.output_interval=0.25", "--quiet", "--out", str(out)]) == EXIT_OK
    assert [t for t, _ in read_pvd(out / "cantilever.pvd")] == [0.0, 0.25, 0.5, 0.75, 1.0]
    rows = list(csv.reader((out / "probes.csv").open()))
    r, E, rho = 5e-3, 2.1e11, 7800.0
    q, EI = rho * np.pi * r**2 * 9.81, E * np.pi * r**4 / 4
    assert [float(row[0]) for row in rows[1:]] == [0.0, 0.25, 0.5, 0.75, 1.0]
    for row in rows[1:]:
        assert float(row[3]) == pytest.approx(-q / (8 * EI), rel=1e-2)
    assert summary(out)["status"] == "completed"
    capsys.readouterr()
    assert main(["run", CANTILEVER, "--set", "simulation.integrator=quasi_static", "--set",
                 "simulation.output_interval=0.25", "--resume", str(out)]) == EXIT_BAD_INPUT
    assert "quasi_static scenario has nothing to resume" in one_error_line(capsys.readouterr().err)


def test_run_writes_output_folder(tmp_path, capsys):
    out = tmp_path / "cant"
    assert main(["run", CANTILEVER, "--t-end", "0.05", "--quiet", "--out", str(out)]) == EXIT_OK
    cap = capsys.readouterr()
    assert cap.out == "" and cap.err == ""
    frames = read_pvd(out / "cantilever.pvd")
    assert [t for t, _ in frames] == pytest.approx([0.0, 0.01, 0.02, 0.03, 0.04, 0.05])
    assert all((out / f).is_file() for _, f in frames)
    assert (out / "vtu").is_dir() and (out / "checkpoint.npz").is_file()
    rows = list(csv.reader((out / "probes.csv").open()))
    assert rows[0] == ["t", "tip_x", "tip_y", "tip_z", "energy"]
    assert len(rows) == 1 + len(frames)
    assert (out / "contacts.csv").read_text().splitlines()[0] == CONTACT_HEADER
    s = summary(out)
    assert s["status"] == "completed" and s["scenario"] == "cantilever"
    assert s["steps"] == 50 and s["newton_iterations"] > 0 and s["final_time"] == 0.05
    assert s["dofs"] == {"coordinates": 102, "multipliers": 5}
    assert s["metadata"]["overrides"] == ["simulation.t_end=0.05"]
    assert "initial_total" in s["energy_balance"]


def test_run_default_folder_and_summary_line(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["run", CANTILEVER, "--t-end", "0.02", "--dt", "2e-3"]) == EXIT_OK
    out = capsys.readouterr().out
    assert "completed" in out and "10 steps" in out and "out/cantilever" in out.replace("\\", "/")
    assert (tmp_path / "out" / "cantilever" / "cantilever.pvd").is_file()
    assert summary(tmp_path / "out" / "cantilever")["metadata"]["overrides"] == [
        "simulation.t_end=0.02", "simulation.dt=0.002"]


def test_static_integrator_writes_one_frame(tmp_path):
    out = tmp_path / "static"
    assert main(["run", CANTILEVER, "--set", "simulation.integrator=static", "--quiet",
                 "--out", str(out)]) == EXIT_OK
    assert len(read_pvd(out / "cantilever.pvd")) == 1
    rows = list(csv.reader((out / "probes.csv").open()))
    assert len(rows) == 2
    # linear theory: tip deflection q L^4 / (8 EI), q = rho A g (small: within 1 %)
    r, E, rho = 5e-3, 2.1e11, 7800.0
    q, EI = rho * np.pi * r**2 * 9.81, E * np.pi * r**4 / 4
    assert float(rows[1][3]) == pytest.approx(-q / (8 * EI), rel=1e-2)
    assert summary(out)["status"] == "completed"


def test_info_prints_model(capsys):
    assert main(["info", CANTILEVER, "--set", "beams.rod.elements=8"]) == EXIT_OK
    text = capsys.readouterr().out
    assert "coordinates  54" in text and "multipliers  5" in text   # 9 nodes x 6
    assert "rod: 8 elements, 9 nodes, length 1 m (element ancf_cable)" in text
    assert "clamp1: clamp rod.node[0], 5 equations" in text
    assert "probes (2)" in text and "tip_x, tip_y, tip_z" in text
    assert "dropped redundant equations (0)" in text and "GeneralizedAlpha(" in text
    assert "integrator path        compiled" in text
    assert main(["info", CANTILEVER, "--set", "simulation.compiled=false"]) == EXIT_OK
    assert "Python Newton loop (compiled = false)" in capsys.readouterr().out


@pytest.mark.parametrize("args, expected", [
    (["run", CANTILEVER, "--set", "beams.rod.radiu=1"], "unknown key 'radiu' in beams[rod]"),
    (["run", CANTILEVER, "--set", "simulation.dt=-1"], "simulation.dt: expected a number > 0"),
    (["run", CANTILEVER, "--set", "nokey"], "expected KEY=VALUE"),
    (["run", "does_not_exist.toml"], "scenario file not found"),
    (["info", CANTILEVER, "--set", "beams.rail.elements=2"], "no entry 'rail' in beams"),
])
def test_bad_input_exit_2_one_line(tmp_path, capsys, args, expected):
    assert main([*args, "--quiet", "--out", str(tmp_path / "x")] if args[0] == "run"
                else args) == EXIT_BAD_INPUT
    assert expected in one_error_line(capsys.readouterr().err)


def test_missing_output_folder_and_sweep_give_one_line(capsys):
    """render/plot of a folder that does not exist, and a sweep without parameters: exit 2 and
    one line on stderr."""
    for cmd, expected in ((["render", "out/x"], "flexmbs: error: output folder not found: out/x"),
                          (["plot", "out/x"], "flexmbs: error: output folder not found: out/x"),
                          (["sweep", CANTILEVER], "flexmbs: error: sweep: no parameters; give "
                           "--grid KEY=V1,V2,... (or --zip)")):
        assert main(cmd) == EXIT_BAD_INPUT
        err = capsys.readouterr().err.strip()
        assert err == expected


def test_usage_error_returns_2(capsys):
    assert main(["run"]) == EXIT_BAD_INPUT
    assert main(["--version"]) == 0
    assert "flexmbs 0.1.0" in capsys.readouterr().out


def test_divergence_exit_3_keeps_valid_output(tmp_path, capsys):
    out = tmp_path / "div"
    rc = main(["run", PENDULUM, "--t-end", "0.1", *DIVERGE, "--quiet", "--out", str(out)])
    assert rc == EXIT_FAILED
    line = one_error_line(capsys.readouterr().err)
    assert "Newton did not converge" in line
    s = summary(out)
    # two Newton iterations per step are not enough once the pendulum swings: the step from
    # t_f fails (no step cut-back); outputs every 0.01 s up to t_f stay readable
    t_f = float(s["status"].split("step from t = ")[1].split()[0])
    assert 0.0 < t_f < 0.1 and s["steps"] == round(t_f / 1e-3)
    frames = read_pvd(out / "flexible_pendulum.pvd")
    assert [t for t, _ in frames] == pytest.approx(np.arange(0.0, t_f + 1e-9, 0.01))
    vtk = pytest.importorskip("vtk")
    for _, f in frames:                 # multiblock frames: the beam piece has its fields
        reader = vtk.vtkXMLMultiBlockDataReader()
        reader.SetFileName(str(out / f))
        reader.Update()
        beam = reader.GetOutput().GetBlock(0).GetBlock(0)
        assert beam.GetNumberOfPoints() > 0 and beam.GetPointData().HasArray("displacement")
    assert len((out / "probes.csv").read_text().splitlines()) == len(frames) + 1


def test_interrupt_exit_130(tmp_path, capsys, monkeypatch):
    from flexmbs.commands import run as run_command

    def ctrl_c(self, state, stats):
        if state.t > 0.02:
            raise KeyboardInterrupt

    monkeypatch.setattr(run_command.Progress, "__call__", ctrl_c)
    out = tmp_path / "int"
    assert main(["run", CANTILEVER, "--t-end", "0.1", "--quiet", "--out", str(out)]) \
        == EXIT_INTERRUPTED
    assert "interrupted" in one_error_line(capsys.readouterr().err)
    s = summary(out)
    assert s["status"] == "interrupted" and s["final_time"] == pytest.approx(0.03)
    assert len(read_pvd(out / "cantilever.pvd")) == 4


def test_subprocess_bad_scenario_one_line(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "bad"\n[simulation]\nt_end = 1.0\ndt = 1e-3\n\n[[beams]]\nname = "b"\n'
                   'geometry = { line = { start = [0, 0, 0], end = [1, 0, 0] } }\nelements = 4\n'
                   'radius = -2e-3\nyoungs_modulus = 2.1e11\ndensity = 7800.0\n')
    proc = subprocess.run([sys.executable, "-m", "flexmbs", "run", str(bad), "--quiet"],
                          capture_output=True, text=True, cwd=tmp_path, timeout=120)
    assert proc.returncode == EXIT_BAD_INPUT
    assert proc.stderr.strip() == ("flexmbs: error: beams[b].radius: expected a number > 0, "
                                   "got -0.002")
    assert proc.stdout == "" and not (tmp_path / "out").exists()


# ------------------------------------------------------------------------- Python API
def small_cantilever():
    model = fm.Model(gravity=(0, 0, -9.81), name="api")
    beam = model.add_beam(fm.line((0, 0, 0), (1, 0, 0), elements=4), name="rod",
                          section=fm.BeamStiffness(axial_stiffness=1e6, bending_stiffness=10.0,
                                                   mass_per_length=0.5))
    model.clamp(beam.first_node)
    return model, beam


def test_simulate_out_and_probes(tmp_path):
    model, beam = small_cantilever()
    probes = [BeamPointProbe("tip", beam, 1.0, "displacement"), EnergyProbe("E")]
    res = fm.simulate(model, t_end=0.02, dt=1e-3, output_interval=5e-3, out=tmp_path / "api",
                      probes=probes)
    assert res.status == "completed" and res.t.size == 5
    s = summary(tmp_path / "api")
    assert s["status"] == "completed" and s["scenario"] == "api" and s["steps"] == 20
    rows = np.loadtxt(tmp_path / "api" / "probes.csv", delimiter=",", skiprows=1)
    np.testing.assert_array_equal(rows[:, 0], res.t)
    np.testing.assert_array_equal(rows[:, 3], res.extra["probes"]["tip_z"])
    np.testing.assert_array_equal(rows[:, 3], res.beam_point(beam, 1.0, "displacement")[:, 2])


def test_simulate_divergence_partial_result_and_folder(tmp_path):
    model, _ = small_cantilever()
    opts = fm.GeneralizedAlpha(newton=fm.NewtonOptions(max_iterations=1), adaptive=False)
    with pytest.raises(fm.ConvergenceError) as exc:
        fm.simulate(model, t_end=0.02, dt=1e-3, integrator=opts, out=tmp_path / "f", name="f")
    part = exc.value.partial_result
    assert part.status.startswith("failed: ") and part.t[0] == 0.0
    assert summary(tmp_path / "f")["status"] == part.status
    assert len(read_pvd(tmp_path / "f" / "f.pvd")) == part.t.size



def test_solve_static_out_writes_one_frame(tmp_path):
    """The static run of ``flexmbs run`` through the API: one frame at t, probes, summary."""
    from flexmbs.assembly import Assembly
    from flexmbs.simulation import checkpoint_time

    model, beam = small_cantilever()
    st = fm.solve_static(model, fm.StaticOptions(load_steps=2), t=0.5, out=tmp_path / "st",
                         probes=[BeamPointProbe("tip", beam, 1.0, "displacement")],
                         metadata={"note": "api"})
    assert [t for t, _ in read_pvd(tmp_path / "st" / "api.pvd")] == [0.5]
    rows = np.loadtxt(tmp_path / "st" / "probes.csv", delimiter=",", skiprows=1, ndmin=2)
    asm = Assembly(model)
    d = asm.node_dofs(beam.last_node)[:3]
    assert rows.shape == (1, 4) and rows[0, 0] == 0.5
    np.testing.assert_allclose(rows[0, 1:], st.q[d] - asm.q_ref[d], rtol=1e-9, atol=1e-15)
    s = summary(tmp_path / "st")
    assert s["status"] == "completed" and s["scenario"] == "api" and s["steps"] == 0
    assert s["newton_iterations"] == st.newton_iterations > 0
    assert s["metadata"]["note"] == "api"
    assert checkpoint_time(tmp_path / "st") == 0.5
    assert checkpoint_time(tmp_path / "missing") is None


def test_solve_static_out_failure_keeps_folder(tmp_path):
    model, _ = small_cantilever()
    opts = fm.StaticOptions(min_increment=0.5, newton=fm.NewtonOptions(
        max_iterations=1, modified=False, line_search=False))
    with pytest.raises(fm.ConvergenceError):
        fm.solve_static(model, opts, out=tmp_path / "f", name="f")
    s = summary(tmp_path / "f")
    assert s["status"].startswith("failed: ") and s["scenario"] == "f"
    assert read_pvd(tmp_path / "f" / "f.pvd") == []


@pytest.mark.parametrize("argv, what", [([], "COMMAND"), (["run"], "SCENARIO"),
                                        (["run", "x.toml", "--bogus"], "--bogus"),
                                        (["run", "x.toml", "--t-end", "soon"], "--t-end")])
def test_usage_errors_take_one_line(argv, what, capsys):
    """argparse's usage block is replaced by one line naming the problem, exit 2."""
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and what in err[0] and err[0].startswith("flexmbs")


def test_every_command_has_quiet_and_help_points_to_the_site():
    """-q/--quiet on every command (issue 55); the help texts name the docs site's pages, not
    files of a clone."""
    from flexmbs.cli import COMMANDS, build_parser
    from flexmbs.commands._common import DOCS_URL

    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    for name in COMMANDS:
        command = sub.choices[name]
        flags = {s for a in command._actions for s in a.option_strings}
        assert {"-q", "--quiet"} <= flags, name
        assert "docs/" not in (command.description or ""), name
    assert DOCS_URL in (parser.description or "")
    assert "-v" in {s for a in sub.choices["run"]._actions for s in a.option_strings}


def test_info_quiet_only_checks(capsys):
    assert main(["info", CANTILEVER, "-q"]) == EXIT_OK
    assert capsys.readouterr().out == ""


def test_run_verbose_prints_the_solver_counters(tmp_path, capsys):
    out = tmp_path / "cant"
    assert main(["run", CANTILEVER, "--t-end", "0.03", "-v", "--out", str(out)]) == EXIT_OK
    err = capsys.readouterr().err.splitlines()
    header = next(ln for ln in err if "newton" in ln and "per step" in ln)
    rows = [ln.split() for ln in err[err.index(header) + 1:] if ln.startswith("cantilever:")]
    assert rows and float(rows[-1][1]) == pytest.approx(0.03)
    assert sum(int(r[3]) for r in rows) == summary(out)["stats"]["steps"]
    assert main(["run", CANTILEVER, "-q", "-v"]) == EXIT_BAD_INPUT     # one or the other


def test_compressed_frames_on_request_are_read_back(tmp_path):
    """simulation.vtk_compression = true: zlib-compressed pieces (VTK's compressor attribute)
    that pyvista reads to the same points as the uncompressed default."""
    pv = pytest.importorskip("pyvista")
    points = {}
    for flag in ("false", "true"):
        out = tmp_path / flag
        assert main(["run", CANTILEVER, "--t-end", "0.02", "-q", "--out", str(out),
                     "--set", f"simulation.vtk_compression={flag}"]) == EXIT_OK
        piece = sorted((out / "vtu").glob("*_beams_0.vtp"))[-1]
        assert ('compressor="vtkZLibDataCompressor"' in piece.read_text()) == (flag == "true")
        reader = pv.get_reader(str(out / "cantilever.pvd"))
        reader.set_active_time_value(reader.time_values[-1])
        points[flag] = reader.read()[0]["beams"]["rod"].points
    np.testing.assert_array_equal(points["true"], points["false"])

"""Bad inputs answered in one line each, exit 2, before any file is written (sizes, time spans,
names, damaged files, signals at start-up, clearance geometry)."""

from __future__ import annotations

import math
import shutil
import signal
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.budget import check_run
from flexmbs.cli import main
from flexmbs.errors import FlexmbsWarning

ROOT = Path(__file__).resolve().parents[1]
CANTILEVER = str(ROOT / "examples" / "cantilever.toml")
SLEEVE = str(ROOT / "examples" / "curved_beam_sleeve.toml")


def _refused(argv, capsys, *needles):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("flexmbs: error: "), err
    for n in needles:
        assert n in err[0], err[0]
    return err[0]


@pytest.mark.parametrize("setting, needles", [
    ("beams.rod.elements=1000000000", ("beams[rod]", "elements = 1000000000", "memory")),
    ("simulation.t_end=1e12", ("simulation.t_end / simulation.dt = 1e+15 steps",)),
    ("simulation.dt=1e-300", ("simulation.dt = 1e-300", "steps")),
    ("simulation.t_end=1e5", ("1e+07 output frames", "simulation.output_interval")),
])
def test_runs_that_cannot_run_here_are_refused_before_anything_is_written(
        setting, needles, tmp_path, capsys):
    out = tmp_path / "out"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FlexmbsWarning)    # the hours warning of the last one
        _refused(["run", CANTILEVER, "--set", setting, "--out", str(out), "-q"], capsys, *needles)
    assert not out.exists()


def test_ten_million_hole_sections_and_an_earlier_output_kept(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["run", CANTILEVER, "--t-end", "0.02", "--out", str(out), "-q"]) == 0
    before = sorted(p.name for p in out.rglob("*"))
    _refused(["run", SLEEVE, "--set", "joints.sleeve.hole.sections=10000000", "--out", str(out),
              "-q"], capsys, "joints[sleeve]", "hole sections = 10000000", "more than 100000")
    # refused before the folder was claimed: the earlier run's files are untouched
    _refused(["run", CANTILEVER, "--set", "simulation.t_end=1e12", "--out", str(out), "-q"],
             capsys, "steps")
    assert sorted(p.name for p in out.rglob("*")) == before


def test_api_run_checks():
    model = fm.Model()
    beam = model.add_beam(fm.line((0, 0, 0), (1, 0, 0), elements=2),
                          section=fm.CircularSection(1e-3), material=fm.Material(E=1e9, rho=1e3))
    model.clamp(beam.first_node)
    for kwargs, text in [(dict(t_end=math.inf, dt=1e-3), "t_end must be a finite number"),
                         (dict(t_end=0.01, dt=0.1), "longer than the run"),
                         (dict(t_end=1.0, dt=1e-300), "steps"),
                         (dict(t_end=1.0, dt=0.0), "dt must be > 0")]:
        with pytest.raises(fm.ModelError, match=text):
            fm.simulate(model, **kwargs)
    with pytest.raises(fm.GeometryError, match="memory"):
        fm.line((0, 0, 0), (1, 0, 0), elements=10**9)
    with pytest.raises(fm.ModelError, match="hole sections must be an integer"):
        fm.CircleHole(2e-3, 0.02, sections=2.7)
    with pytest.raises(fm.ModelError, match="more than 100000 per hole"):
        fm.CircleHole(2e-3, 0.02, sections=10**11)


def test_a_run_of_hours_is_announced():
    model = fm.Model()
    model.add_beam(fm.line((0, 0, 0), (1, 0, 0), elements=8),
                   section=fm.CircularSection(1e-3), material=fm.Material(E=1e9, rho=1e3))
    with pytest.warns(FlexmbsWarning, match="hours on one core"):
        check_run(model, t_end=1e6, dt=1e-3, output_interval=None, out=None)


@pytest.mark.parametrize("setting, needles", [
    ('name="a\\u0000b"', ("name:", "printable")),
    ('beams.rod.name="r\\nx"', ("beams[0].name", "printable")),
    ('rigid_bodies=[{name="rod", mass=1.0, inertia=[1, 1, 1]}]',
     ("rigid_bodies[rod]", "names of beams and rigid bodies must be unique")),
])
def test_names(setting, needles, tmp_path, capsys):
    _refused(["run", CANTILEVER, "--set", setting, "--out", str(tmp_path / "o"), "-q"], capsys,
             *needles)


def test_api_names():
    model = fm.Model()
    model.add_beam(fm.line((0, 0, 0), (1, 0, 0), elements=2), section=fm.CircularSection(1e-3),
                   material=fm.Material(E=1e9, rho=1e3), name="part")
    with pytest.raises(fm.ModelError, match="names of beams and rigid bodies must be unique"):
        model.add_rigid_body(mass=1.0, inertia=(1, 1, 1), name="part")
    with pytest.raises(fm.ModelError, match="control character"):
        model.add_rigid_body(mass=1.0, inertia=(1, 1, 1), name="a\nb")


def test_damaged_checkpoint_is_one_line(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["run", CANTILEVER, "--t-end", "0.02", "--out", str(out), "-q"]) == 0
    for content in (b"garbage", (out / "checkpoint.npz").read_bytes()[:300]):
        (out / "checkpoint.npz").write_bytes(content)
        _refused(["run", CANTILEVER, "--resume", str(out), "--t-end", "0.04", "-q"], capsys,
                 "checkpoint.npz is damaged or not a flexmbs checkpoint", "not an .npz archive")


@pytest.mark.parametrize("target, text", [("/dev/null", "is not a regular file"),
                                          ("/tmp", "is a folder")])
def test_mesh_path_that_is_not_a_file(target, text, tmp_path, capsys):
    if not Path(target).exists():
        pytest.skip(f"{target} does not exist on this platform")
    scenario = tmp_path / "s.toml"
    scenario.write_text(f'name = "s"\n[simulation]\nt_end = 0.01\ndt = 1e-3\n[[beams]]\n'
                        f'name = "b"\ngeometry = {{ mesh = "{target}" }}\nradius = 1e-3\n'
                        'youngs_modulus = 1e9\ndensity = 1e3\n')
    _refused(["info", str(scenario)], capsys, "beams[b].geometry.mesh", text)


def test_meshio_messages_are_one_warning_naming_the_file(tmp_path):
    import meshio

    from flexmbs.geometry import mesh_input

    path = tmp_path / "arc.vtu"
    pts = np.array([[np.cos(a), np.sin(a), 0.0] for a in np.linspace(0, 1, 9)])
    meshio.write(path, meshio.Mesh(pts, [("line", np.array([[i, i + 1] for i in range(8)]))]))
    real_read = meshio.read

    def chatty(p, *a, **k):
        print("\nWarning: something meshio wants to say")
        return real_read(p, *a, **k)

    meshio.read = chatty
    try:
        with pytest.warns(FlexmbsWarning, match=r"arc.vtu: meshio says: Warning: something"):
            mesh_input.read_curve(path)
    finally:
        meshio.read = real_read


def test_an_infinite_load_is_named():
    model = fm.Model(gravity=(0, 0, -9.81))
    beam = model.add_beam(fm.line((0, 0, 0), (1, 0, 0), elements=4),
                          section=fm.CircularSection(1e-3), material=fm.Material(E=1e9, rho=1e3))
    model.clamp(beam.first_node)
    model.add_point_load(beam.last_node, (0, 0, 1.0), function=lambda t: math.inf, name="push")
    with pytest.raises(fm.ConvergenceError, match="load 'push': its time function gives inf"):
        fm.simulate(model, t_end=0.01, dt=1e-3)


def test_ctrl_c_that_a_c_extension_turns_into_another_error_is_one_line(monkeypatch, capsys):
    """A Ctrl-C that lands while a C extension loads can come out as another error with the
    interrupt dropped from its chain (numpy, mid-import: "PyCapsule_Import could not import
    module datetime"): still one line and exit 130, because the command saw the signal."""
    import os
    import signal

    from flexmbs import cli

    def start(argv):
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(5)
        except KeyboardInterrupt:
            pass
        raise ImportError('PyCapsule_Import could not import module "datetime"')

    monkeypatch.setattr(cli, "_main", start)
    handler = signal.getsignal(signal.SIGINT)
    assert cli.main(["run", SLEEVE]) == cli.EXIT_INTERRUPTED
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("flexmbs: error: interrupted")
    assert signal.getsignal(signal.SIGINT) is handler      # restored


def test_ctrl_c_while_starting_is_one_line(tmp_path):
    """SIGINT at several moments of start-up (imports, scenario, compilation, first steps)."""
    for delay in (0.15, 0.4, 0.8):
        p = subprocess.Popen([sys.executable, "-m", "flexmbs", "run", SLEEVE, "--t-end", "0.5",
                              "--out", str(tmp_path / f"o{delay}"), "-q"],
                             stderr=subprocess.PIPE, text=True, cwd=ROOT)
        time.sleep(delay)
        p.send_signal(signal.SIGINT)
        err = p.communicate(timeout=120)[1]
        if p.returncode == 0:
            continue                  # it finished first
        assert p.returncode == 130, err
        lines = err.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("flexmbs: error: interrupted"), err


def test_ctrl_c_wrapped_by_python_is_still_an_interrupt(monkeypatch, capsys):
    """A Ctrl-C landing in a class body being created (a dataclass field's ``__set_name__``)
    reaches the command as a RuntimeError caused by the KeyboardInterrupt (seen in CI while
    the model module loaded): still one line and exit 130; other errors are not swallowed."""
    from flexmbs import cli

    def wrapped(argv):
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as exc:
            raise RuntimeError("Error calling __set_name__ on 'Field' instance") from exc

    monkeypatch.setattr(cli, "_main", wrapped)
    assert cli.main(["run", SLEEVE]) == cli.EXIT_INTERRUPTED
    assert capsys.readouterr().err.strip() == "flexmbs: error: interrupted"

    def plain(argv):
        raise RuntimeError("a bug")

    monkeypatch.setattr(cli, "_main", plain)
    with pytest.raises(RuntimeError, match="a bug"):
        cli.main(["run", SLEEVE])


def test_clearance_geometry_errors_name_the_key(tmp_path, capsys):
    out = str(tmp_path / "o")
    _refused(["run", SLEEVE, "--set", "joints.sleeve.hole.radius=1e-3", "--out", out, "-q"],
             capsys, "joints[sleeve].hole:", "not larger than the beam")
    _refused(["run", SLEEVE, "--set", "rigid_bodies.sleeve.pose={position=[5, 0, 0]}", "--out",
              out, "-q"], capsys, "joints[sleeve] (with rigid_bodies[sleeve].pose)",
             "does not pass through the hole")


def test_api_body_away_from_the_beam_is_refused_when_the_joint_is_added():
    model = fm.Model()
    beam = model.add_beam(fm.line((0, 0, 0), (1, 0, 0), elements=4),
                          section=fm.CircularSection(1e-3), material=fm.Material(E=1e9, rho=1e3))
    body = model.add_rigid_body(mass=0.1, inertia=(1e-5, 1e-5, 1e-5),
                                pose=beam.frame_at(0.5).shifted((0, 5.0, 0)))
    with pytest.raises(fm.ModelError, match="does not pass through the hole"):
        model.add_joint(fm.SlidingClearanceJoint(beam, body, hole=fm.CircleHole(2e-3, 0.02, 3)))


pv = pytest.importorskip("pyvista")


def test_render_refuses_bad_fps_a_damaged_index_and_an_empty_frame(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["run", CANTILEVER, "--t-end", "0.03", "--out", str(out), "-q"]) == 0
    assert main(["render", str(out), "--fps", "0", "--movie", str(tmp_path / "m.gif"),
                 "--quiet"]) == 2          # the flag's declared range (argparse's usage line)
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--fps: expected a finite number > 0, got '0'" in err[0], err
    damaged = tmp_path / "damaged"
    shutil.copytree(out, damaged)
    pvd = damaged / "cantilever.pvd"
    pvd.write_text(pvd.read_text()[:250])
    _refused(["render", str(damaged), "--quiet"], capsys, "cantilever.pvd is damaged",
             "--resume")
    empty = tmp_path / "empty"
    shutil.copytree(out, empty)
    frames = sorted((empty / "vtu").glob("*.vtm"))
    frames[1].write_bytes(b"")
    _refused(["render", str(empty), "--quiet"], capsys, frames[1].name, "is empty",
             f"--resume {empty}", "cantilever.toml")
    assert not (empty / "frames").exists()


# ---------------------------------------------------------------------------- API = scenario
@pytest.mark.parametrize("make, text", [
    (lambda: fm.CircularSection(math.inf), "radius must be a finite number > 0"),
    (lambda: fm.Material(E=math.inf, rho=1e3), "E must be a finite number > 0"),
    (lambda: fm.Material(E=1e9, rho=math.inf), "rho must be a finite number >= 0"),
    (lambda: fm.BeamStiffness(axial_stiffness=1.0, bending_stiffness=math.nan,
                              mass_per_length=1.0), "bending_stiffness must be a finite"),
    (lambda: fm.NewtonOptions(max_iterations=0), "max_iterations must be an integer >= 1"),
    (lambda: fm.NewtonOptions(relative_tolerance=-1.0), "relative_tolerance must be a finite"),
    (lambda: fm.Model().add_rigid_body(mass=1.0, inertia=(1, 1, 5)), "triangle inequality"),
    (lambda: fm.Model().add_rigid_body(mass=math.inf, inertia=(1, 1, 1)), "mass must be a finite"),
    (lambda: fm.simulate(fm.Model(), t_end=0.01, dt=1e-3), "the model is empty"),
])
def test_api_rejects_what_the_scenario_reader_rejects(make, text):
    with pytest.raises(fm.ModelError, match=text):
        make()


def test_one_inertia_check_for_api_and_scenario(tmp_path, capsys):
    tensor = [[10, 1, 2], [1, 7, 3], [2, 3, 6]]   # principal 3.33, 7.78, 11.89 > 3.33 + 7.78
    with pytest.raises(fm.ModelError, match="triangle inequality"):
        fm.Model().add_rigid_body(mass=1.0, inertia=tensor)
    _refused(["run", SLEEVE, "--set", f"rigid_bodies.sleeve.inertia={tensor}", "--out",
              str(tmp_path / "o"), "-q"], capsys, "rigid_bodies[sleeve].inertia: principal moments",
             "triangle inequality")
    disc = fm.Model().add_rigid_body(mass=2.0, inertia=(0.5, 0.25, 0.25))   # on the bound
    assert np.allclose(np.diag(disc.inertia), (0.5, 0.25, 0.25))


def test_modes_count_is_checked():
    model = fm.Model()
    beam = model.add_beam(fm.line((0, 0, 0), (1, 0, 0), elements=2),
                          section=fm.CircularSection(1e-3), material=fm.Material(E=1e9, rho=1e3))
    model.clamp(beam.first_node)
    with pytest.raises(fm.ModelError, match="n_modes must be an integer >= 1"):
        fm.modes(model, n_modes=-1)
    assert fm.modes(model, n_modes=2).omega.size == 2


# ---------------------------------------------------------------------------- meshes
def _quarter_arc(path, n_points=129):
    import meshio

    a = np.linspace(0.0, math.pi / 2, n_points)
    pts = np.c_[np.cos(a), np.sin(a), np.zeros_like(a)]
    cells = np.c_[np.arange(n_points - 1), np.arange(1, n_points)]
    meshio.write(path, meshio.Mesh(pts, [("line", cells)]))


def test_probe_at_the_nominal_end_of_a_mesh_curve(tmp_path, capsys):
    """A quarter arc sampled by 129 points is 4.9e-11 shorter than pi/2 in its elements:
    s = pi/2 is its end (within the curve's own discretisation tolerance); 1e-3 past is not,
    and the message prints the lengths with all their digits."""
    _quarter_arc(tmp_path / "quarter.vtu")
    scenario = tmp_path / "q.toml"
    scenario.write_text(
        'name = "q"\n[simulation]\nt_end = 0.002\ndt = 1e-3\n[[beams]]\nname = "b"\n'
        'geometry = { mesh = "quarter.vtu" }\nradius = 1e-3\nyoungs_modulus = 1e9\n'
        'density = 1e3\n[[constraints]]\ntype = "clamp"\nbeam = "b"\nnode = "first"\n'
        '[[probes]]\nname = "tip"\ntype = "beam_point"\nbeam = "b"\ns = 1.5707963267948966\n')
    assert main(["run", str(scenario), "--out", str(tmp_path / "o"), "-q"]) == 0
    scenario.write_text(scenario.read_text().replace("s = 1.5707963267948966", "s = 1.5718"))
    line = _refused(["info", str(scenario)], capsys, "probes[tip].s", "1.570796326745416",
                    "got 1.5718")
    assert "tolerance" in line


def test_a_mesh_curve_that_folds_back_is_refused(tmp_path):
    import meshio

    pts = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [1, 0, 0.0]])
    meshio.write(tmp_path / "fold.vtu",
                 meshio.Mesh(pts, [("line", np.array([[0, 1], [1, 2], [2, 3]]))]))
    with pytest.raises(fm.GeometryError, match="folds back on itself"):
        fm.read_curve(tmp_path / "fold.vtu")
    # the same cell twice in one direction (two physical groups) still counts once
    meshio.write(tmp_path / "twice.vtu",
                 meshio.Mesh(pts[:3], [("line", np.array([[0, 1], [1, 2], [1, 2]]))]))
    assert len(fm.read_curve(tmp_path / "twice.vtu").lengths) == 2


def test_library_warnings_are_one_line(capsys):
    from flexmbs.cli import _one_line_warnings

    saved = warnings.showwarning
    try:
        _one_line_warnings()
        with warnings.catch_warnings():
            warnings.simplefilter("always")
            with np.errstate(over="warn"):
                _ = np.float64(1e308) * 10.0
    finally:
        warnings.showwarning = saved
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("flexmbs: warning: RuntimeWarning ("), err
    assert "overflow" in err[0]


def test_a_signal_inside_numba_waits_for_the_next_step():
    """A Ctrl-C that lands while numba compiles or loads a kernel is not raised inside numba
    (an exception there left half-built libraries: a SIGSEGV or a numba traceback in 5 of 40
    interrupted start-ups); it is raised at the next progress report, and a second Ctrl-C
    raises at once. Real signals to this process."""
    import os

    from flexmbs.commands import _common as cli
    from flexmbs.errors import Interrupted

    inside_numba = {"__name__": "numba.core.compiler", "os": os, "signal": signal, "time": time}
    exec("def compile_step():\n"
         "    os.kill(os.getpid(), signal.SIGINT)\n"
         "    for _ in range(1000):\n"
         "        time.sleep(0.001)\n", inside_numba)
    restore = cli.terminate_like_ctrl_c()
    try:
        inside_numba["compile_step"]()                     # deferred: no exception here
        with pytest.raises(Interrupted):
            cli.raise_pending()
        cli.PENDING[0].append("SIGINT")                   # one deferred already ...
        with pytest.raises(Interrupted):                   # ... so the next raises at once
            inside_numba["compile_step"]()
        cli.PENDING[0].clear()
        with pytest.raises(Interrupted):                   # outside numba: at once
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(1.0)
    finally:
        restore()
        cli.PENDING.clear()


def test_an_output_folder_of_more_than_1e5_files_is_refused(tmp_path, capsys):
    """60 001 frames of a beam-only model: 2 files each as a multiblock (over 1e5: refused
    before the folder exists, naming output_interval and merged frames), one each merged
    (allowed: the check passes and the run is stopped by its own size check later, not here)."""
    out = tmp_path / "out"
    argv = ["run", CANTILEVER, "--out", str(out), "-q", "--set", "simulation.t_end=60",
            "--set", "simulation.output_interval=1e-3"]
    _refused(argv, capsys, "simulation.output_interval", "60001 output frames of 2 files",
             'simulation.output_frames = "merged"')
    assert not out.exists()
    from flexmbs.assembly import Assembly
    from flexmbs.io.output import MAX_FILES, check_output
    from flexmbs.io.scenario import load_scenario

    asm = Assembly(load_scenario(CANTILEVER).model)
    assert check_output(tmp_path, "c", asm, output_frames="merged", frames=60001) is not None
    with pytest.raises(fm.ModelError, match="give a larger output_interval$"):
        check_output(tmp_path, "c", asm, output_frames="merged", frames=MAX_FILES + 1)

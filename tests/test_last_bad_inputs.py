"""The last bad inputs of issue "nothing lost": one line each, exit 2, before any file is
written (sizes, time spans, names, damaged files, signals at start-up, clearance geometry)."""

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
    _refused(["render", str(out), "--fps", "0", "--movie", str(tmp_path / "m.gif"), "--quiet"],
             capsys, "--fps", "> 0")
    damaged = tmp_path / "damaged"
    shutil.copytree(out, damaged)
    pvd = damaged / "cantilever.pvd"
    pvd.write_text(pvd.read_text()[:250])
    _refused(["render", str(damaged), "--quiet"], capsys, "cantilever.pvd is damaged",
             "--resume")
    empty = tmp_path / "empty"
    shutil.copytree(out, empty)
    frames = sorted((empty / "vtu").glob("*.vtu"))
    frames[1].write_bytes(b"")
    _refused(["render", str(empty), "--quiet"], capsys, frames[1].name, "is empty")
    assert not (empty / "frames").exists()

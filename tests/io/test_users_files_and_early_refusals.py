"""A user's own files are never written over, what can be checked from the scenario is checked
before the output folder is touched, and the messages name the cause (key or file)."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest

from flexmbs.cli import main
from flexmbs.contact.shapes.superellipse_limits import exponent_limit
from flexmbs.io.folder import OUTPUT_FORMAT, output_summary

ROOT = Path(__file__).resolve().parents[2]
SLOT = str(ROOT / "examples" / "rounded_slot_carriage.toml")

BEAM = """name = "{name}"
[simulation]
t_end = 0.002
dt = 1e-3
[[beams]]
name = "rod"
geometry = {{ line = {{ start = [0.0, 0.0, 0.0], end = [1.0, 0.0, 0.0] }} }}
elements = 2
radius = 5e-3
youngs_modulus = 2.1e11
density = {density}
"""
CLAMP = '[[constraints]]\ntype = "clamp"\nbeam = "rod"\nnode = "first"\n'
BODY = ('[[rigid_bodies]]\nname = "blk"\nmass = 1.0\ninertia = [1e-3, 1e-3, 1e-3]\n'
        "pose = {pose}\n")


def _scenario(tmp_path: Path, *extra: str, name: str = "beam", density: str = "7800.0") -> str:
    path = tmp_path / "s.toml"
    path.write_text(BEAM.format(name=name, density=density) + "".join(extra))
    return str(path)


def _refused(argv: list[str], capsys: pytest.CaptureFixture[str], *needles: str,
             code: int = 2) -> str:
    assert main(argv) == code
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("flexmbs: error: "), err
    for n in needles:
        assert n in err[0], err[0]
    return err[0]


# ----------------------------------------------------------------------------------- item 1
def test_a_users_own_files_are_never_written_over(tmp_path, capsys):
    mine = tmp_path / "mine"
    mine.mkdir()
    files = {"probes.csv": b"my,own,data\n1,2,3\n", "summary.json": b'{"mine": true}\n',
             "notes.txt": b"keep me\n"}
    for name, data in files.items():
        (mine / name).write_bytes(data)
    scenario = _scenario(tmp_path, CLAMP)
    for extra in ([], ["--overwrite"]):
        _refused(["run", scenario, "--out", str(mine), "-q", *extra], capsys,
                 "summary.json", "probes.csv", "not flexmbs output", "--overwrite")
        assert {p.name: p.read_bytes() for p in mine.iterdir()} == files
    # a flexmbs folder is marked, and recognised (and replaced) as such
    out = tmp_path / "out"
    assert main(["run", scenario, "--out", str(out), "-q"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["format"] == OUTPUT_FORMAT and summary["format_version"] == 1
    assert main(["run", scenario, "--out", str(out), "-q"]) == 0


def test_older_flexmbs_folders_are_told_apart_from_a_users(tmp_path):
    old = {"scenario": "cantilever", "flexmbs_version": "0.1.0", "status": "completed",
           "dofs": {"coordinates": 12, "multipliers": 6}, "files": {"probes": "probes.csv"}}
    for content, ours in [(old, True), ({"mine": True}, False), ({**old, "format": "other"}, False),
                          ({k: v for k, v in old.items() if k != "dofs"}, False), ([1, 2], False),
                          ({**old, "format": OUTPUT_FORMAT, "format_version": 1}, True)]:
        (tmp_path / "summary.json").write_text(json.dumps(content))
        assert (output_summary(tmp_path) is not None) == ours, content
    (tmp_path / "summary.json").write_bytes(b"\xf2\x00garbage")
    assert output_summary(tmp_path) is None


# ----------------------------------------------------------------------------------- item 2
@pytest.mark.parametrize("case", ["clamped twice", "long name", "garbage shape mesh"])
def test_refused_before_the_output_folder_is_created(case, tmp_path, capsys):
    out = tmp_path / "OUT"
    if case == "clamped twice":
        scenario = _scenario(tmp_path, CLAMP, CLAMP)
        needles: tuple[str, ...] = ("redundant constraint equation(s)", "clamp 'clamp2'")
    elif case == "long name":
        scenario = _scenario(tmp_path, CLAMP, name="x" * 300)
        needles = ("name:", "300 bytes", "too long", "at most")
    else:
        (tmp_path / "garbage.stl").write_bytes(bytes(range(256)) * 4)
        scenario = _scenario(tmp_path, CLAMP, BODY.format(pose="{ position = [0, 0, 1] }"),
                             'shape = { type = "mesh", file = "garbage.stl" }\n')
        needles = ("body 'blk'", "garbage.stl")
    assert main(["run", scenario, "--out", str(out), "-q"]) == 2
    err = [ln for ln in capsys.readouterr().err.strip().splitlines()
           if not ln.startswith("flexmbs: warning:")]     # meshio's own warning, one line
    assert len(err) == 1 and all(n in err[0] for n in needles), err
    assert not out.exists()


def test_plot_section_without_clearance_joints_leaves_no_file(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    out = tmp_path / "out"
    assert main(["run", _scenario(tmp_path, CLAMP), "--out", str(out), "-q"]) == 0
    before = sorted(p.relative_to(out) for p in out.rglob("*"))
    _refused(["plot", str(out), "--section"], capsys, "no sections.csv", "--section")
    assert sorted(p.relative_to(out) for p in out.rglob("*")) == before


# ----------------------------------------------------------------------------------- item 3
def test_scenario_path_that_is_not_a_regular_file(capsys):
    if not Path("/dev/null").exists():
        pytest.skip("no /dev/null here")
    _refused(["info", "/dev/null"], capsys, "exists but is not a regular file")


def test_zero_up_is_called_zero(tmp_path, capsys):
    scenario = _scenario(tmp_path, CLAMP,
                         BODY.format(pose='{ on_beam = "rod", s = 0.5, up = [0, 0, 0] }'))
    msg = _refused(["info", scenario], capsys, "rigid_bodies[blk].pose", "'up' is zero")
    assert "parallel" not in msg


def test_plot_of_a_garbage_probes_csv_names_the_file(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    out = tmp_path / "out"
    assert main(["run", _scenario(tmp_path, CLAMP), "--out", str(out), "-q"]) == 0
    (out / "probes.csv").write_bytes(b"\xf2\xff\x00\x81garbage\x00\n" * 3)
    _refused(["plot", str(out)], capsys, str(out / "probes.csv"), "not UTF-8")
    (out / "probes.csv").write_text("t,tip\n0,1\n0.1,oops\n")
    _refused(["plot", str(out)], capsys, str(out / "probes.csv"), "line 3", "'tip'")


def test_density_zero_on_a_free_beam_names_the_beam_and_key(tmp_path, capsys):
    """Bad input: refused before the output folder exists (exit 2), naming the key."""
    _refused(["run", _scenario(tmp_path, density="0.0"), "--out", str(tmp_path / "o"), "-q"],
             capsys, "beam 'rod' has no mass", "beams[rod].density")
    assert not (tmp_path / "o").exists()


def test_superellipse_exponent_beyond_the_detector_is_refused_with_the_limit(capsys):
    limit = exponent_limit(4e-3, 2.6e-3)
    assert 40.0 < limit < 50.0       # the slot's: resolution and powers (superellipse_limits)
    _refused(["info", SLOT, "--set", "joints.slot.hole.exponent=1e6"], capsys,
             "joints[slot].hole.exponent = 1e+06", f"<= {int(limit * 10) / 10:g}",
             "128 samples")
    assert main(["info", SLOT, "--set", f"joints.slot.hole.exponent={limit - 0.5}"]) == 0
    capsys.readouterr()


def test_api_hole_checks_the_exponent():
    import flexmbs as fm
    from flexmbs.contact.sections import SuperellipseSection

    with pytest.raises(fm.ModelError, match="exponent = 1e.06.*<= "):
        fm.Hole(SuperellipseSection(a=4e-3, b=2.6e-3, exponent=1e6), length=0.04)
    with pytest.raises(fm.ModelError, match="exponent = 1e.06.*<= "):
        fm.SuperellipseHole(a=4e-3, b=2.6e-3, exponent=1e6, length=0.04)


@pytest.mark.parametrize("coordinate", [1e300, 1e10])
def test_a_body_shape_with_absurd_coordinates_is_one_line(tmp_path, capsys, coordinate):
    """An STL with coordinates beyond float32 (read as inf, with numpy's overflow warnings)
    or of 1e10 m: one line naming the body and the file and the fix, nothing printed before
    it, nothing written."""
    import meshio

    stl = tmp_path / "huge.stl"
    points = np.array([[0.0, 0.0, 0.0], [coordinate, 0.0, 0.0], [0.0, coordinate, 0.0]])
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        meshio.write(str(stl), meshio.Mesh(points, [("triangle", np.array([[0, 1, 2]]))]),
                     binary=True)
    body = BODY.format(pose="{ position = [0.5, 0.0, 0.0] }") + (
        f'shape = {{ type = "mesh", file = "{stl}" }}\n')
    out = tmp_path / "o"
    _refused(["run", _scenario(tmp_path, CLAMP, body), "--out", str(out), "-q"], capsys,
             "body 'blk'", str(stl), "scale")
    assert not out.exists()

"""Post-processing, headless: rendered frames and movies are real images of the model, plots
contain the expected series, the section view draws the ellipse of contacts.csv."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("pyvista")
pytest.importorskip("matplotlib")

import postprocess
from flexmbs.cli import main

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
N_FRAMES = 6            # t = 0, 0.01, ..., 0.05
BACKGROUND_CUT = 235    # a pixel with a channel below this is not the white background
MIN_COVERAGE = 5e-3


def _run_example(directory: Path, scenario: str, *options: str) -> Path:
    assert main(["run", str(EXAMPLES / scenario), "--t-end", "0.05", "--quiet",
                 "--set", "simulation.output_interval=0.01", "--out", str(directory),
                 *options]) == 0
    return directory


@pytest.fixture(scope="module")
def sleeve_run(tmp_path_factory) -> Path:
    return _run_example(tmp_path_factory.mktemp("sleeve"), "curved_beam_sleeve.toml")


@pytest.fixture(scope="module")
def cantilever_run(tmp_path_factory) -> Path:
    return _run_example(tmp_path_factory.mktemp("cantilever"), "cantilever.toml")


def _image(path: Path) -> np.ndarray:
    import imageio.v3 as iio

    return np.asarray(iio.imread(path))


def _ink(img: np.ndarray) -> np.ndarray:
    return np.any(img[..., :3] < BACKGROUND_CUT, axis=-1)


def _contact_rows(directory: Path) -> list[dict]:
    with open(directory / "contacts.csv", newline="", encoding="utf-8") as f:
        return list(csv.DictReader(f))


# ------------------------------------------------------------------------------------ render
def test_render_png_frames_are_real_pictures(sleeve_run):
    """One PNG per frame, of the window size, not blank: non-background pixels cover > 0.5 % of
    the image and their centroid lies well inside the picture."""
    files = postprocess.render(sleeve_run, png_every=1, window_size=(400, 300), tube_scale=4,
                               progress=False)
    assert len(files) == len(postprocess.read_run(sleeve_run).frames) == N_FRAMES
    for f in files:
        img = _image(f)
        assert img.shape[:2] == (300, 400)
        ink = _ink(img)
        assert ink.mean() > MIN_COVERAGE
        yc, xc = np.argwhere(ink).mean(axis=0)
        assert 0.1 * 300 < yc < 0.9 * 300 and 0.1 * 400 < xc < 0.9 * 400
    every = postprocess.render(sleeve_run, png_every=4, window_size=(200, 150), progress=False)
    assert [p.name[-10:] for p in every] == ["000000.png", "000004.png"]


def test_render_of_merged_frames_is_the_picture_of_multiblock_ones(sleeve_run, tmp_path):
    """The same run with merged frames (one grid each, parts told apart by ``block_id``):
    every frame renders as the multiblock's, bore outlines and contact arrows included."""
    merged = _run_example(tmp_path / "merged", "curved_beam_sleeve.toml",
                          "--output-frames", "merged")
    shots = {}
    for run in (sleeve_run, merged):
        shots[run] = postprocess.render(run, png_every=1, frames=[0, -1], window_size=(400, 300),
                                        tube_scale=4, progress=False)
    assert len(shots[merged]) == len(shots[sleeve_run]) == 2
    import pyvista as pv

    from postprocess.render import _block  # what render draws of each part

    for (_, fa), (_, fb) in zip(postprocess.read_run(sleeve_run).frames,
                                postprocess.read_run(merged).frames, strict=True):
        ga, gb = pv.read(str(fa)), pv.read(str(fb))
        for part in (0, 1, 2, 4):                   # beams, bodies, contacts, bore outlines
            pa, pb = _block(ga, part), _block(gb, part)
            assert pa is not None and pb is not None, part
            assert (pa.n_points, pa.n_cells > 0) == (pb.n_points, pb.n_cells > 0), part
            np.testing.assert_allclose(pa.bounds, pb.bounds, rtol=0, atol=1e-12)
    for a, b in zip(shots[sleeve_run], shots[merged], strict=True):
        ia, ib = _image(a).astype(float), _image(b).astype(float)
        assert _ink(ia).mean() > MIN_COVERAGE
        differ = np.abs(ia[..., :3] - ib[..., :3]).max(axis=-1) > 30
        assert differ.mean() < 1e-3, (a.name, differ.sum())


def test_render_tube_lies_where_the_beam_is(cantilever_run):
    """Front view (xz) of the horizontal cantilever: the tube spans most of the image width in a
    narrow band around the middle row (the camera frames the whole motion); the scalar bar and
    the time label are excluded by looking at the middle of the picture only."""
    (png,) = postprocess.render(cantilever_run, png_every=1, frames=[-1], camera="xz",
                                color_by="displacement", window_size=(480, 320), tube_scale=3,
                                progress=False)
    ink = _ink(_image(png))[60:240]             # between the label and the scalar bar
    rows, cols = np.nonzero(ink)
    assert ink.mean() > MIN_COVERAGE
    assert cols.max() - cols.min() > 0.5 * 480
    assert 60 + rows.mean() == pytest.approx(160, abs=40)
    assert rows.max() - rows.min() < 40


def test_render_mp4_and_gif_have_one_frame_per_output(sleeve_run, tmp_path):
    import imageio.v2 as imageio
    import imageio.v3 as iio

    mp4 = tmp_path / "m.mp4"
    assert postprocess.render(sleeve_run, movie=mp4, window_size=(320, 240), progress=False) \
        == [mp4]
    reader = imageio.get_reader(mp4)
    assert reader.count_frames() == N_FRAMES
    frame = reader.get_data(N_FRAMES - 1)
    reader.close()
    assert frame.shape[:2] == (240, 320)
    assert frame.std() > 1.0 and _ink(frame).mean() > MIN_COVERAGE
    gif = tmp_path / "m.gif"
    postprocess.render(sleeve_run, movie=gif, window_size=(320, 240), camera="xz",
                       progress=False)
    frames = iio.imread(gif, index=None)
    assert frames.shape[0] == N_FRAMES and frames.shape[1:3] == (240, 320)
    assert frames.std() > 1.0


def test_render_rejects_bad_options(sleeve_run, tmp_path):
    with pytest.raises(ValueError, match=r"\.mp4 or \.gif"):
        postprocess.render(sleeve_run, movie=tmp_path / "m.avi", progress=False)
    with pytest.raises(ValueError, match="unknown beam field 'nope'.*axial_strain"):
        postprocess.render(sleeve_run, color_by="nope", progress=False)
    with pytest.raises(ValueError, match="camera must be one of"):
        postprocess.render(sleeve_run, camera="top", frames=[0], progress=False)
    with pytest.raises(FileNotFoundError, match="not found"):
        postprocess.render(tmp_path / "missing", progress=False)


# ------------------------------------------------------------------------------------- plots
def test_plots_contain_the_expected_series(sleeve_run, cantilever_run):
    from postprocess.plots import make_figures

    run = postprocess.read_run(sleeve_run)
    figs = make_figures(run)
    assert set(figs) == {"probe_sleeve_s", "probe_lowest_point", "probe_contact_force",
                         "energies", "contacts"}
    ax = figs["probe_lowest_point"].axes[0]
    assert [ln.get_label() for ln in ax.lines] == ["lowest_point_x", "lowest_point_y",
                                                   "lowest_point_z"]
    np.testing.assert_array_equal(ax.lines[2].get_ydata(), run.probes["lowest_point_z"])
    assert [ln.get_label() for ln in figs["energies"].axes[0].lines] == ["energy"]
    rows = _contact_rows(sleeve_run)
    force_ax, count_ax = figs["contacts"].axes
    assert {ln.get_label() for ln in force_ax.lines} == \
        {f"sleeve s{s}" for s in {int(r["section"]) for r in rows}}
    per_time = [sum(float(r["t"]) == t for r in rows) for t in run.probes["t"]]
    np.testing.assert_array_equal(count_ax.lines[0].get_ydata(), per_time)
    s0 = next(ln for ln in force_ax.lines if ln.get_label() == "sleeve s0")
    f0 = [sum(float(r["normal_force"]) for r in rows
              if int(r["section"]) == 0 and float(r["t"]) == t) for t in run.probes["t"]]
    np.testing.assert_allclose(s0.get_ydata(), f0, rtol=1e-12)

    other = postprocess.read_run(cantilever_run)        # --compare: a second run overlaid
    both = make_figures(run, other)
    labels = [ln.get_label() for ln in both["energies"].axes[0].lines]
    assert labels == [f"energy ({sleeve_run.name})", f"energy ({cantilever_run.name})"]
    assert both["energies"].axes[0].lines[1].get_linestyle() == "--"
    assert "probe_tip" in both and len(both["probe_tip"].axes[0].lines) == 3
    assert len(both["contacts"].axes[1].lines) == 2     # active points of both runs
    same = make_figures(run, run)
    assert len({ln.get_label() for ln in same["probe_sleeve_s"].axes[0].lines}) == 2

    import matplotlib.pyplot as plt

    plt.close("all")
    written = postprocess.plot(sleeve_run, compare=cantilever_run)
    assert {p.suffix for p in written} == {".png", ".svg"}
    assert all(p.is_file() and p.parent == sleeve_run / "figures" for p in written)
    with pytest.raises(ValueError, match="unknown figure format"):
        postprocess.plot(sleeve_run, formats=("jpg",))


# ----------------------------------------------------------------------------- section view
def test_section_view_draws_the_ellipse_of_contacts_csv(sleeve_run):
    """At a time and section in contact, the drawn ellipse has the a, b of contacts.csv (its
    points lie between b and a from the drawn centre), Q sits on the drawn bore, and
    |Q - P| = b + gap (contacts.csv consistency)."""
    from postprocess.section import section_figure

    rows = _contact_rows(sleeve_run)
    row = rows[-1]
    t, sec = float(row["t"]), int(row["section"])
    fig, st = section_figure(sleeve_run, joint="sleeve", section=sec, time=t + 1e-4)
    assert (st.t, st.section, st.ab_source) == (t, sec, "contacts.csv")
    assert (st.a, st.b) == (float(row["a"]), float(row["b"]))
    ax = fig.axes[0]
    ell = next(ln for ln in ax.lines if ln.get_label().startswith("beam section"))
    centre = next(ln for ln in ax.lines if ln.get_label() == "ellipse centre r_I")
    c = np.array([centre.get_xdata()[0], centre.get_ydata()[0]])
    d = 1e-3 * np.hypot(ell.get_xdata() - c[0], ell.get_ydata() - c[1])     # drawn in mm
    assert d.max() == pytest.approx(st.a, rel=1e-9)
    assert d.min() == pytest.approx(st.b, rel=1e-5)
    f = float(ax.get_title().split("×")[1].split()[0])
    assert f == pytest.approx(0.5 * st.R / (st.R - st.b), rel=1e-3)      # default factor
    bore = 1e-3 * (st.b + f * (st.R - st.b))
    q = next(ln for ln in ax.lines if ln.get_label() == "Q (hole point)")
    assert 1e-6 * math.hypot(q.get_xdata()[0], q.get_ydata()[0]) == pytest.approx(bore, rel=1e-3)
    for gap, dist in zip(st.gaps, st.distances, strict=True):
        assert dist == pytest.approx(st.b + gap, abs=1e-12)
    import matplotlib.pyplot as plt

    plt.close(fig)
    path = postprocess.section_view(sleeve_run, joint="sleeve", section=sec, time=t,
                                    exaggeration=10, radius=3e-3)
    assert path == sleeve_run / "figures" / f"section_sleeve_{sec}.png" and path.is_file()


def test_section_view_needs_sections_csv(sleeve_run, cantilever_run):
    with pytest.raises(ValueError, match="no clearance joint 'other'"):
        postprocess.section_view(sleeve_run, joint="other")
    with pytest.raises(ValueError, match="section 99 of joint 'sleeve' not found"):
        postprocess.section_view(sleeve_run, section=99)
    with pytest.raises(FileNotFoundError, match="no sections.csv.*ey_a, ez_a"):
        postprocess.section_view(cantilever_run)


# ----------------------------------------------------------------------------------------- CLI
def test_cli_render_and_plot(sleeve_run, tmp_path, capsys, monkeypatch):
    assert main(["render", str(sleeve_run), "--png-every", "3", "--size", "320x240",
                 "--camera", "1,-2,1", "--quiet"]) == 0
    assert main(["plot", str(sleeve_run), "--format", "png", "--section", "--section-index", "0",
                 "--time", "0.02"]) == 0
    assert (sleeve_run / "figures" / "section_sleeve_0.png").is_file()
    assert main(["plot", str(tmp_path / "nothing")]) == 2
    assert main(["render", str(sleeve_run), "--size", "big"]) == 2
    capsys.readouterr()
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a: None if name == "pyvista" else real(name, *a))
    assert main(["render", str(sleeve_run)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and 'pip install -e ".[render]"' in err


def test_section_view_draws_a_non_circular_bore(tmp_path):
    """A turned rounded-square bore (superellipse n = 4, 0.3 rad): summary.json records the
    section, the view draws the registered shape's own wall (its undrawn points satisfy the
    turned superellipse equation) and puts Q on the drawn wall."""
    from flexmbs.cli import main
    from postprocess.section import section_figure

    out = tmp_path / "rounded"
    hole = ('joints.sleeve.hole={shape="superellipse", a=2.5e-3, b=2.5e-3, exponent=4.0, '
            'angle=0.3, length=0.04, sections=9}')
    assert main(["run", str(EXAMPLES / "curved_beam_sleeve.toml"), "--t-end", "0.003", "-q",
                 "--out", str(out), "--set", hole]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["hole_sections"]["sleeve"]["shape"] == "superellipse"
    fig, st = section_figure(out, joint="sleeve", section=0, exaggeration=1.0)
    psi = np.linspace(0, 2 * np.pi, 50)
    W = st.wall(psi)
    c, s = math.cos(0.3), math.sin(0.3)
    yl, zl = c * W[:, 0] + s * W[:, 1], -s * W[:, 0] + c * W[:, 1]
    assert np.allclose((yl / 2.5e-3) ** 4 + (zl / 2.5e-3) ** 4, 1.0, atol=1e-12)
    ax = fig.axes[0]
    wall = next(ln for ln in ax.lines if ln.get_label().startswith("bore: superellipse"))
    assert st.Q, "the resting sleeve touches the bore"
    q = next(ln for ln in ax.lines if ln.get_label() == "Q (hole point)")
    Qd = 1e-3 * np.array([q.get_xdata()[0], q.get_ydata()[0]])
    drawn = 1e-3 * np.stack([wall.get_xdata(), wall.get_ydata()], axis=1)
    assert np.min(np.linalg.norm(drawn - Qd, axis=1)) < 2e-5     # on the drawn wall (f = 1)
    import matplotlib.pyplot as plt

    plt.close(fig)
    # where the contacts sit: the angles of the section-0 contacts at that time are the view's
    joint, t, sec, ang, force = postprocess.contact_angles(out, "sleeve")
    sel = (t == st.t) & (sec == 0)
    expect = sorted(math.degrees(math.atan2(Q[1], Q[0])) for Q in st.Q)
    assert sorted(ang[sel]) == pytest.approx(expect, abs=1e-9)
    assert postprocess.contact_angles_view(out, "sleeve").is_file()


def test_contact_force_along_a_bore_of_many_sections(tmp_path):
    """A wire held in a 90° curved tube (examples/capstan.py, sections 2 mm apart): the figure
    of the contact force along the bore draws, at the last output time, each section's force
    of contacts.csv (summed over its points) at its distance along the bore, and the same
    forces over time as a map; the time-history figure drops its per-section legend."""
    import warnings

    import flexmbs as fm
    from postprocess.plots import MANY_SECTIONS, make_figures
    from tests.conftest import load_example

    cap = load_example("capstan")
    model, _, _ = cap.build(math.pi / 2, 0.0, motion=fm.Constant(0.0))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fm.simulate(model, t_end=0.03, dt=2e-4, output_interval=0.01, out=tmp_path / "tube",
                    integrator=fm.GeneralizedAlpha(rho_inf=0.8))
    run = postprocess.read_run(tmp_path / "tube")
    rec = run.summary["hole_sections"]["tube"]
    n, spacing = rec["sections"], rec["length"] / (rec["sections"] - 1)
    assert n > MANY_SECTIONS
    figs = make_figures(run)
    upper, lower = figs["contact_along_tube"].axes[:2]
    last = upper.lines[-1]
    t_last = float(run.probes["t"][-1]) if "t" in run.probes else max(float(r["t"]) for r in
                                                                      run.contacts)
    assert last.get_label() == f"t = {t_last:.4g} s"
    rows = _contact_rows(tmp_path / "tube")
    expected = np.zeros(n)
    for r in rows:
        if float(r["t"]) == t_last:
            expected[int(r["section"])] += float(r["normal_force"])
    assert np.count_nonzero(expected) > MANY_SECTIONS          # the wire lies along the arc
    np.testing.assert_allclose(last.get_xdata(), np.arange(n) * spacing, rtol=1e-12)
    np.testing.assert_allclose(last.get_ydata(), expected, rtol=1e-12)
    grid = np.asarray(lower.collections[0].get_array()).reshape(-1, n)
    np.testing.assert_allclose(grid[-1], expected, rtol=1e-12)
    assert figs["contacts"].axes[0].get_legend() is None
    import matplotlib.pyplot as plt

    plt.close("all")


def test_probes_against_another_column(sleeve_run, tmp_path, capsys):
    """``--against COLUMN``: every probe figure (and the energies) takes that probes.csv column
    as abscissa, in files of their own; an unknown column is one line naming the known ones,
    before anything is written."""
    from postprocess.plots import make_figures

    run = postprocess.read_run(sleeve_run)
    figs = make_figures(run, against="sleeve_s")
    ax = figs["probe_lowest_point_vs_sleeve_s"].axes[0]
    np.testing.assert_array_equal(ax.lines[2].get_xdata(), run.probes["sleeve_s"])
    np.testing.assert_array_equal(ax.lines[2].get_ydata(), run.probes["lowest_point_z"])
    assert ax.get_xlabel() == "sleeve_s" and "energies_vs_sleeve_s" in figs
    import matplotlib.pyplot as plt

    plt.close("all")
    before = sorted((sleeve_run / "figures").glob("*")) if (sleeve_run / "figures").exists() else []
    assert main(["plot", str(sleeve_run), "--against", "depth_x"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--against depth_x: no such column" in err[0] and "sleeve_s" in err[0]
    after = sorted((sleeve_run / "figures").glob("*")) if (sleeve_run / "figures").exists() else []
    assert after == before


def test_a_reaction_probe_is_drawn_as_its_force_and_its_moment(tmp_path):
    """A reaction probe's six columns (``_fx`` … ``_mz``) make two figures, the force and the
    moment (one unit each), not six."""
    from postprocess.data import Run

    t = np.linspace(0.0, 1.0, 3)
    cols = {f"feed_{k}{a}": t * (i + 1) for i, (k, a) in
            enumerate((k, a) for k in "fm" for a in "xyz")}
    run = Run(tmp_path, "r", {}, [], {"t": t, **cols, "tip_x": t, "tip_y": t, "tip_z": t})
    groups = run.probe_groups()
    assert groups["feed_force"] == ["feed_fx", "feed_fy", "feed_fz"]
    assert groups["feed_moment"] == ["feed_mx", "feed_my", "feed_mz"]
    assert groups["tip"] == ["tip_x", "tip_y", "tip_z"] and len(groups) == 3

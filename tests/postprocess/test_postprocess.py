"""Post-processing, headless: rendered frames and movies are real images of the model, plots
contain the expected series, the section view draws the ellipse of sections.csv."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import postprocess
from flexmbs.cli import main

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


@pytest.fixture(scope="module")
def sleeve_run(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("sleeve")
    assert main(["run", str(EXAMPLES / "curved_beam_sleeve.toml"), "--t-end", "0.02", "--quiet",
                 "--set", "simulation.output_interval=0.005", "--out", str(d)]) == 0
    return d


def _image(path: Path) -> np.ndarray:
    import imageio.v3 as iio

    return np.asarray(iio.imread(path))


def test_render_png_frames_are_real_pictures(sleeve_run):
    """One PNG per frame, of the window size, not blank: non-background pixels cover > 0.5 % of
    the image (the tube and the sleeve) and their centroid lies well inside the picture."""
    files = postprocess.render(sleeve_run, png_every=1, window_size=(400, 300), tube_scale=4,
                               progress=False)
    run = postprocess.read_run(sleeve_run)
    assert len(files) == len(run.frames) == 5
    for f in files:
        img = _image(f)
        assert img.shape[:2] == (300, 400)
        ink = np.any(img[..., :3] < 235, axis=-1)     # background is white
        assert ink.mean() > 5e-3
        yc, xc = np.argwhere(ink).mean(axis=0)
        assert 0.1 * 300 < yc < 0.9 * 300 and 0.1 * 400 < xc < 0.9 * 400


def test_render_gif_has_one_frame_per_output(sleeve_run, tmp_path):
    movie = tmp_path / "m.gif"
    files = postprocess.render(sleeve_run, movie=movie, window_size=(320, 240), progress=False)
    assert files == [movie]
    import imageio.v3 as iio

    frames = iio.imread(movie, index=None)
    assert frames.shape[0] == 5 and frames.shape[1:3] == (240, 320)
    assert frames.std() > 1.0   # not a uniform image


def test_render_rejects_bad_options(sleeve_run, tmp_path):
    with pytest.raises(ValueError, match=r"\.mp4 or \.gif"):
        postprocess.render(sleeve_run, movie=tmp_path / "m.avi2", progress=False)
    with pytest.raises(FileNotFoundError, match="not found"):
        postprocess.render(tmp_path / "missing", progress=False)


def test_plots_contain_the_expected_series(sleeve_run):
    from postprocess.plots import make_figures

    run = postprocess.read_run(sleeve_run)
    figs = make_figures(run)
    assert {"probe_sleeve_s", "probe_lowest_point", "probe_contact_force", "probe_energy",
            "contacts"} <= set(figs)
    ax = figs["probe_lowest_point"].axes[0]
    assert [ln.get_label() for ln in ax.lines] == ["lowest_point_x", "lowest_point_y",
                                                   "lowest_point_z"]
    np.testing.assert_allclose(ax.lines[2].get_ydata(), run.probes["lowest_point_z"])
    sections_in_contact = {int(c["section"]) for c in run.contacts}
    force_ax, count_ax = figs["contacts"].axes
    assert len(force_ax.lines) == len(sections_in_contact)
    assert count_ax.lines[0].get_ydata().max() >= 1
    both = make_figures(run, run)      # --compare overlays a second run
    assert len(both["probe_sleeve_s"].axes[0].lines) == 2
    written = postprocess.plot(sleeve_run, formats=("png",))
    assert all(p.is_file() and p.suffix == ".png" for p in written)


def test_section_view_draws_the_ellipse_of_sections_csv(sleeve_run):
    """The drawn ellipse has the semi-axes a, b of sections.csv (distance of its points from the
    drawn centre ranges from b to a, 1e-9 relative)."""
    run = postprocess.read_run(sleeve_run)
    row = next(r for r in run.sections if int(r["section"]) == 0 and float(r["t"]) == 0.02)
    path, fig = postprocess.section_view(sleeve_run, joint="sleeve", section=0, time=0.02)
    assert path.is_file()
    ax = fig.axes[0]
    ell = next(ln for ln in ax.lines if ln.get_label().startswith("beam section"))
    centre = next(ln for ln in ax.lines if ln.get_label() == "ellipse centre r_I")
    c = np.array([centre.get_xdata()[0], centre.get_ydata()[0]])
    d = np.hypot(ell.get_xdata() - c[0], ell.get_ydata() - c[1])
    assert d.max() == pytest.approx(float(row["a"]), rel=1e-9)
    assert d.min() == pytest.approx(float(row["b"]), rel=1e-6)
    with pytest.raises(ValueError, match="no clearance joint 'other'"):
        postprocess.section_view(sleeve_run, joint="other")


def test_cli_render_and_plot(sleeve_run, tmp_path):
    assert main(["render", str(sleeve_run), "--png-every", "2", "--size", "320x240",
                 "--quiet"]) == 0
    assert main(["plot", str(sleeve_run), "--format", "png", "--section"]) == 0
    assert (sleeve_run / "figures" / "section_sleeve_4.png").is_file()
    assert main(["plot", str(tmp_path / "nothing")]) == 2

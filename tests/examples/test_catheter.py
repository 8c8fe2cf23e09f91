"""examples/catheter.py and .toml (issue 53, item 4): a catheter advanced over a guide wire
inside a rigid 3-D vessel, the two pushed in turns: a beam in a flexible tube in a rigid bore.

Checked on the results, independently of the contact code's own bookkeeping:
- the three levels stay nested: every point of the catheter within the vessel's clearance
  (1.2 − 0.8 mm) of the vessel's centre-line, every point of the wire inside the catheter
  within the lumen's (0.45 − 0.3 mm) of the catheter's centre-line, and beyond the catheter's
  tip within the vessel's (1.2 − 0.3 mm), all to the penalty's penetration (5 µm allowed),
  the last TIP_SETBACK radii of each beam to the tip section's setback besides (measured:
  30 µm at 0.24 s for the wire, 12 µm at 0.58 s for the catheter);
- the tips advance along the vessel by the feeders' pushes: the catheter's to 0.3 mm (it is
  stiff and its clearance 0.4 mm); the wire's to 2 mm (it may take the bends' inner or outer
  side: the clearance 0.9 mm times the bends' turn, 1.8 rad, bounds the difference).

The default run goes to 0.6 s (the wire round the first bend, the catheter half way through
its first push: 3 900 steps, about 7 s); ``FLEXMBS_FULL=1`` runs the whole 1.6 s."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.contact._detect import TIP_SETBACK
from tests.conftest import FULL, assert_scenario_is_the_script_s, load_module

ROOT = Path(__file__).resolve().parents[2]
T_END = 1.6 if FULL else 0.6
SLACK = 5e-6                  # the penalty's penetration (forces below 1 N at 5e5 N/m: 2 µm)


@pytest.fixture(scope="module")
def example():
    return load_module(ROOT / "examples" / "catheter.py", "catheter_example")


@pytest.fixture(scope="module")
def run(example):
    return example.advance(T_END)


def _polyline(points: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Distance of each point x (m, 3) to the polyline and the arc length of its projection."""
    a, b = points[:-1], points[1:]
    seg = b - a
    length = np.linalg.norm(seg, axis=1)
    s0 = np.r_[0.0, np.cumsum(length)][:-1]
    u = np.clip(np.einsum("mij,ij->mi", x[:, None, :] - a[None], seg) / length**2, 0.0, 1.0)
    d = np.linalg.norm(x[:, None, :] - (a[None] + u[..., None] * seg[None]), axis=2)
    k = np.argmin(d, axis=1)
    rows = np.arange(x.shape[0])
    return d[rows, k], s0[k] + u[rows, k] * length[k]


def _vessel(example) -> np.ndarray:
    path = fm.read_curve(example.VESSEL_MESH, group="vessel")
    return np.array([path.frame_at(s)[0] for s in np.linspace(0.0, path.total_length, 2301)])


def _samples(res, beam, spacing: float) -> np.ndarray:
    """(outputs, samples, 3): the beam's centre-line every ``spacing`` of reference arc."""
    length = beam.centerline.total_length
    return np.stack([res.beam_point(beam, s) for s in np.linspace(0.0, length,
                                                                    round(length / spacing) + 1)],
                    axis=1)


def test_the_three_levels_stay_nested(example, run) -> None:
    res = run["result"]
    model_beams = {b.name: b for b in res.assembly.model.beams}
    wire, catheter = model_beams["wire"], model_beams["catheter"]
    vessel = _vessel(example)
    cath = _samples(res, catheter, 2.5e-4)
    wire_pts = _samples(res, wire, 1e-3)
    c_vessel = example.VESSEL_R - example.CATHETER_R
    c_lumen = example.LUMEN_R - example.WIRE_R
    c_wire = example.VESSEL_R - example.WIRE_R
    inside_checked = beyond_checked = 0

    def tip_allowance(beam, radius: float) -> np.ndarray:
        """The stretch the tip section leaves (TIP_SETBACK radii behind the end) may go
        θ TIP_SETBACK r past the wall at an angle θ (design notes, "The free tip"; θ < 0.3 rad
        here): that allowance for the samples in it, 0 for the others."""
        back = np.linspace(beam.centerline.total_length, 0.0, cath.shape[1] if beam is catheter
                           else wire_pts.shape[1])
        return np.where(back <= TIP_SETBACK * radius + 1e-12, 0.3 * TIP_SETBACK * radius, 0.0)

    for k in range(res.t.size):
        d, s = _polyline(vessel, cath[k])
        in_vessel = s > 1e-4                      # past the vessel's mouth (x = 0)
        assert (d[in_vessel] - tip_allowance(catheter, example.CATHETER_R)[in_vessel]).max() \
            <= c_vessel + SLACK, (res.t[k], d[in_vessel].max())
        d_l, s_l = _polyline(cath[k], wire_pts[k])
        total = np.linalg.norm(np.diff(cath[k], axis=0), axis=1).sum()
        inside = (s_l > 1e-4) & (s_l < total - 1e-4)
        assert d_l[inside].max() <= c_lumen + SLACK, (res.t[k], d_l[inside].max())
        inside_checked += int(inside.sum())
        d_w, s_w = _polyline(vessel, wire_pts[k])
        beyond = (s_l >= total - 1e-4) & (s_w > 1e-4)  # past the catheter's tip, in the vessel
        if beyond.any():
            allowed = c_wire + SLACK + tip_allowance(wire, example.WIRE_R)[beyond]
            assert np.all(d_w[beyond] <= allowed), (res.t[k], d_w[beyond].max())
            beyond_checked += int(beyond.sum())
    assert inside_checked > 1000 and beyond_checked > 100


def test_the_tips_advance_along_the_vessel_by_the_pushes(example, run) -> None:
    vessel = _vessel(example)
    t = run["t"]

    def arc(tip: np.ndarray) -> np.ndarray:
        return _polyline(vessel, tip)[1]

    wire_pushes = fm.Moves(example.WIRE_PUSHES)
    catheter_pushes = fm.Moves(example.CATHETER_PUSHES)
    wire_arc, cath_arc = arc(run["wire_tip"]), arc(run["catheter_tip"])
    for k in range(t.size):
        assert cath_arc[k] - cath_arc[0] == pytest.approx(catheter_pushes(t[k]), abs=3e-4), t[k]
        assert wire_arc[k] - wire_arc[0] == pytest.approx(wire_pushes(t[k]), abs=2e-3), t[k]
    # the wire is round the first bend (60° from 20 mm on) by 0.4 s
    assert wire_arc[np.argmin(abs(t - 0.4))] > 0.04


def test_the_scenario_file_is_the_script_s_model_and_runs(example, tmp_path) -> None:
    """examples/catheter.toml is what the script writes (edit one source), it builds the
    Python model, and a short run on the command line gives the Python run's tips."""
    from flexmbs.cli import main

    toml = ROOT / "examples" / "catheter.toml"
    assert_scenario_is_the_script_s(toml, example)
    out = tmp_path / "out"
    assert main(["run", str(toml), "--out", str(out), "-q", "--t-end", "0.1"]) == 0
    sys.path.insert(0, str(ROOT))
    try:
        from postprocess.catheter import catheter_figure, crossings
        from postprocess.data import read_run
    finally:
        sys.path.remove(str(ROOT))
    done = read_run(out)
    probes = done.probes
    short = example.advance(0.1)
    np.testing.assert_allclose(np.c_[probes["wire_tip_x"], probes["wire_tip_y"],
                                     probes["wire_tip_z"]], short["wire_tip"], atol=1e-9)
    np.testing.assert_allclose(probes["wire_feeder_fx"], short["wire_force"], atol=1e-6)
    # the figure's centre-lines from sections.csv: the wire's crossings of the vessel's
    # sections lie on the wire (the Python run's, by arc length ~ x at 0.1 s: a straight wire)
    origins, centre = crossings(done, "wire_in_vessel", 0.1)
    wire = next(b for b in short["result"].assembly.model.beams if b.name == "wire")
    for p in centre[::5]:
        s = p[0] - example.WIRE_START - probes["wire_tip_x"][-1] + example.WIRE_TIP
        on_wire = short["result"].beam_point(wire, s)[-1]
        assert np.linalg.norm(on_wire - p) < 1e-6
    assert np.all(np.linalg.norm(origins - centre, axis=1) < example.VESSEL_R)
    import matplotlib.pyplot as plt

    fig = catheter_figure(done, times=(0.05, 0.1), pushes={"wire": example.WIRE_PUSHES})
    assert len(fig.axes) == 2
    plt.close(fig)

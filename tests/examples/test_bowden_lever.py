"""examples/bowden_lever.py and .toml (issue 53, item 3): a Bowden cable turning a lever
through a housing bent by Θ = 90°, the near end pulled 2.5 mm and let back.

The lever's statics k φ = a cos φ T_out, with the capstan law while the wire slides:
T_out = T_pull e^{−μΘ} pulling (0.7304 at μ = 0.2), e^{+μΘ} letting back (1.3691). Measured
(0.035–0.095 s and 0.12–0.175 s, past the wire's breaking loose): 0.7297 (−0.10 %) and
1.3617–1.3654 (−0.5 % to −0.3 %). The input travels cΘ = 471.2 µm before the lever moves
(the wire taken from the housing's centre-line to the bend's inner wall): the pulled end's
travel less the arm's a sin φ and the wire's stretch (T_pull along the exit straight,
T_pull ρ (1 − e^{−μΘ})/μ along the bend, T_out along the entry straight, over EA) is
470.3 µm (−0.2 %; the contacts' penetration at ~100 N, 1.4 µm, shortens the path by 2 µm).
The run (0.18 s) takes 10 s CPU."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import assert_scenario_is_the_script_s, load_module

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def example():
    return load_module(ROOT / "examples" / "bowden_lever.py", "bowden_lever_example")


def test_the_lever_turns_by_the_pull_less_the_capstan_loss(example) -> None:
    out = example.run()
    t, pull, t_out, phi = out["t"], out["pull"], out["t_out"], out["phi"]
    mu, wrap = 0.2, example.WRAP
    pulling, letting_back = (t > 0.035) & (t < 0.095), (t > 0.12) & (t < 0.175)
    assert pulling.sum() >= 20 and letting_back.sum() >= 20
    assert pull[pulling].max() > 100.0                    # T ρ² ≫ EI: the capstan regime
    np.testing.assert_allclose(t_out[pulling] / pull[pulling], math.exp(-mu * wrap), rtol=5e-3)
    np.testing.assert_allclose(t_out[letting_back] / pull[letting_back], math.exp(mu * wrap),
                               rtol=1e-2)
    # the backlash: the input's travel before the lever moves is cΘ
    EA = example.STEEL.E * math.pi * example.WIRE_R ** 2
    stretch = (example.STRAIGHT * (pull + t_out)
               + pull * example.RHO * (1 - math.exp(-mu * wrap)) / mu) / EA
    take_up = out["u_in"] - example.ARM * np.sin(phi) - stretch
    c_theta = (example.BORE - example.WIRE_R) * wrap
    np.testing.assert_allclose(take_up[pulling], c_theta, rtol=1e-2)
    assert np.abs(phi[t < 0.009]).max() < 1e-4           # the lever stands while it is taken up


def test_the_scenario_file_is_the_script_s_model_and_runs(example, tmp_path) -> None:
    """examples/bowden_lever.toml is what the script writes (edit one source), it builds the
    model the Python builder does, and a short run on the CLI writes what the figures read."""
    from flexmbs.cli import main

    toml = ROOT / "examples" / "bowden_lever.toml"
    assert_scenario_is_the_script_s(toml, example)

    out = tmp_path / "out"
    assert main(["run", str(toml), "--out", str(out), "-q", "--set", "simulation.t_end=0.03",
                 "--set", "joints.tube.contact.friction=0"]) == 0
    sys.path.insert(0, str(ROOT))
    try:
        from postprocess.bowden import lever_angle, lever_figure
        from postprocess.data import read_run
    finally:
        sys.path.remove(str(ROOT))
    run = read_run(out)
    phi = lever_angle(run)
    late = run.probes["t"] > 0.02
    # frictionless: the pull reaches the lever whole, k φ = a cos φ F (1 %)
    np.testing.assert_allclose(example.SPRING * phi[late] / (example.ARM * np.cos(phi[late])),
                               run.probes["pull_fx"][late], rtol=1e-2)
    import matplotlib.pyplot as plt

    fig = lever_figure({"μ = 0": run}, stiffness=example.SPRING, arm=example.ARM,
                       wrap=example.WRAP, mu={"μ = 0": 0.0}, take_up=0.3e-3 * example.WRAP)
    assert len(fig.axes) == 2
    plt.close(fig)

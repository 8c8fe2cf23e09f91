"""The Bowden cable (issue 53, item 3): the inner wire pulled through a housing that is a beam
(``fm.TubeJoint``), the housing held along a bend of Θ by a clamp at every node
(examples/capstan.py, ``housing=True``). With friction that sticks (μ = 0.2) the pull follows
the capstan law T_out / T_in = e^{μΘ}, and the housing's supports carry only what the wire
puts on it: their sum is the force of the contacts on the housing, that is the load and the
pull on the wire reversed (the wire's inertia and damping aside).

Measured (0.1 s, Θ = 90°): pull 136.773 N against 136.911 N (−0.10 %, the rigid bore's figure
to five digits); the supports' sum and the wire's external forces cancel to 2.4e-6 N."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.conftest import FULL, load_example


@pytest.mark.parametrize("wrap", [90.0] + ([180.0] if FULL else []))
def test_a_wire_pulled_through_a_bent_housing_follows_the_capstan_law(wrap: float) -> None:
    cap = load_example("capstan")
    out = cap.pull_force(math.radians(wrap), 0.2, t_end=0.1, housing=True)
    late = out["pull"][out["t"] > 0.06]        # the load is in at 0.02 s, the pull from then
    assert late.size >= 5 and np.ptp(late) < 1e-3 * late.mean()     # steady sliding
    assert late.mean() == pytest.approx(out["capstan"], rel=1e-2)
    assert late.mean() / cap.T_LOAD > 1.3      # friction does act (e^{0.2 π/2} = 1.37)

    res = out["result"]
    housing, wire = res.assembly.model.beam("housing"), res.assembly.model.beam("wire")
    supports = sum(res.reaction(f"support{k}", housing)[0] for k in range(housing.n_nodes))
    on_wire = (res.reaction("pull", wire)[0] + res.reaction("pull_line", wire)[0]
               + np.array([0.0, -cap.T_LOAD, 0.0]))
    steady = res.t > 0.06
    assert np.abs(supports[steady]).max() > cap.T_LOAD          # the housing is loaded
    assert np.abs(supports[steady] + on_wire[steady]).max() < 1e-4 * cap.T_LOAD

"""Newton's retreats in the compiled step loop: an iterate the model rejects (a wire's axis
pushed through an eyelet's wall) is halved back towards the last accepted one, as the Python
loop does (``NewtonOptions.retreats``), instead of failing the step at once. (With the held
active set, the default, these iterates do not occur: tests/solvers/test_held_contacts.py;
here it is off.)"""

from __future__ import annotations

import numpy as np
import pytest

import flexmbs as fm
from tests.contact.test_contact_windows import _eyelets


def _pull(retreats: int, compiled: bool = True) -> fm.Result:
    model, _ = _eyelets()
    return fm.simulate(model, t_end=0.14, dt=2e-3, output_interval=0.02, record_energy=False,
                       integrator=fm.GeneralizedAlpha(rho_inf=0.8, compiled=compiled,
                                                      newton=fm.NewtonOptions(
                                                          retreats=retreats, hold_contacts=False)))


def test_the_compiled_loop_retreats_from_a_rejected_iterate():
    """The wire pulled through sagging eyelets has steps whose iterates leave a bore (8
    rejected steps without retreats). With 4 retreats the compiled loop takes other steps
    (it honours the option: before, only the Python loop did), and both loops with retreats
    complete the pull."""
    plain, retreating = _pull(0), _pull(4)
    python = _pull(4, compiled=False)
    assert plain.stats.rejected_steps > 0
    assert (retreating.stats.steps, retreating.stats.newton_iterations) != (
        plain.stats.steps, plain.stats.newton_iterations)
    for res in (plain, retreating, python):
        assert res.t[-1] == np.float64(0.14)
        wire = res.assembly.model.beam("wire0")
        x0 = res.assembly.node_dofs(wire.first_node)[0]
        pulled = fm.Ramp(start=0.0, end=0.2, value=0.03, smooth=True)(0.14)
        assert res.q[-1, x0] - res.q[0, x0] == pytest.approx(pulled, rel=1e-9)

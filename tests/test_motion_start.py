"""A prescribed motion of a beam's node that starts at speed while the beam starts at rest is
an impulse the first step answers with large forces (a damped wire's reaction at t = 0: 918 N
in the Bowden lever with a half sine, 0 without the wire's damping): the run says so once,
at its start, naming the motion; a motion that starts from rest, or a constant, says
nothing."""

from __future__ import annotations

import warnings

import pytest

import flexmbs as fm
from flexmbs.errors import FlexmbsWarning


def _pulled(function: fm.TimeFunction | float) -> fm.Model:
    model = fm.Model(gravity=(0.0, 0.0, 0.0))
    beam = model.add_beam(fm.line((0, 0, 0), (0.1, 0, 0), elements=4), name="wire",
                          section=fm.CircularSection(3e-4), material=fm.Material(E=6e10, rho=6500.0),
                          damping=2e-4)
    model.prescribe(beam.first_node, [0], function, name="feeder")
    model.prescribe(beam.first_node, [1, 2, 4, 5], name="feeder_hold")
    return model


def _warnings(model: fm.Model) -> list[str]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        fm.simulate(model, t_end=2e-3, dt=1e-3, output_interval=2e-3, record_energy=False)
    return [str(w.message) for w in caught if issubclass(w.category, FlexmbsWarning)]


def test_a_motion_that_starts_at_speed_is_named():
    found = [m for m in _warnings(_pulled(fm.Ramp(start=0.0, end=0.1, value=0.01)))
             if "starts at speed" in m]
    assert len(found) == 1
    assert "'feeder'" in found[0] and "beam 'wire' node 0" in found[0]
    assert "rate at t = 0 is 0.1 per s" in found[0] and "smooth = true" in found[0]


@pytest.mark.parametrize("function", [fm.Ramp(start=0.0, end=0.1, value=0.01, smooth=True),
                                      fm.Ramp(start=0.001, end=0.1, value=0.01), 0.0],
                         ids=["smooth", "later", "held"])
def test_a_motion_from_rest_says_nothing(function):
    assert not [m for m in _warnings(_pulled(function)) if "starts at speed" in m]

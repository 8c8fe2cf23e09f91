"""The Bowden cable (issue 53, item 3): the inner wire pulled through a housing that is a beam
(``fm.TubeJoint``), the housing held along a bend of Θ by a clamp at every node
(examples/capstan.py, ``housing=True``). With friction that sticks (μ = 0.2) the pull follows
the capstan law T_out / T_in = e^{μΘ}, and the housing's supports carry only what the wire
puts on it: their sum is the force of the contacts on the housing, that is the load and the
pull on the wire reversed (the wire's inertia and damping aside).

Measured (0.1 s, Θ = 90°): pull 136.773 N against 136.911 N (−0.10 %, the rigid bore's figure
to five digits); the supports' sum and the wire's external forces cancel to 2.4e-6 N.

The push–pull backlash (examples/capstan.py ``backlash_loop``): the housing runs straight for
25 mm, round the 90° bend and straight again; the wire's exit end is driven 0.7 mm out and in
(5 Hz, started from rest), its entry end held by a spring (20 kN/m) to the ground, so the wire
is pulled (up to 4.5 N) and pushed (as much). Pulled, it lies on the bend's inner wall (path
radius ρ − c), pushed on the outer one (ρ + c): at the reversal the output stands while the
input travels the difference of the two paths, 2cΘ = 942.5 µm (c = 0.3 mm). Measured as the
jump of u_in − u_out − f L/EA (the wire's stretch out) between the branches at |f| ≥ 2 N:
941.0 µm (−0.16 %); read off the output (the input's travel between the output stopping and
restarting, ±10 µm): 933.2 µm (−0.99 %). With c = 0.05 mm, 156.9 µm against 157.1 µm (−0.13 %;
off the output 157.0 µm). At Θ = 180° (1.2 mm stroke, FLEXMBS_FULL=1): 1880.9 µm against
1885.0 µm (−0.21 %).
The wire's bending makes the band narrower at low tension: in the bend it lies at a curvature
1/(ρ ∓ c) against its stress-free 1/ρ, a moment EIc/ρ² that tilts its straights at the bend's
ends (by α ≈ EIc/(ρ²TL), L their length), which shortens its path by L α²/2 at each end:
measured −0.57 % at 0.5–1 N, −0.28 % at 1–2 N, −0.15 % at 3–4.5 N (about half the rigid lever's
2(EIc)²/(ρ⁴T²L) over four ends; ∝ c², so −0.04 % at c = 0.05 mm at 0.2 N). The band is
geometric: friction (μ = 0.2) moves it by +0.10 % (942.0 µm), the wire's stretch being
1.4 µm/N; a stroke of 2.5 Hz at half the step gives 941.0 µm again. CPU: 13 s for the band and
the small bore, 8 s each for friction and the slower stroke, 43 s at 180°."""

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


def _band_at(out: dict, lo: float, hi: float = math.inf) -> float:
    """The jump of u_in − u_out − f L/EA between the pulled and pushed branches, at lo < |f| < hi."""
    slip = out["u_in"] - out["u_out"] - out["compliance"] * out["force"]
    f = out["force"]
    pulled, pushed = (f > lo) & (f < hi), (f < -lo) & (f > -hi)
    assert pulled.sum() >= 5 and pushed.sum() >= 3
    return float(slip[pulled].mean() - slip[pushed].mean())


def test_a_push_pull_reversal_of_the_bowden_cable_shows_the_backlash_2_c_theta() -> None:
    cap = load_example("capstan")
    wrap = math.pi / 2
    out = cap.backlash_loop(wrap)
    band = out["backlash"]                                      # 2cΘ = 942.5 µm
    assert np.abs(out["force"]).max() < 5.0                     # small loads: no buckling
    assert out["force"].max() > 4.0 and out["force"].min() < -4.0     # both pulled and pushed
    assert cap.dead_band(out, f_min=2.0) == pytest.approx(band, rel=5e-3)
    # read off the output: it stands while the input travels the band (less at the edges,
    # where the tension is low and the wire's bending shortens it)
    assert cap.stop_to_restart(out) == pytest.approx(band, rel=2e-2)
    # the bending correction: the band narrows at low tension, by less than the rigid lever's
    # 2(EIc)^2/(rho^4 T^2 L) at T = 0.5 N
    EI = cap.STEEL.E * math.pi * cap.WIRE_R ** 4 / 4
    c = cap.BORE - cap.WIRE_R
    lever = 2 * (EI * c) ** 2 / (cap.RHO ** 4 * 0.5 ** 2 * cap.STRAIGHT)
    deficit = _band_at(out, 3.0) - _band_at(out, 0.5, 1.0)
    assert 1e-3 * band < deficit < lever

    # a bore of c = 0.05 mm: the band is 2cΘ again, 6x smaller
    small = cap.backlash_loop(wrap, bore=cap.WIRE_R + 0.05e-3, amplitude=0.3e-3)
    assert small["backlash"] == pytest.approx(band / 6)
    assert cap.dead_band(small, f_min=2.0) == pytest.approx(small["backlash"], rel=5e-3)


@pytest.mark.slow
@pytest.mark.parametrize("case", ["friction", "slower"] + (["180"] if FULL else []))
def test_the_backlash_is_geometric_with_friction_and_slower(case: str) -> None:
    """Friction that sticks (μ = 0.2) and a stroke of half the speed at half the step leave the
    band at 2cΘ: the band is the bend's geometry, not the wire's stretch (~1 µm/N) nor its
    inertia; at Θ = 180° (FLEXMBS_FULL=1) it doubles."""
    cap = load_example("capstan")
    wrap, kw = math.pi / 2, {"mu": 0.2} if case == "friction" else {"frequency": 2.5, "dt": 2.5e-4}
    if case == "180":
        wrap, kw = math.pi, {"amplitude": 1.2e-3}
    out = cap.backlash_loop(wrap, **kw)
    assert out["backlash"] == pytest.approx(2 * (cap.BORE - cap.WIRE_R) * wrap)
    assert np.abs(out["force"]).max() < 5.0
    assert cap.dead_band(out, f_min=2.0) == pytest.approx(out["backlash"], rel=5e-3)

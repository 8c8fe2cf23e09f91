"""A beam that starts away from its stress-free shape (``add_beam(..., stress_free=...)``, the
scenario's ``stress_free``): a pre-curved tube inserted straight, a wire threaded through a
tube of another curvature. Statics follows a path from the starting shapes (the prestress
ramped with the load factor, :meth:`flexmbs.assembly.Assembly.relax_towards_stress_free`).

Checked against closed forms: a free cantilever springs back onto its stress-free arc (to
round-off: the same equilibrium as the beam built on the arc); a straight beam whose
stress-free shape is an arc of radius R stores the bending energy E I L / (2 R²); two
concentric pre-curved beams, clamped together at the root, take the common curvature
(k₁κ₁ + k₂κ₂)/(k₁ + k₂), k_i = E_i I_i, within 1 % (measured: 0.16 % and 0.46 % for a straight
wire in a tube of κ₁ = 5 /m; 0.08 % and 0.22 % with the wire at κ₂ = 10 /m)."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.assembly import Assembly
from flexmbs.errors import ModelError

STEEL = fm.Material(E=2e11, rho=7800.0)


def _arc(radius: float, length: float, n: int, sign: float = 1.0) -> fm.Centerline:
    """An arc from the origin along +x, bending towards ``sign`` y."""
    return fm.arc((0.0, sign * radius, 0.0), radius, (0.0, 0.0, 0.0), sign * length / radius,
                  normal=(0.0, 0.0, 1.0), elements=n)


def test_a_cantilever_springs_back_onto_its_stress_free_arc():
    L, R, n = 0.2, 0.2, 20
    on_arc = fm.Model(gravity=(0.0, 0.0, 0.0))
    b = on_arc.add_beam(_arc(R, L, n), section=fm.CircularSection(5e-4), material=STEEL)
    on_arc.clamp(b.first_node)
    straight = fm.Model(gravity=(0.0, 0.0, 0.0))
    s = straight.add_beam(fm.line((0, 0, 0), (L, 0, 0), elements=n), section=fm.CircularSection(5e-4),
                          material=STEEL, stress_free=_arc(R, L, n))
    straight.clamp(s.first_node)
    asm = Assembly(straight)
    st = fm.solve_static(asm)
    assert np.abs(st.q - Assembly(on_arc).q_ref).max() < 1e-12
    # after the path the elements rest in the stress-free shape again: no strain there
    assert asm.energies(st.q, np.zeros(asm.n_coords))["strain"] < 1e-18
    # dynamics starts where the beam is (its reference), from the stress-free rest state
    res = fm.simulate(asm, t_end=1e-3, dt=1e-4, output_interval=1e-3, initial_static=True)
    assert np.abs(res.q[-1] - st.q).max() < 1e-9


def test_a_straightened_arc_stores_its_bending_energy():
    """U = E I L / (2 R²): the curvature 1/R taken out along the whole length."""
    L, R, n = 0.3, 0.25, 30
    model = fm.Model(gravity=(0.0, 0.0, 0.0))
    beam = model.add_beam(fm.line((0, 0, 0), (L, 0, 0), elements=n), section=fm.CircularSection(5e-4),
                          material=STEEL, stress_free=_arc(R, L, n))
    asm = Assembly(model)
    EI = beam.stiffness.bending_stiffness
    U = asm.energies(asm.q_ref, np.zeros(asm.n_coords))["strain"]
    assert pytest.approx(EI * L / (2 * R**2), rel=1e-4) == U
    # and nothing in the stress-free shape itself
    assert asm.energies(asm.q_free, np.zeros(asm.n_coords))["strain"] < 1e-12 * U


@pytest.mark.parametrize("kappa2", [0.0, 10.0])
def test_concentric_pre_curved_tubes_take_the_common_curvature(kappa2):
    """A pre-curved tube (κ₁ = 5 /m, hollow, k₁ = E₁I₁) and a wire (κ₂, k₂) inside it with 50 µm
    of clearance, both inserted straight and clamped at the root: the curvature between a
    quarter and three quarters of the length is (k₁κ₁ + k₂κ₂)/(k₁ + k₂) on both (the wire's
    tip, free of moment, turns to its own curvature within the clearance: the ends are left
    out). Opposite curvatures (κ₂ < 0) are not an equilibrium a torsion-free cable keeps: its
    curvature plane turns over."""
    L, n, k_1 = 0.2, 40, 5.0
    E1, ro, ri = 60e9, 1.0e-3, 0.6e-3
    area, inertia = math.pi * (ro**2 - ri**2), math.pi / 4 * (ro**4 - ri**4)
    model = fm.Model(gravity=(0.0, 0.0, 0.0))
    tube = model.add_beam(fm.line((0, 0, 0), (L, 0, 0), elements=n), name="tube",
                          section=fm.BeamStiffness(axial_stiffness=E1 * area,
                                                   bending_stiffness=E1 * inertia,
                                                   mass_per_length=6500.0 * area),
                          stress_free=_arc(1 / k_1, L, n))
    wire = model.add_beam(fm.line((0, 0, 0), (L, 0, 0), elements=n), name="wire",
                          section=fm.CircularSection(0.55e-3), material=STEEL,
                          stress_free=_arc(1 / kappa2, L, n) if kappa2 else None)
    model.clamp(tube.first_node)
    model.clamp(wire.first_node)
    model.add_joint(fm.TubeJoint(wire, tube, inner_radius=0.6e-3, spacing=2e-3,
                                 contact=fm.LinearPenalty(stiffness=2e6), name="lumen"))
    asm = Assembly(model)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        st = fm.solve_static(asm, fm.StaticOptions(load_steps=10))
    k1, k2 = tube.stiffness.bending_stiffness, wire.stiffness.bending_stiffness
    expected = (k1 * k_1 + k2 * kappa2) / (k1 + k2)
    a, b = n // 4, 3 * n // 4
    for beam in (tube, wire):
        angle = [math.atan2(*st.q[asm.node_dofs(beam.node(k))[[4, 3]]]) for k in (a, b)]
        kappa = (angle[1] - angle[0]) / ((b - a) * L / n)
        assert kappa == pytest.approx(expected, rel=1e-2), beam.name
    assert abs(expected - k_1) > 0.05 * k_1            # the wire does straighten the tube


def test_a_stress_free_shape_must_match_the_beams_elements():
    model = fm.Model()
    straight = fm.line((0, 0, 0), (0.2, 0, 0), elements=10)
    with pytest.raises(ModelError, match="stress_free has 20 elements, the centreline 10"):
        model.add_beam(straight, section=fm.CircularSection(5e-4), material=STEEL,
                       stress_free=_arc(0.2, 0.2, 20))
    model.add_beam(straight, section=fm.CircularSection(5e-4), material=STEEL,   # resampled
                   stress_free=_arc(0.2, 0.2, 20), elements=10)
    with pytest.raises(ModelError, match="stress_free element 0 is 0.022 m long"):
        model.add_beam(straight, section=fm.CircularSection(5e-4), material=STEEL,
                       stress_free=_arc(0.2, 0.22, 10))
    with pytest.raises(ModelError, match="element 'ancf_cable'"):
        model.add_beam(straight, section=fm.CircularSection(5e-4),
                       material=fm.Material(E=2e11, rho=7800.0, nu=0.3), element="ancf_rod14",
                       stress_free=_arc(0.2, 0.2, 10))
    bent = fm.Model()      # node 9 of the stress-free shape points back along -x
    hairpin = bent.add_beam(fm.line((0, 0, 0), (0.2, 0, 0), elements=10),
                            section=fm.CircularSection(5e-4), material=STEEL,
                            stress_free=_arc(0.2 / (math.pi * 10 / 9), 0.2, 10))
    bent.clamp(hairpin.first_node)
    with pytest.raises(ModelError, match="too far for the static path"):
        fm.solve_static(Assembly(bent), fm.StaticOptions(load_steps=4))


def test_the_scenario_key_builds_the_same_beam(tmp_path):
    """``[[beams]] stress_free = { arc = ... }`` is the Python API's ``stress_free``: the same
    equilibrium (the beam springs back onto the arc)."""
    from flexmbs.io.scenario import load_scenario

    L, R, n = 0.2, 0.2, 10
    (tmp_path / "pre.toml").write_text(f"""
name = "pre_curved"
[simulation]
t_end = 0.01
dt = 1e-3
gravity = [0.0, 0.0, 0.0]
[[beams]]
name = "tube"
geometry = {{ line = {{ start = [0.0, 0.0, 0.0], end = [{L}, 0.0, 0.0] }} }}
stress_free.arc = {{ center = [0.0, {R}, 0.0], radius = {R}, start = [0, 0, 0], angle = {L / R} }}
elements = {n}
radius = 5e-4
youngs_modulus = 2e11
density = 7800.0
[[constraints]]
type = "clamp"
name = "root"
beam = "tube"
node = "first"
""")
    model = load_scenario(tmp_path / "pre.toml").model
    assert model.beams[0].stress_free is not None
    on_arc = fm.Model(gravity=(0.0, 0.0, 0.0))
    b = on_arc.add_beam(_arc(R, L, n), section=fm.CircularSection(5e-4), material=STEEL)
    on_arc.clamp(b.first_node)
    st = fm.solve_static(Assembly(model))
    assert np.abs(st.q - Assembly(on_arc).q_ref).max() < 1e-12

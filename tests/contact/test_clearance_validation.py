"""Clearance joint validation: energy balance, convergence to the clearance-free joint,
two contact points in one section with a continuous section force, friction on an incline."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.assembly import Assembly
from tests.conftest import FULL

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "examples"))
from curved_beam_sleeve import build  # noqa: E402  (examples/curved_beam_sleeve.py)


def test_energy_is_conserved_with_undamped_frictionless_contact():
    """Sleeve with clearance swinging on the Example 1 rail, contact damping 0, rho_inf = 0.98:
    the mechanical energy (kinetic + strain + gravity; the penalty energy ~ k d^2/2 ~ 1e-6 J is
    negligible) stays within 0.5 % of m g dh = 0.28 J over 1 s (fast form: 0.25 s)."""
    model, rail, sleeve, joint, probes = build()
    object.__setattr__(joint, "contact", fm.LinearPenalty(stiffness=1e6, damping=0.0))
    t_end = 1.0 if FULL else 0.25
    res = fm.simulate(model, t_end=t_end, dt=1e-4, output_interval=5e-3,
                      integrator=fm.GeneralizedAlpha(rho_inf=0.98))
    E = res.energy["total"]
    scale = 0.21441 * 9.81 * (1 - math.cos(math.pi / 6))
    assert np.abs(E - E[0]).max() < 5e-3 * scale
    assert res.energy["kinetic"].max() > 0.2 * scale        # it really swings


@pytest.mark.parametrize("hole_length", [0.01])
def test_motion_converges_to_the_clearance_free_joint(hole_length):
    """Hole 10 mm long (the rail's sagitta inside it is 12.5 um, so clearances down to 0.02 mm
    fit without jamming): the slide coordinate approaches the cylindrical sliding joint's as
    c = 0.5 -> 0.1 mm (-> 0.02 mm in the full form): the deviation decreases monotonically and
    is below 2e-4 m over 0.15 s for c = 0.1 mm."""
    t_end = 0.4 if FULL else 0.15
    cs = (5e-4, 1e-4, 2e-5) if FULL else (5e-4, 1e-4)

    def slide(**kw):
        model, rail, sleeve, joint, probes = build(hole_length=hole_length, **kw)
        res = fm.simulate(model, t_end=t_end, dt=1e-4, output_interval=0.01, record_energy=False)
        return np.array([joint.slide_coordinate(q) for q in res.q])

    ideal = slide(ideal=True)
    dev = [np.abs(slide(clearance=c) - ideal).max() for c in cs]
    assert all(d2 < d1 for d1, d2 in zip(dev, dev[1:], strict=False))
    assert dev[1] < 2e-4


def _tilted_sleeve(theta_deg: float, offset_z: float = 2.5e-4, R: float = 2.2e-3):
    """Straight rod (r_b = 2 mm) along x and a one-section hole tilted by theta about z, the
    rod displaced by offset_z along the section's minor axis (z)."""
    model = fm.Model()
    beam = model.add_beam(fm.line((0, 0, 0), (1, 0, 0), elements=4), section=fm.CircularSection(2e-3),
                          material=fm.Material(E=2.1e11, rho=7800))
    h = math.radians(theta_deg) / 2
    body = model.add_rigid_body(mass=1.0, inertia=(1, 1, 1), position=(0.5, 0.0, -offset_z),
                                quaternion=(math.cos(h), 0.0, 0.0, math.sin(h)))
    joint = model.add_joint(fm.SlidingClearanceJoint(beam, body, hole=fm.CircleHole(R, 1e-4, 1),
                                                     contact=fm.LinearPenalty(stiffness=1e6)))
    asm = Assembly(model)
    rows = joint.output(asm, asm.q_ref, np.zeros(asm.n_coords), np.zeros(asm.n_mult), 0.0)
    return joint, asm, rows


def test_two_contact_points_in_one_section():
    """FORMULATION II §3: with r_b/R < cos(theta) < sqrt(r_b/R) (here 0.909 < 0.934 < 0.953) the
    minor vertex of the ellipse is a local minimum of the penetration and two symmetric maxima
    appear: two contact points with equal gaps, and the penetrating minimum counted with -1."""
    joint, asm, rows = _tilted_sleeve(21.0)
    maxima = [r for r in rows if r["normal_force"] > 0]
    minima = [r for r in rows if r["normal_force"] < 0]
    assert len(maxima) == 2 and len(minima) == 1
    assert maxima[0]["gap"] == pytest.approx(maxima[1]["gap"], rel=1e-9)
    assert maxima[0]["a"] ** 2 / maxima[0]["b"] > 2.2e-3
    assert maxima[0]["qy"] == pytest.approx(-maxima[1]["qy"], abs=1e-12)   # symmetric about z
    # below the bifurcation (cos(theta) > sqrt(r_b/R)): one point only
    _, _, rows_small = _tilted_sleeve(10.0)
    assert len(rows_small) == 1


def test_section_force_is_continuous_across_the_split():
    """Across the bifurcation a^2/b = |X - O| (the vertex sits 50 um inside the wall, so the
    split is at cos^2(theta) = r_b / 2.25 mm, theta = 19.47 deg) the signed section force of the
    continuity rule (+maxima, -minima) varies smoothly: second differences of the vertical
    force over a fine theta scan stay at the level of the smooth variation (no jump of the
    size of a contact force, which the single-point rule would produce)."""
    thetas = np.linspace(19.0, 20.0, 25)
    Fz = []
    counts = []
    for th in thetas:
        joint, asm, rows = _tilted_sleeve(th)
        Fz.append(joint.contact_force(asm.q_ref, np.zeros(asm.n_coords))[2])
        counts.append(sum(1 for r in rows if r["normal_force"] > 0))
    Fz = np.array(Fz)
    assert min(counts) == 1 and max(counts) == 2               # the scan crosses the split
    jumps = np.abs(np.diff(Fz))
    assert jumps.max() < 5 * np.median(jumps) + 1e-9 * np.abs(Fz).max()


def test_friction_on_an_incline_with_clearance():
    """Sleeve resting in a 0.5 mm clearance on a stiff rod inclined by alpha, Coulomb friction
    mu = 0.1 (regularised, eps_v = 1e-3 m/s): after settling it slides with
    g (sin alpha - mu cos alpha) (normal force m g cos alpha on the end sections); fitted over
    0.05-0.2 s, 2e-2 relative (regularisation lag and the rod's vibration)."""
    from tests.contact.test_clearance_joint import _beam_with_sleeve

    alpha, mu = 0.3, 0.1
    d = (math.cos(alpha), 0.0, -math.sin(alpha))
    model, beam, sleeve, joint = _beam_with_sleeve(direction=d, offset=-5.05e-4 / math.cos(alpha),
                                                   lock_axial=False, damping=20.0, s=0.3,
                                                   friction=fm.RegularizedCoulomb(mu=mu, eps_v=1e-3))
    for b in model.beams:
        b.stiffness = fm.BeamStiffness(axial_stiffness=2.6e8, bending_stiffness=2.6e2,
                                       mass_per_length=0.098, radius=2e-3)
    res = fm.simulate(model, t_end=0.2, dt=2e-4, output_interval=5e-3, record_energy=False)
    x = res.body_position(sleeve) @ np.asarray(d)
    sel = res.t >= 0.05
    acc = 2 * np.polyfit(res.t[sel], x[sel], 2)[0]
    assert acc == pytest.approx(9.81 * (math.sin(alpha) - mu * math.cos(alpha)), rel=2e-2)

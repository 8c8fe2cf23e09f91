"""Example 2 in the paper's regime (examples/solar_array_wing.toml, .py and _ideal.toml): the
two-point threshold of the eyelet, the Python and scenario versions, two contact points in the
middle section of an eyelet during the run, the clearance-free baseline, energy balance.

The reference for the threshold is geometric (docs/theory.md §II.3): a wire of radius r_b crossing a
section plane at angle theta to the hole axis cuts an ellipse a = r_b / cos(theta), b = r_b; pushed
along its minor axis so that the minor vertex lies at distance d = R + p from the hole centre,
that vertex is the single deepest point while a^2/b < d and splits into two symmetric deepest
points (and a penetrating minimum between them) when a^2/b > d.
"""

from __future__ import annotations

import csv
import math
import sys
from pathlib import Path

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.assembly import Assembly
from flexmbs.io.scenario import load_scenario
from tests.conftest import FULL

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "examples"))
import solar_array_wing as ex2  # noqa: E402  (examples/solar_array_wing.py)

R_BORE = ex2.WIRE_R + 1.2e-3
DEPTH = 2e-5                     # penetration of the minor vertex in the threshold test
#: the split: paper's detection a^2/b = r_b / cos^2(theta) = R + DEPTH; consistent detection
#: (docs/theory.md §II.4b) R sin^2(theta) = R + DEPTH - r_b, the offset of the wire axis from the
#: hole centre (the wall's point nearest the tilted axis leaves the minor vertex); the two
#: agree as DEPTH -> 0 (50.77 deg; 51.00 and 51.35 deg here)
THETA_SPLIT = {"paper": math.degrees(math.acos(math.sqrt(ex2.WIRE_R / (R_BORE + DEPTH)))),
               "consistent": math.degrees(math.asin(math.sqrt((R_BORE + DEPTH - ex2.WIRE_R)
                                                              / R_BORE)))}


def _eyelet_on_a_held_wire(theta_deg: float, detection: str = "consistent"):
    """The Example 2 eyelet (3 sections over 0.2 mm, R = 2 mm, k = 4e4 N/m) on a body turned
    by theta about Y, a straight wire (r_b = 0.8 mm) along X held by clamps; the eyelet centre
    sits 1.2 mm + DEPTH to -Y of the wire axis, so the ellipse's minor vertex in the middle
    section is DEPTH beyond the bore wall for every theta."""
    model = fm.Model()
    wire = model.add_beam(fm.line((-0.5, 0, 0), (0.5, 0, 0), elements=4),
                          section=fm.CircularSection(ex2.WIRE_R),
                          material=fm.Material(E=ex2.WIRE_E, rho=ex2.WIRE_RHO))
    model.clamp(wire.first_node)
    model.clamp(wire.last_node)
    h = math.radians(theta_deg) / 2
    body = model.add_rigid_body(mass=1.0, inertia=(1, 1, 1),
                                position=(0.0, ex2.WIRE_R - R_BORE - DEPTH, 0.0),
                                quaternion=(math.cos(h), 0.0, math.sin(h), 0.0))
    model.fix_body(body)
    joint = model.add_joint(fm.SlidingClearanceJoint(
        wire, body, hole=fm.CircleHole(R_BORE, ex2.EYELET_LENGTH, 3),
        contact=fm.LinearPenalty(stiffness=4e4), detection=detection))
    asm = Assembly(model)
    rows = joint.output(asm, asm.q_ref, np.zeros(asm.n_coords), np.zeros(asm.n_mult), 0.0)
    middle = [r for r in rows if r["section"] == 1]
    return joint, asm, middle


@pytest.mark.filterwarnings("ignore:joint .* starts .* into the bore wall")
@pytest.mark.parametrize("detection", ["consistent", "paper"])
def test_two_point_threshold_in_the_middle_section(detection):
    """Below theta* = 51.0 deg (paper; 51.35 deg consistent) one contact point in the middle
    section, above it two (deepest points, with the penetrating minimum between them counted
    negative), symmetric about the minor axis; the wire crossing the example's eyelets at
    55 deg is in the two-point regime."""
    split = THETA_SPLIT[detection]
    assert 50.9 < split < 51.4
    for theta in (20.0, 40.0, 50.0, split - 0.05):
        _, _, middle = _eyelet_on_a_held_wire(theta, detection)
        assert [r["normal_force"] > 0 for r in middle] == [True], theta
    for theta in (split + 0.05, 52.0, 55.0, 60.0):
        _, _, middle = _eyelet_on_a_held_wire(theta, detection)
        maxima = [r for r in middle if r["normal_force"] > 0]
        minima = [r for r in middle if r["normal_force"] < 0]
        assert len(maxima) == 2 and len(minima) == 1, theta
        assert maxima[0]["gap"] == pytest.approx(maxima[1]["gap"], rel=1e-6)
        assert maxima[0]["position"][2] == pytest.approx(-maxima[1]["position"][2], rel=1e-6)
        if detection == "paper":
            assert maxima[0]["a"] ** 2 / maxima[0]["b"] > R_BORE + DEPTH
    assert 90.0 - math.degrees(ex2.BETA) > split


@pytest.mark.filterwarnings("ignore:joint .* starts .* into the bore wall")
@pytest.mark.parametrize("detection", ["consistent", "paper"])
def test_middle_section_force_is_continuous_across_the_threshold(detection):
    """The middle section's force at theta* +- eps: the jump shrinks with eps (first order: the
    smooth change of the force with theta), while the sum over the deepest points alone would
    jump by the whole force k * DEPTH."""
    k_depth = 4e4 * DEPTH
    jumps, naive = [], []
    for eps in (1e-1, 1e-2, 1e-3):
        F, Fmax = [], []
        for th in (THETA_SPLIT[detection] - eps, THETA_SPLIT[detection] + eps):
            _, _, middle = _eyelet_on_a_held_wire(th, detection)
            F.append(sum(r["normal_force"] * r["normal"] for r in middle))
            Fmax.append(sum(r["normal_force"] * r["normal"] for r in middle if r["normal_force"] > 0))
        jumps.append(np.linalg.norm(F[1] - F[0]))
        naive.append(np.linalg.norm(Fmax[1] - Fmax[0]))
    assert jumps[1] < jumps[0] / 5 and jumps[2] < jumps[1] / 5, jumps
    assert jumps[2] < 1e-2 * k_depth
    assert naive[2] > 0.9 * k_depth


def test_scenario_and_python_versions_are_the_same_model():
    """The TOML files and examples/solar_array_wing.py build the same model: the same
    coordinates and the same static equilibrium (anchor offset applied)."""
    for ideal, name in ((False, "solar_array_wing"), (True, "solar_array_wing_ideal")):
        sc = load_scenario(ROOT / "examples" / f"{name}.toml")
        model, *_ = ex2.build(ideal=ideal)
        a, b = Assembly(sc.model), Assembly(model)
        assert a.n_coords == b.n_coords and a.n_mult == b.n_mult
        assert np.abs(a.q_ref - b.q_ref).max() < 1e-8
        qa = fm.solve_static(a, ex2.STATIC).q
        qb = fm.solve_static(b, ex2.STATIC).q
        assert np.abs(qa - qb).max() < 1e-8, name


def _section_counts(folder: Path) -> dict[tuple[str, int], np.ndarray]:
    """Deepest points (positive contact rows) per (joint, section) at every output time."""
    with open(folder / "contacts.csv") as fh:
        rows = list(csv.DictReader(fh))
    with open(folder / "probes.csv") as fh:
        times = np.array([float(r["t"]) for r in csv.DictReader(fh)])
    out: dict[tuple[str, int], np.ndarray] = {}
    index = {round(t, 9): i for i, t in enumerate(times)}
    for r in rows:
        if float(r["normal_force"]) <= 0:
            continue
        key = (r["joint"], int(r["section"]))
        out.setdefault(key, np.zeros(times.size, int))[index[round(float(r["t"]), 9)]] += 1
    return out


@pytest.mark.slow
def test_the_default_run_shows_two_points_in_the_middle_section(tmp_path):
    """The run of examples/solar_array_wing.toml (CI: 1 s; FLEXMBS_FULL=1: the 20 s of the file):
    the middle sections of the outer eyelets (grommet1, grommet3) touch the wire at two points
    at every output, the middle eyelet's middle section not at all (its rims carry it); golden
    values of the short form."""
    from flexmbs.cli import main

    t_end = 20.0 if FULL else 1.0
    out = tmp_path / "run"
    assert main(["run", str(ROOT / "examples" / "solar_array_wing.toml"), "--out", str(out),
                 "-q", "--t-end", str(t_end)]) == 0
    counts = _section_counts(out)
    for j in ("grommet1", "grommet3"):
        assert np.all(counts[(j, 1)] == 2), j
    assert ("grommet2", 1) not in counts
    with open(out / "probes.csv") as fh:
        rows = list(csv.DictReader(fh))
    f1 = np.array([[float(r[f"grommet1_force_{c}"]) for c in "xyz"] for r in rows])
    mce = np.array([float(r["M_CE_z"]) for r in rows])
    if not FULL:   # golden values of the 1 s form (measured on this version)
        assert np.linalg.norm(f1[0]) == pytest.approx(GOLDEN["f1_0"], rel=1e-4)
        assert np.abs(mce).max() == pytest.approx(GOLDEN["mce_max"], rel=1e-3)


#: the 1 s form (measured): grommet 1's contact force after the static solve, the largest
#: deflection of M_CE (at t = 0.15 s, in the half-sine); with the paper's detection (before
#: the consistent one became the default) 5.085049 N and 2.893550e-3 m
GOLDEN = {"f1_0": 5.109134, "mce_max": 2.895001e-3}


def _penalty_energy(joints, asm: Assembly, q: np.ndarray) -> float:
    """Stored energy of the linear penalty, sum of +-k delta^2 / 2 with the signs of the
    section-force rule (+deepest points, -penetrating minima between them), from the joints'
    output rows (independent of Assembly.energies)."""
    total = 0.0
    for j in joints:
        k = j.contact.stiffness
        for r in j.output(asm, q, np.zeros_like(q), np.zeros(asm.n_mult), 0.0):
            total += math.copysign(0.5 * k * r["gap"] ** 2, r["normal_force"])
    return total


def _energy_drift(stiffness: float, detection: str, t_end: float) -> tuple[float, float, float]:
    """Undamped, frictionless variant, rho_inf = 0.98, dt = 1e-4 s, t_end: after
    the half-sine (t >= 0.2 s) the largest change of kinetic + strain + hinge springs + contact
    energy, the change of the contact energy alone and the swing of the kinetic energy."""
    model, wire, panels, joints, _ = ex2.build(damping=0.0, hinge_damping=0.0, wire_damping=0.0,
                                               stiffness=stiffness)
    for j in joints:
        j.detection = detection
    asm = Assembly(model)
    res = fm.simulate(asm, t_end=t_end, dt=1e-4, output_interval=1e-2, initial_static=True,
                      static_options=ex2.STATIC, integrator=fm.GeneralizedAlpha(rho_inf=0.98))
    late = res.t >= 0.2 + 1e-9
    pen = np.array([_penalty_energy(joints, asm, q) for q in res.q[late]])
    np.testing.assert_allclose(res.energy["contact"][late], pen, rtol=1e-9, atol=1e-15)
    total = res.energy["total"][late]
    return (float(np.abs(total - total[0]).max()), float(np.ptp(pen)),
            float(np.ptp(res.energy["kinetic"][late])))


@pytest.mark.slow
@pytest.mark.parametrize("stiffness", [4e4, 2e4])
def test_energy_balance_of_the_frictionless_undamped_variant(stiffness):
    """No contact, hinge or wire damping, no friction: kinetic + wire strain + hinge springs +
    contact penalty energy stays constant to 1e-3 of the energy that moves between the stores
    (measured over 1 s: 7e-5 at k = 4e4 N/m, the default, 1.4e-6 at 2e4), while the contact
    energy changes by 8e-3 and 5e-3 of it (CI 1 s, FLEXMBS_FULL=1 5 s). With the paper's
    detection the soft contact gains energy (24 % of the swing in 1 s measured; it then pushes
    the wire through a wall at 1.22 s; before the consistent detection the default closed to
    6e-4). The baseline with ideal rings conserves it to 1e-10 J."""
    drift, contact, swing = _energy_drift(stiffness, "consistent", 5.0 if FULL else 1.0)
    assert swing > 1e-3                                   # the panels really swing (J)
    assert contact > 1e-3 * swing                         # and the contacts take part
    assert drift < 1e-3 * swing, (drift, swing)
    if stiffness == 2e4:
        # 1 s: the energy the paper's detection feeds in pushes the wire through an eyelet's
        # wall at t = 1.22 s ("the beam axis left the bore")
        drift, _, swing = _energy_drift(stiffness, "paper", 1.0)
        assert drift > 1e-2 * swing


@pytest.mark.filterwarnings("ignore:joint .* starts .* into the bore wall")
def test_contact_force_is_the_gradient_of_the_penalty_energy_for_shallow_crossings():
    """Force = -dV/dq with V = sum +-k g^2 / 2 over the detected points (re-detected at every
    perturbed q, central differences), the wire perturbed off the held line. The hole point Q is
    chosen by the paper's 2D common normal of circle and ellipse, the force is the 3D gap's
    gradient at fixed Q; the two agree where the ellipse is nearly a circle. Measured relative
    mismatch: ~1e-7 (5 deg), ~1e-6 (10), ~5e-6 (20), ~5e-5 (30), 4e-4 (40), and at steep crossings
    2 % (50), 9 % (55, Example 2), 35 % (60) -- docs/examples.md, "Noticed". This is the
    paper's detection (``detection = "paper"``); the consistent one is a gradient at every
    angle (tests/contact/test_potential.py)."""
    for theta, tol in ((5.0, 1e-5), (10.0, 1e-5), (20.0, 1e-4), (30.0, 1e-3)):
        joint, asm, _ = _eyelet_on_a_held_wire(theta, "paper")
        n = asm.n_coords
        q = asm.q_ref.copy()
        beam = np.unique(joint.geometry.elem_dofs.ravel())
        q[beam] += 2e-6 * np.random.default_rng(1).standard_normal(beam.size)
        v = np.zeros(n)
        r = np.zeros(n)
        joint.evaluate(asm, q, v, np.zeros(asm.n_mult), 0.0, r, None)   # r = -force
        h = 1e-9
        grad = np.zeros(n)
        for i in beam:
            e = np.zeros(n)
            e[i] = h
            grad[i] = (_penalty_energy([joint], asm, q + e)
                       - _penalty_energy([joint], asm, q - e)) / (2 * h)
        scale = np.abs(r[beam]).max()
        assert scale > 1.0
        assert np.abs(r[beam] - grad[beam]).max() < tol * scale, theta

"""Element B, part 1 (issue "torsion rod"): the 14-DOF rod's strain energy against independent
references (docs/theory.md §I.2.2 "verified properties"): zero in a curved, twisted reference,
the closed-form energy of turned cross-sections of a helix, objectivity under a rigid rotation of
a large deformation, a uniform twist of a straight rod (closed form ½ GJ a² L), and
a straight rod bent into a circular arc (½ EI L/ρ²)."""

from __future__ import annotations

import hashlib
import importlib.util
import math
import re
from pathlib import Path

import numpy as np
import pytest

from flexmbs.elements import ancf_rod as rod
from tests.conftest import FULL

N = rod.LAYOUT.node_size


def _rod(points: np.ndarray, slopes: np.ndarray, lengths: np.ndarray, *, EI2=2.0, EI3=2.0):
    """Reference nodal coordinates (φ = 0), element coordinates, properties, rest state."""
    nodes = np.hstack([points, slopes, np.zeros((len(points), 1))])
    ne = len(points) - 1
    q_e = np.hstack([nodes[:-1], nodes[1:]])
    props = rod.RodProperties(np.asarray(lengths, float), np.full(ne, 1e4), np.full(ne, 1.5),
                              np.full(ne, EI2), np.full(ne, EI3), np.full(ne, 0.3),
                              np.full(ne, 0.01), np.zeros(ne), np.zeros(ne))
    t, d = rod.base_frames(slopes, np.column_stack([np.arange(ne), np.arange(1, ne + 1)]))
    t_bar = np.stack([t[:-1], t[1:]], axis=1)
    d_bar = np.stack([d[:-1], d[1:]], axis=1)
    return nodes, q_e, props, rod.rest_state(q_e, props, t_bar, d_bar)


def _elements(nodes: np.ndarray) -> np.ndarray:
    return np.hstack([nodes[:-1], nodes[1:]])


def _helix(n: int = 12, radius: float = 0.3, pitch: float = 0.2, turns: float = 1.5):
    s = np.linspace(0.0, turns * 2 * np.pi, n + 1)
    c = pitch / (2 * np.pi)
    pts = np.column_stack([radius * np.cos(s), radius * np.sin(s), c * s])
    der = np.column_stack([-radius * np.sin(s), radius * np.cos(s), np.full_like(s, c)])
    speed = math.hypot(radius, c)
    slopes = der / speed                                   # unit tangents: x = arc length
    lengths = np.diff(s) * speed
    return pts, slopes, lengths


def _rotation(rng) -> np.ndarray:
    Q, _ = np.linalg.qr(rng.standard_normal((3, 3)))
    return Q * np.sign(np.linalg.det(Q))


def test_zero_reference_energy_and_turned_cross_sections_of_a_helix():
    """A helix (curvature and geometric torsion): U(q_ref) = 0. Turning every cross-section by
    the same angle c about the unchanged centreline is a real deformation of a naturally curved
    rod (the material frame turns against the curvature, as when a ring is everted): K1 is
    unchanged and the curvature seen in the material frame turns by -c, so U = EI kappa^2
    (1 - cos c) L with the helix curvature kappa = R/(R^2 + p^2) (p = pitch/2 pi). Converges at
    O(h^4) (the Hermite centreline): measured 1.0e-3, 6.4e-5, 4.0e-6 for 12, 24, 48 elements."""
    errors = []
    for n in (12, 24, 48):
        pts, slopes, lengths = _helix(n=n)
        nodes, q_e, props, rest = _rod(pts, slopes, lengths)
        assert np.abs(rod.strain_energy(q_e, props, rest)).max() < 1e-20
        turned = nodes.copy()
        turned[:, rod.TWIST] = 0.4
        U = rod.strain_energy(_elements(turned), props, rest).sum()
        p = 0.2 / (2 * np.pi)
        kappa = 0.3 / (0.3**2 + p**2)
        errors.append(abs(U / (2.0 * kappa**2 * (1 - math.cos(0.4)) * lengths.sum()) - 1.0))
    assert errors[2] < 1e-5
    assert errors[1] < errors[0] / 12 and errors[2] < errors[1] / 12, errors


def test_energy_is_objective():
    """A large random deformation of the helix, then a rigid rotation Q of it: positions and
    slopes rotated, each φ_i set so that the nodal director is Q d2_i (the triads rotate with
    the body). U is unchanged to 1e-12 relative (anisotropic section)."""
    rng = np.random.default_rng(4)
    pts, slopes, lengths = _helix()
    nodes, q_e, props, rest = _rod(pts, slopes, lengths, EI2=2.0, EI3=5.0)
    t_bar, d_bar = rod.base_frames(slopes, np.column_stack([np.arange(len(pts) - 1),
                                                            np.arange(1, len(pts))]))
    deformed = nodes + 0.05 * rng.standard_normal(nodes.shape)
    U = rod.strain_energy(_elements(deformed), props, rest).sum()
    assert U > 1.0
    Q = _rotation(rng)
    moved = deformed.copy()
    moved[:, 0:3] = deformed[:, 0:3] @ Q.T
    moved[:, 3:6] = deformed[:, 3:6] @ Q.T
    _, d2 = rod.nodal_triads(deformed[:, 3:6], deformed[:, rod.TWIST], t_bar, d_bar)
    t_new, base = rod.nodal_triads(moved[:, 3:6], np.zeros(len(nodes)), t_bar, d_bar)
    for i in range(len(nodes)):
        target = Q @ d2[i]
        moved[i, rod.TWIST] = math.atan2(np.dot(np.cross(base[i], target), t_new[i]),
                                         np.dot(base[i], target))
    U_moved = rod.strain_energy(_elements(moved), props, rest).sum()
    assert U_moved == pytest.approx(U, rel=1e-12)


def test_uniform_twist_of_a_straight_rod():
    """φ = a s on a straight rod: U = ½ GJ a² L exactly (the twist interpolation is linear)."""
    n, L, a = 8, 2.0, 0.7
    x = np.linspace(0.0, L, n + 1)
    pts = np.column_stack([x, np.zeros_like(x), np.zeros_like(x)])
    slopes = np.tile([1.0, 0.0, 0.0], (n + 1, 1))
    nodes, _, props, rest = _rod(pts, slopes, np.diff(x))
    nodes[:, rod.TWIST] = a * x
    U = rod.strain_energy(_elements(nodes), props, rest).sum()
    assert pytest.approx(0.5 * 1.5 * a * a * L, rel=1e-13) == U


def test_straight_rod_bent_into_an_arc():
    """Nodes on a circle of radius ρ with unit tangent slopes (inextensible bending): U tends
    to ½ EI L / ρ² (Hermite interpolation of the arc, O(h⁴)), no twist."""
    L, rho = 1.0, 0.5
    errors = []
    for n in (4, 8):
        x = np.linspace(0.0, L, n + 1)
        pts = np.column_stack([x, np.zeros_like(x), np.zeros_like(x)])
        slopes = np.tile([1.0, 0.0, 0.0], (n + 1, 1))
        nodes, _, props, rest = _rod(pts, slopes, np.diff(x))
        ang = x / rho
        bent = nodes.copy()
        bent[:, 0:3] = np.column_stack([rho * np.sin(ang), rho * (1 - np.cos(ang)), 0 * ang])
        bent[:, 3:6] = np.column_stack([np.cos(ang), np.sin(ang), 0 * ang])
        U = rod.strain_energy(_elements(bent), props, rest).sum()
        errors.append(abs(U / (0.5 * 2.0 * L / rho**2) - 1.0))
    assert errors[1] < 1e-4 and errors[1] < errors[0] / 8, errors


def _deformed_helix(rng, beta=0.0):
    pts, slopes, lengths = _helix(n=4)
    nodes, q_e, props, rest = _rod(pts, slopes, lengths, EI2=2.0, EI3=5.0)
    props = props._replace(damping=np.full(len(lengths), beta),
                           reference_axial_strain=np.full(len(lengths), -0.01))
    t_bar, d_bar = rest.t_bar, rest.d_bar
    rest = rod.rest_state(q_e, props, t_bar, d_bar)
    deformed = nodes + 0.05 * rng.standard_normal(nodes.shape)
    deformed[:, rod.TWIST] = 0.6 * rng.standard_normal(len(nodes))
    return _elements(deformed), props, rest


def test_force_is_the_gradient_of_the_energy():
    """Q_int = ∂U/∂q: central differences of the strain energy (h = 1e-6) agree with the
    chain-rule force of the generated derivatives to 1e-7 of the largest entry."""
    rng = np.random.default_rng(7)
    q_e, props, rest = _deformed_helix(rng)
    force = np.empty_like(q_e)
    rod.internal_forces(q_e, np.zeros_like(q_e), props, rest, force)
    h = 1e-6
    fd = np.empty_like(q_e)
    for i in range(q_e.shape[1]):
        dq = np.zeros_like(q_e)
        dq[:, i] = h
        fd[:, i] = (rod.strain_energy(q_e + dq, props, rest)
                    - rod.strain_energy(q_e - dq, props, rest)) / (2 * h)
    assert np.abs(force).max() > 10.0
    assert np.abs(fd - force).max() < 1e-7 * np.abs(force).max()


@pytest.mark.parametrize("beta", [0.0, 0.05])
def test_tangents_are_the_derivatives_of_the_force(beta):
    """∂Q_int/∂q (with the damping stresses' q-dependence) and ∂Q_int/∂q̇ against central
    differences of the force, with and without strain-rate damping, a random velocity."""
    rng = np.random.default_rng(8)
    q_e, props, rest = _deformed_helix(rng, beta=beta)
    v_e = rng.standard_normal(q_e.shape)
    n = q_e.shape[1]
    force = np.empty_like(q_e)
    K = np.empty(q_e.shape + (n,))
    C = np.empty(q_e.shape + (n,))
    rod.internal_forces(q_e, v_e, props, rest, force, K, C)
    h = 1e-6
    fK = np.empty_like(K)
    fC = np.empty_like(C)
    fp, fm = np.empty_like(q_e), np.empty_like(q_e)
    for i in range(n):
        dq = np.zeros_like(q_e)
        dq[:, i] = h
        rod.internal_forces(q_e + dq, v_e, props, rest, fp)
        rod.internal_forces(q_e - dq, v_e, props, rest, fm)
        fK[:, :, i] = (fp - fm) / (2 * h)
        rod.internal_forces(q_e, v_e + dq, props, rest, fp)
        rod.internal_forces(q_e, v_e - dq, props, rest, fm)
        fC[:, :, i] = (fp - fm) / (2 * h)
    assert np.abs(fK - K).max() < 1e-8 * np.abs(K).max()
    assert np.abs(fC - C).max() < 1e-8 * np.abs(C if beta else K).max()
    assert np.abs(C).max() > 1e-3 * np.abs(K).max() if beta else np.abs(C).max() == 0.0


ROOT = Path(__file__).resolve().parents[2]


def _generator():
    spec = importlib.util.spec_from_file_location("rod_derivatives", ROOT / "tools" / "rod_derivatives.py")
    return spec, ROOT / "flexmbs" / "elements" / "_rod_derivatives.py"


def test_generated_derivatives_are_current():
    """The committed derivative module was written by the committed generator: its header
    records the generator's sha256 (an edit of the generator without regenerating fails here).
    With sympy installed and FLEXMBS_FULL=1, regenerating gives the committed text (3 min)."""
    text = (ROOT / "flexmbs" / "elements" / "_rod_derivatives.py").read_text()
    recorded = re.search(r"^# generator sha256: ([0-9a-f]{64})$", text, re.M)
    assert recorded is not None
    actual = hashlib.sha256((ROOT / "tools" / "rod_derivatives.py").read_bytes()).hexdigest()
    assert recorded.group(1) == actual, "run python tools/rod_derivatives.py and commit its output"
    if FULL and importlib.util.find_spec("sympy") is not None:
        spec, target = _generator()
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        assert module.generate() == target.read_text()

"""A straight wire forced into a curved tube: the static contact forces against the elastica
(issue "a rod or wire inside a curved tube", Tests: "the static contact force distribution
against an elastica solution you derive").

The problem. A rigid tube bent into a circular arc (centre-line radius ρ, half-angle α, bore
radius R, sections normal to the arc, the mouths at ±α) holds a frictionless wire (radius r_b,
bending stiffness EI) whose stress-free shape is straight and which sticks out of both mouths.
The chord between the outer walls at the mouths passes inside the inner wall at the middle
((ρ+c) cos α < ρ−c, c = R − r_b), so the wire is bent: by symmetry it touches the outer wall at
the two mouths and the inner wall at the middle section, and nowhere else (checked below on
the elastica: its axis keeps inside the bore between these sections).

The elastica, derived for the joint's contact law (docs/theory.md §II.4: at a section the hole
point Q is where the section's ellipse touches the wall — in the plane of the arc, by symmetry,
the wall point in that plane — and the force acts between Q and its closest centre-line point
P, along Q − P, with the penalty f = k (r_b − |Q − P|)). Take the arc's centre at the origin
and its symmetry line along y; the half wire from the middle contact (s = 0) to the mouth
contact (s = S) is a planar inextensible elastica loaded only at its ends (the free overhang
carries nothing):

    x′ = cos θ,  y′ = sin θ,  EI θ′ = M(s) = M₀ − [(r(s) − r(0)) × F]_z,

F the wall's force on the wire at the mouth contact P_e = r(S). By symmetry θ(0) = 0, x(0) = 0,
and the middle force is F_m = −2 F_y (vertical balance), which places the axis at
y(0) = ρ − R + r_b − F_m/k (the inner wall point Q_m = (0, ρ − R), the penalty's penetration).
At the mouth: M(S) = 0 (free overhang), P_e is the closest point of Q_e = (ρ+R)(sin α, cos α):
(Q_e − P_e)·t(S) = 0, and P_e = Q_e + (r_b − |F|/k) F/|F|. Four equations for (M₀, F_x, F_y, S),
solved by shooting (scipy: solve_ivp at rtol 1e-12, fsolve). The small-deflection beam
(three-point bending over the span 2(ρ+c) sin α) is the first guess; the elastica differs from
it by 0.17 % here.

The model. The wire's stress-free reference lies away from the tube (it crosses none of the
bore's sections: the bore's open ends allow that); it is placed into the tube on a first guess
(the three-point bending cubic, 2 µm into the walls) and the static equilibrium is solved from
there. The wire's middle node is held along x (the frictionless wire could slide along the
tube) and three nodes out of the arc's plane (rigid motions the in-plane contacts do not hold);
their reactions vanish at the symmetric equilibrium.

Measured: middle-section force 5.82889 N against the elastica's 5.82884 N (+8e-6; the
small-deflection beam: 5.8386 N, +1.7e-3), each mouth 2.91748 N against 2.91746 N (26 elements
of 2 mm, sections 1.75 mm apart, 9 Newton iterations), no other section in contact; the holds'
reactions below 3e-11 N.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.assembly import Assembly
from flexmbs.errors import FlexmbsWarning
from flexmbs.solvers.static import StaticOptions, solve_static

RHO, ALPHA, BORE, WIRE_R = 0.1, math.radians(10.0), 1.0e-3, 0.5e-3
STEEL = fm.Material(E=2e11, rho=7800.0)
EI = STEEL.E * math.pi * WIRE_R**4 / 4
K = 1e7                      # penalty stiffness [N/m]
SECTIONS = 21                # 1.75 mm apart along the arc; the middle one is section 10
LENGTH, ELEMENTS = 0.052, 26  # the wire: 2 mm elements, 8 mm out of each mouth


def elastica() -> dict[str, float]:
    """The three-contact elastica of the module docstring: forces at the middle and at a mouth,
    the half arc length S and the wire's largest excursion from the tube's axis along its
    span (in the plane of the arc)."""
    from scipy.integrate import solve_ivp
    from scipy.optimize import fsolve

    Qe = (RHO + BORE) * np.array([math.sin(ALPHA), math.cos(ALPHA)])

    def shoot(u: np.ndarray):
        M0, Fx, Fy, S = u
        y0 = RHO - BORE + WIRE_R + 2.0 * Fy / K

        def rhs(_s: float, z: np.ndarray) -> list[float]:
            x, y, th = z
            return [math.cos(th), math.sin(th), (M0 - (x * Fy - (y - y0) * Fx)) / EI]

        sol = solve_ivp(rhs, (0.0, S), [0.0, y0, 0.0], rtol=1e-12, atol=1e-15,
                        dense_output=True)
        x, y, th = sol.y[:, -1]
        Pe, t = np.array([x, y]), np.array([math.cos(th), math.sin(th)])
        F = np.array([Fx, Fy])
        f = float(np.hypot(Fx, Fy))
        residual = [(M0 - (x * Fy - (y - y0) * Fx)) * S / EI, (Qe - Pe) @ t / WIRE_R,
                    *((Pe - Qe - (WIRE_R - f / K) * F / f) / WIRE_R)]
        return np.array(residual), sol

    c = BORE - WIRE_R
    a = (RHO + c) * math.sin(ALPHA)
    delta = (RHO - c) - (RHO + c) * math.cos(ALPHA)
    Fm = 48.0 * EI * delta / (2.0 * a) ** 3            # three-point bending: the first guess
    u0 = np.array([-Fm * a / 2, -0.75 * Fm * delta / a, -Fm / 2, a])
    u, _, ier, msg = fsolve(lambda u: shoot(u)[0], u0, full_output=True, xtol=1e-13)
    res, sol = shoot(u)
    assert ier == 1 and np.abs(res).max() < 1e-9, (msg, res)
    s = np.linspace(0.0, u[3], 400)
    x, y, _ = sol.sol(s)
    return {"middle": -2.0 * u[2], "mouth": float(np.hypot(u[1], u[2])), "S": float(u[3]),
            "linear": Fm, "excursion": float(np.abs(np.hypot(x, y) - RHO).max())}


def _first_guess(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The three-point bending cubic through the outer walls at the mouths and the inner wall
    in the middle, 2 µm into each, straight beyond the mouths: points and unit tangents."""
    c = BORE - WIRE_R
    a = (RHO + c) * math.sin(ALPHA)
    y_end = (RHO + c) * math.cos(ALPHA) + 2e-6
    y_mid = RHO - c - 2e-6
    u = np.minimum(np.abs(x) / a, 1.0)
    y = y_end + (y_mid - y_end) * (1.0 - 1.5 * u**2 + 0.5 * u**3)
    slope = np.sign(x) * (y_mid - y_end) * (-3.0 * u + 1.5 * u**2) / a
    y = np.where(np.abs(x) > a, y_end + slope * (np.abs(x) - a), y)
    t = np.stack([np.ones_like(x), slope, np.zeros_like(x)], axis=1)
    return np.stack([x, y, np.zeros_like(x)], axis=1), t / np.linalg.norm(t, axis=1)[:, None]


def _wire_in_tube():
    model = fm.Model(name="tube_elastica")
    wire = model.add_beam(fm.line((-LENGTH / 2, -1.0, 0.0), (LENGTH / 2, -1.0, 0.0), ELEMENTS),
                          section=fm.CircularSection(WIRE_R), material=STEEL, name="wire")
    tube = model.add_rigid_body(mass=1.0, inertia=(1e-3, 1e-3, 1e-3), name="tube")
    model.fix_body(tube)
    arc = fm.arc((0.0, 0.0, 0.0), RHO, (-RHO * math.sin(ALPHA), RHO * math.cos(ALPHA), 0.0),
                 -2.0 * ALPHA, elements=64)
    joint = fm.SlidingClearanceJoint(wire, tube, hole=fm.CurvedBore(arc, radius=BORE,
                                                                    sections=SECTIONS),
                                     contact=fm.LinearPenalty(stiffness=K), name="tube")
    with warnings.catch_warnings():      # the reference crosses none of the sections
        warnings.simplefilter("ignore", FlexmbsWarning)
        model.add_joint(joint)
    middle = wire.node(ELEMENTS // 2)
    holds = [model.prescribe(middle, [0, 2]),       # along the tube, out of the plane
             model.prescribe(wire.first_node, [2]), model.prescribe(wire.last_node, [2])]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FlexmbsWarning)
        asm = Assembly(model)
    # the wire placed into the tube on the first guess (the reference's x, so the holds agree)
    q0 = asm.q_ref.copy()
    dofs = asm.beam_dofs(wire).reshape(wire.n_nodes, -1)
    x = np.linspace(-LENGTH / 2, LENGTH / 2, wire.n_nodes)
    points, tangents = _first_guess(x)
    layout = wire.layout
    q0[dofs[:, list(layout.position)]] = points
    q0[dofs[:, list(layout.slope)]] = tangents
    joint.initial_extra(q0)                       # the bore's tracking starts here
    names = {h.name for h in holds}
    return asm, joint, q0, [i for i, o in enumerate(asm.multiplier_owner) if o in names]


def test_the_elastica_touches_only_the_mouths_and_the_middle() -> None:
    """The derivation's assumption: between the three contacts the wire's axis stays inside
    the bore (|r − ρ| < c along the span, with the ellipse's growth at the mouths), and the
    elastica differs from the small-deflection answer (so the comparison below tells them
    apart)."""
    el = elastica()
    assert el["excursion"] < (BORE - WIRE_R) * 1.01      # the mouths' ellipse: a > r_b
    assert 1e-3 < 1.0 - el["middle"] / el["linear"] < 5e-3
    assert el["mouth"] == pytest.approx(el["middle"] / 2, rel=5e-3)


def test_static_contact_forces_in_a_curved_tube_match_the_elastica() -> None:
    el = elastica()
    asm, joint, q0, held = _wire_in_tube()
    st = solve_static(asm, StaticOptions(), q0=q0)
    rows = joint.output(asm, st.q, np.zeros_like(st.q), st.lam, 0.0)
    per: dict[int, float] = {}
    for r in rows:
        per[r["section"]] = per.get(r["section"], 0.0) + r["normal_force"]
    touched = {k for k, f in per.items() if f > 1e-9}
    assert touched == {0, SECTIONS // 2, SECTIONS - 1}, per
    assert per[SECTIONS // 2] == pytest.approx(el["middle"], rel=1e-4)
    assert per[0] == pytest.approx(el["mouth"], rel=1e-4)
    assert per[SECTIONS - 1] == pytest.approx(el["mouth"], rel=1e-4)
    # the holds carry nothing at the symmetric equilibrium (relative to the contact forces)
    assert np.abs(st.lam[held]).max() < 1e-8 * el["middle"], st.lam[held]

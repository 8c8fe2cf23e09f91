"""The exact contact tangent (flexmbs.contact.tangent) against central differences of an
independent reference: the contact residual re-derived here in numpy, with the section
crossing, the stationary point of the section ellipse and the closest point solved by Newton at
every perturbed configuration (so the implicit unknowns ξ_I, φ, ψ and ξ_P move with the
coordinates)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flexmbs.contact.laws import FRICTION_NONE, FRICTION_REGULARISED, FRICTION_STICK
from flexmbs.contact.pair import HIST_TWIST, N_HISTORY, N_LOCAL, N_SPIN, TWIST_OFF
from flexmbs.contact.sections import circle_boundary
from flexmbs.contact.tangent import I_OFF, N_EXT, P_OFF, T_OFF, contact_tangent
from flexmbs.elements.hermite import CENTERLINE_SIZE, shape_xi
from flexmbs.elements.rigid_body import rotation

R_BORE = 2.5e-3
R_BEAM = 2.0e-3
L_ELEM = 0.1


def _point(qe: np.ndarray, xi: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    S, dS, ddS = shape_xi(xi, L_ELEM)
    E = qe.reshape(4, 3)
    return S @ E, dS @ E, ddS @ E


def _reference(x: np.ndarray, vel: np.ndarray, sec: tuple, law: np.ndarray, fric: np.ndarray,
               hist: np.ndarray, start: tuple[float, float, float], same: bool,
               tbar: np.ndarray | None = None, *, held: bool = False) -> tuple[np.ndarray, tuple]:
    """Q_c of one contact at coordinates ``x = [body, e_I, e_P, φ_P]`` (numpy, Newton solves)
    in the section ``sec = (u_o, frame)`` (origin and axes in body coordinates); with ``tbar``
    (2, 3) e_P is a rod's element whose nodes' charts have these base tangents (its twists
    and their rates the last two entries of ``x`` and ``vel``), else a cable's."""
    u_o, frame = sec
    qb, qI = x[:7], x[I_OFF:I_OFF + CENTERLINE_SIZE]
    qP = qI if same else x[P_OFF:T_OFF]
    spin = np.zeros(N_SPIN)
    if tbar is not None:
        spin[0] = 1.0
        spin[1:3] = x[T_OFF:]
        spin[3:5] = vel[TWIST_OFF:]
        spin[5:] = tbar.ravel()
    A = rotation(qb[3:7])
    n, ey, ez = A @ frame[:, 0], A @ frame[:, 1], A @ frame[:, 2]
    o = qb[:3] + A @ u_o
    xi, phi, xp = start
    for _ in range(50):
        r, rx, _ = _point(qI, xi)
        xi -= n @ (r - o) / (n @ rx)
    r, rx, _ = _point(qI, xi)
    cy, cz = (r - o) @ ey, (r - o) @ ez
    ty, tz, tn = rx @ ey, rx @ ez, rx @ n
    eax, eay = ty / math.hypot(ty, tz), tz / math.hypot(ty, tz)
    a, b = max(R_BEAM * np.linalg.norm(rx) / abs(tn), R_BEAM), R_BEAM

    def ellipse(phi: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        cf, sf = math.cos(phi), math.sin(phi)
        return (np.array([cy + a * cf * eax - b * sf * eay, cz + a * cf * eay + b * sf * eax]),
                np.array([-a * sf * eax - b * cf * eay, -a * sf * eay + b * cf * eax]),
                np.array([-a * cf * eax + b * sf * eay, -a * cf * eay - b * sf * eax]))

    for _ in range(60):
        X, Xp, Xpp = ellipse(phi)
        phi -= (X @ Xp) / (Xp @ Xp + X @ Xpp)
    X, _, _ = ellipse(phi)
    psi = math.atan2(X[1], X[0])
    Qd = o + R_BORE * (math.cos(psi) * ey + math.sin(psi) * ez)
    Q = qb[:3] + A @ (A.T @ (Qd - qb[:3]))
    for _ in range(60):
        r, rx, rxx = _point(qP, xp)
        xp -= ((r - Q) @ rx) / (rx @ rx + (r - Q) @ rxx)
    Y, Yp, Ypp = np.empty(2), np.empty(2), np.empty(2)
    circle_boundary(R_BORE, psi, Y, Yp, Ypp)
    Qc, K, C = np.empty(N_LOCAL), np.empty((N_LOCAL, N_EXT)), np.empty((N_LOCAL, N_LOCAL))
    g, _, f = contact_tangent(qb, vel[:7], u_o, frame, qI, L_ELEM, xi, qP, vel[7:TWIST_OFF], spin,
                              L_ELEM, xp, phi, Y, Yp, Ypp, R_BEAM, law, fric, hist, 0.3, False,
                              np.ones(1, np.bool_), Qc, K, C, held)
    return Qc, (K, C, xi, phi, xp, g, f)


def _configuration(tilt: float, offset: float, same: bool, seed: int) -> tuple:
    """A slightly curved element tilted by ``tilt`` in the x-z plane through a bore displaced by
    ``offset`` along z, the body rotated a little and its Euler parameters 0.1 % off unit."""
    rng = np.random.default_rng(seed)
    t = np.array([math.cos(tilt), 0.0, math.sin(tilt)])

    def element() -> np.ndarray:
        return np.concatenate([-0.05 * t + rng.normal(scale=1e-4, size=3),
                               t + rng.normal(scale=0.02, size=3),
                               0.05 * t + rng.normal(scale=1e-4, size=3),
                               t + rng.normal(scale=0.02, size=3)])

    qI = element()
    qP = qI.copy() if same else element()
    p = np.array([1.0, *rng.normal(scale=0.05, size=3)])
    p *= 1.001 / np.linalg.norm(p)
    qb = np.concatenate([rng.normal(scale=3e-4, size=3) + [0.0, 0.0, offset], p])
    vel = rng.normal(scale=0.1, size=N_LOCAL)        # [body, e_P, the twists' rates]
    return np.concatenate([qb, qI, qP, rng.normal(scale=0.3, size=2)]), vel


CASES = [  # tilt, bore offset, same element, friction, law [K, n, chi, c_d, v_min]
    (0.05, 9e-4, True, 0.0, [1e6, 1.0, 0.0, 0.0, 1e-3]),
    (0.3, 1e-3, True, 0.3, [1e6, 1.5, 0.0, 20.0, 1e-3]),
    (0.6, 1.6e-3, False, 0.3, [1e6, 1.5, 0.0, 20.0, 1e-3]),
    (1.1, 2.2e-3, True, 0.2, [1e9, 1.5, 0.8, 0.0, 1e-3]),     # a²/b > R: two-point regime
    (1.0, 2.4e-3, False, 0.0, [1e6, 1.0, 0.0, 0.0, 1e-3]),
]


def _turned() -> np.ndarray:
    """Section axes turned in the body (normal tilted 0.15 rad about z, e_y spun 0.7 rad about
    it): a section of a curved bore."""
    cz, sz, cx, sx = math.cos(0.15), math.sin(0.15), math.cos(0.7), math.sin(0.7)
    Rz = np.array([[cz, -sz, 0.0], [sz, cz, 0.0], [0.0, 0.0, 1.0]])
    Rx = np.array([[1.0, 0.0, 0.0], [0.0, cx, -sx], [0.0, sx, cx]])
    return Rz @ Rx


#: section axes in body coordinates (columns: normal, e_y, e_z)
FRAMES = {"straight": np.eye(3), "turned": _turned()}


def _regularised(mu: float) -> np.ndarray:
    return np.array([FRICTION_REGULARISED if mu > 0 else FRICTION_NONE, mu, mu, 1.0, 0.0, 1e-3])


def _history(x: np.ndarray, same: bool, seed: int) -> np.ndarray:
    """A step that started near ``x`` (the body and e_P a little elsewhere, an anchor
    displacement in the hole frame): the stick law's history (pair.N_HISTORY)."""
    rng = np.random.default_rng(seed)
    qP = x[I_OFF:P_OFF] if same else x[P_OFF:T_OFF]
    hist = np.empty(N_HISTORY)
    hist[0:3] = rng.normal(scale=5e-5, size=3)
    hist[3] = 1.0
    hist[4:11] = x[:7] + rng.normal(scale=1e-4, size=7)
    hist[11:HIST_TWIST] = qP + rng.normal(scale=1e-4, size=CENTERLINE_SIZE)
    hist[HIST_TWIST:] = x[T_OFF:] + rng.normal(scale=1e-2, size=2)
    return hist


def _check_tangent(x: np.ndarray, vel: np.ndarray, sec: tuple, law_a: np.ndarray,
                   fric: np.ndarray, hist: np.ndarray, same: bool, info: tuple,
                   tbar: np.ndarray | None = None, step: float = 1e-7, *,
                   held: bool = False) -> None:
    """K and C of the contact at ``info`` against central differences of :func:`_reference`
    (relative ``step``)."""
    K, C, xi, phi, xp = info[:5]
    start = (xi, phi, xp)
    Kfd = np.zeros_like(K)
    for j in range(N_EXT):
        if same and P_OFF <= j < T_OFF:
            continue
        h = step * max(1.0, abs(x[j]))
        xp_, xm_ = x.copy(), x.copy()
        xp_[j] += h
        xm_[j] -= h
        Kfd[:, j] = -(_reference(xp_, vel, sec, law_a, fric, hist, start, same, tbar,
                                 held=held)[0]
                      - _reference(xm_, vel, sec, law_a, fric, hist, start, same, tbar,
                                   held=held)[0]) / (2 * h)
    if same:   # e_I and e_P are one element: their columns add
        K = K.copy()
        K[:, I_OFF:P_OFF] += K[:, P_OFF:T_OFF]
        K[:, P_OFF:T_OFF] = 0.0
    assert np.abs(K - Kfd).max() <= 1e-6 * np.abs(Kfd).max()
    Cfd = np.zeros_like(C)
    for j in range(N_LOCAL):
        h = 1e-6
        vp, vm = vel.copy(), vel.copy()
        vp[j] += h
        vm[j] -= h
        Cfd[:, j] = -(_reference(x, vp, sec, law_a, fric, hist, start, same, tbar, held=held)[0]
                      - _reference(x, vm, sec, law_a, fric, hist, start, same, tbar,
                                   held=held)[0]) / (2 * h)
    assert np.abs(C - Cfd).max() <= 1e-6 * max(np.abs(Cfd).max(), 1e-12) + 1e-12


def _deepest(x: np.ndarray, vel: np.ndarray, sec: tuple, law_a: np.ndarray,
             fric: np.ndarray, hist: np.ndarray, same: bool,
             tbar: np.ndarray | None = None) -> tuple:
    """The deepest stationary point (scan of starting angles)."""
    found = [_reference(x, vel, sec, law_a, fric, hist, (0.5, phi0, 0.5), same, tbar)[1]
             for phi0 in np.linspace(0.0, 2.0 * np.pi, 24, endpoint=False)]
    info = min(found, key=lambda i: i[5])
    assert info[5] < 0.0, "the configuration must be in contact"
    return info


@pytest.mark.parametrize("frame", list(FRAMES))
@pytest.mark.parametrize(("tilt", "offset", "same", "mu", "law"), CASES)
def test_exact_tangent_equals_central_differences(tilt: float, offset: float, same: bool,
                                                  mu: float, law: list, frame: str) -> None:
    """Sections of a straight bore (axes = the body's) and of a curved one (axes turned in the
    body: :class:`flexmbs.CurvedBore`)."""
    x, vel = _configuration(tilt, offset, same, seed=3)
    law_a = np.array(law, float)
    sec = (np.array([0.01 if tilt < 0.5 else 0.0, 0.0, 0.0]), FRAMES[frame])
    fric = _regularised(mu)
    hist = _history(x, same, seed=4)
    _check_tangent(x, vel, sec, law_a, fric, hist, same,
                   _deepest(x, vel, sec, law_a, fric, hist, same))


#: |trial force| / cone radius of the stick-law cases: stick, slip, either side of the transition
RATIOS = [0.5, 3.0, 0.99, 1.01]


@pytest.mark.parametrize("ratio", RATIOS, ids=["stick", "slip", "below_cone", "above_cone"])
@pytest.mark.parametrize(("tilt", "offset", "same", "law"),
                         [(0.3, 1e-3, True, [1e6, 1.5, 0.0, 20.0, 1e-3]),
                          (0.6, 1.6e-3, False, [1e6, 1.0, 0.0, 20.0, 1e-3]),
                          (1.1, 2.2e-3, True, [1e9, 1.5, 0.8, 0.0, 1e-3])],
                         ids=["one_element", "two_elements", "two_point_regime"])
def test_stick_law_tangent_equals_central_differences(ratio: float, tilt: float, offset: float,
                                                      same: bool, law: list) -> None:
    frame = "turned" if ratio > 1.0 else "straight"
    """The stick law's exact tangent (trial displacement from the step's start, anchor in the
    hole frame, return mapping) in stick, in slip and on either side of the cone: the
    tangential stiffness is set so that |T| = ratio · μ f_N at the contact (damping 0.3 % of
    it, so the C block has a friction part too)."""
    x, vel = _configuration(tilt, offset, same, seed=3)
    law_a = np.array(law, float)
    sec = (np.array([0.01 if tilt < 0.5 else 0.0, 0.0, 0.0]), FRAMES[frame])
    hist = _history(x, same, seed=4)
    vel *= 1e-3          # slow: the damping part of the trial force stays small
    mu = 0.3
    probe = np.array([FRICTION_STICK, mu, mu, 1.0, 0.0, 1e-3])
    info = _deepest(x, vel, sec, law_a, probe, hist, same)
    Qc, _ = _reference(x, vel, sec, law_a, probe, hist, info[2:5], same)
    # with k_t = 1 and no damping the friction force is −d (inside any cone of these forces)
    Qn, _ = _reference(x, vel, sec, law_a, _regularised(0.0), hist, info[2:5], same)
    d_norm = np.linalg.norm((Qc - Qn)[:3])      # body translation rows: W = [I, ...] → F_t
    k_t = ratio * mu * info[6] / d_norm
    fric = np.array([FRICTION_STICK, mu, mu, k_t, 0.0, 1e-3])
    _check_tangent(x, vel, sec, law_a, fric, hist, same,
                   _deepest(x, vel, sec, law_a, fric, hist, same))
    fric[4] = 1e-3 * k_t
    _check_tangent(x, vel, sec, law_a, fric, hist, same,
                   _deepest(x, vel, sec, law_a, fric, hist, same))


def _charts(x: np.ndarray, same: bool) -> np.ndarray:
    """Base tangents of e_P's nodes' charts: their slopes turned by 0.2 and 0.35 rad (a chart
    whose base is not the tangent: the chart spin's b is not zero)."""
    qP = x[I_OFF:P_OFF] if same else x[P_OFF:T_OFF]
    out = np.empty((2, 3))
    for a, turn in enumerate((0.2, 0.35)):
        g = qP[6 * a + 3:6 * a + 6] / np.linalg.norm(qP[6 * a + 3:6 * a + 6])
        side = np.cross(g, [0.0, 1.0, 0.0])
        side /= np.linalg.norm(side)
        out[a] = math.cos(turn) * g + math.sin(turn) * side
    return out


@pytest.mark.parametrize("law_kind", ["regularised", "stick", "slip"])
@pytest.mark.parametrize(("tilt", "offset", "same"), [(0.3, 1e-3, True), (0.6, 1.6e-3, False)],
                         ids=["one_element", "two_elements"])
def test_a_rods_turning_surface_tangent_equals_central_differences(law_kind: str, tilt: float,
                                                                   offset: float,
                                                                   same: bool) -> None:
    """A rod's element under friction (issue 30, "turn": torque and drag): its surface turns
    with the section spin ``ω = Σ N_a (φ̇_a + b_a·ġ_a)``, so the friction force and its twist
    and slope shares depend on the twists, their rates and the charts; K (with the twist
    columns) and C (with the twist rates) against central differences, in the regularised law
    and in the stick law sticking and slipping."""
    x, vel = _configuration(tilt, offset, same, seed=5)
    vel *= 1e-2                              # slow translation, the sections spinning
    vel[TWIST_OFF:] = [3.0, -2.0]
    law_a = np.array([1e6, 1.5, 0.0, 2.0, 1e-3])
    sec = (np.array([0.01 if tilt < 0.5 else 0.0, 0.0, 0.0]), FRAMES["turned"])
    hist = _history(x, same, seed=6)
    tbar = _charts(x, same)
    if law_kind == "regularised":
        fric = _regularised(0.3)
    else:
        k_t = {"stick": 1e2, "slip": 1e7}[law_kind]
        fric = np.array([FRICTION_STICK, 0.3, 0.3, k_t, 1e-3 * k_t, 1e-3])
    info = _deepest(x, vel, sec, law_a, fric, hist, same, tbar)
    K, C = info[0], info[1]
    assert info[6] > 0.0, "a loaded contact"
    # the twist rates always act (slip velocity); the twists themselves in the stick law
    assert np.abs(C[:, TWIST_OFF:]).max() > 1e-6 * np.abs(C).max(), "the spin must matter"
    if law_kind != "regularised":
        assert np.abs(K[:, T_OFF:]).max() > 1e-6 * np.abs(K).max(), "the turn must matter"
    # the slip speed r_b ω is near the laws' regularisation: central differences need a
    # smaller step (their error measured ∝ h²: 2.7e-6 → 2.7e-8 from h = 1e-7 to 1e-8)
    _check_tangent(x, vel, sec, law_a, fric, hist, same, info, tbar, step=1e-8)


@pytest.mark.parametrize("mu", [0.0, 0.3])
@pytest.mark.parametrize(("tilt", "offset", "same"), [(0.05, 3e-4, True), (0.6, 8e-4, False)],
                         ids=["one_element", "two_elements"])
def test_a_held_open_contact_pulls_with_an_exact_tangent(tilt: float, offset: float, same: bool,
                                                         mu: float) -> None:
    """A contact the Newton iterations hold (``NewtonOptions.hold_contacts``) whose gap has
    opened: the linear law's extension pulls, ``f = −k g`` (laws.held_law_force), no friction;
    its K and C against central differences; not held, the same point has no force."""
    x, vel = _configuration(tilt, offset, same, seed=3)
    law_a = np.array([1e6, 1.0, 0.0, 0.0, 1e-3, 0.0, 0.0])
    sec = (np.array([0.01 if tilt < 0.5 else 0.0, 0.0, 0.0]), FRAMES["straight"])
    fric = _regularised(mu)
    hist = _history(x, same, seed=4)
    found = [_reference(x, vel, sec, law_a, fric, hist, (0.5, phi0, 0.5), same, held=True)[1]
             for phi0 in np.linspace(0.0, 2.0 * np.pi, 24, endpoint=False)]
    info = min((i for i in found if i[5] > 0.0), key=lambda i: i[5])   # an open point
    g, f = info[5], info[6]
    assert f == pytest.approx(-1e6 * g, rel=1e-12)
    _check_tangent(x, vel, sec, law_a, fric, hist, same, info, held=True)
    Qc, plain = _reference(x, vel, sec, law_a, fric, hist, info[2:5], same)
    assert plain[6] == 0.0 and np.abs(Qc).max() == 0.0

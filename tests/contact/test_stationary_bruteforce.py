"""The consistent detection (docs/theory.md §II.4b) against brute force: a slightly curved beam
element crosses a hole section at a random tilt and offset (circle and superellipse bores,
two-point configurations included). Its contact points are the local minima, below the beam
radius, of the distance from the section's wall to the beam axis; the brute force samples the
wall densely and takes each wall point's distance to a dense sampling of the axis (no
projection, no Newton). The detector must find each minimum, at its wall angle and depth, and
nothing else."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from flexmbs.contact._detect import (
    DETECT_INT_WORK,
    DETECT_WORK,
    MAX_CROSSINGS,
    N_COLS,
    detect_section,
)
from flexmbs.contact.bores import section_tree
from flexmbs.contact.sections import SHAPE_CIRCLE, SHAPE_SUPERELLIPSE, section_boundary
from flexmbs.elements.centerline import element_tree, element_tree_size
from flexmbs.elements.hermite import shape_xi
from tests.conftest import FULL

L_ELEM = 0.02        # the beam element, centred on the section
M_WALL = 4096        # wall samples
M_AXIS = 4001        # axis samples
PSI_TOL = 4 * 2 * math.pi / M_WALL
DEPTH_TOL = 2e-8     # m: the axis sampling (10 µm spacing at mm distances) and the wall grid


def _element(c: np.ndarray, t: np.ndarray, bow: np.ndarray) -> np.ndarray:
    """Hermite coordinates of an element of length L_ELEM through c along t, bent by ±bow
    in its end slopes."""
    return np.concatenate([c - 0.5 * L_ELEM * t, t - bow, c + 0.5 * L_ELEM * t, t + bow])


def _brute_force(qe: np.ndarray, shape: int, params: np.ndarray, r_b: float
                 ) -> tuple[list[tuple[float, float]], list[tuple[float, float]]]:
    """(wall angle, depth) of the local minima of the wall-to-axis distance below r_b: those
    that stand out of the sampling's noise (deeper by 5 DEPTH_TOL than the distance a few
    samples to either side), and all of them (the sampled axis makes small false minima on a
    flat stretch of the distance, next to a pitchfork)."""
    xi = np.linspace(0.0, 1.0, M_AXIS)
    S = np.array([shape_xi(x, L_ELEM)[0] for x in xi])            # (M_AXIS, 4)
    axis = S @ qe.reshape(4, 3)
    psi = np.linspace(0.0, 2 * np.pi, M_WALL, endpoint=False)
    Y, Yp, Ypp = np.empty(2), np.empty(2), np.empty(2)
    wall = np.zeros((M_WALL, 3))
    for i, p in enumerate(psi):
        section_boundary(shape, params, p, Y, Yp, Ypp)
        wall[i, 1:] = Y                                           # section plane x = 0
    ell = np.empty(M_WALL)
    for k in range(0, M_WALL, 512):
        d = wall[k:k + 512, None, :] - axis[None, :, :]
        ell[k:k + 512] = np.sqrt(np.min(np.einsum("ijk,ijk->ij", d, d), axis=1))
    minima = (ell < np.roll(ell, 1)) & (ell <= np.roll(ell, -1)) & (ell < r_b)
    w = 8
    prominent = minima & (np.roll(ell, w) > ell + 5 * DEPTH_TOL) \
        & (np.roll(ell, -w) > ell + 5 * DEPTH_TOL)
    return ([(float(psi[i]), float(r_b - ell[i])) for i in np.flatnonzero(prominent)],
            [(float(psi[i]), float(r_b - ell[i])) for i in np.flatnonzero(minima)])


def _detected(qe: np.ndarray, shape: int, params: np.ndarray, R_out: float, R_in: float,
              r_b: float) -> list[tuple[float, float]] | None:
    rows = np.zeros((8, N_COLS))
    ws_e, ws_x = np.zeros(1, np.int64), np.full(1, 0.5)
    tree = section_tree(np.zeros((1, 3)), 2 * R_out + r_b)
    work = (np.zeros(1, np.int64), np.zeros((1, MAX_CROSSINGS), np.int64),
            np.zeros((1, MAX_CROSSINGS)), np.zeros(1, np.int64),
            np.zeros(1 + DETECT_INT_WORK, np.int64))
    etree = np.zeros((element_tree_size(1), 4))
    element_tree(qe.reshape(1, 12), np.array([L_ELEM]), etree)
    m = detect_section(qe.reshape(1, 12), np.array([L_ELEM]), np.zeros(3), np.eye(3),
                       np.zeros((1, 3)), np.eye(3)[None].copy(), *tree, etree, False,
                       np.zeros(0, np.bool_),
                       *work, ws_e,
                       ws_x, np.full(1, -1, np.int64), ws_e.copy(), ws_x.copy(),
                       np.full(2, -1, np.int64), r_b, shape, params, R_out, R_in, True, None, rows,
                       np.zeros(DETECT_WORK))
    if m < 0:
        return None
    return [(float(r[11]), float(r[10])) for r in rows[:m] if r[2] > 0]


def _angle(a: float, b: float) -> float:
    d = abs(a - b) % (2 * math.pi)
    return min(d, 2 * math.pi - d)


def _check(found: list[tuple[float, float]],
           truth: tuple[list[tuple[float, float]], list[tuple[float, float]]]) -> None:
    """Every clear true minimum deeper than the tolerance is found, and every found one is a
    sampled minimum."""
    clear, every = truth
    for psi, depth in clear:
        if depth > 5 * DEPTH_TOL:
            near = [d for p, d in found if _angle(p, psi) < PSI_TOL]
            assert near, (psi, depth, found, clear)
            assert abs(near[0] - depth) < DEPTH_TOL + 1e-4 * depth, (psi, depth, found, clear)
    for psi, depth in found:
        if depth > 5 * DEPTH_TOL:
            assert any(_angle(p, psi) < PSI_TOL for p, _ in every), (psi, depth, found, clear)


@settings(max_examples=40 if FULL else 15, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(tilt=st.floats(0.0, 1.2), roll=st.floats(0.0, 2 * math.pi), r_b=st.floats(0.5e-3, 1.2e-3),
       where=st.floats(0.0, 2 * math.pi), reach=st.floats(-0.05e-3, 0.3e-3),
       bend=st.floats(-0.05, 0.05), super_=st.booleans(), n=st.floats(2.0, 8.0),
       ratio=st.floats(0.8, 1.25), minor=st.booleans())
def test_detector_finds_every_contact_of_the_wall_and_the_axis(tilt, roll, r_b, where, reach,
                                                                 bend, super_, n, ratio, minor):
    """Tilts up to 69°, the axis offset so that the beam reaches up to 0.3 mm into the wall,
    bent by up to ±0.05 rad over the 20 mm element; circle (R = 2 mm) or superellipse
    (2 mm × 2 mm·ratio, n from 2 to 8). With ``minor`` the offset is along the section
    ellipse's minor axis and the tilt at least 52°: two points per section where
    a²/b exceeds the wall's radius of curvature."""
    if minor:
        tilt = max(tilt, 0.9)
        where = roll + 0.5 * math.pi
    t = np.array([math.cos(tilt), math.sin(tilt) * math.cos(roll), math.sin(tilt) * math.sin(roll)])
    if super_:
        shape, params = SHAPE_SUPERELLIPSE, np.array([2e-3, 2e-3 * ratio, n, 0.0])
        R_in, R_out = min(2e-3, 2e-3 * ratio), 2e-3 * max(1.0, ratio) * 2 ** 0.5
    else:
        shape, params = SHAPE_CIRCLE, np.array([2e-3, 0.0, 0.0, 0.0])
        R_in = R_out = 2e-3
    assume(r_b / math.cos(tilt) < 0.95 * R_in)                  # the section ellipse fits
    u = np.array([0.0, math.cos(where), math.sin(where)])
    c = (R_in - r_b + reach) * u
    m = np.cross(t, u)
    bow = bend * m / max(np.linalg.norm(m), 1e-12)
    qe = _element(c, t, bow)
    found = _detected(qe, shape, params, R_out, R_in, r_b)
    assume(found is not None)                                     # the axis left the bore
    _check(found, _brute_force(qe, shape, params, r_b))

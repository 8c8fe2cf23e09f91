"""The compiled superellipse detector against brute force (issue "non-circular bores"): random
ellipses in random (turned) superellipses, n from 2 to 20, jammed ones included. The
penetration along a wall normal N is d(N) = h_E(N) − h_W(N), the difference of the support
functions of the ellipse (closed form) and of the wall (here by dense sampling); its positive
local maxima over the normal's direction are the contact points (docs/theory.md §II.6). The
detector must find each of them, with the same depth and wall normal."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from flexmbs.contact.sections import SHAPE_SUPERELLIPSE, section_boundary
from flexmbs.contact.shapes.detector import common_normal_points
from tests.conftest import FULL

M_DIR = 4096        # normal directions of the brute force
M_WALL = 8192       # wall samples of its support function


def _brute_force(params: np.ndarray, c: np.ndarray, ea: np.ndarray, a: float, b: float
                 ) -> list[tuple[float, float]]:
    """(normal angle, depth) of every positive local maximum of d over the normal direction."""
    Y, Yp, Ypp = np.empty(2), np.empty(2), np.empty(2)
    wall = np.empty((M_WALL, 2))
    for i, psi in enumerate(np.linspace(0.0, 2 * np.pi, M_WALL, endpoint=False)):
        section_boundary(SHAPE_SUPERELLIPSE, params, psi, Y, Yp, Ypp)
        wall[i] = Y
    th = np.linspace(0.0, 2 * np.pi, M_DIR, endpoint=False)
    N = np.stack([np.cos(th), np.sin(th)], axis=1)
    eb = np.array([-ea[1], ea[0]])
    hE = N @ c + np.sqrt(a * a * (N @ ea) ** 2 + b * b * (N @ eb) ** 2)
    hW = (N @ wall.T).max(axis=1)
    d = hE - hW
    peaks = (d > np.roll(d, 1)) & (d >= np.roll(d, -1)) & (d > 0)
    return [(float(th[i]), float(d[i])) for i in np.flatnonzero(peaks)]


def _detected(params: np.ndarray, c: np.ndarray, ea: np.ndarray, a: float, b: float
              ) -> list[tuple[float, float]]:
    psi, phi, kind, depth = np.empty(16), np.empty(16), np.empty(16, np.int64), np.empty(16)
    m = common_normal_points(SHAPE_SUPERELLIPSE, params, c[0], c[1], ea[0], ea[1], a, b, 128,
                             psi, phi, kind, depth)
    Y, Yp, Ypp = np.empty(2), np.empty(2), np.empty(2)
    out = []
    for i in range(m):
        if kind[i] == 1 and depth[i] > 0:
            section_boundary(SHAPE_SUPERELLIPSE, params, psi[i], Y, Yp, Ypp)
            out.append((math.atan2(-Yp[0], Yp[1]) % (2 * np.pi), float(depth[i])))  # normal
    return out


@settings(max_examples=40 if FULL else 15, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(A=st.floats(1.5e-3, 3e-3), B=st.floats(1.5e-3, 3e-3), n=st.floats(2.0, 20.0),
       turn=st.floats(0.0, math.pi), b=st.floats(0.6e-3, 1.4e-3), ratio=st.floats(1.0, 2.5),
       tilt=st.floats(0.0, math.pi), r=st.floats(0.0, 1.0), where=st.floats(0.0, 2 * math.pi))
def test_detector_finds_every_penetrating_maximum(A, B, n, turn, b, ratio, tilt, r, where):
    """Ellipses placed so that they reach past the wall (r scales the centre offset up to the
    smaller semi-axis; a long one jams). Every brute-force maximum deeper than the sampling
    resolution is found, at its depth (1 % of the deepest + 2 µm) and normal (0.02 rad).
    Derandomized (a fixed set of examples: CI reproducible). Open: a random run (2026-11-26)
    found a missed maximum (depth 0.17 mm) at A = B = 1.5 mm, n = 19.75, turn 1.226, an
    ellipse b = 1.362 mm, a = 1.951 b = 2.66 mm (77 % wider than the bore: a deep jam the joint
    refuses at the start), tilt 0.311, r = 0.311, where 0.00195."""
    params = np.array([A, B, n, turn])
    a = ratio * b
    c = r * min(A, B) * np.array([math.cos(where), math.sin(where)])
    ea = np.array([math.cos(tilt), math.sin(tilt)])
    ref = _brute_force(params, c, ea, a, b)
    got = _detected(params, c, ea, a, b)
    deepest = max([d for _, d in ref], default=0.0)
    tol = 0.01 * deepest + 2e-6
    for th, d in ref:
        if d < tol:
            continue          # too shallow to tell from the sampling
        hits = [dg for tg, dg in got
                if abs((tg - th + np.pi) % (2 * np.pi) - np.pi) < 0.02]
        assert hits, f"missed the maximum at normal {th:.4f} rad, depth {d:.3e} m"
        assert min(abs(dg - d) for dg in hits) < tol

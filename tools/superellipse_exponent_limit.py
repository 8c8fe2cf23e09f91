"""Superellipse exponent the 128-sample detector resolves, and where |c/a|^n over/underflows
(the experiment behind flexmbs/contact/shapes/superellipse_limits.py):

    python tools/superellipse_exponent_limit.py
"""
import math

import numpy as np

from flexmbs.contact.shapes.superellipse import superellipse_boundary

h = 2 * math.pi / 128
def corner_width(n, ratio=1.0):
    # polar angles psi where the wall normal makes 5 and 85 degrees with the y axis (b/a = ratio)
    # tan(theta) = (a/b) (tan(psi) b/a ... ) : normal ~ (x^(n-1)/a, y^(n-1)/b), tan psi = (b/a) y/x
    a, b = 1.0, ratio
    out = []
    for th in (5, 85):
        r = (math.tan(math.radians(th)) * b / a) ** (1 / (n - 1))   # y/x
        out.append(math.atan(b / a * r))
    return out[1] - out[0]
print("sample interval h = 2 pi/128 =", round(h, 5))
for ratio in (1.0, 0.65, 0.5):
    for n in (4, 10, 20, 30, 40, 50, 60, 80, 100, 1e6):
        w = corner_width(n, ratio)
        print(f"b/a={ratio:4}  n={n:>9g}  corner width (normal 5->85 deg) = {w:.4f} = {w / h:.2f} h")
def finite(a, b, n, m=4096):
    Y, Yp, Ypp = np.empty(2), np.empty(2), np.empty(2)
    for psi in np.linspace(0, 2 * np.pi, m, endpoint=False):
        try:
            superellipse_boundary(a, b, n, psi, Y, Yp, Ypp)
        except ZeroDivisionError:       # g underflows to 0: numba raises as Python does
            return False
        if not (np.all(np.isfinite(Y)) and np.all(np.isfinite(Yp)) and np.all(np.isfinite(Ypp))):
            return False
    return True
for a in (1e-4, 1e-3, 4e-3, 1e-2, 1.0, 10.0, 1e3):
    lo, hi = 2.0, 1e5
    if finite(a, a, hi):
        print(f"a = b = {a:g}: finite up to n = 1e5")
        continue
    for _ in range(40):
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if finite(a, a, mid) else (lo, mid)
    print(f"a = b = {a:g}: Y, Y', Y'' finite up to n = {lo:.1f}; "
          f"n ln(1/a) there = {lo * abs(math.log(a)):.1f}")

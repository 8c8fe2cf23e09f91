"""Generate ``flexmbs/elements/_rod_derivatives.py``: the exact first and second derivatives of
the 14-DOF rod's kinematic maps (docs/theory.md §I.2.1–2.2), by sympy.

The rod's strain energy is a composition of four small maps, each differentiated here:

- ``triad``: a node's ``(g, φ)`` -> its unit tangent ``t`` and director ``d2``
  (``t = g/|g|``, ``d2 = Rot(t, φ) SR(t̄ → t) D̄``), 4 inputs, 6 outputs;
- ``twist``: the two nodal triads ``(t0, d20, t1, d21)`` -> the relative twist
  ``Δθ = atan2((d̂ × d21)·t1, d̂·d21)``, ``d̂ = SR(t0 → t1) d20``, 12 inputs (atan2, not
  the half-angle form 2 atan(y/(1 + x)), which divides by zero at Δθ = ±π);
- ``curvatures``: at a point ξ, ``(r′, r″, t0, d20, Δθ)`` -> ``(K1, K2, K3)``, 13 inputs;
- ``axial``: ``r′`` -> ``ε = |r′|/μ − 1`` (integrated at other points, against membrane locking);
- ``director_turn``: ``(t, t0, d20)`` -> the angle β about the unit tangent ``t`` from a frame
  carried without spin, ``SR(t̄ → t) ȳ``, to ``SR(t0 → t) d20`` (parameters ``[t̄, ȳ]``, ``ȳ ⟂ t̄``;
  atan2: β in (−π, π]), 9 inputs. A flexible tube's section on a rod turns by ``ψ = β + ξΔθ``,
  the angle to the rod's director ``d2(ξ) = Rot(t, ξΔθ) SR(t0 → t) d20`` (docs/theory.md
  §II.9); the element kernel adds ``ξΔθ`` and composes ``t = r′/|r′|`` (the map's inputs are
  unit vectors, which keeps sympy's Hessian small: 2 min instead of more than 20 with ``r′``
  and the rotation by ``ξΔθ`` inside).

Besides values with Jacobians (``name``) and with Hessians (``name_h``), except for the
curvatures: ``curvatures_wh``, only the weighted sum ``Σ_j σ_j ∂²K_j/∂z²`` (the tangent's,
half the work of the three Hessians; with unit weights one Hessian, for the damping's rate
terms), and ``spin_value``, the spin map without its Jacobian (for the residual). Fewer and
smaller generated functions also compile faster (the first run on a machine).
The element kernel (:mod:`flexmbs.elements.ancf_rod`) composes them by the chain rule. The
expressions are written for inputs on their manifold (``|t0| = |d20| = 1``, ``d20 ⟂ t0``,
``D̄ ⟂ t̄``), where ``Rot(t, φ) v = v cos φ + (t × v) sin φ`` for ``v ⟂ t``; a composition
through the triads never leaves it, so the composite derivatives are exact.

Run ``python tools/rod_derivatives.py`` after editing the formulas; the test
``tests/elements/test_ancf_rod.py::test_generated_derivatives_are_current`` checks that the
committed module is this script's output. Needs sympy (not a dependency of flexmbs).
"""

from __future__ import annotations

import hashlib
import sys
from pathlib import Path

import sympy as sp
from sympy.printing.pycode import PythonCodePrinter

TARGET = Path(__file__).resolve().parents[1] / "flexmbs" / "elements" / "_rod_derivatives.py"


def generator_hash() -> str:
    """sha256 of this script, recorded in the generated module's header."""
    return hashlib.sha256(Path(__file__).read_bytes()).hexdigest()


def _vec(name: str) -> sp.Matrix:
    return sp.Matrix(sp.symbols(f"{name}0:3", real=True))


def _sr(a: sp.Matrix, b: sp.Matrix, v: sp.Matrix) -> sp.Matrix:
    """SR(a → b) v (docs/theory.md §I.2.1)."""
    c = a.dot(b)
    k = a.cross(b)
    return c * v + k.cross(v) + (k.dot(v) / (1 + c)) * k


def _rot_perp(t: sp.Matrix, phi: sp.Expr, v: sp.Matrix) -> sp.Matrix:
    """Rot(t, φ) v for v ⟂ t."""
    return sp.cos(phi) * v + sp.sin(phi) * t.cross(v)


def triad_map() -> tuple[list[sp.Symbol], list[sp.Symbol], list[sp.Expr]]:
    g = _vec("g")
    phi = sp.Symbol("phi", real=True)
    tb, db = _vec("tb"), _vec("db")
    t = g / sp.sqrt(g.dot(g))
    d2 = _rot_perp(t, phi, _sr(tb, t, db))
    return [*g, phi], [*tb, *db], [*t, *d2]


def twist_map() -> tuple[list[sp.Symbol], list[sp.Symbol], list[sp.Expr]]:
    t0, d20, t1, d21 = _vec("ta"), _vec("da"), _vec("tb"), _vec("db")
    dhat = _sr(t0, t1, d20)
    y = dhat.cross(d21).dot(t1)
    x = dhat.dot(d21)
    return [*t0, *d20, *t1, *d21], [], [sp.atan2(y, x)]


def axial_map() -> tuple[list[sp.Symbol], list[sp.Symbol], list[sp.Expr]]:
    rp = _vec("rp")
    mu = sp.Symbol("mu", real=True)
    return [*rp], [mu], [sp.sqrt(rp.dot(rp)) / mu - 1]


def curvature_map() -> tuple[list[sp.Symbol], list[sp.Symbol], list[sp.Expr]]:
    rp, rpp, t0, d20 = _vec("rp"), _vec("rpp"), _vec("ta"), _vec("da")
    dth = sp.Symbol("dth", real=True)
    xi, L, mu = sp.symbols("xi L mu", real=True)
    n2 = rp.dot(rp)
    nrp = sp.sqrt(n2)
    t = rp / nrp
    v = _sr(t0, t, d20)                     # ⟂ t
    w = t.cross(v)
    kap = rp.cross(rpp)
    a = xi * dth
    kv, kw = kap.dot(v), kap.dot(w)
    c2 = (sp.cos(a) * kv + sp.sin(a) * kw) / n2         # κ·d2/|r′|²
    c3 = (sp.cos(a) * kw - sp.sin(a) * kv) / n2         # κ·d3/|r′|², d3 = t × d2
    tau = -t0.dot(t.cross(rpp)) / (nrp * (1 + t0.dot(t)))
    return [*rp, *rpp, *t0, *d20, dth], [xi, L, mu], [(dth / L + tau) / mu, c2 / mu, c3 / mu]


def director_turn_map() -> tuple[list[sp.Symbol], list[sp.Symbol], list[sp.Expr]]:
    t, t0, d20, tb, yb = _vec("t"), _vec("ta"), _vec("da"), _vec("tb"), _vec("yb")
    carried = _sr(tb, t, yb)                          # ⟂ t
    transported = _sr(t0, t, d20)                     # ⟂ t
    return [*t, *t0, *d20], [*tb, *yb], [sp.atan2(carried.cross(transported).dot(t),
                                                  carried.dot(transported))]


def spin_map() -> tuple[list[sp.Symbol], list[sp.Symbol], list[sp.Expr]]:
    g, gd, tb = _vec("g"), _vec("gd"), _vec("tb")
    n = sp.sqrt(g.dot(g))
    t = g / n
    td = (gd - t * t.dot(gd)) / n
    w = -tb.dot(t.cross(td)) / (1 + tb.dot(t))
    b = [sp.diff(w, x) for x in gd]
    dw = [sp.diff(w, x) for x in g]
    s = sum(dw[j] * gd[j] for j in range(3))
    c = [sum((sp.diff(b[i], g[j]) - sp.diff(b[j], g[i])) * gd[j] for j in range(3))
         for i in range(3)]
    return [*g, *gd], [*tb], [w, *b, s, *c]


def _weighted_hessian(inputs: list[sp.Symbol], outputs: list[sp.Expr],
                      weights: list[sp.Symbol]) -> tuple[list[sp.Expr], list[str]]:
    """The entries of ``Σ_j weights_j ∂²outputs_j/∂x²`` (upper triangle mirrored) and their slots
    in ``hes`` (inputs x inputs)."""
    exprs: list[sp.Expr] = []
    slots: list[str] = []
    for a, x in enumerate(inputs):
        first = [sp.diff(f, x) for f in outputs]
        for b in range(a, len(inputs)):
            d = sum(wj * sp.diff(fa, inputs[b]) for wj, fa in zip(weights, first, strict=True))
            if d != 0:
                exprs.append(d)
                slots.append(f"hes[{a}, {b}]" if a == b else f"hes[{a}, {b}] = hes[{b}, {a}]")
    return exprs, slots


def _emit(name: str, doc: str, inputs: list[sp.Symbol], params: list[sp.Symbol],
          outputs: list[sp.Expr], hessian: bool, *, jacobian: bool = True,
          weights: list[sp.Symbol] | None = None) -> str:
    """A compiled function of the map: the values and (``jacobian``) the Jacobian and
    (``hessian``) the Hessians; or, with ``weights`` (extra parameters after ``params``), only
    the weighted sum of the Hessians ``Σ_j w_j ∂²f_j/∂x²`` into ``hes``."""
    n_in, n_out = len(inputs), len(outputs)
    if weights is not None:
        exprs, slots = _weighted_hessian(inputs, outputs, weights)
        params = [*params, *weights]
        args = ["x", "p", "hes"]
        return _code(name, doc, inputs, params, exprs, slots, args)
    exprs = list(outputs)
    slots = [f"val[{i}]" for i in range(n_out)]
    for i, f in enumerate(outputs if jacobian else []):
        for a, x in enumerate(inputs):
            d = sp.diff(f, x)
            if d != 0:
                exprs.append(d)
                slots.append(f"jac[{i}, {a}]")
    if hessian:
        for i, f in enumerate(outputs):
            for a, x in enumerate(inputs):
                da = sp.diff(f, x)
                for b in range(a, n_in):
                    d = sp.diff(da, inputs[b])
                    if d != 0:
                        exprs.append(d)
                        slots.append(f"hes[{i}, {a}, {b}]" if a == b
                                     else f"hes[{i}, {a}, {b}] = hes[{i}, {b}, {a}]")
    args = ["x", "p", "val"] + (["jac"] if jacobian else []) + (["hes"] if hessian else [])
    return _code(name, doc, inputs, params, exprs, slots, args)


def _code(name: str, doc: str, inputs: list[sp.Symbol], params: list[sp.Symbol],
          exprs: list[sp.Expr], slots: list[str], args: list[str]) -> str:
    reps, reduced = sp.cse(exprs, symbols=sp.numbered_symbols("w"), optimizations="basic")
    printer = PythonCodePrinter({"fully_qualified_modules": False,
                                                    "standard": "python3"})
    lines = [f"@njit(refcount=False)\ndef {name}({', '.join(args)}):",
             f'    """{doc}"""']
    for i, s in enumerate(inputs):
        lines.append(f"    {s} = x[{i}]")
    for i, s in enumerate(params):
        lines.append(f"    {s} = p[{i}]")
    for sym, e in reps:
        lines.append(f"    {sym} = {printer.doprint(e)}")
    for slot, e in zip(slots, reduced, strict=True):
        lines.append(f"    {slot} = {printer.doprint(e)}")
    return "\n".join(lines) + "\n"


def generate() -> str:
    head = ('"""Exact derivatives of the rod\'s kinematic maps: GENERATED by tools/rod_derivatives.py '
            '(sympy).\n\nDo not edit: change the maps in the generator and run it. Each function '
            'takes the inputs ``x``\nand parameters ``p`` and writes the values ``val``, the '
            'Jacobian ``jac`` (outputs x inputs) and,\nwith ``hes``, the Hessians (outputs x '
            'inputs x inputs). Only the nonzero entries are written:\nthe caller zeroes ``jac`` '
            'and ``hes`` once.\n"""\n# generator sha256: ' + generator_hash() + '\n'
            '# ruff: noqa: E501, F841\n# fmt: off\n\nfrom __future__ import '
            'annotations\n\nfrom math import atan, atan2, cos, sin, sqrt  # noqa: F401\n\n'
            'from .._jit import njit\n\n'
            '__all__ = ["triad", "triad_h", "twist", "twist_h", "curvatures", "curvatures_wh", "axial",\n'
            '           "axial_h", "spin", "spin_value", "director_turn", "director_turn_h"]\n')
    parts = [head]
    maps = {"triad": (triad_map, "node (g, φ) -> (t, d2): x = [g, φ], p = [t̄, D̄]"),
            "twist": (twist_map, "nodal triads -> Δθ: x = [t0, d20, t1, d21]"),
            "curvatures": (curvature_map, "point -> (K1, K2, K3): x = [r′, r″, t0, d20, Δθ], "
                                          "p = [ξ, L, μ]"),
            "axial": (axial_map, "point -> ε: x = r′, p = [μ]"),
            "director_turn": (director_turn_map, "point -> β: x = [t, t0, d20], p = [t̄, ȳ]")}
    for name, (fn, doc) in maps.items():
        inputs, params, outputs = fn()
        parts.append("\n\n" + _emit(name, doc + " (values, Jacobian)", inputs, params, outputs,
                                    False))
        if name != "curvatures":
            parts.append("\n\n" + _emit(name + "_h", doc + " (values, Jacobian, Hessians)",
                                        inputs, params, outputs, True))
        else:
            sig = list(sp.symbols("sig0:3", real=True))
            parts.append("\n\n" + _emit(name + "_wh", doc + ", σ: the weighted Hessian "
                                        "Σ_j σ_j ∂²K_j/∂x² only (p = [ξ, L, μ, σ])", inputs,
                                        params, outputs, False, weights=sig))
    inputs, params, outputs = spin_map()
    spin_doc = "node (g, ġ) -> (w, b, s, c): x = [g, ġ], p = [t̄]"
    parts.append("\n\n" + _emit("spin", spin_doc + " (values, Jacobian)", inputs, params,
                                  outputs, False))
    parts.append("\n\n" + _emit("spin_value", spin_doc + " (values)", inputs, params, outputs,
                                  False, jacobian=False))
    text = "".join(parts)
    return text.replace("math.", "")


def main() -> int:
    text = generate()
    if "--check" in sys.argv:
        return 0 if TARGET.read_text() == text else 1
    TARGET.write_text(text)
    print(f"wrote {TARGET} ({text.count(chr(10))} lines)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Joint equation tables and their numba kernels (term_values / term_hessian / concatenate_tables).

Derivative checks use Richardson-extrapolated central differences, ``(4D(h) − D(2h))/3`` with
``D(h) = (f(q + h e_j) − f(q − h e_j))/2h``: its error is ``O(h⁴ f⁽⁵⁾)``, and Φ (and λ·Φ_q) is a
polynomial of degree ≤ 4 (≤ 3) in q, so the difference quotient is exact up to round-off
``~ ε·max|Φ|/h``. With h = 0.05 and O(1)–O(10) coordinates that is ≲ 1e-12 relative; the
tolerance FD_REL = 1e-10 leaves a margin of ~100 while still catching any missing term (O(1)).
"""

from __future__ import annotations

import itertools
from collections.abc import Callable

import numpy as np
import pytest

from flexmbs._jit import njit
from flexmbs.constraints.base import Attachment
from flexmbs.constraints.joints import (
    BODY_DIR,
    BODY_POINT,
    CONST,
    DOT,
    LIN,
    NODE_DIRECTOR,
    NODE_POS,
    NODE_SLOPE,
    BeamNodeRigid,
    BeamNodeSpherical,
    GenericJoint,
    TermTable,
    _TableBuilder,
    concatenate_tables,
    hessian_pattern,
    revolute,
    spherical,
    term_hessian,
    term_values,
    term_work,
)
from flexmbs.elements import rigid_body as rb

FD_H = 0.05
FD_REL = 1e-10      # see module docstring: exact difference quotient, round-off only
SAME_REL = 1e-14    # the same kernel on the same data, called from Python or from numba

BODY_A = np.arange(0, 7)
BODY_B = np.arange(7, 14)
NODE = np.arange(14, 20)
N_GLOBAL = 20

_Factory = Callable[[np.random.Generator], GenericJoint | BeamNodeRigid | BeamNodeSpherical]


def _rot(rng: np.random.Generator) -> np.ndarray:
    return rb.rotation_matrix(rb.normalize(rng.normal(size=4)))


def _body(dofs: np.ndarray, rng: np.random.Generator) -> Attachment:
    return Attachment.rigid_body(dofs, rng.normal(size=3), _rot(rng))


def _ground(rng: np.random.Generator) -> Attachment:
    return Attachment.ground(rng.normal(size=3), _rot(rng))


def _node(rng: np.random.Generator) -> Attachment:
    return Attachment.beam_node(NODE)


def _variants() -> dict[str, _Factory]:
    """Every GenericJoint mask on body–body, body–ground, ground–body (and translation masks on
    node–body, node–ground), BeamNodeSpherical and BeamNodeRigid to a body and to ground."""
    sides = {"bb": (lambda r: _body(BODY_A, r), lambda r: _body(BODY_B, r)),
             "bg": (lambda r: _body(BODY_A, r), _ground),
             "gb": (_ground, lambda r: _body(BODY_B, r)),
             "nb": (_node, lambda r: _body(BODY_B, r)),
             "ng": (_node, _ground)}
    out: dict[str, _Factory] = {}
    for m in itertools.product((0, 1), repeat=6):
        tr, ro = m[:3], m[3:]
        if not any(m):
            continue
        for key, (ma, mb) in sides.items():
            if key[0] == "n" and any(ro):
                continue
            out[f"generic_{key}_{''.join(map(str, m))}"] = (
                lambda r, ma=ma, mb=mb, tr=tr, ro=ro: GenericJoint("g", ma(r), mb(r), tr, ro))
    out["node_spherical_body"] = lambda r: BeamNodeSpherical("s", _node(r), _body(BODY_A, r))
    out["node_spherical_ground"] = lambda r: BeamNodeSpherical("s", _node(r), _ground(r))
    out["node_rigid_body"] = lambda r: BeamNodeRigid("n", _node(r), _body(BODY_A, r),
                                                     r.normal(size=(3, 2)))
    out["node_rigid_ground"] = lambda r: BeamNodeRigid("n", _node(r), _ground(r),
                                                       r.normal(size=(3, 2)))
    return out


VARIANTS = _variants()


def _values(table: TermTable, q: np.ndarray, n_eq: int) -> tuple[np.ndarray, np.ndarray]:
    phi = np.full(n_eq, np.nan)
    jac = np.full((n_eq, q.size), np.nan)   # the kernel must zero the rows itself
    term_values(table, 0, n_eq, q, phi, jac, term_work())
    return phi, jac


def _richardson(f: Callable[[np.ndarray], np.ndarray], q: np.ndarray, j: int) -> np.ndarray:
    def d(h: float) -> np.ndarray:
        e = np.zeros(q.size)
        e[j] = h
        return (f(q + e) - f(q - e)) / (2.0 * h)
    return (4.0 * d(FD_H) - d(2.0 * FD_H)) / 3.0


def _check_kernels(c, q: np.ndarray, lam: np.ndarray) -> None:
    """term_values Jacobian = FD of Φ; term_hessian = FD of λ·Φ_q, exactly symmetric."""
    m, t = c.n_equations, c.table
    phi, jac = _values(t, q, m)
    fd = np.column_stack([_richardson(lambda x: _values(t, x, m)[0], q, j) for j in range(q.size)])
    assert np.abs(jac - fd).max() <= FD_REL * max(np.abs(jac).max(), np.abs(phi).max(), 1.0)
    H = np.full((q.size, q.size), np.nan)             # the kernel must zero H itself
    term_hessian(t, 0, m, q, lam, H, term_work())
    assert np.array_equal(H, H.T)
    fdh = np.column_stack([_richardson(lambda x: _values(t, x, m)[1].T @ lam, q, j)
                           for j in range(q.size)])
    assert np.abs(H - fdh).max() <= FD_REL * max(np.abs(H).max(), np.abs(jac).max(), 1.0)
    # the Constraint methods are the same kernels
    phi_c, jac_c = c.evaluate(q, 0.0)
    assert np.array_equal(phi_c, phi) and np.array_equal(jac_c, jac)
    assert np.array_equal(c.hessian_lambda(q, lam, 0.0), H)


@pytest.mark.parametrize("kind", list(VARIANTS))
def test_kernels_match_finite_differences(kind):
    rng = np.random.default_rng(list(VARIANTS).index(kind))
    for scale in (1.0, 2.0, 3.0):   # p deliberately not unit; coordinates O(1)–O(3)
        c = VARIANTS[kind](rng)
        q = np.ascontiguousarray(scale * rng.normal(size=N_GLOBAL)[c.coordinates()])
        _check_kernels(c, q, rng.normal(size=c.n_equations))


def test_table_semantics():
    """Documented layout: spherical to ground is LIN with P = I of (body point − ground point);
    a revolute between bodies is 3 LIN equations (global components of the points'
    difference) and 2 DOT equations of body directions."""
    g = Attachment.ground((1.0, 2.0, 3.0))
    s = spherical("s", Attachment.rigid_body(BODY_A, (0.5, 0.0, 0.0)), g)
    t = s.table
    assert t.eq_kind.tolist() == [LIN] * 3 and np.array_equal(t.eq_P, np.eye(3))
    u1, u2 = t.eq_vec[0, 0], t.eq_vec[0, 1]
    assert (t.vec_kind[u1], t.vec_off[u1], t.vec_kind[u2]) == (BODY_POINT, 0, CONST)
    assert t.vec_c[u2].tolist() == [1.0, 2.0, 3.0]
    assert np.array_equal(t.vec_T[u1], rb.point_tensor(np.array([0.5, 0.0, 0.0])))
    assert not t.vec_T[u2].any() and (t.eq_vec[:, 2:] == -1).all()
    r = revolute("r", _body(BODY_A, np.random.default_rng(0)), _body(BODY_B, np.random.default_rng(1)))
    t = r.table
    assert t.eq_kind.tolist() == [LIN] * 3 + [DOT] * 2
    assert np.array_equal(t.eq_P[:3], np.eye(3)) and not t.eq_P[3:].any()
    assert set(t.vec_kind[t.eq_vec[:3, :2].ravel()].tolist()) == {BODY_POINT}
    assert set(t.vec_kind[t.eq_vec[3:, :2].ravel()].tolist()) == {BODY_DIR}
    assert set(t.vec_off.tolist()) == {0, 7}
    n = BeamNodeRigid("n", Attachment.beam_node(NODE), g, np.eye(3)[:, :2])
    assert set(n.table.vec_kind.tolist()) == {NODE_POS, NODE_SLOPE, CONST}
    assert n.table.directors is None           # no rod code compiled for such tables
    for arr in n.table:
        assert arr is None or arr.flags.c_contiguous
    # node directors (rods) are listed, also after concatenation (rows shifted)
    tb = _TableBuilder()
    tb.lin(np.eye(3), tb.vec(NODE_POS, 0), tb.vec(CONST, 0, (1.0, 0.0, 0.0)))
    tb.dot(tb.vec(NODE_DIRECTOR, 0, (1.0, 0.0, 0.0), (0.0, 1.0, 0.0)), -1,
           tb.vec(CONST, 0, (0.0, 0.0, 1.0)), -1)
    rod = tb.build()
    assert rod.directors.tolist() == [2]
    both, _ = concatenate_tables([n.table, rod])
    assert both.directors.tolist() == [n.table.vec_kind.size + 2]
    assert concatenate_tables([n.table, n.table])[0].directors is None


def _mixed_constraints(rng: np.random.Generator) -> list:
    names = ["generic_bb_111011", "generic_bg_011111", "generic_gb_111111", "generic_ng_111000",
             "generic_nb_011000", "node_rigid_body", "node_rigid_ground", "node_spherical_body"]
    return [VARIANTS[k](rng) for k in names]


@pytest.mark.parametrize("name", sorted(VARIANTS))
def test_hessian_is_zero_outside_its_pattern(name):
    """The assembler reserves only hessian_pattern's entries of a joint's Hessian (a spherical
    joint's has no block between its two bodies): the kernel's Hessian is exactly zero
    elsewhere, at random q and λ, and the pattern is symmetric."""
    rng = np.random.default_rng(4)
    c = VARIANTS[name](rng)
    n = c.coordinates().size
    mask = hessian_pattern(c.table, 0, c.n_equations, n)
    assert np.array_equal(mask, mask.T)
    for _ in range(3):
        H = c.hessian_lambda(rng.normal(size=n), rng.normal(size=c.n_equations), 0.0)
        assert np.all(H[~mask] == 0.0)


def test_concatenate_tables():
    cons = _mixed_constraints(np.random.default_rng(7))
    big, eq_ptr = concatenate_tables([c.table for c in cons])
    assert eq_ptr.dtype == np.int64 and eq_ptr.tolist() == np.cumsum(
        [0] + [c.n_equations for c in cons]).tolist()
    v0 = 0
    for k, c in enumerate(cons):
        t = c.table
        rows = big.eq_vec[eq_ptr[k]:eq_ptr[k + 1]]
        assert np.array_equal(rows, np.where(t.eq_vec >= 0, t.eq_vec + v0, -1))
        nv = t.vec_kind.size
        assert np.array_equal(big.vec_off[v0:v0 + nv], t.vec_off)   # stays local
        assert np.array_equal(big.vec_T[v0:v0 + nv], t.vec_T)
        v0 += nv
    empty, ptr = concatenate_tables([])
    assert ptr.tolist() == [0] and empty.eq_kind.size == 0 and empty.vec_T.shape == (0, 3, 4, 4)


@njit(cache=False)
def _all_joints(table, eq_ptr, q_all, q_ptr, lam, phi, jac, H, work):
    """What the compiled integrator does: every joint of a concatenated table in one loop, with
    one scratch."""
    for k in range(eq_ptr.size - 1):
        e0, e1 = eq_ptr[k], eq_ptr[k + 1]
        q = q_all[q_ptr[k]:q_ptr[k + 1]]
        n = q.size
        term_values(table, e0, e1, q, phi[e0:e1], jac[e0:e1, :n], work)
        term_hessian(table, e0, e1, q, lam[e0:e1], H[k, :n, :n], work)


def test_kernels_callable_from_numba():
    rng = np.random.default_rng(11)
    cons = _mixed_constraints(rng)
    big, eq_ptr = concatenate_tables([c.table for c in cons])
    q = rng.normal(size=N_GLOBAL)
    q_locals = [q[c.coordinates()] for c in cons]
    q_ptr = np.cumsum([0] + [x.size for x in q_locals]).astype(np.int64)
    n_max, m = max(x.size for x in q_locals), int(eq_ptr[-1])
    lam = rng.normal(size=m)
    phi, jac = np.full(m, np.nan), np.full((m, n_max), np.nan)
    H = np.full((len(cons), n_max, n_max), np.nan)
    _all_joints(big, eq_ptr, np.concatenate(q_locals), q_ptr, lam, phi, jac, H, term_work())
    for k, c in enumerate(cons):
        e0, e1, n = eq_ptr[k], eq_ptr[k + 1], q_locals[k].size
        p_ref, j_ref = c.evaluate(q_locals[k], 0.0)
        h_ref = c.hessian_lambda(q_locals[k], lam[e0:e1], 0.0)
        assert np.allclose(phi[e0:e1], p_ref, rtol=SAME_REL, atol=SAME_REL)
        assert np.allclose(jac[e0:e1, :n], j_ref, rtol=SAME_REL, atol=SAME_REL)
        assert np.allclose(H[k, :n, :n], h_ref, rtol=SAME_REL, atol=SAME_REL)


def test_wrong_local_sizes_raise():
    c = revolute("r", _body(BODY_A, np.random.default_rng(0)), Attachment.ground())
    with pytest.raises(ValueError, match="q_local"):
        c.evaluate(np.zeros(6), 0.0)
    with pytest.raises(ValueError, match="lam"):
        c.hessian_lambda(np.zeros(7), np.zeros(4), 0.0)

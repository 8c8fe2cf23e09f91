"""Element A, the 12-DOF ANCF cable (docs/theory.md §I.1): closed forms, FD derivatives, invariance."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from flexmbs.elements import ancf_cable as cable

# --- tolerances, in one place -----------------------------------------------------------------
#: closed-form mass / load vectors vs. 6-point Gauss (exact for the degree-6 integrands): roundoff
RTOL_EXACT = 1e-13
#: central differences with h = 1e-6 on O(1) coordinates: truncation ~h² ≈ 1e-12, roundoff
#: ~1e-16·|U|/h ≈ 1e-10 of the force scale; 1e-6 leaves margin for the stiff axial terms
RTOL_FD = 1e-6
FD_STEP = 1e-6
#: "zero" force: roundoff of Σ w EA ε ... with EA = 100 and |r′| ≈ 1 is ~1e-14; 1e-9·EA is the brief
ZERO_FORCE = 1e-9
#: docs/theory.md §I.1.3 Evidence gives 2.75 (3 digits) for Exudyn A-vec after R_x(90°)
RTOL_EXUDYN = 1e-2

ALL_OPTIONS = [
    cable.CableOptions(bending=bend, axial_rule=rule, bending_points=nb)
    for bend, rule, nb in itertools.product(("vector", "scalar"), ("lobatto3", "gauss5"), (2, 3))
] + [
    cable.CableOptions(exudyn_compatible=True),
    cable.CableOptions(exudyn_compatible=True, axial_rule="gauss5", bending_points=3),
    cable.CableOptions(exudyn_compatible=True, bending_points=2),
]


def _ids(o: cable.CableOptions) -> str:
    tag = "-exudyn" if o.exudyn_compatible else ""
    return f"{o.bending}-{o.axial_rule}-{o.bending_points}{tag}"


# --- fixtures ---------------------------------------------------------------------------------
def arc_elements(n_elem: int, R: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Quarter circle in the xy-plane: Hermite nodes r_i = R(cos θ, sin θ, 0), r′_i = unit
    tangents, element length R·dθ. Returns q_ref (n_elem, 12) and L (n_elem,)."""
    th = np.linspace(0.0, 0.5 * np.pi, n_elem + 1)
    P = np.stack([R * np.cos(th), R * np.sin(th), 0.0 * th], axis=1)
    T = np.stack([-np.sin(th), np.cos(th), 0.0 * th], axis=1)
    q = np.hstack([P[:-1], T[:-1], P[1:], T[1:]])
    return np.ascontiguousarray(q), np.full(n_elem, R * (th[1] - th[0]))


def straight_elements(n_elem: int, length: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Straight bar along +x with unit slopes."""
    x = np.linspace(0.0, length, n_elem + 1)
    P = np.stack([x, 0 * x, 0 * x], axis=1)
    T = np.tile([1.0, 0.0, 0.0], (n_elem + 1, 1))
    q = np.hstack([P[:-1], T[:-1], P[1:], T[1:]])
    return np.ascontiguousarray(q), np.full(n_elem, length / n_elem)


def make_props(L: np.ndarray, *, EA: float | np.ndarray = 100.0, EI: float | np.ndarray = 1.0,
               rhoA: float = 1.0, d_eps: float = 0.0, d_K: float = 0.0,
               eps0: float = 0.0) -> cable.CableProperties:
    n = L.shape[0]
    return cable.CableProperties(
        length=L.copy(), axial_stiffness=np.broadcast_to(np.asarray(EA, float), (n,)).copy(),
        bending_stiffness=np.broadcast_to(np.asarray(EI, float), (n,)).copy(),
        mass_per_length=np.full(n, rhoA), axial_damping=np.full(n, d_eps),
        bending_damping=np.full(n, d_K), reference_axial_strain=np.full(n, eps0))


def forces(q, v, props, rest, options, *, matrices=False):
    n = q.shape[0]
    F = np.zeros((n, 12))
    if not matrices:
        cable.internal_forces(np.ascontiguousarray(q), np.ascontiguousarray(v), props, rest,
                              options, F)
        return F
    K = np.zeros((n, 12, 12))
    C = np.zeros((n, 12, 12))
    cable.internal_forces(np.ascontiguousarray(q), np.ascontiguousarray(v), props, rest, options,
                          F, K, C)
    return F, K, C


def assemble(F: np.ndarray) -> np.ndarray:
    """Sum element vectors of a single open chain into nodal DOFs, length 6(n_elem + 1)."""
    n = F.shape[0]
    Q = np.zeros(6 * (n + 1))
    for e in range(n):
        Q[6 * e:6 * e + 12] += F[e]
    return Q


def rotate(q: np.ndarray, R: np.ndarray) -> np.ndarray:
    """Rigid rotation of all nodal positions and slopes about the origin."""
    return (q.reshape(-1, 4, 3) @ R.T).reshape(q.shape)


def rot_x(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_z(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def gauss_S(L: float, n: int = 6) -> tuple[np.ndarray, np.ndarray]:
    """(n, 3, 12) S-matrices and dx-weights of an n-point Gauss rule on [0, L]."""
    x, w = np.polynomial.legendre.leggauss(n)
    xi = 0.5 * (x + 1.0)
    S, _, _ = cable.shape_functions(xi, np.full(n, L))
    Smat = np.einsum("pn,cd->pcnd", S, np.eye(3)).reshape(n, 3, 12)
    return Smat, 0.5 * w * L


# --- 1. mass and loads --------------------------------------------------------------------------
def test_shape_functions_interpolate_nodes_and_derivatives() -> None:
    L = np.array([0.7, 0.7, 1.3])
    S, dS, ddS = cable.shape_functions(np.array([0.0, 1.0, 0.3]), L)
    assert S.shape == dS.shape == ddS.shape == (3, 4)
    np.testing.assert_allclose(S[0], [1, 0, 0, 0], atol=1e-15)
    np.testing.assert_allclose(S[1], [0, 0, 1, 0], atol=1e-15)
    np.testing.assert_allclose(dS[0], [0, 1, 0, 0], atol=1e-15)
    np.testing.assert_allclose(dS[1], [0, 0, 0, 1], atol=1e-15)
    # derivative tables vs central differences in x = ξL; cubic => only roundoff ~1e-11/h
    h = 1e-5
    Sp, dSp, _ = cable.shape_functions(np.array([0.3 + h / 1.3]), np.array([1.3]))
    Sm, dSm, _ = cable.shape_functions(np.array([0.3 - h / 1.3]), np.array([1.3]))
    np.testing.assert_allclose((Sp - Sm)[0] / (2 * h), dS[2], rtol=1e-8)
    np.testing.assert_allclose((dSp - dSm)[0] / (2 * h), ddS[2], rtol=1e-8)
    # table form: xi[None, :] with L[:, None]
    S2, _, _ = cable.shape_functions(np.array([0.0, 0.5])[None, :], L[:, None])
    assert S2.shape == (3, 2, 4)


def test_mass_matrix_matches_quadrature_and_total_mass() -> None:
    L = np.array([0.4, 1.0, 2.5])
    props = make_props(L, rhoA=3.2)
    M = cable.mass_matrix(props)
    assert M.shape == (3, 12, 12)
    for e in range(3):
        Smat, w = gauss_S(L[e])
        M_ref = 3.2 * np.einsum("p,pci,pcj->ij", w, Smat, Smat)
        np.testing.assert_allclose(M[e], M_ref, rtol=RTOL_EXACT,
                                   atol=RTOL_EXACT * np.abs(M_ref).max())
        # rigid translation u (positions 1, slopes 0): uᵀMu = ρA L
        u = np.zeros(12)
        u[[0, 6]] = 1.0
        assert u @ M[e] @ u == pytest.approx(3.2 * L[e], rel=RTOL_EXACT)
    np.testing.assert_allclose(M, np.transpose(M, (0, 2, 1)))


def test_gravity_distributed_and_point_loads() -> None:
    L = np.array([0.4, 1.0, 2.5])
    props = make_props(L, rhoA=3.2)
    g = np.array([0.3, -1.0, -9.81])
    Qg = cable.gravity_force(props, g)
    f = np.array([[1.0, 2.0, 3.0], [-1.0, 0.5, 0.0], [0.0, 0.0, 7.0]])
    Qf = cable.distributed_force(props, f)
    for e in range(3):
        Smat, w = gauss_S(L[e])
        ref = 3.2 * np.einsum("p,pci,c->i", w, Smat, g)
        np.testing.assert_allclose(Qg[e], ref, rtol=RTOL_EXACT, atol=RTOL_EXACT * np.abs(ref).max())
        ref = np.einsum("p,pci,c->i", w, Smat, f[e])
        np.testing.assert_allclose(Qf[e], ref, rtol=RTOL_EXACT, atol=RTOL_EXACT * np.abs(ref).max())
    # total gravity force on the positions = ρA L g
    np.testing.assert_allclose(Qg[:, 0:3] + Qg[:, 6:9], 3.2 * L[:, None] * g[None, :], rtol=1e-14)
    # point force: S(ξ)ᵀF; at ξ = 1 it acts on r1 only
    F = np.array([[1.0, -2.0, 0.5], [0.0, 3.0, 0.0]])
    Qp = cable.point_force_vector(np.array([1.0, 0.25]), np.array([2.0, 2.0]), F)
    np.testing.assert_allclose(Qp[0], np.r_[0, 0, 0, 0, 0, 0, F[0], 0, 0, 0], atol=1e-15)
    S, _, _ = cable.shape_functions(np.array([0.25]), np.array([2.0]))
    np.testing.assert_allclose(Qp[1], np.kron(S[0], F[1]), rtol=1e-15)


# --- 2./3. analytic force and tangents vs finite differences -------------------------------------
def _perturbed_arc(rng: np.random.Generator, n: int = 3):
    q_ref, L = arc_elements(n)
    q = q_ref + 0.08 * rng.standard_normal(q_ref.shape)
    return q_ref, L, q


@pytest.mark.parametrize("options", ALL_OPTIONS, ids=_ids)
def test_force_is_gradient_of_strain_energy(options: cable.CableOptions,
                                            rng: np.random.Generator) -> None:
    q_ref, L, q = _perturbed_arc(rng)
    # element-wise different stiffnesses check the per-element indexing; ε0 ≠ 0 the offset
    props = make_props(L, EA=np.array([100.0, 250.0, 80.0]), EI=np.array([1.0, 0.5, 2.0]),
                       eps0=-0.01)
    rest = cable.rest_state(q_ref, props, options)
    F = forces(q, np.zeros_like(q), props, rest, options)
    G = np.zeros_like(F)
    for i in range(12):
        dq = np.zeros(12)
        dq[i] = FD_STEP
        G[:, i] = (cable.strain_energy(q + dq, props, rest, options)
                   - cable.strain_energy(q - dq, props, rest, options)) / (2 * FD_STEP)
    np.testing.assert_allclose(F, G, rtol=0, atol=RTOL_FD * np.abs(F).max())


def _assert_tangents_match_fd(K, C, q, v, props, rest, options):
    """``K = ∂Q/∂q`` and ``C = ∂Q/∂q̇`` against central differences of the forces."""
    K_fd = np.zeros_like(K)
    C_fd = np.zeros_like(C)
    for i in range(12):
        dq = np.zeros(12)
        dq[i] = FD_STEP
        K_fd[:, :, i] = (forces(q + dq, v, props, rest, options)
                         - forces(q - dq, v, props, rest, options)) / (2 * FD_STEP)
        C_fd[:, :, i] = (forces(q, v + dq, props, rest, options)
                         - forces(q, v - dq, props, rest, options)) / (2 * FD_STEP)
    np.testing.assert_allclose(K, K_fd, rtol=0, atol=RTOL_FD * np.abs(K).max())
    np.testing.assert_allclose(C, C_fd, rtol=0, atol=RTOL_FD * np.abs(C).max())


@pytest.mark.parametrize("options", ALL_OPTIONS, ids=_ids)
def test_tangents_match_fd_with_damping_and_velocity(options: cable.CableOptions,
                                                     rng: np.random.Generator) -> None:
    q_ref, L, q = _perturbed_arc(rng)
    v = rng.standard_normal(q.shape)
    props = make_props(L, EA=np.array([100.0, 250.0, 80.0]), EI=np.array([1.0, 0.5, 2.0]),
                       d_eps=0.7, d_K=0.3, eps0=0.02)
    rest = cable.rest_state(q_ref, props, options)
    F, K, C = forces(q, v, props, rest, options, matrices=True)
    _assert_tangents_match_fd(K, C, q, v, props, rest, options)
    # the damping force depends on q: removing it must change the stiffness
    props0 = props._replace(axial_damping=np.zeros(3), bending_damping=np.zeros(3))
    _, K0, C0 = forces(q, v, props0, rest, options, matrices=True)
    assert np.abs(K - K0).max() > 1e-3 * np.abs(K).max()
    assert np.abs(C0).max() == 0.0


@pytest.mark.parametrize("options", ALL_OPTIONS, ids=_ids)
def test_tangents_match_fd_with_damping_on_some_elements(options: cable.CableOptions,
                                                         rng: np.random.Generator) -> None:
    """The kernel skips the damping's terms of an element without damping: element 0 has
    axial damping only, element 1 bending damping only, element 2 none; the tangents still
    match central differences, and the undamped element's ∂Q/∂q̇ is overwritten with zeros."""
    q_ref, L, q = _perturbed_arc(rng)
    v = rng.standard_normal(q.shape)
    props = make_props(L, EA=np.array([100.0, 250.0, 80.0]), EI=np.array([1.0, 0.5, 2.0]),
                       eps0=0.02)
    props = props._replace(axial_damping=np.array([0.7, 0.0, 0.0]),
                           bending_damping=np.array([0.0, 0.3, 0.0]))
    rest = cable.rest_state(q_ref, props, options)
    F = np.zeros((3, 12))
    K = np.full((3, 12, 12), 4.0)
    C = np.full((3, 12, 12), -3.0)
    cable.internal_forces(q, v, props, rest, options, F, K, C)
    _assert_tangents_match_fd(K, C, q, v, props, rest, options)
    assert np.abs(C[0]).max() > 0.0 and np.abs(C[1]).max() > 0.0
    assert np.abs(C[2]).max() == 0.0
    # the undamped element's tangent is the symmetric Hessian of its strain energy
    np.testing.assert_allclose(K[2], K[2].T, rtol=0, atol=1e-12 * np.abs(K[2]).max())


def test_outputs_are_overwritten_and_force_only_matches(rng: np.random.Generator) -> None:
    q_ref, L, q = _perturbed_arc(rng)
    v = rng.standard_normal(q.shape)
    props = make_props(L, d_eps=0.2, d_K=0.1)
    options = cable.CableOptions()
    rest = cable.rest_state(q_ref, props, options)
    F, K, C = forces(q, v, props, rest, options, matrices=True)
    F2 = np.full_like(F, 123.0)
    K2 = np.full_like(K, -7.0)
    C2 = np.full_like(C, 9.0)
    cable.internal_forces(q, v, props, rest, options, F2, K2, C2)
    np.testing.assert_array_equal(F2, F)
    np.testing.assert_array_equal(K2, K)
    np.testing.assert_array_equal(C2, C)
    F3 = np.full_like(F, 5.0)
    cable.internal_forces(q, v, props, rest, options, F3)
    np.testing.assert_array_equal(F3, F)


# --- 4. stress-free reference and objectivity --------------------------------------------------
@pytest.mark.parametrize("options", ALL_OPTIONS, ids=_ids)
def test_zero_force_in_curved_reference_and_inplane_rotation(options: cable.CableOptions) -> None:
    q_ref, L = arc_elements(8)
    props = make_props(L)
    rest = cable.rest_state(q_ref, props, options)
    for R in (np.eye(3), rot_z(0.5 * np.pi)):
        F = forces(rotate(q_ref, R), np.zeros_like(q_ref), props, rest, options)
        assert np.abs(F).max() < ZERO_FORCE * 100.0
    assert np.abs(cable.strain_energy(q_ref, props, rest, options)).max() < 1e-25


def test_scalar_bending_is_objective_out_of_plane() -> None:
    q_ref, L = arc_elements(8)
    props = make_props(L)
    options = cable.CableOptions(bending="scalar")
    rest = cable.rest_state(q_ref, props, options)
    for angle in (0.5 * np.pi, np.pi, 0.3):
        for R in (rot_x(angle), rot_z(0.2) @ rot_x(angle)):
            q = rotate(q_ref, R) + np.tile([0.3, -1.0, 2.0, 0.0, 0.0, 0.0], 2)  # + translation
            F = forces(q, np.zeros_like(q), props, rest, options)
            assert np.abs(F).max() < ZERO_FORCE * 100.0


def test_vector_bending_is_not_objective_exudyn_value() -> None:
    """docs/theory.md §I.1.3 Evidence: Exudyn A-vec, quarter circle R = 1, 8 elements, EI = 1,
    EA = 100, default Exudyn quadrature (axial 5, bending 3): |Q_int| = 2.75 after R_x(90°),
    2.83 after R_x(180°)."""
    q_ref, L = arc_elements(8)
    props = make_props(L, EA=100.0, EI=1.0)
    options = cable.CableOptions(exudyn_compatible=True, axial_rule="gauss5", bending_points=3)
    rest = cable.rest_state(q_ref, props, options)
    Q90 = assemble(forces(rotate(q_ref, rot_x(0.5 * np.pi)), np.zeros_like(q_ref), props, rest,
                          options))
    Q180 = assemble(forces(rotate(q_ref, rot_x(np.pi)), np.zeros_like(q_ref), props, rest, options))
    assert np.linalg.norm(Q90) == pytest.approx(2.75, rel=RTOL_EXUDYN)
    assert np.linalg.norm(Q180) == pytest.approx(2.83, rel=RTOL_EXUDYN)
    # the exact-strain A-vec is equally non-objective
    options = cable.CableOptions(bending="vector")
    rest = cable.rest_state(q_ref, props, options)
    Q = assemble(forces(rotate(q_ref, rot_x(0.5 * np.pi)), np.zeros_like(q_ref), props, rest,
                        options))
    assert np.linalg.norm(Q) > 1.0


# --- 5. rigid translation, uniform stretch -----------------------------------------------------
@pytest.mark.parametrize("options", ALL_OPTIONS, ids=_ids)
def test_rigid_translation_gives_zero_force(options: cable.CableOptions,
                                            rng: np.random.Generator) -> None:
    q_ref, L = arc_elements(4)
    props = make_props(L, d_eps=0.5, d_K=0.5)
    rest = cable.rest_state(q_ref, props, options)
    c = rng.standard_normal(3)
    u = np.tile(np.r_[c, 0, 0, 0], 2)            # positions shift by c, slopes unchanged
    cdot = rng.standard_normal(3)
    v = np.tile(np.r_[cdot, 0, 0, 0], (4, 2))    # rigid translational velocity: no damping force
    F = forces(q_ref + u, v, props, rest, options)
    assert np.abs(F).max() < ZERO_FORCE * 100.0


@pytest.mark.parametrize("options", ALL_OPTIONS, ids=_ids)
def test_uniform_stretch_of_straight_bar(options: cable.CableOptions) -> None:
    """r(x) = (1 + e) x e_x: N = EA(e − ε0) exactly, Q = N [−e_x, 0, e_x, 0] per element."""
    n, e, EA, eps0 = 3, 0.013, 250.0, -0.004
    q_ref, L = straight_elements(n, 1.5)
    props = make_props(L, EA=EA, EI=2.0, eps0=eps0)
    rest = cable.rest_state(q_ref, props, options)
    q = q_ref * (1.0 + e)
    F = forces(q, np.zeros_like(q), props, rest, options)
    N = EA * (e - eps0)
    expected = np.tile(np.r_[-N, 0, 0, 0, 0, 0, N, 0, 0, 0, 0, 0], (n, 1))
    np.testing.assert_allclose(F, expected, rtol=0, atol=1e-12 * N)
    eps, K = cable.axial_strain_and_curvature(q, rest, options, np.array([0.0, 0.3, 1.0]))
    np.testing.assert_allclose(eps, e, rtol=1e-13)
    np.testing.assert_allclose(K, 0.0, atol=1e-14)
    # energy = ½ EA (e − ε0)² × total length (ds0 = dx for a straight unit-slope reference)
    U = cable.strain_energy(q, props, rest, options).sum()
    assert pytest.approx(0.5 * EA * (e - eps0) ** 2 * 1.5, rel=1e-12) == U


def test_straight_reference_exudyn_equals_exact() -> None:
    """With |r′_ref| = 1 the Exudyn and exact strains coincide (docs/theory.md §I.1.3)."""
    rng = np.random.default_rng(7)
    q_ref, L = straight_elements(3)
    q = q_ref + 0.05 * rng.standard_normal(q_ref.shape)
    v = rng.standard_normal(q.shape)
    props = make_props(L, d_eps=0.3, d_K=0.2, eps0=0.01)
    out = []
    for opts in (cable.CableOptions(), cable.CableOptions(exudyn_compatible=True)):
        rest = cable.rest_state(q_ref, props, opts)
        out.append(forces(q, v, props, rest, opts, matrices=True))
    for A, B in zip(out[0], out[1], strict=True):
        np.testing.assert_allclose(A, B, rtol=0, atol=1e-12 * np.abs(A).max())


def test_reference_curvature_of_arc() -> None:
    """K_ref of the Hermite quarter circle ≈ e_z/R. The cubic Hermite arc with unit nodal slopes
    has a curvature error O(θ_e²): ≈ θ_e²/12 ≈ 3.2e-3 at the nodes for 8 elements of 11.25°,
    half of that at the Gauss points; rtol 5e-3."""
    R = 2.0
    q_ref, L = arc_elements(8, R)
    options = cable.CableOptions()
    rest = cable.rest_state(q_ref, make_props(L), options)
    np.testing.assert_allclose(rest.rest_curvature[..., 2], 1.0 / R, rtol=5e-3)
    np.testing.assert_allclose(rest.rest_curvature[..., :2], 0.0, atol=1e-14)
    eps, K = cable.axial_strain_and_curvature(q_ref, rest, options, np.linspace(0, 1, 5))
    np.testing.assert_allclose(eps, 0.0, atol=1e-14)
    np.testing.assert_allclose(K[..., 2], 1.0 / R, rtol=5e-3)


# --- 6. scalar and vector bending agree in the plane ------------------------------------------
@pytest.mark.parametrize("rule", ["lobatto3", "gauss5"])
def test_scalar_and_vector_agree_in_plane(rule: str, rng: np.random.Generator) -> None:
    q_ref, L = arc_elements(4)
    props = make_props(L, d_eps=0.2, d_K=0.1)
    inplane = np.tile([1.0, 1.0, 0.0], 4)
    # small perturbation: the curvature must keep the sign of K_ref (A-scal cannot see a flip)
    q = q_ref + 0.003 * rng.standard_normal(q_ref.shape) * inplane
    v = rng.standard_normal(q.shape) * inplane
    res = []
    for bend in ("vector", "scalar"):
        opts = cable.CableOptions(bending=bend, axial_rule=rule)
        rest = cable.rest_state(q_ref, props, opts)
        res.append(forces(q, v, props, rest, opts, matrices=True))
    ip = np.flatnonzero(inplane)
    assert np.abs(res[0][0]).max() > 1e-2  # a deformed, loaded state
    # δ = 1e-8/L regularisation changes |K| by ~δ²/|K| ≈ 1e-17: agreement to roundoff
    for A, B in zip(res[0], res[1], strict=True):
        scale = np.abs(A).max()
        if A.ndim == 2:
            np.testing.assert_allclose(A, B, rtol=0, atol=1e-11 * scale)
        else:
            np.testing.assert_allclose(A[:, ip][:, :, ip], B[:, ip][:, :, ip], rtol=0,
                                       atol=1e-11 * scale)


def test_options_are_validated() -> None:
    with pytest.raises(ValueError, match="bending_points"):
        cable.CableOptions(bending_points=4)
    with pytest.raises(ValueError, match="bending"):
        cable.CableOptions(bending="tensor")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="axial_rule"):
        cable.CableOptions(axial_rule="gauss2")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="exudyn_compatible"):
        cable.CableOptions(exudyn_compatible=True, bending="scalar")
    with pytest.raises(TypeError):
        cable.CableOptions("scalar")  # type: ignore[misc]  # keyword-only

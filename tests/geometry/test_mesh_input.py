"""read_curve: meshio files (gmsh .msh 2.2/4.1, .vtu, .vtk) -> Centerline; the meshes/ inputs."""

from __future__ import annotations

from pathlib import Path

import meshio
import numpy as np
import pytest

from flexmbs.errors import GeometryError
from flexmbs.geometry.curves import Centerline, hermite_lengths
from flexmbs.geometry.mesh_input import read_curve

MESHES = Path(__file__).resolve().parents[2] / "meshes"

# Tolerances, in one place.
EXACT = 1e-12  # round-off (file round trips write floats with 16+ digits)
# Hermite element length on a circular arc: R theta_e (1 - theta_e^4/720) (see test_curves.py).
HERMITE_C4 = 1.0 / 720.0
# gmsh places the arc nodes through its own parametrisation: angles uniform to ~7e-10 rad.
GMSH_NODE = 1e-8

R = 1.0
CENTER = np.array([0.0, 0.0, 1.0])


def arc_points(n_points: int) -> np.ndarray:
    """Points of the Example 1 arc (R = 1, centre (0,0,1), -45..45 deg about (0,0,0)), in order."""
    phi = np.linspace(-np.pi / 4, np.pi / 4, n_points)
    return np.column_stack([R * np.sin(phi), np.zeros_like(phi), R - R * np.cos(phi)])


def hermite_total(n_elem: int) -> float:
    """Total Hermite length of the 90 deg arc in n_elem equal elements (exact nodes/tangents).

    Close to pi/2 (1 - theta_e^4/720); computed here to avoid the O(theta_e^6) remainder.
    """
    pts = arc_points(n_elem + 1)
    radial = pts - CENTER
    tangents = np.column_stack([-radial[:, 2], np.zeros(n_elem + 1), radial[:, 0]])
    return float(hermite_lengths(pts, tangents).sum())


def cells_of_order(n_cells: int, order: int) -> tuple[np.ndarray, np.ndarray]:
    """Points and gmsh/VTK-ordered cells [end0, end1, interior...] of the arc, order 1..3."""
    pts = arc_points(order * n_cells + 1)
    cells = []
    for k in range(n_cells):
        ids = list(range(order * k, order * k + order + 1))
        cells.append([ids[0], ids[-1], *ids[1:-1]])
    return pts, np.array(cells)


def scramble(pts: np.ndarray, cells: np.ndarray, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Shuffle cell order, flip a minority of the cells, and permute the point numbering."""
    rng = np.random.default_rng(seed)
    cells = cells[rng.permutation(len(cells))].copy()
    flip = rng.permutation(len(cells))[: (len(cells) - 1) // 2]
    for k in flip:
        cells[k] = [cells[k][1], cells[k][0], *cells[k][2:][::-1]]
    perm = rng.permutation(len(pts))  # new id of old point i is perm[i]
    new_pts = np.empty_like(pts)
    new_pts[perm] = pts
    return new_pts, perm[cells]


CELL_TYPE = {1: "line", 2: "line3", 3: "line4"}


def assert_is_arc(c: Centerline, n_elem: int) -> None:
    assert not c.closed
    assert c.n_elem == n_elem
    np.testing.assert_allclose(c.points[0], arc_points(2)[0], atol=EXACT)  # stored direction
    np.testing.assert_allclose(c.points[-1], arc_points(2)[1], atol=EXACT)
    np.testing.assert_allclose(np.linalg.norm(c.points - CENTER, axis=1), R, atol=EXACT)
    radial = c.points - CENTER
    np.testing.assert_allclose(np.einsum("ij,ij->i", radial, c.tangents), 0.0, atol=1e-12)
    assert c.tangents[0, 0] > 0  # pointing along the path
    assert c.total_length == pytest.approx(hermite_total(n_elem), rel=1e-12)


# --------------------------------------------------------------------------------------------------
# round trips


@pytest.mark.parametrize("order", [1, 2, 3])
@pytest.mark.parametrize("fmt", [("vtu", None), ("vtk", None), ("msh", "gmsh22"), ("msh", "gmsh")])
def test_round_trip_scrambled(tmp_path: Path, order: int, fmt: tuple[str, str | None]) -> None:
    pts, cells = scramble(*cells_of_order(8, order), seed=order)
    path = tmp_path / f"arc.{fmt[0]}"
    meshio.write(path, meshio.Mesh(pts, [(CELL_TYPE[order], cells)]), file_format=fmt[1])
    assert_is_arc(read_curve(path), n_elem=8)  # one element per cell, interior points -> tangents


def test_round_trip_vtk_lagrange_curve(tmp_path: Path) -> None:
    pts, cells = scramble(*cells_of_order(6, 3), seed=11)
    path = tmp_path / "arc.vtu"
    meshio.write(path, meshio.Mesh(pts, [("VTK_LAGRANGE_CURVE", cells)]))
    assert_is_arc(read_curve(path), n_elem=6)


def test_reversed_majority_reverses_the_path(tmp_path: Path) -> None:
    pts, cells = cells_of_order(5, 1)
    cells = cells[:, ::-1][::-1]  # every cell stored from +45 deg towards -45 deg
    path = tmp_path / "arc.vtu"
    meshio.write(path, meshio.Mesh(pts, [("line", cells)]))
    c = read_curve(path)
    np.testing.assert_allclose(c.points, pts[::-1], atol=EXACT)


def test_duplicate_points_are_merged(tmp_path: Path) -> None:
    # each segment with its own copy of its end points (as in glued or per-piece VTK output)
    base = arc_points(9)
    pts = np.concatenate([base[k : k + 2] for k in range(8)])
    pts = pts + 1e-13 * np.random.default_rng(0).standard_normal(pts.shape)  # round-off noise
    cells = np.arange(16).reshape(8, 2)
    path = tmp_path / "pieces.vtu"
    meshio.write(path, meshio.Mesh(pts, [("line", cells)]))
    c = read_curve(path)
    assert c.n_nodes == 9 and c.n_elem == 8
    np.testing.assert_allclose(c.points, base, atol=1e-12)


def test_resampling_to_elements(tmp_path: Path) -> None:
    pts, cells = cells_of_order(12, 2)
    path = tmp_path / "arc.msh"
    meshio.write(path, meshio.Mesh(pts, [("line3", cells)]), file_format="gmsh22")
    c = read_curve(path, elements=10)
    assert c.n_elem == 10
    assert np.ptp(c.lengths) / np.mean(c.lengths) < 1e-6  # spline vs Hermite arc length per elem
    # spline through 25 points 3.75 deg apart: radial error of the nodes ~ R dphi^4 / 384 ~ 1e-8
    np.testing.assert_allclose(np.linalg.norm(c.points - CENTER, axis=1), R, atol=1e-7)
    assert c.total_length == pytest.approx(hermite_total(10), rel=5e-7)  # measured 1.1e-7


def test_closed_loop(tmp_path: Path) -> None:
    phi = np.linspace(0, 2 * np.pi, 10, endpoint=False)
    pts = np.column_stack([np.cos(phi), np.sin(phi), np.zeros(10)])
    cells = np.column_stack([np.arange(10), (np.arange(10) + 1) % 10])
    path = tmp_path / "ring.vtu"
    meshio.write(path, meshio.Mesh(pts, [("line", cells[np.r_[3:10, 0:3]])]))
    c = read_curve(path)
    assert c.closed and c.n_nodes == 10 and c.n_elem == 10
    np.testing.assert_allclose(c.points, np.roll(pts, -3, axis=0), atol=EXACT)  # from 1st cell
    exact_t = np.column_stack([-pts[:, 1], pts[:, 0], np.zeros(10)])
    expect = hermite_lengths(pts, exact_t, closed=True).sum()  # ~ 2 pi (1 - theta_e^4/720)
    assert c.total_length == pytest.approx(expect, rel=1e-12)
    assert c.total_length == pytest.approx(2 * np.pi * (1 - (np.pi / 5) ** 4 * HERMITE_C4),
                                           rel=5e-6)  # O(theta_e^6) remainder at 36 deg


def test_closed_loop_of_line3_cells_mixed_directions(tmp_path: Path) -> None:
    phi = np.linspace(0, 2 * np.pi, 16, endpoint=False)
    pts = np.column_stack([2 * np.cos(phi), 2 * np.sin(phi), np.ones(16)])
    cells = np.array([[2 * k, (2 * k + 2) % 16, 2 * k + 1] for k in range(8)])
    cells[[1, 4, 6]] = cells[[1, 4, 6]][:, [1, 0, 2]]  # three cells stored backwards
    path = tmp_path / "ring3.msh"
    meshio.write(path, meshio.Mesh(pts, [("line3", cells)]), file_format="gmsh22")
    c = read_curve(path)
    assert c.closed and c.n_nodes == 8 and c.n_elem == 8
    np.testing.assert_allclose(c.points, pts[::2], atol=EXACT)  # majority direction, from cell 0
    exact_t = np.column_stack([-np.sin(phi), np.cos(phi), np.zeros(16)])[::2]
    np.testing.assert_allclose(c.tangents, exact_t, atol=EXACT)  # Bessel through mid-nodes
    # the tangent field of a loop running the other way reverses the path, keeping node 0
    t_rev = -np.column_stack([-np.sin(phi), np.cos(phi), np.zeros(16)])
    meshio.write(path, meshio.Mesh(pts, [("line3", cells)], point_data={"t": t_rev}),
                 file_format="gmsh22")
    r = read_curve(path, tangents_field="t")
    np.testing.assert_allclose(r.points[0], pts[0], atol=EXACT)
    np.testing.assert_allclose(r.points[1:], pts[::2][1:][::-1], atol=EXACT)
    np.testing.assert_allclose(r.tangents, -exact_t[np.r_[0, 7:0:-1]], atol=EXACT)


def test_tangents_from_point_data(tmp_path: Path) -> None:
    pts, cells = cells_of_order(4, 1)
    # deliberately not the circle's tangents (a tilted but valid field) to see they are used
    t = np.tile([1.0, 0.0, 0.0], (len(pts), 1))
    path = tmp_path / "arc.vtu"
    meshio.write(path, meshio.Mesh(pts, [("line", cells[:, ::-1])], point_data={"T": t}))
    c = read_curve(path, tangents_field="T")
    np.testing.assert_allclose(c.tangents, t, atol=EXACT)
    np.testing.assert_allclose(c.points, pts, atol=EXACT)  # the path follows the field


def test_group_selection_gmsh41(tmp_path: Path) -> None:
    pts_a, cells_a = cells_of_order(4, 1)
    pts_b = np.array([[0.0, 1.0, 0.0], [1.0, 1.0, 0.0], [2.0, 1.0, 0.0]])
    pts = np.vstack([pts_a, pts_b])
    cells_b = np.array([[0, 1], [1, 2]]) + len(pts_a)
    mesh = meshio.Mesh(
        pts, [("line", cells_a), ("line", cells_b)],
        cell_data={"gmsh:physical": [np.full(4, 1), np.full(2, 2)],
                   "gmsh:geometrical": [np.full(4, 1), np.full(2, 2)]},
        field_data={"rail": np.array([1, 1]), "wire": np.array([2, 1])},
        # gmsh 4.1 writer needs each node's entity; tags 1, 2 are the two curves
        point_data={"gmsh:dim_tags": np.array([[1, 1]] * len(pts_a) + [[1, 2]] * len(pts_b))},
    )
    for fmt in ("gmsh", "gmsh22"):
        path = tmp_path / f"two_{fmt}.msh"
        meshio.write(path, mesh, file_format=fmt)
        assert_is_arc(read_curve(path, group="rail"), n_elem=4)
        wire = read_curve(path, group="wire")
        np.testing.assert_allclose(wire.points, pts_b, atol=EXACT)
        np.testing.assert_allclose(wire.lengths, 1.0, rtol=EXACT)
        with pytest.raises(GeometryError, match="2 disconnected curves; pass group=.*rail, wire"):
            read_curve(path)
        with pytest.raises(GeometryError, match="unknown group 'rial'.*rail, wire"):
            read_curve(path, group="rial")


# --------------------------------------------------------------------------------------------------
# meshes/ folder


def test_meshes_arc_r1m_90deg() -> None:
    """16-segment Example 1 rail: sum of Hermite lengths vs pi/2.

    The exact-arc length of the fixed-point Hermite elements is pi/2 (1 - theta_e^4/720) with
    theta_e = pi/32: relative error -1.29e-7 (measured), so the brief's 1e-4 is met with margin;
    we test the predicted value to 1e-8 (gmsh node angles are uniform only to ~7e-10 rad).
    """
    c = read_curve(MESHES / "arc_r1m_90deg.msh", group="rail")
    assert c.n_elem == 16
    assert c.total_length == pytest.approx(np.pi / 2, rel=1e-4)
    assert c.total_length == pytest.approx(hermite_total(16), rel=1e-8)
    np.testing.assert_allclose(c.points[0], [-np.sqrt(0.5), 0, 1 - np.sqrt(0.5)], atol=EXACT)
    np.testing.assert_allclose(c.points[8], [0, 0, 0], atol=GMSH_NODE)
    np.testing.assert_allclose(c.tangents[8], [1, 0, 0], atol=GMSH_NODE)
    np.testing.assert_allclose(np.linalg.norm(c.points - CENTER, axis=1), R, atol=EXACT)
    np.testing.assert_allclose(c.lengths, hermite_total(16) / 16, rtol=1e-8)
    # curvature of the Hermite elements at 5 points each: 1/R up to the Hermite error
    # (measured max |kappa R - 1| = 8.0e-4 = theta_e^2/12 at the element ends, -4e-4 mid-element)
    xi = np.linspace(0.0, 1.0, 5)
    for e in range(c.n_elem):
        p0, p1 = c.points[e], c.points[e + 1]
        length = c.lengths[e]
        coef = np.stack([p0, length * c.tangents[e], p1, length * c.tangents[e + 1]])
        d1 = np.stack([6 * xi**2 - 6 * xi, 1 - 4 * xi + 3 * xi**2, 6 * xi - 6 * xi**2,
                       3 * xi**2 - 2 * xi], axis=-1) @ coef
        d2 = np.stack([12 * xi - 6, 6 * xi - 4, 6 - 12 * xi, 6 * xi - 2], axis=-1) @ coef
        kappa = np.linalg.norm(np.cross(d1, d2), axis=1) / np.linalg.norm(d1, axis=1) ** 3
        np.testing.assert_allclose(kappa * R, 1.0, atol=1e-3)
        binormal = np.cross(d1, d2)
        assert np.all(binormal[:, 1] < 0)  # turning about -y: the arc is concave upwards
    # the same file without naming the group, and resampled to 32 elements
    assert read_curve(MESHES / "arc_r1m_90deg.msh").total_length == c.total_length
    fine = read_curve(MESHES / "arc_r1m_90deg.msh", elements=32)
    assert fine.total_length == pytest.approx(np.pi / 2, rel=1e-6)


def test_meshes_guide_wire() -> None:
    c = read_curve(MESHES / "guide_wire.msh", group="guide_wire")
    assert c.n_elem == 12
    # meshed through the grommet centre (h, -e, 0), docs/theory.md §III.10: y = -e = -0.02
    np.testing.assert_allclose(c.points[0], [-0.1, -0.02, 0.0], atol=EXACT)
    np.testing.assert_allclose(c.points[-1], [1.1, -0.02, 0.0], atol=EXACT)
    np.testing.assert_allclose(c.tangents, np.tile([1.0, 0.0, 0.0], (13, 1)), atol=EXACT)
    # gmsh interpolates the nodes of a transfinite line to ~3e-13 m
    np.testing.assert_allclose(c.lengths, 0.1, rtol=1e-11)
    assert c.total_length == pytest.approx(1.2, rel=1e-12)


def test_meshes_geo_sources_present() -> None:
    for name in ("arc_r1m_90deg", "guide_wire"):
        assert (MESHES / f"{name}.geo").is_file()
        assert (MESHES / f"{name}.msh").read_text().startswith("$MeshFormat\n4.1 0 8")


# --------------------------------------------------------------------------------------------------
# errors


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(GeometryError, match="mesh file not found: .*nothing.msh"):
        read_curve(tmp_path / "nothing.msh")


def test_unreadable_file(tmp_path: Path) -> None:
    path = tmp_path / "bad.msh"
    path.write_text("this is not a gmsh file\n")
    with pytest.raises(GeometryError, match="cannot read mesh file .*bad.msh: "):
        read_curve(path)
    path = tmp_path / "bad.xyz123"
    path.write_text("0 0 0\n")
    with pytest.raises(GeometryError, match="cannot read mesh file .*bad.xyz123: "):
        read_curve(path)


def test_no_line_cells(tmp_path: Path) -> None:
    path = tmp_path / "tri.vtu"
    pts = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    meshio.write(path, meshio.Mesh(pts, [("triangle", np.array([[0, 1, 2]]))]))
    with pytest.raises(GeometryError, match="no 1D .*cell types found: triangle"):
        read_curve(path)


def test_branching_curve(tmp_path: Path) -> None:
    pts = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0], [1, 1, 0]])
    path = tmp_path / "tee.vtu"
    meshio.write(path, meshio.Mesh(pts, [("line", np.array([[0, 1], [1, 2], [1, 3]]))]))
    with pytest.raises(GeometryError, match=r"branches at point \[1.0, 0.0, 0.0\]"):
        read_curve(path)


def test_disconnected_without_groups(tmp_path: Path) -> None:
    pts = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]])
    path = tmp_path / "two.vtu"
    meshio.write(path, meshio.Mesh(pts, [("line", np.array([[0, 1], [2, 3]]))]))
    with pytest.raises(GeometryError, match="2 disconnected curves; split the file or give it"):
        read_curve(path)


def test_group_errors(tmp_path: Path) -> None:
    pts = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    mesh = meshio.Mesh(
        pts, [("line", np.array([[0, 1]])), ("triangle", np.array([[0, 1, 2]]))],
        cell_data={"gmsh:physical": [np.array([1]), np.array([2])],
                   "gmsh:geometrical": [np.array([1]), np.array([1])]},
        field_data={"edge": np.array([1, 1]), "face": np.array([2, 2])},
    )
    path = tmp_path / "mixed.msh"
    meshio.write(path, mesh, file_format="gmsh22")
    with pytest.raises(GeometryError, match="group 'face' .* has dimension 2, not a curve.*edge"):
        read_curve(path, group="face")
    assert read_curve(path, group="edge").n_elem == 1
    vtu = tmp_path / "plain.vtu"
    meshio.write(vtu, meshio.Mesh(pts, [("line", np.array([[0, 1]]))]))
    with pytest.raises(GeometryError, match="unknown group 'rail'.*none"):
        read_curve(vtu, group="rail")


def test_bad_tangent_field(tmp_path: Path) -> None:
    pts, cells = cells_of_order(4, 1)
    t = np.tile([1.0, 0.0, 0.0], (len(pts), 1))
    t[2] = [-1.0, 0.0, 0.0]
    path = tmp_path / "arc.vtu"
    meshio.write(path, meshio.Mesh(pts, [("line", cells)], point_data={"T": t, "s": pts[:, 0]}))
    with pytest.raises(GeometryError, match="point data 'X' not found.*T, s"):
        read_curve(path, tangents_field="X")
    with pytest.raises(GeometryError, match="must be vectors"):
        read_curve(path, tangents_field="s")
    with pytest.raises(GeometryError, match="points against the curve"):
        read_curve(path, tangents_field="T")


def test_degenerate_cell_and_bad_elements(tmp_path: Path) -> None:
    pts = np.array([[0.0, 0, 0], [1, 0, 0], [1, 0, 1e-15]])
    path = tmp_path / "degenerate.vtu"
    meshio.write(path, meshio.Mesh(pts, [("line", np.array([[0, 1], [1, 2]]))]))
    with pytest.raises(GeometryError, match="starts and ends at the same point"):
        read_curve(path)
    ok = tmp_path / "ok.vtu"
    meshio.write(ok, meshio.Mesh(pts[:2], [("line", np.array([[0, 1]]))]))
    with pytest.raises(GeometryError, match="elements must be >= 1"):
        read_curve(ok, elements=0)

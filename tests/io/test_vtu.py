"""VTU frames and PVD series: exact cubic beam sampling, strain/curvature, rigid-body surfaces,
contact vertices, and round trips through meshio and VTK (pyvista).

Tolerances: the three encodings store float64 exactly (base64 bits, zlib-compressed bits, or
the shortest round-trip decimal), so file round trips are compared bit for bit; comparisons
against independently computed geometry use ``RTOL = 1e-12`` relative to the model size.
"""

from __future__ import annotations

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.assembly import Assembly
from flexmbs.elements.rigid_body import angular_velocity_global, rotation_matrix
from flexmbs.errors import ModelError
from flexmbs.io.frames import BLOCK_BEAM, BLOCK_BODY, BLOCK_CONTACT, build_frame
from flexmbs.io.vtu import VTK_LINE, VTK_TRIANGLE, VTUMesh, VTUSeries, read_pvd, write_vtu
from flexmbs.simulation import beam_positions
from flexmbs.solvers.generalized_alpha import State

meshio = pytest.importorskip("meshio")

RTOL = 1e-12
SPE = 8


def _section() -> fm.BeamStiffness:
    return fm.BeamStiffness(axial_stiffness=1e6, bending_stiffness=2.0, mass_per_length=0.3)


def straight_beam_model(n_elem: int = 4) -> tuple[fm.Model, fm.Beam]:
    model = fm.Model(gravity=(0, 0, -9.81))
    beam = model.add_beam(fm.line((0, 0, 0), (1.0, 0, 0), elements=n_elem), section=_section(),
                          name="rail")
    model.clamp(beam.first_node)
    return model, beam


def arc_beam_model(n_elem: int, R: float = 0.5) -> tuple[fm.Model, fm.Beam]:
    model = fm.Model()
    beam = model.add_beam(fm.arc((0, 0, 0), R, (R, 0, 0), np.pi / 2, normal=(0, 0, 1),
                                 elements=n_elem), section=_section())
    model.clamp(beam.first_node)
    return model, beam


def deformed_state(asm: Assembly, rng: np.random.Generator, t: float = 0.125) -> State:
    """The reference perturbed by a smooth field, with random velocities."""
    q = asm.q_ref + 1e-2 * rng.standard_normal(asm.n_coords)
    for body in asm.model.bodies:
        d = asm.body_dofs(body)
        q[d[3:]] /= np.linalg.norm(q[d[3:]])
    v = rng.standard_normal(asm.n_coords)
    z = np.zeros(asm.n_coords)
    return State(t, q, v, z, z.copy(), np.zeros(asm.n_mult))


def reference_state(asm: Assembly) -> State:
    q, v = asm.initial_state()
    z = np.zeros(asm.n_coords)
    return State(0.0, q, v, z, z.copy(), np.zeros(asm.n_mult))


def beam_part(mesh: VTUMesh, beam_index: int = 0) -> np.ndarray:
    """Point indices of beam ``beam_index`` (in sampling order)."""
    conn, _, types = mesh.flat_cells()
    cells = conn.reshape(-1, 2)[(types == VTK_LINE) & (mesh.cell_data["beam_id"] == beam_index)]
    return np.unique(cells)


# ------------------------------------------------------------------------------- beams
def test_beam_samples_are_exact_cubic_positions_and_velocities(rng):
    model, beam = straight_beam_model(4)
    asm = Assembly(model)
    st = deformed_state(asm, rng)
    mesh = build_frame(asm, st, samples_per_element=SPE)
    idx = beam_part(mesh)
    assert idx.size == beam.n_elem * SPE + 1
    s = mesh.point_data["arc_length"][idx]
    np.testing.assert_allclose(s, np.linspace(0, beam.length, idx.size), rtol=0, atol=1e-15)
    pos = beam_positions(asm, beam, st.q, s)
    np.testing.assert_allclose(mesh.points[idx], pos, rtol=0, atol=RTOL)
    np.testing.assert_allclose(mesh.point_data["displacement"][idx],
                               pos - beam_positions(asm, beam, asm.q_ref, s), rtol=0, atol=RTOL)
    np.testing.assert_allclose(mesh.point_data["velocity"][idx],
                               beam_positions(asm, beam, st.v, s), rtol=0, atol=RTOL)
    assert np.all(mesh.cell_data["block_id"][mesh.cell_data["beam_id"] == 0] == BLOCK_BEAM)
    np.testing.assert_array_equal(mesh.field_data["time"], [0.125])


def test_straight_beam_has_zero_curvature_and_strain():
    model, _ = straight_beam_model(6)
    asm = Assembly(model)
    mesh = build_frame(asm, reference_state(asm))
    for k in ("axial_strain", "curvature", "curvature_magnitude", "displacement"):
        np.testing.assert_allclose(mesh.point_data[k], 0.0, atol=1e-14)


def test_stretched_beam_strain():
    model, _ = straight_beam_model(3)
    asm = Assembly(model)
    st = reference_state(asm)
    st.q = asm.q_ref * 1.01          # uniform 1 % stretch: positions and slopes scale
    mesh = build_frame(asm, st)
    np.testing.assert_allclose(mesh.point_data["axial_strain"], 0.01, rtol=1e-12)


@pytest.mark.parametrize("n_elem", [4, 8, 16])
def test_arc_curvature_is_one_over_radius(n_elem):
    R = 0.5
    model, _ = arc_beam_model(n_elem, R)
    asm = Assembly(model)
    mesh = build_frame(asm, reference_state(asm))
    kappa = mesh.point_data["curvature_magnitude"]
    theta_e = (np.pi / 2) / n_elem
    # Hermite interpolation of a circle: the largest curvature error is theta_e^2/12
    err = np.max(np.abs(kappa * R - 1.0))
    assert 0.9 * theta_e**2 / 12 < err < 1.01 * theta_e**2 / 12
    # the vector points along the arc normal (+z for a counter-clockwise arc in the xy plane)
    K = mesh.point_data["curvature"]
    np.testing.assert_allclose(K[:, :2], 0.0, atol=1e-12)
    assert np.all(K[:, 2] > 0)


def test_closed_beam_wraps_around():
    model = fm.Model()
    model.add_beam(fm.arc((0, 0, 0), 1.0, (1, 0, 0), 2 * np.pi, elements=6), section=_section())
    asm = Assembly(model)
    mesh = build_frame(asm, reference_state(asm), samples_per_element=4)
    assert mesh.n_points == 24 and mesh.n_cells == 24   # no duplicated closing point


# ------------------------------------------------------------------------------- bodies
def _rotated_body_model(shape: dict | None) -> tuple[fm.Model, fm.RigidBody]:
    model = fm.Model()
    c, s = np.cos(0.4), np.sin(0.4)
    R = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    body = model.add_rigid_body(mass=2.0, inertia=(1e-3, 2e-3, 2.5e-3), pose=fm.Pose(
        np.array([0.3, -0.2, 0.1]), R), velocity=(1, 2, 3), angular_velocity=(0.5, -1, 2),
        shape=shape, name="sleeve")
    return model, body


def test_hollow_cylinder_surface_in_pose_with_rigid_velocity_field(rng):
    shape = {"type": "cylinder", "radius": 0.015, "length": 0.04, "inner_radius": 0.0025}
    model, body = _rotated_body_model(shape)
    asm = Assembly(model)
    st = deformed_state(asm, rng)
    mesh = build_frame(asm, st)
    d = asm.body_dofs(body)
    r, p = st.q[d[:3]], st.q[d[3:]]
    A = rotation_matrix(p)
    local = (mesh.points - r) @ A        # body-frame coordinates
    radial = np.linalg.norm(local[:, 1:], axis=1)
    assert np.all(np.isclose(radial, 0.015) | np.isclose(radial, 0.0025))
    np.testing.assert_allclose(np.abs(local[:, 0]), 0.02)
    w = angular_velocity_global(p, st.v[d[3:]])
    np.testing.assert_allclose(mesh.point_data["velocity"],
                               st.v[d[:3]] + np.cross(w, mesh.points - r), atol=RTOL)
    q0 = asm.q_ref[d]
    ref = q0[:3] + local @ rotation_matrix(q0[3:]).T
    np.testing.assert_allclose(mesh.point_data["displacement"], mesh.points - ref, atol=RTOL)
    assert np.all(mesh.cell_data["body_id"] == 0)
    assert np.all(mesh.cell_data["block_id"] == BLOCK_BODY)
    assert all(ct == VTK_TRIANGLE for ct, _ in mesh.cells)


def test_default_shape_is_the_inertia_box():
    a, b, c, m = 0.3, 0.2, 0.1, 2.0
    J = m / 12 * np.array([b * b + c * c, a * a + c * c, a * a + b * b])
    model = fm.Model()
    model.add_rigid_body(mass=m, inertia=J)
    asm = Assembly(model)
    mesh = build_frame(asm, reference_state(asm))
    np.testing.assert_allclose(np.ptp(mesh.points, axis=0), [a, b, c], rtol=1e-12)


def test_box_and_mesh_shapes(tmp_path):
    tri = meshio.Mesh(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]]),
                      [("triangle", np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]))])
    tri.write(tmp_path / "tet.vtu")
    model = fm.Model()
    model.add_rigid_body(mass=1.0, inertia=(1, 1, 1), position=(5, 0, 0),
                         shape={"type": "box", "size": [0.1, 0.2, 0.3]})
    model.add_rigid_body(mass=1.0, inertia=(1, 1, 1), position=(0, 5, 0),
                         shape={"type": "mesh", "file": str(tmp_path / "tet.vtu"), "scale": 2.0})
    asm = Assembly(model)
    mesh = build_frame(asm, reference_state(asm))
    ids = mesh.cell_data["body_id"]
    conn, _, _ = mesh.flat_cells()
    conn = conn.reshape(-1, 3)
    box = mesh.points[np.unique(conn[ids == 0])]
    np.testing.assert_allclose(np.ptp(box, axis=0), [0.1, 0.2, 0.3], rtol=1e-12)
    tet = mesh.points[np.unique(conn[ids == 1])]
    np.testing.assert_allclose(tet, [[0, 5, 0], [2, 5, 0], [0, 7, 0], [0, 5, 2]])


@pytest.mark.parametrize("shape, match", [
    ({"type": "sphere"}, "unknown shape type"),
    ({"type": "box", "size": [1, 2]}, "3 positive"),
    ({"type": "cylinder", "radius": 1.0}, "length"),
    ({"type": "cylinder", "radius": 1.0, "length": 1.0, "inner_radius": 2.0}, "inner_radius"),
    ({"type": "box", "size": [1, 1, 1], "colour": "red"}, "unknown keys"),
])
def test_bad_shapes_are_model_errors(shape, match):
    model, _ = _rotated_body_model(shape)
    with pytest.raises(ModelError, match=match) as err:
        build_frame(Assembly(model), reference_state(Assembly(model)))
    assert "sleeve" in str(err.value)


# ------------------------------------------------------------------------------- contacts
def test_contact_points_are_vertices():
    model, _ = straight_beam_model(2)
    asm = Assembly(model)
    contacts = [{"point": (0.1, 0.0, 0.002), "gap": -1e-5, "normal_force": 3.5, "normal": (0, 0, 1)},
                {"qx": 0.2, "qy": 0.0, "qz": -0.002, "gap": -2e-5, "normal_force": 7.0,
                 "normal": (0, 0, -1), "point": 1}]
    mesh = build_frame(asm, reference_state(asm), contacts=contacts)
    sel = mesh.cell_data["block_id"] == BLOCK_CONTACT
    conn, _, types = mesh.flat_cells()
    assert np.all(types[sel] == 1)
    n_beam = mesh.n_points - 2
    np.testing.assert_array_equal(mesh.points[n_beam:], [[0.1, 0, 0.002], [0.2, 0, -0.002]])
    np.testing.assert_array_equal(mesh.point_data["gap"][n_beam:], [-1e-5, -2e-5])
    np.testing.assert_array_equal(mesh.point_data["normal_force"][n_beam:], [3.5, 7.0])
    np.testing.assert_array_equal(mesh.point_data["normal"][n_beam:], [[0, 0, 1], [0, 0, -1]])
    assert np.all(np.isnan(mesh.point_data["gap"][:n_beam]))
    np.testing.assert_array_equal(mesh.point_data["displacement"][n_beam:], 0.0)


# ------------------------------------------------------------------------------- file round trips
def _full_model() -> tuple[fm.Model, fm.Beam]:
    model, beam = straight_beam_model(5)
    model.add_rigid_body(mass=0.2, inertia=(2e-5, 4e-5, 4e-5), position=(0.5, 0, 0),
                         shape={"type": "cylinder", "radius": 0.015, "length": 0.04,
                                "inner_radius": 0.0025})
    model.add_rigid_body(mass=1.0, inertia=(1e-3, 2e-3, 2.5e-3), position=(0, 1, 0))
    return model, beam


@pytest.mark.parametrize("encoding", ["binary", "zlib", "ascii"])
def test_vtu_round_trip_meshio_is_exact(tmp_path, rng, encoding):
    model, _ = _full_model()
    asm = Assembly(model)
    mesh = build_frame(asm, deformed_state(asm, rng), contacts=[
        {"point": (0.1, 0.2, 0.3), "gap": -1e-4, "normal_force": 2.0, "normal": (1, 0, 0)}])
    path = write_vtu(tmp_path / "frame.vtu", mesh, encoding=encoding)
    back = meshio.read(path)
    np.testing.assert_array_equal(back.points, mesh.points)
    for k, val in mesh.point_data.items():
        np.testing.assert_array_equal(back.point_data[k], val, err_msg=k)
    conn, _, types = mesh.flat_cells()
    assert sum(len(c.data) for c in back.cells) == types.size
    for k, val in mesh.cell_data.items():
        np.testing.assert_array_equal(np.concatenate(back.cell_data[k]), val, err_msg=k)
    np.testing.assert_array_equal(back.field_data["time"], mesh.field_data["time"])


@pytest.mark.parametrize("encoding", ["binary", "zlib", "ascii"])
def test_series_is_valid_after_every_write_and_readable_by_vtk(tmp_path, rng, encoding):
    pv = pytest.importorskip("pyvista")
    model, _ = _full_model()
    asm = Assembly(model)
    (tmp_path / "vtu").mkdir()
    (tmp_path / "vtu" / "run_000099.vtu").write_text("stale")
    times = [0.0, 0.01, 0.02]
    meshes = []
    with VTUSeries(tmp_path / "run.pvd", encoding=encoding) as series:
        assert not (tmp_path / "vtu" / "run_000099.vtu").exists()
        for i, t in enumerate(times):
            meshes.append(build_frame(asm, deformed_state(asm, rng, t)))
            path = series.write(t, meshes[-1])
            assert path.name == f"run_{i:06d}.vtu"
            reader = pv.PVDReader(str(tmp_path / "run.pvd"))
            assert reader.time_values == times[:i + 1]
    reader = pv.PVDReader(str(tmp_path / "run.pvd"))
    for t, mesh in zip(times, meshes, strict=True):
        reader.set_active_time_value(t)
        grid = reader.read()[0]
        np.testing.assert_array_equal(grid.points, mesh.points)
        np.testing.assert_array_equal(grid.point_data["displacement"], mesh.point_data["displacement"])
        np.testing.assert_array_equal(grid.cell_data["body_id"], mesh.cell_data["body_id"])
        np.testing.assert_array_equal(grid.field_data["time"], [t])
        assert grid.n_cells == mesh.n_cells


def test_long_series_rewrites_its_index_at_most_every_interval(tmp_path, rng):
    """After the first EAGER_FRAMES frames the .pvd index is rewritten at most every
    pvd_interval seconds (here: never during the run); it stays valid, lists a prefix of the
    frames, and lists them all once the series is closed."""
    model, _ = _full_model()
    asm = Assembly(model)
    mesh = build_frame(asm, deformed_state(asm, rng, 0.0))
    n = VTUSeries.EAGER_FRAMES + 5
    with VTUSeries(tmp_path / "run.pvd", pvd_interval=1e9) as series:
        for i in range(n):
            series.write(0.01 * i, mesh)
            listed = read_pvd(tmp_path / "run.pvd")
            assert len(listed) == min(i + 1, VTUSeries.EAGER_FRAMES)
    assert [t for t, _ in read_pvd(tmp_path / "run.pvd")] == pytest.approx(0.01 * np.arange(n))


def test_background_series_loses_no_frame_to_an_interrupt_while_waiting(tmp_path, monkeypatch):
    """A frame written in the background while the run is interrupted (Ctrl-C, SIGTERM turned
    into one) as it waits for that frame: the interrupt propagates, the frame stays pending and
    close() (the writer's finish) waits for it, so it is on disk and listed; a worker's own
    error is raised at the next call, with the file named."""
    import signal
    import time

    import flexmbs.io.vtu as vtu

    real = vtu._store

    def slow(path, text, atomic):
        time.sleep(0.3)
        return real(path, text, atomic)

    monkeypatch.setattr(vtu, "_store", slow)
    mesh = VTUMesh(np.zeros((2, 3)), [(VTK_LINE, np.array([[0, 1]]))])
    series = VTUSeries(tmp_path / "run.pvd", background=True)
    series.write(0.0, mesh)

    def interrupt(signum, frame):
        raise KeyboardInterrupt

    old = signal.signal(signal.SIGALRM, interrupt)
    try:
        signal.setitimer(signal.ITIMER_REAL, 0.05)
        with pytest.raises(KeyboardInterrupt):
            series.flush()
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, old)
    series.close()
    assert read_pvd(tmp_path / "run.pvd") == [(0.0, "vtu/run_000000.vtu")]
    assert (tmp_path / "vtu" / "run_000000.vtu").is_file()

    def full(path, text, atomic):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(vtu, "_store", full)
    series = VTUSeries(tmp_path / "b.pvd", background=True)
    series.write(0.0, mesh)
    with pytest.raises(OSError, match=r"b_000000\.vtu"):
        series.write(1.0, mesh)
    with pytest.raises(OSError):
        series.close()


def test_read_only_arrays_are_encoded_once_and_writable_ones_each_time(tmp_path):
    """A frame's constants (read-only arrays owning their data) are encoded once; an array
    that may change (writeable) is encoded at every write, also when changed in place."""
    from flexmbs.io.vtu import VTK_POLY_LINE, write_vtp

    pts = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    ring = np.array([0, 1, 2, 3, 0])
    ids = np.array([7], np.int32)
    mesh = VTUMesh(pts, [(VTK_POLY_LINE, [ring])], cell_data={"id": ids})
    plain = write_vtp(tmp_path / "a.vtp", mesh).read_text()
    frozen_ring, frozen_ids = ring.copy(), ids.copy()
    frozen_ring.setflags(write=False)
    frozen_ids.setflags(write=False)
    frozen = VTUMesh(pts, [(VTK_POLY_LINE, [frozen_ring])], cell_data={"id": frozen_ids})
    for _ in range(2):      # encoded, then remembered: the same file
        assert write_vtp(tmp_path / "b.vtp", frozen).read_text() == plain
    ring[:] = [3, 2, 1, 0, 3]       # changed in place: written as it is now
    ids[0] = 8
    again = write_vtp(tmp_path / "c.vtp", mesh).read_text()
    assert again != plain
    fresh = VTUMesh(pts, [(VTK_POLY_LINE, [np.array([3, 2, 1, 0, 3])])],
                    cell_data={"id": np.array([8], np.int32)})
    assert again == write_vtp(tmp_path / "d.vtp", fresh).read_text()


def test_read_pvd_parses_xml_in_any_attribute_order(tmp_path):
    """read_pvd reads a .pvd as XML: attributes in another order, single quotes, an entity,
    a DataSet over two lines; not an index -> one clear error."""
    import pytest

    from flexmbs.errors import FlexmbsError
    from flexmbs.io.vtu import read_pvd

    pvd = tmp_path / "run.pvd"
    pvd.write_text("<?xml version='1.0'?>\n<VTKFile type='Collection' version='0.1'>\n"
                   "<Collection>\n<DataSet file='vtu/a&amp;b_000000.vtu' part='0' timestep='0'/>\n"
                   "<DataSet part=\"0\"\n  file=\"vtu/a_000001.vtu\" timestep=\"0.5\"/>\n"
                   "</Collection>\n</VTKFile>\n", encoding="utf-8")
    assert read_pvd(pvd) == [(0.0, "vtu/a&b_000000.vtu"), (0.5, "vtu/a_000001.vtu")]
    assert read_pvd(tmp_path / "missing.pvd") == []
    pvd.write_text("<VTKFile><Collection><DataSet file='x.vtu'/>", encoding="utf-8")
    with pytest.raises(FlexmbsError, match="not a readable .pvd"):
        read_pvd(pvd)

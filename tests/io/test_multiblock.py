"""The multiblock output (issue 35): every frame a ``.vtm`` of named blocks, read back with VTK's
own readers (``vtkXMLMultiBlockDataReader``; the ``.pvd`` index parsed as XML: VTK's Python
package has no ``vtkPVDReader``, that one is ParaView's) and checked against the model and the
other files of the run, on a small model with two beams, a clearance joint with friction and a
spring; the merged form of the same run (``--output-frames merged``) for comparison.

Tolerances: the pieces store float64 exactly, so values shared with contacts.csv, sections.csv
and the merged frames are compared bit for bit; geometry against the model uses ``RTOL``.
"""

from __future__ import annotations

import csv
import json
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from flexmbs.cli import main
from flexmbs.io.vtu import frame_files, read_pvd

vtk = pytest.importorskip("vtk")
from vtk.util.numpy_support import vtk_to_numpy  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
RTOL = 1e-12
SPE = 8            # samples per element of the output (OutputWriter's default)
MU = 0.3
#: Example 1 with friction, a second beam (a guy wire, clamped at its start and pinned by a joint
#: at its end) and a spring from the sleeve to it (the kind of model of Example 2: one kernel for both)
EXTRA = """
[[beams]]
name = "guy"
geometry = { line = { start = [-0.8, 0.3, 0.5], end = [0.8, 0.3, 0.5] } }
elements = 4
radius = 1e-3
youngs_modulus = 2.1e11
density = 7800.0

[[constraints]]
type = "clamp"
beam = "guy"
node = "first"

[[constraints]]
type = "joint"
name = "guy_pin"
beam = "guy"
node = "last"
point = [0.8, 0.3, 0.5]

[[springs]]
name = "tether"
type = "translational"
body = "sleeve"
beam2 = "guy"
node2 = "first"
stiffness = 5.0
"""


def _scenario(tmp: Path) -> Path:
    text = (ROOT / "examples" / "curved_beam_sleeve.toml").read_text()
    text = text.replace('"../meshes/', f'"{ROOT}/meshes/').replace("friction = 0.0", f"friction = {MU}")
    path = tmp / "two_beams.toml"
    path.write_text(text.replace('name = "curved_beam_sleeve"', 'name = "two_beams"') + EXTRA)
    return path


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """The model run to 0.05 s in both forms (outputs every 0.01 s)."""
    tmp = tmp_path_factory.mktemp("mb")
    scen = _scenario(tmp)
    out = {}
    for form in ("multiblock", "merged"):
        out[form] = tmp / form
        args = ["run", str(scen), "--t-end", "0.05", "--quiet", "--out", str(out[form])]
        assert main(args + (["--output-frames", "merged"] if form == "merged" else [])) == 0
    return out


def read_vtm(path: Path):
    reader = vtk.vtkXMLMultiBlockDataReader()
    reader.SetFileName(str(path))
    reader.Update()
    return reader.GetOutput()


def tree(mb) -> dict:
    """{name: leaf data set or nested dict} of a vtkMultiBlockDataSet."""
    out = {}
    for i in range(mb.GetNumberOfBlocks()):
        name = mb.GetMetaData(i).Get(vtk.vtkCompositeDataSet.NAME())
        block = mb.GetBlock(i)
        out[name] = tree(block) if block.IsA("vtkMultiBlockDataSet") else block
    return out


def point_array(ds, name: str) -> np.ndarray:
    arr = ds.GetPointData().GetArray(name)
    assert arr is not None, name
    return vtk_to_numpy(arr)


def csv_rows(path: Path) -> list[dict]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def pvd_files(pvd: Path) -> list[tuple[float, str]]:
    """The .pvd as XML (what a reader sees), checked against flexmbs' own read_pvd."""
    root = ET.parse(pvd).getroot()
    assert root.get("type") == "Collection"
    entries = [(float(d.get("timestep")), d.get("file")) for d in root.iter("DataSet")]
    assert entries == read_pvd(pvd)
    return entries


def test_every_frame_is_a_vtm_listed_in_the_pvd(runs):
    out = runs["multiblock"]
    entries = pvd_files(out / "two_beams.pvd")
    t = [float(r["t"]) for r in csv_rows(out / "probes.csv")]
    assert [e[0] for e in entries] == t and len(t) == 6
    for k, (_, f) in enumerate(entries):
        assert f == f"vtu/two_beams_{k:06d}.vtm"
        pieces = frame_files(out / f)
        assert [p.name for p in pieces] == [f"two_beams_{k:06d}_{s}.vtp" for s in
                                            ("beams_0", "beams_1", "bodies_0", "contacts",
                                             "springs", "hole_sections")]
    assert sorted(p.name for p in (out / "vtu").iterdir()) == sorted(
        [Path(f).name for _, f in entries] + [p.name for _, f in entries for p in frame_files(out / f)])


def test_block_names_arrays_and_counts_match_the_model(runs):
    out = runs["multiblock"]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["files"]["frames"] == "multiblock"
    assert [b["path"] for b in summary["vtm_blocks"]] == [
        "beams/rail", "beams/guy", "bodies/sleeve", "contacts", "springs", "hole_sections"]
    assert [b.get("radius") for b in summary["vtm_blocks"][:2]] == [2e-3, 1e-3]
    contacts = csv_rows(out / "contacts.csv")
    sections = csv_rows(out / "sections.csv")
    n_contacts_seen = 0
    for t, f in read_pvd(out / "two_beams.pvd"):
        blocks = tree(read_vtm(out / f))
        assert list(blocks) == ["beams", "bodies", "contacts", "springs", "hole_sections"]
        assert list(blocks["beams"]) == ["rail", "guy"] and list(blocks["bodies"]) == ["sleeve"]
        # beams: one poly line through n_elem * SPE + 1 samples, the section radius as point data
        for name, n_elem, radius in (("rail", 16, 2e-3), ("guy", 4, 1e-3)):
            beam = blocks["beams"][name]
            assert beam.IsA("vtkPolyData") and beam.GetNumberOfLines() == 1
            assert beam.GetNumberOfPoints() == n_elem * SPE + 1
            assert beam.GetLines().GetConnectivityArray().GetNumberOfValues() == n_elem * SPE + 1
            np.testing.assert_array_equal(point_array(beam, "radius"), radius)
            for a in ("displacement", "velocity", "arc_length", "axial_strain", "curvature",
                      "curvature_magnitude"):
                assert point_array(beam, a).shape[0] == n_elem * SPE + 1
            # the rail is fitted to a meshed quarter circle of radius 1 m (to 2e-7 in length)
            np.testing.assert_allclose(point_array(beam, "arc_length")[[0, -1]],
                                       [0.0, {"rail": np.pi / 2, "guy": 1.6}[name]], rtol=1e-6)
            assert vtk_to_numpy(beam.GetFieldData().GetArray("time"))[0] == t
        sleeve = blocks["bodies"]["sleeve"]
        assert sleeve.GetNumberOfPolys() > 0 and sleeve.GetNumberOfLines() == 0
        assert point_array(sleeve, "velocity").shape == (sleeve.GetNumberOfPoints(), 3)
        # contacts: one vertex per contacts.csv row of this time, same values
        rows = [r for r in contacts if float(r["t"]) == t]
        cp = blocks["contacts"]
        assert cp.GetNumberOfPoints() == cp.GetNumberOfVerts() == len(rows)
        n_contacts_seen += len(rows)
        if rows:
            np.testing.assert_array_equal(point_array(cp, "gap"), [float(r["gap"]) for r in rows])
            fn = point_array(cp, "normal_force")
            np.testing.assert_array_equal(fn, [float(r["normal_force"]) for r in rows])
            np.testing.assert_array_equal(vtk_to_numpy(cp.GetPoints().GetData()),
                                          [[float(r[k]) for k in ("qx", "qy", "qz")] for r in rows])
            np.testing.assert_array_equal(point_array(cp, "section"), [int(r["section"]) for r in rows])
            np.testing.assert_array_equal(point_array(cp, "point_index"), [int(r["point"]) for r in rows])
            np.testing.assert_array_equal(point_array(cp, "joint_id"), 0)
            normal = point_array(cp, "normal")
            np.testing.assert_allclose(np.linalg.norm(normal, axis=1), 1.0, rtol=1e-12)
            ft = point_array(cp, "tangential_force")
            assert ft.shape == (len(rows), 3)
            # friction: tangential to the normal, inside the Coulomb cone
            np.testing.assert_allclose(np.einsum("ij,ij->i", ft, normal), 0.0,
                                       atol=1e-9 * max(1.0, np.abs(fn).max()))
            assert np.all(np.linalg.norm(ft, axis=1) <= MU * np.abs(fn) * (1 + 1e-9) + 1e-12)
            assert set(point_array(cp, "stick").tolist()) <= {0.0, 1.0}
        # the spring: one line between the sleeve and the guy's first node
        sp = blocks["springs"]
        assert sp.GetNumberOfLines() == 1 and sp.GetNumberOfPoints() == 2
        np.testing.assert_array_equal(vtk_to_numpy(sp.GetCellData().GetArray("spring_id")), [0])
        np.testing.assert_array_equal(vtk_to_numpy(sp.GetPoints().GetData())[1], [-0.8, 0.3, 0.5])
        # hole sections: 9 closed outlines of the bore radius about the sections.csv centres
        hs = blocks["hole_sections"]
        assert hs.GetNumberOfLines() == 9
        pts = vtk_to_numpy(hs.GetPoints().GetData()).reshape(9, -1, 3)
        np.testing.assert_array_equal(vtk_to_numpy(hs.GetCellData().GetArray("section")), range(9))
        for r in (r for r in sections if float(r["t"]) == t):
            k = int(r["section"])
            centre = np.array([float(r[c]) for c in ("ox", "oy", "oz")])
            np.testing.assert_allclose(np.linalg.norm(pts[k] - centre, axis=1), float(r["R"]),
                                       rtol=1e-9)
            axis = np.cross([float(r[c]) for c in ("eyx", "eyy", "eyz")],
                            [float(r[c]) for c in ("ezx", "ezy", "ezz")])
            np.testing.assert_allclose((pts[k] - centre) @ axis, 0.0, atol=1e-12)
    assert n_contacts_seen > 0            # the sleeve rests on the rail: contacts were checked


def test_the_merged_form_holds_the_same_beams(runs):
    """``--output-frames merged``: one .vtu per frame; its beam points are the multiblock's."""
    mb, mg = runs["multiblock"], runs["merged"]
    summary = json.loads((mg / "summary.json").read_text())
    assert summary["files"]["frames"] == "merged" and summary["vtm_blocks"] is None
    for (t, f), (t2, g) in zip(read_pvd(mb / "two_beams.pvd"), read_pvd(mg / "two_beams.pvd"),
                               strict=True):
        assert t == t2 and g.endswith(".vtu")
        reader = vtk.vtkXMLUnstructuredGridReader()
        reader.SetFileName(str(mg / g))
        reader.Update()
        grid = reader.GetOutput()
        rail = tree(read_vtm(mb / f))["beams"]["rail"]
        block = vtk_to_numpy(grid.GetCellData().GetArray("block_id"))
        beam_id = vtk_to_numpy(grid.GetCellData().GetArray("beam_id"))
        assert {0, 1, 3} <= set(np.unique(block).tolist())    # beams, body, spring
        cells = np.flatnonzero((block == 0) & (beam_id == 0))
        ids = sorted({grid.GetCell(c).GetPointId(j) for c in cells for j in range(2)})
        np.testing.assert_array_equal(vtk_to_numpy(grid.GetPoints().GetData())[ids],
                                      vtk_to_numpy(rail.GetPoints().GetData()))


def test_the_merged_form_holds_the_same_bore_outlines(runs):
    """The merged grid's ``block_id`` 4: the bore outlines of ``hole_sections``, as closed
    rings of VTK_LINE segments with the same points, ``joint_id`` and ``section`` (cell data;
    -1 on the other parts); ``summary.json`` names the block and lists the beam radii."""
    mb, mg = runs["multiblock"], runs["merged"]
    summary = json.loads((mg / "summary.json").read_text())
    assert summary["vtu_blocks"]["block_id"]["4"] == "hole_section"
    assert summary["vtu_blocks"]["beam_radius"] == [
        b["radius"] for b in json.loads((mb / "summary.json").read_text())["vtm_blocks"]
        if b["kind"] == "beam"]
    for (_, f), (_, g) in zip(read_pvd(mb / "two_beams.pvd"), read_pvd(mg / "two_beams.pvd"),
                              strict=True):
        reader = vtk.vtkXMLUnstructuredGridReader()
        reader.SetFileName(str(mg / g))
        reader.Update()
        grid = reader.GetOutput()
        holes = tree(read_vtm(mb / f))["hole_sections"]
        cell = {k: vtk_to_numpy(grid.GetCellData().GetArray(k))
                for k in ("block_id", "joint_id", "section")}
        outline = np.flatnonzero(cell["block_id"] == 4)
        assert np.all(cell["joint_id"][cell["block_id"] != 4] == -1)
        pts = vtk_to_numpy(grid.GetPoints().GetData())
        ring_pts = vtk_to_numpy(holes.GetPoints().GetData())
        start = 0
        for r in range(holes.GetNumberOfCells()):       # each ring: its segments in order
            ring = holes.GetCell(r)
            m = ring.GetNumberOfPoints() - 1                # closed: ends on its first point
            segs = outline[start:start + m]
            a = np.array([grid.GetCell(c).GetPointId(0) for c in segs])
            b = np.array([grid.GetCell(c).GetPointId(1) for c in segs])
            assert all(grid.GetCellType(c) == vtk.VTK_LINE for c in segs)
            np.testing.assert_array_equal(b, np.roll(a, -1))
            np.testing.assert_array_equal(pts[a], ring_pts[[ring.GetPointId(j)
                                                            for j in range(m)]])
            for k in ("joint_id", "section"):
                ref = vtk_to_numpy(holes.GetCellData().GetArray(k))[r]
                assert np.all(cell[k][segs] == ref)
            start += m
        assert start == outline.size > 0

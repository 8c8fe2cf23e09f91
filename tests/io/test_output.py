"""The output folder written by OutputWriter during a short simulation: VTU/PVD series read back
with meshio and VTK, probes.csv, contacts.csv, summary.json, checkpoint, and what a failing or
interrupted run leaves behind.

Tolerances: files store float64 exactly (CSV with the shortest round-trip decimal), so values
read back are compared bit for bit with the recorded states; independent geometry uses
``RTOL = 1e-12`` relative to the model size.
"""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.assembly import Assembly
from flexmbs.errors import ConvergenceError, ModelError
from flexmbs.io.builders import PROBES
from flexmbs.io.checkpoint import load_checkpoint
from flexmbs.io.output import CONTACT_COLUMNS, OutputWriter
from flexmbs.io.probes import (
    BeamPointProbe,
    BodyOrientationProbe,
    BodyPositionProbe,
    EnergyProbe,
)
from flexmbs.simulation import beam_positions
from flexmbs.solvers.generalized_alpha import consistent_initial_state

meshio = pytest.importorskip("meshio")

RTOL = 1e-12
CONTACT_HEADER = "t,joint,section,point,gap,normal_force,qx,qy,qz,px,py,pz,a,b"


def cantilever_and_pendulum(n_elem: int = 6):
    """A clamped cantilever under gravity and a rigid pendulum on a spherical joint."""
    model = fm.Model(gravity=(0, 0, -9.81), name="demo")
    beam = model.add_beam(fm.line((0, 0, 0), (1.0, 0, 0), elements=n_elem), name="rail",
                          section=fm.BeamStiffness(axial_stiffness=1e6, bending_stiffness=5.0,
                                                   mass_per_length=0.5))
    model.clamp(beam.first_node)
    body = model.add_rigid_body(mass=0.5, inertia=(1e-3, 2e-3, 2e-3), position=(0.2, 1.0, 0.0),
                                angular_velocity=(0, 0, 1.0), name="bob",
                                shape={"type": "box", "size": [0.1, 0.05, 0.05]})
    model.spherical(body, fm.GROUND, point=(0.0, 1.0, 0.0))
    return model, beam, body


def make_probes(beam, body):
    return [BeamPointProbe("tip", beam, beam.length, quantity="displacement"),
            BeamPointProbe("mid_v", beam, 0.5 * beam.length, quantity="velocity"),
            BodyPositionProbe("bob_r", body), BodyOrientationProbe("bob_p", body),
            EnergyProbe("E"), EnergyProbe("T", "kinetic")]


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.reader(f))


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """A short simulation written with OutputWriter; the observed states are kept."""
    out = tmp_path_factory.mktemp("out") / "demo"
    model, beam, body = cantilever_and_pendulum()
    asm = Assembly(model)
    probes = make_probes(beam, body)
    states = []
    contact = {"joint": "sleeve", "section": 2, "point": 0, "gap": -1e-5, "normal_force": 1.5,
               "qx": 0.1, "qy": 0.2, "qz": 0.3, "px": 0.1, "py": 0.2, "pz": 0.29, "a": 2e-3,
               "b": 2e-3, "normal": (0, 0, 1)}
    # the merged form (one .vtu grid per frame, read by meshio); the multiblock form (the
    # default) is tests/io/test_multiblock.py
    with OutputWriter(out, "demo", asm, probes=probes, output_frames="merged",
                      metadata={"scenario_file": "none.toml", "dt": 1e-3}) as writer:
        summary0 = json.loads((out / "summary.json").read_text())

        def observe(s):
            states.append(s.copy())
            writer.write(s, contacts=[contact] if len(states) == 2 else None)

        res = fm.simulate(asm, t_end=0.02, dt=1e-3, output_interval=5e-3, observer=observe)
        writer.finish("completed", stats=res.stats, wall_time=res.wall_time,
                      energy_balance={"work_external": 0.0})
    return {"dir": out, "asm": asm, "beam": beam, "body": body, "probes": probes,
            "states": states, "summary0": summary0, "result": res, "contact": contact}


def test_files_exist(run):
    names = {p.name for p in run["dir"].iterdir()}
    assert {"demo.pvd", "vtu", "probes.csv", "contacts.csv", "summary.json",
            "checkpoint.npz"} <= names
    assert not any(n.endswith(".tmp") for n in names)
    assert len(list((run["dir"] / "vtu").glob("demo_*.vtu"))) == len(run["states"]) == 5


def test_vtu_frames_match_states_meshio(run):
    asm, beam, states = run["asm"], run["beam"], run["states"]
    for i, st in enumerate(states):
        m = meshio.read(run["dir"] / "vtu" / f"demo_{i:06d}.vtu")
        np.testing.assert_array_equal(m.field_data["time"], [st.t])
        line = m.cells_dict["line"][m.cell_data_dict["beam_id"]["line"] == 0]
        idx = np.unique(line)
        s = m.point_data["arc_length"][idx]
        np.testing.assert_allclose(m.points[idx], beam_positions(asm, beam, st.q, s), atol=RTOL)
        np.testing.assert_allclose(m.point_data["displacement"][idx],
                                   beam_positions(asm, beam, st.q - asm.q_ref, s), atol=RTOL)


def test_pvd_series_matches_states_pyvista(run):
    pv = pytest.importorskip("pyvista")
    states, asm, body = run["states"], run["asm"], run["body"]
    reader = pv.PVDReader(str(run["dir"] / "demo.pvd"))
    assert reader.time_values == [st.t for st in states]
    d = asm.body_dofs(body)
    for st in states:
        reader.set_active_time_value(st.t)
        grid = reader.read()[0]
        np.testing.assert_array_equal(grid.field_data["time"], [st.t])
        on_body = grid.extract_cells(np.flatnonzero(grid.cell_data["body_id"] == 0))
        # the box is centred on the body reference point
        np.testing.assert_allclose(on_body.points.mean(axis=0), st.q[d[:3]], atol=RTOL)
        on_beam = grid.cell_data["beam_id"] == 0
        assert on_beam.sum() == 6 * 8


def test_probes_csv(run):
    rows = read_csv(run["dir"] / "probes.csv")
    header = rows[0]
    assert header == ["t", "tip_x", "tip_y", "tip_z", "mid_v_x", "mid_v_y", "mid_v_z",
                      "bob_r_x", "bob_r_y", "bob_r_z", "bob_p_w", "bob_p_x", "bob_p_y", "bob_p_z",
                      "E", "T"]
    data = np.array(rows[1:], float)
    assert data.shape == (5, len(header))
    for row, st in zip(data, run["states"], strict=True):
        expect = np.concatenate([[st.t]] + [p.evaluate(run["asm"], st) for p in run["probes"]])
        np.testing.assert_array_equal(row, expect)
    # independent checks of two probes
    last = run["states"][-1]
    tip = beam_positions(run["asm"], run["beam"], last.q - run["asm"].q_ref, [1.0])[0]
    np.testing.assert_allclose(data[-1, 1:4], tip, atol=RTOL)
    np.testing.assert_allclose(data[:, 14], run["result"].energy["total"], rtol=1e-12)


def test_contacts_csv(run):
    text = (run["dir"] / "contacts.csv").read_text().splitlines()
    assert text[0] == CONTACT_HEADER == ",".join(CONTACT_COLUMNS)
    rows = read_csv(run["dir"] / "contacts.csv")[1:]
    assert len(rows) == 1
    c = run["contact"]
    assert float(rows[0][0]) == run["states"][1].t
    assert rows[0][1:4] == ["sleeve", "2", "0"]
    np.testing.assert_array_equal(np.array(rows[0][4:], float),
                                  [c[k] for k in CONTACT_COLUMNS[4:]])


def test_summary_json(run):
    assert run["summary0"]["status"] == "running"
    s = json.loads((run["dir"] / "summary.json").read_text())
    res, asm = run["result"], run["asm"]
    assert s["status"] == "completed"
    assert s["scenario"] == "demo"
    assert s["flexmbs_version"] == fm.__version__
    assert s["final_time"] == run["states"][-1].t == pytest.approx(0.02)
    assert s["steps"] == res.stats.steps > 0
    assert s["newton_iterations"] == res.stats.newton_iterations > 0
    assert s["rejected_steps"] == res.stats.rejected_steps
    assert s["wall_time"] == res.wall_time
    assert s["dofs"] == {"coordinates": asm.n_coords, "multipliers": asm.n_mult}
    eb = s["energy_balance"]
    assert eb["initial_total"] == res.energy["total"][0]
    assert eb["final_total"] == res.energy["total"][-1]
    assert eb["work_external"] == 0.0
    assert s["metadata"] == {"scenario_file": "none.toml", "dt": 1e-3}
    assert s["vtu_blocks"]["beam_id"] == ["rail"] and s["vtu_blocks"]["body_id"] == ["bob"]
    assert s["outputs"] == 5


def test_checkpoint_is_latest_state(run):
    st, extra = load_checkpoint(run["dir"] / "checkpoint.npz")
    last = run["states"][-1]
    assert st.t == last.t
    for f in ("q", "v", "qdd", "a", "lam"):
        np.testing.assert_array_equal(getattr(st, f), getattr(last, f))
    assert extra["output_step"] == 4


def test_checkpoint_interval_bounds_the_cost_and_the_end_is_always_saved(tmp_path):
    """Checkpoints are written at most every ``checkpoint_interval`` s of wall time (here: only
    the first output) and for the last output when the writer finishes."""
    model, _, _ = cantilever_and_pendulum(2)
    asm = Assembly(model)
    st = _initial(asm)
    with OutputWriter(tmp_path, "x", asm, checkpoint_interval=1e9) as w:
        for k in range(3):
            st.t = 0.01 * k
            w.write(st)
            w.flush()           # the writer's thread has written the output
            assert load_checkpoint(tmp_path / "checkpoint.npz")[0].t == 0.0
    st_ck, extra = load_checkpoint(tmp_path / "checkpoint.npz")
    assert st_ck.t == 0.02 and extra["output_step"] == 2


# ------------------------------------------------------------------------------- failures
def _initial(asm):
    q, v = asm.initial_state()
    return consistent_initial_state(asm, q, v, 0.0)


@pytest.mark.parametrize("exc, status", [
    (RuntimeError("boom\nsecond line"), "failed: RuntimeError: boom"),
    (ConvergenceError("Newton diverged at t = 0.003"), "failed: Newton diverged at t = 0.003"),
    (KeyboardInterrupt(), "interrupted"),
])
def test_failure_leaves_readable_series(tmp_path, exc, status):
    pv = pytest.importorskip("pyvista")
    model, beam, body = cantilever_and_pendulum(3)
    asm = Assembly(model)
    st = _initial(asm)
    with (pytest.raises(type(exc)),
          OutputWriter(tmp_path, "demo", asm, probes=make_probes(beam, body)) as writer):
        for k in range(3):
            st.t = 0.01 * k
            writer.write(st)
        raise exc
    s = json.loads((tmp_path / "summary.json").read_text())
    assert s["status"] == status
    assert s["final_time"] == 0.02 and s["outputs"] == 3
    reader = pv.PVDReader(str(tmp_path / "demo.pvd"))
    assert reader.time_values == [0.0, 0.01, 0.02]
    for t in reader.time_values:
        reader.set_active_time_value(t)
        frame = reader.read()[0]        # a multiblock frame: its beam and body have points
        assert frame["beams"]["rail"].n_points > 0 and frame["bodies"]["bob"].n_points > 0
    assert len(read_csv(tmp_path / "probes.csv")) == 4
    assert load_checkpoint(tmp_path / "checkpoint.npz")[0].t == 0.02


def test_without_vtu_and_checkpoint(tmp_path):
    model, _, _ = cantilever_and_pendulum(2)
    asm = Assembly(model)
    with OutputWriter(tmp_path, "x", asm, write_vtu=False, checkpoints=False) as w:
        w.write(_initial(asm))
    names = {p.name for p in tmp_path.iterdir()}
    assert names == {"probes.csv", "contacts.csv", "summary.json"}
    assert (tmp_path / "probes.csv").read_text().splitlines() == ["t", "0.0"]
    assert (tmp_path / "contacts.csv").read_text().splitlines() == [CONTACT_HEADER]
    assert json.loads((tmp_path / "summary.json").read_text())["status"] == "completed"


# ------------------------------------------------------------------------------- probes
def test_beam_point_probe_range_is_checked():
    _, beam, _ = cantilever_and_pendulum(2)
    with pytest.raises(ModelError, match=r"probe 'p'.*0 <= s <= 1"):
        BeamPointProbe("p", beam, 1.5)
    with pytest.raises(ModelError, match="quantity"):
        BeamPointProbe("p", beam, 0.5, quantity="acceleration")


def test_probe_registry():
    assert {"beam_point", "body_position", "body_orientation", "energy"} <= set(PROBES)
    with pytest.raises(ModelError, match=r"unknown probe type 'strain_gauge' \(known: beam_point, "
                                         "body_position, body_orientation, body_point, energy"):
        PROBES.get("strain_gauge")


def test_probe_names_must_be_unique_and_belong_to_the_model(tmp_path):
    model, beam, body = cantilever_and_pendulum(2)
    asm = Assembly(model)
    with pytest.raises(ModelError, match="unique"):
        OutputWriter(tmp_path, "x", asm, probes=[EnergyProbe("E"), EnergyProbe("E", "kinetic")])
    other, beam2, _ = cantilever_and_pendulum(2)
    with pytest.raises(ModelError, match="not part of the model"):
        OutputWriter(tmp_path, "x", asm, probes=[BeamPointProbe("p", beam2, 0.5)])


def test_beam_point_probe_keeps_its_coordinates_and_pickles():
    """The probe keeps the beam's coordinates for the assembly it last evaluated (every
    output asks again): the same values as a new probe, for another assembly too, and it
    pickles (a sweep sends probes to its workers)."""
    import pickle

    model, beam, _ = cantilever_and_pendulum(3)
    asm = Assembly(model)
    st = _initial(asm)
    st.q[asm.centerline_dofs(beam)[-1]] += 1e-3
    probe = BeamPointProbe("tip", beam, 0.8, quantity="displacement")
    first = probe.evaluate(asm, st)
    np.testing.assert_array_equal(probe.evaluate(asm, st), first)
    np.testing.assert_array_equal(
        BeamPointProbe("tip", beam, 0.8, quantity="displacement").evaluate(asm, st), first)
    assert np.any(first != 0.0)
    other = Assembly(model)         # another assembly of the model: its own coordinates
    st2 = _initial(other)
    np.testing.assert_array_equal(probe.evaluate(other, st2), np.zeros(3))
    probe2, model2 = pickle.loads(pickle.dumps((probe, model)))     # with its model
    asm2 = Assembly(model2)
    st3 = _initial(asm2)
    st3.q[:] = st.q
    np.testing.assert_array_equal(probe2.evaluate(asm2, st3), first)


def test_keep_history_false_keeps_the_last_output_and_writes_them_all(tmp_path):
    """``simulate(keep_history=False)`` (what ``flexmbs run`` does: memory flat over long runs,
    issue 57) returns the last output only; the folder and the final state are the same."""
    results, folders = {}, {}
    for keep in (True, False):
        model, beam, body = cantilever_and_pendulum(2)
        folders[keep] = tmp_path / f"keep_{keep}"
        results[keep] = fm.simulate(model, t_end=0.02, dt=1e-3, output_interval=5e-3,
                                    out=folders[keep], probes=make_probes(beam, body),
                                    write_vtu=False, keep_history=keep)
    full, last = results[True], results[False]
    assert len(full.t) == 5 and list(last.t) == [full.t[-1]]
    np.testing.assert_array_equal(last.q, full.q[-1:])
    np.testing.assert_array_equal(last.lam, full.lam[-1:])
    assert {k: list(v) for k, v in last.energy.items()} == {k: [v[-1]] for k, v in
                                                           full.energy.items()}
    for column, values in full.extra["probes"].items():
        np.testing.assert_array_equal(last.extra["probes"][column], values[-1:])
    np.testing.assert_array_equal(last.final_state.q, full.final_state.q)
    assert last.stats.steps == full.stats.steps
    assert read_csv(folders[False] / "probes.csv") == read_csv(folders[True] / "probes.csv")

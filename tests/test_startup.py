"""Start-up and compilation: what ``import flexmbs`` and a run load, the kernel compiled for the
kinds of terms a model has, ``flexmbs compile`` and the compile notice."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

import flexmbs as fm
from flexmbs import kernel as kmod
from flexmbs._jit import HAVE_NUMBA
from flexmbs.assembly import Assembly
from flexmbs.cli import main
from flexmbs.commands.compile import compile_notice
from flexmbs.driver import OPTIONAL_KINDS

HEAVY = ("matplotlib", "pyvista", "vtk", "dask", "distributed", "meshio", "imageio")


def _loaded(code: str) -> set[str]:
    out = subprocess.run([sys.executable, "-c", code + "\nimport sys, json\n"
                          "print(json.dumps(sorted({m.split('.')[0] for m in sys.modules})))"],
                         capture_output=True, text=True, check=True)
    return set(json.loads(out.stdout.splitlines()[-1]))


def test_import_flexmbs_loads_no_heavy_library():
    loaded = _loaded("import flexmbs")
    assert not loaded & {*HEAVY, "numba", "scipy", "numpy"}, loaded & {*HEAVY, "numba", "scipy"}


def test_a_run_loads_no_plotting_rendering_dask_or_mesh_library(tmp_path):
    loaded = _loaded("from flexmbs.cli import main\n"
                     f"assert main(['run', 'examples/cantilever.toml', '--t-end', '0.002', "
                     f"'--out', {str(tmp_path / 'o')!r}, '--quiet']) == 0")
    assert not loaded & set(HEAVY), loaded & set(HEAVY)


def _cantilever(**kw):
    model = fm.Model(gravity=(0, 0, -9.81))
    beam = model.add_beam(fm.line((0, 0, 0), (1, 0, 0), elements=2), section=fm.CircularSection(5e-3),
                          material=fm.Material(E=2.1e11, rho=7800.0), **kw)
    model.clamp(beam.first_node)
    return model, beam


def test_kernel_gets_none_for_the_kinds_a_model_lacks():
    model, beam = _cantilever()
    asm = Assembly(model)
    for k in OPTIONAL_KINDS:
        assert getattr(asm.lean_system, k) is None
        assert getattr(asm.system, k) is not None          # Python's view keeps every part
    assert asm.lean_system.loads is asm.system.loads      # the same arrays
    assert kmod.model_kind(asm.lean_system) == "BeamPart"
    assert kmod.model_kind(asm.complete_system, complete=True) == "BeamPart complete"
    body = model.add_rigid_body(mass=0.1, inertia=(1e-5, 1e-5, 1e-5), position=(1.0, 0, 0))
    model.rigid(beam.last_node, body)
    asm = Assembly(model)
    present = {k for k in OPTIONAL_KINDS if getattr(asm.lean_system, k) is not None}
    # the joint brings the springs along (driver.COMPILED_TOGETHER), empty here
    assert present == {"bodies", "norms", "joints", "springs"}
    assert asm.lean_system.springs.idx.shape[0] == 0


def test_a_first_spring_next_to_a_joint_needs_no_kernel_of_its_own():
    """Models of bodies with joints, springs or both have one kind of kernel; bodies alone
    another (driver.COMPILED_TOGETHER)."""
    kinds = set()
    for extra in ("spring", "joint", "both"):
        model, beam = _cantilever()
        body = model.add_rigid_body(mass=0.1, inertia=(1e-5, 1e-5, 1e-5), position=(1.0, 0, 0))
        if extra in ("spring", "both"):
            model.add_spring_damper(body, beam.first_node, stiffness=10.0)
        if extra in ("joint", "both"):
            model.spherical(body, point=(1.0, 0.0, 0.0))
        kinds.add(kmod.model_kind(Assembly(model).lean_system))
    assert kinds == {"BeamPart+bodies+norms+joints+springs"}
    model, beam = _cantilever()
    model.add_rigid_body(mass=0.1, inertia=(1e-5, 1e-5, 1e-5), position=(1.0, 0, 0))
    assert kmod.model_kind(Assembly(model).lean_system) == "BeamPart+bodies+norms"


@pytest.mark.skipif(not HAVE_NUMBA, reason="numba disabled")
def test_compile_announces_once_with_the_recorded_estimate(tmp_path, monkeypatch):
    """prepare(): a kind compiled here is announced with the last duration recorded beside the
    cache; a kind compiled or cached is not announced."""
    model, _ = _cantilever()
    asm = Assembly(model)          # compiled (or loaded) now: ready in this process
    seen: list[tuple[float | None, str]] = []
    monkeypatch.setattr(kmod, "announce_compile",
                        lambda est, kind, same: seen.append((est, kind)))
    Assembly(model)
    assert seen == []
    kmod._write_times(tmp_path, {"BeamPart": 12.0, "RodPart+bodies": 40.0})
    assert kmod._read_times(tmp_path) == {"BeamPart": 12.0, "RodPart+bodies": 40.0}
    assert kmod._read_times(tmp_path / "missing") == {}
    assert "about 12 s" in compile_notice(12.0) and "\n" not in compile_notice(None)
    assert "took 40 s" in compile_notice(40.0, same_kind=False)
    assert asm.kernel_system is not None


def test_compile_command_names_kinds_and_refuses_others(capsys, tmp_path):
    assert main(["compile", "cable"]) == 0
    assert "cable: kernels ready (BeamPart" in capsys.readouterr().out
    assert main(["compile", "no-such-kind"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "neither a kind of model" in err
    assert main(["compile", str(tmp_path / "missing.toml")]) == 2
    assert capsys.readouterr().err.startswith("flexmbs: error:")


# ------------------------------------------------------------------ the complete kernels


class _StubKernel:
    """Stands for numba's dispatcher in :func:`flexmbs.kernel.prepare`: argument types are the
    values' ids, ``compile`` records what it compiled."""

    def __init__(self, folder):
        self.compiled: list[tuple] = []
        self.overloads: dict = {}
        self._cache = type("Cache", (), {"_cache_path": str(folder)})()

    def typeof_pyval(self, value):
        return id(value)

    def compile(self, sig):
        self.compiled.append(sig)


@pytest.mark.parametrize("choice, ready, expected, compiled", [
    ("auto", {"own", "complete"}, "own", False),
    ("auto", {"complete"}, "complete", False),
    ("auto", set(), "own", True),
    ("own", {"complete"}, "own", True),
    ("complete", {"own"}, "complete", True),
    ("complete", {"complete"}, "complete", False),
])
def test_prepare_chooses_the_models_own_kernel_or_the_complete_one(
        choice, ready, expected, compiled, monkeypatch, tmp_path):
    """FLEXMBS_KERNEL: auto takes the own kind's kernel when compiled or cached, else the
    complete one when it is, else compiles the own; own and complete take theirs, compiled
    if needed; a compile is announced and timed under its kind's name."""
    model, _ = _cantilever()
    asm = Assembly(model)
    own, complete = asm.lean_system, asm.complete_system
    stub = _StubKernel(tmp_path)
    monkeypatch.setattr(kmod, "kernel", stub)
    monkeypatch.setattr(kmod, "_READY", set())
    names = {id(own): "own", id(complete): "complete"}
    monkeypatch.setattr(kmod, "_is_ready", lambda sig: names[sig[1]] in ready)
    seen: list[str] = []
    monkeypatch.setattr(kmod, "announce_compile", lambda est, kind, same: seen.append(kind))
    monkeypatch.setenv("FLEXMBS_KERNEL", choice)
    args = (0, own, 1.0)
    chosen = kmod.prepare(args, complete)
    assert chosen is (own if expected == "own" else complete)
    assert bool(stub.compiled) == compiled == bool(seen)
    if compiled:
        assert stub.compiled == [(id(0), id(chosen), id(1.0))]
        kind = "BeamPart complete" if expected == "complete" else "BeamPart"
        assert seen == [kind] and kind in kmod._read_times(tmp_path)
    assert kmod.prepare(args, None) is own          # no complete system offered: the own


def test_a_bad_kernel_choice_is_one_line_before_anything_is_written(monkeypatch, tmp_path, capsys):
    monkeypatch.setenv("FLEXMBS_KERNEL", "fastest")
    out = tmp_path / "o"
    assert main(["run", "examples/cantilever.toml", "--t-end", "0.002", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "FLEXMBS_KERNEL='fastest'" in err and "auto, own, complete" in err
    assert not out.exists()


def _short_run(model, kernel_choice, monkeypatch):
    """A few steps of ``model`` with the kernel ``kernel_choice``; (the run's states, its
    assembly)."""
    monkeypatch.setenv("FLEXMBS_KERNEL", kernel_choice)
    asm = Assembly(model)
    res = fm.simulate(asm, t_end=2e-3, dt=1e-4, output_interval=5e-4, record_energy=False)
    return res, asm


@pytest.mark.skipif(not HAVE_NUMBA, reason="numba disabled")
@pytest.mark.parametrize("scenario", ["cantilever", "curved_beam_sleeve"])
def test_the_complete_kernel_gives_the_models_own_results_bit_for_bit(scenario, monkeypatch):
    """A model run on the complete kernel of its element types (every optional part present,
    empty where the model has none) and on its own kind's (those parts None: not compiled)
    steps through the same states, bit for bit: the beam-only model (every optional kind
    absent) and Example 1 (bodies, normalisations and a clearance joint present, the other
    kinds and the clearance's optional features absent)."""
    from flexmbs.io.scenario import load_scenario

    path = f"examples/{scenario}.toml"
    own, asm_own = _short_run(load_scenario(path).model, "own", monkeypatch)
    complete, asm_complete = _short_run(load_scenario(path).model, "complete", monkeypatch)
    assert asm_own.kernel_system is asm_own.lean_system
    assert asm_complete.kernel_system is asm_complete.complete_system
    assert any(getattr(asm_own.kernel_system, k) is None for k in OPTIONAL_KINDS)
    assert all(getattr(asm_complete.kernel_system, k) is not None for k in OPTIONAL_KINDS)
    assert own.stats.steps == complete.stats.steps > 0
    np.testing.assert_array_equal(own.q, complete.q)
    np.testing.assert_array_equal(own.v, complete.v)
    np.testing.assert_array_equal(own.lam, complete.lam)
    assert np.ptp(own.q, axis=0).max() > 0      # it moved


def _rod_weld_with_driver():
    """A rod with a body welded to its tip (node directors in the joints' table) and a
    driven hinge (the drivers' part)."""
    model = fm.Model(gravity=(0, 0, -9.81))
    rod = model.add_beam(fm.line((0, 0, 0), (1, 0, 0), elements=3), section=fm.CircularSection(5e-3),
                         material=fm.Material(E=2.1e11, rho=7800.0), element="ancf_rod14")
    model.clamp(rod.first_node)
    tip = model.add_rigid_body(mass=1.0, inertia=(1e-3, 1e-3, 1e-3), position=(1.0, 0, 0))
    model.rigid(rod.last_node, tip)
    arm = model.add_rigid_body(mass=1.0, inertia=(1e-3, 1e-3, 1e-3), position=(0, 1.0, 0))
    hinge = model.revolute(arm, fm.GROUND, point=(0, 0.5, 0), axis=(0, 0, 1))
    model.add_driver(hinge, fm.Sine(amplitude=0.1, frequency=1.0))
    return model


@pytest.mark.skipif(not HAVE_NUMBA, reason="numba disabled")
def test_models_of_the_same_element_groups_share_one_complete_kernel(monkeypatch):
    """The complete system (SystemPart.complete) of models with every mix of kinds and
    features — beams only, bodies, joints with and without node directors, drivers, springs,
    sliding joints, clearance joints with closed and open bores, the paper's detection, a
    rod in a clearance joint — has one numba type per set of element groups (one cable
    group; a rod group with or without cables): two complete kernels serve them all, while
    their own kernels differ."""
    from conftest import EXAMPLES, load_example

    from flexmbs.io.scenario import load_scenario

    models = [load_scenario(path).model for path in sorted(EXAMPLES.glob("*.toml"))]
    models += [load_example("helical_spring").build(per_coil=4)[0], _rod_weld_with_driver(),
               load_example("capstan").build(np.pi / 2, 0.2)[0]]
    paper = load_scenario(EXAMPLES / "curved_beam_sleeve.toml", ["joints.sleeve.detection=paper"]).model
    models.append(paper)
    monkeypatch.setenv("FLEXMBS_KERNEL", "complete")     # no own kernel compiled here
    complete: dict[str, set[str]] = {}
    own = set()
    for model in models:
        asm = Assembly(model)
        groups = kmod.model_kind(asm.complete_system, complete=True)
        complete.setdefault(groups, set()).add(str(kmod.kernel.typeof_pyval(asm.complete_system)))
        own.add(str(kmod.kernel.typeof_pyval(asm.lean_system)))
    assert set(complete) == {"BeamPart complete", "BeamPart+RodPart complete"}
    assert all(len(types) == 1 for types in complete.values())
    assert len(own) >= 8

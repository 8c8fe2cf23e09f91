"""Start-up and compilation: what ``import flexmbs`` and a run load, the kernel compiled for the
kinds of terms a model has, ``flexmbs compile`` and the compile notice."""

from __future__ import annotations

import json
import subprocess
import sys

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
        assert getattr(asm.kernel_system, k) is None
        assert getattr(asm.system, k) is not None          # Python's view keeps every part
    assert asm.kernel_system.loads is asm.system.loads      # the same arrays
    assert kmod.model_kind(asm.kernel_system) == "BeamPart"
    body = model.add_rigid_body(mass=0.1, inertia=(1e-5, 1e-5, 1e-5), position=(1.0, 0, 0))
    model.rigid(beam.last_node, body)
    asm = Assembly(model)
    present = {k for k in OPTIONAL_KINDS if getattr(asm.kernel_system, k) is not None}
    # the joint brings the springs along (driver.COMPILED_TOGETHER), empty here
    assert present == {"bodies", "norms", "joints", "springs"}
    assert asm.kernel_system.springs.idx.shape[0] == 0


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
        kinds.add(kmod.model_kind(Assembly(model).kernel_system))
    assert kinds == {"BeamPart+bodies+norms+joints+springs"}
    model, beam = _cantilever()
    model.add_rigid_body(mass=0.1, inertia=(1e-5, 1e-5, 1e-5), position=(1.0, 0, 0))
    assert kmod.model_kind(Assembly(model).kernel_system) == "BeamPart+bodies+norms"


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

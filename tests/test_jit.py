"""The numba cache guard: an on-disk index written by older code that names a module which no
longer exists is treated as empty (the kernel recompiles) instead of failing."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from flexmbs._jit import HAVE_NUMBA

ROOT = Path(__file__).resolve().parents[1]

USER = f'''
import sys
sys.path.insert(0, {str(ROOT)!r})
import numpy as np
from flexmbs._jit import njit
try:
    from gone import P
except ImportError:
    from typing import NamedTuple

    class P(NamedTuple):
        a: np.ndarray

@njit
def total(p):
    return p.a.sum()

print(total(P(np.ones(3))))
'''


@pytest.mark.skipif(not HAVE_NUMBA, reason="numba caching only")
def test_stale_cache_index_recompiles(tmp_path: Path) -> None:
    (tmp_path / "gone.py").write_text(
        "from typing import NamedTuple\nimport numpy as np\n\n\nclass P(NamedTuple):\n"
        "    a: np.ndarray\n")
    (tmp_path / "user.py").write_text(USER)

    def run() -> subprocess.CompletedProcess[str]:
        return subprocess.run([sys.executable, "user.py"], cwd=tmp_path, capture_output=True,
                              text=True, timeout=300)

    assert run().stdout.strip() == "3.0"           # writes an index naming gone.P
    (tmp_path / "gone.py").unlink()
    for stale in (tmp_path / "__pycache__").glob("gone*"):
        stale.unlink()
    second = run()                                  # the index now names a missing module
    assert second.returncode == 0, second.stderr[-500:]
    assert second.stdout.strip() == "3.0"


def test_kernels_are_stamped_with_every_kernel_module(tmp_path):
    """numba stamps a cached kernel with its own file; flexmbs' kernels carry the code of their
    callees, so their stamp is the content of every kernel module: an edit of a callee's module
    (here a copy of the package) changes it, an edit of a module without kernels does not."""
    import shutil
    from pathlib import Path

    import flexmbs
    from flexmbs._jit import HAVE_NUMBA, package_stamp

    root = Path(flexmbs.__file__).parent
    copy = tmp_path / "flexmbs"
    shutil.copytree(root, copy, ignore=shutil.ignore_patterns("__pycache__"))
    before = package_stamp(copy)
    cli = copy / "cli.py"
    cli.write_text(cli.read_text() + "\n# edited\n")
    assert package_stamp(copy) == before
    tangent = copy / "contact" / "tangent.py"
    tangent.write_text(tangent.read_text() + "\n# edited\n")
    assert package_stamp(copy) != before
    if HAVE_NUMBA:
        from flexmbs.kernel import kernel

        locator = kernel._cache._impl._locator
        assert locator.get_source_stamp() == package_stamp(root)


@pytest.mark.skipif(not HAVE_NUMBA, reason="numba caching only")
def test_a_caller_outside_the_package_is_stamped_with_the_package(tmp_path, monkeypatch):
    """A function outside the package compiled by flexmbs' njit (a benchmark's timing loop)
    caches the package kernels it calls with its own code: its stamp is its file's and the
    package's, so an edit of a kernel module recompiles it too (it measured stale code
    before); numba's own functions keep numba's stamp."""
    import importlib

    import numba

    import flexmbs
    from flexmbs._jit import package_stamp

    (tmp_path / "timing_loop.py").write_text(
        "from flexmbs._jit import njit\nimport numba\n\n\n@njit\ndef loop(n):\n"
        "    return n + 1\n\n\n@njit(refcount=False)\ndef loop2(n):\n    return n + 2\n\n\n"
        "@numba.njit(cache=True)\ndef plain(n):\n    return n + 3\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    mod = importlib.import_module("timing_loop")
    assert (mod.loop(1), mod.loop2(1), mod.plain(1)) == (2, 3, 4)
    package = package_stamp(Path(flexmbs.__file__).parent)
    for d in (mod.loop, mod.loop2):
        own, stamp = d._cache._impl._locator.get_source_stamp()
        assert stamp == package and own
    assert isinstance(mod.plain, numba.core.dispatcher.Dispatcher)
    assert mod.plain._cache._impl._locator.get_source_stamp() != package
    assert package not in tuple(mod.plain._cache._impl._locator.get_source_stamp())


def _arrays_returned_without_refcount(dispatchers) -> list[str]:
    """Compiled signatures of reference-count-free kernels whose result holds an array (the
    caller would release a reference it was never given, ``_jit.njit``)."""
    from numba.core import types

    def holds_array(t) -> bool:
        if isinstance(t, types.Array):
            return True
        if isinstance(t, types.BaseTuple):
            return any(holds_array(x) for x in t)
        return False

    found = []
    for d in dispatchers:
        if d.targetoptions.get("_nrt") is not False:
            continue
        cache = getattr(getattr(d, "_cache", None), "_cache_file", None)
        for key in (cache._load_index() if cache is not None else {}):
            d.compile(key[0])   # every signature on disk (loaded, not compiled again)
        found += [f"{d.py_func.__module__}.{d.py_func.__name__}{sig}"
                  for sig in d.nopython_signatures if holds_array(sig.return_type)]
    return found


@pytest.mark.skipif(not HAVE_NUMBA, reason="compiled kernels only")
def test_reference_counting_is_stated_and_kept_where_arrays_are_returned():
    """Every flexmbs kernel states numba's ``_nrt`` flag (a callee that leaves it unset takes
    its first caller's, and the contact kernels allocate), and none compiled without reference
    counting returns an array: checked on every signature in numba's cache (at least those of
    a model with cable, rigid body, joints and a clearance joint, Example 1, and of a clamped
    rod, built here), with a planted offender to show that the check sees one."""
    import importlib
    import pkgutil

    import numpy as np
    from numba.core.registry import CPUDispatcher

    import flexmbs as fm
    from flexmbs._jit import _NRT_OPTION, njit
    from flexmbs.assembly import Assembly
    from flexmbs.io.scenario import load_scenario

    if not _NRT_OPTION:
        pytest.skip("this numba does not know the _nrt option")
    for model in (load_scenario(ROOT / "examples" / "curved_beam_sleeve.toml").model, None):
        if model is None:
            model = fm.Model()
            beam = model.add_beam(fm.line((0, 0, 0), (1, 0, 0), elements=2), element="ancf_rod14",
                                  section=fm.BeamStiffness(axial_stiffness=1e6, bending_stiffness=1.0,
                                                           mass_per_length=1.0,
                                                           torsional_stiffness=0.8))
            model.clamp(beam.first_node)
        asm = Assembly(model)
        n, m = asm.n_coords, asm.n_total - asm.n_coords
        asm.evaluate(asm.q_ref, np.zeros(n), np.zeros(n), np.zeros(m), 0.0, np.zeros(n),
                     np.zeros(m), matrix=(1.0, 0.0, 1.0))
    dispatchers = {}
    for info in pkgutil.walk_packages(fm.__path__, "flexmbs."):
        if info.name.endswith("__main__"):
            continue
        module = importlib.import_module(info.name)
        for obj in vars(module).values():
            if isinstance(obj, CPUDispatcher) and obj.py_func.__module__ == info.name:
                dispatchers[id(obj)] = obj
    assert len(dispatchers) > 100
    unstated = [d.py_func.__name__ for d in dispatchers.values() if "_nrt" not in d.targetoptions]
    assert unstated == []
    assert _arrays_returned_without_refcount(dispatchers.values()) == []

    @njit(refcount=False, cache=False)
    def planted(a):
        return a

    planted(np.ones(3))
    assert len(_arrays_returned_without_refcount([planted])) == 1


@pytest.mark.skipif(not HAVE_NUMBA, reason="compiled kernels only")
def test_internal_kernel_serves_compiled_callers_and_refuses_python():
    """A kernel compiled without a Python entry (``internal=True``) is called by compiled code
    as any other, and a call from Python raises a TypeError naming it instead of crashing."""
    import numpy as np

    from flexmbs._jit import njit

    @njit(internal=True, cache=False)
    def doubled(a):
        return 2.0 * a[0]

    @njit(cache=False)
    def caller(a):
        return doubled(a) + 1.0

    assert caller(np.array([3.0])) == 7.0
    with pytest.raises(TypeError, match="doubled is compiled for compiled callers only"):
        doubled(np.array([3.0]))

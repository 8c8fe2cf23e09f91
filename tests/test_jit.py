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

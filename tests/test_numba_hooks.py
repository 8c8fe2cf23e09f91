"""numba's private hooks that flexmbs relies on (issue 54, item 7) are in effect.

Each hook falls back quietly at run time when numba's internals change (flexmbs keeps
working, only slower or with a stale-cache risk), so this test is where such a change is
seen: it fails, it never skips, whenever numba is in use. The hooks:

- ``_nrt`` (:func:`flexmbs._jit.njit` ``refcount=False``): the rod's and the contact kernels'
  speed (a 4x slower element kernel without it);
- the cache locators that stamp every package kernel with the package's source
  (:func:`flexmbs._jit._install_package_stamp`): without them an edit of a callee's module
  leaves its callers' stale machine code in the cache;
- the tolerant cache index (:func:`flexmbs._jit._tolerate_stale_cache`);
- the class swap of kernels for compiled callers only (:func:`flexmbs._jit._compiled_callers_only`);
- the cache's path and index key that the compile announcement and
  :func:`flexmbs.kernel.kernels_cached` read.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest
import tomllib

from flexmbs import _jit

ROOT = Path(__file__).resolve().parents[1]

pytestmark = pytest.mark.skipif(os.environ.get("FLEXMBS_DISABLE_JIT", "") == "1",
                                reason="numba deliberately disabled (FLEXMBS_DISABLE_JIT=1)")


def test_numba_is_within_the_tested_range() -> None:
    import numba

    spec = next(d for d in tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
                ["dependencies"] if d.startswith("numba"))
    low, high = re.fullmatch(r"numba>=([\d.]+),<([\d.]+)", spec).groups()  # type: ignore[union-attr]

    def version(text: str) -> tuple[int, ...]:
        return tuple(int(x) for x in re.findall(r"\d+", text)[:2])

    assert version(low) <= version(numba.__version__) < version(high), (numba.__version__, spec)
    assert _jit.HAVE_NUMBA


def test_kernels_compile_without_reference_counting() -> None:
    from flexmbs.elements import ancf_rod

    assert _jit._NRT_OPTION, "numba no longer knows _nrt: the rod kernels lose their speed-up"
    kernels = [obj for obj in vars(ancf_rod).values()
               if hasattr(obj, "targetoptions") and obj.py_func.__module__ == ancf_rod.__name__]
    assert kernels
    assert any(k.targetoptions.get("_nrt") is False for k in kernels)


def test_package_kernels_carry_the_package_stamp() -> None:
    from numba.core import caching

    from flexmbs import kernel

    impl = getattr(caching, "CacheImpl", None) or caching._CacheImpl
    names = [c.__name__ for c in impl._locator_classes]
    assert names[0].startswith("Flexmbs"), names
    locator = kernel.kernel._cache._impl.locator
    assert type(locator).__name__.startswith("Flexmbs")
    assert locator.get_source_stamp() == _jit.package_stamp(ROOT / "flexmbs")


def test_cache_index_and_paths_are_reachable() -> None:
    from flexmbs import kernel

    cache = kernel.kernel._cache
    load = cache._cache_file._load_index
    assert load.__qualname__.startswith("_tolerate_stale_cache"), load.__qualname__
    assert isinstance(load(), dict)
    assert Path(cache._cache_path).is_dir()
    assert callable(cache._index_key)


def test_internal_kernels_swap_their_class() -> None:
    from flexmbs.contact.clearance_term import clearance_terms

    assert type(clearance_terms).__name__ == type(clearance_terms).__mro__[1].__name__
    assert type(clearance_terms) in _jit._INTERNAL_CLASSES.values()
    with pytest.raises(TypeError, match="compiled callers only"):
        clearance_terms(None, None, None, False, 0.0, 0.0, None, None, None)

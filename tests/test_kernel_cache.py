"""numba's cache of the kernels lives in one directory per version of their whole source
(core_se3/kernels/cache.py): numba itself checks only the defining file of a function, and the
kernels inline functions of other files, so a cache kept across an edit or an upgrade could run
old code (seen: drivers of element_passes kept the old material block of element_ops)."""
import importlib
import importlib.util
import os
import shutil

import pytest

from core_se3.kernels import cache

pytestmark = pytest.mark.skipif(importlib.util.find_spec("numba") is None, reason="needs numba")

KERNEL_MODULES = ["csr", "element", "element_mixed", "element_ops", "element_passes", "lie", "loads"]


def test_the_fingerprint_changes_with_any_kernel_file(tmp_path):
    for f in cache.HERE.glob("*.py"):
        shutil.copy(f, tmp_path / f.name)
    files = sorted(tmp_path.glob("*.py"))
    assert len(files) >= 8
    before = cache.source_fingerprint(files)
    assert before == cache.source_fingerprint(files)                     # deterministic
    assert before == cache.source_fingerprint()                          # the package's own files
    for f in files:                                                      # any one of them
        text = f.read_text()
        f.write_text(text + "\n# edited\n")
        assert cache.source_fingerprint(files) != before, f.name
        f.write_text(text)
    assert cache.source_fingerprint(files) == before


def test_every_cached_kernel_is_cached_under_the_fingerprint_of_the_sources():
    from numba.core import config
    from numba.core.registry import CPUDispatcher
    where = cache.cache_directory()
    assert os.path.basename(where) == cache.PREFIX + cache.source_fingerprint()
    seen = 0
    for name in KERNEL_MODULES:
        mod = importlib.import_module(f"core_se3.kernels.{name}")
        for obj in vars(mod).values():
            if isinstance(obj, CPUDispatcher) and obj.__module__ == mod.__name__ and obj._cache._cache_path:
                assert obj._cache._cache_path.startswith(where), (name, obj.__name__, obj._cache._cache_path)
                seen += 1
    assert seen > 50
    # the setting was numba's only while the kernels were imported: other numba code keeps its own
    assert config.CACHE_DIR == (os.environ.get("NUMBA_CACHE_DIR") or "")


def test_caches_of_earlier_sources_are_removed(monkeypatch, tmp_path):
    tree = cache.HERE / "__pycache__"
    stale = tree / (cache.PREFIX + "0" * 16)
    stale.mkdir(parents=True, exist_ok=True)
    (stale / "x.nbi").write_text("")
    legacy = tree / "lie.retract-1.py311.nbi"                            # numba's own layout
    legacy.write_text("")
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    with cache.fingerprinted_cache() as path:
        assert os.path.basename(path) == cache.PREFIX + cache.source_fingerprint()
    assert not stale.exists() and not legacy.exists()
    # a user-provided NUMBA_CACHE_DIR is the base and is never pruned
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    (tmp_path / (cache.PREFIX + "1" * 16)).mkdir()
    with cache.fingerprinted_cache() as path:
        assert os.path.dirname(path) == str(tmp_path)
    assert (tmp_path / (cache.PREFIX + "1" * 16)).exists()

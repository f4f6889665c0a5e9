"""bladelab.numba_cache: a compiled module's on-disk cache is flushed when bladelab's compiled
sources change (numba keys a cached function on its own file only)."""

from __future__ import annotations

import importlib
import sys

import bladelab.numba_cache as nc


def _module(tmp_path, name: str):
    (tmp_path / f"{name}.py").write_text(
        "from numba import njit\n\n"
        "@njit(cache=True)\n"
        "def twice(x):\n"
        "    return 2 * x\n")
    sys.path.insert(0, str(tmp_path))
    try:
        return importlib.import_module(name)
    finally:
        sys.path.remove(str(tmp_path))


def test_a_cache_is_flushed_once_per_change_of_the_sources(tmp_path, monkeypatch):
    mod = _module(tmp_path, "bladelab_cache_probe")
    assert mod.twice(3) == 6  # compiled and saved
    cache = mod.twice._cache
    sig = mod.twice.signatures[0]
    target = mod.twice.targetdescr
    assert cache.load_overload(sig, target.target_context) is not None
    # first sight of the sources: flushed, the stamp written; then nothing until they change
    assert nc.refresh_stale_caches(vars(mod))
    assert cache.load_overload(sig, target.target_context) is None
    assert not nc.refresh_stale_caches(vars(mod))
    sys.path.insert(0, str(tmp_path))
    mod = importlib.reload(mod)  # a new process, in effect: compiled again and saved
    sys.path.remove(str(tmp_path))
    assert mod.twice(4) == 8
    cache = mod.twice._cache
    assert cache.load_overload(sig, target.target_context) is not None
    assert not nc.refresh_stale_caches(vars(mod))
    monkeypatch.setattr(nc, "sources_digest", lambda: "an edited source")
    assert nc.refresh_stale_caches(vars(mod))
    assert cache.load_overload(sig, target.target_context) is None


def test_the_digest_covers_the_compiled_sources():
    digest = nc.sources_digest()
    assert len(digest) == 64 and digest == nc.sources_digest()
    # modules without compiled code do not count; every module that caches compiled code calls
    # the refresh at its end
    root = nc._ROOT
    for path in root.rglob("*.py"):
        text = path.read_text(encoding="utf-8")
        if "cache=True" in text and "@njit" in text:
            assert text.rstrip().endswith("refresh_stale_caches(globals())"), path

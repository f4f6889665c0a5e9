"""numba's on-disk cache, kept fresh across files.

numba keys a cached function on its own source file (time stamp and size) and its own bytecode;
the machine code of the functions it calls, from other files, is compiled into it. After an
edit to a callee in another file, the caller's cached code is stale and runs the old callee
(2026-11-27: a new reflex term had no effect in the closed loop, and a changed one kept its old
formula, until the cache was deleted; kernel.py's ``_CACHE_GENERATION`` was the manual fix).

:func:`refresh_stale_caches`, called at the end of every module that defines cached compiled
functions, flushes those functions' cache index once whenever any compiled source of bladelab
changed since it was last flushed, so that they are compiled again from the current sources.
An installed package never changes, so users compile once; a developer's edit costs one
compilation of what is used next.
"""

from __future__ import annotations

import functools
import hashlib
from pathlib import Path

from numba.core.registry import CPUDispatcher

__all__ = ["refresh_stale_caches", "sources_digest"]

_ROOT = Path(__file__).resolve().parent


@functools.cache
def sources_digest() -> str:
    """SHA-256 of bladelab's source files that use numba (their paths and contents)."""
    h = hashlib.sha256()
    for path in sorted(_ROOT.rglob("*.py")):
        data = path.read_bytes()
        if b"numba" in data:
            h.update(str(path.relative_to(_ROOT)).encode())
            h.update(data)
    return h.hexdigest()


def refresh_stale_caches(namespace: dict) -> bool:
    """Flush the on-disk cache of the compiled functions defined in the module ``namespace``
    (its ``globals()``) if bladelab's compiled sources changed since the module's last flush
    (a stamp file beside the cache). Returns whether it flushed."""
    module = namespace["__name__"]
    dispatchers = [v for v in namespace.values()
                   if isinstance(v, CPUDispatcher) and v.py_func.__module__ == module
                   and getattr(v, "_cache", None) is not None
                   and hasattr(v._cache, "_cache_path")]
    if not dispatchers:
        return False
    stamp = Path(dispatchers[0]._cache._cache_path) / f"{module}.sources-digest"
    digest = sources_digest()
    try:
        if stamp.read_text() == digest:
            return False
    except OSError:
        pass
    for dispatcher in dispatchers:
        dispatcher._cache.flush()
    try:
        stamp.parent.mkdir(parents=True, exist_ok=True)
        stamp.write_text(digest)
    except OSError:
        pass  # a read-only cache: numba falls back to compiling in memory anyway
    return True

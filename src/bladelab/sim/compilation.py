"""Saying out loud that a numba kernel is about to be compiled.

The first call of a large kernel after an install or an update compiles it (35–114 s for the
blade kernel or the runner's loop on a 2-core machine) and caches the machine code on disk;
later processes load it in well under a second. :func:`announce_compilation` prints one line on
stderr before such a first call when the kernel's on-disk cache holds nothing for this machine,
so that a long silence is not taken for a hang.
"""

from __future__ import annotations

import sys

__all__ = ["announce_compilation", "cache_is_cold"]

_checked: set[int] = set()  # id() of the kernels already looked at in this process


def cache_is_cold(dispatcher) -> bool:
    """True when calling ``dispatcher`` (a ``numba.njit(cache=True)`` function) would compile it:
    nothing compiled or loaded in this process yet, and its on-disk cache index holds no entry for
    this machine and this version of the function (missing, stale, or from another CPU or numba).

    Reads one small index file, only until the first call has compiled or loaded the kernel.
    False when numba's cache cannot be inspected (no cache, JIT disabled, a numba without these
    internals): the notice is a courtesy and never stops a run.
    """
    try:
        if dispatcher.signatures:  # compiled or loaded in this process already
            return False
        cache = dispatcher._cache
        index = cache._cache_file._load_index()  # {} when missing or stale (source stamp)
        codegen = dispatcher.targetctx.codegen()
        return not any(cache._index_key(key[0], codegen) == key for key in index)
    except Exception:  # numba internals changed: a notice must never break a simulation
        return False


def announce_compilation(dispatcher, what: str) -> None:
    """Print ``compiling WHAT (first run after install or update, about a minute; cached
    afterwards)…`` on stderr when ``dispatcher``'s cache is cold (:func:`cache_is_cold`).

    Looks once per kernel and process (later calls cost a set lookup: callers may sit in an
    identification's inner loop)."""
    if id(dispatcher) in _checked:
        return
    _checked.add(id(dispatcher))
    if not cache_is_cold(dispatcher):
        return
    print(
        f"compiling {what} (first run after install or update, about a minute; "
        "cached afterwards)…",
        file=sys.stderr,
        flush=True,
    )

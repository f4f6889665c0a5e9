"""One mesh node's functions compiled to C and cached on disk.

Every node of a stride NLP evaluates the same SX function
(:attr:`~bladelab.predict.collocation.transcription.StrideNLP.node`). :func:`compiled_node`
generates C for it and its Jacobian with CasADi's code generator, compiles them with the
machine's C compiler (``cc``, else ``gcc``) into a shared library, and returns them as a CasADi
``external`` that the NLP maps over the mesh instead of the interpreted function; its solver is
then built without expanding the graph to SX.

Measured on the amputee Cat6 stride at mesh 50 (benchmarks/collocation_speed/README.md, "One
mesh node compiled to C"): the node's 2 MB of C compile in about 13 s, once; the solver is then
built in 0.3 s instead of about 18 s and holds half the memory; an iteration costs the same
(the node evaluations are faster, CasADi's MX Jacobian around them slower, and IPOPT's own
linear algebra is most of it).

The cache (:func:`cache_dir`) holds one library per node function, keyed by the node's
serialized graph (the model, its parameters and the objective's terms), the CasADi version,
the compiler's version and its flags: a changed model or setting compiles anew, a stale library
is never loaded. A library is written under a temporary name and renamed into place, so two
processes compiling the same node at once leave one valid file. A compiler that is missing or
fails gives one :class:`CompileWarning` and the interpreted functions (None); the NLP is the
same either way. ``BLADELAB_COMPILE=0`` turns compiling off (the test suite does, except where
it tests this module).
"""

from __future__ import annotations

import hashlib
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import casadi as ca

__all__ = ["CACHE_ENV", "CFLAGS", "COMPILE_ENV", "CompileWarning", "cache_dir", "compiled_node",
           "compiling_enabled"]

#: Environment variable that turns compiling off ("0", "no", "off" or "false").
COMPILE_ENV = "BLADELAB_COMPILE"
#: Environment variable that sets the cache folder (default: the user's cache folder).
CACHE_ENV = "BLADELAB_CACHE_DIR"
#: The compiler's flags (-O1: measured 13 s for the node at mesh-independent size).
CFLAGS = ("-O1", "-shared", "-fPIC")
#: Name of the node function in the generated library.
NODE_NAME = "node"


class CompileWarning(UserWarning):
    """The node functions could not be compiled; the interpreted ones are used."""


def compiling_enabled() -> bool:
    """False when :data:`COMPILE_ENV` says "0", "no", "off" or "false"."""
    return os.environ.get(COMPILE_ENV, "1").strip().lower() not in ("0", "no", "off", "false")


def cache_dir() -> Path:
    """The folder of the compiled libraries: :data:`CACHE_ENV`, else
    ``$XDG_CACHE_HOME/bladelab/casadi`` (``~/.cache/bladelab/casadi``); a folder that cannot be
    created or written falls back to one under the system's temporary folder."""
    base = os.environ.get(CACHE_ENV)
    if not base:
        xdg = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
        base = str(Path(xdg) / "bladelab" / "casadi")
    for folder in (Path(base), Path(tempfile.gettempdir()) / f"bladelab-casadi-{_user()}"):
        try:
            folder.mkdir(parents=True, exist_ok=True)
            probe = tempfile.NamedTemporaryFile(dir=folder, prefix=".probe-")
            probe.close()
            return folder
        except OSError:
            continue
    return Path(tempfile.mkdtemp(prefix="bladelab-casadi-"))


def compiled_node(node: ca.Function) -> ca.Function | None:
    """``node`` (an SX function) as a compiled ``external`` with its Jacobian, loaded from the
    cache or compiled into it (a line on stderr says so, and how long it took); None, with a
    :class:`CompileWarning`, when no compiler works."""
    compiler = _compiler()
    if compiler is None:
        warnings.warn("no C compiler (cc or gcc) found: the collocation functions are "
                      "interpreted (install gcc to compile them)", CompileWarning, stacklevel=2)
        return None
    path = cache_dir() / f"{NODE_NAME}-{_key(node, compiler)}.so"
    try:
        if path.exists():
            try:
                return ca.external(NODE_NAME, str(path))
            except RuntimeError:  # unreadable (another machine's, damaged): compiled again
                path.unlink(missing_ok=True)
        _compile(node, compiler[0], path)
        return ca.external(NODE_NAME, str(path))
    except (OSError, subprocess.CalledProcessError, RuntimeError) as err:
        detail = getattr(err, "stderr", None) or str(err)
        warnings.warn(f"compiling the collocation functions with {compiler[0]} failed "
                      f"({str(detail).strip()[:300]}): they are interpreted",
                      CompileWarning, stacklevel=2)
        return None


def _compile(node: ca.Function, compiler: str, path: Path) -> None:
    """Generate C for ``node`` and its Jacobian and compile it into ``path`` (written under a
    temporary name in the same folder, then renamed)."""
    print(f"compiling the collocation functions ({compiler} {CFLAGS[0]}, about 15 s; cached "
          f"in {path.parent})…", file=sys.stderr, flush=True)
    t0 = time.perf_counter()
    work = Path(tempfile.mkdtemp(prefix="bladelab-node-"))
    try:
        f = ca.Function(NODE_NAME, node.sx_in(), node.call(node.sx_in()))
        gen = ca.CodeGenerator(f"{NODE_NAME}.c", {"with_header": False})
        gen.add(f)
        gen.add(f.jacobian())
        source = Path(gen.generate(str(work) + os.sep))
        partial = path.with_name(f".{path.name}.{os.getpid()}.tmp")
        subprocess.run([compiler, *CFLAGS, str(source), "-o", str(partial), "-lm"],
                       check=True, capture_output=True, text=True)
        os.replace(partial, path)
    finally:
        shutil.rmtree(work, ignore_errors=True)
        for stale in path.parent.glob(f".{path.name}.{os.getpid()}.tmp"):
            stale.unlink(missing_ok=True)
    print(f"compiled the collocation functions in {time.perf_counter() - t0:.1f} s",
          file=sys.stderr, flush=True)


def _key(node: ca.Function, compiler: tuple[str, str]) -> str:
    """Hash of everything that changes the library: the node's graph, CasADi, the machine's
    architecture and system, the compiler and its flags."""
    h = hashlib.sha256()
    for part in (node.serialize(), ca.__version__, platform.machine(), platform.system(),
                 *compiler, *CFLAGS):
        h.update(part.encode())
        h.update(b"\0")
    return h.hexdigest()[:20]


def _compiler() -> tuple[str, str] | None:
    """(path, version text) of the first working C compiler of ``cc`` and ``gcc``, or None."""
    for name in ("cc", "gcc"):
        exe = shutil.which(name)
        if exe is None:
            continue
        try:
            out = subprocess.run([exe, "--version"], capture_output=True, text=True, timeout=30,
                                 check=True).stdout
        except (OSError, subprocess.SubprocessError):
            continue
        return exe, out.splitlines()[0] if out else name
    return None


def _user() -> str:
    try:
        return str(os.getuid())
    except AttributeError:  # not POSIX
        return os.environ.get("USERNAME", "user")

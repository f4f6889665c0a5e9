"""The house rules of docs/architecture.md: wings import one way, no import loop between wings
or between files, no private names imported across modules (the CLI uses none of the library's
at all), and every import inside a function says why it is there. Every import counts,
function-local ones included."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "bladelab"

FOUNDATION = {"bladelab", "units", "constants", "errors", "_io", "parameters", "contact",
              "executors", "numba_cache", "datasets"}
# wing -> the wings it may import (besides itself); docs/architecture.md draws the same graph
ALLOWED: dict[str, set[str]] = {
    **{name: FOUNDATION for name in FOUNDATION},
    "trial": FOUNDATION,
    "blade": FOUNDATION,
    "sim": FOUNDATION | {"trial", "blade"},
    "identify": FOUNDATION | {"trial", "blade", "sim"},
    "mechanics": FOUNDATION | {"trial"},
    "stats": FOUNDATION,
    "study": FOUNDATION | {"trial", "blade", "sim", "identify"},
    "runner": FOUNDATION | {"blade", "sim"},
    "predict": FOUNDATION | {"trial", "blade", "sim", "runner"},
    "design": FOUNDATION | {"trial", "blade", "sim", "runner", "predict"},
    "example": FOUNDATION | {"trial", "blade", "sim", "identify", "study"},
    "report": FOUNDATION | {"trial", "blade", "sim", "identify", "mechanics", "stats", "study",
                            "runner", "predict", "design", "example"},
    "cli": None,  # the top: may import anything
    "demo": None,
    "__main__": None,
}


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(SRC.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _wing(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "bladelab"


def _in_functions(tree: ast.AST) -> set[int]:
    """The ids of the nodes inside a function (at any depth, methods included)."""
    return {id(node) for func in ast.walk(tree)
            if isinstance(func, (ast.FunctionDef, ast.AsyncFunctionDef))
            for node in ast.walk(func) if node is not func}


def _imports(path: Path, source: str | None = None) -> list[tuple[str, str, int, bool]]:
    """(imported module, imported name or '', line, inside a function) of every bladelab import
    in a file (or in ``source`` as if it were that file)."""
    module = _module_name(path)
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    out = []
    text = path.read_text(encoding="utf-8") if source is None else source
    tree = ast.parse(text)
    local = _in_functions(tree)
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.split(".")[0] == "bladelab":
                out += [(target, alias.name, node.lineno, id(node) in local)
                        for alias in node.names]
        elif isinstance(node, ast.Import):
            out += [(a.name, "", node.lineno, id(node) in local) for a in node.names
                    if a.name.split(".")[0] == "bladelab"]
    return out


def _edges(sources: dict[Path, str] | None = None) -> list[tuple[str, str, str, int]]:
    """(importing wing, imported wing, file, line) for every cross-wing import of the package
    (or of ``sources``: path -> text)."""
    edges = []
    for path in sources or sorted(SRC.rglob("*.py")):
        wing = _wing(_module_name(path))
        for target, name, line, _ in _imports(path, (sources or {}).get(path)):
            # `from bladelab import units` imports the module bladelab.units
            is_module = (SRC / f"{name}.py").is_file() or (SRC / name).is_dir()
            other = _wing(f"{target}.{name}" if target == "bladelab" and is_module else target)
            if other != wing:
                edges.append((wing, other, str(path.relative_to(SRC.parent)), line))
    return edges


def _module_graph(sources: dict[Path, str] | None = None) -> dict[str, dict[str, list[str]]]:
    """module -> {module it imports: ['file:line', ...]} over the package's files (or over
    ``sources``: path -> text), function-local imports included. ``from a.b import c`` imports
    the module ``a.b.c`` where that is a module, else ``a.b``; a package is its ``__init__``."""
    paths = sorted(sources) if sources else sorted(SRC.rglob("*.py"))
    modules = {_module_name(p) for p in [*SRC.rglob("*.py"), *paths]}
    graph: dict[str, dict[str, list[str]]] = {}
    for path in paths:
        module = _module_name(path)
        imported = graph.setdefault(module, {})
        for target, name, line, local in _imports(path, (sources or {}).get(path)):
            other = f"{target}.{name}" if f"{target}.{name}" in modules else target
            if other in modules and other != module:
                where = f"{path.relative_to(SRC.parent)}:{line}" + (" (in a function)" if local
                                                                     else "")
                if where not in imported.setdefault(other, []):
                    imported[other].append(where)
    return graph


def _loops(graph: dict[str, dict[str, list[str]]]) -> list[list[str]]:
    """The import loops of ``graph``: its strongly connected components of two or more modules
    (each sorted), sorted."""
    def reachable(start: str) -> set[str]:
        seen, stack = set(), [start]
        while stack:
            node = stack.pop()
            if node not in seen:
                seen.add(node)
                stack += graph.get(node, ())
        return seen

    reach = {module: reachable(module) for module in graph}
    loops = {tuple(sorted(m for m in reach[module] if module in reach.get(m, ())))
             for module in graph}
    return sorted(list(loop) for loop in loops if len(loop) > 1)


def _describe_loops(graph: dict[str, dict[str, list[str]]], loops: list[list[str]]) -> str:
    """Each loop: its files, then every import between them (file:line: importer -> imported)."""
    out = []
    for loop in loops:
        files = [Path(*m.split(".")) for m in loop]
        files = [f / "__init__.py" if (SRC.parent / f).is_dir() else f.with_suffix(".py")
                 for f in files]
        out.append(f"a loop of {len(loop)} files: {', '.join(map(str, files))}")
        out += [f"  {where}: {a} -> {b}" for a in loop for b in sorted(graph[a]) if b in loop
                for where in graph[a][b]]
    return "\n".join(out)


def _unexplained_local_imports(sources: dict[Path, str] | None = None) -> list[str]:
    """'file:line: module names' of every bladelab import inside a function that has no
    reason: a comment containing ``deferred:`` on its line, or alone on the line right above it."""
    bad: dict[str, list[str]] = {}
    for path in sources or sorted(SRC.rglob("*.py")):
        text = (sources or {}).get(path) or path.read_text(encoding="utf-8")
        lines = ["", *text.splitlines()]  # lines[n] is line n
        for target, name, line, local in sorted(_imports(path, text), key=lambda i: i[2]):
            above = lines[line - 1].strip()
            if local and "deferred:" not in lines[line].partition("#")[2] and not (
                    above.startswith("#") and "deferred:" in above):
                where = f"{path.relative_to(SRC.parent)}:{line}: {target}"
                bad.setdefault(where, []).extend([name] if name else [])
    return [f"{where} {', '.join(names)}".rstrip() for where, names in bad.items()]


def _private(target: str, name: str) -> list[str]:
    """The ``_private`` parts of an imported module path and name (``_io`` is public)."""
    return [p for p in [*target.split(".")[1:], name]
            if p.startswith("_") and not p.startswith("__") and p != "_io"]


def _private_uses(path: Path, source: str | None = None) -> list[str]:
    """'file:line: what' for every private bladelab name a file imports or reaches through a
    name it imported from bladelab (``analyses._swing``, ``bladelab.runner._x``)."""
    text = path.read_text(encoding="utf-8") if source is None else source
    where = path.relative_to(SRC.parent)
    bad = {f"{where}:{line}: {target} {name}".rstrip()
           for target, name, line, _ in _imports(path, text) if _private(target, name)}
    tree = ast.parse(text)
    bound = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and (
                node.level or (node.module or "").split(".")[0] == "bladelab"):
            bound |= {a.asname or a.name for a in node.names}
        elif isinstance(node, ast.Import):
            bound |= {a.asname or a.name.split(".")[0] for a in node.names
                      if a.name.split(".")[0] == "bladelab"}
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and _private("", node.attr):
            root = node.value
            while isinstance(root, ast.Attribute):
                root = root.value
            if isinstance(root, ast.Name) and root.id in bound:
                bad.add(f"{where}:{node.lineno}: {ast.unparse(node)}")
    return sorted(bad)


def test_every_wing_is_known():
    wings = {_wing(_module_name(p)) for p in SRC.rglob("*.py")}
    assert wings <= set(ALLOWED), f"add {sorted(wings - set(ALLOWED))} to ALLOWED and the docs"


def test_wings_import_only_what_the_architecture_allows():
    bad = [f"{f}:{line}: {a} imports {b}" for a, b, f, line in _edges()
           if ALLOWED[a] is not None and b not in ALLOWED[a]]
    assert not bad, "imports against docs/architecture.md:\n" + "\n".join(bad)


def test_no_import_cycle_between_wings():
    graph: dict[str, set[str]] = {}
    for a, b, _, _ in _edges():
        graph.setdefault(a, set()).add(b)

    def reaches(start: str, goal: str) -> bool:
        seen, stack = set(), [start]
        while stack:
            node = stack.pop()
            if node == goal:
                return True
            if node not in seen:
                seen.add(node)
                stack += graph.get(node, ())
        return False

    cycles = sorted({tuple(sorted((a, b))) for a in graph for b in graph[a] if reaches(b, a)})
    assert not cycles, f"import cycles between wings: {cycles}"


def test_no_import_loop_between_files():
    graph = _module_graph()
    loops = _loops(graph)
    assert not loops, ("import loops between files (imports inside functions count; break each "
                       "loop, e.g. by moving what both files need into a third):\n"
                       + _describe_loops(graph, loops))


def test_every_import_inside_a_function_says_why():
    bad = _unexplained_local_imports()
    assert not bad, (
        "bladelab imports inside functions without a reason: move each to the top of its file, "
        "or, where it keeps the CLI's start-up fast (or breaks a loop), say so in a comment "
        "containing 'deferred:' on its line or the line above (e.g. "
        "'# deferred: keeps bladelab --help fast'):\n" + "\n".join(bad))


def test_no_private_name_is_imported_from_another_module():
    bad = []
    for path in sorted(SRC.rglob("*.py")):
        for target, name, line, _ in _imports(path):
            if _private(target, name):
                bad.append(f"{path.relative_to(SRC.parent)}:{line}: {target} {name}")
    assert not bad, "private names imported across modules:\n" + "\n".join(bad)


def test_the_cli_uses_no_private_name_of_the_library():
    files = sorted((SRC / "cli").rglob("*.py"))
    assert len(files) > 1, "the CLI is not where this test looks"
    bad = [use for path in files for use in _private_uses(path)]
    assert not bad, ("the CLI uses private names (give what it needs a public name and a "
                     "docstring in the library):\n" + "\n".join(bad))


@pytest.mark.parametrize("source, wing", [
    ("from bladelab.design.study import run_design\n", "design"),
    ("def f():\n    from bladelab.cli import main\n", "cli"),
])
def test_the_checks_see_function_local_and_top_level_imports(source, wing):
    found = [(a, b) for a, b, _, _ in _edges({SRC / "runner" / "probe.py": source})]
    assert found == [("runner", wing)]
    assert wing not in ALLOWED["runner"]


def test_the_loop_check_sees_a_loop_through_a_function_local_import():
    a, b, c = (SRC / "runner" / f"probe_{x}.py" for x in "abc")
    graph = _module_graph({
        a: "from bladelab.runner import probe_b\n",
        b: "def f():\n    from bladelab.runner.probe_a import g\n",
        c: "from bladelab.runner.probe_a import g\n",  # imports into the loop: not part of it
    })
    loops = _loops(graph)
    assert loops == [["bladelab.runner.probe_a", "bladelab.runner.probe_b"]]
    text = _describe_loops(graph, loops)
    assert "bladelab/runner/probe_a.py:1: bladelab.runner.probe_a -> bladelab.runner.probe_b" in text
    assert "bladelab/runner/probe_b.py:2 (in a function)" in text


@pytest.mark.parametrize("source, unexplained", [
    ("def f():\n    from bladelab.sim import prepare, simulate\n", ["2: bladelab.sim prepare, simulate"]),
    ("class A:\n    def f(self):\n        import bladelab.sim\n", ["3: bladelab.sim"]),
    ("def f():\n    from bladelab.sim import simulate  # deferred: numba at start-up\n", []),
    ("def f():\n    # deferred: numba at start-up\n    from bladelab.sim import simulate\n", []),
    # one reason per import: the comment above the first does not cover the second
    ("def f():\n    # deferred: numba\n    from bladelab.blade import load_blade\n"
     "    from bladelab.sim import simulate\n", ["4: bladelab.sim simulate"]),
    ("from bladelab.sim import simulate\n", []),  # at the top
    ("def f():\n    import numpy\n", []),  # not bladelab
])
def test_the_reason_check_sees_an_unexplained_local_import(source, unexplained):
    found = _unexplained_local_imports({SRC / "runner" / "probe.py": source})
    assert found == [f"bladelab/runner/probe.py:{u}" for u in unexplained]


@pytest.mark.parametrize("source, private", [
    ("from bladelab.runner.model import _build\n", 1),
    ("def f():\n    from bladelab.runner import _model\n", 1),
    ("from bladelab.runner import analyses\nx = analyses._swing(1)\n", 1),
    ("import bladelab.runner.analyses as a\ndef f():\n    return a._swing\n", 1),
    ("import bladelab.runner\nx = bladelab.runner._build\n", 1),
    ("from bladelab._io import read_json\nfrom bladelab.runner import analyses\n"
     "x = analyses.swing_contacts\ny = {}._z\n", 0),
])
def test_the_private_check_sees_imports_and_uses_through_imported_names(source, private):
    assert len(_private_uses(SRC / "cli" / "probe.py", source)) == private


_WRITERS = {"atomic_path", "atomic_open", "write_json"}


def _cli_writers(sources: dict[Path, str] | None = None) -> list[str]:
    """file:line of every file writer of ``bladelab._io`` that a CLI module imports."""
    found = []
    for path in sources or sorted((SRC / "cli").rglob("*.py")):
        for target, name, line, _ in _imports(path, (sources or {}).get(path)):
            if target == "bladelab._io" and name in _WRITERS:
                found.append(f"{path.relative_to(SRC.parent)}:{line}: {name}")
    return found


def test_the_cli_writes_no_file_format_itself():
    """A command's output files are written by the library function that defines their format
    (docs/architecture.md), so no CLI module imports the atomic writers."""
    assert (SRC / "cli").is_dir()
    bad = _cli_writers()
    assert not bad, "the CLI writes files itself; move the writer into the library:\n" + "\n".join(bad)


def test_the_cli_writer_check_flags_a_writer():
    path = SRC / "cli" / "example.py"
    assert _cli_writers({path: "from bladelab._io import atomic_open, read_json\n"}) == [
        "bladelab/cli/example.py:1: atomic_open"]
    assert _cli_writers({path: "from bladelab._io import read_json\n"}) == []

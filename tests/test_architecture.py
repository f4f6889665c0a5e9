"""The house rules of docs/architecture.md: wings import one way, no cycles, no private names
imported across modules. Every import counts, function-local ones included."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "bladelab"

FOUNDATION = {"bladelab", "units", "constants", "errors", "_io", "parameters", "contact",
              "executors", "numba_cache"}
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


def _imports(path: Path, source: str | None = None) -> list[tuple[str, str, int]]:
    """(imported module, imported name or '', line) of every bladelab import in a file (or in
    ``source`` as if it were that file)."""
    module = _module_name(path)
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    out = []
    text = path.read_text(encoding="utf-8") if source is None else source
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.split(".")[0] == "bladelab":
                out += [(target, alias.name, node.lineno) for alias in node.names]
        elif isinstance(node, ast.Import):
            out += [(a.name, "", node.lineno) for a in node.names
                    if a.name.split(".")[0] == "bladelab"]
    return out


def _edges(sources: dict[Path, str] | None = None) -> list[tuple[str, str, str, int]]:
    """(importing wing, imported wing, file, line) for every cross-wing import of the package
    (or of ``sources``: path -> text)."""
    edges = []
    for path in sources or sorted(SRC.rglob("*.py")):
        wing = _wing(_module_name(path))
        for target, name, line in _imports(path, (sources or {}).get(path)):
            # `from bladelab import units` imports the module bladelab.units
            is_module = (SRC / f"{name}.py").is_file() or (SRC / name).is_dir()
            other = _wing(f"{target}.{name}" if target == "bladelab" and is_module else target)
            if other != wing:
                edges.append((wing, other, str(path.relative_to(SRC.parent)), line))
    return edges


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


def test_no_private_name_is_imported_from_another_module():
    bad = []
    for path in sorted(SRC.rglob("*.py")):
        for target, name, line in _imports(path):
            private = [p for p in [*target.split(".")[1:], name]
                       if p.startswith("_") and not p.startswith("__") and p != "_io"]
            if private:
                bad.append(f"{path.relative_to(SRC.parent)}:{line}: {target} {name}")
    assert not bad, "private names imported across modules:\n" + "\n".join(bad)


@pytest.mark.parametrize("source, wing", [
    ("from bladelab.design.study import run_design\n", "design"),
    ("def f():\n    from bladelab.cli import main\n", "cli"),
])
def test_the_checks_see_function_local_and_top_level_imports(source, wing):
    found = [(a, b) for a, b, _, _ in _edges({SRC / "runner" / "probe.py": source})]
    assert found == [("runner", wing)]
    assert wing not in ALLOWED["runner"]

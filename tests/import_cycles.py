"""The module import graph of a package and the import cycles in it.

Every import counts wherever it stands: at the top, inside a function, under `TYPE_CHECKING`,
relative, or as a string passed to `__import__` / `importlib.import_module`
(tests/import_layers.py finds those). `from a.b import c` depends on `a.b` and, when `c` is a
module, on `a.b.c` too. Importing a submodule runs its parent packages' `__init__`, which is
not counted as an edge (every package `__init__` here holds a docstring only).
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

from tests.import_layers import imports_of

__all__ = ["cycles", "import_graph", "module_name"]

Graph = dict[str, set[str]]


def module_name(root: Path, path: Path) -> str:
    """emulator/flight/fleet.py -> emulator.flight.fleet; emulator/__init__.py -> emulator."""
    parts = list(path.relative_to(root).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _named_modules(source: str, module: str, is_package: bool) -> Iterator[str]:
    """Every module name an import of `source` (module `module`) may refer to."""
    for _, name in imports_of(source):
        yield name
    package = module if is_package else module.rpartition(".")[0]
    for node in ast.walk(ast.parse(source)):
        if not isinstance(node, ast.ImportFrom):
            continue
        if node.level:
            base = package.split(".")
            base = base[: len(base) - (node.level - 1)]
            stem = ".".join(base + ([node.module] if node.module else []))
        else:
            stem = node.module or ""
        yield stem
        for alias in node.names:
            yield f"{stem}.{alias.name}"


def import_graph(root: Path, package: str) -> Graph:
    """module -> the modules of `package` (under `root`) it imports."""
    paths = {module_name(root, p): p for p in sorted((root / package).rglob("*.py"))}
    graph: Graph = {}
    for module, path in paths.items():
        source = path.read_text(encoding="utf-8")
        names = _named_modules(source, module, path.name == "__init__.py")
        graph[module] = {n for n in names if n in paths and n != module}
    return graph


def cycles(graph: Graph) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(found)

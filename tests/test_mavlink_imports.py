"""No import circle inside `emulator/mavlink/`: every import counts, wherever it stands
(at the top, inside a function, under TYPE_CHECKING)."""

from __future__ import annotations

import ast
from pathlib import Path

from tests.cli_fixtures import ROOT

PACKAGE = "emulator.mavlink"


def _imported(source: str) -> set[str]:
    """Every module an absolute import names (`from pkg import mod` names pkg.mod too)."""
    found = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            found |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
            found.add(node.module)
            found |= {f"{node.module}.{alias.name}" for alias in node.names}
    return found


def _graph(root: Path) -> dict[str, set[str]]:
    modules = {f"{PACKAGE}.{p.stem}": p for p in (root / "emulator" / "mavlink").glob("*.py")
               if p.stem != "__init__"}
    graph: dict[str, set[str]] = {}
    for name, path in modules.items():
        imported = _imported(path.read_text(encoding="utf-8"))
        graph[name] = {m for m in imported if m in modules and m != name}
    return graph


def _cycle(graph: dict[str, set[str]]) -> list[str] | None:
    state: dict[str, int] = {}  # 1: on the path, 2: done
    path: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        path.append(node)
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                return [*path[path.index(nxt):], nxt]
            if nxt not in state and (found := visit(nxt)):
                return found
        path.pop()
        state[node] = 2
        return None

    for node in sorted(graph):
        if node not in state and (found := visit(node)):
            return found
    return None


def test_the_mavlink_modules_import_one_way() -> None:
    graph = _graph(ROOT)
    assert f"{PACKAGE}.vehicle_link" in graph and f"{PACKAGE}.protocol" in graph
    cycle = _cycle(graph)
    assert cycle is None, " -> ".join(cycle or [])


def test_a_planted_circle_is_found(tmp_path: Path) -> None:
    package = tmp_path / "emulator" / "mavlink"
    package.mkdir(parents=True)
    (package / "a.py").write_text("from emulator.mavlink.b import B\n")
    (package / "b.py").write_text("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
                                  "    from emulator.mavlink.a import A\n")
    (package / "c.py").write_text("from emulator.mavlink import a\nimport numpy\n")
    assert _cycle(_graph(tmp_path)) == [f"{PACKAGE}.a", f"{PACKAGE}.b", f"{PACKAGE}.a"]
    (package / "b.py").write_text("def f():\n    from emulator.mavlink import c\n")
    assert _cycle(_graph(tmp_path)) == [f"{PACKAGE}.a", f"{PACKAGE}.b", f"{PACKAGE}.c",
                                        f"{PACKAGE}.a"]

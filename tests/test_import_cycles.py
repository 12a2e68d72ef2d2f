"""No import circle inside the emulator (tests/import_cycles.py), counting every import
(TYPE_CHECKING, in functions, relative); and the scanner finds planted circles."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.cli_fixtures import ROOT
from tests.import_cycles import cycles, import_graph, module_name

# The packages that must hold no import circle (the whole emulator, flight/ and mavlink/
# included).
CYCLE_FREE = ("emulator",)


def _inside(module: str, package: str) -> bool:
    return module == package or module.startswith(package + ".")


@pytest.mark.parametrize("package", CYCLE_FREE)
def test_no_import_cycle_inside(package: str) -> None:
    graph = import_graph(ROOT, "emulator")
    assert any(_inside(m, package) for m in graph), f"no module of {package} found"
    found = [c for c in cycles(graph) if any(_inside(m, package) for m in c)]
    assert not found, "import circles: " + "; ".join(" <-> ".join(c) for c in found)


def test_the_emulator_graph_sees_the_flight_modules_and_their_imports() -> None:
    graph = import_graph(ROOT, "emulator")
    assert "emulator.flight.dynamics" in graph["emulator.flight.fleet"]
    # `from emulator.flight import dynamics as dy` names the submodule
    assert "emulator.flight.dynamics" in graph["emulator.flight.sequences"]


def _plant(root: Path, files: dict[str, str]) -> None:
    for name, source in files.items():
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(source)


def test_planted_circles_are_found_however_they_import(tmp_path: Path) -> None:
    _plant(tmp_path, {
        "pkg/__init__.py": "",
        "pkg/sub/__init__.py": "",
        # a TYPE_CHECKING import closes a circle
        "pkg/sub/a.py": "from pkg.sub.b import B\n",
        "pkg/sub/b.py": ("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
                         "    from pkg.sub.a import A\n"),
        # a function-level `from package import module` and a relative import
        "pkg/sub/c.py": "def f():\n    from pkg.sub import d\n",
        "pkg/sub/d.py": "from . import c\n",
        # a dynamic import
        "pkg/e.py": "import importlib\nimportlib.import_module('pkg.f')\n",
        "pkg/f.py": "import pkg.e\n",
        # one way only: no circle
        "pkg/g.py": "from pkg.sub.a import A\nimport pkg.sub.b\nimport json\n",
    })
    graph = import_graph(tmp_path, "pkg")
    assert cycles(graph) == [["pkg.e", "pkg.f"], ["pkg.sub.a", "pkg.sub.b"],
                             ["pkg.sub.c", "pkg.sub.d"]]
    assert graph["pkg.g"] == {"pkg.sub.a", "pkg.sub.b"}
    assert module_name(tmp_path, tmp_path / "pkg" / "sub" / "__init__.py") == "pkg.sub"

"""The packages import one way only (tests/import_layers.py), with no exemption; the scanner
finds a planted violation; and loading the agent side loads nothing of the benchmark or the
emulator, so no validator, hidden task data or ground truth can reach an agent."""

from __future__ import annotations

import ast
import json
import subprocess
import sys
from pathlib import Path

import pytest

from tests.cli_fixtures import ROOT
from tests.import_layers import LAYERS, TIERS, crossings, tier_crossings

AGENT_SIDE = ("mavlink_gateway", "agent_contract", "llm_tools")


def test_every_package_imports_only_the_layers_below_it() -> None:
    assert set(LAYERS) <= {p.name for p in ROOT.iterdir() if (p / "__init__.py").exists()}
    found = crossings(ROOT)
    assert not found, "\n".join(map(str, found))


def test_the_benchmark_parts_import_only_their_own_tier_or_earlier_ones() -> None:
    assert {p.name.removesuffix(".py") for p in (ROOT / "benchmark").iterdir()
            if p.suffix == ".py" or (p / "__init__.py").exists()} <= set().union(
                *TIERS["benchmark"])
    found = tier_crossings(ROOT)
    assert not found, "\n".join(map(str, found))


def test_a_planted_tier_violation_is_found(tmp_path: Path) -> None:
    for part in ("scoring", "running", "authoring"):
        (tmp_path / "benchmark" / part).mkdir(parents=True)
        (tmp_path / "benchmark" / part / "__init__.py").write_text("")
    (tmp_path / "benchmark" / "scoring" / "up.py").write_text(
        "from benchmark.authoring.suite import Draw\n")
    (tmp_path / "benchmark" / "authoring" / "up.py").write_text(
        "import benchmark.scoring.metrics\ndef f():\n    from benchmark import running\n")
    (tmp_path / "benchmark" / "running" / "fine.py").write_text(
        "from benchmark.authoring import suite\nfrom benchmark.running import episode\n")
    (tmp_path / "benchmark" / "stray.py").write_text("")
    found = sorted((c.path, c.line, c.imported) for c in tier_crossings(tmp_path))
    assert found == [("benchmark/authoring/up.py", 3, "benchmark.running"),
                     ("benchmark/scoring/up.py", 1, "benchmark.authoring.suite"),
                     ("benchmark/stray.py", 0, "benchmark.stray (in no tier)")]


def test_the_layers_form_no_cycle() -> None:
    order: list[str] = []
    while len(order) < len(LAYERS):
        ready = [p for p, allowed in LAYERS.items() if p not in order and allowed <= set(order)]
        assert ready, f"a cycle among {set(LAYERS) - set(order)}"
        order.extend(sorted(ready))
    assert order[-1] == "mavswarm"


def test_a_planted_violation_is_found(tmp_path: Path) -> None:
    for package in LAYERS:
        (tmp_path / package).mkdir()
        (tmp_path / package / "__init__.py").write_text("")
    (tmp_path / "mavlink_gateway" / "up.py").write_text(
        "import json\nfrom emulator.geo import GeoOrigin\n")
    (tmp_path / "llm_tools" / "sneaky.py").write_text(
        "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
        "    import benchmark.running.episode\n"
        "def f():\n    from benchmark.scoring.validators import evaluate\n"
        "    return __import__('emulator.truth')\n")
    (tmp_path / "emulator" / "fine.py").write_text("from . import geo\nimport numpy\n")
    (tmp_path / "benchmark" / "fine.py").write_text("import llm_tools.registry\n")
    found = sorted((c.path, c.line, c.imported) for c in crossings(tmp_path))
    assert found == [("llm_tools/sneaky.py", 3, "benchmark.running.episode"),
                     ("llm_tools/sneaky.py", 5, "benchmark.scoring.validators"),
                     ("llm_tools/sneaky.py", 6, "emulator.truth"),
                     ("mavlink_gateway/up.py", 2, "emulator.geo")]


@pytest.mark.slow
def test_loading_the_agent_side_loads_no_benchmark_or_emulator_module() -> None:
    code = ("import json, sys\n"
            f"for m in {list(AGENT_SIDE)!r}: __import__(m)\n"
            "import llm_tools.agents, llm_tools.mcp_server, llm_tools.registry\n"
            "print(json.dumps(sorted(sys.modules)))\n")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                         text=True, check=True, timeout=60)
    loaded = json.loads(out.stdout)
    assert "agent_contract.tools" in loaded and "llm_tools.mcp_server" in loaded
    below = [m for m in loaded if m.split(".")[0] in ("benchmark", "emulator", "mavswarm")]
    assert not below, below


def test_every_package_says_what_it_is_and_names_its_public_surface() -> None:
    lacking = []
    for package in LAYERS:
        for init in sorted((ROOT / package).rglob("__init__.py")):
            if "node_modules" in init.parts:
                continue
            tree = ast.parse(init.read_text(encoding="utf-8"))
            doc = ast.get_docstring(tree) or ""
            names = {t.id for n in tree.body if isinstance(n, ast.Assign | ast.AnnAssign)
                     for t in (n.targets if isinstance(n, ast.Assign) else [n.target])
                     if isinstance(t, ast.Name)}
            if len(doc.split()) < 6 or "__all__" not in names:
                lacking.append(str(init.relative_to(ROOT)))
    assert not lacking, lacking

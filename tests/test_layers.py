"""The layers import one way only (tests/import_layers.py), with no exemption; the scanner
finds planted violations, relative and `from a import b` ones included; and loading the agent
side (the agent contract, the LLM tools and the LLM, baseline and team agents) loads nothing of
the benchmark or the emulator, so no validator, hidden task data or ground truth can reach an
agent."""

from __future__ import annotations

import ast
import json
import subprocess
import sys
from pathlib import Path

import pytest

from tests.cli_fixtures import ROOT
from tests.import_layers import LAYERS, TIERS, crossings, layer_of, tier_crossings

AGENT_SIDE = ("mavlink_gateway", "agent_contract", "llm_tools", "swarm_agents.llm",
              "swarm_agents.baselines", "swarm_agents.teams")


def _exists(root: Path, layer: str) -> bool:
    path = root.joinpath(*layer.split("."))
    return (path / "__init__.py").is_file() or path.with_suffix(".py").is_file()


def test_every_layer_imports_only_the_layers_below_it() -> None:
    missing = [layer for layer in LAYERS if not _exists(ROOT, layer)]
    assert not missing, f"layers that are no module of the repository: {missing}"
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


def test_nothing_that_knows_hidden_parts_is_below_the_agent_side() -> None:
    for agent_side in AGENT_SIDE:
        below: set[str] = set()
        todo = [agent_side]
        while todo:
            for layer in LAYERS[todo.pop()] - below:
                below.add(layer)
                todo.append(layer)
        hidden = below & {"emulator", "benchmark", "benchmark.scoring.validators",
                          "benchmark.authoring.session_file", "swarm_agents.oracle",
                          "swarm_agents.plugins"}
        assert not hidden, (agent_side, hidden)


def test_a_module_belongs_to_the_longest_layer_it_starts_with() -> None:
    assert layer_of("swarm_agents.llm.react") == "swarm_agents.llm"
    assert layer_of("swarm_agents.oracle") == "swarm_agents.oracle"
    assert layer_of("swarm_agents") == "swarm_agents"
    assert layer_of("benchmark.scoring.validators.tree") == "benchmark.scoring.validators"
    assert layer_of("benchmark.running.orchestrator") == "benchmark"
    assert layer_of("numpy.linalg") is None


def _plant(root: Path, files: dict[str, str]) -> None:
    for layer in LAYERS:
        package = root / layer.split(".")[0]
        package.mkdir(exist_ok=True)
        (package / "__init__.py").write_text("")
    for name, source in files.items():
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(source)


def test_planted_violations_are_found(tmp_path: Path) -> None:
    _plant(tmp_path, {
        "mavlink_gateway/up.py": "import json\nfrom emulator.geo import GeoOrigin\n",
        "llm_tools/sneaky.py": (
            "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
            "    import benchmark.running.episode\n"
            "def f():\n    from benchmark.scoring.validators import evaluate\n"
            "    return __import__('emulator.truth')\n"),
        "emulator/fine.py": "from . import geo\nimport numpy\n",
        "benchmark/fine.py": "import llm_tools.registry\nfrom swarm_agents import oracle\n",
        "swarm_agents/llm/__init__.py": "",
        "swarm_agents/llm/peek.py": ("from .. import oracle\n"
                                     "from ..oracle.agent import OracleAgent\n"
                                     "from swarm_agents.teams import DroneView\n"),
        "swarm_agents/oracle/__init__.py": "",
        "swarm_agents/oracle/fine.py": ("from benchmark.scoring import validators\n"
                                  "from benchmark.authoring.session_file import Session\n"
                                  "from . import planner\nfrom ..oracle import agent\n"),
        "swarm_agents/oracle/up.py": ("from benchmark.running import orchestrator\n"
                                "from benchmark.scoring import validators\n"),
        "swarm_agents/teams.py": "from swarm_agents.llm import react\n",
        "benchmark/scoring/validators/__init__.py": "",
        "benchmark/scoring/validators/up.py": "from benchmark.authoring.generate import proven\n",
    })
    found = sorted((c.path, c.line, c.layer, c.imported) for c in crossings(tmp_path))
    assert found == sorted([
        ("swarm_agents/llm/peek.py", 1, "swarm_agents.llm", "swarm_agents.oracle"),
        ("swarm_agents/llm/peek.py", 2, "swarm_agents.llm",
         "swarm_agents.oracle.agent.OracleAgent"),
        ("swarm_agents/llm/peek.py", 3, "swarm_agents.llm", "swarm_agents.teams.DroneView"),
        ("swarm_agents/oracle/up.py", 1, "swarm_agents.oracle", "benchmark.running.orchestrator"),
        ("swarm_agents/teams.py", 1, "swarm_agents.teams", "swarm_agents.llm.react"),
        ("benchmark/scoring/validators/up.py", 1, "benchmark.scoring.validators",
         "benchmark.authoring.generate.proven"),
        ("llm_tools/sneaky.py", 3, "llm_tools", "benchmark.running.episode"),
        ("llm_tools/sneaky.py", 5, "llm_tools", "benchmark.scoring.validators.evaluate"),
        ("llm_tools/sneaky.py", 6, "llm_tools", "emulator.truth"),
        ("mavlink_gateway/up.py", 2, "mavlink_gateway", "emulator.geo.GeoOrigin")])


@pytest.mark.slow
def test_loading_the_agent_side_loads_no_benchmark_or_emulator_module() -> None:
    code = ("import json, sys\n"
            f"for m in {list(AGENT_SIDE)!r}: __import__(m)\n"
            "import swarm_agents.llm.react, swarm_agents.llm.workflow, swarm_agents.llm.scripted\n"
            "import llm_tools.mcp_server, llm_tools.registry\n"
            "print(json.dumps(sorted(sys.modules)))\n")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                         text=True, check=True, timeout=60)
    loaded = json.loads(out.stdout)
    assert {"agent_contract.tools", "llm_tools.mcp_server", "swarm_agents.llm.openai_model",
            "swarm_agents.teams.per_drone", "swarm_agents.baselines.noop"} <= set(loaded)
    below = [m for m in loaded if m.split(".")[0] in ("benchmark", "emulator", "mavswarm")
             or m.startswith(("swarm_agents.oracle", "swarm_agents.plugins"))]
    assert not below, below


def test_every_package_says_what_it_is_and_names_its_public_surface() -> None:
    lacking = []
    for package in sorted({layer.split(".")[0] for layer in LAYERS}):
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

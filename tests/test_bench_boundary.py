"""Agent-side code never reaches validators, hidden task data or ground truth.

Agent side: the agent protocol and tools, the gateway, and llm_tools (registry, adapters,
agents, MCP server). The REST server in `llm_tools.rest` and the launcher `llm_tools.serve`
are the platform itself, serving every role (admins read checks through it) and starting
swarms; their agent routes are tested for leaks instead (tests/test_llm_rest.py).
"""

from __future__ import annotations

import ast
import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
AGENT_SIDE = ("benchmark.agents", "mavlink_gateway", "llm_tools")
HIDDEN = ("benchmark.validators", "benchmark.templates", "benchmark.session_file",
          "benchmark.oracle", "benchmark.generate", "benchmark.episode",
          "benchmark.orchestrator", "benchmark.suite", "benchmark.importer",
          "benchmark.scenarios", "emulator.truth", "emulator.services")


def _is_hidden(module: str) -> bool:
    return any(module == h or module.startswith(h + ".") for h in HIDDEN)


PLATFORM = (ROOT / "llm_tools" / "rest", ROOT / "llm_tools" / "serve.py")


def _agent_side_files() -> list[Path]:
    files: list[Path] = []
    for package in AGENT_SIDE:
        files.extend(sorted(p for p in (ROOT / package.replace(".", "/")).rglob("*.py")
                            if p not in PLATFORM and not set(PLATFORM) & set(p.parents)))
    return files


def test_agent_side_sources_import_nothing_hidden() -> None:
    files = _agent_side_files()
    assert len(files) >= 10, files
    offenders = []
    for path in files:
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        for node in ast.walk(tree):
            names: list[str] = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module:
                names = [node.module] + [f"{node.module}.{a.name}" for a in node.names]
            elif isinstance(node, ast.Call) and getattr(node.func, "id", "") == "__import__":
                names = [a.value for a in node.args if isinstance(a, ast.Constant)]
            offenders += [f"{path.relative_to(ROOT)}:{node.lineno}: {n}"
                          for n in names if _is_hidden(n)]
    assert not offenders, offenders


def test_importing_the_agent_side_loads_nothing_hidden() -> None:
    code = (
        "import json, sys\n"
        f"for m in {list(AGENT_SIDE)!r}: __import__(m)\n"
        "import benchmark.agents.tools, benchmark.agents.noop, llm_tools.agents\n"
        "import llm_tools.mcp_server\n"
        "print(json.dumps(sorted(sys.modules)))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                         text=True, check=True, timeout=60)
    loaded = json.loads(out.stdout)
    assert "benchmark.agents.tools" in loaded
    hidden = [m for m in loaded if _is_hidden(m)]
    assert not hidden, hidden


def test_the_check_detects_a_hidden_import(tmp_path: Path) -> None:
    """The scanner would catch an agent-side file importing a validator."""
    sample = "from benchmark.validators import evaluate\nimport emulator.truth\n"
    tree = ast.parse(sample)
    found = [n.module if isinstance(n, ast.ImportFrom) else n.names[0].name
             for n in ast.walk(tree) if isinstance(n, ast.Import | ast.ImportFrom)]
    assert all(_is_hidden(m) for m in found)

"""The package layers of mavswarm and a scanner that finds every import crossing them.

Each package may import only the packages listed for it: every package the MAVLink vocabulary
(`mavlink_vocabulary`, which imports nothing of ours), the emulator and the MAVLink gateway
nothing else of ours, the agent contract the gateway, the LLM tools the gateway and the contract,
the MQTT bus the emulator and the agent side (it reads what vehicles report, never ground
truth), the benchmark all of them, the web console all of those, and the composition root
(`mavswarm`) whatever it assembles. Every import counts wherever it stands: at the top, inside
a function, under `TYPE_CHECKING`, or as a string passed to `__import__` /
`importlib.import_module`.
"""

from __future__ import annotations

import ast
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path

__all__ = ["LAYERS", "Crossing", "crossings", "imports_of"]

_BOTTOM = frozenset({"mavlink_vocabulary"})
LAYERS: dict[str, frozenset[str]] = {
    "mavlink_vocabulary": frozenset(),
    "emulator": _BOTTOM,
    "mavlink_gateway": _BOTTOM,
    "agent_contract": _BOTTOM | {"mavlink_gateway"},
    "llm_tools": _BOTTOM | {"mavlink_gateway", "agent_contract"},
    "mqtt_bus": _BOTTOM | {"emulator", "mavlink_gateway", "agent_contract", "llm_tools"},
    "benchmark": _BOTTOM | {"emulator", "mavlink_gateway", "agent_contract", "llm_tools",
                            "mqtt_bus"},
    "console": _BOTTOM | {"emulator", "mavlink_gateway", "agent_contract", "llm_tools",
                          "mqtt_bus", "benchmark"},
    "mavswarm": _BOTTOM | {"emulator", "mavlink_gateway", "agent_contract", "llm_tools",
                           "mqtt_bus", "benchmark", "console"},
}


@dataclass(frozen=True)
class Crossing:
    """One import from `package` of `imported` that its layer does not allow."""

    path: str
    line: int
    package: str
    imported: str

    def __str__(self) -> str:
        return f"{self.path}:{self.line}: {self.package} imports {self.imported}"


def imports_of(source: str) -> Iterator[tuple[int, str]]:
    """(line, module) for every absolute import in a module's source."""
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name
        elif isinstance(node, ast.ImportFrom):
            if node.level:  # relative: stays inside its own package
                continue
            if node.module:
                yield node.lineno, node.module
        elif isinstance(node, ast.Call):
            name = getattr(node.func, "id", None) or getattr(node.func, "attr", None)
            if name in ("__import__", "import_module") and node.args:
                first = node.args[0]
                if isinstance(first, ast.Constant) and isinstance(first.value, str):
                    yield node.lineno, first.value


def crossings(root: Path, layers: Mapping[str, frozenset[str]] = LAYERS) -> list[Crossing]:
    """Every import under `root` from one of `layers`' packages into another package of
    `layers` that it may not import."""
    found = []
    for package, allowed in layers.items():
        for path in sorted((root / package).rglob("*.py")):
            for line, module in imports_of(path.read_text(encoding="utf-8")):
                top = module.split(".")[0]
                if top in layers and top != package and top not in allowed:
                    found.append(Crossing(str(path.relative_to(root)), line, package, module))
    return found

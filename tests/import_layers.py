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

__all__ = ["LAYERS", "TIERS", "Crossing", "crossings", "imports_of", "tier_crossings"]

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

# Inside a package, its parts in tiers: a part (a subpackage or a module) imports parts of its
# own tier or of the tiers before it, never a later one. The benchmark: scoring knows nothing of
# tasks being written, authoring nothing of runs, runs (and the server that runs sessions live)
# nothing of reports; `cli` assembles them.
TIERS: dict[str, tuple[frozenset[str], ...]] = {
    "benchmark": (
        frozenset({"scoring"}),
        frozenset({"authoring"}),
        frozenset({"oracle", "agents", "agent_plugins"}),
        frozenset({"running", "server"}),
        frozenset({"reporting"}),
        frozenset({"cli", "__init__"}),
    ),
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


def _part(module: str, package: str) -> str | None:
    parts = module.split(".")
    return parts[1] if parts[0] == package and len(parts) > 1 else None


def tier_crossings(root: Path, tiers: Mapping[str, tuple[frozenset[str], ...]] = TIERS
                   ) -> list[Crossing]:
    """Every import inside one of `tiers`' packages from a part into a part of a later tier
    (`from package import part` counts as importing that part)."""
    found = []
    for package, order in tiers.items():
        rank = {part: k for k, group in enumerate(order) for part in group}
        for path in sorted((root / package).rglob("*.py")):
            relative = path.relative_to(root / package)
            own = relative.parts[0].removesuffix(".py")
            if own not in rank:
                found.append(Crossing(str(path.relative_to(root)), 0, package,
                                      f"{package}.{own} (in no tier)"))
                continue
            tree = ast.parse(path.read_text(encoding="utf-8"))
            for line, module in imports_of(path.read_text(encoding="utf-8")):
                part = _part(module, package)
                if part is not None and rank.get(part, -1) > rank[own]:
                    found.append(Crossing(str(path.relative_to(root)), line, package, module))
            for node in ast.walk(tree):
                if isinstance(node, ast.ImportFrom) and node.module == package and not node.level:
                    for alias in node.names:
                        if rank.get(alias.name, -1) > rank[own]:
                            found.append(Crossing(str(path.relative_to(root)), node.lineno,
                                                  package, f"{package}.{alias.name}"))
    return found

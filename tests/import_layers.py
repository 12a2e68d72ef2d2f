"""The layers of mavswarm and a scanner that finds every import crossing them.

A layer is a package, or a subpackage or module named apart (`swarm_agents.llm`,
`benchmark.scoring.validators`): a module belongs to the longest layer its dotted name starts
with, and may import only its own layer and those listed for it. The MAVLink vocabulary
(`mavlink_vocabulary`) imports nothing of ours and every layer may import it; the emulator and
the MAVLink gateway import nothing else of ours; the agent contract imports the gateway, the LLM
tools the gateway and the contract. The agent side of `swarm_agents` (the LLM agents and their
model seam, the baselines, the per-drone teams) stands on those alone, so loading an agent loads
no validator, hidden task data or ground truth. The benchmark's session files and checks
(`benchmark.authoring.session_file`, `benchmark.authoring.task_faults`,
`benchmark.scoring.validators`) stand on the emulator and the agent side; the oracle
(`swarm_agents.oracle`) on them, the agent loader (`swarm_agents.plugins`) on every agent; the
MQTT bus on the emulator and the agent side (it reads what vehicles report, never ground truth);
the rest of the benchmark on all of them, the web console on all of those, and the composition
root (`mavswarm`) on whatever it assembles. `swarm_agents` itself (its `__init__`) imports
nothing.

Every import counts wherever it stands: at the top, inside a function, under `TYPE_CHECKING`,
relative, or as a string passed to `__import__` / `importlib.import_module`; `from a import b`
imports `a.b` where that is a layer of its own.
"""

from __future__ import annotations

import ast
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path

__all__ = ["LAYERS", "TIERS", "Crossing", "crossings", "imports_of", "layer_of",
           "tier_crossings"]

_BOTTOM = frozenset({"mavlink_vocabulary"})
_AGENT_SIDE = _BOTTOM | {"mavlink_gateway", "agent_contract", "llm_tools"}
_SESSIONS_AND_CHECKS = frozenset({"benchmark.authoring.session_file",
                                  "benchmark.authoring.task_faults",
                                  "benchmark.authoring.plan_steps",
                                  "benchmark.authoring.session_model",
                                  "benchmark.scoring.validators"})
_AGENTS = frozenset({"swarm_agents", "swarm_agents.llm", "swarm_agents.baselines",
                     "swarm_agents.teams", "swarm_agents.oracle", "swarm_agents.plugins"})
_BELOW_BENCHMARK = _AGENT_SIDE | {"emulator", "mqtt_bus"} | _SESSIONS_AND_CHECKS | _AGENTS
LAYERS: dict[str, frozenset[str]] = {
    "mavlink_vocabulary": frozenset(),
    "emulator": _BOTTOM,
    "mavlink_gateway": _BOTTOM,
    "agent_contract": _BOTTOM | {"mavlink_gateway"},
    "llm_tools": _AGENT_SIDE - {"llm_tools"},
    "swarm_agents": frozenset(),
    "swarm_agents.baselines": _BOTTOM | {"agent_contract"},
    "swarm_agents.teams": _BOTTOM | {"mavlink_gateway", "agent_contract"},
    "swarm_agents.llm": _AGENT_SIDE,
    "mqtt_bus": _AGENT_SIDE | {"emulator"},
    "benchmark.authoring.task_faults": _AGENT_SIDE | {"emulator"},
    "benchmark.scoring.validators": _AGENT_SIDE | {"emulator"},
    "benchmark.authoring.plan_steps": _BOTTOM,
    "benchmark.authoring.session_model": _AGENT_SIDE | {"emulator",
                                                        "benchmark.scoring.validators"},
    "benchmark.authoring.session_file": _AGENT_SIDE | {"emulator",
                                                       "benchmark.authoring.task_faults",
                                                       "benchmark.authoring.plan_steps",
                                                       "benchmark.authoring.session_model",
                                                       "benchmark.scoring.validators"},
    "swarm_agents.oracle": _AGENT_SIDE | {"emulator"} | _SESSIONS_AND_CHECKS,
    "swarm_agents.plugins": (_AGENT_SIDE | _SESSIONS_AND_CHECKS
                             | (_AGENTS - {"swarm_agents.plugins"})),
    "benchmark": _BELOW_BENCHMARK,
    "console": _BELOW_BENCHMARK | {"benchmark"},
    "mavswarm": _BELOW_BENCHMARK | {"benchmark", "console"},
}

# Inside a package, its parts in tiers: a part (a subpackage or a module) imports parts of its
# own tier or of the tiers before it, never a later one (a finer cut than LAYERS' "benchmark",
# whose running and server parts need each other). The benchmark: scoring knows nothing of
# tasks being written, authoring nothing of runs, runs (and the server that runs sessions live)
# nothing of reports; `cli` assembles them.
TIERS: dict[str, tuple[frozenset[str], ...]] = {
    "benchmark": (
        frozenset({"scoring"}),
        frozenset({"authoring"}),
        frozenset({"running", "server"}),
        frozenset({"reporting"}),
        frozenset({"cli", "__init__"}),
    ),
}


def layer_of(module: str, layers: Mapping[str, frozenset[str]] = LAYERS) -> str | None:
    """The layer a dotted module name belongs to (the longest that it starts with), or None
    for a module of none (the standard library, third parties)."""
    parts = module.split(".")
    for k in range(len(parts), 0, -1):
        name = ".".join(parts[:k])
        if name in layers:
            return name
    return None


@dataclass(frozen=True)
class Crossing:
    """One import of `imported` from a module of `layer` that the layer does not allow."""

    path: str
    line: int
    layer: str
    imported: str

    def __str__(self) -> str:
        return f"{self.path}:{self.line}: {self.layer} imports {self.imported}"


def _dynamic_import(node: ast.Call) -> str | None:
    """The module a call `__import__("m")` / `import_module("m")` names, else None."""
    if node.args:
        name = getattr(node.func, "id", None) or getattr(node.func, "attr", None)
        first = node.args[0]
        if name in ("__import__", "import_module") and isinstance(first, ast.Constant) \
                and isinstance(first.value, str):
            return first.value
    return None


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
        elif isinstance(node, ast.Call) and (name := _dynamic_import(node)) is not None:
            yield node.lineno, name


def _imported(source: str, module: str, is_package: bool) -> Iterator[tuple[int, str]]:
    """(line, module) for every import of a module's source, relative ones made absolute;
    `from a import b` imports `a.b` (in the layer of `a` unless `a.b` is a layer of its own)."""
    package = module if is_package else module.rpartition(".")[0]
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name
        elif isinstance(node, ast.ImportFrom):
            stem = node.module or ""
            if node.level:
                base = package.split(".")
                stem = ".".join(base[: len(base) - (node.level - 1)] + ([stem] if stem else []))
            for alias in node.names:
                yield node.lineno, stem if alias.name == "*" else f"{stem}.{alias.name}"
        elif isinstance(node, ast.Call) and (name := _dynamic_import(node)) is not None:
            yield node.lineno, name


def crossings(root: Path, layers: Mapping[str, frozenset[str]] = LAYERS) -> list[Crossing]:
    """Every import under `root` from a module of one of `layers` into another layer that it
    may not import."""
    found = []
    for package in sorted({layer.split(".")[0] for layer in layers}):
        for path in sorted((root / package).rglob("*.py")):
            parts = list(path.relative_to(root).with_suffix("").parts)
            is_package = parts[-1] == "__init__"
            module = ".".join(parts[:-1] if is_package else parts)
            own = layer_of(module, layers)
            if own is None:
                continue
            seen = set()
            for line, name in _imported(path.read_text(encoding="utf-8"), module, is_package):
                target = layer_of(name, layers)
                if target is None or target == own or target in layers[own]:
                    continue
                # `from a import b` is one import: report it once, by its layer
                if (line, target) not in seen:
                    seen.add((line, target))
                    found.append(Crossing(str(path.relative_to(root)), line, own, name))
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

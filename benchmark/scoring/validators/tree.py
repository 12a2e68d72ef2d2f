"""Check trees: parsing and validation, JSON form, and evaluation on a context.

JSON form: a group ``{"logic": "and" | "or" | "not", "checks": [nodes]}`` (logic defaults to
"and"; an object with neither endpoint nor checks is an empty "and" group) or a leaf
``{"endpoint": name, "parameters": {...}, "expect": true}``. A bare list is an "and" group.
The node at ``path`` names its children ``path[0]``, ``path[1]``, ...
"""

from __future__ import annotations

import difflib
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from benchmark.scoring.validators._errors import CheckDefinitionError
from benchmark.scoring.validators.context import CheckContext
from benchmark.scoring.validators.endpoint import check_entities
from benchmark.scoring.validators.params import show
from benchmark.scoring.validators.registry import ENDPOINTS, endpoint_name
from emulator.scenario import Scenario

__all__ = [
    "LOGICS",
    "Evaluation",
    "Group",
    "Leaf",
    "LeafResult",
    "Node",
    "endpoints_used",
    "evaluate",
    "leaf_count",
    "parse_tree",
    "tree_to_json",
]

LOGICS = ("and", "or", "not")
_GROUP_KEYS = frozenset({"logic", "checks"})
_LEAF_KEYS = frozenset({"endpoint", "parameters", "expect"})
_NOTE_KEYS = frozenset({"name", "description"})


@dataclass(frozen=True, slots=True)
class Leaf:
    """One check: endpoint name, normalised parameters, and the expected result."""

    endpoint: str
    parameters: Mapping[str, Any]
    expect: bool = True


@dataclass(frozen=True, slots=True)
class Group:
    """and: all children pass (empty: true); or: any passes (empty: false); not: not all
    children pass (empty: false)."""

    logic: str = "and"
    checks: tuple[Leaf | Group, ...] = ()


Node = Leaf | Group


def parse_tree(data: object, scenario: Scenario | None = None, *, path: str = "checks") -> Node:
    """Validate a check tree and return it with normalised parameters.

    With a scenario, every drone, target and obstacle id must exist in it. Raises
    CheckDefinitionError whose message starts with the path of the bad field.
    """
    if isinstance(data, list | tuple):
        return Group("and", tuple(parse_tree(item, scenario, path=f"{path}[{k}]")
                                  for k, item in enumerate(data)))
    if not isinstance(data, Mapping):
        raise CheckDefinitionError(
            f"{path}: a check node must be an object or a list, got {show(data)}")
    keys = {str(k) for k in data}
    if "endpoint" in keys:
        if extra := sorted(keys - _LEAF_KEYS - _NOTE_KEYS):
            raise CheckDefinitionError(
                f"{path}.{extra[0]}: unknown key in a leaf (keys: endpoint, parameters, expect)")
        return _parse_leaf(data, scenario, path)
    if extra := sorted(keys - _GROUP_KEYS - _NOTE_KEYS):
        raise CheckDefinitionError(
            f"{path}.{extra[0]}: unknown key in a group (keys: logic, checks; a leaf needs "
            f"endpoint)")
    logic = data.get("logic", "and")
    if not isinstance(logic, str) or logic.strip().lower() not in LOGICS:
        raise CheckDefinitionError(
            f"{path}.logic: must be one of {', '.join(LOGICS)}, got {show(logic)}")
    children = data.get("checks", [])
    if children is None:
        children = []
    if not isinstance(children, list | tuple):
        raise CheckDefinitionError(f"{path}.checks: must be a list, got {show(children)}")
    return Group(logic.strip().lower(), tuple(
        parse_tree(item, scenario, path=f"{path}[{k}]") for k, item in enumerate(children)))


def _parse_leaf(data: Mapping[str, Any], scenario: Scenario | None, path: str) -> Leaf:
    raw = data["endpoint"]
    if not isinstance(raw, str) or not raw.strip():
        raise CheckDefinitionError(f"{path}.endpoint: must be an endpoint name, got {show(raw)}")
    name = endpoint_name(raw)
    if name not in ENDPOINTS:
        close = difflib.get_close_matches(name, list(ENDPOINTS), n=1)
        hint = f"; did you mean {close[0]!r}?" if close else ""
        raise CheckDefinitionError(f"{path}.endpoint: unknown endpoint {raw!r}{hint}")
    parameters = ENDPOINTS[name].normalise(data.get("parameters"), scenario,
                                           f"{path}.parameters")
    return Leaf(name, parameters, _parse_expect(data.get("expect", True), f"{path}.expect"))


def _parse_expect(raw: object, path: str) -> bool:
    if raw is None or isinstance(raw, bool):
        return raw is not False
    if isinstance(raw, str) and raw.strip().lower() in ("true", "false"):
        return raw.strip().lower() == "true"
    raise CheckDefinitionError(f"{path}: must be true or false, got {show(raw)}")


def _plain(value: Any) -> Any:
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    return value


def tree_to_json(node: Node) -> dict[str, Any]:
    """The JSON form of a parsed tree; parse_tree reads it back to an equal tree."""
    if isinstance(node, Leaf):
        return {"endpoint": node.endpoint, "parameters": _plain(node.parameters),
                "expect": node.expect}
    return {"logic": node.logic, "checks": [tree_to_json(child) for child in node.checks]}


def leaf_count(node: Node) -> int:
    """Number of leaf checks in the tree."""
    if isinstance(node, Leaf):
        return 1
    return sum(leaf_count(child) for child in node.checks)


def endpoints_used(node: Node) -> set[str]:
    """Names of the endpoints the tree's leaves use."""
    if isinstance(node, Leaf):
        return {node.endpoint}
    return set().union(*(endpoints_used(child) for child in node.checks))


@dataclass(frozen=True)
class LeafResult:
    """The evaluation of one leaf; result is None (and error set) when it could not run."""

    path: str
    endpoint: str
    parameters: dict[str, Any]
    expect: bool
    result: bool | None
    value: object
    passed: bool
    error: str | None

    def to_json(self) -> dict[str, Any]:
        return {"path": self.path, "endpoint": self.endpoint,
                "parameters": _plain(self.parameters), "expect": self.expect,
                "result": self.result, "value": _plain(self.value), "passed": self.passed,
                "error": self.error}


@dataclass(frozen=True)
class Evaluation:
    """Whether the root passed, and every leaf's result in tree order."""

    passed: bool
    leaves: tuple[LeafResult, ...]

    @property
    def passed_leaves(self) -> int:
        return sum(leaf.passed for leaf in self.leaves)

    def to_json(self) -> dict[str, Any]:
        return {"passed": self.passed, "leaves": [leaf.to_json() for leaf in self.leaves]}


def evaluate(node: Node, ctx: CheckContext, *, path: str = "checks") -> Evaluation:
    """Evaluate every leaf of the tree on ctx; never raises for a leaf's problem."""
    leaves: list[LeafResult] = []
    passed = _evaluate(node, ctx, path, leaves)
    return Evaluation(passed, tuple(leaves))


def _evaluate(node: Node, ctx: CheckContext, path: str, out: list[LeafResult]) -> bool:
    if isinstance(node, Leaf):
        result = _evaluate_leaf(node, ctx, path)
        out.append(result)
        return result.passed
    outcomes = [_evaluate(child, ctx, f"{path}[{k}]", out) for k, child in enumerate(node.checks)]
    if node.logic == "and":
        return all(outcomes)
    if node.logic == "or":
        return any(outcomes)
    return bool(outcomes) and not all(outcomes)


def _evaluate_leaf(leaf: Leaf, ctx: CheckContext, path: str) -> LeafResult:
    parameters = _plain(leaf.parameters)
    try:
        endpoint = ENDPOINTS[leaf.endpoint]
        check_entities(endpoint, leaf.parameters, ctx.scenario, f"{path}.parameters")
        outcome = endpoint.run(ctx, leaf.parameters)
    except Exception as exc:  # a leaf that cannot run fails; the tree still evaluates
        error = str(exc) or type(exc).__name__
        return LeafResult(path, leaf.endpoint, parameters, leaf.expect, None, None, False, error)
    result = bool(outcome.result)
    return LeafResult(path, leaf.endpoint, parameters, leaf.expect, result, outcome.value,
                      result == leaf.expect, None)

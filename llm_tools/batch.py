"""The `batch` tool: several tool calls run side by side in one request, one result per call.

An agent that drives several drones at once over REST or MCP sends their calls together; they
run as `tools.concurrently(...)` runs them in-process, each as a thread of its own, so under a
lockstep clock they start at the same simulated instant and the request ends when the last
one does. Its schemas are generated from the registry's own tool specs: each call is
`{"tool": NAME, "arguments": {...}}` with NAME's input schema, and each result follows the
tools' shared output schema. Each call is validated as a single call would be; a bad call gets
its own error result and the others still run. A batch holds 1 to `MAX_BATCH_CALLS` calls and
no batch inside it.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Awaitable, Callable, Mapping, Sequence
from typing import TYPE_CHECKING, Annotated, Any

from pydantic import BaseModel, ConfigDict, Field, Strict

from agent_contract import AgentTools, BudgetExhausted
from llm_tools.input_limits import preview
from mavlink_gateway import Outcome

if TYPE_CHECKING:
    from llm_tools.registry import ToolSpec

__all__ = ["BATCH", "MAX_BATCH_CALLS", "BatchArguments", "batch_input_schema",
           "batch_output_schema", "run_batch"]

BATCH = "batch"
MAX_BATCH_CALLS = 16
DESCRIPTION = (f"Run up to {MAX_BATCH_CALLS} tool calls side by side, e.g. one per drone, and "
               "get one result per call, in order (each with its own status). Use it to fly "
               "several drones at once: the calls start at the same simulated time and the "
               "batch ends when the last one does. A batch cannot contain a batch.")

Call = Callable[[str, Mapping[str, Any] | None], Awaitable[dict[str, Any]]]


class BatchArguments(BaseModel):
    """The batch tool's arguments: 1 to MAX_BATCH_CALLS calls (each checked by `run_batch`)."""

    model_config = ConfigDict(extra="forbid")

    calls: Annotated[list[Any], Strict(), Field(min_length=1, max_length=MAX_BATCH_CALLS)]


def batch_input_schema(specs: Sequence[ToolSpec]) -> dict[str, Any]:
    """`{"calls": [{"tool", "arguments"}, ...]}`, each call one of `specs` with its schema."""
    variants = [{"type": "object",
                 "properties": {"tool": {"type": "string", "enum": [spec.name]},
                                "arguments": spec.input_schema},
                 "required": ["tool"], "additionalProperties": False} for spec in specs]
    return {"type": "object",
            "properties": {"calls": {
                "type": "array", "minItems": 1, "maxItems": MAX_BATCH_CALLS,
                "description": "The calls, each a tool's name and its arguments object "
                               "(omit arguments for a tool that takes none).",
                "items": {"oneOf": variants}}},
            "required": ["calls"], "additionalProperties": False}


def batch_output_schema(result_schema: Mapping[str, Any]) -> dict[str, Any]:
    """The batch's own status and message, and `results`: one `result_schema` per call."""
    return {"type": "object",
            "properties": {**result_schema["properties"],
                           "results": {"type": "array", "items": dict(result_schema)}},
            "required": [*result_schema["required"], "results"]}


def _error(message: str) -> dict[str, Any]:
    return {"status": "error", "message": message}


def _item_problem(k: int, item: Any, known: Sequence[str]) -> str | None:
    where = f"calls[{k}]"
    if not isinstance(item, Mapping):
        return f"{where} must be an object {{tool, arguments}}, got {preview(item)}"
    extra = [key for key in item if key not in ("tool", "arguments")]
    if extra:
        return (f"{where} has unknown key(s) {', '.join(preview(key) for key in extra[:5])}; "
                "expected tool and arguments")
    tool = item.get("tool")
    if tool == BATCH:
        return f"{where}: a batch cannot contain a batch"
    if not isinstance(tool, str) or tool not in known:
        return f"{where}.tool must name a tool ({', '.join(known)}), got {preview(tool)}"
    arguments = item.get("arguments")
    if arguments is not None and not isinstance(arguments, Mapping):
        return f"{where}.arguments must be a JSON object, got {preview(arguments)}"
    return None


def _as_result(name: str, value: Any) -> dict[str, Any]:
    if isinstance(value, BudgetExhausted):
        return _error(f"{name}: the task is over ({value})")
    if isinstance(value, BaseException):
        raise value
    return dict(value)


async def run_batch(tools: AgentTools, calls: Sequence[Any], known: Sequence[str],
                    call: Call) -> dict[str, Any]:
    """Run the valid `calls` side by side on `tools` through `call(name, arguments)`; the
    batch's result. `known`: the tools a batch may call. A surface whose thread cannot run the
    batch now answers each call with its refusal (an `Outcome`, not a result dict): the batch
    is then refused as a whole."""
    results: list[dict[str, Any] | None] = []
    runs: list[tuple[int, str, Awaitable[dict[str, Any]]]] = []
    for k, item in enumerate(calls):
        problem = _item_problem(k, item, known)
        if problem is not None:
            results.append(_error(f"{BATCH}: {problem}"))
            continue
        results.append(None)
        runs.append((k, item["tool"], call(item["tool"], item.get("arguments"))))
    outcomes = await tools.concurrently(*(run for _, _, run in runs)) if runs else []
    refusal = next((v for v in outcomes if isinstance(v, Outcome)), None)
    if refusal is not None:
        return {**refusal.to_dict(), "results": []}
    for (k, name, _), value in zip(runs, outcomes, strict=True):
        results[k] = _as_result(name, value)
    done = [r for r in results if r is not None]
    counts = Counter(str(r.get("status")) for r in done)
    summary = ", ".join(f"{n} {s}" for s, n in sorted(counts.items()))
    return {"status": "ok", "message": f"{len(done)} calls: {summary}", "results": done}

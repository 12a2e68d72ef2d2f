"""A structured agent: observe -> understand and plan -> execute -> verify, with bounded
replanning.

Each round the agent senses with every drone, asks the model for a JSON plan of tool calls,
runs it, senses again and asks the model whether the task is complete. A plan the model cannot
state as JSON after one re-ask is replaced, for that round, by ReAct-style tool calling. All
the model learns comes from tool results gathered on a `Blackboard`.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from agent_contract import AgentTask, AgentTools
from llm_tools.openai_adapter import openai_tools, parse_tool_calls
from llm_tools.registry import ToolRegistry, default_registry
from swarm_agents.llm.blackboard import Blackboard, StepRecord
from swarm_agents.llm.model import ChatModel
from swarm_agents.llm.openai_model import ModelConfig, opened
from swarm_agents.llm.react import assistant_message, result_text
from swarm_agents.llm.transcript import record_messages, unrecorded_from

__all__ = ["PLAN_PROMPT", "VERIFY_PROMPT", "Plan", "PlanStep", "Verdict", "WorkflowAgent",
           "parse_json_object", "parse_plan", "parse_verdict"]

PLAN_PROMPT = """You plan actions for a swarm of real quadrotor drones.
Coordinates are local metres: x east, y north; z is altitude above home. Headings are compass
degrees (0 north, 90 east). A drone must take off before it can move. Moves fly straight and
stop before obstacles ("blocked"); route around them with intermediate points. You know only
what the blackboard shows: drone states and what their sensors have reported.

Available tools (name(arguments): purpose):
{tools}

Answer with one JSON object and nothing else:
{{"steps": [{{"tool": "<name>", "arguments": {{...}}}}, ...], "done_when": "<how to tell>"}}
Steps run in order; flights of different drones that follow each other may run at once.
Do not include finish: it is called for you once the task is verified complete."""

VERIFY_PROMPT = """You check whether a drone task has been fully carried out, using only the
blackboard (drone states and sensor reports) and the log of tool calls.
Answer with one JSON object and nothing else: {"complete": true or false, "reason": "..."}"""

REACT_PROMPT = """You command a swarm of real quadrotor drones through tools. Coordinates are
local metres (x east, y north, z altitude above home). Act with the tools; when the whole task
is done call finish."""

REASK = ("That answer was not a usable JSON object. Reply again with only the JSON object in "
         "the requested form, without any other text.")

# Flight primitives on different drones are independent and may run concurrently.
FLIGHT_TOOLS = frozenset({"take_off", "land", "move_to", "move_towards", "change_altitude",
                          "move_along_path", "hover", "rotate", "return_home", "take_photo",
                          "charge"})
REACT_TURNS_PER_ROUND = 8


@dataclass(frozen=True)
class PlanStep:
    """One planned tool call."""

    tool: str
    arguments: Mapping[str, Any] | str

    @property
    def drone_id(self) -> str | None:
        if isinstance(self.arguments, Mapping):
            drone = self.arguments.get("drone_id")
            return drone if isinstance(drone, str) else None
        return None


@dataclass(frozen=True)
class Plan:
    """The model's plan for one round."""

    steps: tuple[PlanStep, ...]
    done_when: str = ""


@dataclass(frozen=True)
class Verdict:
    """The model's judgement of whether the task is complete."""

    complete: bool
    reason: str


# ---------------------------------------------------------------------------- parsing
def parse_json_object(text: Any) -> dict[str, Any] | None:
    """The first JSON object in a model's text (code fences and surrounding prose allowed),
    or None."""
    if not isinstance(text, str):
        return None
    stripped = text.strip()
    try:
        value = json.loads(stripped)
    except json.JSONDecodeError:
        value = None
    if isinstance(value, dict):
        return value
    decoder = json.JSONDecoder()
    start = stripped.find("{")
    while start != -1:
        try:
            value, _ = decoder.raw_decode(stripped, start)
        except json.JSONDecodeError:
            value = None
        if isinstance(value, dict):
            return value
        start = stripped.find("{", start + 1)
    return None


def parse_plan(text: Any) -> Plan | None:
    """A plan from the model's text, or None when it is not one."""
    data = parse_json_object(text)
    if data is None or not isinstance(data.get("steps"), list):
        return None
    steps = []
    for raw in data["steps"]:
        if not isinstance(raw, Mapping) or not isinstance(raw.get("tool"), str):
            return None
        arguments = raw.get("arguments", {})
        if arguments is None:
            arguments = {}
        if not isinstance(arguments, Mapping | str):
            return None
        steps.append(PlanStep(raw["tool"], arguments))
    done_when = data.get("done_when")
    return Plan(tuple(steps), done_when if isinstance(done_when, str) else "")


def parse_verdict(text: Any) -> Verdict | None:
    """A verdict from the model's text, or None when it is not one."""
    data = parse_json_object(text)
    if data is None:
        return None
    complete = data.get("complete")
    if isinstance(complete, str) and complete.strip().lower() in ("true", "false"):
        complete = complete.strip().lower() == "true"
    if not isinstance(complete, bool):
        return None
    reason = data.get("reason")
    return Verdict(complete, reason if isinstance(reason, str) else "")


# ------------------------------------------------------------------------------ agent
class WorkflowAgent:
    """Observe, plan, execute and verify over a chat model (a `ChatModel`, or a `ModelConfig`
    of an OpenAI-compatible server, as for `ReactAgent`)."""

    name = "workflow"

    def __init__(self, model: ChatModel | ModelConfig, *, registry: ToolRegistry | None = None,
                 max_steps: int = 40, max_tokens: int = 400_000, max_rounds: int = 3) -> None:
        if max_rounds < 1:
            raise ValueError(f"max_rounds must be at least 1, got {max_rounds!r}")
        self.model = model
        self.registry = registry or default_registry()
        self.max_steps = max_steps
        self.max_tokens = max_tokens
        self.max_rounds = max_rounds
        self.blackboard = Blackboard()
        self._steps_used = 0

    async def run(self, task: AgentTask, tools: AgentTools) -> None:
        self.blackboard = Blackboard()
        self._steps_used = 0
        async with opened(self.model) as model:
            await self._workflow(model, task, tools)

    # ---------------------------------------------------------------- rounds
    async def _workflow(self, model: ChatModel, task: AgentTask, tools: AgentTools) -> None:
        board = self.blackboard
        await self._observe(tools)
        feedback = ""
        stop = f"stopped: {self.max_rounds} round(s) did not complete the task"
        for round_index in range(self.max_rounds):
            first_step = len(board.steps)
            plan = await self._plan(model, task, tools, feedback)
            if plan is None:
                await self._react_round(model, task, tools)
            else:
                await self._execute(plan, tools)
            if tools.finished or self._out_of_budget(tools):
                break
            failures = board.failures(first_step)
            await self._observe(tools)
            verdict = await self._verify(model, task, tools, first_step)
            if verdict.complete:
                await self._call(tools, "finish", {"summary": verdict.reason[:500]})
                return
            if self._out_of_budget(tools):
                break
            board.add_note(f"round {round_index + 1} incomplete: {verdict.reason}")
            feedback = _feedback(verdict, failures)
            stop = (f"stopped: {self.max_rounds} round(s) did not complete the task (last "
                    f"verdict: {(verdict.reason or 'not complete')[:200]})")
        if not tools.finished:
            tools.finish(self._budget_reason(tools) or stop)

    def _out_of_budget(self, tools: AgentTools) -> bool:
        return self._budget_reason(tools) is not None

    def _budget_reason(self, tools: AgentTools) -> str | None:
        """Why the agent must stop now, or None while its budgets last."""
        if self._steps_used >= self.max_steps:
            return f"stopped: the budget of {self.max_steps} planned tool calls is spent"
        if tools.prompt_tokens + tools.completion_tokens >= self.max_tokens:
            return f"stopped: the budget of {self.max_tokens} tokens is spent"
        return None

    async def _call(self, tools: AgentTools, name: str,
                    arguments: Mapping[str, Any] | str | None) -> StepRecord:
        result = await self.registry.call(tools, name, arguments)
        return self.blackboard.ingest(name, arguments, result)

    async def _ask(self, model: ChatModel, tools: AgentTools,
                   messages: list[dict[str, Any]],
                   schema: list[dict[str, Any]] | None = None) -> dict[str, Any]:
        record_messages(tools, messages, unrecorded_from(messages))
        reply = await model.complete(messages, schema or [])
        usage = reply.usage
        tools.add_tokens(usage.prompt, usage.completion, usage.cost_usd)
        record_messages(tools, [assistant_message(reply.message, parse_tool_calls(reply.message))],
                        0, usage.tokens())
        return reply.message

    # --------------------------------------------------------------- observe
    async def _observe(self, tools: AgentTools) -> None:
        """Every drone's state and sensor reading, onto the blackboard."""
        await self._call(tools, "list_drones", {})
        for drone in tools.drone_ids:
            await self._call(tools, "nearby", {"drone_id": drone})

    # ------------------------------------------------------------------ plan
    async def _plan(self, model: ChatModel, task: AgentTask, tools: AgentTools,
                    feedback: str) -> Plan | None:
        user = (f"Task: {task.text}\nYour drones: {', '.join(tools.drone_ids)}.\n"
                f"Blackboard: {self.blackboard.summary()}")
        if feedback:
            user += f"\nThe previous round did not complete the task.\n{feedback}"
        messages: list[dict[str, Any]] = [
            {"role": "system", "content": PLAN_PROMPT.format(tools=self._tool_lines())},
            {"role": "user", "content": user}]
        for attempt in range(2):
            message = await self._ask(model, tools, messages)
            content = message.get("content")
            plan = parse_plan(content)
            if plan is not None or attempt == 1 or self._out_of_budget(tools):
                return plan
            messages.append({"role": "assistant", "content": str(content or "")})
            messages.append({"role": "user", "content": REASK})
        return None

    def _tool_lines(self) -> str:
        lines = []
        for spec in self.registry.specs():
            if spec.name == "finish":
                continue
            params = ", ".join(spec.input_schema.get("properties", {}))
            lines.append(f"- {spec.name}({params}): {spec.description}")
        return "\n".join(lines)

    # --------------------------------------------------------------- execute
    async def _execute(self, plan: Plan, tools: AgentTools) -> None:
        """Run the plan's steps; later steps of a drone whose step failed are skipped."""
        failed: set[str] = set()
        steps = [s for s in plan.steps if s.tool != "finish"]
        index = 0
        while index < len(steps) and not self._out_of_budget(tools):
            batch = [steps[index]]
            index += 1
            while index < len(steps) and _joins(batch, steps[index]):
                batch.append(steps[index])
                index += 1
            runnable = []
            for step in batch:
                if step.drone_id is not None and step.drone_id in failed:
                    self.blackboard.add_note(f"skipped {step.tool} for {step.drone_id}: an "
                                             "earlier step of that drone failed")
                elif self._steps_used < self.max_steps:
                    self._steps_used += 1
                    runnable.append(step)
            records = _raise_first(await tools.concurrently(
                *(self._call(tools, s.tool, s.arguments) for s in runnable)))
            for step, record in zip(runnable, records, strict=True):
                if not record.ok and step.drone_id is not None:
                    failed.add(step.drone_id)

    # ---------------------------------------------------------------- verify
    async def _verify(self, model: ChatModel, task: AgentTask, tools: AgentTools,
                      first_step: int) -> Verdict:
        log = "\n".join(s.describe() for s in self.blackboard.steps[first_step:]
                        if s.tool not in ("list_drones", "nearby")) or "(no actions)"
        messages: list[dict[str, Any]] = [
            {"role": "system", "content": VERIFY_PROMPT},
            {"role": "user", "content": f"Task: {task.text}\nActions this round:\n{log}\n"
                                        f"Blackboard: {self.blackboard.summary()}"}]
        for attempt in range(2):
            message = await self._ask(model, tools, messages)
            content = message.get("content")
            verdict = parse_verdict(content)
            if verdict is not None:
                return verdict
            if attempt == 0:
                messages.append({"role": "assistant", "content": str(content or "")})
                messages.append({"role": "user", "content": REASK})
        return Verdict(False, "the verification answer was not readable")

    # ----------------------------------------------------------- react round
    async def _react_round(self, model: ChatModel, task: AgentTask,
                           tools: AgentTools) -> None:
        """Tool calling for one round, when no plan could be read."""
        schema = openai_tools(self.registry)
        messages: list[dict[str, Any]] = [
            {"role": "system", "content": REACT_PROMPT},
            {"role": "user", "content": f"Task: {task.text}\nYour drones: "
                                        f"{', '.join(tools.drone_ids)}.\n"
                                        f"Blackboard: {self.blackboard.summary()}"}]
        for _ in range(REACT_TURNS_PER_ROUND):
            message = await self._ask(model, tools, messages, schema)
            calls = parse_tool_calls(message)
            messages.append(assistant_message(message, calls))
            if not calls:
                return
            for call in calls:
                self._steps_used += 1
                result = await self.registry.call(tools, call.name, call.arguments)
                self.blackboard.ingest(call.name, call.arguments, result)
                messages.append({"role": "tool", "tool_call_id": call.id,
                                 "content": result_text(result)})
            if tools.finished or self._out_of_budget(tools):
                break
        # The last turn's tool results, which no further question carries into the transcript.
        record_messages(tools, messages, unrecorded_from(messages))


def _joins(batch: list[PlanStep], step: PlanStep) -> bool:
    """Whether a step may run concurrently with a batch: flights of distinct drones only."""
    if step.tool not in FLIGHT_TOOLS or step.drone_id is None:
        return False
    if any(s.tool not in FLIGHT_TOOLS or s.drone_id is None for s in batch):
        return False
    return step.drone_id not in {s.drone_id for s in batch}


def _feedback(verdict: Verdict, failures: list[StepRecord]) -> str:
    lines = [f"Verifier: {verdict.reason or 'not complete'}"]
    if failures:
        lines.append("Failed steps:")
        lines.extend(f"- {f.describe()}" for f in failures[-10:])
    return "\n".join(lines)


def _raise_first(results: list[Any]) -> list[Any]:
    """Results of `tools.concurrently`: the first exception one of them raised, raised."""
    for result in results:
        if isinstance(result, BaseException):
            raise result
    return results

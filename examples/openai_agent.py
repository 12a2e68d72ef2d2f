"""A minimal LLM agent: a tool-calling loop over the openai SDK.

    mavswarm bench run --agent examples/openai_agent.py:OpenAIAgent \\
        --model MODEL --base-url URL --price-in USD --price-out USD --suite smoke

The model sees the agent tools as OpenAI function schemas generated from their definitions
(`llm_tools.openai_tools`); `ToolRegistry.call` validates each call's arguments and runs it.
Several tool calls in one reply run side by side (`tools.concurrently`), tokens and their cost
are reported with `tools.add_tokens`. The key comes from OPENAI_API_KEY (any text for a local
server).
"""

from __future__ import annotations

import json
import os
from typing import Any

import openai

from agent_contract import AgentOptions, AgentTask, AgentTools
from llm_tools import default_registry, openai_tools

MAX_TURNS = 40
SYSTEM = ("You command a swarm of drones through the tools. Positions are metres: x east, "
          "y north, z altitude. Do what the task asks, then call finish with a summary.")


class OpenAIAgent:
    """Built with the run's options: `--model`, `--base-url` and the token prices."""

    def __init__(self, options: AgentOptions) -> None:
        self.options = options
        self.model = options.model or os.environ.get("OPENAI_MODEL", "gpt-4o-mini")
        self.client = openai.AsyncOpenAI(
            base_url=options.base_url or os.environ.get("OPENAI_BASE_URL") or None,
            api_key=os.environ.get("OPENAI_API_KEY") or "none")
        self.registry = default_registry()
        self.schemas: Any = openai_tools(self.registry)

    async def run(self, task: AgentTask, tools: AgentTools) -> None:
        messages: list[Any] = [{"role": "system", "content": SYSTEM},
                               {"role": "user", "content": task.text}]
        for _ in range(MAX_TURNS):
            reply = await self.client.chat.completions.create(
                model=self.model, messages=messages, tools=self.schemas)
            if reply.usage is not None:
                used = reply.usage.prompt_tokens, reply.usage.completion_tokens
                tools.add_tokens(*used, self.options.cost_usd(*used))
            message = reply.choices[0].message
            messages.append(message.model_dump(exclude_none=True))
            calls = [c for c in message.tool_calls or [] if c.type == "function"]
            if not calls:  # the model answered in text: nudge it back to the tools
                messages.append({"role": "user", "content": "Use the tools; call finish "
                                 "when the task is done."})
                continue
            results = await tools.concurrently(*(
                self.registry.call(tools, c.function.name, c.function.arguments)
                for c in calls))
            for call, result in zip(calls, results, strict=True):
                if isinstance(result, BaseException):  # BudgetExhausted: the task is over
                    raise result
                messages.append({"role": "tool", "tool_call_id": call.id,
                                 "content": json.dumps(result)})
            if tools.finished:
                return
        tools.finish(f"stopped after {MAX_TURNS} model turns")

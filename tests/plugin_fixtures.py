"""Plug-in agents for the plug-in tests, written to a file the way a user would write them:
good ones (an instance, a class built with or without the run's options, a factory, the ReAct
agent on a scripted model), and bad
ones (raising, hanging, not agents)."""

from __future__ import annotations

from pathlib import Path

__all__ = ["PLUGINS", "write_plugins"]

PLUGINS = '''
import asyncio

from agent_contract import AgentOptions


class WithOptions:
    def __init__(self, options: AgentOptions) -> None:
        self.options = options

    async def run(self, task, tools):
        tools.finish(self.options.session_id)


class NoArguments:
    def __init__(self, altitude_m=10.0):
        self.altitude_m = altitude_m

    async def run(self, task, tools):
        await tools.take_off(tools.drone_ids[0], self.altitude_m)
        tools.finish("up")


instance = NoArguments(7.0)


def factory(options):
    return WithOptions(options)


class FailsFirst:
    async def run(self, task, tools):
        if task.task_id == "t01":
            raise RuntimeError("boom in run")
        tools.finish()


class HangsFirst:
    async def run(self, task, tools):
        if task.task_id == "t01":
            await asyncio.Event().wait()
        tools.finish()


class SlowThinker:
    async def run(self, task, tools):
        for _ in range(6):
            await asyncio.sleep(0.3)
            tools.list_drones()
        tools.finish()


def scripted_react(options):
    """The built-in ReAct loop on a scripted model in process: the drone it is told is its own
    takes off, then it finishes (an agent told of no drone only talks)."""
    from swarm_agents.llm import ReactAgent, ScriptedChatModel, tool_call
    me = options.drone_id

    def answer(request):
        if f"You are the agent of drone {me} only" not in request.messages[1]["content"]:
            return "I was not told which drone is mine."
        if len(request.messages) == 2:
            return [tool_call("take_off", {"drone_id": me, "altitude_m": 8.0}, f"{me}-1")]
        return [tool_call("finish", {"summary": f"{me} up"}, f"{me}-2")]

    return ReactAgent(ScriptedChatModel(answer))


def broken_factory(options):
    raise KeyError("no model configured")


def makes_no_agent():
    return 42


class SyncRun:
    def run(self, task, tools):
        tools.finish()


class NoRun:
    pass


class WrongRun:
    async def run(self, task):
        pass


class NeedsTwo:
    def __init__(self, a, b):
        pass

    async def run(self, task, tools):
        pass


async def coroutine(task, tools):
    pass
'''


def write_plugins(folder: Path, name: str = "plugins_under_test.py") -> Path:
    path = folder / name
    path.write_text(PLUGINS)
    return path

"""The solver of the inspect tasks: one benchmark task flown on a swarm of its own.

It runs the same episode `bench run` does (`benchmark.running.episode.run_one_task`: the session's
swarm and gateway, the operator's reset, the task's faults, the clock, the agent under its
budget, the play-out) with the ReAct agent thinking through inspect's model. The task's record
(finish, tool calls, simulated time, tokens; as `bench run` writes it, less the replay) goes
into the sample's store under ``mavswarm/record``; a copy of the ground truth as it stood at
the window's end (the clock held there) is kept in this process for the scorer, which runs the
hidden checks on it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from inspect_ai.solver import Generate, Solver, TaskState, solver

from benchmark.authoring.session_file import Session, TaskSpec
from benchmark.running.episode import CLOCKS, EpisodeOptions, run_one_task
from benchmark.scoring.validators import CheckContext
from emulator.truth import TruthRecorder
from mavswarm.inspect.agent import InspectReactAgent, InspectSolverAgent
from mavswarm.inspect.dataset import load_session

__all__ = ["RECORD_KEY", "HeldTruth", "swarm_agent", "take_truth"]

RECORD_KEY = "mavswarm/record"


@dataclass(frozen=True)
class HeldTruth:
    """What the scorer needs of a flown task: its checks and its window's ground truth."""

    session: Session
    task: TaskSpec
    context: CheckContext | None  # None: the task could not be run (see the record's error)


_held: dict[str, HeldTruth] = {}


def take_truth(state: TaskState) -> HeldTruth | None:
    """The truth the solver kept for this sample (once: it is then let go)."""
    return _held.pop(state.uuid, None)


@solver
def swarm_agent(clock: str = "lockstep", max_turns: int = 40, physics_hz: float = 50.0,
                agent_wall_timeout_s: float = 900.0, agent: Solver | None = None) -> Solver:
    """Fly the sample's benchmark task with the ReAct agent on inspect's model (or with
    `agent`, an inspect solver given the agent tools in ``state.tools``).

    Args:
        clock: "lockstep" (simulated time passes only while the agent waits on the world,
            so results do not depend on the model's latency) or "stepped".
        max_turns: Most model turns per task.
        physics_hz: The swarm's physics rate.
        agent_wall_timeout_s: Wall time after which a hung agent ends as an agent error.
        agent: An inspect solver to play the task instead of the ReAct loop (``max_turns``
            does not apply; inspect's sample limits do).
    """
    if clock not in CLOCKS:
        raise ValueError(f"unknown clock {clock!r} (known: {', '.join(CLOCKS)})")
    if max_turns < 1:
        raise ValueError(f"max_turns must be >= 1, got {max_turns}")

    async def solve(state: TaskState, generate: Generate) -> TaskState:
        session = load_session(state.metadata["session_path"])
        task = next((t for t in session.tasks if t.id == state.metadata["task"]), None)
        if task is None:
            raise ValueError(f"{session.source} has no task {state.metadata['task']!r}")
        options = EpisodeOptions(trial=state.epoch - 1, physics_hz=physics_hz, clock=clock,
                                 agent_wall_timeout_s=agent_wall_timeout_s)
        player = (InspectReactAgent(state, max_turns=max_turns) if agent is None
                  else InspectSolverAgent(state, agent, generate))
        kept: list[CheckContext] = []

        def keep(context: CheckContext) -> None:  # at the window's end, the clock held
            history = context.history
            frozen = history.snapshot() if isinstance(history, TruthRecorder) else history
            kept.append(CheckContext(frozen, context.scenario, context.t0_s, context.t1_s))

        record: dict[str, Any] = await run_one_task(session, task, player, options, truth=keep)
        record.pop("replay", None)
        state.store.set(RECORD_KEY, record)
        _held[state.uuid] = HeldTruth(session, task, kept[0] if kept else None)
        state.completed = True
        return state

    return solve

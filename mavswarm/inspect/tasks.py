"""The inspect tasks: the smoke and full suites, one task per family, and any sessions.

Each sample is one benchmark task flown on a swarm of its own by the ReAct agent
(`swarm_agent`) and scored by its hidden checks (`swarm_checks`). Parameters (``-T``):

- ``clock``: "lockstep" (default) or "stepped" (see `benchmark.running.episode.CLOCKS`);
- ``max_turns``: most model turns per task (default 40);
- ``task_limit``: only the first N tasks of each session;
- ``level`` (family tasks): one level or several, comma-separated;
- ``sessions`` (``mavswarm/sessions``): session ids of the shipped suite or session files.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from inspect_ai import Task, task
from inspect_ai.solver import Solver

from benchmark.authoring.suite import suite_paths
from mavswarm.inspect.dataset import family_paths, session_dataset, session_paths
from mavswarm.inspect.scorer import swarm_checks
from mavswarm.inspect.solver import swarm_agent

__all__ = ["area_assignment_and_patrol", "area_search", "full", "resilience", "sessions",
           "smoke", "target_assignment", "target_tracking"]


def swarm_task(paths: Sequence[Path], task_limit: int | None = None, *,
               name: str = "mavswarm", clock: str = "lockstep", max_turns: int = 40,
               agent: Solver | None = None) -> Task:
    """A task of one sample per benchmark task of the sessions at `paths`, played by the
    ReAct loop or by `agent` (an inspect solver; see `swarm_agent`)."""
    return Task(dataset=session_dataset(paths, task_limit, name=name),
                solver=swarm_agent(clock=clock, max_turns=max_turns, agent=agent),
                scorer=swarm_checks(), metadata={"clock": clock, "task_limit": task_limit})


@task
def smoke(clock: str = "lockstep", max_turns: int = 40) -> Task:
    """The smoke suite: the first tasks of three easy sessions (18 samples)."""
    paths, limit = suite_paths("smoke")
    return swarm_task(paths, limit, name="mavswarm-smoke", clock=clock, max_turns=max_turns)


@task
def full(clock: str = "lockstep", max_turns: int = 40, task_limit: int | None = None) -> Task:
    """The full suite: every task of the 125 shipped sessions."""
    paths, _ = suite_paths("full")
    return swarm_task(paths, task_limit, name="mavswarm-full", clock=clock,
                      max_turns=max_turns)


@task
def sessions(sessions: str | list[str], task_limit: int | None = None,
             clock: str = "lockstep", max_turns: int = 40) -> Task:
    """The tasks of the sessions named: ids of the shipped suite or session files."""
    return swarm_task(session_paths(sessions), task_limit, name="mavswarm-sessions",
                      clock=clock, max_turns=max_turns)


def _family(family: str, level: str | list[str] | None, task_limit: int | None, clock: str,
            max_turns: int) -> Task:
    return swarm_task(family_paths(family, level), task_limit, name=f"mavswarm-{family}",
                      clock=clock, max_turns=max_turns)


@task
def area_search(level: str | list[str] | None = None, task_limit: int | None = None,
                clock: str = "lockstep", max_turns: int = 40) -> Task:
    """The area_search family (every level, or the ones named)."""
    return _family("area_search", level, task_limit, clock, max_turns)


@task
def area_assignment_and_patrol(level: str | list[str] | None = None,
                               task_limit: int | None = None, clock: str = "lockstep",
                               max_turns: int = 40) -> Task:
    """The area_assignment_and_patrol family (every level, or the ones named)."""
    return _family("area_assignment_and_patrol", level, task_limit, clock, max_turns)


@task
def target_assignment(level: str | list[str] | None = None, task_limit: int | None = None,
                      clock: str = "lockstep", max_turns: int = 40) -> Task:
    """The target_assignment family (every level, or the ones named)."""
    return _family("target_assignment", level, task_limit, clock, max_turns)


@task
def target_tracking(level: str | list[str] | None = None, task_limit: int | None = None,
                    clock: str = "lockstep", max_turns: int = 40) -> Task:
    """The target_tracking family (every level, or the ones named)."""
    return _family("target_tracking", level, task_limit, clock, max_turns)


@task
def resilience(level: str | list[str] | None = None, task_limit: int | None = None,
               clock: str = "lockstep", max_turns: int = 40) -> Task:
    """The resilience family (every level, or the ones named)."""
    return _family("resilience", level, task_limit, clock, max_turns)

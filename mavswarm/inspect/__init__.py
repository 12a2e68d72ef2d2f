"""inspect_ai integration: the benchmark's suites and families as inspect tasks.

``inspect eval mavswarm/smoke --model openai/gpt-4o-mini`` evaluates a model on the smoke
suite; each sample is one benchmark task on its own swarm, flown by the ReAct agent over the
agent tools and scored by the task's hidden checks (see `tasks`, `solver`, `scorer`).
Importing this package needs the ``inspect`` extra (``pip install mavswarm[inspect]``).
"""

from mavswarm.inspect.agent import InspectReactAgent
from mavswarm.inspect.scorer import check_ratio, swarm_checks
from mavswarm.inspect.solver import swarm_agent
from mavswarm.inspect.tasks import (
    area_assignment_and_patrol,
    area_search,
    full,
    resilience,
    sessions,
    smoke,
    swarm_task,
    target_assignment,
    target_tracking,
)

__all__ = ["InspectReactAgent", "area_assignment_and_patrol", "area_search", "check_ratio",
           "full", "resilience", "sessions", "smoke", "swarm_agent", "swarm_checks",
           "swarm_task", "target_assignment", "target_tracking"]

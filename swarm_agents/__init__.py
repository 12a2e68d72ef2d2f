"""Every agent mavswarm ships, and the loader of everyone else's.

- `swarm_agents.llm`: the LLM agents (`react`, `workflow`) and their model seam (`ChatModel`, over
  the `openai` SDK or scripted in process);
- `swarm_agents.baselines`: agents without a model (`noop`);
- `swarm_agents.teams`: one agent per drone (`NAME:per-drone`);
- `swarm_agents.oracle`: the oracle, which reads a task's hidden plan and checks (the ceiling);
- `swarm_agents.plugins`: agents by name for `bench run --agent` (built-ins and plug-ins).

The first three are on the agent side: loading them loads nothing of the benchmark or the
emulator. The oracle sits on the benchmark's session files and checks, and the loader on all
of them (`tests/import_layers.py`). This module imports none of its subpackages.
"""

__all__: list[str] = []

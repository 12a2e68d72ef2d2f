"""Every agent mavswarm ships, and the loader of everyone else's.

- `agents.llm`: the LLM agents (`react`, `workflow`) and their model seam (`ChatModel`, over
  the `openai` SDK or scripted in process);
- `agents.baselines`: agents without a model (`noop`);
- `agents.teams`: one agent per drone (`NAME:per-drone`);
- `agents.oracle`: the oracle, which reads a task's hidden plan and checks (the ceiling);
- `agents.plugins`: agents by name for `bench run --agent` (built-ins and plug-ins).

The first three are on the agent side: loading them loads nothing of the benchmark or the
emulator. The oracle sits on the benchmark's session files and checks, and the loader on all
of them (`tests/import_layers.py`). This module imports none of its subpackages.
"""

__all__: list[str] = []

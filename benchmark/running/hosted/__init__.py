"""Hosted benchmark runs: `mavswarm bench run --agent external` serves every task to an agent
outside the process (any language, over REST or MCP, or MultiUAV-Plat's client through the
reference routes) and scores it exactly as an in-process agent.

- `agent.ExternalAgent` runs in each unit as the run's agent and serves each task's own tools
  (`unit_server.UnitServer`, `task_tools.HostedTools`);
- `endpoint.Endpoint` runs in the driver: `GET /next` hands out the tasks units offer
  (`board.Board`), reference clients play through seat keys;
- `offer` holds the shapes that cross the wire; `run` wires it into `bench run`, whose
  `--host`/`--port` options are in `options`.

This module itself imports nothing heavy: the orchestrator reads `EXTERNAL` from it.
"""

EXTERNAL = "external"

__all__ = ["EXTERNAL"]

"""Baseline agents without a model: `noop`, the floor every other agent should beat (the
ceiling, the oracle, is `swarm_agents.oracle`). Agent side: they import the agent contract alone."""

from swarm_agents.baselines.noop import NoopAgent

__all__ = ["NoopAgent"]

"""Teams of agents: `PerDroneTeam` runs one agent per drone, each seeing only its drone's tools
and perception (`DroneView`) and talking to the others by radio (`--agent NAME:per-drone`).
Agent side: it imports the agent contract and the gateway's outcomes alone."""

from swarm_agents.teams.per_drone import DroneView, PerDroneTeam, per_drone_task

__all__ = ["DroneView", "PerDroneTeam", "per_drone_task"]

"""The benchmark, cut by concept: `authoring` (templates, generation, the suite, session files),
`scoring` (hidden validators and metrics), `running` (episodes, the orchestrator, backends,
verified generation, hosted runs, results, replay data), `reporting` (reports, charts,
comparisons) and `server` (`mavswarm serve`, with the MultiUAV-Plat routes in
`server.compat`). Agents, the oracle included, live in the `swarm_agents` package; `cli` is
`mavswarm bench`."""

__all__ = ["authoring", "reporting", "running", "scoring", "server"]

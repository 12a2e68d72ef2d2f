"""The benchmark, cut by concept: `authoring` (templates, generation, the suite, session files),
`scoring` (hidden validators and metrics), `running` (episodes, the orchestrator, backends,
hosted runs, results), `reporting` (reports, charts, comparisons, replay data) and `server`
(`mavswarm serve`, with the MultiUAV-Plat routes in `server.compat`). Agents, the oracle
included, live in `benchmark.agents` and `benchmark.oracle`; `cli` is `mavswarm bench`."""

__all__ = ["authoring", "reporting", "running", "scoring", "server"]

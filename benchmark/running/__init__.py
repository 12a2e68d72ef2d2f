"""Running: one session as an episode (a stepped swarm, a gateway and an agent), the
orchestrator over many sessions with its backends (in-process, processes, Ray), hosted runs for
agents outside the process, and the append-only results log."""

__all__: list[str] = []

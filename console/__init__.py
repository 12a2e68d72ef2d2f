"""The web console: a browser page served by mavswarm's own HTTP server that shows a swarm
live (2D map and 3D view over a WebSocket), replays recorded runs, inspects benchmark results
task by task, commands drones (operators and admins) and edits scenarios. It sits above the
benchmark and below the composition root."""

__all__: list[str] = []

"""The MultiUAV-Plat compatible routes of `mavswarm serve`: the reference platform's agent
commands, world and entity queries, task, session, history and statistics routes, each module one
group of routes, all behind the server's roles and its operator rule."""

__all__: list[str] = []

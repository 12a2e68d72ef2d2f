"""REST API over live benchmark sessions, with API keys mapped to roles (agent, operator,
admin)."""

from benchmark.server.app import create_app
from benchmark.server.hub import Hub, LiveSession, Role

__all__ = ["Hub", "LiveSession", "Role", "create_app"]

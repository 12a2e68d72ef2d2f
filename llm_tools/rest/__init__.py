"""REST API over live benchmark sessions, with API keys mapped to roles (agent, operator,
admin)."""

from llm_tools.rest.app import create_app
from llm_tools.rest.hub import Hub, LiveSession, Role

__all__ = ["Hub", "LiveSession", "Role", "create_app"]

"""The registry's tools served over the Model Context Protocol (official `mcp` SDK).

`build_server(registry, provider)` gives a low-level MCP server whose `tools/list` reports each
tool's strict input schema and the shared output schema, and whose `tools/call` runs the tool
on the `AgentTools` the provider returns at that moment (the current benchmark task, or a live
session). Every call answers with the result dict as structured content plus a text block of
its compact JSON; a result with status "error" or "rejected" is flagged `isError`. Unknown
tools, bad arguments, a spent budget and the absence of a running task come back as such error
results, never as protocol errors, so a model can read them and act.

A registry with the batch tool (`llm_tools.registry.served_registry`) serves it too: several
calls side by side in one request, one result per call.

Transports: `serve_stdio` (one client over stdin/stdout) and `streamable_http_app` (an ASGI
app for Streamable HTTP, e.g. under uvicorn).
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

from agent_contract import AgentTools, BudgetExhausted
from agent_contract.tools import ERROR_STATUS, RESULT_STATUSES
from llm_tools.body_limit import BodyLimit
from llm_tools.input_limits import preview
from llm_tools.registry import ToolRegistry

if TYPE_CHECKING:  # the MCP SDK is imported where a server is built: the CLI starts faster
    import mcp_types as types
    from mcp.server.lowlevel import Server
    from starlette.applications import Starlette

__all__ = ["ERROR_STATUSES", "SERVER_NAME", "ToolsProvider", "build_server", "call_result",
           "mcp_tools", "serve_stdio", "streamable_http_app"]

ToolsProvider = Callable[[], AgentTools | None]
"""Returns the tool surface of the task now running, or None when none is."""

SERVER_NAME = "mavswarm"
ERROR_STATUSES = frozenset({ERROR_STATUS, "rejected"})
_INSTRUCTIONS = ("Tools that command a swarm of drones. Every result has a status "
                 f"({', '.join(RESULT_STATUSES)}) and a message; read them before the next "
                 "call, and call finish once the task is done.")


def mcp_tools(registry: ToolRegistry) -> list[types.Tool]:
    """The registry's tools as MCP tool definitions (input and output schemas included)."""
    import mcp_types as types
    return [types.Tool(name=spec.name, description=spec.description,
                       input_schema=spec.input_schema, output_schema=spec.output_schema)
            for spec in registry.specs()]


def call_result(result: Mapping[str, Any]) -> types.CallToolResult:
    """A tool's result dict as an MCP call result: structured content, its compact JSON as
    text, and `is_error` for an "error" or "rejected" status."""
    if not isinstance(result, Mapping) or not isinstance(result.get("status"), str):
        raise ValueError(f"a tool result needs a string 'status', got {result!r}")
    import mcp_types as types
    structured = dict(result)
    text = json.dumps(structured, separators=(",", ":"), ensure_ascii=False)
    return types.CallToolResult(content=[types.TextContent(text=text)],
                                structured_content=structured,
                                is_error=structured["status"] in ERROR_STATUSES)


def _error(message: str) -> dict[str, Any]:
    return {"status": ERROR_STATUS, "message": message}


def build_server(registry: ToolRegistry, provider: ToolsProvider, *,
                 name: str = SERVER_NAME) -> Server[Any]:
    """An MCP server for `registry`, running each call on `provider()`'s tools."""
    import mcp_types as types
    from mcp.server.lowlevel import Server
    listed = types.ListToolsResult(tools=mcp_tools(registry))

    async def on_list_tools(ctx: Any, params: types.PaginatedRequestParams | None
                            ) -> types.ListToolsResult:
        return listed

    async def on_call_tool(ctx: Any, params: types.CallToolRequestParams
                           ) -> types.CallToolResult:
        return call_result(await _run(registry, provider, params.name, params.arguments))

    def input_schema(tool_name: str) -> Mapping[str, Any] | None:
        spec = registry.get(tool_name)
        return None if spec is None else spec.input_schema

    return Server(name, instructions=_INSTRUCTIONS, on_list_tools=on_list_tools,
                  on_call_tool=on_call_tool, get_tool_input_schema=input_schema)


async def _run(registry: ToolRegistry, provider: ToolsProvider, name: str,
               arguments: Mapping[str, Any] | None) -> dict[str, Any]:
    if registry.get(name) is None:
        known = ", ".join(spec.name for spec in registry.specs())
        return _error(f"unknown tool {preview(name)}; available tools: {known}")
    tools = provider()
    if tools is None:
        return _error(f"{name}: no task is running, so there are no drones to command")
    if tools.spent is not None:
        return _error(f"{name}: the task is over ({tools.spent})")
    try:
        return await registry.call(tools, name, arguments)
    except BudgetExhausted as spent:
        return _error(f"{name}: the task is over ({spent})")


async def serve_stdio(registry: ToolRegistry, provider: ToolsProvider, *,
                      name: str = SERVER_NAME) -> None:
    """Serve one MCP client over this process's stdin/stdout until it disconnects."""
    from mcp.server.stdio import stdio_server
    server = build_server(registry, provider, name=name)
    async with stdio_server() as (read_stream, write_stream):
        await server.run(read_stream, write_stream, server.create_initialization_options())


def streamable_http_app(registry: ToolRegistry, provider: ToolsProvider, *,
                        path: str = "/mcp", host: str = "127.0.0.1",
                        json_response: bool = False, name: str = SERVER_NAME) -> Starlette:
    """An ASGI app serving the tools over Streamable HTTP at `path` (run it with uvicorn;
    its lifespan starts the session manager). `host` is the address it will be served on,
    which sets the SDK's DNS-rebinding protection for local addresses. Request bodies over
    the input limit are refused with HTTP 413."""
    if not path.startswith("/"):
        raise ValueError(f"path must start with '/', got {path!r}")
    server = build_server(registry, provider, name=name)
    app = server.streamable_http_app(streamable_http_path=path, host=host,
                                     json_response=json_response)
    app.add_middleware(BodyLimit)
    return app

"""Agent tools for LLMs: one registry of the agent-side primitives, served to models through
adapters (OpenAI function calling first)."""

from llm_tools.openai_adapter import openai_tools, parse_tool_calls
from llm_tools.registry import OUTPUT_SCHEMA, ToolRegistry, ToolSpec, default_registry

__all__ = ["OUTPUT_SCHEMA", "ToolRegistry", "ToolSpec", "default_registry", "openai_tools",
           "parse_tool_calls"]

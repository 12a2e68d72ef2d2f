"""LLM agents on any OpenAI-compatible chat-completions backend."""

from llm_tools.agents.chat import ChatClient, ModelConfig, ModelError
from llm_tools.agents.react import ReactAgent

__all__ = ["ChatClient", "ModelConfig", "ModelError", "ReactAgent"]

"""LLM agents on any OpenAI-compatible chat-completions backend."""

from llm_tools.agents.chat import ChatClient, ModelConfig, ModelError
from llm_tools.agents.react import ReactAgent
from llm_tools.agents.workflow import WorkflowAgent

__all__ = ["ChatClient", "ModelConfig", "ModelError", "ReactAgent", "WorkflowAgent"]

"""The built-in LLM agents (`react`, `workflow`) and the model seam they think through.

The agents ask a `ChatModel` (conversation and tool schemas in, assistant message and token
use out): `OpenAIChatModel` for any OpenAI-compatible server through the `openai` SDK (made
from a `ModelConfig`), `ScriptedChatModel` in process. They act only through the agent tools,
so this package stays on the agent side: it imports the agent contract and the LLM tools,
nothing of the benchmark or the emulator.
"""

from swarm_agents.llm.model import ChatModel, ModelError, ModelReply, Usage
from swarm_agents.llm.openai_model import ModelConfig, OpenAIChatModel
from swarm_agents.llm.react import ReactAgent
from swarm_agents.llm.scripted import ScriptedChatModel, tool_call
from swarm_agents.llm.workflow import WorkflowAgent

__all__ = ["ChatModel", "ModelConfig", "ModelError", "ModelReply", "OpenAIChatModel",
           "ReactAgent", "ScriptedChatModel", "Usage", "WorkflowAgent", "tool_call"]

"""The agent contract: what an agent is given for one task (its text and budget), the tools it
acts with (the gateway's primitives, counted against that budget, plus `finish`) and the one
method it implements. It sits on the MAVLink gateway and below every agent and server, and it
can reach no validator, hidden task data or ground truth: it imports the gateway alone."""

from agent_contract.protocol import Agent, AgentOptions, AgentTask, BudgetExhausted, TaskBudget
from agent_contract.tools import AgentTools, tool_names

__all__ = ["Agent", "AgentOptions", "AgentTask", "AgentTools", "BudgetExhausted", "TaskBudget",
           "tool_names"]

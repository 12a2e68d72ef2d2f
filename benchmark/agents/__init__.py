"""The agent side of the benchmark: what an agent is given (its task text and its tools) and the
protocol it implements. Nothing here can reach validators, hidden task data or ground truth; a
test checks that these modules never import them."""

from benchmark.agents.noop import NoopAgent
from benchmark.agents.protocol import Agent, AgentTask, BudgetExhausted, TaskBudget
from benchmark.agents.tools import AgentTools

__all__ = ["Agent", "AgentTask", "AgentTools", "BudgetExhausted", "NoopAgent", "TaskBudget"]

"""The oracle agent: it reads a task's hidden plan (or derives one from its checks) and the
whole world, but acts only through the same tools as any agent. Generation uses it to prove
every task solvable."""

from agents.oracle.agent import OracleAgent, OracleCannotPlan, OracleError

__all__ = ["OracleAgent", "OracleCannotPlan", "OracleError"]

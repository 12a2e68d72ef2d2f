"""The oracle agent: it reads a task's hidden plan and the whole world, but acts only through
the same tools as any agent. Generation uses it to prove every task solvable."""

from benchmark.oracle.agent import OracleAgent, OracleError

__all__ = ["OracleAgent", "OracleError"]

"""The oracle agent: it reads a task's hidden plan (or derives one from its checks) and the
whole world, but acts only through the same tools as any agent. Generation uses it to prove
every task solvable. Unlike the other agents it stands on the benchmark's session files and
checks (`tests/import_layers.py`), so no agent-side module may import it."""

from swarm_agents.oracle.agent import OracleAgent, OracleCannotPlan, OracleError
from swarm_agents.oracle.session_oracle import oracle_for_session

__all__ = ["OracleAgent", "OracleCannotPlan", "OracleError", "oracle_for_session"]

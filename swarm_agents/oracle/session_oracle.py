"""The oracle for one session: hand-written plans where tasks carry them, plans derived from
the checks elsewhere; ``MAVSWARM_ORACLE=derived`` turns hand plans off (the derived planner
proved on its own)."""

from __future__ import annotations

import os

from benchmark.authoring.session_file import Session
from swarm_agents.oracle.agent import OracleAgent

__all__ = ["ORACLE_MODES", "ORACLE_MODE_ENV", "oracle_for_session"]

ORACLE_MODE_ENV = "MAVSWARM_ORACLE"
ORACLE_MODES = ("hand", "derived")


def oracle_mode() -> str:
    """hand (default: hand plans first, derived ones as the fallback) or derived."""
    mode = os.environ.get(ORACLE_MODE_ENV, "hand").strip() or "hand"
    if mode not in ORACLE_MODES:
        raise ValueError(f"{ORACLE_MODE_ENV}={mode!r}: must be one of {', '.join(ORACLE_MODES)}")
    return mode


def oracle_for_session(session: Session, mode: str | None = None) -> OracleAgent:
    """The oracle agent for `session` (mode: hand or derived; default from the env)."""
    mode = oracle_mode() if mode is None else mode
    plans = {t.id: t.oracle for t in session.tasks if t.oracle is not None}
    checks = {t.id: t.checks for t in session.tasks if t.checks is not None}
    faulted = {t.id: sorted({f.drone for f in t.faults.failures})
               for t in session.tasks if t.faults is not None}
    return OracleAgent(session.scenario, plans, checks=checks, faulted=faulted,
                       derived_only=mode == "derived")

"""Refusals and STATUSTEXT severities shared by the flight logic."""

from __future__ import annotations

__all__ = ["CommandRefused", "Severity"]


class CommandRefused(Exception):
    """Raised when a command cannot be carried out in the vehicle's present state.

    The message is a short pilot-readable sentence; nothing has changed when it is raised.
    """


class Severity:
    """MAV_SEVERITY levels used in STATUSTEXT."""

    EMERGENCY = 0
    CRITICAL = 2
    ERROR = 3
    WARNING = 4
    NOTICE = 5
    INFO = 6

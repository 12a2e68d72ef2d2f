"""Whether MAVSDK's own log lines reach the terminal.

MAVSDK (the C++ core behind the Python binding, loaded in this process) prints every log
line, debug level included and coloured, to standard output unless a log subscriber takes
it. This module holds one switch per process: off (the default), a subscriber takes every
line and drops it, so nothing is printed; on, there is no subscriber and MAVSDK prints as
it always does. The binding's Python logger (``mavsdk``) follows the same switch.
`FleetConnection.connect` applies the switch before it creates MAVSDK, so
every process that talks MAVLink through the gateway is quiet unless it asked otherwise.

Nothing is undone at exit: the subscriber is called on MAVSDK's threads, and those end with
their MAVSDK instance (`FleetConnection.close`, or the binding's own exit hook for one left
open), before the interpreter finalises.
"""

from __future__ import annotations

import logging
import threading

import mavsdk

__all__ = ["mavsdk_log_enabled", "set_mavsdk_log"]

_lock = threading.Lock()
_enabled = False
_applied: bool | None = None  # what the MAVSDK core was last told (None: nothing yet)


def _drop(_level: mavsdk.LogLevel, _message: str, _file: str | None, _line: int) -> bool:
    return True  # handled: MAVSDK prints nothing


def mavsdk_log_enabled() -> bool:
    """Whether MAVSDK's log lines are printed in this process."""
    return _enabled


def set_mavsdk_log(enabled: bool | None = None) -> None:
    """Print MAVSDK's log lines in this process (True) or drop them (False); None keeps the
    current choice and only makes sure the MAVSDK core follows it."""
    global _enabled, _applied
    with _lock:
        if enabled is not None:
            _enabled = bool(enabled)
        logging.getLogger("mavsdk").setLevel(logging.NOTSET if _enabled
                                              else logging.CRITICAL + 1)
        if _applied is _enabled:
            return
        if _enabled:
            mavsdk.log_unsubscribe()
        else:
            mavsdk.log_subscribe(_drop)
        _applied = _enabled


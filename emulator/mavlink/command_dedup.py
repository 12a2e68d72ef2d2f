"""A vehicle acts on a command once: retransmissions get the first answer again.

MAVSDK (like most ground stations) retransmits a COMMAND_LONG/COMMAND_INT whose ACK it has not
seen, unchanged (`confirmation` stays 0). On a lossy link the first copy may have been executed
and only its ACK lost; executing the copy again would answer, for a take-off, "already in the
air", and the client would report a refusal of something that happened. So a state-changing
command identical to the last one from the same client, arriving in the same physics step (a
lockstep clock stands still while a client exchanges commands) or within the client's
retransmission span while the vehicle is still as the first copy left it, is answered with the
cached result and not executed again. Commands that
only ask for data are always executed (answering them twice is harmless), and camera captures
use the camera protocol's capture sequence number instead (see emulator.mavlink.camera).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

from mavlink_vocabulary import MavCmd, MessageId

__all__ = ["RETRANSMIT_WINDOW_S", "STATEFUL_COMMANDS", "CommandDedup", "command_key"]

RETRANSMIT_WINDOW_S = 2.5  # MAVSDK retransmits 3 times, 0.5 s apart
STATEFUL_COMMANDS = frozenset({
    MavCmd.COMPONENT_ARM_DISARM, MavCmd.NAV_TAKEOFF, MavCmd.NAV_LAND,
    MavCmd.NAV_RETURN_TO_LAUNCH, MavCmd.DO_SET_MODE, MavCmd.DO_REPOSITION, MavCmd.DO_SET_HOME,
    MavCmd.DO_CHANGE_SPEED, MavCmd.CONDITION_YAW, MavCmd.MISSION_START,
    MavCmd.DO_SET_MISSION_CURRENT, MavCmd.INJECT_FAILURE,
})


def command_key(m) -> tuple[object, ...]:
    """What identifies a command's content (NaN parameters compare equal by their bytes)."""
    if m.get_msgId() == MessageId.COMMAND_INT:
        return ("int", m.command, m.frame, target_component(m),
                struct.pack("<4f", m.param1, m.param2, m.param3, m.param4), m.x, m.y,
                struct.pack("<f", m.z))
    return ("long", m.command, target_component(m),
            struct.pack("<7f", m.param1, m.param2, m.param3, m.param4, m.param5, m.param6,
                        m.param7))


def target_component(m) -> int:
    return int(getattr(m, "target_component", 0))


@dataclass(slots=True)
class _Answered:
    key: tuple[object, ...]
    step: int
    wall_s: float
    result: int
    state: object  # the vehicle's state right after it acted


class CommandDedup:
    """The last state-changing command of each client and its result."""

    def __init__(self) -> None:
        self._last: dict[tuple[int, int], _Answered] = {}
        self.duplicates = 0

    def repeat_of(self, source: tuple[int, int], key: tuple[object, ...], step: int,
                  wall_s: float, state: object) -> int | None:
        """The cached result if this command repeats the last one from `source`: in the same
        physics step, or within the retransmission span while the vehicle is still in the
        state the first copy left it in (a command sent again after that goal ended, say a
        move towards an obstacle it already stopped at, is a new command)."""
        last = self._last.get(source)
        if last is None or last.key != key:
            return None
        if last.step != step and (wall_s - last.wall_s > RETRANSMIT_WINDOW_S
                                  or state != last.state):
            return None
        last.wall_s = wall_s  # the window runs from the latest copy
        self.duplicates += 1
        return last.result

    def answered(self, source: tuple[int, int], key: tuple[object, ...], step: int,
                 wall_s: float, result: int, state: object) -> None:
        self._last[source] = _Answered(key, step, wall_s, result, state)

    def forget(self) -> None:
        """The vehicle's state changed otherwise (an operator moved it, a client changed its
        mission or a parameter): a command sent before is no retransmission of the next."""
        self._last.clear()

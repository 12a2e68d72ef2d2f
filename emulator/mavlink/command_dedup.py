"""A vehicle acts on a command once: retransmissions get the first answer again.

MAVSDK (like most ground stations) retransmits a COMMAND_LONG/COMMAND_INT whose ACK it has not
seen, unchanged (`confirmation` stays 0). On a lossy link the first copy may have been executed
and only its ACK lost; executing the copy again would answer, for a take-off, "already in the
air" (and the client would report a refusal of something that happened), or would start a
finished mission over. So a state-changing command identical to the last one from the same
client is answered with the cached result and not executed again when it arrives in the same
physics step (a lockstep clock stands still while a client exchanges commands), or within the
client's retransmission span (wall time, from the latest copy) while nothing but the first
copy's own goal changed the vehicle: no other state-changing command from any client, and no
event that ended or undid that goal otherwise. A stepped clock runs flat out, so within that
span a take-off may have climbed or a mission finished: that is the goal's own course. What
ends it otherwise (`forget`): an obstacle or a failsafe stopping the vehicle (a STATUSTEXT of
WARNING or worse: an identical move sent again after the vehicle stopped at an obstacle is a
new command and flies again), an automatic disarm, an operator's reset, a mission or
parameter change.

A copy that is executed anyway (after `forget`) and *refused*, when the first copy was
accepted and no other state-changing command reached the vehicle since, is answered with the
first copy's result (`acted_before`): its refusal would only say that the first copy acted.
Commands that only ask for data are always executed (answering them twice is harmless), and
camera captures use the camera protocol's capture sequence number instead (see
emulator.mavlink.camera).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

from mavlink_vocabulary import MavCmd, MavResult, MessageId

__all__ = ["RETRANSMIT_WINDOW_S", "STATEFUL_COMMANDS", "CommandDedup", "command_key"]

RETRANSMIT_WINDOW_S = 2.5  # MAVSDK retransmits 3 times, 0.5 s apart
WARNING_SEVERITY = 4  # MAV_SEVERITY_WARNING: an obstacle stop, a failsafe, a failure
AUTO_DISARM_TEXT = "Disarmed: no takeoff"  # armed and never took off: the arming is undone
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
    serial: int  # state-changing commands this vehicle had executed, this one included


class CommandDedup:
    """The last state-changing command of each client and its result."""

    def __init__(self) -> None:
        self._last: dict[tuple[int, int], _Answered] = {}
        self._serial = 0  # state-changing commands executed, from any client
        self.duplicates = 0

    def repeat_of(self, source: tuple[int, int], key: tuple[object, ...], step: int,
                  wall_s: float) -> int | None:
        """The cached result if this command repeats the last one from `source`: in the same
        physics step, or within the retransmission span with no other state-changing command
        since and nothing forgotten (see the module docstring)."""
        last = self._last.get(source)
        if last is None or last.key != key:
            return None
        if last.step != step and (wall_s - last.wall_s > RETRANSMIT_WINDOW_S
                                  or last.serial != self._serial):
            return None
        last.wall_s = wall_s  # the window runs from the latest copy
        self.duplicates += 1
        return last.result

    def acted_before(self, source: tuple[int, int], key: tuple[object, ...], wall_s: float
                     ) -> int | None:
        """For a copy that was executed again and refused: the first copy's result if it was
        accepted, this copy repeats it within the retransmission span (from the latest
        copy), and no other state-changing command reached the vehicle since (the refusal
        then says only that the first copy acted), else None."""
        last = self._last.get(source)
        if last is None or last.key != key or last.result != MavResult.ACCEPTED \
                or last.serial != self._serial or wall_s - last.wall_s > RETRANSMIT_WINDOW_S:
            return None
        last.wall_s = wall_s
        self.duplicates += 1
        return last.result

    def answered(self, source: tuple[int, int], key: tuple[object, ...], step: int,
                 wall_s: float, result: int) -> None:
        self._serial += 1
        self._last[source] = _Answered(key, step, wall_s, result, self._serial)

    def forget(self) -> None:
        """The vehicle's state changed otherwise (an operator moved it, a client changed its
        mission or a parameter, an obstacle or a failsafe stopped it): a command sent before
        is no retransmission of the next."""
        self._last.clear()

    def on_vehicle_text(self, severity: int, text: str) -> None:
        """A STATUSTEXT the vehicle sent of its own accord: forget if the event it reports
        ended or undid a goal otherwise than by its course (see the module docstring)."""
        if severity <= WARNING_SEVERITY or text.startswith(AUTO_DISARM_TEXT):
            self.forget()

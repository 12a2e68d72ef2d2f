"""What a command handler returns: the COMMAND_ACK's result, a reason and what follows.

Handlers do not send anything themselves. The vehicle link acknowledges the command with
`result`, sends `reason` as a STATUSTEXT (a warning when refused, information when accepted),
and only for an accepted command then carries out `follow_ups` in order: messages to send
once, ready messages, and vehicle actions that must come after the ACK (a photo whose report
follows the ACK, a failure that silences the link, which must not silence its own ACK).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from emulator.mavlink.codec import mavlink
from mavlink_vocabulary import MavComponent, MavResult

__all__ = ["Action", "FollowUp", "Reply", "SendMessage", "SendOnce"]


@dataclass(frozen=True, slots=True)
class SendOnce:
    """Send message `msg_id` of the vehicle's state once (a stream or a camera message)."""

    msg_id: int


@dataclass(frozen=True, slots=True)
class SendMessage:
    """Send this ready message as `component`."""

    message: mavlink.MAVLink_message
    component: MavComponent = MavComponent.AUTOPILOT1


@dataclass(frozen=True, slots=True)
class Action:
    """Do this to the vehicle after the ACK went out."""

    run: Callable[[], object]


FollowUp = SendOnce | SendMessage | Action


@dataclass(frozen=True, slots=True)
class Reply:
    result: MavResult
    reason: str | None = None
    follow_ups: tuple[FollowUp, ...] = ()

    @classmethod
    def accepted(cls, *follow_ups: FollowUp) -> Reply:
        return cls(MavResult.ACCEPTED, None, follow_ups)

    @classmethod
    def denied(cls, reason: str | None = None) -> Reply:
        return cls(MavResult.DENIED, reason)

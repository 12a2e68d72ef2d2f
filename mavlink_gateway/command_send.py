"""Sending one command through MAVSDK and reading its answer truthfully on a lossy link.

MAVSDK sends a command again, unchanged, when its ACK does not come within its time-out
(0.5 s); the gateway makes the whole call again when MAVSDK gives up (COMMAND_TRIES in all).
So the answer that comes may be the answer to a later copy, and a later copy may come after the
first one acted: a take-off copy that arrives once the drone has climbed is refused ("already
in the air"). A vehicle that remembers its last command (the emulator does: see
emulator.mavlink.command_dedup) answers such a copy as it answered the first; any other (PX4)
refuses it. A refusal is therefore taken as a refusal only when it answers the only copy sent;
otherwise the command's effect is looked for in fresh telemetry (`Acted`, see
mavlink_gateway.effects): seen, the command
succeeded; not seen, the refusal stands; where the effect cannot be seen, the outcome is
unknown (NoAnswer), never a refusal. A command that may be made again whatever an earlier
copy did (`repeatable`: a mission upload, which replaces the plan with the same one) is made
again instead, and a refusal of a fresh call of it is a refusal: the mission protocol's
answer to a late copy of an earlier upload (MISSION_ACK carries no transfer id) can reach
the next upload's transfer and end it.
"""

from __future__ import annotations

import time
from collections.abc import Awaitable, Callable
from typing import Any

from mavlink_gateway.drone_link import DroneLink
from mavlink_gateway.goals import Goal

__all__ = ["COMMAND_TRIES", "Acted", "NoAnswer", "Refusal", "send_command"]

STATUSTEXT_WAIT_S = 0.05  # how long a refusal waits for the autopilot's STATUSTEXT
# A command MAVSDK got no answer to (it retransmits 3 times itself) is sent again this many
# times in all; the vehicle acts on a command once (emulator.mavlink.command_dedup).
COMMAND_TRIES = 3
SILENT_WALL_S = 5.0  # a drone whose telemetry stopped this long ago is tried only once
# ... once its telemetry is still missing this long after the call: what arrived while this
# process's loop was busy (a long computation, a loaded machine) is taken in first
SILENCE_CHECK_WALL_S = 0.2
# MAVSDK sends a command again after 0.5 s without its ACK: an answer that took this long
# (wall time) may answer a later copy than the first.
RETRANSMITTED_AFTER_S = 0.45
# MAVSDK results that mean "no answer came", not "the vehicle said no"
NO_ANSWER_RESULTS = frozenset({"TIMEOUT", "CONNECTION_ERROR", "NO_SYSTEM", "UNKNOWN", "BUSY"})
# MAVSDK results given both for a refusal and for no answer (a parameter write that timed out)
AMBIGUOUS_RESULTS = frozenset({"PARAMETER_ERROR"})

# Whether fresh telemetry shows the command's effect (None: it cannot show it).
Acted = Callable[[DroneLink], bool | None]


class Refusal(Exception):
    """A precondition failed: the primitive is refused and nothing is sent."""


class NoAnswer(Exception):
    """A command got no answer: whether the drone acted cannot be known."""


async def send_command(link: DroneLink, what: str, call: Callable[[], Awaitable[Any]], *,
                       goal: Goal | None, sent: Callable[[], None],
                       refresh: Callable[[], Awaitable[bool]], acted: Acted | None = None,
                       repeatable: bool = False) -> None:
    """Run a MAVSDK call (`call()` makes it; `sent()` is told before each try, and again
    once it is answered if a later copy than the first may have acted). A refusal by
    the autopilot becomes a Refusal with its reason, unless it may answer a copy sent after
    an earlier one acted (see the module docstring): then `acted(link)`, on telemetry sent
    after `refresh()` (False: none came, nothing can be seen), decides. A call that got no
    answer is made again up to COMMAND_TRIES times in all, then raises NoAnswer; so is a
    `repeatable` one whose refusal may answer a copy. An interrupted `goal` sends nothing
    more."""
    tries = COMMAND_TRIES
    if link.silent_for_s() > SILENT_WALL_S:
        await link.wait_update(link.updates, SILENCE_CHECK_WALL_S)
        if link.silent_for_s() > SILENT_WALL_S:
            tries = 1
    for attempt in range(1, tries + 1):
        if goal is not None:
            goal.check()
        texts = len(link.status_texts)
        sent()
        start = time.monotonic()
        try:
            await call()
            if time.monotonic() - start >= RETRANSMITTED_AFTER_S:
                sent()  # a later copy may be the one that acted: its goal starts by now
            return
        except Refusal:
            raise
        except Exception as error:  # MAVSDK raises one error class per plugin
            result = getattr(getattr(error, "result", None), "name", "UNKNOWN")
            if result in AMBIGUOUS_RESULTS:  # a refusal comes with the autopilot's text
                await _refusal_text(link, texts)
                if len(link.status_texts) == texts:
                    result = "TIMEOUT"
            if result in NO_ANSWER_RESULTS:
                if attempt == tries:
                    raise NoAnswer(f"no answer from {link.drone_id} to {what} after "
                                   f"{attempt} tr{'y' if attempt == 1 else 'ies'} "
                                   f"(the link is lossy or down)") from None
                continue
            await _refusal_text(link, texts)
            reason = next(iter(link.status_texts[texts:]), None)
            detail = reason or str(error)
            slow = time.monotonic() - start >= RETRANSMITTED_AFTER_S
            if slow or (attempt > 1 and not repeatable):
                # Copies were sent: the refusal may answer one that came after another acted.
                fresh = await refresh()
                verdict = acted(link) if acted is not None and fresh else None
                if verdict is True:
                    sent()  # it acted, at some time before now
                    return  # a repeat's refusal is the command's success
                if verdict is None and repeatable and attempt < tries:
                    continue
                if verdict is None:
                    raise NoAnswer(f"{link.drone_id} refused a repeat of {what} ({detail}), "
                                   f"and an earlier copy may have acted") from None
            raise Refusal(f"the autopilot refused {what}: {detail}") from None


async def _refusal_text(link: DroneLink, texts: int) -> None:
    """The autopilot's STATUSTEXT follows its ACK: wait for it, not for a fixed time."""
    deadline = time.monotonic() + STATUSTEXT_WAIT_S
    while len(link.status_texts) == texts:
        left = deadline - time.monotonic()
        if left <= 0.0:
            break
        await link.wait_update(link.updates, left)

"""A refusal that may answer a later copy of a command: a command that can be made again
(a mission upload) is made again; any other becomes an unknown outcome; a refusal of the
only copy sent stays a refusal."""

from __future__ import annotations

import asyncio
from types import SimpleNamespace
from typing import Any

import pytest

from mavlink_gateway import command_send
from mavlink_gateway.command_send import COMMAND_TRIES, NoAnswer, Refusal, send_command

SLOW_S = 0.2  # longer than the patched RETRANSMITTED_AFTER_S: copies may have been sent


class Denied(Exception):
    """What MAVSDK raises when the vehicle answered DENIED."""

    result = SimpleNamespace(name="DENIED")


class FakeLink:
    """The parts of a DroneLink that send_command reads."""

    drone_id = "d1"

    def __init__(self) -> None:
        self.status_texts: list[str] = []
        self.updates = 0

    def silent_for_s(self) -> float:
        return 0.0

    async def wait_update(self, _counter: Any, timeout_s: float) -> None:
        await asyncio.sleep(min(timeout_s, 0.001))


@pytest.fixture(autouse=True)
def _short_retransmission(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(command_send, "RETRANSMITTED_AFTER_S", SLOW_S / 2)
    monkeypatch.setattr(command_send, "STATUSTEXT_WAIT_S", 0.01)  # no text comes here


def _calls(*answers: tuple[float, bool]) -> tuple[list[int], Any]:
    """A call that answers each time (delay_s, refused) in turn, the last one from then on."""
    made: list[int] = []

    async def call() -> None:
        delay_s, refused = answers[min(len(made), len(answers) - 1)]
        made.append(1)
        await asyncio.sleep(delay_s)
        if refused:
            raise Denied

    return made, call


async def _send(call: Any, *, repeatable: bool, acted: Any = None) -> None:
    async def refresh() -> bool:
        return True

    link: Any = FakeLink()
    await send_command(link, "the test mission", call, goal=None, sent=lambda: None,
                       refresh=refresh, acted=acted, repeatable=repeatable)


async def test_a_repeatable_command_refused_after_copies_is_made_again() -> None:
    made, call = _calls((SLOW_S, True), (0.0, False))
    await _send(call, repeatable=True)
    assert len(made) == 2


async def test_a_fresh_refusal_of_a_repeatable_command_is_a_refusal() -> None:
    made, call = _calls((0.0, True))
    with pytest.raises(Refusal, match="refused the test mission"):
        await _send(call, repeatable=True)
    assert len(made) == 1
    made, call = _calls((SLOW_S, True), (0.0, True))  # the second call is answered at once
    with pytest.raises(Refusal):
        await _send(call, repeatable=True)
    assert len(made) == 2


async def test_a_repeatable_command_refused_after_copies_every_time_is_unknown() -> None:
    made, call = _calls((SLOW_S, True))
    with pytest.raises(NoAnswer, match="refused a repeat of the test mission"):
        await _send(call, repeatable=True)
    assert len(made) == COMMAND_TRIES


async def test_any_other_command_refused_after_copies_is_unknown_at_once() -> None:
    made, call = _calls((SLOW_S, True), (0.0, False))
    with pytest.raises(NoAnswer, match="an earlier copy may have acted"):
        await _send(call, repeatable=False)
    assert len(made) == 1
    made, call = _calls((SLOW_S, True))
    await _send(call, repeatable=False, acted=lambda _link: True)  # its effect is seen
    assert len(made) == 1

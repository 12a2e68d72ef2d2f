"""A lockstep halt explained by a STATUSTEXT the client never got (lost on the way, or dropped
by MAVSDK under load) is judged at the same halt all the same: the gateway asks the swarm for
the texts of that instant again, and records a repeat it already has only once."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import pytest

from benchmark.authoring.session_file import load_session
from benchmark.running.episode import swarm_gateway
from mavlink_gateway import Status
from mavlink_gateway.drone_link import DroneLink
from mavlink_gateway.pacing import Thinker, run_as
from tests.cli_fixtures import ROOT

SESSION = ROOT / "benchmark" / "sessions" / "target_assignment-easy-1.json"
CRITICAL = "Critical battery"


async def _hover_into_the_failsafe() -> tuple[Any, float, list[str]]:
    session = load_session(SESSION)
    async with swarm_gateway(session, lockstep=True) as (_swarm, services, gateway):
        async def agent() -> tuple[Any, float]:  # one thread of control, as a tool call's
            assert (await gateway.take_off("d1", 10.0)).ok
            x_m, y_m, _ = gateway.drones["d1"].position_m
            assert (await gateway.move_to("d1", x_m + 80.0, y_m, 10.0)).ok  # away from home
            services.operator_reset_batteries(7.3)  # the critical level a few seconds on
            return await gateway.hover("d1", 60.0), services.clock_s()

        thinker = Thinker(services)
        try:
            outcome, halted_s = await run_as(thinker, agent())
        finally:
            thinker.close()
        return outcome, halted_s, list(gateway.drones["d1"].status_texts)


async def test_a_lost_failsafe_text_is_asked_for_again_at_the_halt(
        monkeypatch: pytest.MonkeyPatch) -> None:
    heard, halted_s, texts = await _hover_into_the_failsafe()
    assert heard.status is Status.BLOCKED
    assert heard.message.startswith(f"hover stopped: {CRITICAL} 7%: returning home")

    receive = DroneLink._on_status_text
    lost: list[str] = []

    def lose_the_first(link: DroneLink, s: Any) -> None:
        if CRITICAL in s.text and not lost:
            lost.append(s.text)  # as if MAVSDK had dropped the callback
            return
        receive(link, s)

    monkeypatch.setattr(DroneLink, "_on_status_text", lose_the_first)
    again, halted_again_s, texts_again = await _hover_into_the_failsafe()
    assert lost, "the failsafe's text never came"
    assert (again.status, again.message) == (heard.status, heard.message)
    assert halted_again_s == halted_s  # the same halt, not a later one
    assert sum(CRITICAL in t for t in texts_again) == sum(CRITICAL in t for t in texts) == 1


def test_a_repeat_asked_for_is_recorded_once() -> None:
    link = DroneLink.__new__(DroneLink)
    link.status_texts, link.texts_received, link.failure = ["Takeoff detected"], 0, None
    link.repeats_since = None
    link._on_status_text(SimpleNamespace(text="Critical battery 7%: returning home"))
    link.repeats_since = 1  # the texts since the wait began
    for text in ("Critical battery 7%: returning home", "Takeoff detected", "Landing"):
        link._on_status_text(SimpleNamespace(text=text))
    link.repeats_since = None
    link._on_status_text(SimpleNamespace(text="Landing"))
    assert link.status_texts == ["Takeoff detected", "Critical battery 7%: returning home",
                                 "Takeoff detected", "Landing", "Landing"]
    assert link.texts_received == 5


def test_a_motor_failure_tells_one_report_and_keeps_telling_it_while_it_holds() -> None:
    """The report a halt's burst repeats is the one the failure began with while it holds, so
    whichever copy a client gets first, it reads the same words."""
    from emulator.flight.fleet import Fleet
    from tests.scenario_fixtures import tiny_scenario, vehicle

    fleet = Fleet(tiny_scenario([vehicle(1)]))
    ap = fleet.autopilots[0]
    said: list[str] = []
    ap.listener.on_statustext = lambda _severity, text: said.append(text)
    ap.arm()
    ap.takeoff(10.0)
    while fleet.any_busy:
        fleet.run(50)
    ap.failures.fail("motor", "test")
    assert [t for t in said if t.startswith("Motor failure")] == [
        "Motor failure: vehicle going down"]
    assert ap.failures.standing_report()[1] == "Motor failure: vehicle going down"
    while ap.in_air:
        fleet.run(50)
    assert ap.failures.standing_report()[1] == "Motor failure: vehicle out of service"

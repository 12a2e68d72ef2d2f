"""Outcomes that never lie on a lossy link: the answer to a repeat of a command that acted.

A ground station sends a command again when its ACK is lost. Under a stepped clock (flat out)
the first copy's goal may have run its whole course before the copy arrives: a take-off copy
then finds the drone in the air, a landing copy finds it down. The vehicle answers such a
copy as it answered the first (emulator.mavlink.command_dedup), and the gateway, facing a
vehicle that does not (PX4 executes every copy), looks for the command's effect before it
calls a refusal a refusal (mavlink_gateway.command_send): an outcome is `ok` when the command
acted, `unknown` when that cannot be known, and never `rejected` when the drone did act.
"""

from __future__ import annotations

import asyncio
import math
from collections import Counter
from pathlib import Path
from typing import Any

import pytest

from emulator.flight.autopilot_mission import MissionState
from emulator.flight.modes import FlightMode
from emulator.link_faults import LinkFaults, LinkProfile
from emulator.mavlink import vehicle_link
from emulator.mavlink.command_dedup import RETRANSMIT_WINDOW_S, CommandDedup
from emulator.world import Obstacle
from mavlink_gateway import Status
from mavlink_vocabulary import MavCmd, MavFrame, MavResult
from tests.bench_fixtures import small_session
from tests.gateway_fixtures import gateway_session
from tests.memory_link import MemoryLink
from tests.scenario_fixtures import tiny_scenario, vehicle
from tests.test_serve_faults import AGENT, _serving

NAN7 = (math.nan,) * 7


# ------------------------------------------------------------ the vehicle (in memory)
def _copy(link: MemoryLink, frame: bytes, *, after_s: float) -> tuple[list[int], list[str]]:
    """Send `frame` again `after_s` wall seconds later (the physics ran meanwhile, as a
    stepped clock runs flat out): (the ACK results, the STATUSTEXTs) it brought."""
    link.now += after_s
    since = link.send_raw(frame)
    acks = [m.result for m in link.messages("COMMAND_ACK", since=since)]
    texts = [m.text for m in link.messages("STATUSTEXT", since=since)]
    return acks, texts


def _run_physics(link: MemoryLink, seconds: float) -> None:
    link.fleet.run(round(seconds / link.fleet.dt_s))


def _command(link: MemoryLink, command: int, *params: float) -> bytes:
    p = [*params, *([0.0] * (7 - len(params)))]
    return link.pack(link.mav.command_long_encode(1, 1, command, 0, *p))


def test_a_take_off_copy_after_the_climb_is_answered_as_the_first_copy() -> None:
    link = MemoryLink(1)
    ap = link.fleet.autopilots[0]
    assert link.command_long(1, MavCmd.COMPONENT_ARM_DISARM, 1.0).result == MavResult.ACCEPTED
    takeoff = _command(link, MavCmd.NAV_TAKEOFF, *NAN7)
    assert _copy(link, takeoff, after_s=0.0)[0] == [MavResult.ACCEPTED]
    _run_physics(link, 30.0)  # the whole climb, while the ACK is lost on the way
    assert ap.in_air and ap.mode is FlightMode.HOLD
    # MAVSDK's retransmission 0.5 s later: the first copy's answer, no refusal, no second act
    assert _copy(link, takeoff, after_s=0.5) == ([MavResult.ACCEPTED], [])
    assert link.swarm.links[0].dedup.duplicates == 1
    assert len(link.swarm.recorder.events("d1", kinds=("takeoff",))) == 1
    # A copy after the retransmission span is a new command: refused, as the vehicle is up.
    acks, texts = _copy(link, takeoff, after_s=RETRANSMIT_WINDOW_S + 0.1)
    assert acks == [MavResult.DENIED] and texts == ["Takeoff refused: already in the air"]


def test_a_landing_copy_after_touchdown_is_answered_as_the_first_copy() -> None:
    link = MemoryLink(1)
    ap = link.fleet.autopilots[0]
    link.arm_and_take_off(1)
    land = _command(link, MavCmd.NAV_LAND, *NAN7)
    assert _copy(link, land, after_s=0.0)[0] == [MavResult.ACCEPTED]
    _run_physics(link, 60.0)
    assert not ap.in_air
    acks, texts = _copy(link, land, after_s=0.5)
    assert acks == [MavResult.ACCEPTED] and not any("refused" in t for t in texts), texts
    rtl = _command(link, MavCmd.NAV_RETURN_TO_LAUNCH)
    link.arm_and_take_off(1)
    assert _copy(link, rtl, after_s=0.0)[0] == [MavResult.ACCEPTED]
    _run_physics(link, 120.0)
    assert not ap.in_air
    acks, texts = _copy(link, rtl, after_s=1.0)
    assert acks == [MavResult.ACCEPTED] and not any("refused" in t for t in texts), texts


def test_a_refused_copy_stays_refused_when_another_command_came_between() -> None:
    link = MemoryLink(1)
    link.arm_and_take_off(1)
    land = _command(link, MavCmd.NAV_LAND, *NAN7)
    assert _copy(link, land, after_s=0.0)[0] == [MavResult.ACCEPTED]
    _run_physics(link, 60.0)
    # another state-changing command reached the vehicle: the next land is a new command
    assert link.command_long(1, MavCmd.COMPONENT_ARM_DISARM, 1.0).result == MavResult.ACCEPTED
    acks, texts = _copy(link, land, after_s=0.2)
    assert acks == [MavResult.DENIED] and texts == ["Land refused: vehicle is on the ground"]
    # a command refused the first time is refused again, copy or not
    bad = _command(link, MavCmd.COMPONENT_ARM_DISARM, 7.0)
    assert _copy(link, bad, after_s=0.0)[0] == [MavResult.DENIED]
    assert _copy(link, bad, after_s=0.5)[0] == [MavResult.DENIED]


def test_a_mission_start_copy_after_the_mission_finished_does_not_fly_it_again() -> None:
    link = MemoryLink(1)
    ap = link.fleet.autopilots[0]
    link.arm_and_take_off(1)
    lat, lon, _ = link.fleet.world.origin.to_geodetic(0.0, 30.0, 0.0)
    item = link.mission_item(1, 0, MavCmd.NAV_WAYPOINT, lat, lon, 10.0)
    assert link.upload_mission(1, [item]).type == 0
    start = _command(link, MavCmd.MISSION_START, 0, 0)
    assert _copy(link, start, after_s=0.0)[0] == [MavResult.ACCEPTED]
    _run_physics(link, 60.0)  # the whole mission, while the ACK is lost on the way
    assert ap.mission.state == MissionState.COMPLETE, ap.mission.state
    assert _copy(link, start, after_s=0.5)[0] == [MavResult.ACCEPTED]
    starts = link.swarm.recorder.events("d1", kinds=("mission_start",))
    assert len(starts) == 1, starts  # not started over
    assert ap.mission.state == MissionState.COMPLETE


def test_the_same_move_sent_again_after_an_obstacle_stop_flies_again() -> None:
    wall = Obstacle.disc("o-wall", "Wall", (0.0, 60.0), 10.0, height_m=0.0)
    link = MemoryLink(scenario=tiny_scenario([vehicle(1)], obstacles=[wall]))
    ap = link.fleet.autopilots[0]
    link.arm_and_take_off(1)
    lat, lon, alt = link.fleet.world.origin.to_geodetic(0.0, 100.0, 10.0)
    move = link.pack(link.mav.command_int_encode(
        1, 1, MavFrame.GLOBAL, MavCmd.DO_REPOSITION, 0, 0, -1.0, 0.0, 0.0, math.nan,
        round(lat * 1e7), round(lon * 1e7), alt))
    assert _copy(link, move, after_s=0.0)[0] == [MavResult.ACCEPTED]
    _run_physics(link, 60.0)
    stops = link.swarm.recorder.events("d1", kinds=("obstacle_stop",))
    assert len(stops) == 1 and ap.position_m[1] < 50.0
    # The obstacle stopped the goal: the same command again is a new one, executed (it meets
    # the obstacle at once and stops again), not a retransmission answered from the cache.
    duplicates = link.swarm.links[0].dedup.duplicates
    assert _copy(link, move, after_s=0.5)[0] == [MavResult.ACCEPTED]
    _run_physics(link, 5.0)
    assert link.swarm.links[0].dedup.duplicates == duplicates
    assert len(link.swarm.recorder.events("d1", kinds=("obstacle_stop",))) == 2


# ----------------------------------------------------- the gateway (MAVSDK over UDP)
class AckLoss:
    """Loses the ACK of the next accepted copy of each command put in `next_lost`, or the
    next copy itself of each command in `next_unheard` (lost on its way up), and counts
    what it lost."""

    def __init__(self) -> None:
        self.next_lost: set[int] = set()
        self.next_unheard: set[int] = set()
        self.dropped: Counter[int] = Counter()


@pytest.fixture
def ack_loss(monkeypatch: pytest.MonkeyPatch) -> AckLoss:
    """The vehicle loses chosen ACKs (AckLoss) and executes every copy of a command it gets,
    as PX4 does (no de-duplication)."""
    loss = AckLoss()
    ack = vehicle_link.VehicleLink._ack

    def lose(self: Any, m: Any, command: int, result: int, component: int) -> None:
        if command in loss.next_lost and result == MavResult.ACCEPTED:
            loss.next_lost.discard(command)
            loss.dropped[command] += 1
            return
        ack(self, m, command, result, component)

    on_command = vehicle_link.VehicleLink._on_command

    def unheard(self: Any, m: Any, args: Any) -> None:
        if args.command in loss.next_unheard:
            loss.next_unheard.discard(args.command)
            loss.dropped[args.command] += 1
            return
        on_command(self, m, args)

    monkeypatch.setattr(vehicle_link.VehicleLink, "_ack", lose)
    monkeypatch.setattr(vehicle_link.VehicleLink, "_on_command", unheard)
    monkeypatch.setattr(CommandDedup, "repeat_of", lambda *a, **k: None)
    monkeypatch.setattr(CommandDedup, "acted_before", lambda *a, **k: None)
    return loss


@pytest.mark.mavsdk
async def test_the_gateway_calls_a_refused_repeat_of_a_command_that_acted_a_success(
        ack_loss: AckLoss) -> None:
    async with gateway_session(tiny_scenario([vehicle(1)])) as s:
        ap = s.ap("d1")
        ack_loss.next_lost.add(MavCmd.NAV_TAKEOFF)
        out = await s.gw.take_off("d1", 10.0)
        assert ack_loss.dropped[MavCmd.NAV_TAKEOFF] == 1
        assert out.status is Status.OK and out.message == "d1 took off to 10.0 m", out
        assert ap.in_air
        assert (await s.gw.move_to("d1", 30.0, 0.0, 10.0)).ok
        ack_loss.next_lost.add(MavCmd.NAV_LAND)
        out = await s.gw.land("d1")
        assert ack_loss.dropped[MavCmd.NAV_LAND] == 1
        assert out.status is Status.OK and out.message.startswith("d1 landed at (30.0, 0.0)"), out
        assert not ap.in_air
        assert (await s.gw.take_off("d1", 10.0)).ok
        ack_loss.next_lost.add(MavCmd.DO_SET_MODE)  # MAVSDK's return to launch: mode RTL
        out = await s.gw.return_home("d1")
        assert ack_loss.dropped[MavCmd.DO_SET_MODE] == 1
        assert out.status is Status.OK and "returned home" in out.message, out
        assert not ap.in_air and math.dist(ap.position_m[:2], (0.0, 0.0)) < 1.0


@pytest.mark.mavsdk
async def test_a_budget_counts_from_the_copy_that_acted(ack_loss: AckLoss) -> None:
    # d2 flies far, so the stepped clock runs flat out while d1's first take-off copy is lost
    # on its way up and MAVSDK sends it again 0.5 s of wall time later: minutes of simulated
    # time. d1's take-off budget (130 s) must count from the copy that acted, not the lost
    # one (the climb to 100 m is still on when the answer comes).
    async with gateway_session(tiny_scenario([vehicle(1), vehicle(2, 50.0, 0.0)])) as s:
        assert (await s.gw.take_off("d2", 10.0)).ok
        far = asyncio.create_task(s.gw.move_to("d2", 5000.0, 0.0, 10.0))
        ack_loss.next_unheard.add(MavCmd.NAV_TAKEOFF)
        t0 = s.now_s
        out = await s.gw.take_off("d1", 100.0)
        assert ack_loss.dropped[MavCmd.NAV_TAKEOFF] == 1
        assert s.now_s - t0 > 130.0  # the clock ran past the budget while the copy was lost
        assert out.status is Status.OK and out.message == "d1 took off to 100.0 m", out
        assert (await far).ok


@pytest.mark.mavsdk
async def test_a_mission_whose_last_item_reached_was_lost_still_ends_ok(
        monkeypatch: pytest.MonkeyPatch) -> None:
    # MISSION_ITEM_REACHED comes once per item; lost, MAVSDK never calls the mission finished.
    # MISSION_CURRENT (periodic) still says it is complete.
    monkeypatch.setattr(vehicle_link.VehicleLink, "on_mission_item_reached",
                        lambda self, seq: setattr(self, "last_reached", seq))
    async with gateway_session(tiny_scenario([vehicle(1)])) as s:
        assert (await s.gw.take_off("d1", 10.0)).ok
        out = await asyncio.wait_for(s.gw.hover("d1", 5.0), 20.0)
        assert out.status is Status.OK and out.message.startswith("d1 hovered 5 s"), out
        out = await asyncio.wait_for(
            s.gw.move_along_path("d1", [[0.0, 30.0], [30.0, 30.0]]), 20.0)
        assert out.status is Status.OK and "path of 2 waypoints" in out.message, out
        assert math.dist(s.ap("d1").position_m[:2], (30.0, 30.0)) < 1.0


# ------------------------------------------ every call against the truth, stepped clock
LOSSY = LinkProfile(loss=0.2)
RATES = {"HEARTBEAT": 1.0, "EXTENDED_SYS_STATE": 1.0, "SYS_STATUS": 1.0,
         "BATTERY_STATUS": 1.0, "HOME_POSITION": 0.5, "GLOBAL_POSITION_INT": 2.0}


async def _chains(s: Any, drone: str, chains: int, tally: Counter[str]) -> None:
    """take_off, move_to, take_photo, hover, move_along_path (missions), return_home or land,
    each outcome judged at once against the drone's ground truth."""
    gw, ap = s.gw, s.ap(drone)
    for k in range(chains):
        x, y, _ = ap.position_m

        def judge(name: str, status: Status, acted: bool, finished: bool | None = None) -> None:
            """A refusal is false if the drone acted on the call; a timeout (\"did not finish
            within its budget\") if it finished (`finished`, where it differs from acting)."""
            tally[f"{name}:{status.value}"] += 1
            done = acted if finished is None else finished
            if (status is Status.REJECTED and acted) or (status is Status.TIMEOUT and done):
                tally["false"] += 1
                tally[f"false {name}"] += 1

        out = await gw.take_off(drone, 10.0)
        judge("take_off", out.status, ap.in_air)
        if not ap.in_air:
            continue
        out = await gw.move_to(drone, x + (60.0 if k % 2 == 0 else -60.0), y, 10.0)
        judge("move_to", out.status, abs(ap.position_m[0] - x) > 59.0)
        photos = ap.photo_count
        out = await gw.take_photo(drone)
        judge("take_photo", out.status, ap.photo_count > photos)
        path = [[x, y + 20.0], [x + 20.0, y + 20.0]]
        for name, args in (("hover", (5.0,)), ("move_along_path", (path,))):
            t0 = s.now_s
            out = await getattr(gw, name)(drone, *args)
            t1 = s.now_s
            started = s.swarm.recorder.events(drone, t0_s=t0, kinds=("mission_start",))
            # Under the stepped clock the other drones keep simulated time running while a
            # lost upload is sent again in wall time: the budget may run out on a mission that
            # started, which is a timeout, not a false one.
            completed = s.swarm.recorder.events(drone, t0_s=t0, t1_s=t1,
                                                kinds=("mission_complete",))
            judge(name, out.status, bool(started), bool(completed))
        if k % 2:
            out = await gw.return_home(drone)
            judge("return_home", out.status, ap.mode in (FlightMode.RTL, FlightMode.LAND)
                  or not ap.in_air)
        out = await gw.land(drone) if ap.in_air else None
        if out is not None:
            judge("land", out.status, not ap.in_air or ap.mode is FlightMode.LAND)
        while ap.in_air:  # left flying by an unknown outcome: down for the next chain
            await gw.land(drone)


@pytest.mark.mavsdk
@pytest.mark.slow
async def test_no_call_is_rejected_when_it_acted_on_a_lossy_link_under_the_stepped_clock():
    sc = tiny_scenario([vehicle(1), vehicle(2, 200.0, 0.0), vehicle(3, 0.0, 200.0)])
    tally: Counter[str] = Counter()
    async with gateway_session(sc, telemetry_hz=RATES) as s:
        s.swarm.set_link_faults(LinkFaults(seed=7, uplink=LOSSY, downlink=LOSSY))
        await asyncio.gather(*(_chains(s, d, 3, tally) for d in ("d1", "d2", "d3")))
    calls = sum(v for k, v in tally.items() if ":" in k)
    assert calls >= 30, tally
    assert tally["false"] == 0, tally


@pytest.mark.mavsdk
@pytest.mark.slow
async def test_serve_agents_over_rest_get_no_false_refusal_on_a_lossy_link(tmp_path: Path):
    # `mavswarm serve --clock stepped` over real HTTP, as an external agent drives it, one
    # request per drone at once (under the default lockstep clock one agent key is one thread
    # of control, so concurrent calls take the batch tool or a key per drone).
    data = {**small_session(["takeoff_hold"]), "link_faults": {"seed": 5, "loss": 0.2}}
    tally: Counter[str] = Counter()
    async with _serving(tmp_path, data, clock="stepped") as (client, live):
        base = f"/sessions/{live.id}/tools"
        drones = [d["id"] for d in data["drones"]][:3]

        async def fly(drone: str) -> None:
            ap = live.swarm.fleet.autopilots[live.swarm.fleet.index_by_id[drone]]
            for _ in range(3):
                for name, args, acted in (
                        ("take_off", {"altitude_m": 10.0}, lambda: ap.in_air),
                        ("land", {}, lambda: not ap.in_air or ap.mode is FlightMode.LAND)):
                    answer = await client.post(f"{base}/{name}", headers=AGENT,
                                               json={"drone_id": drone, **args})
                    assert answer.status_code == 200, answer.text
                    status = answer.json()["status"]
                    tally[f"{name}:{status}"] += 1
                    if acted() and status in ("rejected", "timeout"):
                        tally["false"] += 1

        await asyncio.gather(*(fly(d) for d in drones))
    assert sum(v for k, v in tally.items() if ":" in k) == 18, tally
    assert tally["false"] == 0, tally

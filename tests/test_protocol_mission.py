"""The mission protocol over real UDP: upload, download, clear, failures and a flown mission."""

from __future__ import annotations

import asyncio

import pytest

from emulator.geo import DEFAULT_ORIGIN
from mavlink_vocabulary import MavMissionResult
from tests.mavlink_client import MavClient, running_swarm

M = MavMissionResult
ACCEPTED, UNSUPPORTED, INVALID_SEQUENCE, DENIED, CANCELLED = (
    M.ACCEPTED, M.UNSUPPORTED, M.INVALID_SEQUENCE, M.DENIED, M.OPERATION_CANCELLED)
WAYPOINT, LAND, TAKEOFF = 16, 21, 22
FENCE, RALLY = 1, 2


def geo(x_m: float, y_m: float) -> tuple[float, float]:
    lat, lon, _ = DEFAULT_ORIGIN.to_geodetic(x_m, y_m, 0.0)
    return lat, lon


def mission(client: MavClient, system: int, points: list[tuple[float, float, float]],
            *, takeoff: bool = True, land: bool = False) -> list:
    """Items in MAVSDK mission_raw form: frame 6 (relative altitude), x/y as deg * 1e7."""
    items = []
    if takeoff:
        items.append(client.mission_item(system, 0, TAKEOFF, 0.0, 0.0, 10.0))
    for x, y, z in points:
        lat, lon = geo(x, y)
        items.append(client.mission_item(system, len(items), WAYPOINT, lat, lon, z))
    if land:
        items.append(client.mission_item(system, len(items), LAND, 0.0, 0.0, 0.0))
    return items


def summary(items) -> list[tuple]:
    return [(m.seq, m.command, m.frame, m.x, m.y, round(m.z, 3)) for m in items]


async def test_upload_download_and_clear() -> None:
    async with running_swarm(2) as (swarm, client):
        items = mission(client, 1, [(0, 30, 10), (20, 30, 12), (20, 0, 15)], land=True)
        ack = await client.upload_mission(1, items)
        assert (ack.type, ack.mission_type) == (ACCEPTED, 0)
        assert (ack.target_system, ack.target_component) == (255, 190)
        assert swarm.fleet.autopilots[0].mission.total == len(items)
        assert swarm.fleet.autopilots[1].mission.total == 0

        got = await client.download_mission(1)
        assert summary(got) == summary(items)
        assert [m.get_srcSystem() for m in got] == [1] * len(items)
        current = await client.wait_for("MISSION_CURRENT", system=1, timeout=2.0,
                                        since=0, where=lambda m: m.total == len(items))
        assert current.seq == 0
        # legacy MISSION_REQUEST gets float MISSION_ITEM with degrees
        client.send(client.mav.mission_request_encode(1, 1, 1, 0))
        legacy = await client.wait_for("MISSION_ITEM", system=1)
        assert legacy.x == pytest.approx(items[1].x * 1e-7, abs=5e-6)  # float32 degrees
        # a request past the end is an INVALID_SEQUENCE
        client.send(client.mav.mission_request_int_encode(1, 1, len(items), 0))
        assert (await client.wait_for("MISSION_ACK", system=1)).type == INVALID_SEQUENCE

        assert await client.download_mission(2) == []

        client.send(client.mav.mission_clear_all_encode(1, 1, 0))
        ack = await client.wait_for("MISSION_ACK", system=1)
        assert ack.type == ACCEPTED
        assert await client.download_mission(1) == []
        assert swarm.fleet.autopilots[0].mission.total == 0


@pytest.mark.slow
async def test_stalled_upload_is_re_requested_then_cancelled_keeping_the_old_mission() -> None:
    async with running_swarm(1) as (swarm, client):
        old = mission(client, 1, [(0, 20, 10)])
        assert (await client.upload_mission(1, old)).type == ACCEPTED
        new = mission(client, 1, [(0, 50, 10), (10, 50, 10), (10, 0, 10)])
        client.send(client.mav.mission_count_encode(1, 1, len(new), 0))
        start = client.mark
        for seq in (0, 1):
            req = await client.wait_for("MISSION_REQUEST_INT", system=1, since=start,
                                        where=lambda m, s=seq: m.seq == s)
            assert req.mission_type == 0
            client.send_raw(client.pack(new[seq]))
        # ... and the client goes silent
        ack = await client.wait_for("MISSION_ACK", system=1, since=start, timeout=6.0)
        assert ack.type == CANCELLED
        rerequests = client.messages("MISSION_REQUEST_INT", system=1, since=start,
                                     where=lambda m: m.seq == 2)
        assert len(rerequests) >= 3
        assert client.messages("STATUSTEXT", system=1, since=start,
                               where=lambda m: "old mission" in m.text)
        assert summary(await client.download_mission(1)) == summary(old)
        assert swarm.fleet.autopilots[0].mission.total == len(old)
        # and re-requests stop once cancelled
        mark = len(client.received)
        await client.expect_none("MISSION_REQUEST_INT", within=0.7, since=mark)
        # items arriving after the cancel are refused
        client.send(new[2])
        assert (await client.wait_for("MISSION_ACK", system=1)).type == DENIED


async def test_upload_restarted_by_a_new_count_completes_with_the_new_mission() -> None:
    async with running_swarm(1) as (_swarm, client):
        old = mission(client, 1, [(0, 20, 10)])
        assert (await client.upload_mission(1, old)).type == ACCEPTED
        abandoned = mission(client, 1, [(0, 60, 10), (10, 60, 10), (20, 60, 10)])
        client.send(client.mav.mission_count_encode(1, 1, len(abandoned), 0))
        await client.wait_for("MISSION_REQUEST_INT", system=1, where=lambda m: m.seq == 0)
        client.send(abandoned[0])
        await client.wait_for("MISSION_REQUEST_INT", system=1, where=lambda m: m.seq == 1)

        fresh = mission(client, 1, [(30, 30, 20)], takeoff=False)
        start = len(client.received)
        ack = await client.upload_mission(1, fresh)
        assert ack.type == ACCEPTED
        assert client.messages("STATUSTEXT", system=1, since=start,
                               where=lambda m: "restarted" in m.text)
        assert summary(await client.download_mission(1)) == summary(fresh)
        # no leftover of the abandoned upload: no re-requests, no late ACK
        await client.expect_none(("MISSION_REQUEST_INT", "MISSION_ACK"), within=0.8,
                                 since=len(client.received))


async def test_unsupported_item_is_refused_and_nothing_is_stored() -> None:
    async with running_swarm(1) as (_swarm, client):
        old = mission(client, 1, [(0, 20, 10)])
        assert (await client.upload_mission(1, old)).type == ACCEPTED
        bad = mission(client, 1, [(0, 30, 10), (0, 40, 10)])
        lat, lon = geo(0, 35)
        bad[1] = client.mission_item(1, 1, 183, lat, lon, 10.0)  # DO_SET_SERVO
        start = len(client.received)
        ack = await client.upload_mission(1, bad)
        assert ack.type == UNSUPPORTED
        # refused at item 1: item 2 was never requested
        assert not client.messages("MISSION_REQUEST_INT", system=1, since=start,
                                   where=lambda m: m.seq == 2)
        text = await client.wait_for("STATUSTEXT", system=1, since=start)
        assert "183" in text.text
        assert summary(await client.download_mission(1)) == summary(old)

        # unsupported frame and out-of-range latitude are refused the same way
        bad = mission(client, 1, [(0, 30, 10)])
        bad[1] = client.mission_item(1, 1, WAYPOINT, 47.4, 8.5, 10.0, frame=1)
        assert (await client.upload_mission(1, bad)).type == MavMissionResult.UNSUPPORTED_FRAME
        bad[1] = client.mission_item(1, 1, WAYPOINT, 91.0, 8.5, 10.0)
        assert (await client.upload_mission(1, bad)).type == MavMissionResult.INVALID_PARAM5_X
        bad[1] = client.mission_item(1, 1, WAYPOINT, *geo(0, 30), 500.0)  # above the ceiling
        assert (await client.upload_mission(1, bad)).type == MavMissionResult.INVALID_PARAM7
        assert summary(await client.download_mission(1)) == summary(old)


async def test_out_of_order_and_duplicate_items_are_re_requested() -> None:
    async with running_swarm(1) as (_swarm, client):
        items = mission(client, 1, [(0, 30, 10), (10, 30, 10), (10, 0, 10)])
        client.send(client.mav.mission_count_encode(1, 1, len(items), 0))
        start = client.mark
        await client.wait_for("MISSION_REQUEST_INT", system=1, where=lambda m: m.seq == 0)
        client.send(items[0])
        await client.wait_for("MISSION_REQUEST_INT", system=1, where=lambda m: m.seq == 1)
        client.send(items[2])  # out of order
        await client.wait_for("MISSION_REQUEST_INT", system=1, where=lambda m: m.seq == 1,
                              timeout=0.2)
        client.send(items[0])  # duplicate
        await client.wait_for("MISSION_REQUEST_INT", system=1, where=lambda m: m.seq == 1,
                              timeout=0.2)
        for seq in range(1, len(items)):
            client.send(items[seq])
            if seq < len(items) - 1:
                await client.wait_for("MISSION_REQUEST_INT", system=1,
                                      where=lambda m, s=seq: m.seq == s + 1)
        ack = await client.wait_for("MISSION_ACK", system=1)
        assert ack.type == ACCEPTED
        assert not client.messages("MISSION_ACK", system=1, since=start,
                                   where=lambda m: m.type != ACCEPTED)
        assert summary(await client.download_mission(1)) == summary(items)


async def test_fence_and_rally_lists_start_empty_apart_from_the_mission() -> None:
    async with running_swarm(1) as (swarm, client):
        for mission_type in (FENCE, RALLY):
            client.send(client.mav.mission_request_list_encode(1, 1, mission_type))
            count = await client.wait_for("MISSION_COUNT", system=1)
            assert (count.count, count.mission_type) == (0, mission_type)
            # clearing or uploading an empty list is fine; a non-empty one is requested
            # item by item in its own type (tests/test_px4_geofence.py uploads them)
            client.send(client.mav.mission_count_encode(1, 1, 0, mission_type))
            ack = await client.wait_for("MISSION_ACK", system=1)
            assert (ack.type, ack.mission_type) == (ACCEPTED, mission_type)
            client.send(client.mav.mission_count_encode(1, 1, 3, mission_type))
            req = await client.wait_for("MISSION_REQUEST_INT", system=1)
            assert (req.seq, req.mission_type) == (0, mission_type)
            client.send(client.mav.mission_clear_all_encode(1, 1, mission_type))
            ack = await client.wait_for("MISSION_ACK", system=1)
            assert (ack.type, ack.mission_type) == (ACCEPTED, mission_type)
        # an unknown plan type is unsupported
        client.send(client.mav.mission_count_encode(1, 1, 3, 7))
        ack = await client.wait_for("MISSION_ACK", system=1)
        assert (ack.type, ack.mission_type) == (UNSUPPORTED, 7)
        # the rally/fence traffic did not touch the mission
        items = mission(client, 1, [(0, 20, 10)])
        assert (await client.upload_mission(1, items)).type == ACCEPTED
        client.send(client.mav.mission_clear_all_encode(1, 1, FENCE))
        assert (await client.wait_for("MISSION_ACK", system=1)).mission_type == FENCE
        assert swarm.fleet.autopilots[0].mission.total == len(items)


@pytest.mark.slow
async def test_flown_mission_reports_each_item_reached_and_progress() -> None:
    async with running_swarm(2, speed=20.0) as (swarm, client):
        items = mission(client, 1, [(0, 40, 10), (30, 40, 15)], land=True)
        assert (await client.upload_mission(1, items)).type == ACCEPTED
        start = len(client.received)
        assert (await client.command_long(1, 400, 1.0)).result == ACCEPTED
        assert (await client.command_long(1, 176, 1, 4, 4)).result == ACCEPTED  # AUTO.MISSION
        await client.wait_for("MISSION_ITEM_REACHED", system=1, since=start, timeout=15.0,
                              where=lambda m: m.seq == len(items) - 1)
        reached = [m.seq for m in client.messages("MISSION_ITEM_REACHED", system=1,
                                                  since=start)]
        assert reached == list(range(len(items)))
        await asyncio.sleep(0.3)
        progress = [m.seq for m in client.messages("MISSION_CURRENT", system=1, since=start)]
        assert progress == sorted(progress)
        assert set(range(len(items))) <= set(progress)
        assert {m.total for m in client.messages("MISSION_CURRENT", system=1,
                                                 since=start)} == {len(items)}
        done = client.messages("MISSION_CURRENT", system=1, since=start)[-1]
        assert done.mission_state == 5  # MISSION_STATE_COMPLETE
        # ground truth agrees, and the vehicle landed at the last waypoint
        truth = [e.data["item"] for e in swarm.recorder.events("d1",
                                                               kinds=("mission_item_reached",))]
        assert truth == list(range(len(items)))
        assert swarm.recorder.events("d1", kinds=("mission_complete",))
        landed = swarm.recorder.events("d1", kinds=("landed",))
        assert landed and landed[-1].data["position_m"][:2] == pytest.approx([30, 40], abs=2.5)
        assert not swarm.recorder.events("d2", kinds=("takeoff",))


async def test_items_from_another_ground_station_do_not_enter_an_upload() -> None:
    """PX4 ties an upload to its partner (system and component): an item that another
    ground station sends meanwhile is ignored ("partner id mismatch")."""
    async with running_swarm(1) as (swarm, client):
        intruder = await MavClient.connect(client.remote, system=254, component=190)
        try:
            items = mission(client, 1, [(0, 30, 10)])
            client.send(client.mav.mission_count_encode(1, 1, len(items), 0))
            await client.wait_for("MISSION_REQUEST_INT", system=1, where=lambda m: m.seq == 0)
            lat, lon = geo(80, 80)
            intruder.send(intruder.mission_item(1, 0, WAYPOINT, lat, lon, 77.0))
            await asyncio.sleep(0.1)
            for item in items:
                client.send(item)
                await client.wait_for(("MISSION_REQUEST_INT", "MISSION_ACK"), system=1,
                                      where=lambda m, s=item.seq: m.get_type() == "MISSION_ACK"
                                      or m.seq == s + 1)
            ack = client.messages("MISSION_ACK", system=1, since=0)
            assert [a.type for a in ack] == [ACCEPTED]
            assert summary(await client.download_mission(1)) == summary(items)
            assert [it.z for it in swarm.fleet.autopilots[0].mission.items] == [10.0, 10.0]
        finally:
            intruder.close()

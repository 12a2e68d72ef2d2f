"""MultiUAV-Plat's tracking history of moving targets over the compatibility routes: a scripted
client that knows only the reference's routes follows a moving target of the reference's
tracking example by what its drone senses; the target's record then says `tracked`, the
session data holds its tracking periods (the same as moving_target_tracked measures), and once
the drone leaves the target turns `stale`, out of the agent's sight."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from benchmark.scoring.validators.reach import Visit
from benchmark.server.compat.tracking import PERIODS_KEPT, RECENT_PERIODS, tracking_entry
from tests.compat_fixtures import KEYS, PlatClient, plat_server

EXAMPLE = Path(__file__).parent / "reference" / "Example_Session_Target_Tracking.json"
DRONE, OTHER, TARGET = "f2a74de4", "128b2f33", "ca02135e"  # Drone 1, Drone 2, Moving Target 1
ALTITUDE_M = 20.0
FOLLOW_S = 30.0
PERIOD_FIELDS = {"start_at", "end_at", "last_update_at", "event_count"}


def _record(records: list[dict[str, Any]], ident: str) -> dict[str, Any] | None:
    return next((r for r in records if r["id"] == ident), None)


async def _follow(agent: PlatClient, seconds: float) -> None:
    """Fly to where the drone senses the target, hover, again, for `seconds` of session time."""
    start = (await agent.get("/sessions/current/task-progress"))["details"]["sim_time_s"]
    elapsed = 0.0
    while elapsed < seconds:
        seen = await agent.get(f"/drones/{DRONE}/nearby/targets")
        here = _record(seen, TARGET)
        assert here is not None, [r["name"] for r in seen]
        moved = await agent.command(DRONE, "move_to", x=here["position"]["x"],
                                    y=here["position"]["y"], z=ALTITUDE_M)
        assert moved["status"] == "success", moved
        assert (await agent.command(DRONE, "hover", duration=2.0))["status"] == "success"
        details = (await agent.get("/sessions/current/task-progress"))["details"]
        elapsed = details["sim_time_s"] - start


@pytest.mark.mavsdk
async def test_a_followed_moving_target_gets_the_reference_tracking_history(
        tmp_path: Path) -> None:
    async with plat_server(tmp_path, json.loads(EXAMPLE.read_text())) as served:
        agent = PlatClient(served.client)  # no key: the agent, as `serve --open`
        operator = PlatClient(served.client, KEYS["operator"])
        before = _record(await operator.get("/targets"), TARGET)
        assert before is not None
        assert (before["tracking_status"], before["last_tracked_at"]) == ("never_tracked", None)
        data = await operator.get("/sessions/current/data")
        assert data["history"]["moving_target_tracking"] == {}
        assert all("tracking_status" not in t for t in data["targets"] if t["type"] != "moving")
        assert all(t["tracking_status"] == "never_tracked" for t in data["targets"]
                   if t["type"] == "moving")

        assert (await agent.command(DRONE, "take_off", altitude=ALTITUDE_M))["status"] == \
            "success"
        x, y = before["position"]["x"], before["position"]["y"]
        assert (await agent.command(DRONE, "move_to", x=x, y=y, z=ALTITUDE_M))["status"] == \
            "success"
        await _follow(agent, FOLLOW_S)

        # the agent's drone perceives it: its record says tracked, just now
        seen = _record(await agent.get(f"/drones/{DRONE}/nearby/targets"), TARGET)
        assert seen is not None and seen["tracking_status"] == "tracked"
        data = await operator.get("/sessions/current/data")
        now_s = data["statistics"]["session_time"]
        assert seen["last_tracked_at"] == pytest.approx(now_s, abs=0.5)
        history = data["history"]["moving_target_tracking"]
        assert set(history) == {TARGET}  # no other moving target came near a drone
        entry = history[TARGET]
        assert entry["tracking_status"] == "tracked"
        assert (entry["tracked_by"], entry["last_tracked_by"]) == ([DRONE], DRONE)
        assert entry["total_track_events"] >= 1
        assert 1 <= len(entry["recent_periods"]) <= RECENT_PERIODS
        for period in entry["recent_periods"]:
            assert set(period) == PERIOD_FIELDS | {"last_tracked_by", "tracked_by"}
            assert period["tracked_by"] == [DRONE]
            assert period["start_at"] <= period["last_update_at"] < period["end_at"]
        last = entry["recent_periods"][-1]
        assert entry["active_period_start"] == last["start_at"]
        assert last["end_at"] == pytest.approx(entry["last_tracked_at"] + 10.0, abs=1e-3)
        longest = max(p["end_at"] - p["start_at"] for p in entry["recent_periods"])
        assert longest >= FOLLOW_S
        mine = entry["by_drone"][DRONE]
        assert set(mine) == {"first_tracked_at", "last_tracked_at", "total_track_events",
                             "recent_periods"}
        assert mine["total_track_events"] == entry["total_track_events"]
        assert [set(p) for p in mine["recent_periods"]] == [PERIOD_FIELDS] * len(
            mine["recent_periods"])
        assert entry["first_tracked_at"] == mine["first_tracked_at"] <= now_s - FOLLOW_S
        # the hidden check measures the same periods on the ground truth
        admin = PlatClient(served.client, KEYS["admin"])
        check = await admin.get("/check/moving_target_tracked", target_id=TARGET,
                                drone_id=DRONE, min_duration=FOLLOW_S)
        assert check["result"] is True
        assert check["value"] == pytest.approx(longest, abs=1e-2)

        # the drone flies away and waits: stale, and out of the agent's sight
        assert (await agent.command(DRONE, "move_to", x=60, y=60, z=ALTITUDE_M))["status"] \
            == "success"
        assert (await agent.command(DRONE, "hover", duration=12.0))["status"] == "success"
        stale = _record(await operator.get("/targets"), TARGET)
        assert stale is not None and stale["tracking_status"] == "stale"
        assert stale["last_tracked_at"] >= entry["last_tracked_at"]
        assert _record(await agent.get("/targets"), TARGET) is None
        entry = (await operator.get("/sessions/current/data"))["history"][
            "moving_target_tracking"][TARGET]
        assert entry["tracking_status"] == "stale" and entry["active_period_start"] is None
        assert OTHER not in entry["by_drone"]


def test_track_events_merge_into_the_reference_periods() -> None:
    events = [(Visit(0.0, 5.0), "d1"), (Visit(3.0, 8.0), "d2"), (Visit(30.0, 31.0), "d1")]
    entry = tracking_entry(events, now_s=40.0)
    assert entry["recent_periods"] == [
        {"start_at": 0.0, "end_at": 18.0, "last_update_at": 8.0, "event_count": 2,
         "last_tracked_by": "d2", "tracked_by": ["d1", "d2"]},
        {"start_at": 30.0, "end_at": 41.0, "last_update_at": 31.0, "event_count": 1,
         "last_tracked_by": "d1", "tracked_by": ["d1"]}]
    assert (entry["tracking_status"], entry["active_period_start"]) == ("tracked", 30.0)
    assert (entry["first_tracked_at"], entry["last_tracked_at"], entry["last_tracked_by"]) == \
        (0.0, 31.0, "d1")
    assert (entry["tracked_by"], entry["total_track_events"]) == (["d1", "d2"], 3)
    assert entry["by_drone"]["d2"] == {
        "first_tracked_at": 3.0, "last_tracked_at": 8.0, "total_track_events": 1,
        "recent_periods": [{"start_at": 3.0, "end_at": 18.0, "last_update_at": 8.0,
                            "event_count": 1}]}
    assert [p["start_at"] for p in entry["by_drone"]["d1"]["recent_periods"]] == [0.0, 30.0]
    late = tracking_entry(events, now_s=41.5)
    assert (late["tracking_status"], late["active_period_start"]) == ("stale", None)
    # many separate periods: the reference keeps 10 and serialises the last 5
    many = events + [(Visit(100.0 + 20 * k, 101.0 + 20 * k), "d1") for k in range(12)]
    entry = tracking_entry(many, now_s=400.0)
    assert PERIODS_KEPT == 10 and entry["total_track_events"] == 15
    assert [p["start_at"] for p in entry["recent_periods"]] == \
        [100.0 + 20 * k for k in range(7, 12)]
    assert entry["tracking_status"] == "stale"

"""MultiUAV-Plat's agent client plays a hosted run with nothing changed but its base URL and
key: the reference routes (`/sessions/current/tasks/next`, `/sessions/current`, `/drones`,
direct commands, `nearby`, `mark-done`) through a seat key on the run's endpoint, over real
sockets to a `mavswarm bench run --agent external` process; the task passes and is recorded
as any agent's, and the hidden parts stay hidden."""

from __future__ import annotations

from pathlib import Path

import httpx
import pytest

from benchmark.running.results import read_records
from tests.bench_fixtures import write_json
from tests.compat_fixtures import PlatClient, plat_world
from tests.hosted_fixtures import start_host

pytestmark = [pytest.mark.mavsdk, pytest.mark.slow]


async def test_the_reference_client_plays_a_hosted_run_through_a_seat(tmp_path: Path) -> None:
    world = write_json(tmp_path / "plat_world.json", plat_world())
    host = start_host([world], tmp_path / "out")
    try:
        async with httpx.AsyncClient(base_url=host.url, timeout=60.0) as http:
            seat = host.seats[0]
            agent = PlatClient(http, seat)
            r = await http.get("/drones", headers=agent.headers)
            assert r.status_code == 409 and "tasks/next" in r.json()["detail"]  # none held yet
            task = await agent.get("/sessions/current/tasks/next")
            assert set(task) == {"id", "content"} and "Fixed Target 1" in task["content"]
            assert await agent.get("/sessions/current/tasks/next") == task  # held until done
            current = await agent.get("/sessions/current")
            assert "targets" not in current and "checks" not in str(current)
            drones = await agent.get("/drones")
            assert {d["id"] for d in drones} == {"d1d1d1d1", "d2d2d2d2"}
            took_off = await agent.command("d1d1d1d1", "take_off", altitude=12)
            assert took_off["status"] == "success", took_off
            moved = await agent.command("d1d1d1d1", "move_to", x=100, y=160, z=12)
            assert moved["status"] == "success", moved
            seen = await agent.get("/drones/d1d1d1d1/nearby")
            assert "f1f1f1f1" in {t["id"] for t in seen["targets"]}
            assert (await agent.command("d1d1d1d1", "take_photo"))["status"] == "success"
            assert (await agent.command("d1d1d1d1", "land"))["status"] == "success"
            progress = await agent.get("/sessions/current/task-progress")
            assert progress["is_completed"] is None  # judged out of the agent's sight
            for hidden in ("/sessions/current/data", "/check/sessions/c0ffee01/task"):
                r = await http.get(hidden, headers=agent.headers)
                assert r.status_code == 403, (hidden, r.text)
            done = await agent.post(f"/sessions/current/tasks/{task['id']}/mark-done")
            assert done["is_done"] is True and done["id"] == task["id"]
            r = await http.get("/drones", headers=agent.headers)
            assert r.status_code == 409  # the seat holds no task any more
            r = await http.get("/sessions/current/tasks/next", headers=agent.headers)
            assert r.status_code == 404 and "over" in r.json()["detail"]
            assert (await http.get("/next")).status_code == 204
        status, printed = host.wait()
    finally:
        host.kill()
    assert status == 0, printed
    (record,) = read_records(tmp_path / "out" / "results.jsonl")
    assert record["agent"] == "external" and record["finish"] == "finished"
    assert record["passed"] is True, record["checks"]
    assert record["tool_calls"] == 5  # the 4 commands and the nearby read

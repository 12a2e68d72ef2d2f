"""One rule for operators on every surface (benchmark.server.operator_rule): while a benchmark
task runs for a served session's agent, flight commands from the web console are refused with
409 as MQTT commands and link changes are, and nothing flies; a world served without tasks
takes them. Against `mavswarm serve` with the console mounted, real sockets and MAVLink."""

from __future__ import annotations

import asyncio
import contextlib
import io
import json
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest

from benchmark.server import Hub
from benchmark.server.serve import ApiKey, mqtt_refusal, serve_rest
from console.cli import console_for_hub
from tests.browser_fixtures import LoopThread, open_page, shot
from tests.cli_fixtures import ROOT
from tests.ports import unused_tcp_port

pytestmark = [pytest.mark.browser, pytest.mark.mavsdk]

TASKED, FREE = "tasked", "free"
RULE = "refused while a task runs (they would change its result)"


@pytest.fixture(scope="module")
def served(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[str, Hub]]:
    """`mavswarm serve` of a session running its task t01 and a world without tasks."""
    source = json.loads((ROOT / "benchmark/sessions/area_search-easy-1.json").read_text())
    folder: Path = tmp_path_factory.mktemp("serve")
    paths = []
    for ident, tasks in ((TASKED, source["tasks"][:1]), (FREE, [])):
        paths.append(folder / f"{ident}.json")
        paths[-1].write_text(json.dumps({**source, "id": ident, "tasks": tasks}))
    loop = LoopThread()
    ready: asyncio.Future[str] = loop.loop.create_future()
    hubs: list[Hub] = []

    def extend(app: Any, hub: Hub, keys: list[ApiKey]) -> Any:
        hubs.append(hub)
        return console_for_hub(app, hub, keys)

    async def run() -> None:
        keys = [f"agent:{TASKED}=ak", "operator=op", "admin=adm"]
        await serve_rest(paths, port=unused_tcp_port(), keys=keys, out=io.StringIO(),
                         extend=extend,
                         on_ready=lambda url: ready.set_result(url))

    task = asyncio.run_coroutine_threadsafe(run(), loop.loop)
    deadline = time.monotonic() + 60
    while not ready.done():  # a server that failed to start says why
        if task.done():
            task.result()
        assert time.monotonic() < deadline, "serve did not start in 60 s"
        time.sleep(0.05)
    try:
        yield ready.result(), hubs[0]
    finally:
        task.cancel()
        with contextlib.suppress(BaseException):
            task.result(30)
        loop.close()


def _altitude(hub: Hub, session: str, drone: str) -> float:
    fleet = hub.sessions[session].swarm.fleet
    return float(fleet.dyn.position_m[fleet.index_by_id[drone]][2])


def test_console_flight_commands_are_refused_while_a_task_runs(
        browser: Any, served: tuple[str, Hub]) -> None:
    url, hub = served
    command = f"{url}/console/api/live/{TASKED}/command"
    for key in ("op", "adm"):
        for body in ({"drone_id": "d1", "tool": "take_off", "args": {"altitude_m": 12}},
                     {"drone_ids": "all", "tool": "hold"},
                     {"drone_id": "d1", "tool": "move_to", "args": {"x": 50, "y": 50, "z": 10}}):
            refused = httpx.post(command, json=body, headers={"X-API-Key": key})
            assert refused.status_code == 409, refused.text
            detail = refused.json()["detail"]
            assert "benchmark task t01" in detail and RULE in detail
            assert "flight commands from the console" in detail
    agent = httpx.post(command, json={"drone_id": "d1", "tool": "hold"},
                       headers={"X-API-Key": "ak"})
    assert agent.status_code == 403  # an agent never gets the console, commands included
    assert httpx.get(f"{url}/console/api/editor/shipped",
                     headers={"X-API-Key": "ak"}).status_code == 403
    time.sleep(1.0)
    assert _altitude(hub, TASKED, "d1") == pytest.approx(0.0, abs=0.1)  # nothing flew

    # The same rule, word for word, answers MQTT commands and link changes.
    assert RULE in (mqtt_refusal(hub, TASKED) or "")
    link = httpx.put(f"{url}/console/api/live/{TASKED}/link-faults", json={"loss": 0.1},
                     headers={"X-API-Key": "op"})
    assert link.status_code == 409 and RULE in link.json()["detail"]

    listed = httpx.get(f"{url}/console/api/live/{TASKED}/commands",
                       headers={"X-API-Key": "op"}).json()
    assert "hold" in listed["commands"] and RULE in listed["refusal"]

    # The page says so up front and greys every command button.
    with open_page(browser, f"{url}/console/live/{TASKED}?key=op") as page:
        page.wait_for_function("window.consoleView.state.frames >= 2", timeout=20_000)
        page.wait_for_selector("#cmd-refusal", timeout=15_000)
        note = page.text_content("#cmd-refusal") or ""
        assert "benchmark task t01" in note and "refused" in note
        for button in ("hold", "hold-all", "take_off", "fly", "hover", "land", "return_home"):
            assert page.is_disabled(f"#cmd-{button}"), button
        shot(page, "operator-rule-refused")
    assert _altitude(hub, TASKED, "d1") == pytest.approx(0.0, abs=0.1)


def test_a_world_without_tasks_takes_console_commands(served: tuple[str, Hub]) -> None:
    url, hub = served
    assert mqtt_refusal(hub, FREE) is None
    listed = httpx.get(f"{url}/console/api/live/{FREE}/commands", headers={"X-API-Key": "op"})
    assert listed.json()["refusal"] is None
    answer = httpx.post(f"{url}/console/api/live/{FREE}/command",
                        json={"drone_id": "d2", "tool": "take_off", "args": {"altitude_m": 6}},
                        headers={"X-API-Key": "op"}, timeout=30)
    assert answer.status_code == 200 and answer.json()["status"] in ("ok", "accepted")
    deadline = time.monotonic() + 60
    while _altitude(hub, FREE, "d2") < 5.0:
        assert time.monotonic() < deadline, "d2 never climbed"
        time.sleep(0.1)

"""The resilience family: its templates schedule hidden faults (a motor, GPS or battery failure,
a lossy link) that no agent-facing payload mentions; the oracle, which knows the schedule,
passes every template with the faults striking; the same seed gives the same truth and
verdicts byte for byte; and nothing that does not fly passes."""

from __future__ import annotations

import asyncio
import hashlib
import json
import random
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from benchmark.authoring.generate import build_task
from benchmark.authoring.scenarios import LEVELS, generate_world
from benchmark.authoring.session_file import session_from_dict
from benchmark.authoring.templates import SessionView
from benchmark.authoring.templates.resilience import FAULT_AFTER_S, TEMPLATES
from benchmark.running.episode import EpisodeOptions, run_task, swarm_gateway
from benchmark.running.orchestrator import RunPlan, run_benchmark
from benchmark.running.results import read_records
from llm_tools import default_registry
from llm_tools.mcp_server import build_server
from swarm_agents.oracle import OracleAgent
from tests.bench_fixtures import small_session, write_json
from tests.rest_fixtures import as_role, served

KEYS = [t.key for t in TEMPLATES]
# What would give a fault away (the words of a schedule, its fields, the failing units); task
# texts do not speak of batteries either (drone states do, as a level).
TELLING = re.compile(r"\b(faults?|failures?|fail|after_s|schedule[ds]?|motors?|gps|outages?|"
                     r"latency|loss|lossy)\b", re.IGNORECASE)
TEXT_TELLING = re.compile(TELLING.pattern + r"|\bbattery\b", re.IGNORECASE)
AGENT_ROUTES = ("/sessions/{s}", "/sessions/{s}/task", "/sessions/{s}/tools",
                "/sessions/{s}/drones", "/sessions/{s}/drones/{d}", "/drones", "/drones/{d}",
                "/drones/{d}/nearby", "/sessions/current", "/sessions/current/tasks",
                "/sessions/current/tasks/next")
WALL_FIELDS = ("wall_time_s", "overhead_s", "replay")


def _telling(text: str, words: re.Pattern[str] = TELLING) -> list[str]:
    return sorted({m.group(0).lower() for m in words.finditer(text)})


def test_task_texts_state_the_goal_never_the_fault() -> None:
    for level in LEVELS:
        world = generate_world("resilience", level, 1)
        scenario = session_from_dict({**world, "tasks": []}).scenario
        w, h = world["map_size_m"]
        view = SessionView("resilience", scenario, float(w), float(h))
        for template in TEMPLATES:
            assert template.fits(view), (level, template.key)
            for seed in range(4):
                task = build_task(template, view, random.Random(f"{seed}"), "t01")
                for text in (task["text"], *task["aliases"]):
                    assert not _telling(text, TEXT_TELLING), (template.key, text)
                faults = task["faults"]
                for failure in faults.get("failures", []):
                    assert FAULT_AFTER_S[0] <= failure["after_s"] <= FAULT_AFTER_S[1]
                    # the failing drone is one the task names, and the plan only holds it
                    name = scenario.vehicles[[v.id for v in scenario.vehicles].index(
                        failure["drone"])].name
                    assert name in task["text"]
                    own = [op for phase in task["oracle"] for op in phase
                           if op.get("drone") == failure["drone"]
                           or failure["drone"] in op.get("drones", ())]
                    assert [op["op"] for op in own] == ["until_fault"], own
                assert faults.get("failures") or faults.get("link"), task


@pytest.mark.mavsdk
async def test_no_rest_or_mcp_payload_for_agents_mentions_the_scheduled_faults() -> None:
    from mcp import Client
    data = small_session(KEYS, family="resilience", seed=7)
    assert all(task.get("faults") for task in data["tasks"])
    async with served(data=data) as s:
        sid = next(iter(s.hub.sessions))
        texts = []
        for route in AGENT_ROUTES:
            for drone in data["drones"]:
                r = await s.client.get(route.format(s=sid, d=drone["id"]),
                                       headers=as_role("agent"))
                assert r.status_code == 200, (route, r.text)
                texts.append(r.text)
        async with Client(build_server(default_registry(), lambda: s.live.tools)) as client:
            listed = (await client.list_tools()).tools
            texts += [f"{t.name} {t.description}" for t in listed]
            for drone in data["drones"]:
                result = await client.call_tool("drone_state", {"drone_id": drone["id"]})
                texts.append(json.dumps(result.structured_content))
        assert not _telling("\n".join(texts)), _telling("\n".join(texts))
        # An admin's view of the same task shows the schedule: the scan can fail.
        admin = (await s.client.get(f"/sessions/{sid}/task", headers=as_role("admin"))).json()
        assert admin["faults"] == data["tasks"][0]["faults"]
        assert "after_s" in json.dumps(admin) and _telling(json.dumps(admin))


def _truth_digest(recorder: Any, t0_s: float, t1_s: float) -> str:
    digest = hashlib.sha256()
    for vehicle in recorder.vehicle_ids:
        digest.update(np.ascontiguousarray(recorder.trajectory(vehicle, t0_s, t1_s)).tobytes())
    for event in recorder.events(t0_s=t0_s, t1_s=t1_s):
        digest.update(json.dumps([event.t_s, event.vehicle_id, event.kind, event.data],
                                 sort_keys=True, default=dict).encode())
    return digest.hexdigest()


async def _oracle_run(data: dict[str, Any]) -> list[tuple[dict[str, Any], str, list, list]]:
    """Each task flown by the oracle: its record (wall fields dropped), the digest of its
    window's ground truth, its tool calls and the window's events."""
    session = session_from_dict(data, source="resilience.json")
    agent = OracleAgent(session.scenario, {t.id: t.oracle for t in session.tasks})
    out = []
    async with swarm_gateway(session, lockstep=True) as (swarm, services, gateway):
        for task in session.tasks:
            record = await run_task(session, task, agent, swarm, services, gateway,
                                    EpisodeOptions())
            t0_s, t1_s = record["window_s"]
            calls = record["replay"]["calls"]
            stable = {k: v for k, v in record.items() if k not in WALL_FIELDS}
            events = [(e.t_s, e.vehicle_id, e.kind, dict(e.data))
                      for e in swarm.recorder.events(t0_s=t0_s, t1_s=t1_s)]
            out.append((stable, _truth_digest(swarm.recorder, t0_s, t1_s), calls, events))
    return out


@pytest.mark.mavsdk
async def test_the_oracle_passes_with_the_faults_striking_and_the_same_seed_gives_the_same_truth(
        ) -> None:
    data = small_session(KEYS, family="resilience", seed=7)
    first = await _oracle_run(data)
    failed = [(r["template"], [c for c in r["checks"] if not c["passed"]])
              for r, *_ in first if not r["passed"]]
    assert not failed, failed
    for (record, _, calls, events), task in zip(first, data["tasks"], strict=True):
        for failure in task["faults"].get("failures", []):
            drone, unit = failure["drone"], failure["unit"]
            struck = [e for e in events if e[2] == "failure" and e[1] == drone]
            assert [(e[3]["unit"], e[3]["source"]) for e in struck] == [(unit, "schedule")]
            at_s = struck[0][0]
            assert round(at_s - record["window_s"][0], 1) <= failure["after_s"] + 0.1
            # No tool result before the fault tells of it; the failing drone's calls end
            # when it strikes (motor and GPS: reported failed).
            before = [c for c in calls if c["t1_s"] is not None and c["t1_s"] < at_s - 1e-6]
            assert not any(_telling(str(c["message"])) for c in before), before
            if unit in ("motor", "gps"):
                assert any(c["drone"] == drone and c["status"] == "failed" for c in calls)
        if "link" in task["faults"]:
            (lossy,) = task["faults"]["link"]["vehicles"]
            kinds = [(e[1], e[2]) for e in events]
            assert (lossy, "link_faults") in kinds
    second = await _oracle_run(data)
    for (r1, truth1, calls1, _), (r2, truth2, calls2, _) in zip(first, second, strict=True):
        assert r1 == r2, r1["template"]
        assert truth1 == truth2, r1["template"]
        assert [(c["name"], c["drone"], c["t0_s"], c["t1_s"], c["status"]) for c in calls1] \
            == [(c["name"], c["drone"], c["t0_s"], c["t1_s"], c["status"]) for c in calls2]


@pytest.mark.mavsdk
def test_the_do_nothing_agent_passes_no_resilience_task(tmp_path: Path) -> None:
    path = write_json(tmp_path / "resilience.json",
                      small_session(KEYS, family="resilience", seed=7))
    run_benchmark(RunPlan(sessions=(path,), agent="noop", out_dir=tmp_path / "noop"),
                  progress=print)
    records = read_records(tmp_path / "noop" / "results.jsonl")
    assert sorted(r["template"] for r in records) == sorted(KEYS)
    assert not any(r["passed"] for r in records)
    # a drone left on the ground meets "ends on the ground", nothing more
    assert all(r["checks_passed"] <= 1 for r in records)


def _kept_to_the_split(task: dict[str, Any]) -> list[list[dict[str, Any]]]:
    """The plan of an agent that keeps to the delivery task's split and never notices the
    fault: each drone carries its own parcel."""
    alt = next(op["z"] for phase in task["oracle"] for op in phase if op["op"] == "goto")
    ops = []
    for k, parcel in enumerate(task["checks"]["checks"]):
        own = parcel["checks"][k]["checks"]  # parcel k planned for the k-th drone
        for landing in own:
            p = landing["parameters"]
            ops += [{"op": "goto", "drone": p["drone_id"], "x": p["x"], "y": p["y"], "z": alt},
                    {"op": "land", "drone": p["drone_id"]}]
    return [ops]


@pytest.mark.mavsdk
def test_keeping_to_the_plan_without_noticing_the_fault_fails(tmp_path: Path) -> None:
    """The failing drone's parcel is left undelivered when nobody takes it over: the check
    is on what the team achieves, and the fault makes the difference."""
    data = small_session(["delivery_despite_motor_failure"], family="resilience", seed=7)
    (task,) = data["tasks"]
    naive = {**task, "oracle": _kept_to_the_split(task)}
    write_json(tmp_path / "naive.json", {**data, "tasks": [naive]})
    clean = {**naive, "id": "t02"}
    del clean["faults"]
    write_json(tmp_path / "clean.json", {**data, "tasks": [clean]})
    for name in ("naive", "clean"):
        run_benchmark(RunPlan(sessions=(tmp_path / f"{name}.json",), agent="oracle",
                              out_dir=tmp_path / name), progress=print)
    (faulty,) = read_records(tmp_path / "naive" / "results.jsonl")
    (unfaulted,) = read_records(tmp_path / "clean" / "results.jsonl")
    assert unfaulted["passed"], unfaulted["checks"]  # the split itself works without a fault
    assert not faulty["passed"]
    failing = task["faults"]["failures"][0]["drone"]
    own = [c["passed"] for c in faulty["checks"] if c["parameters"]["drone_id"] == failing]
    assert own and not all(own)  # the failing drone's parcel was not delivered


@pytest.mark.parametrize(("faults", "named"), [
    ({"failures": [{"drone": "d9", "after_s": 5, "unit": "motor"}]}, "unknown drone 'd9'"),
    ({"failures": [{"drone": "d1", "after_s": -1, "unit": "motor"}]}, "after_s"),
    ({"failures": [{"drone": "d1", "after_s": 5, "unit": "rotor"}]}, "unit: expected one of"),
    ({"link": {"loss": 2}}, "loss"),
    ({"later": []}, "expected an object with 'failures' and/or 'link'"),
])
def test_a_task_with_bad_faults_is_a_task_error_naming_the_field(faults: dict[str, Any],
                                                                  named: str) -> None:
    data = small_session(["delivery_over_lossy_link"], family="resilience")
    good = session_from_dict(data).tasks[0]
    assert good.error is None and good.faults is not None and good.faults.link is not None
    data["tasks"][0]["faults"] = faults
    (task,) = session_from_dict(data).tasks
    assert task.error is not None and "tasks[0] (t01).faults" in task.error, task.error
    assert named in task.error and task.faults is None


@pytest.mark.mavsdk
async def test_a_lost_failure_report_is_told_again_at_the_halt() -> None:
    """The STATUSTEXT of a motor failure lost on the way (a loaded machine drops datagrams
    too): the swarm tells it again with the halt's telemetry, so the primitive under way ends
    as failed instead of waiting on a drone that has come to rest."""
    from mavlink_gateway import Status
    from tests.test_gateway_faults import act, lockstep_gateway

    async with lockstep_gateway(1) as (swarm, _services, gw, thinker):
        assert (await act(thinker, gw.take_off("d1", 12.0))).ok
        ap, link = swarm.fleet.autopilots[0], swarm.links[0]
        sent = link.statustext
        lost: list[str] = []

        def lossy(severity: int, text: str) -> None:
            if text.startswith("Motor failure") and len(lost) < 2:
                lost.append(text)  # what the vehicle says as the motor fails never arrives
                return
            sent(severity, text)

        link.statustext = lossy  # type: ignore[method-assign]
        failure_s = swarm.fleet.now_s + 5.0
        swarm.faults.schedule(failure_s, "failure",
                              lambda: ap.failures.fail("motor", "schedule"))
        async with asyncio.timeout(60.0):  # without the report again it waits for ever
            outcome = await act(thinker, gw.hover("d1", 40.0))
        assert len(lost) == 2 and outcome.status is Status.FAILED, outcome
        assert "Motor failure" in outcome.message
        assert swarm.fleet.now_s < failure_s + 10.0  # at the failure, not the hover's end

"""Link faults without a client: settings and their errors, each frame's seeded fate, and the
timed events (outages, the data-link-loss failsafe) in simulated time, read from the truth."""

from __future__ import annotations

import argparse
import asyncio

import pytest

from emulator.clock import ClockConfig
from emulator.link_faults import (
    DOWNLINK,
    UPLINK,
    LinkFaultError,
    LinkFaults,
    LinkGate,
    LinkProfile,
    add_link_arguments,
    link_faults_from_args,
)
from emulator.swarm import PortPlan, Swarm
from tests.scenario_fixtures import tiny_scenario, vehicle


def _gate(faults: LinkFaults, n: int = 2) -> tuple[LinkGate, list[tuple[float, int]]]:
    clock = [(0.0, 0)]
    return LinkGate(faults, [f"d{k + 1}" for k in range(n)], lambda: clock[0]), clock


def test_settings_from_json_both_directions_and_per_vehicle() -> None:
    faults = LinkFaults.from_json({
        "seed": 7, "loss": 0.2, "latency_ms": 50, "jitter_ms": 20,
        "downlink": {"duplicate": 0.1}, "vehicles": {"d2": {"uplink": {"outages": [[30, 60]]}}},
    }, vehicle_ids=["d1", "d2"])
    assert faults.seed == 7
    assert faults.uplink == LinkProfile(loss=0.2, latency_ms=50.0, jitter_ms=20.0)
    assert faults.downlink.duplicate == 0.1 and faults.downlink.loss == 0.2
    up2, down2 = faults.vehicles["d2"]
    assert up2.outages == ((30.0, 60.0),) and up2.loss == 0.2
    assert down2 == faults.downlink
    assert LinkFaults.from_json(faults.to_json()) == faults


@pytest.mark.parametrize(("raw", "message"), [
    ({"loss": 1.5}, "loss must be a number within [0, 1]"),
    ({"loss": True}, "loss must be a number within [0, 1]"),
    ({"latency_ms": -1}, "latency_ms must be a number of milliseconds"),
    ({"jitter_ms": float("nan")}, "jitter_ms must be a number of milliseconds"),
    ({"outages": [[60, 30]]}, "outages[0] must be [start_s, end_s]"),
    ({"outages": "30-60"}, "outages must be a list"),
    ({"lost": 0.2}, "lost is not a link setting"),
    ({"seed": -1}, "seed must be a non-negative integer"),
    ({"vehicles": {"d9": {"loss": 0.1}}}, "unknown drone 'd9'"),
    ({"uplink": [0.1]}, "uplink must be an object"),
])
def test_bad_settings_are_refused_by_name(raw: dict, message: str) -> None:
    with pytest.raises(LinkFaultError) as error:
        LinkFaults.from_json(raw, vehicle_ids=["d1", "d2"])
    assert message in str(error.value)


def test_command_line_options() -> None:
    parser = argparse.ArgumentParser()
    add_link_arguments(parser)
    args = parser.parse_args(["--link-loss", "0.2", "--link-latency-ms", "50",
                              "--link-outage", "10:20", "--link-direction", "uplink"])
    faults = link_faults_from_args(args)
    assert faults is not None
    assert faults.uplink == LinkProfile(loss=0.2, latency_ms=50.0, jitter_ms=20.0,
                                        outages=((10.0, 20.0),))
    assert faults.downlink.clean
    assert link_faults_from_args(parser.parse_args([])) is None
    session = LinkFaults.from_json({"seed": 2, "vehicles": {"d1": {"uplink": {"loss": 0.5}}}})
    merged = link_faults_from_args(parser.parse_args(["--link-latency-ms", "40"]), session)
    assert merged is not None and merged.seed == 2
    assert merged.vehicles["d1"][0] == LinkProfile(loss=0.5, latency_ms=40.0, jitter_ms=20.0)
    assert merged.downlink.latency_ms == 40.0
    with pytest.raises(LinkFaultError, match="START:END"):
        link_faults_from_args(parser.parse_args(["--link-outage", "ten"]))
    with pytest.raises(LinkFaultError, match="loss must be"):
        link_faults_from_args(parser.parse_args(["--link-loss", "2"]))


def test_fates_are_seeded_by_simulated_step_and_ordinal() -> None:
    faults = LinkFaults(seed=3, uplink=LinkProfile(loss=0.3, latency_ms=50.0, jitter_ms=20.0,
                                                   duplicate=0.1, reorder=0.1))
    fates = []
    for _ in range(2):
        gate, clock = _gate(faults)
        run = []
        for step in range(400):
            clock[0] = (step * 0.02, step)
            run.append(gate.fate(0, UPLINK, 76))  # a command and its retransmission
            run.append(gate.fate(0, UPLINK, 76))
        fates.append(run)
    assert fates[0] == fates[1]
    dropped = sum(1 for f in fates[0] if f == ())
    assert 0.22 < dropped / len(fates[0]) < 0.38
    delays = [d for f in fates[0] if f for d in f]
    assert all(d >= 0.0 for d in delays) and max(delays) > 0.07  # jitter and reordering
    assert any(f is not None and len(f) == 2 for f in fates[0])  # duplicates
    assert fates[0][0::2] != fates[0][1::2]  # a retransmission draws its own fate
    other, _ = _gate(LinkFaults(seed=4, uplink=faults.uplink))
    assert [other.fate(0, UPLINK, 76) for _ in range(50)] != fates[0][:50]
    gate, _ = _gate(faults)
    assert gate.fate(0, DOWNLINK, 0) is None  # a clean direction is not touched


def test_outages_and_silenced_vehicles_drop_everything() -> None:
    gate, clock = _gate(LinkFaults(downlink=LinkProfile(outages=((10.0, 20.0),))))
    clock[0] = (9.98, 499)
    assert gate.fate(0, DOWNLINK, 0) == (0.0,)
    clock[0] = (10.0, 500)
    assert gate.fate(0, DOWNLINK, 0) == ()
    assert not gate.link_down(0, 15.0)  # the uplink is up: the vehicle still hears
    clock[0] = (20.0, 1000)
    assert gate.fate(0, DOWNLINK, 0) == (0.0,)
    gate.silenced.add(1)
    assert gate.fate(1, UPLINK, 76) == () and gate.link_down(1, 0.0)


async def _flying_swarm(faults: LinkFaults, dll_action: int) -> Swarm:
    scenario = tiny_scenario([vehicle(1), vehicle(2, x=50.0)])
    swarm = Swarm(scenario, clock=ClockConfig(stepped=True),
                  ports=PortPlan(bind_host="127.0.0.1", api_port=0, gcs_port=0),
                  link_faults=faults)
    await swarm.start()
    for ap in swarm.fleet.autopilots:
        ap.set_param("NAV_DLL_ACT", dll_action)
        ap.arm()
        ap.takeoff(20.0)
    await asyncio.wait_for(swarm.wait_idle(), 30.0)
    return swarm


async def test_uplink_outage_triggers_the_data_link_loss_failsafe_at_its_time() -> None:
    faults = LinkFaults.from_json({"vehicles": {"d1": {"uplink": {"outages": [[30, 100]]}},
                                                "d2": {"uplink": {"outages": [[31, 35]]}}}})
    swarm = await _flying_swarm(faults, dll_action=2)
    try:
        await asyncio.wait_for(swarm.advance(120.0 - swarm.fleet.now_s), 60.0)
        events = swarm.recorder.events()
        d1 = [(e.kind, round(e.t_s, 2)) for e in events if e.vehicle_id == "d1"
              and e.kind in ("link_outage", "link_lost", "failsafe", "link_restored")]
        # COM_DL_LOSS_T (10 s) after the outage began: lost, and RTL (NAV_DLL_ACT 2)
        assert d1 == [("link_outage", 30.0), ("link_lost", 40.0), ("failsafe", 40.0),
                      ("link_restored", 100.0)]
        failsafe = next(e for e in events if e.kind == "failsafe" and e.vehicle_id == "d1")
        assert failsafe.data == {"reason": "data_link_lost", "action": "return"}
        assert swarm.fleet.autopilots[0].mode.name == "RTL" or \
            not swarm.fleet.autopilots[0].in_air
        # d2's outage was shorter than COM_DL_LOSS_T: no failsafe, still flying
        d2 = [e.kind for e in events if e.vehicle_id == "d2" and e.t_s > 1.0]
        assert "link_lost" not in d2 and "failsafe" not in d2
        assert swarm.fleet.autopilots[1].in_air
        assert [e.kind for e in events if e.t_s == 0.0 and e.kind == "link_faults"] == \
            ["link_faults", "link_faults"]
    finally:
        await swarm.close()


async def test_data_link_loss_with_no_action_is_recorded_and_changes_nothing() -> None:
    faults = LinkFaults(uplink=LinkProfile(outages=((30.0, 60.0),)))
    swarm = await _flying_swarm(faults, dll_action=0)
    try:
        await asyncio.wait_for(swarm.advance(70.0 - swarm.fleet.now_s), 60.0)
        lost = [e for e in swarm.recorder.events() if e.kind == "link_lost"]
        assert [(e.vehicle_id, e.data["action"]) for e in lost] == [("d1", "none"),
                                                                    ("d2", "none")]
        assert not any(e.kind == "failsafe" for e in swarm.recorder.events())
        assert all(ap.in_air and ap.mode.name == "HOLD" for ap in swarm.fleet.autopilots)
    finally:
        await swarm.close()


async def test_link_faults_changed_at_run_time_are_recorded() -> None:
    swarm = await _flying_swarm(LinkFaults(), dll_action=3)
    try:
        t0 = swarm.fleet.now_s
        swarm.set_link_faults(LinkFaults.from_json({"vehicles": {"d2": {"uplink": {"loss": 1}}}}))
        await asyncio.wait_for(swarm.advance(15.0), 60.0)
        events = [e for e in swarm.recorder.events() if e.t_s >= t0 - 1e-9]
        assert [(e.vehicle_id, e.data["uplink"]["loss"]) for e in events
                if e.kind == "link_faults"] == [("d1", 0.0), ("d2", 1.0)]
        lost = [e for e in events if e.kind == "link_lost"]
        assert [(e.vehicle_id, round(e.t_s - t0, 2)) for e in lost] == [("d2", 10.0)]
        to_land = [e for e in events if e.kind == "mode" and e.data["mode"] == "land"]
        assert [(e.vehicle_id, round(e.t_s - t0, 2)) for e in to_land] == [("d2", 10.0)]
    finally:
        await swarm.close()


async def test_a_retransmitted_command_is_answered_as_the_first_and_run_once() -> None:
    from tests.mavlink_client import running_swarm
    nan = float("nan")
    async with running_swarm(1) as (swarm, client):
        assert (await client.command_long(1, 400, 1.0)).result == 0
        first = await client.command_long(1, 22, nan, nan, nan, nan, nan, nan, nan)
        again = await client.command_long(1, 22, nan, nan, nan, nan, nan, nan, nan)
        assert (first.result, again.result) == (0, 0)  # not "already in the air"
        takeoffs = [e for e in swarm.recorder.events() if e.kind == "takeoff"]
        assert len(takeoffs) == 1
        assert swarm.links[0].dedup.duplicates == 1
        # a photo repeated with its capture sequence number: one photo, reported twice
        for _ in range(2):
            ack = await client.command_long(1, 2000, 0.0, 0.0, 1.0, 5.0, component=100)
            assert ack.result == 0
        await client.settle()
        reports = client.messages("CAMERA_IMAGE_CAPTURED", system=1)
        assert swarm.fleet.autopilots[0].photo_count == 1
        assert [m.image_index for m in reports] == [1, 1]  # the same photo, twice


def test_operator_link_faults_are_checked_before_anything_changes() -> None:
    from emulator.services import SwarmServices
    swarm = Swarm(tiny_scenario([vehicle(1), vehicle(2, x=50.0)]), clock=ClockConfig(stepped=True))
    services = SwarmServices(swarm)
    with pytest.raises(LinkFaultError, match="loss must be"):
        services.operator_set_link_faults({"vehicles": {"d1": {"loss": -0.5}}})
    with pytest.raises(LinkFaultError, match="unknown drone 'd7'"):
        services.operator_set_link_faults({"vehicles": {"d7": {"loss": 0.5}}})
    assert swarm.faults.gate.faults.clean and not swarm.recorder.events()
    services.operator_set_link_faults({"vehicles": {"d1": {"loss": 0.5}}})
    assert swarm.faults.gate.profile(0, UPLINK).loss == 0.5
    assert swarm.faults.gate.profile(1, UPLINK).clean
    assert [e.kind for e in swarm.recorder.events()] == ["link_faults", "link_faults"]


def test_mavswarm_up_refuses_bad_link_options_with_the_field_named(capsys) -> None:
    from emulator.cli import add_parsers
    parser = argparse.ArgumentParser()
    add_parsers(parser.add_subparsers())
    args = parser.parse_args(["up", "--link-loss", "1.5", "--no-truth"])
    assert args.run(args) == 2
    assert "loss must be a number within [0, 1]" in capsys.readouterr().err

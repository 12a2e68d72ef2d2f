"""Bursts at a lockstep halt: the halted vehicle twice, then only the vehicles whose telemetry
may have changed since their last burst (emulator.telemetry_bursts)."""

from __future__ import annotations

import math

from emulator.clock import ClockConfig
from emulator.mavlink.codec import mavlink
from emulator.mavlink.queries import changes_state
from emulator.scenario import default_scenario
from emulator.swarm import Swarm
from emulator.telemetry_bursts import BURST_VEHICLES_PER_TURN
from mavlink_vocabulary import MavCmd, MessageId

N = 6


def _swarm() -> Swarm:
    return Swarm(default_scenario(N), clock=ClockConfig(stepped=True, lockstep=True))


def _drain(swarm: Swarm) -> list[dict[int, int]]:
    turns = []
    while swarm.bursts.pending:
        turns.append(swarm.bursts.take_turn(swarm.left))
    return turns


def _command(system_id: int, command: int, *params: float) -> mavlink.MAVLink_message:
    padded = [*params, *[0.0] * (7 - len(params))]
    return mavlink.MAVLink_command_long_message(system_id, 1, command, 0, *padded)


def _halt_sends(swarm: Swarm, k: int) -> list[int]:
    swarm.bursts.halt(k)
    return [v for turn in _drain(swarm) for v in turn]


def test_first_halt_sends_everyone_then_only_the_halted_vehicle():
    swarm = _swarm()
    turns = _drain(swarm) or None
    assert turns is None  # nothing asked yet
    first = _halt_sends(swarm, 2)
    assert first[0] == 2 and sorted(set(first)) == list(range(N))
    assert first.count(2) == 2 and len(first) == N + 1
    assert _halt_sends(swarm, 2) == [2, 2]  # at rest since: nothing else changed


def test_turns_hold_at_most_a_few_vehicles_halted_one_first():
    swarm = _swarm()
    swarm.bursts.halt(4)
    turns = _drain(swarm)
    assert all(len(t) <= BURST_VEHICLES_PER_TURN for t in turns)
    assert next(iter(turns[0])) == 4 and 4 in turns[1]  # its second burst on the next turn


def test_a_query_changes_nothing_a_command_does():
    swarm = _swarm()
    _halt_sends(swarm, 0)
    link = swarm.links[3]
    link.handle(_command(link.system_id, MavCmd.REQUEST_MESSAGE, MessageId.HOME_POSITION), 0.0)
    link.handle(mavlink.MAVLink_param_request_read_message(link.system_id, 1, b"MIS_TAKEOFF_ALT",
                                                           -1), 0.0)
    assert _halt_sends(swarm, 0) == [0, 0]
    link.handle(_command(link.system_id, MavCmd.COMPONENT_ARM_DISARM, 1.0), 0.0)
    assert swarm.fleet.armed[3]
    assert _halt_sends(swarm, 0) == [0, 3, 0]
    # armed: it may change at every step, so every halt after steps sends it
    swarm.bursts.note_active()
    assert 3 in _halt_sends(swarm, 0)


def test_charging_faults_failures_and_lossy_links_send_more():
    swarm = _swarm()
    _halt_sends(swarm, 0)
    swarm.fleet.bat.charge_rate_pct_s[5] = 0.5
    swarm.bursts.note_active()
    assert sorted(set(_halt_sends(swarm, 0))) == [0, 5]
    swarm.fleet.bat.charge_rate_pct_s[5] = 0.0
    swarm.bursts.all_changed()  # a fault fired
    assert sorted(set(_halt_sends(swarm, 0))) == list(range(N))
    swarm.bursts.halt(1, also={4})  # a vehicle with a failure to report again
    assert sorted({v for t in _drain(swarm) for v in t}) == [1, 4]
    swarm.bursts.halt(1, every_vehicle=True)
    assert sorted({v for t in _drain(swarm) for v in t}) == list(range(N))


def test_which_messages_are_queries():
    asks = [
        _command(1, MavCmd.REQUEST_MESSAGE, MessageId.AUTOPILOT_VERSION),
        _command(1, MavCmd.REQUEST_CAMERA_INFORMATION, 1.0),
        _command(1, MavCmd.SET_MESSAGE_INTERVAL, MessageId.ATTITUDE, 1e6),
        mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 4, 3),
        mavlink.MAVLink_mission_request_list_message(1, 1, 0),
    ]
    acts = [
        _command(1, MavCmd.COMPONENT_ARM_DISARM, 1.0),
        _command(1, MavCmd.NAV_TAKEOFF, *[math.nan] * 7),
        mavlink.MAVLink_command_int_message(1, 1, 0, MavCmd.DO_REPOSITION, 0, 0, -1, 1, 0, 0,
                                            0, 0, 20.0),
        mavlink.MAVLink_mission_count_message(1, 1, 3, 0),
        mavlink.MAVLink_param_set_message(1, 1, b"MIS_TAKEOFF_ALT", 10.0, 9),
    ]
    assert [changes_state(m) for m in asks] == [False] * len(asks)
    assert [changes_state(m) for m in acts] == [True] * len(acts)

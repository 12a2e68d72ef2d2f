"""Quiet streams on a lockstep clock: heartbeats at their rates, every other stream only when
its vehicle may have changed (emulator.quiet_streams)."""

from __future__ import annotations

import numpy as np

from emulator.clock import ClockConfig
from emulator.link_faults import LinkFaults
from emulator.mavlink.codec import mavlink
from emulator.mavlink.streams import CAMERA_HEARTBEAT, DEFAULT_STREAMS
from emulator.quiet_streams import NEW_PEER_FULL_S, REFRESH_S, QuietStreams
from emulator.scenario import default_scenario
from emulator.swarm import Swarm
from mavlink_vocabulary import MavCmd, MessageId

N = 4
HB, GPI = int(MessageId.HEARTBEAT), int(MessageId.GLOBAL_POSITION_INT)


def _due(ks: list[int]) -> list[tuple[int, np.ndarray]]:
    return [(s.msg_id, np.array(ks, dtype=np.intp)) for s in DEFAULT_STREAMS]


def _sent(quiet: QuietStreams, wall_s: float, ks: list[int]) -> dict[int, list[int]]:
    return {m: sorted(k.tolist()) for m, k in quiet.filter(_due(ks), wall_s)}


def test_streams_go_out_once_per_change_heartbeats_always():
    quiet = QuietStreams(N, DEFAULT_STREAMS, 0.0)
    first = _sent(quiet, NEW_PEER_FULL_S, [0, 1, 2, 3])
    assert first[GPI] == [0, 1, 2, 3] and len(first) == len(DEFAULT_STREAMS)
    again = _sent(quiet, NEW_PEER_FULL_S + 0.1, [0, 1, 2, 3])
    assert again == {HB: [0, 1, 2, 3], CAMERA_HEARTBEAT: [0, 1, 2, 3]}
    quiet.mark([2])
    changed = _sent(quiet, NEW_PEER_FULL_S + 0.2, [0, 1, 2, 3])
    assert changed[GPI] == [2] and changed[HB] == [0, 1, 2, 3]
    # a stream not due yet keeps the change for its own turn
    quiet.mark([1])
    assert _sent(quiet, NEW_PEER_FULL_S + 0.3, [0])[HB] == [0]
    assert _sent(quiet, NEW_PEER_FULL_S + 0.4, [1])[GPI] == [1]


def test_a_burst_counts_as_sent_and_a_refresh_sends_all_again():
    quiet = QuietStreams(N, DEFAULT_STREAMS, 0.0)
    _sent(quiet, NEW_PEER_FULL_S, [0, 1, 2, 3])
    quiet.mark([0, 3])
    quiet.sent(np.array([3]))  # vehicle 3's burst went out
    assert _sent(quiet, NEW_PEER_FULL_S + 0.1, [0, 1, 2, 3])[GPI] == [0]
    refreshed = _sent(quiet, NEW_PEER_FULL_S + REFRESH_S + 0.1, [0, 1, 2, 3])
    assert refreshed[GPI] == [0, 1, 2, 3]


def test_a_new_ground_station_gets_every_stream_for_a_while_and_new_vehicles_theirs():
    quiet = QuietStreams(N, DEFAULT_STREAMS, 0.0)
    assert _sent(quiet, 1.0, [0])[GPI] == [0]
    assert _sent(quiet, 1.5, [0])[GPI] == [0]  # still the start's window
    _sent(quiet, NEW_PEER_FULL_S + 0.1, [0, 1, 2, 3])
    assert GPI not in _sent(quiet, NEW_PEER_FULL_S + 0.2, [0])
    quiet.new_peer(10.0)
    assert _sent(quiet, 10.5, [0])[GPI] == [0]
    assert _sent(quiet, 11.0, [0])[GPI] == [0]
    assert _sent(quiet, 10.0 + NEW_PEER_FULL_S + 0.1, [6])[GPI] == [6]  # joined: not yet sent


def _stream_log(swarm: Swarm) -> list[list[tuple[int, list[int]]]]:
    log: list[list[tuple[int, list[int]]]] = []
    send = swarm.out.send

    def record(due):
        turn = [(int(m), sorted(ks.tolist())) for m, ks in due if len(ks)]
        log.append(turn)
        send(iter([(m, np.array(ks, dtype=np.intp)) for m, ks in turn]))

    swarm.out.send = record  # type: ignore[method-assign]
    return log


def _positions_sent(swarm: Swarm, log: list, wall_s: float) -> list[int]:
    swarm.send_due_telemetry(wall_s)
    return next((ks for m, ks in log[-1] if m == GPI), [])


def test_a_lockstep_swarm_sends_only_what_changed_other_clocks_everything():
    period = {"GLOBAL_POSITION_INT": 10.0}
    lockstep = Swarm(default_scenario(N), clock=ClockConfig(stepped=True, lockstep=True),
                     telemetry_hz=period)
    stepped = Swarm(default_scenario(N), clock=ClockConfig(stepped=True), telemetry_hz=period)
    start = lockstep.streams.next_wakeup_s() + NEW_PEER_FULL_S
    logs = {id(s): _stream_log(s) for s in (lockstep, stepped)}
    for swarm in (lockstep, stepped):
        _positions_sent(swarm, logs[id(swarm)], start)
    assert _positions_sent(lockstep, logs[id(lockstep)], start + 1.0) == []
    assert _positions_sent(stepped, logs[id(stepped)], start + 1.0) == list(range(N))
    heartbeats = next(ks for m, ks in logs[id(lockstep)][-1] if m == HB)
    assert heartbeats == list(range(N))
    # a command changes vehicle 2: its streams go out at their next period, once
    link = lockstep.links[2]
    link.handle(mavlink.MAVLink_command_long_message(link.system_id, 1,
                                                     MavCmd.COMPONENT_ARM_DISARM, 0, 1.0,
                                                     0, 0, 0, 0, 0, 0), start + 1.0)
    assert _positions_sent(lockstep, logs[id(lockstep)], start + 2.0) == [2]
    assert _positions_sent(lockstep, logs[id(lockstep)], start + 3.0) == []
    # armed, it may change at every physics step
    lockstep.bursts.note_active()
    assert _positions_sent(lockstep, logs[id(lockstep)], start + 4.0) == [2]


def test_a_lossy_link_keeps_every_stream():
    faults = LinkFaults.from_json({"loss": 0.2}, "test", [v.id for v in
                                                          default_scenario(N).vehicles])
    swarm = Swarm(default_scenario(N), clock=ClockConfig(stepped=True, lockstep=True),
                  link_faults=faults)
    log = _stream_log(swarm)
    start = swarm.streams.next_wakeup_s() + NEW_PEER_FULL_S
    _positions_sent(swarm, log, start)
    assert _positions_sent(swarm, log, start + 1.0) == list(range(N))

"""How often the swarm gathers due telemetry: every 20 ms, or at a fifth of the shortest stream
period when every stream is slower (at most 0.1 s apart); a lockstep clock's quiet streams once
per shortest period (at most 0.5 s apart). The streams keep their rates."""

from __future__ import annotations

import numpy as np
import pytest

from emulator.mavlink.streams import StreamSchedule
from emulator.swarm import (
    QUIET_TELEMETRY_TICK_MAX_S,
    TELEMETRY_TICK_MAX_S,
    TELEMETRY_TICK_S,
    telemetry_tick_s,
)


@pytest.mark.parametrize(("shortest_s", "tick_s"), [
    (0.01, 0.01),                    # a client asked for 100 Hz
    (0.05, TELEMETRY_TICK_S),        # 20 Hz
    (0.1, TELEMETRY_TICK_S),         # the default streams (10 Hz)
    (0.25, 0.05),
    (0.5, TELEMETRY_TICK_MAX_S),     # a lockstep run's 2 Hz
    (2.0, TELEMETRY_TICK_MAX_S),
    (float("inf"), TELEMETRY_TICK_MAX_S),  # every stream off
])
def test_tick_follows_the_shortest_period(shortest_s: float, tick_s: float) -> None:
    assert telemetry_tick_s(shortest_s) == pytest.approx(tick_s)


@pytest.mark.parametrize(("shortest_s", "tick_s"), [
    (0.01, 0.01),                          # a client asked a lockstep swarm for 100 Hz
    (0.05, 0.05),
    (0.5, QUIET_TELEMETRY_TICK_MAX_S),     # a lockstep run's 2 Hz
    (2.0, QUIET_TELEMETRY_TICK_MAX_S),
    (float("inf"), QUIET_TELEMETRY_TICK_MAX_S),
])
def test_quiet_streams_are_gathered_once_a_period(shortest_s: float, tick_s: float) -> None:
    assert telemetry_tick_s(shortest_s, quiet=True) == pytest.approx(tick_s)


@pytest.mark.parametrize("quiet", [False, True])
def test_streams_keep_their_rates_at_the_slow_tick(quiet: bool) -> None:
    rates = {"GLOBAL_POSITION_INT": 2.0, "HEARTBEAT": 1.0, "HOME_POSITION": 0.5}
    schedule = StreamSchedule(7, 0.0, rates)
    tick = telemetry_tick_s(schedule.shortest_period_s(), quiet=quiet)
    sent: dict[int, np.ndarray] = {}
    for turn in range(1, int(60.0 / tick) + 1):
        for msg_id, ks in schedule.due(turn * tick):
            sent[msg_id] = sent.get(msg_id, np.zeros(7, dtype=int)) + np.bincount(ks, minlength=7)
    by_name = {spec.name: sent.get(spec.msg_id) for spec in schedule.streams}
    for name, hz in rates.items():
        counts = by_name[name]
        assert counts is not None and (np.abs(counts - 60.0 * hz) <= 1).all(), (name, counts)

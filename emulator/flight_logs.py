"""Flight logs from the ground truth: one ULog per flight (arm to disarm) of a vehicle.

Each log holds the vehicle's local position (NED about its own origin, as LOCAL_POSITION_NED)
and heading at up to 10 Hz, its battery, and its truth events as logged strings. Built when
a client lists the logs, from the recorder, so they are the flights as they happened.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from emulator.flight.fleet_view import FleetView
from emulator.truth_events import TruthEventKind
from emulator.ulog import LOG_LEVEL_WARNING, ULogWriter

__all__ = ["FlightLog", "flight_log", "flight_spans"]

SAMPLE_PERIOD_S = 0.1


@dataclass(frozen=True, slots=True)
class FlightLog:
    start_s: float  # simulated time of the arming
    end_s: float  # of the disarming (now while still armed)
    data: bytes  # the ULog file


def flight_spans(fleet: FleetView, vehicle_id: str) -> list[tuple[float, float]]:
    """(arm, disarm) simulated times of each flight, oldest first (now for one under way)."""
    spans: list[tuple[float, float]] = []
    armed_at: float | None = None
    for e in fleet.recorder.events(vehicle_id, kinds=(TruthEventKind.ARM, TruthEventKind.DISARM)):
        if e.kind is TruthEventKind.ARM and armed_at is None:
            armed_at = e.t_s
        elif e.kind is TruthEventKind.DISARM and armed_at is not None:
            spans.append((armed_at, e.t_s))
            armed_at = None
    if armed_at is not None:
        spans.append((armed_at, fleet.now_s))
    return spans


def _ulog(fleet: FleetView, k: int, vehicle_id: str, t0: float, t1: float) -> bytes:
    writer = ULogWriter(round(t0 * 1e6))
    writer.info("sys_name", "mavswarm")
    writer.info("ver_hw", "SITL")
    position = writer.topic("vehicle_local_position", [
        ("uint64_t", "timestamp"), ("float", "x"), ("float", "y"), ("float", "z"),
        ("float", "heading")])
    battery = writer.topic("battery_status", [("uint64_t", "timestamp"), ("float", "remaining")])
    ox, oy, oz = fleet.local_origin(k)
    rows = fleet.recorder.trajectory(vehicle_id, t0, t1)
    if len(rows):
        # one row per sample period (the last one at or before each instant)
        instants = np.arange(t0, t1 + 1e-9, SAMPLE_PERIOD_S)
        picks = np.clip(np.searchsorted(rows[:, 0], instants, side="right") - 1, 0, None)
        for t, i in zip(instants.tolist(), picks.tolist(), strict=True):
            _, x, y, z, yaw, pct = rows[i].tolist()
            us = round(t * 1e6)
            writer.data(position, us, y - oy, x - ox, -(z - oz),
                        math.atan2(math.sin(math.radians(yaw)), math.cos(math.radians(yaw))))
            writer.data(battery, us, pct / 100.0)
    for e in fleet.recorder.events(vehicle_id, t0, t1):
        level = LOG_LEVEL_WARNING if e.kind is TruthEventKind.FAILSAFE else None
        text = e.kind + "".join(f" {key}={value}" for key, value in e.data.items())
        if level is None:
            writer.log(round(e.t_s * 1e6), text)
        else:
            writer.log(round(e.t_s * 1e6), text, level)
    return bytes(writer)


def flight_log(fleet: FleetView, k: int, vehicle_id: str, t0_s: float,
               t1_s: float) -> FlightLog:
    """The log of vehicle k's flight from t0_s to t1_s."""
    return FlightLog(t0_s, t1_s, _ulog(fleet, k, vehicle_id, t0_s, t1_s))

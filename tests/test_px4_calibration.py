"""MAV_CMD_PREFLIGHT_CALIBRATION: the ACK, then PX4's "[cal]" progress STATUSTEXTs in order;
refused while armed; an unknown selection is unsupported."""

from __future__ import annotations

import math

import pytest

from mavlink_vocabulary import MavCmd, MavResult
from tests.memory_link import MemoryLink


def _calibrate(link: MemoryLink, *params: float) -> tuple[int, list[str]]:
    since = len(link.received)
    ack = link.command_long(1, MavCmd.PREFLIGHT_CALIBRATION, *params)
    texts = [m.text for m in link.messages("STATUSTEXT", system=1, since=since)]
    return ack.result, texts


def test_gyro_calibration_reports_started_progress_done() -> None:
    link = MemoryLink(1, telemetry=False)
    result, texts = _calibrate(link, 1, 0, 0, 0, 0, 0, 0)
    assert result == MavResult.ACCEPTED
    assert texts[0] == "[cal] calibration started: 2 gyro"
    assert texts[-1] == "[cal] calibration done: gyro"
    progress = [int(t[len("[cal] progress <"):-1]) for t in texts if "progress" in t]
    assert progress == sorted(progress) and progress[-1] == 100
    assert [e.data["sensor"] for e in link.fleet.recorder.events("d1", kinds="calibration")] \
        == ["gyro"]


@pytest.mark.parametrize(("params", "sensor"), [((0, 0, 0, 0, 1, 0, 0), "accel"),
                                                ((0, 1, 0, 0, 0, 0, 0), "mag")])
def test_six_side_calibrations_walk_through_every_orientation(params, sensor) -> None:
    link = MemoryLink(1, telemetry=False)
    result, texts = _calibrate(link, *params)
    assert result == MavResult.ACCEPTED
    assert texts[0] == f"[cal] calibration started: 2 {sensor}"
    detected = [t.split()[1] for t in texts if t.endswith("orientation detected")]
    assert sorted(detected) == sorted(["down", "up", "left", "right", "front", "back"])
    assert texts[-1] == f"[cal] calibration done: {sensor}"


def test_level_horizon_and_refusals() -> None:
    link = MemoryLink(1, telemetry=False)
    result, texts = _calibrate(link, 0, 0, 0, 0, 2, 0, 0)
    assert (result, texts[-1]) == (MavResult.ACCEPTED, "[cal] calibration done: level")
    result, texts = _calibrate(link, 0, 0, 0, 0, 0, 0, 0)
    assert (result, texts) == (MavResult.ACCEPTED, ["[cal] calibration cancelled"])
    result, texts = _calibrate(link, 0, 0, 0, 0, 0, 0, 1)  # ESC calibration: not emulated
    assert result == MavResult.UNSUPPORTED
    result, texts = _calibrate(link, math.nan, math.nan, math.nan, math.nan, math.nan)
    assert result == MavResult.UNSUPPORTED
    assert link.command_long(1, MavCmd.COMPONENT_ARM_DISARM, 1.0).result == 0
    result, texts = _calibrate(link, 1, 0, 0, 0, 0, 0, 0)
    assert result == MavResult.TEMPORARILY_REJECTED
    assert texts == ["[cal] calibration denied: system armed"]

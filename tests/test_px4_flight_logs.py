"""Flight logs over the MAVLink log protocol, in memory: one ULog per flight, listed with
LOG_ENTRY, downloaded in LOG_DATA chunks, read back with pyulog (PX4's own log reader) and
compared with the ground truth; erased with LOG_ERASE."""

from __future__ import annotations

import io
import math

import numpy as np
import pytest
from pyulog import ULog

from mavlink_vocabulary import MavCmd, MavComponent
from tests.memory_link import MemoryLink


def _fly_once(link: MemoryLink) -> None:
    link.arm_and_take_off(1, 8.0)
    link.advance(2.0)
    assert link.command_long(1, MavCmd.NAV_LAND, *[math.nan] * 7).result == 0
    link.advance(30.0)
    assert not link.fleet.autopilots[0].armed


def _entries(link: MemoryLink) -> list:
    since = link.send(link.mav.log_request_list_encode(1, MavComponent.AUTOPILOT1, 0, 0xFFFF))
    return link.messages("LOG_ENTRY", system=1, since=since)


def _download(link: MemoryLink, log_id: int, size: int) -> bytes:
    since = link.send(link.mav.log_request_data_encode(1, MavComponent.AUTOPILOT1, log_id, 0,
                                                       0xFFFFFFFF))
    data = bytearray(size)
    for m in link.messages("LOG_DATA", system=1, since=since):
        data[m.ofs:m.ofs + m.count] = bytes(m.data[:m.count])
    # past the end: one empty chunk
    since = link.send(link.mav.log_request_data_encode(1, MavComponent.AUTOPILOT1, log_id, size,
                                                       90))
    assert [m.count for m in link.messages("LOG_DATA", system=1, since=since)] == [0]
    return bytes(data)


def test_each_flight_is_a_ulog_of_the_ground_truth() -> None:
    link = MemoryLink(1, telemetry=False)
    assert [(e.num_logs, e.size) for e in _entries(link)] == [(0, 0)]  # no flight yet
    _fly_once(link)
    _fly_once(link)
    entries = _entries(link)
    assert [(e.id, e.num_logs, e.last_log_num) for e in entries] == [(0, 2, 1), (1, 2, 1)]
    ulog = ULog(io.BytesIO(_download(link, 1, entries[1].size)))
    position = ulog.get_dataset("vehicle_local_position").data
    truth = link.fleet.recorder.trajectory("d1")
    arms = [e.t_s for e in link.fleet.recorder.events("d1", kinds="arm")]
    t_us = position["timestamp"]
    assert t_us[0] == round(arms[1] * 1e6)
    # the highest point of the flight is the take-off altitude, as flown
    assert -position["z"].min() == pytest.approx(
        truth[truth[:, 0] >= arms[1]][:, 3].max(), abs=0.2)
    assert np.abs(position["x"]).max() < 0.5 and np.abs(position["y"]).max() < 0.5
    messages = [m.message for m in ulog.logged_messages]
    assert messages[0] == "arm" and "landed" in " ".join(messages)
    assert ulog.msg_info_dict["sys_name"] == "mavswarm"


def test_log_erase_empties_the_list() -> None:
    link = MemoryLink(1, telemetry=False)
    _fly_once(link)
    assert _entries(link)[0].num_logs == 1
    link.send(link.mav.log_erase_encode(1, MavComponent.AUTOPILOT1))
    assert [(e.num_logs, e.size) for e in _entries(link)] == [(0, 0)]
    # a bad id is not answered
    since = link.send(link.mav.log_request_data_encode(1, MavComponent.AUTOPILOT1, 7, 0, 90))
    assert not link.messages("LOG_DATA", since=since)

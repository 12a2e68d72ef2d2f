"""The MAVLink log protocol (LOG_REQUEST_LIST / LOG_ENTRY, LOG_REQUEST_DATA / LOG_DATA,
LOG_ERASE, LOG_REQUEST_END) serving a vehicle's flight logs (emulator.flight_logs), as PX4
serves its ULog files: ids from 0, one LOG_ENTRY with num_logs 0 when there are none, data
in 90-byte LOG_DATA chunks and a zero-length chunk past the end. Every method returns the
messages to send.
"""

from __future__ import annotations

from emulator.flight.autopilot import Autopilot
from emulator.flight_logs import FlightLog, flight_log, flight_spans
from emulator.mavlink.codec import mavlink
from mavlink_vocabulary import MessageId

__all__ = ["LOG_DATA_BYTES", "LOG_MESSAGES", "LogTransfer"]

LOG_DATA_BYTES = 90
MAX_CHUNKS_PER_REQUEST = 2000  # 180 kB: a client asks again for what is left
LOG_MESSAGES = (MessageId.LOG_REQUEST_LIST, MessageId.LOG_REQUEST_DATA, MessageId.LOG_ERASE,
                MessageId.LOG_REQUEST_END)
Messages = list[mavlink.MAVLink_message]


class LogTransfer:
    """The log micro-service of one vehicle."""

    def __init__(self, ap: Autopilot) -> None:
        self.ap = ap
        self._logs: list[FlightLog] = []
        self._built: dict[tuple[float, float], FlightLog] = {}  # a finished flight's log
        self._erased_at_s = -1.0

    def _refresh(self) -> list[FlightLog]:
        ap = self.ap
        built, logs = self._built, []
        spans = flight_spans(ap.fleet, ap.vehicle_id)
        for i, span in enumerate(spans):
            if span[0] > self._erased_at_s:
                log = built.get(span) or flight_log(ap.fleet, ap.k, ap.vehicle_id, *span)
                if not (ap.armed and i == len(spans) - 1):  # one under way grows
                    built[span] = log
                logs.append(log)
        self._logs = logs
        return logs

    def files(self) -> list[bytes]:
        """The flight logs' contents, oldest first (served over FTP too)."""
        return [log.data for log in self._refresh()]

    def handle(self, m) -> Messages:
        msg_id = m.get_msgId()
        if msg_id == MessageId.LOG_REQUEST_LIST:
            return self._entries(m.start, m.end)
        if msg_id == MessageId.LOG_REQUEST_DATA:
            return self._data(m.id, m.ofs, m.count)
        if msg_id == MessageId.LOG_ERASE:
            self._erased_at_s = self.ap.now_s
            self._logs = []
        return []  # LOG_REQUEST_END: nothing is streaming in between requests

    def _entries(self, start: int, end: int) -> Messages:
        logs = self._refresh()
        n = len(logs)
        if not n:
            return [mavlink.MAVLink_log_entry_message(0, 0, 0, 0, 0)]
        return [mavlink.MAVLink_log_entry_message(i, n, n - 1, 0, len(logs[i].data))
                for i in range(start, min(end, n - 1) + 1)]

    def _data(self, log_id: int, ofs: int, count: int) -> Messages:
        if not self._logs:
            self._refresh()
        if not 0 <= log_id < len(self._logs):
            return []
        data = self._logs[log_id].data
        end = min(len(data), ofs + count, ofs + LOG_DATA_BYTES * MAX_CHUNKS_PER_REQUEST)
        if ofs >= end:
            return [mavlink.MAVLink_log_data_message(log_id, ofs, 0, bytes(LOG_DATA_BYTES))]
        out = []
        for at in range(ofs, end, LOG_DATA_BYTES):
            chunk = data[at:min(at + LOG_DATA_BYTES, end)]
            out.append(mavlink.MAVLink_log_data_message(
                log_id, at, len(chunk), chunk.ljust(LOG_DATA_BYTES, b"\0")))
        return out

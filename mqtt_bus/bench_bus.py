"""A benchmark run on the bus: each task's record as it ends, in the order `results.jsonl`
holds them, and the run's progress. The orchestrator is synchronous, so the connection runs
on a thread of its own with its own event loop; `record()` only hands a message over.

A record is published as written, less its `checks` (the hidden check tree with its
measured values): the verdict counts stay.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import contextlib
import os
import threading
from collections.abc import Mapping
from typing import Any

from mqtt_bus.connection import BusConnection, BusStats
from mqtt_bus.payloads import bench_progress_payload, bench_status_payload, encode
from mqtt_bus.topics import BenchTopics
from mqtt_bus.url import BrokerUrl

__all__ = ["HIDDEN_RECORD_FIELDS", "BenchBus", "public_record"]

HIDDEN_RECORD_FIELDS = ("checks",)


def public_record(record: Mapping[str, Any]) -> dict[str, Any]:
    """A task record without what the hidden checks hold."""
    return {k: v for k, v in record.items() if k not in HIDDEN_RECORD_FIELDS}


class BenchBus:
    """Use `with BenchBus(url, run) as bus: ... bus.record(r)`. Records are QoS 1 and queue
    while the broker is away (up to `queue_size`); on exit the queue is flushed for at most
    `flush_timeout_s`."""

    def __init__(self, url: BrokerUrl, run: str, *, queue_size: int = 100_000,
                 flush_timeout_s: float = 10.0) -> None:
        self.topics = BenchTopics(url.prefix, run)
        self.url = url
        self._queue_size = queue_size
        self._flush_timeout_s = flush_timeout_s
        self._loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self._loop.run_forever,
                                        name=f"mqtt-bench-{run}", daemon=True)
        self._connection: BusConnection | None = None
        self.counts = {"tasks": 0, "passed": 0, "failed": 0}

    def __enter__(self) -> BenchBus:
        self._thread.start()
        future = asyncio.run_coroutine_threadsafe(self._open(), self._loop)
        future.result(timeout=30)
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    async def _open(self) -> None:
        run = self.topics.run
        self._connection = BusConnection(
            self.url, client_id=f"mavswarm-bench-{run}-{os.getpid()}",
            status_topic=self.topics.status,
            online_payload=encode(bench_status_payload(True, run)),
            offline_payload=encode(bench_status_payload(False, run)),
            queue_size=self._queue_size)
        await self._connection.__aenter__()
        await self._connection.wait_connected(2.0)

    @property
    def stats(self) -> BusStats:
        assert self._connection is not None
        return self._connection.stats

    def record(self, record: Mapping[str, Any]) -> None:
        """One task's record, as it was appended to results.jsonl."""
        self.counts["tasks"] += 1
        self.counts["passed" if record.get("passed") else "failed"] += 1
        progress = bench_progress_payload(self.topics.run, self.counts, last=record)
        self._loop.call_soon_threadsafe(self._publish, encode(public_record(record)),
                                        encode(progress))

    def _publish(self, record: bytes, progress: bytes) -> None:
        assert self._connection is not None
        self._connection.publish(self.topics.tasks, record, qos=1)
        self._connection.publish(self.topics.progress, progress, qos=1, retain=True)

    def finish(self, total_records: int) -> None:
        """The run ended with `total_records` in results.jsonl."""
        progress = bench_progress_payload(self.topics.run, self.counts,
                                          records_in_results=total_records)
        self._loop.call_soon_threadsafe(self._publish_progress, encode(progress))

    def _publish_progress(self, progress: bytes) -> None:
        assert self._connection is not None
        self._connection.publish(self.topics.progress, progress, qos=1, retain=True)

    def close(self) -> None:
        if not self._thread.is_alive():
            return
        if self._connection is not None:
            future = asyncio.run_coroutine_threadsafe(
                self._connection.close(self._flush_timeout_s), self._loop)
            with contextlib.suppress(concurrent.futures.TimeoutError, TimeoutError):
                future.result(timeout=self._flush_timeout_s + 5.0)
        self._loop.call_soon_threadsafe(self._loop.stop)
        self._thread.join(timeout=5.0)
        self._loop.close()

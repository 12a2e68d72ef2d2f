"""Helpers for the MQTT tests: a broker fixture (tests/mosquitto_broker.py) and a subscriber
that keeps every message it receives, with waits on them."""

from __future__ import annotations

import asyncio
import contextlib
import json
import time
from collections.abc import AsyncIterator, Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import aiomqtt
import pytest

from tests.mosquitto_broker import PASSWORDS, Broker, mosquitto_binary

__all__ = ["Got", "Listener", "broker", "listener", "request"]


@pytest.fixture
def broker(tmp_path: Path) -> Iterator[Broker]:
    """A running Mosquitto with the shipped ACL, stopped after the test."""
    if mosquitto_binary() is None:
        pytest.skip("mosquitto is not installed (.ci/run installs Debian's mosquitto)")
    b = Broker(tmp_path)
    b.start()
    try:
        yield b
    finally:
        b.stop()


@dataclass(frozen=True)
class Got:
    topic: str
    payload: dict[str, Any]
    retain: bool
    wall_s: float

    @property
    def kind(self) -> str:
        return self.topic.rsplit("/", 1)[-1]


class Listener:
    """A client of `user` subscribed to `topic_filter`, keeping what arrives in `got`."""

    def __init__(self, client: aiomqtt.Client) -> None:
        self.client = client
        self.got: list[Got] = []
        self._new = asyncio.Event()

    async def _read(self) -> None:
        async for m in self.client.messages:
            payload = m.payload if isinstance(m.payload, bytes) else str(m.payload).encode()
            self.got.append(Got(m.topic.value, json.loads(payload), bool(m.retain),
                                time.monotonic()))
            self._new.set()

    async def wait_for(self, match: Callable[[Got], bool], timeout_s: float = 30.0,
                       after: int = 0) -> Got:
        """The first message (from index `after`) that matches, waiting for it."""
        deadline = time.monotonic() + timeout_s
        while True:
            for got in self.got[after:]:
                if match(got):
                    return got
            left = deadline - time.monotonic()
            if left <= 0:
                kinds = sorted({g.topic for g in self.got[after:]})[:20]
                raise AssertionError(f"no matching message in {timeout_s} s; seen {kinds}")
            self._new.clear()
            with contextlib.suppress(TimeoutError):
                async with asyncio.timeout(min(left, 0.5)):
                    await self._new.wait()

    def of(self, kind: str, drone: str | None = None) -> list[Got]:
        return [g for g in self.got if g.kind == kind
                and (drone is None or g.payload.get("drone") == drone)]


@contextlib.asynccontextmanager
async def listener(b: Broker, user: str | None, topic_filter: str | None = None
                   ) -> AsyncIterator[Listener]:
    """A subscribed Listener (user None: anonymous, which the broker refuses)."""
    client = aiomqtt.Client("127.0.0.1", b.port, username=user,
                            password=PASSWORDS.get(user or ""), timeout=10,
                            protocol=aiomqtt.ProtocolVersion.V5)
    async with client:
        lst = Listener(client)
        if topic_filter:
            await client.subscribe(topic_filter, qos=1)
        task = asyncio.create_task(lst._read(), name="test-mqtt-listener")
        try:
            yield lst
        finally:
            task.cancel()
            with contextlib.suppress(asyncio.CancelledError, aiomqtt.MqttError):
                await task


_ids = iter(range(1, 1_000_000))


async def request(lst: Listener, base: str, drone: str, tool: str, timeout_s: float = 60.0,
                  **args: Any) -> dict[str, Any]:
    """Publish a command as lst's user and wait for its reply (lst subscribed to replies)."""
    request_id = f"r{next(_ids)}"
    await lst.client.publish(f"{base}/{drone}/services",
                             json.dumps({"id": request_id, "tool": tool, "args": args}), qos=1)
    got = await lst.wait_for(lambda g: g.kind == "services_reply"
                             and g.payload.get("id") == request_id, timeout_s)
    return got.payload

"""One broker connection that never stands in the swarm's way.

`publish` only puts a message on a bounded queue and returns at once; a background task
sends it. While the broker is unreachable, periodic (QoS 0) messages are dropped (they would
be stale by the time it is back) and QoS 1 ones (events, records) wait on the queue, in
order; when the queue is full, messages are dropped and counted. The connection comes back
with exponential backoff, and each time it does it announces the session online again and
republishes every retained message (the broker may have lost them). The broker's Last Will
marks the session offline when the process dies.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import random
import socket
from collections.abc import Callable, Iterable
from dataclasses import dataclass

import aiomqtt
import paho.mqtt.client as paho

from mqtt_bus.url import BrokerUrl

__all__ = ["BusConnection", "BusStats"]

log = logging.getLogger("mavswarm.mqtt")

BATCH = 64  # aiomqtt scans its pending calls on every publish: keep batches small
PAHO_QUEUE = 5_000  # paho's own outgoing queue, bounded too (a full one counts as a drop)


@dataclass
class BusStats:
    """What the connection did so far."""

    published: int = 0
    dropped_full: int = 0  # the queue (or the client library's) was full
    dropped_offline: int = 0  # periodic messages while the broker was unreachable
    connects: int = 0
    connected: bool = False
    last_error: str = ""

    @property
    def dropped(self) -> int:
        return self.dropped_full + self.dropped_offline


@dataclass(frozen=True, slots=True)
class _Message:
    topic: str
    payload: bytes
    qos: int
    retain: bool


class BusConnection:
    """A broker connection run by a named background task. Use `async with`.

    `status_topic` gets `online_payload` (retained) on every connect and `offline_payload`
    as the Last Will and on a clean exit. `incoming(topic, payload)` receives the messages of
    `subscriptions`."""

    def __init__(self, url: BrokerUrl, *, client_id: str, status_topic: str,
                 online_payload: bytes, offline_payload: bytes,
                 subscriptions: Iterable[str] = (),
                 incoming: Callable[[str, bytes], None] | None = None,
                 queue_size: int = 10_000, keepalive_s: int = 10,
                 backoff_s: tuple[float, float] = (0.25, 5.0)) -> None:
        if queue_size < 1:
            raise ValueError(f"queue_size must be at least 1, got {queue_size}")
        if subscriptions and incoming is None:
            raise ValueError("subscriptions need an incoming callback")
        self.url = url
        self.client_id = client_id
        self.status_topic = status_topic
        self._online = online_payload
        self._offline = offline_payload
        self._subscriptions = tuple(subscriptions)
        self._incoming = incoming
        self._queue: asyncio.Queue[_Message] = asyncio.Queue(queue_size)
        self._retained: dict[str, _Message] = {}
        self._resend: list[_Message] = []  # QoS 1 messages a lost connection did not confirm
        self._keepalive_s = keepalive_s
        self._backoff_s = backoff_s
        self._task: asyncio.Task[None] | None = None
        self._client: aiomqtt.Client | None = None
        self._inflight = 0  # messages the writer took off the queue and awaits
        self._warned = False
        self.stats = BusStats()
        self.connected_event = asyncio.Event()

    # ----------------------------------------------------------- lifecycle
    async def __aenter__(self) -> BusConnection:
        self._task = asyncio.create_task(self._run(), name=f"mqtt-bus-{self.client_id}")
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.close()

    async def close(self, flush_timeout_s: float = 2.0) -> None:
        """Send what is queued (for at most flush_timeout_s), mark the session offline and
        disconnect."""
        if self._task is None:
            return
        if self.stats.connected:
            with contextlib.suppress(TimeoutError):
                async with asyncio.timeout(flush_timeout_s):
                    while (self._inflight or not self._queue.empty()) \
                            and self.stats.connected:
                        await asyncio.sleep(0.01)
            client = self._client
            if client is not None and self.stats.connected:
                with contextlib.suppress(aiomqtt.MqttError, TimeoutError):
                    await client.publish(self.status_topic, self._offline, qos=1, retain=True,
                                         timeout=flush_timeout_s)
        self._task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await self._task
        self._task = None

    async def wait_connected(self, timeout_s: float) -> bool:
        """True once connected, subscribed and announced online (False after timeout_s)."""
        with contextlib.suppress(TimeoutError):
            async with asyncio.timeout(timeout_s):
                await self.connected_event.wait()
        return self.connected_event.is_set()

    # ------------------------------------------------------------ publishing
    def publish(self, topic: str, payload: bytes, *, qos: int = 0, retain: bool = False
                ) -> bool:
        """Queue a message; never waits. Retained messages are remembered and republished
        after a reconnect; QoS 1 messages (events, records) wait on the queue while the
        broker is unreachable; QoS 0 ones (periodic telemetry) are then dropped. False when
        the message was dropped."""
        message = _Message(topic, payload, qos, retain)
        if retain:
            self._retained[topic] = message
            if not self.stats.connected:  # sent from the cache once connected
                return True
        if not self.stats.connected and qos == 0:
            self.stats.dropped_offline += 1
            return False
        try:
            self._queue.put_nowait(message)
        except asyncio.QueueFull:
            self.stats.dropped_full += 1
            return False
        return True

    @property
    def queued(self) -> int:
        return self._queue.qsize()

    # ------------------------------------------------------------ the task
    def _client_for(self) -> aiomqtt.Client:
        url = self.url
        client = aiomqtt.Client(
            url.host, url.port, username=url.username, password=url.password,
            identifier=self.client_id, protocol=aiomqtt.ProtocolVersion.V5,
            will=aiomqtt.Will(self.status_topic, self._offline, qos=1, retain=True),
            keepalive=self._keepalive_s, tls_context=url.tls_context(), timeout=10.0,
            max_queued_outgoing_messages=PAHO_QUEUE,
            # small messages (a command's reply) go out at once, not after Nagle's delay
            socket_options=[(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)],
        )
        # batches, and the retained messages after a reconnect, are awaited together
        client.pending_calls_threshold = 1_000_000
        return client

    async def _run(self) -> None:
        delay = self._backoff_s[0]
        while True:
            try:
                async with self._client_for() as client:
                    self._client = client
                    self.stats.connects += 1
                    self.stats.connected = True
                    self._warned = False
                    delay = self._backoff_s[0]
                    await self._session(client)
            except (aiomqtt.MqttError, OSError) as error:
                self.stats.last_error = str(error)
                if self.stats.connected or not self._warned:  # once per outage
                    log.warning("MQTT broker %s: %s; reconnecting", self.url.redacted(), error)
                    self._warned = True
            finally:
                self._client = None
                self.stats.connected = False
                self.connected_event.clear()
            self._drop_periodic()
            await asyncio.sleep(delay * random.uniform(0.8, 1.2))
            delay = min(delay * 2.0, self._backoff_s[1])

    def _drop_periodic(self) -> None:
        """While offline only QoS 1 messages stay queued (retained ones are resent from the
        cache on reconnect)."""
        kept: list[_Message] = []
        while not self._queue.empty():
            message = self._queue.get_nowait()
            if message.qos > 0 and not message.retain:
                kept.append(message)
            elif not message.retain:
                self.stats.dropped_offline += 1
        for message in kept:
            self._queue.put_nowait(message)

    async def _session(self, client: aiomqtt.Client) -> None:
        for topic in self._subscriptions:  # before "online": online means listening
            await client.subscribe(topic, qos=1)
        await client.publish(self.status_topic, self._online, qos=1, retain=True)
        self.connected_event.set()  # subscribed and online
        # side by side, not one acknowledgement after another (paho keeps their order)
        retained = list(self._retained.values())
        await asyncio.gather(*(client.publish(m.topic, m.payload, qos=m.qos, retain=True)
                               for m in retained))
        self.stats.published += len(retained)
        resend, self._resend = self._resend, []
        try:
            await asyncio.gather(*(client.publish(m.topic, m.payload, qos=m.qos)
                                   for m in resend))
        except aiomqtt.MqttError:
            self._resend = resend + self._resend
            raise
        self.stats.published += len(resend)
        # The reader also notices a lost connection while nothing is being sent.
        tasks = [asyncio.create_task(self._read(client), name=f"mqtt-read-{self.client_id}"),
                 asyncio.create_task(self._write(client), name=f"mqtt-write-{self.client_id}")]
        try:
            done, _ = await asyncio.wait(tasks, return_when=asyncio.FIRST_COMPLETED)
        finally:
            for task in tasks:
                task.cancel()
            for task in tasks:
                with contextlib.suppress(asyncio.CancelledError, aiomqtt.MqttError):
                    await task
        for task in done:
            task.result()
        raise aiomqtt.MqttError("the connection ended")

    async def _read(self, client: aiomqtt.Client) -> None:
        async for message in client.messages:
            if self._incoming is None:
                continue
            payload = message.payload if isinstance(message.payload, bytes) else \
                str(message.payload).encode()
            try:
                self._incoming(message.topic.value, payload)
            except Exception:  # the I/O edge: a handler bug must not end the connection
                log.exception("MQTT message on %s not handled", message.topic.value)

    async def _write(self, client: aiomqtt.Client) -> None:
        # QoS 0 telemetry is handed to the client's paho core without awaiting each write:
        # aiomqtt's publish awaits every message's write and scans its pending calls each
        # time, which at 2,500 messages a second costs more than the swarm's physics. paho's
        # own queue is bounded (PAHO_QUEUE): beyond it a message is dropped and counted.
        core = getattr(client, "_client", None)
        while True:
            batch = [await self._queue.get()]
            while len(batch) < BATCH and not self._queue.empty():
                batch.append(self._queue.get_nowait())
            acknowledged = []
            for message in batch:
                if message.qos == 0 and core is not None:
                    rc = core.publish(message.topic, message.payload, 0, message.retain).rc
                    if rc == paho.MQTT_ERR_SUCCESS:
                        self.stats.published += 1
                    elif rc == paho.MQTT_ERR_QUEUE_SIZE:
                        self.stats.dropped_full += 1
                    else:
                        self.stats.dropped_offline += 1
                        raise aiomqtt.MqttCodeError(rc, "Could not publish message")
                else:
                    acknowledged.append(message)
            if not acknowledged:
                await asyncio.sleep(0)  # let the loop write what paho queued
                continue
            self._inflight = len(acknowledged)
            try:
                results = await asyncio.gather(
                    *(client.publish(m.topic, m.payload, qos=m.qos, retain=m.retain)
                      for m in acknowledged), return_exceptions=True)
            finally:
                self._inflight = 0
            failure: BaseException | None = None
            for message, result in zip(acknowledged, results, strict=True):
                if result is None:
                    self.stats.published += 1
                elif isinstance(result, aiomqtt.MqttCodeError) and \
                        result.rc == paho.MQTT_ERR_QUEUE_SIZE:
                    self.stats.dropped_full += 1
                elif isinstance(result, aiomqtt.MqttError):
                    if message.qos > 0 and not message.retain:  # sent first after reconnect
                        self._resend.append(message)
                    elif not message.retain:
                        self.stats.dropped_offline += 1
                    failure = failure or result
                elif isinstance(result, BaseException):
                    raise result
            if failure is not None:
                raise failure

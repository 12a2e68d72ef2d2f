"""The services a fleet behind a bridge offers the gateway: its own wall clock and nothing
else. A real PX4 or ArduPilot fleet has no drone-to-drone radio or sensor feed the gateway
could read, so those tools answer with a refusal that says why."""

from __future__ import annotations

import asyncio
import contextlib
import math
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

from mavlink_gateway.interfaces import Sensed, WorldWatch

__all__ = ["WallClockServices"]


@dataclass(frozen=True)
class _Nothing:
    targets: tuple[Sensed, ...] = field(default=())
    obstacles: tuple[Sensed, ...] = field(default=())
    vehicles: tuple[Sensed, ...] = field(default=())


class WallClockServices:
    """Services of a MAVLink fleet this process does not run (time: wall seconds)."""

    def __init__(self) -> None:
        self._start_s = time.monotonic()

    def clock_s(self) -> float:
        return time.monotonic() - self._start_s

    @contextlib.contextmanager
    def clock_limit(self, t_s: float) -> Iterator[None]:
        yield

    @property
    def lockstep(self) -> bool:
        return False

    def pin(self) -> object:
        return object()

    def unpin(self, token: object) -> None:
        pass

    def refresh_telemetry(self, drone_id: str) -> None:
        pass

    def repeat_status_texts(self, drone_id: str) -> int:
        return 0

    def watch(self, drone_id: str | None = None, *, until_s: float = math.inf,
              advance: bool = False, message_for: str | None = None) -> WorldWatch:
        raise RuntimeError("a bridged fleet has no lockstep clock to watch")

    async def advance(self, seconds: float) -> None:
        await asyncio.sleep(seconds)

    def sense(self, drone_id: str) -> _Nothing:
        return _Nothing()

    def send_message(self, sender: str, recipient: str, text: str) -> Any:
        raise ValueError("this fleet has no drone-to-drone radio behind the bridge")

    def broadcast(self, sender: str, text: str) -> int:
        raise ValueError("this fleet has no drone-to-drone radio behind the bridge")

    def read_messages(self, drone_id: str) -> list[Any]:
        raise ValueError("this fleet has no drone-to-drone radio behind the bridge")

    def operator_land_all(self) -> None:
        raise ValueError("operator resets are not offered behind a bridge")

    def operator_reset_batteries(self, pct: float = 100.0) -> None:
        raise ValueError("operator resets are not offered behind a bridge")

    def operator_reset_to_start(self) -> None:
        raise ValueError("operator resets are not offered behind a bridge")

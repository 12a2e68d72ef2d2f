"""The MQTT bus listens to each autopilot through a tee in front of its MAVLink link: the tee
must forward every event an autopilot tells its listener, or a swarm on the bus breaks where
one without it flies (a mission's payload item, say)."""

from __future__ import annotations

import inspect as pyinspect
from typing import Any

from emulator.flight.listener import AutopilotListener
from mqtt_bus.swarm_view import _Tee


class _Recorder:
    def __init__(self) -> None:
        self.calls: list[tuple[str, tuple[Any, ...]]] = []

    def __getattr__(self, name: str) -> Any:
        return lambda *args: self.calls.append((name, args))


def test_the_tee_forwards_every_listener_event_to_the_link() -> None:
    events = [name for name, _ in pyinspect.getmembers(AutopilotListener, pyinspect.isfunction)
              if name.startswith("on_")]
    assert "on_payload_item" in events
    link = _Recorder()
    tee = _Tee(link, lambda *_: None, lambda *_: None)  # type: ignore[arg-type]
    for name in events:
        arity = len(pyinspect.signature(getattr(AutopilotListener, name)).parameters) - 1
        getattr(tee, name)(*(object() for _ in range(arity)))
    assert [name for name, _ in link.calls] == events

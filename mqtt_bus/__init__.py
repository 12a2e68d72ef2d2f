"""mqtt_bus: the swarm's telemetry, state, events and commands on an MQTT broker (aiomqtt).

Topics are in `mqtt_bus.topics`, payload schemas in `mqtt_bus.schemas`. Publishing never
waits on the broker (`mqtt_bus.connection`); commands run the agent tools' registry
(`mqtt_bus.commands`). It sits above the agent side and the emulator, below the benchmark.
"""

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from mqtt_bus.bench_bus import BenchBus, public_record
    from mqtt_bus.commands import CommandService, CommandUnavailable, drone_tool_names
    from mqtt_bus.connection import BusConnection, BusStats
    from mqtt_bus.payloads import DroneSample
    from mqtt_bus.session_bus import SessionBus
    from mqtt_bus.swarm_bus import gateway_session_bus, swarm_session_bus
    from mqtt_bus.telemetry import FleetView, TelemetryPublisher
    from mqtt_bus.topics import DEFAULT_PREFIX, BenchTopics, SessionTopics
    from mqtt_bus.url import BrokerUrl, parse_broker_url

_EXPORTS = {
    "BenchBus": "mqtt_bus.bench_bus",
    "BenchTopics": "mqtt_bus.topics",
    "BrokerUrl": "mqtt_bus.url",
    "BusConnection": "mqtt_bus.connection",
    "BusStats": "mqtt_bus.connection",
    "CommandService": "mqtt_bus.commands",
    "CommandUnavailable": "mqtt_bus.commands",
    "DEFAULT_PREFIX": "mqtt_bus.topics",
    "DroneSample": "mqtt_bus.payloads",
    "FleetView": "mqtt_bus.telemetry",
    "SessionBus": "mqtt_bus.session_bus",
    "SessionTopics": "mqtt_bus.topics",
    "TelemetryPublisher": "mqtt_bus.telemetry",
    "drone_tool_names": "mqtt_bus.commands",
    "gateway_session_bus": "mqtt_bus.swarm_bus",
    "parse_broker_url": "mqtt_bus.url",
    "public_record": "mqtt_bus.bench_bus",
    "swarm_session_bus": "mqtt_bus.swarm_bus",
}
"""Where each public name is defined: imported on first use, so that importing one
module of mqtt_bus (its command line, its topics) does not load the rest."""

__all__ = [
    "DEFAULT_PREFIX",
    "BenchBus",
    "BenchTopics",
    "BrokerUrl",
    "BusConnection",
    "BusStats",
    "CommandService",
    "CommandUnavailable",
    "DroneSample",
    "FleetView",
    "SessionBus",
    "SessionTopics",
    "TelemetryPublisher",
    "drone_tool_names",
    "gateway_session_bus",
    "parse_broker_url",
    "public_record",
    "swarm_session_bus",
]


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})

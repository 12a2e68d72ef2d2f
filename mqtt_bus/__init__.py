"""mqtt_bus: the swarm's telemetry, state, events and commands on an MQTT broker (aiomqtt).

Topics are in `mqtt_bus.topics`, payload schemas in `mqtt_bus.schemas`. Publishing never
waits on the broker (`mqtt_bus.connection`); commands run the agent tools' registry
(`mqtt_bus.commands`). It sits above the agent side and the emulator, below the benchmark.
"""

from mqtt_bus.bench_bus import BenchBus, public_record
from mqtt_bus.commands import CommandService, CommandUnavailable, drone_tool_names
from mqtt_bus.connection import BusConnection, BusStats
from mqtt_bus.payloads import DroneSample
from mqtt_bus.session_bus import SessionBus
from mqtt_bus.swarm_bus import gateway_session_bus, swarm_session_bus
from mqtt_bus.telemetry import FleetView, TelemetryPublisher
from mqtt_bus.topics import DEFAULT_PREFIX, BenchTopics, SessionTopics
from mqtt_bus.url import BrokerUrl, parse_broker_url

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

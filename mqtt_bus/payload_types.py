"""The shape of every payload the bus carries, as typed dicts: the builders in
`mqtt_bus.payloads` (and the services, session and bench publishers) are typed with them, so
mypy holds each builder to its shape, and `mqtt_bus.schemas` generates the published JSON
Schemas from them with pydantic. A typed dict is a plain dict at run time: building a payload
costs nothing more for being typed (telemetry is built at 10 Hz for every drone).
"""

from __future__ import annotations

from typing import Annotated, Any, Literal, NotRequired

from pydantic import ConfigDict, Field, WithJsonSchema, with_config
from typing_extensions import TypedDict

from agent_contract.tools import RESULT_STATUSES

__all__ = [
    "REQUEST_ID_PATTERN",
    "BenchLast",
    "BenchProgressPayload",
    "BenchStatusPayload",
    "BenchTaskPayload",
    "EventPayload",
    "FailsafeEvent",
    "Home",
    "ObstacleHoldEvent",
    "OsdPayload",
    "OsdPosition",
    "PhotoEvent",
    "RadioEvent",
    "ServicesReply",
    "ServicesRequest",
    "StatePayload",
    "StatusPayload",
    "StatustextEvent",
    "Velocity",
    "Wgs84",
    "Xyz",
]

_CLOSED = ConfigDict(extra="forbid")
REQUEST_ID_PATTERN = r"^[\x21-\x7e]{1,64}$"
"""A services request's id: 1-64 printable ASCII characters."""

Num = Annotated[float | None, Field(description="null: not reported (e.g. a battery not yet "
                                                "heard) or not finite")]
Drone = Annotated[str, Field(description="the drone's id, as in the topic")]
TimeS = Annotated[float, Field(description="simulated seconds (a bridge: seconds since it "
                                           "started)")]
FlightState = Literal["on_ground", "taking_off", "hovering", "flying", "landing"]
ResultStatus = Annotated[str, WithJsonSchema({"type": "string", "enum": list(RESULT_STATUSES)})]


@with_config(_CLOSED)
class Xyz(TypedDict):
    x_m: Num
    y_m: Num
    z_m: Num


@with_config(_CLOSED)
class OsdPosition(TypedDict):
    """Local ENU metres from the session origin's ground; altitude_m above home."""

    x_m: Num
    y_m: Num
    z_m: Num
    altitude_m: Num


@with_config(_CLOSED)
class Wgs84(TypedDict):
    latitude_deg: Num
    longitude_deg: Num
    altitude_amsl_m: Num


@with_config(_CLOSED)
class Velocity(TypedDict):
    east_m_s: Num
    north_m_s: Num
    up_m_s: Num


@with_config(ConfigDict(extra="forbid", title="{prefix}/{session}/{drone}/osd"))
class OsdPayload(TypedDict):
    """A drone's telemetry sample, at --mqtt-osd-hz."""

    drone: Drone
    time_s: TimeS
    position: OsdPosition
    wgs84: Wgs84
    velocity: Velocity
    heading_deg: Num
    battery_pct: Num
    mode: Annotated[str, Field(description="PX4 mode, lower case (hold, mission, ...)")]
    armed: bool


@with_config(_CLOSED)
class Home(TypedDict):
    x_m: Num
    y_m: Num
    z_m: Num
    latitude_deg: Num
    longitude_deg: Num
    altitude_amsl_m: Num


@with_config(ConfigDict(
    extra="forbid", title="{prefix}/{session}/{drone}/state (retained, on change)"))
class StatePayload(TypedDict):
    """What changes seldom: published on change, retained."""

    drone: Drone
    time_s: TimeS
    flight_state: FlightState
    mode: str
    armed: bool
    home: Home | None
    primitive: Annotated[str | None, Field(description="the gateway primitive running for "
                                                       "the drone")]


Severity = Annotated[int | None, Field(description="MAV_SEVERITY (null: not reported)")]


@with_config(_CLOSED)
class StatustextEvent(TypedDict):
    drone: Drone
    time_s: TimeS
    kind: Literal["statustext"]
    severity: Severity
    text: str


@with_config(_CLOSED)
class ObstacleHoldEvent(TypedDict):
    drone: Drone
    time_s: TimeS
    kind: Literal["obstacle_hold"]
    severity: Severity
    text: str
    obstacle: str


@with_config(_CLOSED)
class FailsafeEvent(TypedDict):
    drone: Drone
    time_s: TimeS
    kind: Literal["failsafe"]
    severity: Severity
    text: str
    reason: Literal["battery_critical", "battery_emergency", "offboard_lost", "geofence"]
    action: Literal["returning_home", "landing", "hold"]


@with_config(_CLOSED)
class PhotoEvent(TypedDict):
    drone: Drone
    time_s: TimeS
    kind: Literal["photo"]
    index: int
    position: Xyz
    targets: Annotated[list[str] | None, Field(
        description="targets in the photo's footprint, as the drone's sensor perceived them "
                    "(null: unknown behind a bridge)")]


@with_config(_CLOSED)
class RadioEvent(TypedDict):
    drone: Drone
    time_s: TimeS
    kind: Literal["radio"]
    to: str | None
    broadcast: bool
    text: str


EventPayload = Annotated[
    StatustextEvent | ObstacleHoldEvent | FailsafeEvent | PhotoEvent | RadioEvent,
    Field(discriminator="kind", title="{prefix}/{session}/{drone}/events")]


@with_config(ConfigDict(
    extra="allow", title="{prefix}/{session}/status (retained; offline is the Last Will)"))
class StatusPayload(TypedDict):
    """The session's presence (retained; offline is the Last Will); more keys may follow."""

    status: Literal["online", "offline"]
    session: str
    drones: NotRequired[list[str]]
    commands: NotRequired[bool]


@with_config(ConfigDict(
    extra="forbid", title="{prefix}/{session}/{drone}/services (operators only)"))
class ServicesRequest(TypedDict):
    """A command for the drone of the topic (operators only)."""

    id: Annotated[str, Field(pattern=REQUEST_ID_PATTERN, description="echoed in the reply")]
    tool: Annotated[str, Field(description="an agent tool that takes drone_id, or get_link / "
                                           "set_link (an emulated swarm's link faults)")]
    args: NotRequired[Annotated[dict[str, Any], Field(
        description="the tool's arguments; drone_id comes from the topic")]]


@with_config(ConfigDict(extra="allow"))
class LinkState(TypedDict):
    uplink: Any
    downlink: Any


@with_config(ConfigDict(
    extra="allow", title="{prefix}/{session}/{drone}/services_reply"))
class ServicesReply(TypedDict):
    """The answer to one request: a tool result (status, message, ...) for the drone."""

    id: str | None
    drone: Drone
    tool: str | None
    status: ResultStatus
    message: str
    state: NotRequired[Annotated[dict[str, Any], Field(
        description="the drone's state after (as every surface's tool results)")]]
    link: NotRequired[Annotated[LinkState, Field(
        description="get_link / set_link: the drone's link faults in force")]]


@with_config(ConfigDict(
    extra="allow", title="{prefix}/bench/{run}/tasks: one results.jsonl record without "
                         "`checks`", json_schema_extra={"not": {"required": ["checks"]}}))
class BenchTaskPayload(TypedDict):
    """One results.jsonl record without `checks`."""

    key: Any
    session: Any
    task: Any
    passed: Any


@with_config(ConfigDict(extra="forbid"))
class BenchLast(TypedDict):
    """The task a progress payload follows: from its record."""

    key: Any
    session: Any
    task: Any
    passed: Any


@with_config(ConfigDict(
    extra="forbid", title="{prefix}/bench/{run}/progress (retained)"))
class BenchProgressPayload(TypedDict):
    """A run's counts so far (retained): after each task, then once at the end."""

    run: str
    tasks: int
    passed: int
    failed: int
    last: NotRequired[BenchLast]
    finished: NotRequired[bool]
    records_in_results: NotRequired[int]


@with_config(ConfigDict(
    extra="forbid", title="{prefix}/bench/{run}/status (retained; offline is the Last Will)"))
class BenchStatusPayload(TypedDict):
    """A benchmark run's presence."""

    status: Literal["online", "offline"]
    run: str

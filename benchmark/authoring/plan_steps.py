"""The steps of an oracle plan, one type per operation (see benchmark.authoring.templates.base
for what each does), and the parser that reads a plan as session files and the derived planner
write it: a list of phases, each a list of ``{"op": ..., ...}`` objects.

All lengths are in metres, angles in degrees, durations in simulated seconds. A step of one
drone names it in ``drone``; a team step (``sweep``, ``visit_targets``) names its ``drones``
and is shared out among them when the oracle runs it.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Annotated, Any, Literal

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, TypeAdapter, ValidationError

__all__ = [
    "STEP_TYPES",
    "Altitude",
    "Broadcast",
    "Charge",
    "DroneStep",
    "Goto",
    "Home",
    "Hover",
    "Intercept",
    "Land",
    "Meet",
    "Message",
    "Photo",
    "PhotoTarget",
    "Plan",
    "Reach",
    "Rotate",
    "SetHome",
    "Step",
    "Sweep",
    "Takeoff",
    "TeamStep",
    "Towards",
    "Track",
    "UntilFault",
    "VisitTargets",
    "Waypoints",
    "parse_plan",
    "parse_step",
]

DEFAULT_HOME_ALTITUDE_M = 20.0


def _tuples(value: Any) -> Any:
    """JSON arrays (lists) as tuples, at every depth, so a step stays immutable."""
    if isinstance(value, list | tuple):
        return tuple(_tuples(v) for v in value)
    return value


Point = tuple[float, float, float]
Points = Annotated[tuple[Point, ...], BeforeValidator(_tuples)]
Zone = Annotated[tuple[float, float, float], BeforeValidator(_tuples)]  # x, y, radius
Names = Annotated[tuple[str, ...], BeforeValidator(_tuples)]


class _Step(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid", strict=True)


class _OneDrone(_Step):
    drone: str


class Takeoff(_OneDrone):
    """Take off to altitude_m (change altitude when already in the air)."""

    op: Literal["takeoff"] = "takeoff"
    altitude_m: float


class Goto(_OneDrone):
    """Fly an obstacle-free path to (x, y, z), taking off first if needed."""

    op: Literal["goto"] = "goto"
    x: float
    y: float
    z: float


class Waypoints(_OneDrone):
    """Visit each point in order, around obstacles."""

    op: Literal["path"] = "path"
    points: Points


class Land(_OneDrone):
    op: Literal["land"] = "land"


class Hover(_OneDrone):
    op: Literal["hover"] = "hover"
    duration_s: float


class Rotate(_OneDrone):
    op: Literal["rotate"] = "rotate"
    heading_deg: float


class Altitude(_OneDrone):
    op: Literal["altitude"] = "altitude"
    altitude_m: float


class Towards(_OneDrone):
    """A straight move of distance_m towards heading_deg."""

    op: Literal["towards"] = "towards"
    heading_deg: float
    distance_m: float


class Photo(_OneDrone):
    op: Literal["photo"] = "photo"


class SetHome(_OneDrone):
    op: Literal["set_home"] = "set_home"


class Home(_OneDrone):
    """Fly home at altitude_m around obstacles, then land there."""

    op: Literal["home"] = "home"
    altitude_m: float = DEFAULT_HOME_ALTITUDE_M


class Charge(_OneDrone):
    """Fly to the station, land on it, charge."""

    op: Literal["charge"] = "charge"
    station: str


class Message(_OneDrone):
    op: Literal["message"] = "message"
    to: str
    text: str


class Broadcast(_OneDrone):
    op: Literal["broadcast"] = "broadcast"
    text: str


class Reach(_OneDrone):
    """Fly over the target at altitude_m."""

    op: Literal["reach"] = "reach"
    target: str
    altitude_m: float


class Track(_OneDrone):
    """Meet a moving target where it will be and follow it for duration_s."""

    op: Literal["track"] = "track"
    target: str
    duration_s: float
    altitude_m: float


class Intercept(_OneDrone):
    """Meet a moving target at a time it is inside the zone (x, y, radius)."""

    op: Literal["intercept"] = "intercept"
    target: str
    zone: Zone
    altitude_m: float


class Meet(_OneDrone):
    """Fly to where a moving target will be and wait for it there."""

    op: Literal["meet"] = "meet"
    target: str
    altitude_m: float


class PhotoTarget(_OneDrone):
    """Meet a moving target and photograph it."""

    op: Literal["photo_target"] = "photo_target"
    target: str
    altitude_m: float


class UntilFault(_OneDrone):
    """Take off and hold while the task's hidden faults strike the drone; whatever outcome
    the fault gives ends it."""

    op: Literal["until_fault"] = "until_fault"
    altitude_m: float
    duration_s: float


class Sweep(_Step):
    """Cover an area target together."""

    op: Literal["sweep"] = "sweep"
    drones: Names
    target: str
    altitude_m: float


class VisitTargets(_Step):
    """Share the targets out and reach each one."""

    op: Literal["visit_targets"] = "visit_targets"
    drones: Names
    targets: Names
    altitude_m: float


DroneStep = (Takeoff | Goto | Waypoints | Land | Hover | Rotate | Altitude | Towards | Photo
             | SetHome | Home | Charge | Message | Broadcast | Reach | Track | Intercept | Meet
             | PhotoTarget | UntilFault)
TeamStep = Sweep | VisitTargets
Step = DroneStep | TeamStep
Plan = tuple[tuple[Step, ...], ...]

STEP_TYPES: dict[str, type[_Step]] = {
    t.model_fields["op"].default: t for t in (
        Takeoff, Goto, Waypoints, Land, Hover, Rotate, Altitude, Towards, Photo, SetHome, Home,
        Charge, Message, Broadcast, Reach, Track, Intercept, Meet, PhotoTarget, UntilFault,
        Sweep, VisitTargets)
}
"""Each step type by its ``op``."""

_STEP: TypeAdapter[Step] = TypeAdapter(Annotated[Step, Field(discriminator="op")])


def _reason(error: ValidationError) -> str:
    first = error.errors()[0]
    where = ".".join(str(p) for p in first["loc"][1:])  # [0] is the op's tag
    if first["type"] in ("union_tag_invalid", "union_tag_not_found"):
        return f"'op' must be one of {', '.join(sorted(STEP_TYPES))}"
    return f"{where}: {first['msg'].lower()}" if where else first["msg"].lower()


def parse_step(raw: Any, where: str = "step") -> Step:
    """One step from its JSON object. ValueError naming `where`, the field and the reason."""
    if not isinstance(raw, Mapping):
        raise ValueError(f"{where}: expected an operation object with 'op'")
    try:
        return _STEP.validate_python(dict(raw))
    except ValidationError as error:
        raise ValueError(f"{where} ({raw.get('op')!r}): {_reason(error)}") from None


def parse_plan(raw: Any, where: str = "plan") -> Plan:
    """A plan from its JSON form: a list of phases, each a list of steps."""
    if not isinstance(raw, Sequence) or isinstance(raw, str) or not all(
            isinstance(p, Sequence) and not isinstance(p, str) for p in raw):
        raise ValueError(f"{where}: expected a list of phases (lists of operations)")
    return tuple(tuple(parse_step(op, f"{where}[{k}][{j}]") for j, op in enumerate(phase))
                 for k, phase in enumerate(raw))

"""Hypothesis strategies for what a broken or hostile ground station can send a swarm.

Every message type a vehicle handles (`HANDLED_MESSAGES`), plus a few it ignores, built
field by field from the pymavlink class: floats from NaN, +-inf, +-F32_MAX, 1.4e-45,
negatives, zeros and any float32; integers from the edges of their type; char fields from
parameter names and random strings. Addresses are every vehicle of a 3-vehicle swarm and
the broadcast 0. Positions are drawn near the session origin half the time, so commands get
past the coordinate checks to the code behind them.

Sweeps guarantee coverage: for one address, every command id (COMMAND_LONG or COMMAND_INT)
with absurd parameters, and one message of every type, in a drawn order. `value_sweep` is
exhaustive instead of drawn: every command with each of its seven parameters in turn set to
every absurd value and every parameter floor, the others plausible, so that each value
reaches the check behind the plausible ones (a 1.4e-45 m/s speed with a valid speed type).

Single messages rarely reach deep state, so there are episodes too (and `plausible_missions`,
one valid upload per vehicle then AUTO.MISSION and arm, so that a mission is flown whatever
the absurd uploads drew): arm + take-off followed
by absurd commands and by DO_SET_HOME, DO_CHANGE_SPEED and DO_REPOSITION with absurd or
plausible values (they then hit a flying vehicle), complete mission uploads with absurd
items followed by AUTO.MISSION, offboard set-points followed by OFFBOARD. Parameter values
are absurd or a parameter's range minimum: the floors are where a vehicle would crawl.
SIM_HOVER_ENDUR is left out: its only effect is how fast the battery drains, and a battery
legitimately drained by a short endurance refuses to arm by design, which is not damage.
SYS_FAILURE_EN is left out too: it lets MAV_CMD_INJECT_FAILURE fail a motor or the GPS, after
which a vehicle refuses to arm by design; with it at 0 every injection is refused.
"""

from __future__ import annotations

import math

from hypothesis import strategies as st

from emulator.flight.mission import SUPPORTED_COMMANDS
from emulator.flight.params import PARAM_DEFINITIONS
from emulator.geo import DEFAULT_ORIGIN
from emulator.mavlink.commands import HANDLERS
from emulator.mavlink.vehicle_link import HANDLED_MESSAGES
from mavlink_vocabulary import MavCmd, MavFrame, MavMissionType
from tests.mavlink_client import mavlink
from tests.mavlink_values import ABSURD_FLOATS, ALT0_M, INT_RANGES, UNKNOWN_COMMANDS, int_edges

__all__ = ["BASELINES", "IGNORED_MESSAGES", "SYSTEMS", "TARGETS", "plausible_missions", "storms",
           "sweep", "value_sweep"]

SYSTEMS = (1, 2, 3)
TARGETS = (0, *SYSTEMS)
IGNORED_MESSAGES = ("HEARTBEAT", "SET_MODE", "REQUEST_DATA_STREAM", "MISSION_ACK")
FLOORS = tuple(sorted({float(d.minimum) for d in PARAM_DEFINITIONS}))
PARAM_NAMES = tuple(d.name.encode() for d in PARAM_DEFINITIONS
                    if d.name not in ("SIM_HOVER_ENDUR", "SYS_FAILURE_EN"))
COMMANDS = (*sorted(HANDLERS), *UNKNOWN_COMMANDS, MavCmd.NAV_LAND, MavCmd.NAV_TAKEOFF)
LAT0, LON0 = DEFAULT_ORIGIN.latitude_deg, DEFAULT_ORIGIN.longitude_deg
ALT0 = ALT0_M
NEAR_DEG = 0.003  # about 330 m

absurd_floats = st.one_of(st.sampled_from(ABSURD_FLOATS), st.floats(width=32))
altitudes = st.one_of(absurd_floats, st.floats(ALT0 - 10.0, ALT0 + 60.0, width=32),
                      st.floats(-10.0, 60.0, width=32))
near_lat = st.floats(LAT0 - NEAR_DEG, LAT0 + NEAR_DEG)
near_lon = st.floats(LON0 - NEAR_DEG, LON0 + NEAR_DEG)


def integers(ftype: str) -> st.SearchStrategy[int]:
    lo, hi = INT_RANGES[ftype]
    return st.one_of(st.sampled_from(int_edges(ftype)), st.integers(lo, hi))


def _e7(degrees: st.SearchStrategy[float], ftype: str) -> st.SearchStrategy[int]:
    return st.one_of(degrees.map(lambda d: round(d * 1e7)), integers(ftype))


def field(type_name: str, name: str, ftype: str, length: int) -> st.SearchStrategy:
    """Values for one field of one message type."""
    if ftype == "char":
        text = st.text(max_size=length).map(lambda s: s.encode("utf-8")[:length])
        if name == "param_id":
            return st.one_of(st.sampled_from(PARAM_NAMES), text)
        return text
    if length:
        if ftype == "uint8_t":
            return st.binary(min_size=length, max_size=length).map(list)
        element = integers(ftype) if ftype in INT_RANGES else absurd_floats
        return st.lists(element, min_size=length, max_size=length)
    if name == "target_system":
        return st.one_of(st.sampled_from(TARGETS), integers(ftype))
    if name == "target_component":
        return st.sampled_from((0, 1, 1, 100, 190, 255))
    if name == "command":
        return st.one_of(st.sampled_from(COMMANDS), st.sampled_from(COMMANDS), integers(ftype))
    if name in ("seq", "count", "start_index", "end_index"):
        return st.one_of(st.integers(0, 6), integers(ftype))
    if name == "mission_type":
        return st.sampled_from((0, 0, 0, 1, 2, 255))
    if name in ("frame", "coordinate_frame"):
        return st.one_of(st.integers(0, 12), integers(ftype))
    if name == "type_mask" and ftype == "uint8_t":  # SET_ATTITUDE_TARGET's
        return st.one_of(st.sampled_from((0, 7, 64, 128, 0xFF)), integers(ftype))
    if name == "type_mask":
        return st.one_of(st.sampled_from((0x9F8, 0xDC7, 0xDFF, 0, 0xFFFF)), integers(ftype))
    if name == "param_value":
        return st.one_of(absurd_floats, st.sampled_from(FLOORS))
    if name in ("x", "lat_int") and ftype == "int32_t":
        return _e7(near_lat, ftype)
    if name in ("y", "lon_int") and ftype == "int32_t":
        return _e7(near_lon, ftype)
    if ftype in INT_RANGES:
        return integers(ftype)
    if (type_name, name) in (("COMMAND_LONG", "param5"), ("MISSION_ITEM", "x")):
        return st.one_of(absurd_floats, near_lat)
    if (type_name, name) in (("COMMAND_LONG", "param6"), ("MISSION_ITEM", "y")):
        return st.one_of(absurd_floats, near_lon)
    if name in ("param7", "z", "alt"):
        return altitudes
    return absurd_floats


def message(type_name: str, **fixed: object) -> st.SearchStrategy:
    """One message of `type_name`; keyword arguments fix fields (strategies or values)."""
    cls = mavlink.mavlink_map[getattr(mavlink, f"MAVLINK_MSG_ID_{type_name}")]
    lengths = dict(zip(cls.ordered_fieldnames, cls.array_lengths, strict=True))
    args = []
    for name, ftype in zip(cls.fieldnames, cls.fieldtypes, strict=True):
        value = fixed.get(name, field(type_name, name, ftype, lengths[name]))
        args.append(value if isinstance(value, st.SearchStrategy) else st.just(value))
    return st.builds(cls, *args)


def _command(target: int, command: int, *params: object) -> st.SearchStrategy:
    """A COMMAND_LONG; each param a value or a strategy (NaN when left out)."""
    p = [*params] + [math.nan] * (7 - len(params))
    return message("COMMAND_LONG", target_system=target, target_component=1, command=command,
                   confirmation=0, **{f"param{i + 1}": v for i, v in enumerate(p)})


speeds = st.one_of(absurd_floats, st.sampled_from(FLOORS), st.floats(0.0, 31.0, width=32))
lat_deg = st.one_of(absurd_floats, near_lat)
lon_deg = st.one_of(absurd_floats, near_lon)


def _targeted(target: int) -> st.SearchStrategy:
    """Commands aimed at the settings that used to persist: home, speeds, reposition."""
    return st.one_of(
        _command(target, 179, st.sampled_from((0.0, 1.0)), math.nan, math.nan, math.nan,
                 lat_deg, lon_deg, altitudes),
        _command(target, 178, st.one_of(st.integers(0, 4).map(float), absurd_floats), speeds,
                 -1.0),
        _command(target, 192, speeds, 1.0, math.nan, absurd_floats, lat_deg, lon_deg,
                 altitudes),
    )


@st.composite
def flight_episode(draw: st.DrawFn) -> list:
    """Arm and take off, then absurd commands to the same (now flying) vehicle."""
    target = draw(st.sampled_from(SYSTEMS))
    kind = draw(st.sampled_from(("COMMAND_LONG", "COMMAND_INT")))
    absurd = draw(st.lists(st.one_of(message(kind, target_system=target, target_component=1),
                                     _targeted(target)), min_size=1, max_size=4))
    return [draw(_command(target, 400, 1.0)), draw(_command(target, 22)), *absurd]


@st.composite
def mission_episode(draw: st.DrawFn) -> list:
    """A complete upload of absurd items, then AUTO.MISSION and arm."""
    target = draw(st.sampled_from(SYSTEMS))
    n = draw(st.integers(1, 5))
    kind = draw(st.sampled_from(("MISSION_ITEM_INT", "MISSION_ITEM")))
    frames = st.sampled_from((0, 2, 3, 5, 6))
    items = [draw(message(kind, target_system=target, target_component=1, seq=i,
                          command=st.sampled_from(sorted(SUPPORTED_COMMANDS)), frame=frames,
                          mission_type=0))
             for i in range(n)]
    count = draw(message("MISSION_COUNT", target_system=target, target_component=1, count=n,
                         mission_type=0))
    start = [draw(_command(target, 176, 1.0, 4.0, 4.0)), draw(_command(target, 400, 1.0))]
    return [count, *items, *start]


@st.composite
def offboard_episode(draw: st.DrawFn) -> list:
    """A set-point (local or global), then OFFBOARD and arm."""
    target = draw(st.sampled_from(SYSTEMS))
    kind = draw(st.sampled_from(("SET_POSITION_TARGET_LOCAL_NED",
                                 "SET_POSITION_TARGET_GLOBAL_INT", "SET_ATTITUDE_TARGET")))
    setpoint = draw(message(kind, target_system=target, target_component=1))
    return [setpoint, draw(_command(target, 176, 1.0, 6.0, 0.0)),
            draw(_command(target, 400, 1.0)), setpoint]


@st.composite
def pilot_episode(draw: st.DrawFn) -> list:
    """Joystick input and a stick mode, or a follow target and follow mode, or video mode
    and a recording; arm on the way."""
    target = draw(st.sampled_from(SYSTEMS))
    sticks = draw(message("MANUAL_CONTROL", target=target))
    fix = draw(message("FOLLOW_TARGET"))
    camera = [draw(message("COMMAND_LONG", target_system=target, target_component=100,
                           command=530, confirmation=0, param2=1.0)),
              draw(message("COMMAND_LONG", target_system=target, target_component=100,
                           command=st.sampled_from((2500, 2501, 2502, 2503)), confirmation=0))]
    mode = draw(st.sampled_from(((3.0, 0.0), (2.0, 0.0), (4.0, 8.0))))
    return [sticks, fix, draw(_command(target, 176, 1.0, *mode)),
            draw(_command(target, 400, 1.0)), sticks, fix, *camera]


def storms(max_parts: int) -> st.SearchStrategy[list]:
    """A list of messages: single ones of every type and the episodes above."""
    singles = st.one_of(*(message(name) for name in (*sorted(HANDLED_MESSAGES),
                                                    *IGNORED_MESSAGES)))
    commands = st.one_of(message("COMMAND_LONG"), message("COMMAND_INT"))
    parts = st.one_of(singles.map(lambda m: [m]), commands.map(lambda m: [m]),
                      flight_episode(), mission_episode(), offboard_episode(),
                      pilot_episode())
    return st.lists(parts, min_size=4, max_size=max_parts).map(
        lambda chunks: [m for chunk in chunks for m in chunk])


@st.composite
def sweep(draw: st.DrawFn, target: int, kind: str) -> list:
    """Every command id as `kind` to `target`, plus one message of every type, shuffled."""
    out = [draw(message(kind, target_system=target, command=command))
           for command in sorted(HANDLERS)]
    for name in (*sorted(HANDLED_MESSAGES), *IGNORED_MESSAGES):
        cls = mavlink.mavlink_map[getattr(mavlink, f"MAVLINK_MSG_ID_{name}")]
        fixed = {"target_system": target} if "target_system" in cls.fieldnames else \
            {"target": target} if "target" in cls.fieldnames else {}
        out.append(draw(message(name, **fixed)))
    return draw(st.permutations(out))


NEAR_LAT, NEAR_LON = LAT0 + 0.0002, LON0 + 0.0003
# For every handled command, plausible parameters 1-7 (NaN: unset)
BASELINES: dict[int, tuple[float, ...]] = {
    20: (), 21: (math.nan,) * 4 + (NEAR_LAT, NEAR_LON), 22: (),
    34: (10.0, 2.0, 0.0, math.nan, NEAR_LAT, NEAR_LON, ALT0 + 12.0),
    241: (1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
    115: (90.0, 10.0, 1.0, 0.0), 176: (1.0, 4.0, 3.0), 178: (1.0, 5.0, -1.0),
    179: (0.0, math.nan, math.nan, math.nan, NEAR_LAT, NEAR_LON, ALT0 + 1.0),
    192: (math.nan, 1.0, math.nan, math.nan, NEAR_LAT, NEAR_LON, ALT0 + 12.0),
    224: (0.0,), 300: (0.0, 0.0), 400: (1.0,), 410: (), 511: (33.0, 1e5), 512: (33.0,),
    520: (1.0,), 521: (1.0,), 522: (), 525: (), 527: (), 530: (0.0, 0.0),
    2000: (0.0, 0.0, 1.0), 2001: (), 420: (4.0, 0.0, 0.0),
    1000: (-30.0, 10.0), 1001: (-2.0, -2.0),
    2500: (0.0, 1.0), 2501: (0.0,), 2502: (1.0,), 2503: (1.0,), 2504: (1.0,), 2505: (1.0,),
}
SWEEP_VALUES = tuple(dict.fromkeys((*ABSURD_FLOATS, *FLOORS)))


def _long(target: int, command: int, params: list[float]) -> mavlink.MAVLink_message:
    return mavlink.MAVLink_command_long_message(target, 1, command, 0, *params)


def value_sweep() -> list:
    """Every command x parameter slot x value (see the module docstring), round-robin over
    the vehicles, each (command, slot) group preceded by arm + take-off of all of them."""
    out = []
    i = 0
    for command in sorted(BASELINES):
        base = [*BASELINES[command], *[math.nan] * (7 - len(BASELINES[command]))]
        for slot in range(7):
            for target in SYSTEMS:
                out += [_long(target, 400, [1.0, *[math.nan] * 6]),
                        _long(target, 22, [math.nan] * 7)]
            for value in SWEEP_VALUES:
                params = list(base)
                params[slot] = value
                out.append(_long(SYSTEMS[i % len(SYSTEMS)], command, params))
                i += 1
    return out


def plausible_missions() -> list:
    """For every vehicle, a valid upload (take-off, one waypoint near the origin, land) sent
    without waiting for the requests, then AUTO.MISSION and arm."""
    out = []
    for target in SYSTEMS:
        items = [(MavCmd.NAV_TAKEOFF, 0.0, 0.0), (MavCmd.NAV_WAYPOINT, NEAR_LAT, NEAR_LON),
                 (MavCmd.NAV_LAND, 0.0, 0.0)]
        out.append(mavlink.MAVLink_mission_count_message(target, 1, len(items),
                                                         MavMissionType.MISSION))
        for seq, (command, lat, lon) in enumerate(items):
            out.append(mavlink.MAVLink_mission_item_int_message(
                target, 1, seq, MavFrame.GLOBAL_RELATIVE_ALT_INT, command, 0, 1,
                0.0, 0.0, 0.0, math.nan, round(lat * 1e7), round(lon * 1e7), 8.0,
                MavMissionType.MISSION))
        out += [_long(target, MavCmd.DO_SET_MODE, [1.0, 4.0, 4.0, *[math.nan] * 4]),
                _long(target, MavCmd.COMPONENT_ARM_DISARM, [1.0, *[math.nan] * 6])]
    return out

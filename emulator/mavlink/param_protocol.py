"""The parameter protocol, sans I/O: PARAM_REQUEST_LIST / _READ / PARAM_SET -> PARAM_VALUEs.

Integer parameters travel as PX4 sends them: INT32 with the bytes of the integer in the
float field (bytewise encoding). A PARAM_SET is echoed with the value in force, also when it
was refused (the reason comes as a problem text the link sends as a STATUSTEXT first).
"""

from __future__ import annotations

import math
import struct

from emulator.flight.autopilot import Autopilot
from emulator.flight.params import ParamError, ParamStore
from emulator.mavlink.codec import mavlink
from mavlink_vocabulary import MavParamType

__all__ = ["Answer", "param_list", "param_read", "param_set", "param_value"]

# (a problem to report, or ""; the PARAM_VALUE to send, or None)
Answer = tuple[str, mavlink.MAVLink_message | None]
_INT_TYPES = frozenset({MavParamType.UINT8, MavParamType.INT8, MavParamType.UINT16,
                        MavParamType.INT16, MavParamType.UINT32, MavParamType.INT32})


def _bytewise_int(value: float) -> int:
    return struct.unpack("<i", struct.pack("<f", value))[0]


def _bytewise_float(value: int) -> float:
    return struct.unpack("<f", struct.pack("<i", value))[0]


def param_value(store: ParamStore, name: str) -> mavlink.MAVLink_message:
    d = ParamStore.definition(name)
    value = store[name]
    if d.is_int:
        wire, ptype = _bytewise_float(int(value)), MavParamType.INT32
    else:
        wire, ptype = value, MavParamType.REAL32
    return mavlink.MAVLink_param_value_message(
        name.encode(), wire, ptype, len(store), ParamStore.index_of(name)
    )


def param_list(ap: Autopilot) -> list[mavlink.MAVLink_message]:
    return [param_value(ap.params, name) for name in ap.params]


def param_read(ap: Autopilot, m) -> Answer:
    try:
        name = m.param_id if m.param_index < 0 else ParamStore.name_at(m.param_index)
        ParamStore.definition(name)
    except ParamError as error:
        return str(error), None
    return "", param_value(ap.params, name)


def param_set(ap: Autopilot, m) -> Answer:
    name = m.param_id
    try:
        d = ParamStore.definition(name)
    except ParamError as error:
        return str(error), None
    value = m.param_value
    if m.param_type in _INT_TYPES:
        value = float(_bytewise_int(value))
    elif d.is_int and math.isfinite(value) and value == int(value):
        value = float(int(value))
    problem = ""
    try:
        ap.set_param(name, value)
    except ParamError as error:
        problem = f"Param rejected: {error}"
    return problem, param_value(ap.params, name)  # the echo carries the value now in force

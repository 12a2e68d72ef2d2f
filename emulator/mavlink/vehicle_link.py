"""One vehicle's MAVLink endpoint, sans I/O: decoded messages in, messages out.

It dispatches what a ground station sends (commands, parameters, missions, offboard
set-points, camera requests) to the vehicle's autopilot and answers as PX4 does. Bytes go
out through the `emit` callable the transport provides; nothing here touches a socket.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Callable

from emulator.flight.autopilot import Autopilot, ImageCapture
from emulator.flight.params import ParamError, ParamStore
from emulator.flight.refusal import Severity
from emulator.mavlink import messages as msgs
from emulator.mavlink.camera import CAMERA_COMPONENT_ID, CAMERA_MESSAGES, CameraComponent
from emulator.mavlink.codec import Encoder, mavlink
from emulator.mavlink.command_dedup import STATEFUL_COMMANDS, CommandDedup, command_key
from emulator.mavlink.commands import CommandArgs, Result, execute_command
from emulator.mavlink.mission_transfer import MissionTransfer
from emulator.mavlink.offboard import apply_global_setpoint, apply_local_setpoint
from emulator.mavlink.streams import CAMERA_HEARTBEAT, StreamSchedule

__all__ = ["HANDLED_MESSAGES", "VehicleLink"]

PARAM_TYPE_INT32 = 6
PARAM_TYPE_REAL32 = 9
_INT_TYPES = frozenset({1, 2, 3, 4, 5, 6})
AUTOPILOT_COMPONENT_ID = 1
MIN_STREAM_INTERVAL_S = 0.01  # streams are capped at 100 Hz whatever a client asks


def _bytewise_int(value: float) -> int:
    return struct.unpack("<i", struct.pack("<f", value))[0]


def _bytewise_float(value: int) -> float:
    return struct.unpack("<f", struct.pack("<i", value))[0]


# SYS_STATUS, BATTERY_STATUS, GLOBAL_POSITION_INT, LOCAL_POSITION_NED, HOME_POSITION
_OPERATOR_RESET_STREAMS = (1, 147, 33, 32, 242)


class VehicleLink:
    """MAVLink side of vehicle `ap` (system id k + 1)."""

    def __init__(self, ap: Autopilot, emit: Callable[[int, bytes], None],
                 streams: StreamSchedule, wall_clock: Callable[[], float]) -> None:
        self.ap = ap
        self.k = ap.k
        self.system_id = ap.k + 1
        self._emit = emit
        self._streams = streams
        self._wall_clock = wall_clock
        self._encoders = {
            AUTOPILOT_COMPONENT_ID: Encoder(self.system_id, AUTOPILOT_COMPONENT_ID),
            CAMERA_COMPONENT_ID: Encoder(self.system_id, CAMERA_COMPONENT_ID),
        }
        self._after_ack: list[Callable[[], object]] = []
        self.camera = CameraComponent(self)
        self.missions = MissionTransfer(self)
        self.wall_now_s = wall_clock()
        self.warned: set[str] = set()  # problems already reported once by STATUSTEXT
        self.dedup = CommandDedup()
        self.last_reached: int | None = None  # the last MISSION_ITEM_REACHED of this mission
        # told when this vehicle's MAVLink goes off or comes back (the swarm's link faults)
        self.on_mavlink_signal: Callable[[Autopilot], None] | None = None
        ap.listener = self

    # ---------------------------------------------------------------- sending
    def send(self, message: mavlink.MAVLink_message,
             component_id: int = AUTOPILOT_COMPONENT_ID) -> None:
        self._emit(self.k, self._encoders[component_id].pack(message))

    def encoder(self, component_id: int) -> Encoder:
        return self._encoders[component_id]

    def statustext(self, severity: int, text: str) -> None:
        self.send(msgs.statustext(severity, text))

    def time_boot_ms(self) -> int:
        return int(self.ap.now_s * 1000.0) & 0xFFFFFFFF

    def after_ack(self, action: Callable[[], object]) -> None:
        self._after_ack.append(action)

    def build(self, msg_id: int) -> mavlink.MAVLink_message | None:
        ap = self.ap
        if msg_id == 0:
            return msgs.heartbeat(ap)
        if msg_id == 1:
            return msgs.sys_status(ap)
        if msg_id == 245:
            return msgs.extended_sys_state(ap)
        if msg_id == 33:
            return msgs.global_position_int(ap, self.time_boot_ms())
        if msg_id == 32:
            return msgs.local_position_ned(ap, self.time_boot_ms())
        if msg_id == 30:
            return msgs.attitude(ap, self.time_boot_ms())
        if msg_id == 24:
            return msgs.gps_raw_int(ap, self.time_boot_ms() * 1000)
        if msg_id == 74:
            return msgs.vfr_hud(ap)
        if msg_id == 42:
            return msgs.mission_current(ap)
        if msg_id == 147:
            return msgs.battery_status(ap)
        if msg_id == 242:
            return msgs.home_position(ap, self.time_boot_ms() * 1000)
        if msg_id == 148:
            return msgs.autopilot_version(ap)
        return None

    def send_stream(self, msg_id: int) -> None:
        if msg_id == CAMERA_HEARTBEAT:
            self.send(self.camera.heartbeat(), CAMERA_COMPONENT_ID)
            return
        message = self.build(msg_id)
        if message is not None:
            self.send(message)

    def can_send_once(self, msg_id: int) -> bool:
        return msg_id in CAMERA_MESSAGES or msg_id in _ONE_SHOT

    def send_once(self, msg_id: int) -> None:
        if msg_id in CAMERA_MESSAGES:
            self.camera.send_once(msg_id)
        else:
            self.send_stream(msg_id)

    def set_stream_interval(self, msg_id: int, interval_s: float | None) -> bool:
        if msg_id == 0:
            return False  # the 1 Hz heartbeat is the link's pulse: its rate is fixed
        if interval_s is not None:
            interval_s = max(interval_s, MIN_STREAM_INTERVAL_S)
        return self._streams.set_interval(self.k, msg_id, interval_s, self.wall_now_s)

    # ------------------------------------------------------ autopilot listener
    def on_statustext(self, severity: int, text: str) -> None:
        self.statustext(severity, text)

    def on_mission_item_reached(self, seq: int) -> None:
        self.last_reached = seq
        self.send(mavlink.MAVLink_mission_item_reached_message(seq))

    def resend_mission_reached(self) -> None:
        """MISSION_ITEM_REACHED comes once per item: on a lossy link the swarm repeats the
        last one with the vehicle's telemetry at a lockstep halt, or a client could never
        learn that its mission finished."""
        if self.last_reached is not None:
            self.send(mavlink.MAVLink_mission_item_reached_message(self.last_reached))

    def on_mission_current(self) -> None:
        self.send(msgs.mission_current(self.ap))

    def on_home_changed(self) -> None:
        self.send_once(242)

    def on_image_captured(self, capture: ImageCapture) -> None:
        self.camera.image_captured(capture)

    def on_state_changed(self) -> None:
        """Mode, arming or landed state changed: say so now, not at the next 1 Hz slot."""
        self.send(msgs.heartbeat(self.ap))
        self.send(msgs.extended_sys_state(self.ap))

    def on_operator_reset(self) -> None:
        """An operator moved the vehicle or refilled its battery: report the new state now."""
        self.dedup.forget()
        self.on_state_changed()
        for msg_id in _OPERATOR_RESET_STREAMS:
            self.send_once(msg_id)

    # --------------------------------------------------------------- receiving
    def handle(self, m: mavlink.MAVLink_message, wall_now_s: float) -> None:
        """Handle one message addressed to this vehicle (or broadcast)."""
        self.wall_now_s = wall_now_s
        handler = _DISPATCH.get(m.get_type())
        if handler is not None:
            handler(self, m)

    def tick(self, wall_now_s: float) -> None:
        self.wall_now_s = wall_now_s
        self.missions.tick(wall_now_s)
        self.ap.offboard.check_link(wall_now_s)

    def _peer(self, m) -> tuple[int, int]:
        return m.get_srcSystem(), m.get_srcComponent()

    def _on_command(self, m, args: CommandArgs) -> None:
        target_component = getattr(m, "target_component", 0)
        if target_component not in (0, AUTOPILOT_COMPONENT_ID, CAMERA_COMPONENT_ID):
            return  # for a component this vehicle does not have: not ours to answer
        if target_component == CAMERA_COMPONENT_ID and args.command not in (
            2000, 2001, 521, 522, 525, 527, 530, 512
        ):
            result, reason = Result.UNSUPPORTED, None
        elif args.command in STATEFUL_COMMANDS:
            key, step = command_key(m), self.ap.fleet.step_count
            repeated = self.dedup.repeat_of(self._peer(m), key, step, self.wall_now_s,
                                            self._state_key())
            if repeated is not None:  # a retransmission: the first copy's answer again
                self._after_ack.clear()
                self._ack(m, args.command, repeated, target_component)
                return
            result, reason = execute_command(self, args)
            self._answer(m, args.command, result, reason, target_component)
            self.dedup.answered(self._peer(m), key, step, self.wall_now_s, result,
                                self._state_key())
            return
        else:
            result, reason = execute_command(self, args)
        self._answer(m, args.command, result, reason, target_component)

    def _answer(self, m, command: int, result: int, reason: str | None,
                target_component: int) -> None:
        self._ack(m, command, result, target_component)
        if reason:
            self.statustext(Severity.WARNING if result else Severity.INFO, reason)
        actions, self._after_ack = self._after_ack, []
        if result == Result.ACCEPTED:
            for action in actions:
                action()

    def _state_key(self) -> tuple[object, ...]:
        """What a command changes: mode, arming, landed state, goal, whether a goal runs."""
        ap, fleet = self.ap, self.ap.fleet
        return (ap.mode, ap.armed, ap.landed_state, fleet.dyn.goal_m[self.k].tobytes(),
                bool(fleet.busy[self.k]))

    def _ack(self, m, command: int, result: int, target_component: int) -> None:
        component = CAMERA_COMPONENT_ID if target_component == CAMERA_COMPONENT_ID else 1
        src_system, src_component = self._peer(m)
        self.send(mavlink.MAVLink_command_ack_message(
            command, result, 0, 0, src_system, src_component
        ), component)

    def _command_long(self, m) -> None:
        self._on_command(m, CommandArgs.from_long(m))

    def _command_int(self, m) -> None:
        self._on_command(m, CommandArgs.from_int(m))

    # -------------------------------------------------------------- parameters
    def _param_value(self, name: str) -> mavlink.MAVLink_message:
        store = self.ap.params
        d = ParamStore.definition(name)
        value = store[name]
        if d.is_int:
            wire, ptype = _bytewise_float(int(value)), PARAM_TYPE_INT32
        else:
            wire, ptype = value, PARAM_TYPE_REAL32
        return mavlink.MAVLink_param_value_message(
            name.encode(), wire, ptype, len(store), ParamStore.index_of(name)
        )

    def _param_request_list(self, m) -> None:
        for name in self.ap.params:
            self.send(self._param_value(name))

    def _param_request_read(self, m) -> None:
        try:
            name = m.param_id if m.param_index < 0 else ParamStore.name_at(m.param_index)
            ParamStore.definition(name)
        except ParamError as error:
            self.statustext(Severity.WARNING, str(error))
            return
        self.send(self._param_value(name))

    def _param_set(self, m) -> None:
        self.dedup.forget()
        name = m.param_id
        try:
            d = ParamStore.definition(name)
        except ParamError as error:
            self.statustext(Severity.WARNING, str(error))
            return
        value = m.param_value
        if m.param_type in _INT_TYPES:
            value = float(_bytewise_int(value))
        elif d.is_int and math.isfinite(value) and value == int(value):
            value = float(int(value))
        try:
            self.ap.set_param(name, value)
        except ParamError as error:
            self.statustext(Severity.WARNING, f"Param rejected: {error}")
        self.send(self._param_value(name))  # the echo carries the value now in force

    # ---------------------------------------------------------------- missions
    def _mission_count(self, m) -> None:
        self.last_reached = None
        self.dedup.forget()  # a command after this one is no retransmission of one before
        self.missions.on_count(m, self._peer(m), self.wall_now_s)

    def _mission_item_int(self, m) -> None:
        self.missions.on_item(m, self._peer(m), self.wall_now_s, is_int=True)

    def _mission_item(self, m) -> None:
        self.missions.on_item(m, self._peer(m), self.wall_now_s, is_int=False)

    def _mission_request_list(self, m) -> None:
        self.missions.on_request_list(m, self._peer(m))

    def _mission_request_int(self, m) -> None:
        self.missions.on_request(m, self._peer(m), wants_int=True)

    def _mission_request(self, m) -> None:
        self.missions.on_request(m, self._peer(m), wants_int=False)

    def _mission_clear_all(self, m) -> None:
        self.last_reached = None
        self.dedup.forget()
        self.missions.on_clear_all(m, self._peer(m))

    def _mission_set_current(self, m) -> None:
        self.dedup.forget()
        self.missions.on_set_current(m)

    # ------------------------------------------------------------------ others
    def _set_position_target_local_ned(self, m) -> None:
        apply_local_setpoint(self, m)

    def _set_position_target_global_int(self, m) -> None:
        apply_global_setpoint(self, m)

    def _ping(self, m) -> None:
        if m.target_system == self.system_id:  # broadcast pings are not answered
            src_system, src_component = self._peer(m)
            self.send(mavlink.MAVLink_ping_message(m.time_usec, m.seq, src_system, src_component))

    def _timesync(self, m) -> None:
        if m.tc1 == 0:
            now_ns = int(self.ap.now_s * 1e9)
            self.send(mavlink.MAVLink_timesync_message(now_ns, m.ts1))

    def _file_transfer(self, m) -> None:
        # No MAVLink FTP: answer every request with NAK(UnknownCommand) so clients fall back.
        payload = bytes(m.payload)
        if len(payload) < 12:
            return
        seq = (int.from_bytes(payload[0:2], "little") + 1) & 0xFFFF
        reply = bytearray(251)
        reply[0:2] = seq.to_bytes(2, "little")
        reply[2] = payload[2]
        reply[3] = 129  # NAK
        reply[4] = 1
        reply[5] = payload[3]
        reply[12] = 7  # kErrUnknownCommand
        src_system, src_component = self._peer(m)
        self.send(mavlink.MAVLink_file_transfer_protocol_message(
            0, src_system, src_component, list(reply)
        ))


_ONE_SHOT = frozenset({0, 1, 24, 30, 32, 33, 42, 74, 147, 148, 242, 245})

_DISPATCH: dict[str, Callable[[VehicleLink, mavlink.MAVLink_message], None]] = {
    "COMMAND_LONG": VehicleLink._command_long,
    "COMMAND_INT": VehicleLink._command_int,
    "PARAM_REQUEST_LIST": VehicleLink._param_request_list,
    "PARAM_REQUEST_READ": VehicleLink._param_request_read,
    "PARAM_SET": VehicleLink._param_set,
    "MISSION_COUNT": VehicleLink._mission_count,
    "MISSION_ITEM_INT": VehicleLink._mission_item_int,
    "MISSION_ITEM": VehicleLink._mission_item,
    "MISSION_REQUEST_LIST": VehicleLink._mission_request_list,
    "MISSION_REQUEST_INT": VehicleLink._mission_request_int,
    "MISSION_REQUEST": VehicleLink._mission_request,
    "MISSION_CLEAR_ALL": VehicleLink._mission_clear_all,
    "MISSION_SET_CURRENT": VehicleLink._mission_set_current,
    "SET_POSITION_TARGET_LOCAL_NED": VehicleLink._set_position_target_local_ned,
    "SET_POSITION_TARGET_GLOBAL_INT": VehicleLink._set_position_target_global_int,
    "PING": VehicleLink._ping,
    "TIMESYNC": VehicleLink._timesync,
    "FILE_TRANSFER_PROTOCOL": VehicleLink._file_transfer,
}

HANDLED_MESSAGES: frozenset[str] = frozenset(_DISPATCH)  # what a vehicle acts on or answers

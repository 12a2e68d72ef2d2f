"""One vehicle's MAVLink endpoint, sans I/O: decoded messages in, encoded frames out.

It dispatches what a ground station sends (commands, parameters, missions, offboard
set-points, camera requests) to the vehicle's autopilot and answers as PX4 does: handlers
return replies (emulator.mavlink.reply) or messages, and the link encodes them and hands the
frames to the `emit` callable of its network (emulator.mavlink.protocol); nothing here
touches a socket. Messages are dispatched by their `MessageId`.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Callable, Iterable

from emulator.flight.autopilot import Autopilot, ImageCapture
from emulator.flight.params import ParamError, ParamStore
from emulator.flight.refusal import Severity
from emulator.mavlink import messages as msgs
from emulator.mavlink.camera import CAMERA_COMMANDS, CAMERA_MESSAGES, CameraComponent
from emulator.mavlink.codec import Encoder, mavlink
from emulator.mavlink.command_args import CommandArgs
from emulator.mavlink.command_dedup import STATEFUL_COMMANDS, CommandDedup, command_key
from emulator.mavlink.commands import execute_command
from emulator.mavlink.ftp import FtpServer
from emulator.mavlink.imu import highres_imu
from emulator.mavlink.log_transfer import LOG_MESSAGES, LogTransfer
from emulator.mavlink.mission_transfer import MissionTransfer
from emulator.mavlink.offboard import SETPOINT_APPLIERS, Complaint
from emulator.mavlink.reply import Action, Reply, SendMessage, SendOnce
from emulator.mavlink.streams import CAMERA_HEARTBEAT, StreamSchedule
from mavlink_vocabulary import MavComponent, MavParamType, MavResult, MessageId

__all__ = ["HANDLED_MESSAGES", "VehicleLink"]

_INT_TYPES = frozenset({MavParamType.UINT8, MavParamType.INT8, MavParamType.UINT16,
                        MavParamType.INT16, MavParamType.UINT32, MavParamType.INT32})
AUTOPILOT_COMPONENT_ID = MavComponent.AUTOPILOT1
CAMERA_COMPONENT_ID = MavComponent.CAMERA
MIN_STREAM_INTERVAL_S = 0.01  # streams are capped at 100 Hz whatever a client asks
# MAVLink FTP is not offered: every request gets a NAK(UnknownCommand) so clients fall back


def _bytewise_int(value: float) -> int:
    return struct.unpack("<i", struct.pack("<f", value))[0]


def _bytewise_float(value: int) -> float:
    return struct.unpack("<f", struct.pack("<i", value))[0]


_OPERATOR_RESET_STREAMS = (MessageId.SYS_STATUS, MessageId.BATTERY_STATUS,
                           MessageId.GLOBAL_POSITION_INT, MessageId.LOCAL_POSITION_NED,
                           MessageId.HOME_POSITION)
# what a vehicle sends on request (MAV_CMD_REQUEST_MESSAGE), besides the camera's messages

class VehicleLink:
    """MAVLink side of vehicle `ap` (system id k + 1)."""

    def __init__(self, ap: Autopilot, emit: Callable[[int, bytes], None],
                 streams: StreamSchedule, wall_clock: Callable[[], float]) -> None:
        self.ap = ap
        self.k = ap.k
        self.system_id = ap.k + 1
        self._emit = emit
        self._streams = streams
        self._encoders: dict[int, Encoder] = {
            AUTOPILOT_COMPONENT_ID: Encoder(self.system_id, AUTOPILOT_COMPONENT_ID),
            CAMERA_COMPONENT_ID: Encoder(self.system_id, CAMERA_COMPONENT_ID),
        }
        self.camera = CameraComponent()
        self.missions = MissionTransfer(ap)
        self.logs = LogTransfer(ap)
        self.ftp = FtpServer(self.logs.files)
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

    def send_all(self, messages: Iterable[mavlink.MAVLink_message]) -> None:
        for message in messages:
            self.send(message)

    def encoder(self, component_id: int) -> Encoder:
        return self._encoders[component_id]

    def statustext(self, severity: int, text: str) -> None:
        self.send(msgs.statustext(severity, text))

    def time_boot_ms(self) -> int:
        return int(self.ap.now_s * 1000.0) & 0xFFFFFFFF

    def build(self, msg_id: int) -> mavlink.MAVLink_message | None:
        builder = _BUILDERS.get(msg_id)
        return None if builder is None else builder(self)

    def send_stream(self, msg_id: int) -> None:
        if msg_id == CAMERA_HEARTBEAT:
            self.send(self.camera.heartbeat(), CAMERA_COMPONENT_ID)
            return
        message = self.build(msg_id)
        if message is not None:
            self.send(message)

    def can_send_once(self, msg_id: int) -> bool:
        return msg_id in CAMERA_MESSAGES or msg_id in _BUILDERS  # each can be sent once

    def send_once(self, msg_id: int) -> None:
        if msg_id in CAMERA_MESSAGES:
            message = self.camera.build(self.ap, msg_id)
            if message is not None:
                self.send(message, CAMERA_COMPONENT_ID)
        else:
            self.send_stream(msg_id)

    def set_stream_interval(self, msg_id: int, interval_s: float | None) -> bool:
        if msg_id == MessageId.HEARTBEAT:
            return False  # the 1 Hz heartbeat is the link's pulse: its rate is fixed
        if interval_s is not None:
            interval_s = max(interval_s, MIN_STREAM_INTERVAL_S)
        return self._streams.set_interval(self.k, msg_id, interval_s, self.wall_now_s)

    # ------------------------------------------------------ autopilot listener
    def on_statustext(self, severity: int, text: str) -> None:
        self.dedup.on_vehicle_text(severity, text)
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
        self.send_once(MessageId.HOME_POSITION)

    def on_image_captured(self, capture: ImageCapture) -> None:
        self.send(self.camera.image_captured(self.ap, capture), CAMERA_COMPONENT_ID)

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
        handler = _DISPATCH.get(m.get_msgId())
        if handler is not None:
            handler(self, m)

    def tick(self, wall_now_s: float) -> None:
        self.wall_now_s = wall_now_s
        self.send_all(self.missions.tick(wall_now_s))
        self.ap.offboard.check_link(wall_now_s)

    def _peer(self, m) -> tuple[int, int]:
        return m.get_srcSystem(), m.get_srcComponent()

    def _on_command(self, m, args: CommandArgs) -> None:
        target_component = getattr(m, "target_component", MavComponent.ALL)
        if target_component not in _COMMAND_COMPONENTS:
            return  # for a component this vehicle does not have: not ours to answer
        if target_component == CAMERA_COMPONENT_ID and args.command not in CAMERA_COMMANDS:
            self._answer(m, args.command, Reply(MavResult.UNSUPPORTED), target_component)
            return
        if args.command not in STATEFUL_COMMANDS:
            self._answer(m, args.command, execute_command(self, args), target_component)
            return
        key, step = command_key(m), self.ap.fleet.step_count
        repeated = self.dedup.repeat_of(self._peer(m), key, step, self.wall_now_s)
        if repeated is not None:  # a retransmission: the first copy's answer again
            self._ack(m, args.command, repeated, target_component)
            return
        reply = execute_command(self, args)
        if reply.result != MavResult.ACCEPTED:  # refused: because a first copy acted?
            acted = self.dedup.acted_before(self._peer(m), key, self.wall_now_s)
            if acted is not None:
                self._ack(m, args.command, acted, target_component)
                return
        self._answer(m, args.command, reply, target_component)
        self.dedup.answered(self._peer(m), key, step, self.wall_now_s, reply.result)

    def _answer(self, m, command: int, reply: Reply, target_component: int) -> None:
        """The ACK, the reason as a STATUSTEXT, then what follows an accepted command."""
        self._ack(m, command, reply.result, target_component)
        if reply.reason:
            self.statustext(Severity.WARNING if reply.result else Severity.INFO, reply.reason)
        if reply.result != MavResult.ACCEPTED:
            return
        for follow_up in reply.follow_ups:
            if isinstance(follow_up, SendOnce):
                self.send_once(follow_up.msg_id)
            elif isinstance(follow_up, SendMessage):
                self.send(follow_up.message, follow_up.component)
            elif isinstance(follow_up, Action):
                follow_up.run()

    def _ack(self, m, command: int, result: int, target_component: int) -> None:
        component = CAMERA_COMPONENT_ID if target_component == CAMERA_COMPONENT_ID \
            else AUTOPILOT_COMPONENT_ID
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
            wire, ptype = _bytewise_float(int(value)), MavParamType.INT32
        else:
            wire, ptype = value, MavParamType.REAL32
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
        self.send_all(self.missions.on_count(m, self._peer(m), self.wall_now_s))

    def _mission_item_int(self, m) -> None:
        self.send_all(self.missions.on_item(m, self._peer(m), self.wall_now_s, is_int=True))

    def _mission_item(self, m) -> None:
        self.send_all(self.missions.on_item(m, self._peer(m), self.wall_now_s, is_int=False))

    def _mission_request_list(self, m) -> None:
        self.send_all(self.missions.on_request_list(m, self._peer(m)))

    def _mission_request_int(self, m) -> None:
        self.send_all(self.missions.on_request(m, self._peer(m), wants_int=True))

    def _mission_request(self, m) -> None:
        self.send_all(self.missions.on_request(m, self._peer(m), wants_int=False))

    def _mission_clear_all(self, m) -> None:
        self.last_reached = None
        self.dedup.forget()
        self.send_all(self.missions.on_clear_all(m, self._peer(m)))

    def _mission_set_current(self, m) -> None:
        self.dedup.forget()
        self.send_all(self.missions.on_set_current(m))

    # ------------------------------------------------------------------ others
    def _complain(self, complaint: Complaint | None) -> None:
        if complaint is not None and complaint.key not in self.warned:
            self.warned.add(complaint.key)
            self.statustext(Severity.WARNING, complaint.text)

    def _offboard_setpoint(self, m) -> None:
        self._complain(SETPOINT_APPLIERS[m.get_msgId()](self.ap, m, self.wall_now_s))

    def _ping(self, m) -> None:
        if m.target_system == self.system_id:  # broadcast pings are not answered
            src_system, src_component = self._peer(m)
            self.send(mavlink.MAVLink_ping_message(m.time_usec, m.seq, src_system, src_component))

    def _timesync(self, m) -> None:
        if m.tc1 == 0:
            now_ns = int(self.ap.now_s * 1e9)
            self.send(mavlink.MAVLink_timesync_message(now_ns, m.ts1))

    def _log_request(self, m) -> None:
        self.send_all(self.logs.handle(m))

    def _file_transfer(self, m) -> None:
        src_system, src_component = self._peer(m)
        for reply in self.ftp.handle(bytes(m.payload)):
            self.send(mavlink.MAVLink_file_transfer_protocol_message(
                0, src_system, src_component, list(reply)))


_COMMAND_COMPONENTS = frozenset({MavComponent.ALL, AUTOPILOT_COMPONENT_ID, CAMERA_COMPONENT_ID})

_BUILDERS: dict[int, Callable[[VehicleLink], mavlink.MAVLink_message]] = {
    MessageId.HEARTBEAT: lambda v: msgs.heartbeat(v.ap),
    MessageId.SYS_STATUS: lambda v: msgs.sys_status(v.ap),
    MessageId.EXTENDED_SYS_STATE: lambda v: msgs.extended_sys_state(v.ap),
    MessageId.GLOBAL_POSITION_INT: lambda v: msgs.global_position_int(v.ap, v.time_boot_ms()),
    MessageId.LOCAL_POSITION_NED: lambda v: msgs.local_position_ned(v.ap, v.time_boot_ms()),
    MessageId.ATTITUDE: lambda v: msgs.attitude(v.ap, v.time_boot_ms()),
    MessageId.GPS_RAW_INT: lambda v: msgs.gps_raw_int(v.ap, v.time_boot_ms() * 1000),
    MessageId.VFR_HUD: lambda v: msgs.vfr_hud(v.ap),
    MessageId.MISSION_CURRENT: lambda v: msgs.mission_current(v.ap),
    MessageId.BATTERY_STATUS: lambda v: msgs.battery_status(v.ap),
    MessageId.HOME_POSITION: lambda v: msgs.home_position(v.ap, v.time_boot_ms() * 1000),
    MessageId.AUTOPILOT_VERSION: lambda v: msgs.autopilot_version(v.ap),
    MessageId.HIGHRES_IMU: lambda v: highres_imu(v.ap.fleet, v.k),
}

_DISPATCH: dict[MessageId, Callable[[VehicleLink, mavlink.MAVLink_message], None]] = {
    MessageId.COMMAND_LONG: VehicleLink._command_long,
    MessageId.COMMAND_INT: VehicleLink._command_int,
    MessageId.PARAM_REQUEST_LIST: VehicleLink._param_request_list,
    MessageId.PARAM_REQUEST_READ: VehicleLink._param_request_read,
    MessageId.PARAM_SET: VehicleLink._param_set,
    MessageId.MISSION_COUNT: VehicleLink._mission_count,
    MessageId.MISSION_ITEM_INT: VehicleLink._mission_item_int,
    MessageId.MISSION_ITEM: VehicleLink._mission_item,
    MessageId.MISSION_REQUEST_LIST: VehicleLink._mission_request_list,
    MessageId.MISSION_REQUEST_INT: VehicleLink._mission_request_int,
    MessageId.MISSION_REQUEST: VehicleLink._mission_request,
    MessageId.MISSION_CLEAR_ALL: VehicleLink._mission_clear_all,
    MessageId.MISSION_SET_CURRENT: VehicleLink._mission_set_current,
    **{msg_id: VehicleLink._offboard_setpoint for msg_id in SETPOINT_APPLIERS},
    MessageId.PING: VehicleLink._ping,
    MessageId.TIMESYNC: VehicleLink._timesync,
    MessageId.FILE_TRANSFER_PROTOCOL: VehicleLink._file_transfer,
    **{msg_id: VehicleLink._log_request for msg_id in LOG_MESSAGES},
}

# the names of the messages a vehicle acts on or answers
HANDLED_MESSAGES: frozenset[str] = frozenset(m.name for m in _DISPATCH)

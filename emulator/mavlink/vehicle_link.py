"""One vehicle's MAVLink endpoint, sans I/O: decoded messages in, encoded frames out.

It dispatches what a ground station sends (commands, parameters, missions, offboard
set-points, camera requests) to the vehicle's autopilot and answers as PX4 does: handlers
return replies (emulator.mavlink.reply) or messages, and the link encodes them and hands the
frames to the `emit` callable of its network (emulator.mavlink.protocol); nothing here
touches a socket. Messages are dispatched by their `MessageId`.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

from emulator.flight.autopilot import Autopilot, ImageCapture
from emulator.flight.manual_control import MANUAL_MODES
from emulator.flight.mission import MissionItem
from emulator.flight.modes import FlightMode
from emulator.flight.refusal import Severity
from emulator.mavlink import messages as msgs
from emulator.mavlink import param_protocol
from emulator.mavlink.camera import CAMERA_COMMANDS, CAMERA_MESSAGES, CameraComponent
from emulator.mavlink.codec import Encoder, mavlink
from emulator.mavlink.command_args import CommandArgs
from emulator.mavlink.command_dedup import STATEFUL_COMMANDS, CommandDedup, command_key
from emulator.mavlink.commands import execute_command
from emulator.mavlink.ftp import FtpServer
from emulator.mavlink.gimbal import GIMBAL_COMPONENT_ID, GIMBAL_MESSAGES, GimbalComponent
from emulator.mavlink.imu import highres_imu
from emulator.mavlink.log_transfer import LOG_MESSAGES, LogTransfer
from emulator.mavlink.mission_transfer import MissionTransfer
from emulator.mavlink.offboard import SETPOINT_APPLIERS, Complaint
from emulator.mavlink.payload_items import payload_item_reply
from emulator.mavlink.pilot_input import apply_follow_target, apply_manual_control
from emulator.mavlink.queries import changes_state
from emulator.mavlink.reply import Action, Reply, SendMessage, SendOnce
from emulator.mavlink.streams import CAMERA_HEARTBEAT, StreamSchedule
from mavlink_vocabulary import MavComponent, MavResult, MessageId

__all__ = ["HANDLED_MESSAGES", "VehicleLink"]

AUTOPILOT_COMPONENT_ID = MavComponent.AUTOPILOT1
CAMERA_COMPONENT_ID = MavComponent.CAMERA
MIN_STREAM_INTERVAL_S = 0.01  # streams are capped at 100 Hz whatever a client asks
_OPERATOR_RESET_STREAMS = (MessageId.SYS_STATUS, MessageId.BATTERY_STATUS,
                           MessageId.GLOBAL_POSITION_INT, MessageId.LOCAL_POSITION_NED,
                           MessageId.HOME_POSITION)


class VehicleLink:
    """MAVLink side of vehicle `ap` (system id k % 250 + 1: emulator.networks)."""

    def __init__(self, ap: Autopilot, emit: Callable[[int, bytes], None],
                 streams: StreamSchedule, wall_clock: Callable[[], float]) -> None:
        self.ap = ap
        self.k = ap.k
        self.system_id = ap.system_id
        self._emit = emit
        self._streams = streams
        self._encoders: dict[int, Encoder] = {
            AUTOPILOT_COMPONENT_ID: Encoder(self.system_id, AUTOPILOT_COMPONENT_ID),
            CAMERA_COMPONENT_ID: Encoder(self.system_id, CAMERA_COMPONENT_ID),
        }
        self.camera = CameraComponent()
        self.gimbal = GimbalComponent() if ap.spec.gimbal else None  # the session asks
        if self.gimbal is not None:
            self._encoders[GIMBAL_COMPONENT_ID] = Encoder(self.system_id, GIMBAL_COMPONENT_ID)
        self.command_peer = (0, 0)  # who sent the command being handled
        self.missions = MissionTransfer(ap)
        self.logs = LogTransfer(ap)
        self.ftp = FtpServer(self.logs.files)
        self.wall_now_s = wall_clock()
        self.warned: set[str] = set()  # problems already reported once by STATUSTEXT
        self.dedup = CommandDedup()
        self.last_reached: int | None = None  # the last MISSION_ITEM_REACHED of this mission
        # the autopilot's STATUSTEXTs at one simulated time, the latest (`repeat_texts_now`)
        self._texts_at_s = -1.0
        self._texts_now: list[tuple[int, str]] = []
        # told when this vehicle's MAVLink goes off or comes back (the swarm's link faults)
        self.on_mavlink_signal: Callable[[Autopilot], None] | None = None
        # told (with k) whenever this link may have gained a wall-clock duty (`needs_tick`):
        # a message handled, the vehicle's state changed, a payload item reached
        self.on_tick_duty: Callable[[int], None] | None = None
        # told (with k) whenever what this vehicle's telemetry shows may have changed other
        # than by flying: a message that is not a query, an autopilot event
        self.on_changed: Callable[[int], None] | None = None
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
            self.send(self.camera.heartbeat(self.ap), CAMERA_COMPONENT_ID)
            return
        message = self.build(msg_id)
        if message is not None:
            self.send(message)

    def can_send_once(self, msg_id: int) -> bool:  # each can be sent once
        return msg_id in CAMERA_MESSAGES or msg_id in _BUILDERS or (
            self.gimbal is not None and msg_id in GIMBAL_MESSAGES)

    def send_once(self, msg_id: int) -> None:
        if self.gimbal is not None and (msg_id in GIMBAL_MESSAGES or msg_id == -1):
            message = self.gimbal.build(self.ap, msg_id)
            if message is not None:
                self.send(message, self.gimbal.component_of(msg_id))
        elif msg_id in CAMERA_MESSAGES:
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
        self._changed()
        self.dedup.on_vehicle_text(severity, text)
        now_s = self.ap.now_s
        if now_s != self._texts_at_s:
            self._texts_at_s, self._texts_now = now_s, []
        self._texts_now.append((severity, text))
        self.statustext(severity, text)

    def repeat_texts_now(self) -> int:
        """The autopilot's STATUSTEXTs of the present simulated time, sent again (how many)."""
        if self._texts_at_s != self.ap.now_s:
            return 0
        for severity, text in self._texts_now:
            self.statustext(severity, text)
        return len(self._texts_now)

    def on_mission_item_reached(self, seq: int) -> None:
        self._changed()
        self.last_reached = seq
        self.send(mavlink.MAVLink_mission_item_reached_message(seq))

    def resend_mission_reached(self) -> None:
        """MISSION_ITEM_REACHED comes once per item: on a lossy link the swarm repeats the
        last one with the vehicle's telemetry at a lockstep halt, or a client could never
        learn that its mission finished."""
        if self.last_reached is not None:
            self.send(mavlink.MAVLink_mission_item_reached_message(self.last_reached))

    def on_mission_current(self) -> None:
        self._changed()
        self.send(msgs.mission_current(self.ap))

    def on_home_changed(self) -> None:
        self._changed()
        self.send_once(MessageId.HOME_POSITION)

    def on_image_captured(self, capture: ImageCapture) -> None:
        self._changed()
        self.send(self.camera.image_captured(self.ap, capture), CAMERA_COMPONENT_ID)

    def on_payload_item(self, item: MissionItem) -> None:
        """A mission's gimbal or camera item, reached: the gimbal or camera acts on it."""
        reply = payload_item_reply(self, item)
        if reply is not None:
            self._answer(None, None, reply, AUTOPILOT_COMPONENT_ID)
        self._tick_duty()

    def on_state_changed(self) -> None:
        """Mode, arming or landed state changed: say so now, not at the next 1 Hz slot."""
        self.send(msgs.heartbeat(self.ap))
        self.send(msgs.extended_sys_state(self.ap))
        self._tick_duty()
        self._changed()

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
            try:
                handler(self, m)
            finally:
                self._tick_duty()
                if changes_state(m):
                    self._changed()

    def _changed(self) -> None:
        if self.on_changed is not None:
            self.on_changed(self.k)

    def _tick_duty(self) -> None:
        if self.on_tick_duty is not None:
            self.on_tick_duty(self.k)

    @property
    def needs_tick(self) -> bool:
        """Whether `tick` has a wall-clock duty now (an upload, a set-point or stick link, a
        recording's capture status)."""
        return (self.missions.uploading or self.ap.mode in _LINK_WATCHED_MODES
                or self.camera.video.status_due_wall_s is not None or self.gimbal is not None)

    def tick(self, wall_now_s: float) -> None:
        self.wall_now_s = wall_now_s
        self.send_all(self.missions.tick(wall_now_s))
        self.ap.offboard.check_link(wall_now_s)
        self.ap.manual.check_link(wall_now_s)
        self.ap.follow.check_link(wall_now_s)
        if self.camera.video.status_due(wall_now_s):  # a recording's capture status
            self.send_once(MessageId.CAMERA_CAPTURE_STATUS)
        if self.gimbal is not None:
            for msg_id in self.gimbal.due(wall_now_s):
                self.send_once(msg_id)

    def _peer(self, m) -> tuple[int, int]:
        return m.get_srcSystem(), m.get_srcComponent()

    def _on_command(self, m, args: CommandArgs) -> None:
        target_component = getattr(m, "target_component", MavComponent.ALL)
        if target_component == GIMBAL_COMPONENT_ID and self.gimbal is not None:
            wanted = self.gimbal.device_request(args)  # the gimbal device answers
            result = MavResult.UNSUPPORTED if wanted is None else MavResult.ACCEPTED
            self._ack(m, args.command, result, target_component)
            if wanted is not None:
                self.send_once(wanted)
            return
        if target_component not in _COMMAND_COMPONENTS:
            return  # for a component this vehicle does not have: not ours to answer
        if target_component == CAMERA_COMPONENT_ID and args.command not in CAMERA_COMMANDS:
            self._answer(m, args.command, Reply(MavResult.UNSUPPORTED), target_component)
            return
        self.command_peer = self._peer(m)
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

    def _answer(self, m, command: int | None, reply: Reply, target_component: int) -> None:
        """The ACK (none for a mission item), the reason as a STATUSTEXT, then what follows
        an accepted command."""
        if command is not None:
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
        component = target_component if target_component in (
            CAMERA_COMPONENT_ID, GIMBAL_COMPONENT_ID) else AUTOPILOT_COMPONENT_ID
        src_system, src_component = self._peer(m)
        self.send(mavlink.MAVLink_command_ack_message(
            command, result, 0, 0, src_system, src_component
        ), component)

    def _command_long(self, m) -> None:
        self._on_command(m, CommandArgs.from_long(m))

    def _command_int(self, m) -> None:
        self._on_command(m, CommandArgs.from_int(m))

    # -------------------------------------------------------------- parameters
    def _param_request_list(self, m) -> None:
        self.send_all(param_protocol.param_list(self.ap))

    def _param_request_read(self, m) -> None:
        self._param_answer(param_protocol.param_read(self.ap, m))

    def _param_set(self, m) -> None:
        self.dedup.forget()
        self._param_answer(param_protocol.param_set(self.ap, m))

    def _param_answer(self, answer: param_protocol.Answer) -> None:
        problem, value = answer
        if problem:
            self.statustext(Severity.WARNING, problem)
        if value is not None:
            self.send(value)

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

    def _streamed_input(self, m) -> None:
        self._complain(_STREAMED_INPUT[m.get_msgId()](self.ap, m, self.wall_now_s))

    def _ping(self, m) -> None:
        if m.target_system == self.system_id:  # broadcast pings are not answered
            src_system, src_component = self._peer(m)
            self.send(mavlink.MAVLink_ping_message(m.time_usec, m.seq, src_system, src_component))

    def _timesync(self, m) -> None:
        if m.tc1 == 0:
            now_ns = int(self.ap.now_s * 1e9)
            self.send(mavlink.MAVLink_timesync_message(now_ns, m.ts1))

    def _gimbal_setpoint(self, m) -> None:
        if self.gimbal is None:
            return
        aim = (self.gimbal.on_set_pitchyaw if m.get_msgId() == MessageId.GIMBAL_MANAGER_SET_PITCHYAW
               else self.gimbal.on_set_attitude)
        problem = aim(self.ap, m, self._peer(m))
        self._complain(Complaint(problem.split(":")[0], problem) if problem else None)

    def _log_request(self, m) -> None:
        self.send_all(self.logs.handle(m))

    def _file_transfer(self, m) -> None:
        src_system, src_component = self._peer(m)
        for reply in self.ftp.handle(bytes(m.payload)):
            self.send(mavlink.MAVLink_file_transfer_protocol_message(
                0, src_system, src_component, list(reply)))


# modes whose input a link watches (its loss is a failsafe)
_LINK_WATCHED_MODES = frozenset({FlightMode.OFFBOARD, FlightMode.FOLLOW_TARGET, *MANUAL_MODES})
# set-points and stick input: streamed, never answered (a problem is reported once)
_STREAMED_INPUT = {**SETPOINT_APPLIERS, MessageId.MANUAL_CONTROL: apply_manual_control,
                   MessageId.FOLLOW_TARGET: apply_follow_target}
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
    **{msg_id: VehicleLink._streamed_input for msg_id in _STREAMED_INPUT},
    MessageId.PING: VehicleLink._ping,
    MessageId.TIMESYNC: VehicleLink._timesync,
    MessageId.FILE_TRANSFER_PROTOCOL: VehicleLink._file_transfer,
    **{msg_id: VehicleLink._log_request for msg_id in LOG_MESSAGES},
    MessageId.GIMBAL_MANAGER_SET_PITCHYAW: VehicleLink._gimbal_setpoint,
    MessageId.GIMBAL_MANAGER_SET_ATTITUDE: VehicleLink._gimbal_setpoint,
}

# the names of the messages a vehicle acts on or answers
HANDLED_MESSAGES: frozenset[str] = frozenset(m.name for m in _DISPATCH)

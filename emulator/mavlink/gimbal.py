"""A gimbal on a vehicle whose scenario asks for one (MAVLink gimbal protocol v2).

As on PX4, the autopilot (component 1) is the gimbal manager and the gimbal device is its own
component (MAV_COMP_ID_GIMBAL, 154, with a heartbeat). The manager announces itself with
GIMBAL_MANAGER_INFORMATION and GIMBAL_MANAGER_STATUS (who is in control); the device reports
GIMBAL_DEVICE_ATTITUDE_STATUS. DO_GIMBAL_MANAGER_PITCHYAW and the GIMBAL_MANAGER_SET_PITCHYAW /
_SET_ATTITUDE messages aim it (angles, or rates to the limits) and it slews there at up to
SLEW_RATE_DEG_S in simulated time; a yaw is about the vehicle's front unless the yaw-lock
flag asks for an earth-frame heading. DO_GIMBAL_MANAGER_CONFIGURE sets the primary controller;
while another ground station is in control, aiming is refused. Nothing here sends: the link
sends what these methods build.
"""

from __future__ import annotations

import math

from emulator.flight.autopilot import Autopilot
from emulator.geo import wrap_heading_deg
from emulator.mavlink.codec import mavlink
from emulator.mavlink.command_args import CommandArgs
from emulator.mavlink.messages import component_heartbeat
from emulator.mavlink.reply import Reply, SendOnce
from emulator.truth_events import TruthEventKind
from mavlink_vocabulary import MavCmd, MavComponent, MavType, MessageId

__all__ = ["GIMBAL_COMMANDS", "GIMBAL_COMPONENT_ID", "GIMBAL_MESSAGES", "GimbalComponent"]

GIMBAL_COMPONENT_ID = MavComponent.GIMBAL
ATTITUDE_INTERVAL_S = 0.1  # GIMBAL_DEVICE_ATTITUDE_STATUS (wall s, as every stream)
STATUS_INTERVAL_S = 1.0  # the device's heartbeat and GIMBAL_MANAGER_STATUS
PITCH_RANGE_DEG = (-90.0, 30.0)
YAW_RANGE_DEG = (-180.0, 180.0)
SLEW_RATE_DEG_S = 90.0
FLAG_YAW_LOCK = 16  # GIMBAL_MANAGER_FLAGS_YAW_LOCK / GIMBAL_DEVICE_FLAGS_YAW_LOCK
FLAG_YAW_IN_VEHICLE_FRAME = 32
FLAG_YAW_IN_EARTH_FRAME = 64
CAP_FLAGS = 4 | 8 | 16 | 64 | 128 | 256 | 512  # pitch/yaw axis, follow and lock, rates
GIMBAL_COMMANDS = frozenset({MavCmd.DO_GIMBAL_MANAGER_PITCHYAW,
                             MavCmd.DO_GIMBAL_MANAGER_CONFIGURE})
GIMBAL_MESSAGES = frozenset({MessageId.GIMBAL_MANAGER_INFORMATION,
                             MessageId.GIMBAL_MANAGER_STATUS,
                             MessageId.GIMBAL_DEVICE_INFORMATION,
                             MessageId.GIMBAL_DEVICE_ATTITUDE_STATUS})
# what the device itself (component 154) sends on request
_DEVICE_MESSAGES = frozenset({-1, MessageId.GIMBAL_DEVICE_INFORMATION,
                              MessageId.GIMBAL_DEVICE_ATTITUDE_STATUS})
Peer = tuple[int, int]


def _euler_to_q(roll: float, pitch: float, yaw: float) -> list[float]:
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return [cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy]


def _q_to_pitch_yaw_deg(q) -> tuple[float, float]:
    w, x, y, z = (float(v) for v in q)
    pitch = math.asin(max(-1.0, min(1.0, 2.0 * (w * y - z * x))))
    yaw = math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    return math.degrees(pitch), math.degrees(yaw)


def _relative_deg(a: float) -> float:
    return (a + 180.0) % 360.0 - 180.0


class GimbalComponent:
    """One vehicle's gimbal: where it points, where it is aimed, who controls it."""

    def __init__(self) -> None:
        self.pitch_deg = 0.0
        self.yaw_deg = 0.0  # about the vehicle's front
        self._goal = (0.0, 0.0)
        self._yaw_lock_heading_deg: float | None = None  # earth-frame yaw held
        self._at_s = 0.0  # simulated time of the angles above
        self.primary: Peer = (0, 0)
        self._attitude_due_s = self._status_due_s = -math.inf  # wall

    def due(self, wall_now_s: float) -> list[int]:
        """The gimbal's streams due now (-1: the device's heartbeat)."""
        out: list[int] = []
        if wall_now_s >= self._status_due_s:
            self._status_due_s = wall_now_s + STATUS_INTERVAL_S
            out += [-1, MessageId.GIMBAL_MANAGER_STATUS]
        if wall_now_s >= self._attitude_due_s:
            self._attitude_due_s = wall_now_s + ATTITUDE_INTERVAL_S
            out.append(MessageId.GIMBAL_DEVICE_ATTITUDE_STATUS)
        return out

    # ------------------------------------------------------------- attitude
    def update(self, ap: Autopilot) -> None:
        """Slew towards the goal for the simulated time since the last update."""
        now = ap.now_s
        step = SLEW_RATE_DEG_S * max(0.0, now - self._at_s)
        self._at_s = now
        goal_pitch, goal_yaw = self._goal
        if self._yaw_lock_heading_deg is not None:
            goal_yaw = _relative_deg(self._yaw_lock_heading_deg - float(ap.fleet.dyn.yaw_deg[ap.k]))
            goal_yaw = min(max(goal_yaw, YAW_RANGE_DEG[0]), YAW_RANGE_DEG[1])
        self.pitch_deg += max(-step, min(step, goal_pitch - self.pitch_deg))
        self.yaw_deg += max(-step, min(step, _relative_deg(goal_yaw - self.yaw_deg)))
        self.yaw_deg = _relative_deg(self.yaw_deg)

    def aim(self, ap: Autopilot, pitch_deg: float, yaw_deg: float, pitch_rate: float,
            yaw_rate: float, flags: int, sender: Peer) -> str:
        """Aim the gimbal (NaN angle: by the rate to the limit, or unchanged); "" when done,
        else why it was refused (nothing changed)."""
        if self.primary != (0, 0) and sender != self.primary:
            return f"Gimbal: controlled by {self.primary[0]}/{self.primary[1]}"
        for what, value, (low, high) in (("pitch", pitch_deg, PITCH_RANGE_DEG),
                                         ("yaw", yaw_deg, YAW_RANGE_DEG)):
            if math.isinf(value) or (math.isfinite(value) and not low <= value <= high):
                return f"Gimbal: {what} {value:g} outside [{low:g}, {high:g}]"
        self.update(ap)
        goal_pitch, goal_yaw = self._goal
        if math.isfinite(pitch_deg):
            goal_pitch = pitch_deg
        elif math.isfinite(pitch_rate) and pitch_rate:
            goal_pitch = PITCH_RANGE_DEG[pitch_rate > 0]
        lock = bool(flags & (FLAG_YAW_LOCK | FLAG_YAW_IN_EARTH_FRAME))
        self._yaw_lock_heading_deg = None
        if math.isfinite(yaw_deg):
            goal_yaw = yaw_deg
            if lock:
                self._yaw_lock_heading_deg = wrap_heading_deg(yaw_deg)
        elif math.isfinite(yaw_rate) and yaw_rate:
            goal_yaw = YAW_RANGE_DEG[yaw_rate > 0]
        self._goal = (goal_pitch, goal_yaw)
        ap.event(TruthEventKind.GIMBAL, pitch_deg=goal_pitch, yaw_deg=goal_yaw, earth_frame=lock)
        return ""

    # -------------------------------------------------------------- protocol
    def handle_command(self, ap: Autopilot, a: CommandArgs, sender: Peer) -> Reply:
        if a.command == MavCmd.DO_GIMBAL_MANAGER_CONFIGURE:
            return self._configure(a, sender)
        device = a.altitude_m if math.isfinite(a.altitude_m) else 0.0  # param7
        if device not in (0.0, float(GIMBAL_COMPONENT_ID), 1.0):
            return Reply.denied(f"Gimbal: no gimbal device {device:g}")
        flags = int(a.p5) if math.isfinite(a.p5) and 0 <= a.p5 < 2**32 else 0
        problem = self.aim(ap, a.p1, a.p2, a.p3, a.p4, flags, sender)
        return Reply.denied(problem) if problem else Reply.accepted(
            SendOnce(MessageId.GIMBAL_DEVICE_ATTITUDE_STATUS))

    def _configure(self, a: CommandArgs, sender: Peer) -> Reply:
        """p1/p2: primary control sysid/compid (-1 leave, -2 the sender, -3 release)."""
        sysid = a.p1 if math.isfinite(a.p1) else -1.0
        compid = a.p2 if math.isfinite(a.p2) else -1.0
        if sysid == -1.0:
            return Reply.accepted(SendOnce(MessageId.GIMBAL_MANAGER_STATUS))
        if sysid == -2.0:
            self.primary = sender
        elif sysid == -3.0:
            if self.primary not in ((0, 0), sender):
                return Reply.denied("Gimbal: only its controller releases it")
            self.primary = (0, 0)
        elif 0.0 <= sysid <= 255.0 and 0.0 <= compid <= 255.0:
            if self.primary not in ((0, 0), sender) and (int(sysid), int(compid)) != (0, 0):
                return Reply.denied(f"Gimbal: controlled by {self.primary[0]}/"
                                    f"{self.primary[1]}")
            self.primary = (int(sysid), int(compid))
        else:
            return Reply.denied(f"Gimbal: no controller {sysid:g}/{compid:g}")
        return Reply.accepted(SendOnce(MessageId.GIMBAL_MANAGER_STATUS))

    def on_set_pitchyaw(self, ap: Autopilot, m, sender: Peer) -> str:
        return self.aim(ap, math.degrees(m.pitch), math.degrees(m.yaw),
                        math.degrees(m.pitch_rate), math.degrees(m.yaw_rate), m.flags, sender)

    def on_set_attitude(self, ap: Autopilot, m, sender: Peer) -> str:
        if all(math.isfinite(v) for v in m.q):
            pitch, yaw = _q_to_pitch_yaw_deg(m.q)
        else:
            pitch = yaw = math.nan
        return self.aim(ap, pitch, yaw, math.degrees(m.angular_velocity_y),
                        math.degrees(m.angular_velocity_z), m.flags, sender)

    # -------------------------------------------------------------- messages
    def build(self, ap: Autopilot, msg_id: int) -> mavlink.MAVLink_message | None:
        t_ms = int(ap.now_s * 1000.0) & 0xFFFFFFFF
        if msg_id == -1:
            return component_heartbeat(ap, MavType.GIMBAL)
        if msg_id == MessageId.GIMBAL_MANAGER_INFORMATION:
            return mavlink.MAVLink_gimbal_manager_information_message(
                t_ms, CAP_FLAGS, GIMBAL_COMPONENT_ID, 0.0, 0.0,
                *(math.radians(v) for v in (*PITCH_RANGE_DEG, *YAW_RANGE_DEG)))
        if msg_id == MessageId.GIMBAL_DEVICE_INFORMATION:
            return mavlink.MAVLink_gimbal_device_information_message(
                t_ms, b"mavswarm", b"gimbal", b"", 1, 1, ap.k + 1, CAP_FLAGS, 0, 0.0, 0.0,
                *(math.radians(v) for v in (*PITCH_RANGE_DEG, *YAW_RANGE_DEG)))
        if msg_id == MessageId.GIMBAL_MANAGER_STATUS:
            return mavlink.MAVLink_gimbal_manager_status_message(
                t_ms, self._flags(), GIMBAL_COMPONENT_ID, *self.primary, 0, 0)
        if msg_id == MessageId.GIMBAL_DEVICE_ATTITUDE_STATUS:
            self.update(ap)
            vehicle_yaw = float(ap.fleet.dyn.yaw_deg[ap.k])
            q = _euler_to_q(0.0, math.radians(self.pitch_deg), math.radians(self.yaw_deg))
            return mavlink.MAVLink_gimbal_device_attitude_status_message(
                0, 0, t_ms, self._flags() | FLAG_YAW_IN_VEHICLE_FRAME, q, 0.0, 0.0, 0.0, 0,
                math.radians(_relative_deg(vehicle_yaw)), 0.0, 0)  # 0: from the device itself
        return None

    def _flags(self) -> int:
        return FLAG_YAW_LOCK if self._yaw_lock_heading_deg is not None else 0

    @staticmethod
    def component_of(msg_id: int) -> int:
        """The component that sends a gimbal message: the device its heartbeat and attitude,
        the manager (the autopilot) the rest."""
        return GIMBAL_COMPONENT_ID if msg_id in _DEVICE_MESSAGES else MavComponent.AUTOPILOT1

    @staticmethod
    def device_request(a: CommandArgs) -> int | None:
        """The message a command to the device (component 154) asks for, None if it is
        not one the device answers (only REQUEST_MESSAGE of its own messages)."""
        if a.command != MavCmd.REQUEST_MESSAGE or not math.isfinite(a.p1):
            return None
        wanted = int(a.p1)
        return wanted if wanted in _DEVICE_MESSAGES - {-1} else None

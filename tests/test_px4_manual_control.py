"""PX4 conformance in memory: MANUAL_CONTROL joystick input flies POSCTL and ALTCTL (checked
against the ground truth), COM_RC_IN_MODE decides whether a joystick is taken, and the loss
of input triggers NAV_RCL_ACT; bad input changes nothing."""

from __future__ import annotations

import math

import pytest

from emulator.flight.manual_control import ALTCTL_DRAG_1_S
from emulator.flight.modes import FlightMode
from mavlink_vocabulary import MavCmd, MavParamType, MavResult
from tests.memory_link import MemoryLink

POSCTL, ALTCTL = (1, 3, 0), (1, 2, 0)  # DO_SET_MODE: base (custom), main, sub


def _stick(link: MemoryLink, x: int = 0, y: int = 0, z: int = 500, r: int = 0,
           target: int = 1) -> int:
    return link.send(link.mav.manual_control_encode(target, x, y, z, r, 0))


def _set_param(link: MemoryLink, name: str, value: float) -> None:
    link.send(link.mav.param_set_encode(1, 1, name.encode(), value, MavParamType.REAL32))
    assert link.fleet.autopilots[0].params[name] == value


def _fly(link: MemoryLink, seconds: float, **axes: int) -> None:
    """Hold the sticks for `seconds`, sent at 20 Hz as a joystick does."""
    for _ in range(round(seconds / 0.05)):
        _stick(link, **axes)
        link.advance(0.05)


def test_posctl_sticks_fly_the_body_frame_velocity_and_centred_holds() -> None:
    link = MemoryLink(1, telemetry=False)
    link.arm_and_take_off(1, 10.0)
    ap = link.fleet.autopilots[0]
    assert ap.params["COM_RC_IN_MODE"] == 3  # PX4's default: RC or joystick, first kept
    _stick(link)
    assert link.command_long(1, MavCmd.DO_SET_MODE, *POSCTL).result == MavResult.ACCEPTED
    assert ap.mode is FlightMode.POSCTL
    x0, y0, z0 = ap.position_m
    heading = float(link.fleet.dyn.yaw_deg[0])
    # full forward pitch: MPC_VEL_MANUAL (10 m/s) along the heading, altitude held
    _fly(link, 6.0, x=1000)
    speed = link.fleet.dyn.speed_m_s(0)
    assert speed == pytest.approx(ap.params["MPC_VEL_MANUAL"], rel=0.02)
    x1, y1, z1 = ap.position_m
    course = math.degrees(math.atan2(x1 - x0, y1 - y0)) % 360.0
    assert abs((course - heading + 180.0) % 360.0 - 180.0) < 1.0
    assert z1 == pytest.approx(z0, abs=0.05)
    # centred sticks: it brakes and holds where it stopped
    _fly(link, 6.0)
    here = ap.position_m
    _fly(link, 4.0)
    assert math.dist(ap.position_m, here) < 0.05
    # half throttle up (z 750, beyond the deadzone): climbs at part of MPC_Z_VEL_MAX_UP
    _fly(link, 3.0, z=750)
    rate = float(link.fleet.dyn.velocity_m_s[0, 2])
    dz = ap.params["MPC_HOLD_DZ"]
    assert rate == pytest.approx((0.5 - dz) / (1 - dz) * ap.params["MPC_Z_VEL_MAX_UP"],
                                 rel=0.02)
    # the yaw stick turns the vehicle clockwise at its share of MPC_MAN_Y_MAX
    yaw0, t0 = float(link.fleet.dyn.yaw_deg[0]), link.fleet.now_s
    _fly(link, 2.0, r=400)
    turned = (float(link.fleet.dyn.yaw_deg[0]) - yaw0) % 360.0
    expected = (0.4 - dz) / (1 - dz) * ap.params["MPC_MAN_Y_MAX"] * (link.fleet.now_s - t0)
    assert turned == pytest.approx(expected, rel=0.05)


def test_altctl_tilts_accelerate_and_a_level_vehicle_drifts_to_a_stop() -> None:
    link = MemoryLink(1, telemetry=False)
    link.arm_and_take_off(1, 10.0)
    ap = link.fleet.autopilots[0]
    _stick(link)
    assert link.command_long(1, MavCmd.DO_SET_MODE, *ALTCTL).result == MavResult.ACCEPTED
    assert ap.mode is FlightMode.ALTCTL
    z0, t0 = ap.position_m[2], link.fleet.now_s
    _fly(link, 1.0, y=300)  # roll right, (0.3 - dz) / (1 - dz) of MPC_MAN_TILT_MAX
    dz = ap.params["MPC_HOLD_DZ"]
    tilt = math.radians((0.3 - dz) / (1 - dz) * ap.params["MPC_MAN_TILT_MAX"])
    accel, t = 9.80665 * math.tan(tilt), link.fleet.now_s - t0
    drag = ALTCTL_DRAG_1_S  # dv/dt = a - drag v
    v_east = link.fleet.dyn.velocity_m_s[0, 0]
    assert v_east == pytest.approx(accel / drag * (1 - math.exp(-drag * t)), rel=0.05)
    assert abs(link.fleet.dyn.velocity_m_s[0, 1]) < 0.01
    _fly(link, 1.0)  # level: it keeps drifting, slower
    drifting = link.fleet.dyn.velocity_m_s[0, 0]
    assert 0.5 * v_east < drifting < v_east
    _fly(link, 12.0)
    assert link.fleet.dyn.speed_m_s(0) < 0.1
    assert ap.position_m[2] == pytest.approx(z0, abs=0.05)


def test_posctl_takes_off_with_the_throttle_and_lands_when_flown_down() -> None:
    link = MemoryLink(1, telemetry=False)
    ap = link.fleet.autopilots[0]
    _stick(link)
    assert link.command_long(1, MavCmd.DO_SET_MODE, *POSCTL).result == MavResult.ACCEPTED
    assert link.command_long(1, MavCmd.COMPONENT_ARM_DISARM, 1.0).result == MavResult.ACCEPTED
    _fly(link, 1.0)  # centred throttle: stays on the ground
    assert not ap.in_air
    _fly(link, 4.0, z=1000)
    assert ap.in_air and ap.position_m[2] > 5.0
    _fly(link, 12.0, z=0)
    assert not ap.in_air and ap.position_m[2] == 0.0
    kinds = [e.kind for e in link.fleet.recorder.events("d1")]
    assert "takeoff" in kinds and "landed" in kinds
    _fly(link, ap.params["COM_DISARM_LAND"] + 0.5)
    assert not ap.armed


@pytest.mark.parametrize(("action", "mode"), [(1, FlightMode.HOLD), (2, FlightMode.RTL),
                                              (3, FlightMode.LAND)])
def test_losing_the_joystick_in_the_air_triggers_nav_rcl_act(action: int,
                                                             mode: FlightMode) -> None:
    link = MemoryLink(1, telemetry=False)
    link.arm_and_take_off(1, 10.0)
    ap = link.fleet.autopilots[0]
    ap.set_param("NAV_RCL_ACT", action)
    _stick(link)
    assert link.command_long(1, MavCmd.DO_SET_MODE, *POSCTL).result == MavResult.ACCEPTED
    _fly(link, 1.0, x=500)
    since = len(link.received)
    link.advance(ap.params["COM_RC_LOSS_T"] + 0.1)
    assert ap.mode is mode
    texts = [m.text for m in link.messages("STATUSTEXT", since=since)]
    assert any(t.startswith("Manual control lost") for t in texts)
    failsafes = link.fleet.recorder.events("d1", kinds="failsafe")
    assert [e.data["reason"] for e in failsafes] == ["manual_control_lost"]


def test_without_a_joystick_or_with_stick_input_disabled_posctl_is_refused() -> None:
    link = MemoryLink(1, telemetry=False)
    link.arm_and_take_off(1, 10.0)
    ap = link.fleet.autopilots[0]
    ack = link.command_long(1, MavCmd.DO_SET_MODE, *POSCTL)  # no input yet
    assert ack.result == MavResult.DENIED and ap.mode is FlightMode.HOLD
    for rc_in_mode in (0, 4):  # RC only, stick input disabled: the joystick is not taken
        _set_param(link, "COM_RC_IN_MODE", rc_in_mode)
        since = _stick(link)
        ack = link.command_long(1, MavCmd.DO_SET_MODE, *ALTCTL)
        assert ack.result == MavResult.DENIED and ap.mode is FlightMode.HOLD
        texts = [m.text for m in link.messages("STATUSTEXT", since=since)]
        assert texts[-1] == f"Mode altctl refused: no joystick, COM_RC_IN_MODE {rc_in_mode}"
        assert f"Joystick ignored: COM_RC_IN_MODE {rc_in_mode}" in texts or rc_in_mode == 4
    _set_param(link, "COM_RC_IN_MODE", 1)
    _stick(link)
    link.advance(ap.params["COM_RC_LOSS_T"] + 0.1)  # too old by now
    assert link.command_long(1, MavCmd.DO_SET_MODE, *POSCTL).result == MavResult.DENIED
    for main, label in ((1, "manual"), (5, "acro"), (7, "stabilized")):  # not flown
        _stick(link)
        since = len(link.received)
        assert link.command_long(1, MavCmd.DO_SET_MODE, 1, main, 0).result == MavResult.DENIED
        assert link.messages("STATUSTEXT", since=since)[-1].text == (
            f"Mode {label} refused: only posctl/altctl flown")
    assert ap.mode is FlightMode.HOLD


def test_out_of_range_axes_are_ignored_and_reported_once() -> None:
    link = MemoryLink(1, telemetry=False)
    link.arm_and_take_off(1, 10.0)
    ap = link.fleet.autopilots[0]
    _stick(link)
    assert link.command_long(1, MavCmd.DO_SET_MODE, *POSCTL).result == MavResult.ACCEPTED
    since = _stick(link, x=5000)
    _stick(link, x=5000)
    _stick(link, z=-200)
    texts = [m.text for m in link.messages("STATUSTEXT", since=since)]
    assert texts == ["Joystick x 5000 outside [-1000, 1000]: ignored",
                     "Joystick z -200 outside [0, 1000]: ignored"]
    assert ap.manual.sticks == (0.0, 0.0, 0.0, 0.0)
    # an invalid axis (INT16_MAX) reads as centred; input for another system is not ours
    _fly(link, 2.0, x=32767, y=32767, z=32767, r=32767)
    assert link.fleet.dyn.speed_m_s(0) < 0.05
    x0, y0, _ = ap.position_m
    for _ in range(20):
        _stick(link, x=1000, target=2)
        link.advance(0.05)
    x1, y1, _ = ap.position_m
    assert math.hypot(x1 - x0, y1 - y0) < 0.05 and ap.mode is FlightMode.RTL  # input lost

"""PX4 conformance through the real MAVSDK client (native binding) over UDP: the official
examples' offboard velocity-body circle, orbit, and multi-vehicle local frames, checked
against the ground truth."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from mavsdk.asyncio.plugins.action import ActionAsync
from mavsdk.asyncio.plugins.calibration import CalibrationAsync
from mavsdk.asyncio.plugins.ftp import FtpAsync
from mavsdk.asyncio.plugins.log_files import LogFilesAsync
from mavsdk.asyncio.plugins.offboard import OffboardAsync
from mavsdk.asyncio.plugins.telemetry import TelemetryAsync
from mavsdk.plugins.action import OrbitYawBehavior
from mavsdk.plugins.calibration import CalibrationResult
from mavsdk.plugins.log_files import LogFilesResult
from mavsdk.plugins.offboard import Attitude, PositionNedYaw, VelocityBodyYawspeed
from mavsdk.plugins.telemetry import FlightMode
from pyulog import ULog

from tests.mavsdk_helpers import eventually, first, geodetic, take_off, truth_pos

pytestmark = pytest.mark.mavsdk


def _rows_since(swarm, sysid: int, t0_s: float) -> np.ndarray:
    rows = swarm.recorder.trajectory(f"d{sysid}")
    return rows[rows[:, 0] >= t0_s]


async def test_velocity_body_with_yawspeed_flies_a_circle(swarm_factory, mavsdk_client) -> None:
    swarm = await swarm_factory(1, speed=5.0)
    async with mavsdk_client(swarm.ports.api_port, 1) as systems:
        system = systems[0]
        offboard, telemetry = OffboardAsync(system), TelemetryAsync(system)
        await take_off(swarm, system, 1, 8.0)
        # the official offboard_velocity_body example's circle: forward 5 m/s, 30 deg/s
        await offboard.set_velocity_body(VelocityBodyYawspeed(5.0, 0.0, 0.0, 30.0))
        await offboard.start()
        await first(telemetry.subscribe_flight_mode(), lambda m: m == FlightMode.OFFBOARD, 3.0,
                    "OFFBOARD mode")
        t_start = swarm.fleet.now_s
        await eventually(lambda: swarm.fleet.now_s > t_start + 16.0, 10.0, "16 s flown")
        rows = _rows_since(swarm, 1, t_start + 4.0)  # once on the circle
        turned = np.sum((np.diff(rows[:, 4]) + 180.0) % 360.0 - 180.0)
        assert turned / (rows[-1, 0] - rows[0, 0]) == pytest.approx(30.0, rel=0.03)
        xy = rows[:, 1:3]
        r = np.hypot(*(xy - xy.mean(axis=0)).T)
        assert r.mean() == pytest.approx(5.0 / math.radians(30.0), rel=0.05)
        assert np.ptp(r) < 0.1 * r.mean()  # setpoints stream in wall time: loaded machines jitter
        await offboard.stop()


async def test_do_orbit_is_a_circle_of_the_asked_radius(swarm_factory, mavsdk_client) -> None:
    swarm = await swarm_factory(1, speed=5.0)
    async with mavsdk_client(swarm.ports.api_port, 1) as systems:
        system = systems[0]
        action, telemetry = ActionAsync(system), TelemetryAsync(system)
        await take_off(swarm, system, 1, 10.0)
        cx, cy = 20.0, 10.0
        lat, lon, alt = geodetic(swarm, cx, cy, 12.0)
        await action.do_orbit(15.0, 3.0, OrbitYawBehavior.HOLD_FRONT_TO_CIRCLE_CENTER,
                              lat, lon, alt)
        await first(telemetry.subscribe_flight_mode(), lambda m: m == FlightMode.POSCTL, 3.0,
                    "orbit (POSCTL/ORBIT) mode")
        t0 = swarm.fleet.now_s
        await eventually(lambda: swarm.fleet.now_s > t0 + 45.0, 20.0, "45 s orbiting")
        rows = _rows_since(swarm, 1, t0 + 15.0)
        r = np.hypot(rows[:, 1] - cx, rows[:, 2] - cy)
        assert r.min() > 14.7 and r.max() < 15.3
        assert rows[:, 3] == pytest.approx(np.full(r.shape, 12.0), abs=0.2)
        angle = np.unwrap(np.arctan2(rows[:, 2] - cy, rows[:, 1] - cx))
        assert (angle[0] - angle[-1]) / (rows[-1, 0] - rows[0, 0]) == pytest.approx(
            3.0 / 15.0, rel=0.03)  # clockwise at 3 m/s
        await action.hold()
        await first(telemetry.subscribe_flight_mode(), lambda m: m == FlightMode.HOLD, 3.0,
                    "HOLD after the orbit")


async def test_each_vehicle_flies_its_own_local_frame(swarm_factory, mavsdk_client) -> None:
    swarm = await swarm_factory(3, speed=5.0)
    async with mavsdk_client(swarm.ports.api_port, 3) as systems:
        for sysid in (2, 3):
            await take_off(swarm, systems[sysid - 1], sysid, 6.0)
        for sysid in (2, 3):
            telemetry = TelemetryAsync(systems[sysid - 1])
            pv = await first(telemetry.subscribe_position_velocity_ned(), lambda v: True, 3.0,
                             "local position")
            assert math.hypot(pv.position.north_m, pv.position.east_m) < 0.2
            offboard = OffboardAsync(systems[sysid - 1])
            await offboard.set_position_ned(PositionNedYaw(12.0, 0.0, -8.0, 0.0))
            await offboard.start()
        aps = swarm.fleet.autopilots
        await eventually(lambda: math.dist(truth_pos(swarm, 2), (5.0, 12.0, 8.0)) < 0.5
                         and math.dist(truth_pos(swarm, 3), (10.0, 12.0, 8.0)) < 0.5, 10.0,
                         "each vehicle 12 m north of its own start")
        assert aps[1].mode.name == aps[2].mode.name == "OFFBOARD"


async def test_imu_rate_set_through_mavsdk(swarm_factory, mavsdk_client) -> None:
    swarm = await swarm_factory(1)
    async with mavsdk_client(swarm.ports.api_port, 1) as systems:
        telemetry = TelemetryAsync(systems[0])
        await telemetry.set_rate_imu(50.0)  # SET_MESSAGE_INTERVAL(HIGHRES_IMU)
        imu = await first(telemetry.subscribe_imu(), lambda m: True, 3.0, "an IMU reading")
        assert imu.acceleration_frd.down_m_s2 == pytest.approx(-9.80665, abs=1e-3)
        assert imu.magnetic_field_frd.forward_gauss == pytest.approx(0.21, abs=1e-3)
        assert swarm.streams.interval_s(0, 105) == pytest.approx(0.02)


async def test_offboard_attitude_example_flies(swarm_factory, mavsdk_client) -> None:
    swarm = await swarm_factory(1, speed=5.0)
    async with mavsdk_client(swarm.ports.api_port, 1) as systems:
        system = systems[0]
        action, offboard = ActionAsync(system), OffboardAsync(system)
        telemetry = TelemetryAsync(system)
        await action.arm()
        await offboard.set_attitude(Attitude(0.0, 0.0, 0.0, 0.0))
        await offboard.start()
        await first(telemetry.subscribe_flight_mode(), lambda m: m == FlightMode.OFFBOARD, 3.0,
                    "OFFBOARD mode")
        await offboard.set_attitude(Attitude(0.0, 0.0, 0.0, 0.7))  # climb
        await eventually(lambda: truth_pos(swarm, 1)[2] > 5.0, 10.0, "climbed 5 m")
        x0 = truth_pos(swarm, 1)[0]
        await offboard.set_attitude(Attitude(30.0, 0.0, 0.0, 0.5))  # roll right: east
        await eventually(lambda: truth_pos(swarm, 1)[0] > x0 + 10.0, 10.0, "10 m east")
        assert abs(truth_pos(swarm, 1)[1]) < 1.0
        await offboard.stop()


async def test_calibration_example_runs_to_the_end(swarm_factory, mavsdk_client) -> None:
    swarm = await swarm_factory(1)
    async with mavsdk_client(swarm.ports.api_port, 1) as systems:
        calibration = CalibrationAsync(systems[0])
        for calibrate in (calibration.calibrate_gyro, calibration.calibrate_accelerometer,
                          calibration.calibrate_magnetometer,
                          calibration.calibrate_level_horizon):
            updates = [u async for u in calibrate()]  # (result, progress data) until SUCCESS
            assert updates[-1][0] == CalibrationResult.SUCCESS, calibrate.__name__
            progress = [data.progress for _, data in updates if data.has_progress]
            assert progress and progress[-1] == pytest.approx(1.0), calibrate.__name__
        sensors = [e.data["sensor"] for e in swarm.recorder.events("d1", kinds="calibration")]
        assert sensors == ["gyro", "accel", "mag", "level"]


async def test_logfile_download_example(swarm_factory, mavsdk_client, tmp_path) -> None:
    swarm = await swarm_factory(1, speed=10.0)
    async with mavsdk_client(swarm.ports.api_port, 1) as systems:
        system = systems[0]
        action, telemetry = ActionAsync(system), TelemetryAsync(system)
        await take_off(swarm, system, 1, 5.0)
        await action.land()
        await first(telemetry.subscribe_armed(), lambda armed: not armed, 20.0, "disarmed")
        log_files = LogFilesAsync(system)
        entries = await log_files.get_entries()
        assert len(entries) == 1 and entries[0].size_bytes > 0
        path = tmp_path / "flight.ulg"
        updates = [u async for u in log_files.download_log_file(entries[0], str(path))]
        result, progress = updates[-1]  # (result, progress) until SUCCESS
        assert result == LogFilesResult.SUCCESS and progress.progress == pytest.approx(1.0)
        ulog = ULog(str(path))
        heights = -ulog.get_dataset("vehicle_local_position").data["z"]
        assert heights.max() == pytest.approx(5.0, abs=0.3)


async def test_ftp_lists_and_downloads(swarm_factory, mavsdk_client, tmp_path) -> None:
    swarm = await swarm_factory(1)
    async with mavsdk_client(swarm.ports.api_port, 1) as systems:
        ftp = FtpAsync(systems[0])
        listing = await ftp.list_directory("/metadata")
        sizes = {e.name: e.size_bytes for e in listing.entries}
        assert set(sizes) == {"component_general.json", "parameters.json"}
        for use_burst in (False, True):
            local = tmp_path / ("burst" if use_burst else "plain")
            local.mkdir()
            updates = [u async for u in ftp.download("/metadata/parameters.json", str(local),
                                                     use_burst)]
            assert updates, use_burst
            assert (local / "parameters.json").stat().st_size == sizes["parameters.json"]
            parameters = json.loads((local / "parameters.json").read_text())
            assert len(parameters["parameters"]) == len(swarm.fleet.autopilots[0].params)

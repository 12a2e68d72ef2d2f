"""PX4 conformance through the real MAVSDK client (native binding) over UDP: the geofence
and mission_import examples (fence plans and rally points uploaded, downloaded, enforced and
used by RTL), checked against the ground truth."""

from __future__ import annotations

import json
import math

import pytest
from mavsdk.asyncio.plugins.action import ActionAsync
from mavsdk.asyncio.plugins.geofence import GeofenceAsync
from mavsdk.asyncio.plugins.mission_raw import MissionRawAsync
from mavsdk.asyncio.plugins.offboard import OffboardAsync
from mavsdk.asyncio.plugins.telemetry import TelemetryAsync
from mavsdk.plugins.action import ActionError
from mavsdk.plugins.geofence import Circle, FenceType, GeofenceData, Point, Polygon
from mavsdk.plugins.offboard import VelocityNedYaw
from mavsdk.plugins.telemetry import FlightMode

from tests.mavsdk_helpers import eventually, first, geodetic, take_off, truth_pos

pytestmark = pytest.mark.mavsdk


def _point(swarm, x: float, y: float) -> Point:
    lat, lon, _ = geodetic(swarm, x, y, 0.0)
    return Point(lat, lon)


async def test_geofence_uploaded_downloaded_and_enforced(swarm_factory, mavsdk_client) -> None:
    swarm = await swarm_factory(1, speed=5.0)
    async with mavsdk_client(swarm.ports.api_port, 1) as systems:
        system = systems[0]
        geofence, action = GeofenceAsync(system), ActionAsync(system)
        telemetry, offboard = TelemetryAsync(system), OffboardAsync(system)
        square = [_point(swarm, x, y) for x, y in [(-40, -40), (40, -40), (40, 40), (-40, 40)]]
        keep_out = Circle(_point(swarm, 0.0, 25.0), 8.0, FenceType.EXCLUSION)
        await geofence.upload_geofence(GeofenceData([Polygon(square, FenceType.INCLUSION)],
                                                    [keep_out]))
        ap = swarm.fleet.autopilots[0]
        assert len(ap.geofence.fence.zones) == 2
        down = await geofence.download_geofence()
        assert [len(p.points) for p in down.polygons] == [4]
        assert [round(c.radius, 3) for c in down.circles] == [8.0]
        await take_off(swarm, system, 1, 10.0)
        lat, lon, alt = geodetic(swarm, 60.0, 0.0, 10.0)
        with pytest.raises(ActionError):
            await action.goto_location(lat, lon, alt, 0.0)
        # flown out east by velocity set-points: GF_ACTION 2 holds at the fence
        await offboard.set_velocity_ned(VelocityNedYaw(0.0, 4.0, 0.0, 90.0))
        await offboard.start()
        await first(telemetry.subscribe_flight_mode(), lambda m: m == FlightMode.HOLD, 20.0,
                    "HOLD at the geofence")
        events = swarm.recorder.events("d1", kinds="failsafe")
        assert [e.data["reason"] for e in events] == ["geofence"]
        assert events[0].data["position_m"][0] == pytest.approx(40.0, abs=0.3)
        await geofence.clear_geofence()
        await eventually(lambda: not ap.geofence.fenced, 3.0, "fence cleared")


QGC_PLAN = {
    "fileType": "Plan", "version": 1, "groundStation": "QGroundControl",
    "mission": {"version": 2, "firmwareType": 12, "vehicleType": 2, "cruiseSpeed": 15,
                "hoverSpeed": 5, "plannedHomePosition": None, "items": []},
    "geoFence": {"version": 2, "circles": [], "polygons": []},
    "rallyPoints": {"version": 2, "points": []},
}


def _qgc_plan(swarm) -> str:
    """A QGroundControl plan: one waypoint, a keep-out circle and two rally points."""
    plan = json.loads(json.dumps(QGC_PLAN))
    home = list(geodetic(swarm, 0.0, 0.0, 0.0))
    plan["mission"]["plannedHomePosition"] = home
    lat, lon, _ = geodetic(swarm, 60.0, 40.0, 0.0)
    plan["mission"]["items"] = [{
        "type": "SimpleItem", "autoContinue": True, "command": 16, "doJumpId": 1, "frame": 3,
        "params": [0, 0, 0, None, lat, lon, 15], "Altitude": 15, "AltitudeMode": 1,
        "AMSLAltAboveTerrain": None}]
    clat, clon, _ = geodetic(swarm, -100.0, -100.0, 0.0)
    plan["geoFence"]["circles"] = [{"circle": {"center": [clat, clon], "radius": 20},
                                    "inclusion": False, "version": 1}]
    plan["rallyPoints"]["points"] = [list(geodetic(swarm, 90.0, 50.0, 20.0)),
                                     list(geodetic(swarm, -200.0, 0.0, 20.0))]
    return json.dumps(plan)


async def test_mission_import_rally_points_used_by_rtl(swarm_factory, mavsdk_client) -> None:
    swarm = await swarm_factory(1, speed=10.0)
    async with mavsdk_client(swarm.ports.api_port, 1) as systems:
        system = systems[0]
        mission_raw, action = MissionRawAsync(system), ActionAsync(system)
        imported = await mission_raw.import_qgroundcontrol_mission_from_string(_qgc_plan(swarm))
        await mission_raw.upload_mission(imported.mission_items)
        await mission_raw.upload_geofence(imported.geofence_items)
        await mission_raw.upload_rally_points(imported.rally_items)
        ap = swarm.fleet.autopilots[0]
        assert len(ap.geofence.rally_m) == 2 and len(ap.geofence.fence.zones) == 1
        assert len(await mission_raw.download_rallypoints()) == 2
        assert len(await mission_raw.download_geofence()) == 1
        await take_off(swarm, system, 1, 10.0)
        await mission_raw.start_mission()
        await eventually(lambda: math.hypot(truth_pos(swarm, 1)[0] - 60.0,
                                            truth_pos(swarm, 1)[1] - 40.0) < 1.0, 20.0,
                         "the waypoint reached")
        await action.return_to_launch()
        await eventually(lambda: not ap.in_air, 30.0, "landed")
        x, y, _ = truth_pos(swarm, 1)
        assert math.hypot(x - 90.0, y - 50.0) < 0.5  # the closest rally point, not home

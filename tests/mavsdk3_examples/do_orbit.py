"""A do_orbit script in the style of MAVSDK-Python 3.x's examples (the gRPC client, with the
mavsdk_server it bundles), run by tests/test_mavsdk3_examples.py with .venv-mavsdk3's Python.

    do_orbit.py UDP_PORT GRPC_PORT

Connects, waits for a global position and home, arms, takes off, orbits 10 m around a point
20 m north of home at 2 m/s facing the centre, returns to launch and waits until landed.
"""

import asyncio
import sys

from mavsdk import System
from mavsdk.action import OrbitYawBehavior

METRES_PER_DEG_LAT = 111_320.0


async def run(udp_port: int, grpc_port: int) -> None:
    drone = System(port=grpc_port)
    await drone.connect(system_address=f"udp://:{udp_port}")

    print("Waiting for drone to connect...")
    async for state in drone.core.connection_state():
        if state.is_connected:
            print("-- Connected to drone!")
            break

    print("Waiting for drone to have a global position estimate...")
    async for health in drone.telemetry.health():
        if health.is_global_position_ok and health.is_home_position_ok:
            print("-- Global position estimate OK")
            break

    home = await drone.telemetry.home().__aiter__().__anext__()
    print("-- Arming")
    await drone.action.arm()
    print("-- Taking off")
    await drone.action.takeoff()
    async for in_air in drone.telemetry.in_air():
        if in_air:
            break
    await asyncio.sleep(2)

    print("-- Orbiting")
    await drone.action.do_orbit(
        radius_m=10.0, velocity_ms=2.0,
        yaw_behavior=OrbitYawBehavior.HOLD_FRONT_TO_CIRCLE_CENTER,
        latitude_deg=home.latitude_deg + 20.0 / METRES_PER_DEG_LAT,
        longitude_deg=home.longitude_deg,
        absolute_altitude_m=home.absolute_altitude_m + 10.0)
    await asyncio.sleep(4)

    print("-- Returning to launch")
    await drone.action.return_to_launch()
    async for in_air in drone.telemetry.in_air():
        if not in_air:
            print("-- Landed")
            break


if __name__ == "__main__":
    asyncio.run(asyncio.wait_for(run(int(sys.argv[1]), int(sys.argv[2])), timeout=60.0))

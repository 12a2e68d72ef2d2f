"""Flight primitives: each becomes MAVLink traffic and waits for its outcome.

Flight uses MAVLink the way a ground station does: takeoff, reposition (goto), missions for
paths and timed hovers (progress from MISSION_ITEM_REACHED), land, RTL, DO_SET_HOME and camera
capture. Preconditions are checked before anything is sent, so a refused primitive changes
nothing. Two primitives for the same drone are never interleaved: the second is refused with
a message saying what the drone is busy with. Every primitive ends, at the latest when its
simulated-time budget runs out.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from mavsdk.asyncio.plugins.mission_raw import MissionItem

from mavlink_gateway import effects
from mavlink_gateway.core import GatewayCore, Refusal, _number, _short
from mavlink_gateway.drone_link import PERIODIC, DroneLink
from mavlink_gateway.interfaces import wrap_heading_deg
from mavlink_gateway.outcomes import Outcome, Status
from mavlink_vocabulary import FlightState, MavCmd, MavFrame

__all__ = ["FlightPrimitives"]

ARRIVAL_M = 1.0
# MAVSDK's mission items take plain ints
FRAME_RELATIVE_ALT = int(MavFrame.GLOBAL_RELATIVE_ALT_INT)
NAV_WAYPOINT, NAV_LOITER_TIME = int(MavCmd.NAV_WAYPOINT), int(MavCmd.NAV_LOITER_TIME)
CRUISE_M_S = 5.0  # a conservative speed for time budgets
MAX_WAYPOINTS = 100
MAX_HOVER_S = 3600.0
MISSION_STATE_COMPLETE = 5  # MAVLink MISSION_STATE_COMPLETE, in MISSION_CURRENT.mission_state


def _fmt(p: Sequence[float]) -> str:
    return "(" + ", ".join(f"{v:.1f}" for v in p) + ")"


class FlightPrimitives(GatewayCore):
    """Take-off, moves, paths, hovers, landing and return home (see the module docstring)."""

    # ------------------------------------------------------------ flight
    async def take_off(self, drone: str, altitude_m: float) -> Outcome:
        async def body(link: DroneLink) -> Outcome:
            altitude = self._altitude(link, altitude_m)
            if link.flight_state != FlightState.ON_GROUND:
                raise Refusal(f"drone {link.drone_id} is already in the air")
            if link.battery_pct < 10.0:
                raise Refusal(f"battery {link.battery_pct:.0f}% is too low to take off")
            x, y, _ = link.position_m or (0.0, 0.0, 0.0)
            texts = len(link.status_texts)
            await self._mavsdk(link, "the takeoff altitude",
                               lambda: link.action.set_takeoff_altitude(altitude))
            await self._mavsdk(link, "arming", lambda: link.action.arm(), effects.armed)
            await self._mavsdk(link, "takeoff", lambda: link.action.takeoff(), effects.in_air)
            home_z = link.home_m[2] if link.home_m else 0.0
            target = (x, y, home_z + altitude)

            def done() -> Outcome | None:
                # Armed comes with the 1 Hz heartbeat, position at 10 Hz: without waiting for
                # it the state reported could be "hovering" and "disarmed" at once.
                if link.flight_state == FlightState.HOVERING and link.armed and \
                        self._arrived(link, target, ARRIVAL_M):
                    return Outcome(Status.OK, f"{link.drone_id} took off to {altitude:.1f} m",
                                   link.state())
                return None

            return await self._wait(link, altitude / 1.0 + 30.0, "take_off", done,
                                    texts_from=texts)

        return await self._run("take_off", drone, body)

    async def land(self, drone: str, *, replace: bool = False) -> Outcome:
        """Land where the drone is. `replace`: interrupt the running primitive (as `hold`
        does) instead of being refused while the drone is busy."""
        async def body(link: DroneLink) -> Outcome:
            self._require_air(link)
            height = link.state().altitude_m
            texts = len(link.status_texts)
            await self._mavsdk(link, "landing", lambda: link.action.land(), effects.landing)

            def done() -> Outcome | None:
                if self._landed(link):
                    x, y, _ = link.position_m or (math.nan,) * 3
                    return Outcome(Status.OK, f"{link.drone_id} landed at ({x:.1f}, {y:.1f})",
                                   link.state())
                return None

            return await self._wait(link, height / 0.5 + 30.0, "land", done, texts_from=texts)

        return await self._run("land", drone, body, replace=replace)

    async def _goto(self, link: DroneLink, target: tuple[float, float, float], what: str,
                    yaw_deg: float = math.nan) -> Outcome:
        x, y, z = target
        self._coordinate("x", x)
        self._coordinate("y", y)
        self._altitude(link, z, "z")
        home = link.home_m or (0.0, 0.0, 0.0)
        if math.hypot(x - home[0], y - home[1]) > 10_000.0:
            raise Refusal(f"({x:.0f}, {y:.0f}) is more than 10 km from home")
        start = link.position_m or target
        lat, lon, alt = link.geodetic(x, y, home[2] + z)
        # Home's altitude arrives in whole millimetres, then as float32 (HOME_POSITION or
        # the GPS origin): the same home can differ by 3e-5 m. A millimetre altitude makes
        # the same command of the same move on every run.
        alt = round(alt, 3)
        texts = len(link.status_texts)
        await self._mavsdk(link, what, lambda: link.action.goto_location(lat, lon, alt, yaw_deg))
        goal = (x, y, home[2] + z)

        def done() -> Outcome | None:
            if not self._arrived(link, goal, ARRIVAL_M):
                return None
            if math.isfinite(yaw_deg) and abs((link.heading_deg - yaw_deg + 180) % 360 - 180) > 2:
                return None
            return Outcome(Status.OK, f"{link.drone_id} reached {_fmt(target)}", link.state())

        budget = math.dist(start, goal) / CRUISE_M_S * 2.0 + 30.0
        return await self._wait(link, budget, what, done, texts_from=texts)

    async def move_to(self, drone: str, x: float, y: float, z: float, *,
                      replace: bool = False) -> Outcome:
        """Fly to (x, y) at altitude z. `replace`: interrupt the running primitive (as `hold`
        does) instead of being refused while the drone is busy (a ground station's Go-to)."""
        async def body(link: DroneLink) -> Outcome:
            self._require_air(link)
            target = (self._coordinate("x", x), self._coordinate("y", y), _number("z", z))
            return await self._goto(link, target, "move_to")

        return await self._run("move_to", drone, body, replace=replace)

    async def move_towards(self, drone: str, heading_deg: float, distance_m: float,
                           dz_m: float = 0.0) -> Outcome:
        async def body(link: DroneLink) -> Outcome:
            self._require_air(link)
            heading = math.radians(_number("heading_deg", heading_deg))
            distance = _number("distance_m", distance_m)
            if not 0.0 < distance <= 10_000.0:
                raise Refusal(f"distance_m must be within (0, 10000], got {distance:g}")
            x, y, _ = link.position_m or (0.0, 0.0, 0.0)
            z = link.state().altitude_m + _number("dz_m", dz_m)
            target = (x + distance * math.sin(heading), y + distance * math.cos(heading), z)
            return await self._goto(link, target, "move_towards")

        return await self._run("move_towards", drone, body)

    async def change_altitude(self, drone: str, altitude_m: float) -> Outcome:
        async def body(link: DroneLink) -> Outcome:
            self._require_air(link)
            altitude = self._altitude(link, altitude_m)
            x, y, _ = link.position_m or (0.0, 0.0, 0.0)
            return await self._goto(link, (x, y, altitude), "change_altitude")

        return await self._run("change_altitude", drone, body)

    async def rotate(self, drone: str, heading_deg: float) -> Outcome:
        async def body(link: DroneLink) -> Outcome:
            self._require_air(link)
            heading = wrap_heading_deg(_number("heading_deg", heading_deg))
            x, y, _ = link.position_m or (0.0, 0.0, 0.0)
            outcome = await self._goto(link, (x, y, link.state().altitude_m), "rotate", heading)
            if outcome.ok:
                return Outcome(Status.OK, f"{link.drone_id} now heads {heading:.0f} deg",
                               outcome.state)
            return outcome

        return await self._run("rotate", drone, body)

    async def hold(self, drone: str) -> Outcome:
        """Interrupt whatever the drone is doing (a move, a mission, the take-off climb,
        return home, a landing) and hover where it is (HOLD mode). The interrupted primitive
        ends with Status.INTERRUPTED. On the ground with nothing running: nothing to do."""
        async def body(link: DroneLink) -> Outcome:
            interrupted = self._replaced.get(link.drone_id)
            data = {"interrupted": interrupted}
            if interrupted is None:
                if link.flight_state == FlightState.ON_GROUND:
                    return Outcome(Status.OK, f"{link.drone_id} is on the ground: nothing to "
                                   "hold", link.state(), data)
                await self._mavsdk(link, "hold", link.action.hold, effects.holding)
            await self._show_mode(link, "HOLD")
            x, y, z = link.position_m or (math.nan,) * 3
            ended = f"; {interrupted} interrupted" if interrupted else ""
            return Outcome(Status.OK, f"{link.drone_id} holds at {_fmt((x, y, z))}{ended}",
                           link.state(), data)

        return await self._run("hold", drone, body, replace=True)

    async def return_home(self, drone: str) -> Outcome:
        async def body(link: DroneLink) -> Outcome:
            self._require_air(link)
            start = link.position_m or (0.0, 0.0, 0.0)
            home = link.home_m or (0.0, 0.0, 0.0)
            texts = len(link.status_texts)
            await self._mavsdk(link, "return to launch", lambda: link.action.return_to_launch(),
                               effects.returning)

            def done() -> Outcome | None:
                if self._landed(link):
                    return Outcome(Status.OK, f"{link.drone_id} returned home and landed at "
                                   f"({home[0]:.1f}, {home[1]:.1f})", link.state())
                return None

            budget = math.dist(start, home) / CRUISE_M_S * 2.0 + 120.0
            return await self._wait(link, budget, "return_home", done, texts_from=texts)

        return await self._run("return_home", drone, body)

    async def set_home(self, drone: str) -> Outcome:
        async def body(link: DroneLink) -> Outcome:
            x, y, _ = link.position_m or (0.0, 0.0, 0.0)
            await self._mavsdk(link, "set home", lambda: link.action.set_home(True, 0.0, 0.0, 0.0))

            def done() -> Outcome | None:
                home = link.home_m
                if home is not None and math.hypot(home[0] - x, home[1] - y) < 0.5:
                    return Outcome(Status.OK, f"{link.drone_id} home set to ({x:.1f}, {y:.1f})",
                                   link.state())
                return None

            return await self._wait(link, 5.0, "set_home", done, watch_obstacles=False,
                                    instant=True)

        return await self._run("set_home", drone, body)

    # ----------------------------------------------------------- missions
    async def _fly_mission(self, link: DroneLink, items: list[MissionItem], what: str,
                           budget_s: float, goal: tuple[float, float, float]) -> Outcome:
        texts = len(link.status_texts)
        await self._mavsdk(link, f"the {what} mission", lambda: link.mission.upload_mission(items),
                           repeatable=True)  # the same plan again
        link.mission_progress = (0, len(items))
        await self._mavsdk(link, f"the {what} mission start", lambda: link.mission.start_mission())
        total = len(items)
        states_mark = link.seen.get("mission_current", 0)

        async def done() -> Outcome | None:
            if not self._arrived(link, goal, ARRIVAL_M):
                return None
            # MISSION_CURRENT (periodic) says the mission is complete even when the one
            # MISSION_ITEM_REACHED of its last item was lost on the way.
            if link.seen.get("mission_current", 0) > states_mark and \
                    link.mission_state == (total, MISSION_STATE_COMPLETE):
                return Outcome(Status.OK, "", link.state())
            # A lockstep wait asks only where the clock stopped, so it asks MAVSDK directly;
            # otherwise the progress stream says when asking is worth it (a progress update
            # dropped under load then only delays the answer).
            current, reported = link.mission_progress
            near_end = self.services.lockstep or (reported == total and current >= total - 1)
            if near_end and await link.mission.is_mission_finished():
                return Outcome(Status.OK, "", link.state())
            return None

        # Once the budget has run out, a MISSION_CURRENT sent after it also tells whether the
        # mission ended (its MISSION_ITEM_REACHED and progress may have been lost).
        return await self._wait(link, budget_s, what, done, texts_from=texts,
                                fresh=(*PERIODIC, "mission_current"))

    async def move_along_path(self, drone: str, waypoints: Sequence[Sequence[float]]
                              ) -> Outcome:
        async def body(link: DroneLink) -> Outcome:
            self._require_air(link)
            if not isinstance(waypoints, Sequence) or not 1 <= len(waypoints) <= MAX_WAYPOINTS:
                raise Refusal(f"waypoints must be a list of 1 to {MAX_WAYPOINTS} points")
            start_alt = round(link.state().altitude_m, 3)  # mm: see _goto
            points: list[tuple[float, float, float]] = []
            for i, wp in enumerate(waypoints):
                if not isinstance(wp, Sequence) or len(wp) not in (2, 3):
                    raise Refusal(f"waypoint {i + 1} must be [x, y] or [x, y, z], got {_short(wp)}")
                z = self._altitude(link, wp[2], f"waypoint {i + 1} z") if len(wp) == 3 \
                    else start_alt
                points.append((self._coordinate(f"waypoint {i + 1} x", wp[0]),
                               self._coordinate(f"waypoint {i + 1} y", wp[1]), z))
            home = link.home_m or (0.0, 0.0, 0.0)
            items = []
            for seq, (x, y, z) in enumerate(points):
                lat, lon, _ = link.geodetic(x, y, 0.0)
                items.append(MissionItem(seq, FRAME_RELATIVE_ALT, NAV_WAYPOINT, int(seq == 0), 1,
                                         0.0, 0.0, 0.0, math.nan, round(lat * 1e7),
                                         round(lon * 1e7), z, 0))
            start = link.position_m or points[0]
            length = sum(math.dist(a, b) for a, b in zip([start, *points], points, strict=False))
            goal = (points[-1][0], points[-1][1], home[2] + points[-1][2])
            outcome = await self._fly_mission(link, items, "move_along_path",
                                              length / CRUISE_M_S * 2.0 + 30.0, goal)
            if outcome.ok:
                return Outcome(Status.OK, f"{link.drone_id} completed a path of {len(points)} "
                               f"waypoints ({length:.0f} m)", outcome.state)
            reached = min(link.mission_progress[0], len(points))
            if outcome.status is Status.BLOCKED and reached > 0:
                return Outcome(Status.PARTIAL, f"reached {reached} of {len(points)} waypoints; "
                               f"{outcome.message}", outcome.state, {"reached": reached})
            return outcome

        return await self._run("move_along_path", drone, body)

    async def hover(self, drone: str, duration_s: float) -> Outcome:
        async def body(link: DroneLink) -> Outcome:
            self._require_air(link)
            duration = _number("duration_s", duration_s)
            if not 0.0 < duration <= MAX_HOVER_S:
                raise Refusal(f"duration_s must be within (0, {MAX_HOVER_S:g}], got {duration:g}")
            x, y, z = link.position_m or (0.0, 0.0, 0.0)
            altitude = round(link.state().altitude_m, 3)  # mm: see _goto
            item = MissionItem(0, FRAME_RELATIVE_ALT, NAV_LOITER_TIME, 1, 1, duration, 0.0, 0.0,
                               math.nan, 0, 0, altitude, 0)
            outcome = await self._fly_mission(link, [item], "hover", duration + 30.0, (x, y, z))
            if outcome.ok:
                return Outcome(Status.OK, f"{link.drone_id} hovered {duration:g} s at "
                               f"{_fmt((x, y, altitude))}", outcome.state)
            return outcome

        return await self._run("hover", drone, body)

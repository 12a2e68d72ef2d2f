"""One vehicle's fence and rally plans: stored, enforced in flight and at arming, and used by
RTL (emulator.flight.geofence has the geometry and the parsing)."""

from __future__ import annotations

import math

from emulator.flight.geofence import Fence, parse_fence, parse_rally
from emulator.flight.mission import MissionItem
from emulator.flight.refusal import CommandRefused
from emulator.flight.vehicle_control import VehicleControl
from emulator.truth_events import TruthEventKind
from mavlink_vocabulary import GeofenceAction, GeofenceBreached

__all__ = ["GF_ACTION_NONE", "GeofencePlans"]

GF_ACTION_NONE, GF_ACTION_WARN, GF_ACTION_HOLD, GF_ACTION_RTL = 0, 1, 2, 3
GF_ACTION_TERMINATE, GF_ACTION_LAND = 4, 5
Vec3 = tuple[float, float, float]


class GeofencePlans:
    """The fence and rally plans of one vehicle (items as uploaded, and parsed)."""

    def __init__(self, autopilot: VehicleControl) -> None:
        self.ap = autopilot
        self.fence_items: tuple[MissionItem, ...] = ()
        self.rally_items: tuple[MissionItem, ...] = ()
        self.fence = Fence()
        self.rally_m: tuple[Vec3, ...] = ()
        self.breached = False

    @property
    def fenced(self) -> bool:
        return bool(self.fence.zones)

    def set_fence(self, items: list[MissionItem]) -> None:
        """Replace the fence plan (all or nothing: CommandRefused if malformed)."""
        fence = parse_fence(items, self.ap.fleet.world.origin)
        self.fence_items, self.fence, self.breached = tuple(items), fence, False
        self.ap.fleet.fence_changed()

    def set_rally(self, items: list[MissionItem]) -> None:
        """Replace the rally points (all or nothing: CommandRefused if malformed)."""
        self.rally_m = parse_rally(items, self.ap.fleet.world.origin, self.ap.state.home_m)
        self.rally_items = tuple(items)

    def contains(self, x_m: float, y_m: float) -> bool:
        return self.fence.contains(x_m, y_m)

    def check_target(self, target_m: Vec3, what: str) -> None:
        """Refuse a destination outside the fence plan (as PX4 refuses such a reposition)."""
        if self.fenced and not self.fence.contains(target_m[0], target_m[1]):
            raise CommandRefused(f"{what} refused: outside the geofence")

    def check_mission(self, items: list[MissionItem]) -> None:
        """Refuse a mission with a position item outside the fence plan (PX4's feasibility
        check at upload)."""
        if not self.fenced:
            return
        ap = self.ap
        origin, home = ap.fleet.world.origin, ap.state.home_m
        for item in items:
            if item.is_nav and not item.uses_current_position:
                x, y, _ = item.local_target_m(origin, home, home)
                if not self.fence.contains(x, y):
                    raise CommandRefused(f"Mission item {item.seq} outside the geofence")

    def check_arming(self) -> None:
        ap = self.ap
        x, y, _ = ap.position_m
        if (self.fenced and ap.params["GF_ACTION"] != GF_ACTION_NONE
                and not self.fence.contains(x, y)):
            raise CommandRefused("Arming denied: vehicle outside the geofence")

    def rtl_destination_m(self) -> Vec3:
        """Home or the closest rally point, whichever is closer (PX4's RTL_TYPE 0)."""
        home = self.ap.state.home_m
        if not self.rally_m:
            return home
        x, y, _ = self.ap.position_m
        return min((home, *self.rally_m), key=lambda p: math.hypot(p[0] - x, p[1] - y))

    def check(self) -> None:
        """In flight, every physics step while a fence exists: act once per breach."""
        ap = self.ap
        x, y, z = ap.position_m
        inside = self.fence.contains(x, y)
        if inside or self.breached:
            self.breached = not inside
            return
        self.breached = True
        action = int(ap.params["GF_ACTION"])
        if action == GF_ACTION_NONE:
            return
        ap.event(TruthEventKind.FAILSAFE, reason="geofence", action=action, position_m=[x, y, z])
        if action == GF_ACTION_WARN:
            ap.announce(GeofenceBreached(GeofenceAction.WARN))
        elif action == GF_ACTION_HOLD:
            ap.announce(GeofenceBreached(GeofenceAction.HOLD))
            ap.hold()
        elif action == GF_ACTION_RTL:
            ap.announce(GeofenceBreached(GeofenceAction.RETURN))
            ap.start_rtl()
        elif action == GF_ACTION_TERMINATE:
            ap.announce(GeofenceBreached(GeofenceAction.TERMINATE))
            ap.disarm(force=True)
        else:
            ap.announce(GeofenceBreached(GeofenceAction.LAND))
            ap.start_land(None)

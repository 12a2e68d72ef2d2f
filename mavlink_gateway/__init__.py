"""mavlink_gateway: tool-call primitives over MAVSDK, with per-drone perception."""

from mavlink_gateway.drone_link import DroneLink, DroneProfile
from mavlink_gateway.fleet import FleetConnection, FleetError
from mavlink_gateway.gateway import Gateway, profiles_from_scenario
from mavlink_gateway.interfaces import FleetSpec, GeoFrame, Services
from mavlink_gateway.mavsdk_log import mavsdk_log_enabled, set_mavsdk_log
from mavlink_gateway.outcomes import DroneState, Outcome, Status

__all__ = [
    "DroneLink",
    "DroneProfile",
    "DroneState",
    "FleetConnection",
    "FleetError",
    "FleetSpec",
    "Gateway",
    "GeoFrame",
    "Outcome",
    "Services",
    "Status",
    "mavsdk_log_enabled",
    "profiles_from_scenario",
    "set_mavsdk_log",
]

"""The bus on the command line: `--mqtt URL` for `mavswarm up`, `serve` and `bench run`, and
`mavswarm mqtt-bridge`."""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import functools
import sys
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

from mqtt_bus.session_bus import SessionBus
from mqtt_bus.topics import check_segment
from mqtt_bus.url import BrokerUrl, parse_broker_url

__all__ = ["add_mqtt_arguments", "add_parsers", "extend_up", "mqtt_options"]

SITL_ORIGIN = (47.397742, 8.545594, 488.0)  # PX4 SITL's default home (Zurich)


def add_mqtt_arguments(parser: argparse.ArgumentParser, *, session: bool = True) -> None:
    """--mqtt URL [--mqtt-osd-hz HZ] [--mqtt-session NAME] on a command's parser."""
    parser.add_argument("--mqtt", metavar="URL", default=None,
                        help="publish on an MQTT broker: mqtt://[user:pass@]host[:port]"
                             "[/prefix] (TLS: mqtts://..., ?ca=FILE); see docs/mqtt.md")
    parser.add_argument("--mqtt-osd-hz", type=float, default=2.0, metavar="HZ",
                        help="--mqtt: telemetry (osd) rate per drone, wall-clock Hz "
                             "(default 2)")
    if session:
        parser.add_argument("--mqtt-session", default=None, metavar="NAME",
                            help="--mqtt: the session level of the topics (default: the "
                                 "session's id, or 'swarm')")


def mqtt_options(args: argparse.Namespace) -> BrokerUrl | None:
    """The parsed --mqtt URL (None without one); ValueError on a bad URL or rate."""
    if getattr(args, "mqtt", None) is None:
        return None
    url = parse_broker_url(args.mqtt)
    if not 0.0 < args.mqtt_osd_hz <= 50.0:
        raise ValueError(f"--mqtt-osd-hz {args.mqtt_osd_hz:g} outside (0, 50]")
    name = getattr(args, "mqtt_session", None)
    if name is not None:
        check_segment(name, "--mqtt-session")
    return url


# ---------------------------------------------------------------------- up
def extend_up(sub: argparse._SubParsersAction) -> None:
    """Give `mavswarm up` (on the `mavswarm` command's subparsers) the --mqtt options."""
    up = sub.choices["up"]
    add_mqtt_arguments(up)
    up.set_defaults(run=_run_up)


def _run_up(args: argparse.Namespace) -> int:
    from emulator import cli as emulator_cli
    try:
        url = mqtt_options(args)
    except ValueError as error:
        print(f"mavswarm: {error}", file=sys.stderr)
        return 2
    if url is not None:
        base = args.mqtt_session or (args.session.stem if args.session else "swarm")
        args.attachments = [*getattr(args, "attachments", ()), functools.partial(
            _up_bus, url, base if _ok(base) else "swarm", args.mqtt_osd_hz,
            not args.per_vehicle_ports)]
    return emulator_cli.run_up(args)


def _ok(name: str) -> bool:
    try:
        check_segment(name, "session")
    except ValueError:
        return False
    return True


@contextlib.asynccontextmanager
async def _up_bus(url: BrokerUrl, base: str, osd_hz: float, commands: bool, swarm: Any,
                  network: int | None) -> AsyncIterator[SessionBus]:
    from mqtt_bus.swarm_bus import swarm_session_bus
    session = base if network is None else f"{base}-net{network}"
    async with swarm_session_bus(url, session, swarm, osd_hz=osd_hz,
                                 commands=commands) as bus:
        print(f"MQTT: {url.redacted()} topics {bus.topics.base}/... "
              f"(osd {osd_hz:g} Hz{', commands on services' if commands else ''})",
              flush=True)
        try:
            yield bus
        finally:
            print(bus.report(), flush=True)


# ------------------------------------------------------------------ bridge
def add_parsers(sub: argparse._SubParsersAction) -> None:
    """`mqtt-bridge`, on the `mavswarm` command's subparsers."""
    bridge = sub.add_parser(
        "mqtt-bridge", help="put any MAVLink fleet on an MQTT broker (through the gateway)",
        description="Put a MAVLink fleet (PX4 SITL, real vehicles, a mavswarm swarm) on the "
                    "MQTT bus: telemetry, state, events, status and commands.")
    bridge.add_argument("--mavlink", required=True, metavar="CONNECTION",
                        help="MAVSDK connection, e.g. udpin://0.0.0.0:14540")
    bridge.add_argument("--drones", type=int, default=None,
                        help="systems 1..N as d1..dN (default 1; or --session)")
    bridge.add_argument("--session", type=Path, default=None, metavar="FILE",
                        help="a session file naming the fleet's drones and origin")
    bridge.add_argument("--origin", default=None, metavar="LAT,LON,ALT",
                        help="the local frame's origin (default: the session's, else PX4 "
                             "SITL's home)")
    bridge.add_argument("--no-commands", action="store_true",
                        help="publish only; do not subscribe to services topics")
    bridge.add_argument("--timeout", type=float, default=30.0,
                        help="seconds to wait for every drone to appear")
    add_mqtt_arguments(bridge)
    bridge.set_defaults(run=run_bridge_command)


def _origin(text: str) -> Any:
    from emulator.geo import GeoOrigin
    try:
        lat, lon, alt = (float(v) for v in text.split(","))
    except ValueError:
        raise ValueError(f"--origin {text!r}: expected LAT,LON,ALT in degrees and metres") \
            from None
    return GeoOrigin(lat, lon, alt)


def run_bridge_command(args: argparse.Namespace) -> int:
    """Run a parsed `mavswarm mqtt-bridge` until interrupted."""
    from emulator.geo import GeoOrigin
    from emulator.scenario import ScenarioError, load_scenario
    from mavlink_gateway import FleetError, profiles_from_scenario
    from mqtt_bus.bridge import run_bridge, sitl_profiles
    try:
        url = mqtt_options(args)
        if url is None:
            raise ValueError("mqtt-bridge needs --mqtt URL")
        if args.session is not None:
            if args.drones is not None:
                raise ValueError("give --session or --drones, not both")
            scenario = load_scenario(args.session)
            profiles = profiles_from_scenario(scenario)
            origin = scenario.world.origin
            name = args.mqtt_session or Path(args.session).stem
        else:
            profiles = sitl_profiles(args.drones if args.drones is not None else 1)
            origin = GeoOrigin(*SITL_ORIGIN)
            name = args.mqtt_session or "fleet"
        if args.origin is not None:
            origin = _origin(args.origin)
        session = name if _ok(name) else "fleet"
        asyncio.run(run_bridge(url, args.mavlink, profiles, origin, session,
                               osd_hz=args.mqtt_osd_hz, commands=not args.no_commands,
                               timeout_s=args.timeout))
    except (ValueError, ScenarioError, FleetError, OSError) as error:
        print(f"mavswarm: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130
    return 0

"""Camera, charging, messages, perception and the operator's resets."""

from __future__ import annotations

import json
from typing import Any

from mavsdk.plugins.mavlink_direct import MavlinkMessage

from mavlink_gateway import effects
from mavlink_gateway.core import Refusal, _number
from mavlink_gateway.drone_link import DroneLink
from mavlink_gateway.flight import FlightPrimitives
from mavlink_gateway.interfaces import Sensed, SensedWorld
from mavlink_gateway.lockstep_wait import wait_instant, wait_world
from mavlink_gateway.outcomes import Outcome, Status
from mavlink_vocabulary import FlightState, MavCmd, MavComponent, MavResult

__all__ = ["PayloadPrimitives", "perception_dict"]

CHARGING_KIND = "waypoint"  # charging stations are the session's waypoint targets
# Telemetry carries the battery in whole percent, truncated: 99 means 99 to 100, and a drone
# resting on a station at 99.9 % charges no further (a lockstep wait for 99.5 never ended).
FULL_PCT = 99.0
MAX_WAIT_S = 3600.0
PHOTO_TRIES = 4
PHOTO_REPORT_WALL_S = 0.6  # wall time a capture report may take before it is asked again

MAV_RESULTS = {MavResult.TEMPORARILY_REJECTED: "temporarily rejected", MavResult.DENIED: "denied",
               MavResult.UNSUPPORTED: "unsupported", MavResult.FAILED: "failed"}


def _entity(e: Sensed) -> dict[str, Any]:
    return {"id": e.id, "kind": e.kind, "distance_m": round(e.distance_m, 1),
            "position": [round(v, 1) for v in e.position_m]}


def perception_dict(p: SensedWorld) -> dict[str, Any]:
    """What one drone senses, as plain data (never more than its sensor reports)."""
    return {"targets": [_entity(e) for e in p.targets],
            "obstacles": [_entity(e) for e in p.obstacles],
            "drones": [_entity(e) for e in p.vehicles]}


class PayloadPrimitives(FlightPrimitives):
    """Primitives that use the camera, the charger (flying to a station first), the radio and
    the sensor feed."""

    async def take_photo(self, drone: str) -> Outcome:
        async def body(link: DroneLink) -> Outcome:
            self._require_air(link)
            before = len(link.captures)
            # One capture sequence number per photo: a repeat of the command (its ACK or the
            # capture report was lost) takes no second photo, and the camera reports the
            # photo again (emulator.mavlink.camera).
            link.capture_sequence += 1
            sequence = link.capture_sequence

            def done() -> Outcome | None:
                if len(link.captures) > before:
                    info = link.captures[-1]
                    x, y, _ = link.origin.to_local(info.latitude_deg, info.longitude_deg,
                                                   0.0)
                    return Outcome(Status.OK, f"{link.drone_id} took photo {info.index} at "
                                   f"({x:.1f}, {y:.1f})", link.state(), {"photo": info.index})
                return None

            for _ in range(PHOTO_TRIES):
                await self._mavsdk(link, "the photo", lambda: self._capture(link, sequence))
                outcome = await wait_instant(link, "take_photo", done, PHOTO_REPORT_WALL_S)
                if outcome.status is not Status.TIMEOUT:
                    return outcome
            return Outcome(Status.UNKNOWN, f"take_photo: the camera of {link.drone_id} accepted "
                           f"the photo but its report did not arrive after {PHOTO_TRIES} tries "
                           "(the link is lossy); the photo was probably taken", link.state())

        return await self._run("take_photo", drone, body)

    @staticmethod
    async def _capture(link: DroneLink, sequence: int) -> None:
        """IMAGE_START_CAPTURE (one image, with its capture sequence number) to the camera;
        a refusal by the camera is a Refusal; MAVSDK's errors (no answer) pass through."""
        fields = {"target_system": link.profile.system_id, "target_component": MavComponent.CAMERA,
                  "command": MavCmd.IMAGE_START_CAPTURE, "confirmation": 0, "param1": 0.0,
                  "param2": 0.0, "param3": 1.0, "param4": float(sequence), "param5": 0.0,
                  "param6": 0.0, "param7": 0.0}
        command = MavlinkMessage("COMMAND_LONG", 0, 0, link.profile.system_id,
                                 MavComponent.CAMERA,
                                 json.dumps(fields))
        ack = await link.direct.send_command(command)
        result = json.loads(ack.fields_json or "{}").get("result")
        if result != MavResult.ACCEPTED:
            raise Refusal(f"the camera refused the photo: "
                          f"{MAV_RESULTS.get(result, f'MAV_RESULT {result}')}")

    async def charge(self, drone: str) -> Outcome:
        """Land on a charging station this drone senses and charge to full."""
        async def body(link: DroneLink) -> Outcome:
            stations = [t for t in self.services.sense(link.drone_id).targets
                        if t.kind == CHARGING_KIND]
            if not stations:
                raise Refusal(f"no charging station within {link.profile.perceived_radius_m:g} m"
                              f" of {link.drone_id}")
            station = stations[0]
            texts = len(link.status_texts)
            if link.flight_state == FlightState.ON_GROUND:
                if station.distance_m > 0.0:
                    raise Refusal(f"{link.drone_id} is on the ground {station.distance_m:.0f} m "
                                  f"from station {station.id}: take off and charge again")
            else:
                sx, sy, _ = station.position_m
                moved = await self._goto(link, (sx, sy, link.state().altitude_m), "charge")
                if not moved.ok:
                    return moved
                texts = len(link.status_texts)
                await self._mavsdk(link, "landing", lambda: link.action.land(),
                                   effects.landing)
            start_pct = link.battery_pct

            def done() -> Outcome | None:
                if self._landed(link) and not link.armed and \
                        link.battery_pct >= FULL_PCT:
                    return Outcome(Status.OK, f"{link.drone_id} charged at {station.id} from "
                                   f"{start_pct:.0f}% to {link.battery_pct:.0f}%", link.state())
                return None

            return await self._wait(link, 4000.0, "charge", done, texts_from=texts)

        return await self._run("charge", drone, body)

    # ------------------------------------------------------------- radio
    def _radio(self, action: str, drone: object, call) -> Outcome:
        try:
            link = self._link(drone)
        except Refusal as error:
            return Outcome(Status.REJECTED, f"{action} refused: {error}")
        try:
            return call(link)
        except ValueError as error:  # the radio refused; a known drone: its state, as every
            # other refusal gives
            return Outcome(Status.REJECTED, f"{action} refused: {error}", link.state())

    def send_message(self, drone: str, to: str, text: str) -> Outcome:
        def call(link: DroneLink) -> Outcome:
            self.services.send_message(link.drone_id, to, text)
            return Outcome(Status.OK, f"{link.drone_id} sent a message to {to}", link.state())

        return self._radio("send_message", drone, call)

    def broadcast(self, drone: str, text: str) -> Outcome:
        def call(link: DroneLink) -> Outcome:
            count = self.services.broadcast(link.drone_id, text)
            return Outcome(Status.OK, f"{link.drone_id} broadcast to {count} drones",
                           link.state(), {"recipients": count})

        return self._radio("broadcast", drone, call)

    def read_messages(self, drone: str) -> Outcome:
        def call(link: DroneLink) -> Outcome:
            messages = self.services.read_messages(link.drone_id)
            data = {"messages": [{"from": m.sender, "text": m.text, "t_s": round(m.t_s, 1)}
                                 for m in messages]}
            return Outcome(Status.OK, f"{link.drone_id} has {len(messages)} new messages",
                           link.state(), data)

        return self._radio("read_messages", drone, call)

    async def wait(self, drone: str, duration_s: float) -> Outcome:
        """Let simulated time pass for the caller (its drones keep doing what they do), up to
        duration_s, ending early once a radio message for this drone can be read."""
        try:
            link = self._link(drone)
            duration = _number("duration_s", duration_s)
            if not 0.0 < duration <= MAX_WAIT_S:
                raise Refusal(f"duration_s must be within (0, {MAX_WAIT_S:g}], "
                              f"got {duration:g}")
        except Refusal as refusal:
            return Outcome(Status.REJECTED, f"wait refused: {refusal}")
        waited_s, message = await wait_world(self.services, link.drone_id, duration)
        data = {"waited_s": round(waited_s, 3), "message_arrived": bool(message)}
        if message:
            return Outcome(Status.OK, f"a message for {link.drone_id} arrived after "
                           f"{waited_s:.1f} s: read it with read_messages", link.state(), data)
        return Outcome(Status.OK, f"waited {waited_s:.1f} s", link.state(), data)

    # --------------------------------------------------------- perception
    def nearby(self, drone: str) -> Outcome:
        """Targets, obstacles and drones within this drone's perceived radius."""
        try:
            link = self._link(drone)
        except Refusal as refusal:
            return Outcome(Status.REJECTED, str(refusal))
        seen = perception_dict(self.services.sense(link.drone_id))
        counts = ", ".join(f"{len(v)} {k}" for k, v in seen.items())
        return Outcome(Status.OK, f"{link.drone_id} senses {counts} within "
                       f"{link.profile.perceived_radius_m:g} m", link.state(), seen)

    # ----------------------------------------------------------- operator
    def operator_land_all(self) -> None:
        """Operator reset (not flight): every drone disarmed on the ground where it is."""
        self.services.operator_land_all()

    def operator_reset_batteries(self) -> None:
        """Operator reset (not flight): every battery full."""
        self.services.operator_reset_batteries()

    def operator_reset_to_start(self) -> None:
        """Operator reset (not flight): the session's start state."""
        self.services.operator_reset_to_start()

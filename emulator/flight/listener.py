"""What an autopilot tells the outside world; the MAVLink link implements it."""

from __future__ import annotations

from typing import Protocol

from emulator.flight.camera import ImageCapture
from emulator.flight.mission import MissionItem

__all__ = ["AutopilotListener", "SilentListener"]


class AutopilotListener(Protocol):
    """What the autopilot tells the outside world (the MAVLink link implements it)."""

    def on_statustext(self, severity: int, text: str) -> None: ...
    def on_mission_item_reached(self, seq: int) -> None: ...
    def on_mission_current(self) -> None: ...
    def on_home_changed(self) -> None: ...
    def on_image_captured(self, capture: ImageCapture) -> None: ...
    def on_payload_item(self, item: MissionItem) -> None: ...
    def on_state_changed(self) -> None: ...
    def on_operator_reset(self) -> None: ...


class SilentListener:
    """Hears nothing: the listener of a vehicle with no MAVLink link (core tests)."""

    def on_statustext(self, severity: int, text: str) -> None:
        pass

    def on_mission_item_reached(self, seq: int) -> None:
        pass

    def on_mission_current(self) -> None:
        pass

    def on_home_changed(self) -> None:
        pass

    def on_image_captured(self, capture: ImageCapture) -> None:
        pass

    def on_payload_item(self, item: MissionItem) -> None:
        pass

    def on_state_changed(self) -> None:
        pass

    def on_operator_reset(self) -> None:
        pass

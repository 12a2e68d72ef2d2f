"""STATUSTEXT reasons a ground station reads: the beginnings of the texts an emulated vehicle
sends when it stops, fails or is repaired (emulator.flight), which the gateway matches."""

from __future__ import annotations

__all__ = ["FAILSAFE_TEXTS", "FAILURE_TEXTS", "OBSTACLE_TEXT", "REPAIRED_TEXT"]

OBSTACLE_TEXT = "Obstacle"  # "Obstacle <name> ahead: holding"
# failsafes that end a goal: the vehicle lands, returns or holds on its own
FAILSAFE_TEXTS = ("Critical battery", "Emergency battery", "Offboard setpoints lost",
                  "Data link lost")
# failures that take a vehicle out of the task (emulator.flight.failures, as PX4 says them)
FAILURE_TEXTS = ("Motor failure", "GPS lost")
REPAIRED_TEXT = "Failures cleared"

"""A drone whose position, home or battery telemetry has not told yet is reported with those
quantities unknown (JSON null), so every surface can encode it: never NaN, never an error."""

from __future__ import annotations

import json
import math

from mavlink_gateway import DroneState, Outcome, Status


def _state(**unknown: float) -> DroneState:
    values = dict(drone="d1", x_m=1.234, y_m=-5.0, altitude_m=10.0, heading_deg=90.0,
                  battery_pct=80.0, flight_state="hovering", armed=True, mode="hold",
                  home_x_m=0.0, home_y_m=0.0)
    values.update(unknown)
    return DroneState(**values)  # type: ignore[arg-type]


def test_unknown_quantities_are_null_and_encode_as_strict_json() -> None:
    state = _state(x_m=math.nan, y_m=math.nan, altitude_m=math.nan, battery_pct=math.nan,
                   home_x_m=math.nan, home_y_m=math.nan)
    d = Outcome(Status.OK, "d1 hovering", state=state).to_dict()
    assert d["state"]["x_m"] is None and d["state"]["battery_pct"] is None
    assert d["state"]["home_x_m"] is None and d["state"]["heading_deg"] == 90.0
    assert json.loads(json.dumps(d, allow_nan=False))["state"]["altitude_m"] is None


def test_known_quantities_keep_their_rounded_values() -> None:
    assert _state().to_dict()["x_m"] == 1.23
    assert _state().to_dict()["battery_pct"] == 80.0

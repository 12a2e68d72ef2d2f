"""The compiled hot path, where it matches the sources in this tree.

build_native.py compiles some modules of this package with mypyc (`emulator/flight/NAME.py` as
`emulator.flight._NAME_native`, carrying the SHA-256 of the source it was built from). A compiled
module runs the same operations on C doubles, so its results are the same to the last bit; it
is used only when its digest matches the source now here, so an edited module runs as plain
Python until it is built again, and a tree without the compiled libraries (a wheel, a machine
without a C compiler) runs the pure-Python modules. MAVSWARM_PURE_PYTHON=1 turns them off.
"""

from __future__ import annotations

import hashlib
import importlib
import logging
import os
from pathlib import Path
from types import ModuleType

from emulator.flight import cruise, solo, solo_battery

__all__ = ["COMPILED", "SoloBattery", "SoloVehicle", "compiled", "cruise_plan", "fleet_deltas",
           "run_solo_steps", "step_all"]

log = logging.getLogger("mavswarm.native")


def compiled(name: str) -> ModuleType | None:
    """The compiled build of emulator/flight/NAME.py, or None when it is missing, stale or
    turned off (a stale one is logged once, as a warning)."""
    if os.environ.get("MAVSWARM_PURE_PYTHON", "") not in ("", "0"):
        return None
    try:
        module = importlib.import_module(f"emulator.flight._{name}_native")
    except ImportError:
        return None
    digest = hashlib.sha256(Path(__file__).with_name(f"{name}.py").read_bytes()).hexdigest()
    if getattr(module, "SOURCE_SHA256", None) != digest:
        log.warning("emulator/flight/%s.py changed since it was compiled: running it as plain "
                    "Python (`python build_native.py` compiles it again)", name)
        return None
    return module


_solo = compiled("solo")
SoloVehicle: type[solo.SoloVehicle] = solo.SoloVehicle if _solo is None else _solo.SoloVehicle
step_all = solo.step_all if _solo is None else _solo.step_all
run_solo_steps = solo.run_solo_steps if _solo is None else _solo.run_solo_steps
_cruise = compiled("cruise")
cruise_plan = cruise.cruise_plan if _cruise is None else _cruise.cruise_plan
_battery = compiled("solo_battery")
SoloBattery: type[solo_battery.SoloBattery] = (solo_battery.SoloBattery if _battery is None
                                               else _battery.SoloBattery)
fleet_deltas = solo_battery.fleet_deltas if _battery is None else _battery.fleet_deltas
COMPILED: frozenset[str] = frozenset(
    name for name, module in (("solo", _solo), ("cruise", _cruise), ("solo_battery", _battery))
    if module is not None)

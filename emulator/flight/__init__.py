"""The emulator's vehicles, free of I/O: vectorised rigid-body dynamics, battery, the PX4-like
autopilot (modes, take-off, land, return, offboard, orbit), missions and failures."""

__all__: list[str] = []

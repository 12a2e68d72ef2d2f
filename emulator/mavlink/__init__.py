"""The emulator's MAVLink side, free of I/O: the v2 frame codec, each vehicle's link and
network protocol (heartbeats, parameters, missions, commands and their replies, FTP, logs) and
the telemetry streams a vehicle sends."""

__all__: list[str] = []

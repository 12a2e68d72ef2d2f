"""The swarm emulator: PX4-like quadrotors that speak MAVLink v2, with a sans-I/O core
(`flight/` the vehicles' dynamics, autopilot and missions; `mavlink/` the codec, the network
protocol and telemetry streams), a world with moving targets and obstacles, the ground-truth
recorder, clocks (real time, stepped, lockstep), faults, UDP transport and `mavswarm up`.
Modules are imported by name (`emulator.swarm`, `emulator.scenario` ...)."""

__all__: list[str] = []

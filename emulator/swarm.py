"""A running swarm: the fleet, its MAVLink links and sockets, driven by one scheduler loop."""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import math
import sys
import time
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from emulator.clock import ClockConfig, RealTimePacer
from emulator.flight.fleet import Fleet
from emulator.link_faults import LinkFaults
from emulator.lockstep import Watch, WatchBoard
from emulator.mavlink.protocol import Address, NetworkProtocol
from emulator.mavlink.streams import StreamSchedule
from emulator.mavlink.telemetry import FleetTelemetry
from emulator.mavlink.vehicle_link import VehicleLink
from emulator.networks import VEHICLES_PER_NETWORK
from emulator.port_plan import PortPlan
from emulator.quiet_streams import QuietStreams
from emulator.scenario import Scenario
from emulator.scenario_export import scenario_to_dict
from emulator.stepped_clock import SteppedClock
from emulator.swarm_faults import SwarmFaults
from emulator.telemetry_bursts import TelemetryBursts
from emulator.telemetry_out import TelemetryOut
from emulator.transport import UdpEndpoint

__all__ = ["PortPlan", "Swarm", "SwarmStats"]

LOOP_TICK_S = 0.005  # the longest the loop sleeps while bursts wait for their turn
# The longest it sleeps otherwise, when no step, telemetry or link duty is due sooner: what
# needs it sooner wakes it (a datagram, a clock released, a watch, a burst asked for).
IDLE_TICK_S = 0.25
# Due telemetry is gathered and sent in batches this often, or at the shortest stream period
# when a client asked for a faster stream (streams are capped at 100 Hz). When every stream is
# slower than TICKS_PER_PERIOD ticks of it (a lockstep run's 0.5-2 Hz keep-alive streams), the
# ticks are a TICKS_PER_PERIOD-th of the shortest period apart, at most TELEMETRY_TICK_MAX_S:
# each tick costs about the same whatever it sends, and an idle hosted session pays it
# all the time.
TELEMETRY_TICK_S = 0.02
TELEMETRY_TICK_MAX_S = 0.1
TICKS_PER_PERIOD = 5
# A lockstep clock's streams only keep links alive and caches roughly current (outcomes are
# read from the bursts sent where the clock stops), so they are gathered once per shortest
# period, at most this far apart: a vehicle's message goes out up to a tick late, and an idle
# hosted session wakes twice a second instead of ten times.
QUIET_TELEMETRY_TICK_MAX_S = 0.5
STEP_BUDGET_S = 0.005  # stepped mode: wall time simulated between looks at the sockets
# A lockstep clock steps in slices of STEPS_PER_SLICE: a fast-forward through steady flight
# ends with its slice, so where the slices end is part of every result (the truth's last bits)
# and lockstep results never change. A stepped clock without lockstep runs flat out, and where
# its slices end already depends on when datagrams arrive; it takes slices of up to
# FREE_STEPS_PER_SLICE (fewer cruise plans, leaps and truth writes) and looks at its sockets
# after STEP_BUDGET_S of wall time or FREE_SIM_S_PER_LOOK of simulated time, whichever comes
# first: however fast the machine, a datagram waits at most that much simulated time for the
# scheduler to read it.
STEPS_PER_SLICE = 50
FREE_STEPS_PER_SLICE = 250
FREE_SIM_S_PER_LOOK = 15.0
LINK_TICK_S = 0.05
log = logging.getLogger("mavswarm.swarm")


def telemetry_tick_s(shortest_period_s: float, *, quiet: bool = False) -> float:
    """How often due telemetry is gathered, given the shortest stream period (see above);
    quiet: the streams of a lockstep clock (emulator.quiet_streams), gathered once a period."""
    if quiet:
        return min(shortest_period_s, max(TELEMETRY_TICK_S, QUIET_TELEMETRY_TICK_MAX_S))
    slow = min(TELEMETRY_TICK_MAX_S, shortest_period_s / TICKS_PER_PERIOD)
    return min(shortest_period_s, max(TELEMETRY_TICK_S, slow))


@dataclass(frozen=True, slots=True)
class SwarmStats:
    sim_time_s: float
    wall_time_s: float
    real_time_factor: float
    steps: int
    slipped_s: float
    frames_ok: int
    frames_bad: int
    datagrams_in: int
    datagrams_out: int
    frames_out: int
    unroutable: int
    internal_errors: int


class Swarm:
    """N emulated PX4 quadrotors on UDP. Use `async with Swarm(...) as swarm:`."""

    def __init__(self, scenario: Scenario, *, clock: ClockConfig | None = None,
                 ports: PortPlan | None = None,
                 telemetry_hz: Mapping[str, float] | None = None,
                 link_faults: LinkFaults | None = None,
                 shared_local_origin: bool = False) -> None:
        self.clock = clock or ClockConfig()
        self.ports = ports or PortPlan()
        self.ports.check(len(scenario.vehicles))
        self.fleet = Fleet(scenario, physics_hz=self.clock.physics_hz)
        self.shared_local_origin = shared_local_origin
        self.left: set[int] = set()  # vehicles that left the run (emulator.fleet_membership)
        if shared_local_origin:  # LOCAL_POSITION_NED about the session origin for every vehicle
            self.fleet.share_local_origin()
        if self.clock.stepped:
            # A client's thinking time is not simulated, so "armed but no takeoff for 10 s"
            # would disarm vehicles while others fly: stepped swarms do not auto-disarm.
            for ap in self.fleet.autopilots:
                ap.set_param("COM_DISARM_PRFLT", -1.0)
        wall = time.monotonic()
        self.streams = StreamSchedule(self.fleet.n, wall, telemetry_hz)
        self.faults = SwarmFaults(self.fleet, link_faults)
        # One MAVLink network (emulator.mavlink.protocol) per socket: all vehicles, or one
        # each per-vehicle. A link's replies go straight into its network's queue.
        p = self.ports
        n = self.fleet.n
        groups = [[k] for k in range(n)] if p.per_vehicle else [
            list(range(j, min(n, j + VEHICLES_PER_NETWORK)))
            for j in range(0, n, VEHICLES_PER_NETWORK)]
        # each telemetry row's network when several share the batches (None: one, or one each)
        self._network_index = (np.arange(n) // VEHICLES_PER_NETWORK
                               if len(groups) > 1 and not p.per_vehicle else None)
        self.networks = [NetworkProtocol(self._destinations(i), self.faults.gate)
                         for i in range(len(groups))]
        self.network_of = [self.networks[0]] * self.fleet.n
        for network, group in zip(self.networks, groups, strict=True):
            for k in group:
                self.network_of[k] = network
        self.links = [
            VehicleLink(ap, self.network_of[ap.k].send_frame, self.streams, time.monotonic)
            for ap in self.fleet.autopilots
        ]
        for link in self.links:
            self.network_of[link.k].add(link)
        # Periodic telemetry is built for all due vehicles at once; the links' encoders
        # share its sequence numbers, so every vehicle/component keeps one sequence.
        self.telemetry = FleetTelemetry(self.fleet)
        for link in self.links:
            for component, sequences in self.telemetry.sequences.items():
                link.encoder(component).share_sequence(sequences, link.k)
        self.out = TelemetryOut(self.telemetry, self.networks, self.network_of, self.links,
                                self._network_index)
        # The links that may have a wall-clock duty (VehicleLink.needs_tick): a link joins
        # when it gets a message, its vehicle's state changes or it has a gimbal, and leaves
        # when a tick finds it without one, so idle vehicles cost nothing per link tick.
        self._tick_candidates: set[int] = set()
        # a lockstep clock's periodic streams carry only what may have changed
        self.quiet = (QuietStreams(n, self.streams.streams, wall) if self.clock.lockstep
                      else None)
        self.bursts = TelemetryBursts(self.fleet, self.quiet)
        if self.quiet is not None:  # a new ground station is sent everything for a while
            for network in self.networks:
                network.on_new_peer = self.quiet.new_peer
        for link in self.links:
            self.hook_link(link)
        self.endpoints: list[UdpEndpoint] = []
        self._task: asyncio.Task[None] | None = None
        self._wake = asyncio.Event()
        self._clock = SteppedClock(self.fleet, self._wake.set)
        self._pacer: RealTimePacer | None = None
        self._wall_start_s = wall
        self._sim_start_s = 0.0
        self.watches = WatchBoard(self.fleet, self.hold_clock_at, self.release_clock,
                                  self._request_burst)

    # -------------------------------------------------------------- lifecycle
    async def __aenter__(self) -> Swarm:
        await self.start()
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.close()

    def _destinations(self, i: int) -> list[Address]:
        """Where network i sends (besides the peers that talk to it)."""
        p = self.ports
        dests = []
        if p.api_port:
            dests.append((p.api_host, p.api_port + i))
        if p.gcs_port:
            dests.append((p.api_host, p.gcs_port + (0 if p.per_vehicle else i)))
        return dests

    async def start(self) -> None:
        p = self.ports
        try:
            for i, network in enumerate(self.networks):
                port = p.bind_port + i if p.bind_port else 0
                endpoint = UdpEndpoint(network, time.monotonic, self._wake.set)
                endpoint.open(p.bind_host, port)
                self.endpoints.append(endpoint)
        except OSError as error:
            for endpoint in self.endpoints:
                endpoint.close()
            raise OSError(f"cannot open the swarm's UDP sockets: {error}") from error
        self._wall_start_s = time.monotonic()
        self._sim_start_s = self.fleet.now_s
        self._pacer = None if self.clock.stepped else RealTimePacer(self.clock, self._wall_start_s)
        self._task = asyncio.create_task(self._run(), name="mavswarm-scheduler")

    async def close(self) -> None:
        if self._task is not None:
            self._task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._task
            self._task = None
        for endpoint in self.endpoints:
            endpoint.close()
        self._clock.cancel_waiters()

    def hook_link(self, link: VehicleLink) -> None:
        """Hear what a vehicle's link tells the swarm (its MAVLink signal, its duties)."""
        link.on_mavlink_signal = self.faults.mavlink_signal_changed
        link.on_tick_duty = self._tick_candidates.add
        link.on_changed = self.bursts.changed
        self.bursts.changed(link.k)
        if link.needs_tick:
            self._tick_candidates.add(link.k)

    # ----------------------------------------------------------------- access
    @property
    def n(self) -> int:
        return self.fleet.n

    @property
    def recorder(self):
        """Ground truth: for validators and tests, never for agents."""
        return self.fleet.recorder

    def connection_urls(self) -> list[str]:
        """Where MAVSDK, QGroundControl and MAVProxy connect (emulator.port_plan)."""
        bound = [e.local_address[1] for e in self.endpoints]
        return self.ports.connection_urls(len(self.networks), self.n, bound)

    def stats(self) -> SwarmStats:
        wall = time.monotonic() - self._wall_start_s
        sim = self.fleet.now_s - self._sim_start_s
        return SwarmStats(
            sim_time_s=sim, wall_time_s=wall, real_time_factor=sim / wall if wall > 0 else 0.0,
            steps=self.fleet.step_count,
            slipped_s=self._pacer.slipped_s if self._pacer else 0.0,
            frames_ok=sum(n.decoder.frames_ok for n in self.networks),
            frames_bad=sum(n.decoder.frames_bad for n in self.networks),
            datagrams_in=sum(n.stats.datagrams_in for n in self.networks),
            datagrams_out=sum(n.stats.datagrams_out for n in self.networks),
            frames_out=sum(n.stats.frames_out for n in self.networks),
            unroutable=sum(n.stats.unroutable for n in self.networks),
            internal_errors=self.out.errors
            + sum(n.stats.handler_errors for n in self.networks),
        )

    def set_link_faults(self, faults: LinkFaults) -> None:
        """Change the link faults from now on (an operator at run time); recorded in the
        ground truth."""
        self.faults.configure(faults)
        self._wake.set()

    def export_truth(self, path: str | Path) -> Path:
        """The ground truth, with the scenario attached as `scenario` (session-file JSON)."""
        scene = json.dumps(scenario_to_dict(self.fleet.scenario))
        return self.fleet.recorder.export(path, attachments={"scenario": scene})

    # -------------------------------------------------------------- stepping
    async def advance(self, seconds: float) -> None:
        """Advance simulated time by `seconds` (stepped mode; in real time, just wait)."""
        if not (math.isfinite(seconds) and seconds >= 0.0):
            raise ValueError(f"cannot advance by {seconds!r} s")
        if not self.clock.stepped:
            await asyncio.sleep(seconds / self.clock.speed)
            return
        await self._clock.advance_to(self.fleet.now_s + seconds)

    async def wait_idle(self) -> None:
        """Return once no vehicle is executing a goal (stepped mode: the clock stops)."""
        await self._clock.wait_idle()

    def hold_clock_at(self, t_s: float) -> object:
        """Stepped mode: never step past t_s until `release_clock(token)`. A caller waiting
        for an outcome with a simulated-time budget uses it, so a time-out happens at exactly
        its budget whatever the wall-clock delays. Real-time mode ignores it."""
        return self._clock.hold_at(t_s)

    def release_clock(self, token: object) -> None:
        self._clock.release(token)

    def pin(self) -> object:
        """Stepped mode: stop the clock where it is until `release_clock(token)`."""
        return self.hold_clock_at(self.fleet.now_s)

    def watch(self, drone_id: str | None = None, *, until_s: float = math.inf,
              advance: bool = False, message_for: str | None = None) -> Watch:
        """Lockstep: wait on the world (see emulator.lockstep). `drone_id`: halt when its goal
        ends; `until_s`: halt there at the latest (`advance`: run the clock up to it even if
        every vehicle is at rest); `message_for`: halt once a radio message for that drone
        can be read."""
        k = None if drone_id is None else self.fleet.index_by_id[drone_id]
        watch = self.watches.open(k, until_s, advance=advance, message_for=message_for)
        self._wake.set()
        return watch

    def _request_burst(self, k: int) -> None:
        """Lockstep halt of vehicle k: its whole telemetry now and once more on the next loop
        turn, once that of every other vehicle that changed since its last (on a lossy link or
        in real time, of every other vehicle: changes are noted between stepped slices), so a
        client sees the stopped state within milliseconds whatever the stream rates (k first:
        its client waits on it). See emulator.telemetry_bursts."""
        failed = {ap.k for ap in self.fleet.autopilots if ap.failures.standing_report()}
        everyone = self.faults.gate.active or not self.clock.stepped
        self.bursts.halt(k, also=failed, every_vehicle=everyone)
        self._wake.set()

    def send_telemetry_of(self, drone_id: str) -> None:
        """One vehicle's whole telemetry now and once more on the next loop turn."""
        self.bursts.first(self.fleet.index_by_id[drone_id], 2)
        self._wake.set()

    def repeat_status_texts(self, drone_id: str) -> int:
        """drone_id's STATUSTEXTs of the present simulated time, sent again now (how many)."""
        return self.links[self.fleet.index_by_id[drone_id]].repeat_texts_now()

    def wake(self) -> None:
        """Have the scheduler look at the fleet again now (it changed between steps)."""
        self._wake.set()

    def send_all_telemetry(self) -> None:
        """Every vehicle's whole telemetry on the next loop turn (after an operator reset)."""
        self.bursts.everyone()
        self._wake.set()

    def _send_bursts(self) -> None:
        bursts = self.bursts.take_turn(self.left)
        if not bursts:
            return
        if self.faults.gate.active:  # a lost MISSION_ITEM_REACHED is told again
            for k in bursts:
                self.links[k].resend_mission_reached()
        for k in bursts:  # a failure report (a motor, the GPS), on any link: UDP loses some
            report = self.fleet.autopilots[k].failures.standing_report()
            if report is not None:
                self.links[k].statustext(*report)
        ks = np.fromiter(bursts, dtype=np.intp, count=len(bursts))
        schedule = self.streams
        on = np.isfinite(schedule.period_s[ks])
        self.out.send((spec.msg_id, ks[on[:, col]])
                           for col, spec in enumerate(schedule.streams))
        if self.quiet is not None:
            self.quiet.sent(ks)

    async def _run(self) -> None:
        fleet = self.fleet
        next_link_tick = next_peer_tick = next_telemetry = 0.0
        while True:
            wall = time.monotonic()
            if self.clock.stepped:
                deadline = wall + STEP_BUDGET_S
                slice_steps, look_ends = self._slicing()
                noted = False
                while time.monotonic() < deadline and fleet.step_count < look_ends:
                    watched = self.watches.advance_targets()  # the wait tools' deadlines
                    if not self._clock.should_step(watched):
                        break
                    if not noted:  # once per run of slices: steps never wake a vehicle at
                        # rest (commands do, between runs; a fault marks every vehicle)
                        self.bursts.note_active()
                        noted = True
                    # never past a fault's time either
                    allowed = self._clock.steps_allowed([*watched, self.faults.next_event_s()])
                    fleet.run(min(allowed, slice_steps, look_ends - fleet.step_count))
                    if self.faults.fire_due():
                        self.bursts.all_changed()
                    self._clock.release_waiters()
                    self.watches.check()
            else:
                assert self._pacer is not None
                for _ in range(self._pacer.steps_due(wall, fleet.step_count)):
                    fleet.step()
                    if self.faults.fire_due():
                        self.bursts.all_changed()
                self._clock.release_waiters()
            wall = time.monotonic()
            if wall >= next_telemetry:
                tick = telemetry_tick_s(self.streams.shortest_period_s(),
                                        quiet=self.quiet is not None)
                next_telemetry += tick
                if next_telemetry <= wall:  # late (or the first turn): keep the cadence from now
                    next_telemetry = wall + tick
                self._send_telemetry(wall)
            if self.bursts.pending:
                self._send_bursts()
            if wall >= next_link_tick:
                next_link_tick = wall + LINK_TICK_S
                self.tick_links(wall)
            if wall >= next_peer_tick:
                next_peer_tick = wall + 1.0
                for network in self.networks:
                    network.expire_peers(wall)
            if self.clock.stepped and self._clock.should_step(self.watches.advance_targets()):
                await asyncio.sleep(0)
                continue
            self._wake.clear()
            wake_at = max(self.streams.next_wakeup_s(), next_telemetry)
            if self._tick_candidates:  # a link with a wall-clock duty (an upload's retries)
                wake_at = min(wake_at, next_link_tick)
            if self._pacer is not None:  # real time: sleep until a step or telemetry is due
                wake_at = min(wake_at, self._pacer.next_step_wall_s(fleet.step_count))
            cap = LOOP_TICK_S if self.bursts.pending else IDLE_TICK_S
            timeout = min(cap, max(0.0, wake_at - time.monotonic()))
            if self.clock.stepped:
                # Not asyncio.wait_for: before Python 3.12 it swallows a cancellation that
                # arrives as the event is set, and close() would then wait forever.
                with contextlib.suppress(TimeoutError):
                    async with asyncio.timeout(max(timeout, 0.0005)):
                        await self._wake.wait()
            else:
                await asyncio.sleep(max(timeout, 0.0005))

    def _slicing(self) -> tuple[int, int]:
        """A stepped clock's steps per slice, and the step count at which its scheduler looks
        at the sockets again whatever the wall time (none for a lockstep clock)."""
        if self.clock.lockstep:
            return STEPS_PER_SLICE, sys.maxsize
        look_steps = max(1, round(FREE_SIM_S_PER_LOOK / self.fleet.dt_s))
        return FREE_STEPS_PER_SLICE, self.fleet.step_count + look_steps

    def _send_telemetry(self, wall: float) -> None:
        due = self.streams.due(wall)
        if self.quiet is not None and not self.faults.gate.active:  # lossy: every period
            due = self.quiet.filter(due, wall)
        self.out.send(due)

    def send_due_telemetry(self, wall_now_s: float) -> None:
        """Send every telemetry stream due by `wall_now_s` (the scheduler does this every
        turn; a driver of the networks without the scheduler calls it)."""
        self._send_telemetry(wall_now_s)

    def tick_links(self, wall_now_s: float) -> None:
        """The links' wall-clock duties: mission item retries, the offboard failsafe."""
        links, idle = self.links, []
        for k in sorted(self._tick_candidates):
            link = links[k]
            if not link.needs_tick:
                idle.append(k)
            elif k not in self.left:
                link.tick(wall_now_s)
                if self.quiet is not None:  # a duty may change it (a link-loss failsafe)
                    self.quiet.mark((k,))
        self._tick_candidates.difference_update(idle)

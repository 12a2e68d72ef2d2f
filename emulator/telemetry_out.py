"""Periodic telemetry into the swarm's MAVLink networks: each stream's due vehicles built
at once from the fleet arrays (emulator.mavlink.telemetry), framed together
(emulator.mavlink.frames) and packed several frames to a datagram, each network's share
handed over at once."""

from __future__ import annotations

import logging
from collections.abc import Iterable

import numpy as np

from emulator.mavlink.frames import FramePart, frame_batch
from emulator.mavlink.protocol import NetworkProtocol
from emulator.mavlink.telemetry import BATCHED_STREAMS, FleetTelemetry
from emulator.mavlink.vehicle_link import VehicleLink

__all__ = ["TelemetryOut"]

log = logging.getLogger("mavswarm.swarm")


class TelemetryOut:
    """Sends telemetry streams of a swarm's vehicles; `errors` counts what failed at the I/O
    edge (logged, then sent one message at a time, the swarm kept alive)."""

    def __init__(self, telemetry: FleetTelemetry, networks: list[NetworkProtocol],
                 network_of: list[NetworkProtocol], links: list[VehicleLink],
                 network_index: np.ndarray | None) -> None:
        """network_of, links: the swarm's lists (vehicles that join are appended to them);
        network_index: each vehicle's network when several share the batches, else None."""
        self.telemetry = telemetry
        self.networks = networks
        self._network_of = network_of
        self.links = links
        self._network_index = network_index
        self.errors = 0

    def send(self, due: Iterable[tuple[int, np.ndarray]]) -> None:
        """Stream `msg_id` of vehicles `ks`, for each (msg_id, ks): batched, framed together
        and packed several frames to a datagram."""
        for network in self.networks:
            network.begin_batch()
        try:
            parts: list[FramePart] = []
            order: list[np.ndarray] = []
            for msg_id, ks in due:
                if not len(ks):
                    continue
                if msg_id in BATCHED_STREAMS:
                    try:
                        parts.append(self.telemetry.part(msg_id, ks))
                        order.append(ks)
                        continue
                    except Exception:  # the I/O edge: log, count, send them one by one
                        self.errors += 1
                        log.exception("batched message %d failed", msg_id)
                self._send_one_by_one(msg_id, ks)
            if parts:
                self._emit_parts(parts, order)
        finally:
            for network in self.networks:
                network.end_batch()

    def _emit_parts(self, parts: list[FramePart], order: list[np.ndarray]) -> None:
        ks = np.concatenate(order)
        rows = net = None
        if self._network_index is not None:  # several networks: each one's frames together
            net = self._network_index[ks]
            rows = np.argsort(net, kind="stable")
            ks, net = ks[rows], net[rows]
        try:
            frames = frame_batch(parts, rows)
        except Exception:  # the I/O edge: log, count, send them one by one
            self.errors += 1
            log.exception("framing a telemetry batch failed")
            for part, part_ks in zip(parts, order, strict=True):
                self._send_one_by_one(part.layout.msg_id, part_ks)
            return
        data, network_of, start, ends = frames.data, self._network_of, 0, frames.ends.tolist()
        if len(self.networks) == 1 and self.networks[0].send_frames(data, ends):
            return  # one shared network and a clean link: the whole batch at once
        if net is not None and self._send_by_network(data, frames.ends, ends, net):
            return
        for k, end in zip(ks.tolist(), ends, strict=True):
            network_of[k].send_frame(k, data[start:end])
            start = end

    def _send_by_network(self, data: bytes, ends_at: np.ndarray, ends: list[int],
                         net: np.ndarray) -> bool:
        """Frames sorted by network (`net`: each one's network), each network's at once.
        False, sending nothing, when a network present cannot take a whole batch (a link
        with faults)."""
        present = np.flatnonzero(np.diff(net, prepend=-1)).tolist()  # first row of each
        nets = net[present].tolist()
        if not all(self.networks[j].can_send_frames() for j in nets):
            return False
        bounds = [*present[1:], len(ends)]
        base = 0
        for j, first, last in zip(nets, present, bounds, strict=True):
            top = ends[last - 1]
            self.networks[j].send_frames(data[base:top], (ends_at[first:last] - base).tolist())
            base = top
        return True

    def _send_one_by_one(self, msg_id: int, ks: np.ndarray) -> None:
        for k in ks.tolist():
            try:
                self.links[k].send_stream(msg_id)
            except Exception:  # the I/O edge: log, count, keep the swarm alive
                self.errors += 1
                log.exception("vehicle %d failed to send message %d", k + 1, msg_id)

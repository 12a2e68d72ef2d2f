"""A batch of frames handed to the network at once leaves in the same datagrams, byte for
byte, as the same frames sent one by one (the sans-I/O protocol, no socket needed)."""

from __future__ import annotations

import random

from emulator.link_faults import LinkFaults, LinkGate
from emulator.mavlink.protocol import MAX_BATCH_BYTES, NetworkProtocol

SINK = ("127.0.0.1", 14550)


def _network() -> NetworkProtocol:
    network = NetworkProtocol([SINK])
    network.open()
    return network


def _one_by_one(frames: list[bytes]) -> list[bytes]:
    network = _network()
    network.begin_batch()
    network.send_frame(0, b"\xfd" + bytes(300))  # a partly filled datagram before the batch
    for k, frame in enumerate(frames):
        network.send_frame(k, frame)
    network.end_batch()
    return [data for data, _ in network.datagrams_to_send(0.0)]


def _at_once(frames: list[bytes]) -> list[bytes]:
    network = _network()
    data = b"".join(frames)
    ends, end = [], 0
    for frame in frames:
        end += len(frame)
        ends.append(end)
    assert not network.send_frames(data, ends)  # not batching: the caller sends each
    assert network.stats.frames_out == 0
    network.begin_batch()
    network.send_frame(0, b"\xfd" + bytes(300))
    assert network.send_frames(data, ends)
    network.end_batch()
    assert network.stats.frames_out == len(frames) + 1
    return [data for data, _ in network.datagrams_to_send(0.0)]


def test_a_batch_of_frames_leaves_in_the_datagrams_sending_one_by_one_would_fill() -> None:
    rng = random.Random(7)
    frames = [bytes([0xFD]) + rng.randbytes(rng.randint(11, 279)) for _ in range(400)]
    frames.append(b"\xfd" + bytes(MAX_BATCH_BYTES + 10))  # larger than a datagram: alone
    frames += [b"\xfd" + bytes(20)] * 3
    one_by_one = _one_by_one(frames)
    at_once = _at_once(frames)
    assert len(one_by_one) > 10
    assert at_once == one_by_one
    oversized = [d for d in at_once if len(d) > MAX_BATCH_BYTES]
    assert oversized == [b"\xfd" + bytes(MAX_BATCH_BYTES + 10)]  # the one frame too big
    assert b"".join(at_once) == b"\xfd" + bytes(300) + b"".join(frames)


def test_a_faulty_link_takes_no_batch_and_its_frames_go_through_the_gate() -> None:
    faults = LinkFaults.from_json({"seed": 3, "downlink": {"loss": 1.0}}, vehicle_ids=["d1"])
    gate = LinkGate(faults, ["d1"], lambda: (0.0, 0))
    assert gate.active
    network = NetworkProtocol([SINK], gate)
    network.open()
    network.begin_batch()
    frame = b"\xfd" + bytes(20)
    assert not network.send_frames(frame, [len(frame)])
    network.send_frame(0, frame)  # what the caller then does: the gate drops it
    network.end_batch()
    assert network.datagrams_to_send(0.0) == []
    assert gate.stats.dropped == 1

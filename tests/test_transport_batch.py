"""A batch of frames handed to the transport at once leaves in the same datagrams, byte for
byte, as the same frames emitted one by one (real UDP on 127.0.0.1)."""

from __future__ import annotations

import asyncio
import random
import socket
import time

from emulator.transport import MAX_BATCH_BYTES, UdpEndpoint


def _received(sink: socket.socket, count: int) -> list[bytes]:
    out: list[bytes] = []
    deadline = time.monotonic() + 5.0
    while len(out) < count and time.monotonic() < deadline:
        try:
            out.append(sink.recv(65536))
        except BlockingIOError:
            time.sleep(0.001)
    return out


async def _send_both_ways(frames: list[bytes], sink_port: int) -> tuple[int, int]:
    endpoint = UdpEndpoint([], [("127.0.0.1", sink_port)], time.monotonic, lambda: None)
    endpoint.open("127.0.0.1", 0)
    try:
        endpoint.batching = True
        endpoint.emit(0, b"\xfd" + bytes(300))  # a partly filled datagram before the batch
        for k, frame in enumerate(frames):
            endpoint.emit(k, frame)
        endpoint.batching = False
        endpoint.flush()
        one_by_one = endpoint.stats.datagrams_out
        data = b"".join(frames)
        ends, end = [], 0
        for frame in frames:
            end += len(frame)
            ends.append(end)
        assert not endpoint.emit_frames(data, ends)  # not batching: the caller emits each
        endpoint.batching = True
        endpoint.emit(0, b"\xfd" + bytes(300))
        assert endpoint.emit_frames(data, ends)
        endpoint.batching = False
        endpoint.flush()
        assert endpoint.stats.frames_out == 2 * (len(frames) + 1)
        return one_by_one, endpoint.stats.datagrams_out - one_by_one
    finally:
        endpoint.close()


def test_a_batch_of_frames_leaves_in_the_datagrams_emit_would_send() -> None:
    rng = random.Random(7)
    frames = [bytes([0xFD]) + rng.randbytes(rng.randint(11, 279)) for _ in range(400)]
    frames.append(b"\xfd" + bytes(MAX_BATCH_BYTES + 10))  # larger than a datagram: alone
    frames += [b"\xfd" + bytes(20)] * 3
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sink:
        sink.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 22)
        sink.bind(("127.0.0.1", 0))
        sink.setblocking(False)
        first, second = asyncio.run(_send_both_ways(frames, sink.getsockname()[1]))
        got = _received(sink, first + second)
    assert first == second > 10
    assert len(got) == first + second
    assert got[:first] == got[first:]
    assert all(len(d) <= MAX_BATCH_BYTES for d in got if len(d) < MAX_BATCH_BYTES + 10)
    assert b"".join(got[:first]) == b"\xfd" + bytes(300) + b"".join(frames)

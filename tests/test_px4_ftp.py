"""MAVLink FTP, in memory: the root, /log/ (the flight logs) and /metadata/ (component
metadata generated from the parameter definitions) listed and read, plain and in bursts;
write operations refused, unknown ones NAKed, bad sessions reported."""

from __future__ import annotations

import json
import math
import struct

from emulator.flight.params import PARAM_DEFINITIONS
from emulator.mavlink.ftp import FTP_HEADER_BYTES, Op
from mavlink_vocabulary import MavCmd
from tests.memory_link import MemoryLink


class Ftp:
    def __init__(self, link: MemoryLink) -> None:
        self.link, self.seq = link, 0

    def request(self, op: int, data: bytes = b"", *, session: int = 0, offset: int = 0,
                size: int | None = None) -> list[tuple[int, int, bytes, int, int]]:
        """(opcode, req_opcode, data, offset, burst_complete) of every reply."""
        self.seq += 1
        head = struct.pack("<HBBBBBBI", self.seq, session, op,
                           len(data) if size is None else size, 0, 0, 0, offset)
        payload = (head + data).ljust(251, b"\0")
        since = self.link.send(self.link.mav.file_transfer_protocol_encode(0, 1, 1,
                                                                            list(payload)))
        out = []
        for m in self.link.messages("FILE_TRANSFER_PROTOCOL", system=1, since=since):
            raw = bytes(m.payload)
            _, _, opcode, n, req, burst, _, at = struct.unpack_from("<HBBBBBBI", raw)
            out.append((opcode, req, raw[FTP_HEADER_BYTES:FTP_HEADER_BYTES + n], at, burst))
        return out

    def listing(self, path: str) -> list[str]:
        entries: list[str] = []
        while True:
            (opcode, _, data, _, _), = self.request(Op.LIST_DIRECTORY, path.encode(),
                                                    offset=len(entries))
            if opcode == Op.NAK:
                assert data == bytes([6])  # EOF
                return entries
            entries += [e for e in data.decode().split("\0") if e]

    def read(self, path: str, *, burst: bool) -> bytes:
        (opcode, _, data, _, _), = self.request(Op.OPEN_FILE_RO, path.encode())
        assert opcode == Op.ACK
        size = struct.unpack("<I", data)[0]
        content = bytearray()
        while len(content) < size:
            replies = self.request(Op.BURST_READ_FILE if burst else Op.READ_FILE,
                                   offset=len(content), size=239)
            for opcode, _, chunk, at, _ in replies:
                assert opcode == Op.ACK and at == len(content)
                content += chunk
        assert self.request(Op.TERMINATE_SESSION)[0][0] == Op.ACK
        return bytes(content)


def test_root_logs_and_metadata_are_listed_and_read() -> None:
    link = MemoryLink(1, telemetry=False)
    ftp = Ftp(link)
    assert ftp.listing("/") == ["Dlog", "Dmetadata"]
    assert ftp.listing("/log/") == []
    link.arm_and_take_off(1, 5.0)
    assert link.command_long(1, MavCmd.NAV_LAND, *[math.nan] * 7).result == 0
    link.advance(20.0)
    listing = ftp.listing("/log")
    assert len(listing) == 1 and listing[0].startswith("Fflight_0.ulg\t")
    size = int(listing[0].split("\t")[1])
    plain = ftp.read("/log/flight_0.ulg", burst=False)
    assert len(plain) == size and plain.startswith(b"ULog")
    assert ftp.read("/log/flight_0.ulg", burst=True) == plain
    assert plain == link.swarm.links[0].logs.files()[0]  # the log protocol's file
    names = [e.split("\t")[0] for e in ftp.listing("/metadata/")]
    assert names == ["Fcomponent_general.json", "Fparameters.json"]
    general = json.loads(ftp.read("/metadata/component_general.json", burst=True))
    assert general["metadataTypes"][0]["uri"] == "mftp:///metadata/parameters.json"
    parameters = json.loads(ftp.read("/metadata/parameters.json", burst=False))
    assert [p["name"] for p in parameters["parameters"]] == [d.name for d in PARAM_DEFINITIONS]


def test_refusals() -> None:
    ftp = Ftp(MemoryLink(1, telemetry=False))
    assert ftp.request(Op.OPEN_FILE_RO, b"/nope.txt")[0][:3] == (Op.NAK, Op.OPEN_FILE_RO,
                                                                 bytes([10]))
    assert ftp.request(Op.READ_FILE, session=3)[0][2] == bytes([4])  # invalid session
    assert ftp.request(7, b"/x")[0][2] == bytes([9])  # WriteFile: read-only file system
    assert ftp.request(200)[0][2] == bytes([7])  # unknown opcode
    for _ in range(4):
        assert ftp.request(Op.OPEN_FILE_RO, b"/metadata/parameters.json")[0][0] == Op.ACK
    assert ftp.request(Op.OPEN_FILE_RO, b"/metadata/parameters.json")[0][2] == bytes([5])
    assert ftp.request(Op.RESET_SESSIONS)[0][0] == Op.ACK
    assert ftp.request(Op.OPEN_FILE_RO, b"/metadata/parameters.json")[0][0] == Op.ACK
    assert ftp.request(Op.LIST_DIRECTORY, b"/metadata", offset=5)[0][2] == bytes([6])  # EOF

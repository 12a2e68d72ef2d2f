"""Link faults: what a degraded radio link does to each MAVLink frame, per vehicle and direction.

A `LinkProfile` says how one direction of one vehicle's link misbehaves: a loss rate, a latency
with jitter, duplication, reordering, and outage windows (simulated seconds, during which
nothing gets through). `LinkFaults` holds the profiles of a swarm (a default for every vehicle,
per-vehicle overrides) and a seed.

Each frame's fate is drawn from a hash of (seed, vehicle, direction, physics step, message id,
the frame's ordinal among frames of that message id in that step): the same command sent at
the same simulated time meets the same fate on every run, and its retransmissions (ordinals
1, 2, ...) meet theirs. Fates are decided in simulated time; the latency itself is wall time,
because the clients on the other end (MAVSDK, QGroundControl) time their retransmissions in
wall time. A lockstep clock is pinned while a client exchanges commands with a vehicle, so
latency costs wall time and never changes a simulated result.
"""

from __future__ import annotations

import hashlib
import math
import struct
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

__all__ = ["DIRECTIONS", "DOWNLINK", "UPLINK", "LinkFaultError", "LinkFaults", "LinkGate",
           "LinkProfile", "add_link_arguments", "link_faults_from_args"]

UPLINK, DOWNLINK = 0, 1  # ground -> vehicle, vehicle -> ground
DIRECTIONS = {"uplink": UPLINK, "downlink": DOWNLINK}
REORDER_HOLD_S = 0.03  # a reordered frame is held this much longer than its latency
DUPLICATE_GAP_S = 0.001
MAX_LATENCY_MS = 10_000.0
_PROFILE_KEYS = ("loss", "latency_ms", "jitter_ms", "duplicate", "reorder", "outages")


class LinkFaultError(ValueError):
    """A link fault setting that cannot be used; names the field."""


def _rate(where: str, name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) \
            or not (math.isfinite(value) and 0.0 <= value <= 1.0):
        raise LinkFaultError(f"{where}{name} must be a number within [0, 1], got {value!r}")
    return float(value)


def _ms(where: str, name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) \
            or not (math.isfinite(value) and 0.0 <= value <= MAX_LATENCY_MS):
        raise LinkFaultError(f"{where}{name} must be a number of milliseconds within "
                             f"[0, {MAX_LATENCY_MS:g}], got {value!r}")
    return float(value)


def _outages(where: str, value: object) -> tuple[tuple[float, float], ...]:
    if not isinstance(value, Sequence) or isinstance(value, str):
        raise LinkFaultError(f"{where}outages must be a list of [start_s, end_s] pairs")
    windows = []
    for i, pair in enumerate(value):
        ok = isinstance(pair, Sequence) and not isinstance(pair, str) and len(pair) == 2 and all(
            not isinstance(v, bool) and isinstance(v, int | float) for v in pair)
        start, end = (float(pair[0]), float(pair[1])) if ok else (math.nan, math.nan)
        if not (ok and math.isfinite(start) and start >= 0.0 and end > start):
            raise LinkFaultError(f"{where}outages[{i}] must be [start_s, end_s] with "
                                 f"0 <= start_s < end_s (simulated seconds), got {pair!r}")
        windows.append((start, end))
    return tuple(sorted(windows))


@dataclass(frozen=True, slots=True)
class LinkProfile:
    """One direction of one vehicle's link (see the module docstring)."""

    loss: float = 0.0  # fraction of frames dropped
    latency_ms: float = 0.0  # mean one-way delay (wall milliseconds)
    jitter_ms: float = 0.0  # the delay varies uniformly within +- this
    duplicate: float = 0.0  # fraction of frames delivered twice
    reorder: float = 0.0  # fraction of frames held back so later ones overtake them
    outages: tuple[tuple[float, float], ...] = ()  # [start_s, end_s) in simulated seconds

    @property
    def clean(self) -> bool:
        return not (self.loss or self.latency_ms or self.jitter_ms or self.duplicate
                    or self.reorder or self.outages)

    def in_outage(self, t_s: float) -> bool:
        return any(start <= t_s < end for start, end in self.outages)

    @classmethod
    def from_json(cls, raw: object, where: str = "", base: LinkProfile | None = None
                  ) -> LinkProfile:
        """A profile from {loss, latency_ms, jitter_ms, duplicate, reorder, outages}; fields
        not given keep `base`'s values."""
        if not isinstance(raw, Mapping):
            raise LinkFaultError(f"{where.rstrip('.') or 'link profile'} must be an object")
        unknown = sorted(set(raw) - set(_PROFILE_KEYS))
        if unknown:
            raise LinkFaultError(f"{where}{unknown[0]} is not a link setting (known: "
                                 f"{', '.join(_PROFILE_KEYS)})")
        p = base or cls()
        values: dict[str, Any] = {}
        for name in ("loss", "duplicate", "reorder"):
            if name in raw:
                values[name] = _rate(where, name, raw[name])
        for name in ("latency_ms", "jitter_ms"):
            if name in raw:
                values[name] = _ms(where, name, raw[name])
        if "outages" in raw:
            values["outages"] = _outages(where, raw["outages"])
        return replace(p, **values)

    def to_json(self) -> dict[str, Any]:
        return {"loss": self.loss, "latency_ms": self.latency_ms, "jitter_ms": self.jitter_ms,
                "duplicate": self.duplicate, "reorder": self.reorder,
                "outages": [list(w) for w in self.outages]}


@dataclass(frozen=True)
class LinkFaults:
    """The link profiles of a swarm: `uplink`/`downlink` for every vehicle, and overrides in
    `vehicles` (vehicle id -> (uplink, downlink))."""

    seed: int = 0
    uplink: LinkProfile = field(default_factory=LinkProfile)
    downlink: LinkProfile = field(default_factory=LinkProfile)
    vehicles: Mapping[str, tuple[LinkProfile, LinkProfile]] = field(default_factory=dict)

    @property
    def clean(self) -> bool:
        return self.uplink.clean and self.downlink.clean and all(
            up.clean and down.clean for up, down in self.vehicles.values())

    def profile(self, vehicle_id: str, direction: int) -> LinkProfile:
        pair = self.vehicles.get(vehicle_id)
        if pair is not None:
            return pair[direction]
        return self.uplink if direction == UPLINK else self.downlink

    @classmethod
    def from_json(cls, raw: object, where: str = "link_faults",
                  vehicle_ids: Sequence[str] | None = None) -> LinkFaults:
        """From a session file's ``link_faults`` object: profile fields apply to both
        directions, ``uplink``/``downlink`` objects to one, ``vehicles`` maps a drone id to
        the same structure (on top of the swarm's), ``seed`` seeds every fate."""
        if not isinstance(raw, Mapping):
            raise LinkFaultError(f"{where} must be an object")
        seed = raw.get("seed", 0)
        if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed < 2**63:
            raise LinkFaultError(f"{where}.seed must be a non-negative integer, got {seed!r}")
        up, down = _pair(raw, f"{where}.", LinkProfile(), LinkProfile(), allow=("seed",
                                                                               "vehicles"))
        vehicles: dict[str, tuple[LinkProfile, LinkProfile]] = {}
        per = raw.get("vehicles", {})
        if not isinstance(per, Mapping):
            raise LinkFaultError(f"{where}.vehicles must be an object of drone id -> settings")
        for vid, settings in per.items():
            if vehicle_ids is not None and vid not in vehicle_ids:
                raise LinkFaultError(f"{where}.vehicles: unknown drone {vid!r} (known: "
                                     f"{', '.join(vehicle_ids)})")
            if not isinstance(settings, Mapping):
                raise LinkFaultError(f"{where}.vehicles.{vid} must be an object")
            vehicles[str(vid)] = _pair(settings, f"{where}.vehicles.{vid}.", up, down)
        return cls(seed=seed, uplink=up, downlink=down, vehicles=vehicles)

    def to_json(self) -> dict[str, Any]:
        return {"seed": self.seed, "uplink": self.uplink.to_json(),
                "downlink": self.downlink.to_json(),
                "vehicles": {vid: {"uplink": u.to_json(), "downlink": d.to_json()}
                             for vid, (u, d) in self.vehicles.items()}}


def _pair(raw: Mapping[str, Any], where: str, up: LinkProfile, down: LinkProfile,
          allow: tuple[str, ...] = ()) -> tuple[LinkProfile, LinkProfile]:
    unknown = sorted(set(raw) - set(_PROFILE_KEYS) - set(DIRECTIONS) - set(allow))
    if unknown:
        raise LinkFaultError(f"{where}{unknown[0]} is not a link setting (known: "
                             f"{', '.join(_PROFILE_KEYS + tuple(DIRECTIONS) + allow)})")
    both = {k: v for k, v in raw.items() if k in _PROFILE_KEYS}
    up = LinkProfile.from_json(both, where, up)
    down = LinkProfile.from_json(both, where, down)
    if "uplink" in raw:
        up = LinkProfile.from_json(raw["uplink"], f"{where}uplink.", up)
    if "downlink" in raw:
        down = LinkProfile.from_json(raw["downlink"], f"{where}downlink.", down)
    return up, down


@dataclass(slots=True)
class GateStats:
    frames: int = 0
    dropped: int = 0
    duplicated: int = 0
    delayed: int = 0


class LinkGate:
    """Decides each frame's fate for a running swarm (see the module docstring).

    `clock()` gives (simulated seconds, physics step). `fate` returns None for "deliver now,
    untouched" (a clean link), else the wall-clock delays of the copies to deliver: () drops
    the frame, two delays duplicate it."""

    def __init__(self, faults: LinkFaults, vehicle_ids: Sequence[str],
                 clock: Callable[[], tuple[float, int]]) -> None:
        self._clock = clock
        self._ids = tuple(vehicle_ids)
        self.silenced: set[int] = set()  # vehicles whose MAVLink is off (failure injection)
        self.stats = GateStats()
        self._ordinal: dict[tuple[int, int, int], tuple[int, int]] = {}
        self.faults = faults
        self._profiles: list[tuple[LinkProfile, LinkProfile]] = []
        self.configure(faults)

    def configure(self, faults: LinkFaults) -> None:
        self.faults = faults
        self._profiles = [(faults.profile(v, UPLINK), faults.profile(v, DOWNLINK))
                          for v in self._ids]
        self._seed = struct.pack("<Q", faults.seed)
        self._clean = faults.clean

    def add_vehicle(self, vehicle_id: str) -> None:
        """One more vehicle (joining a running swarm), under the current settings."""
        self._ids = (*self._ids, vehicle_id)
        f = self.faults
        self._profiles.append((f.profile(vehicle_id, UPLINK), f.profile(vehicle_id, DOWNLINK)))

    @property
    def active(self) -> bool:
        """Any frame to decide (the transport skips the gate otherwise)."""
        return bool(self.silenced) or not self._clean

    def profile(self, k: int, direction: int) -> LinkProfile:
        return self._profiles[k][direction]

    def link_down(self, k: int, t_s: float) -> bool:
        """Vehicle k hears nothing from the ground at simulated time t_s."""
        if k in self.silenced:
            return True
        up = self._profiles[k][UPLINK]
        return up.loss >= 1.0 or up.in_outage(t_s)

    def fate(self, k: int, direction: int, msg_id: int) -> tuple[float, ...] | None:
        if k in self.silenced:
            self.stats.dropped += 1
            return ()
        p = self._profiles[k][direction]
        if p.clean:
            return None
        now_s, step = self._clock()
        self.stats.frames += 1
        if p.outages and p.in_outage(now_s):
            self.stats.dropped += 1
            return ()
        key = (k, direction, msg_id)
        last_step, count = self._ordinal.get(key, (-1, 0))
        ordinal = count if last_step == step else 0
        self._ordinal[key] = (step, ordinal + 1)
        digest = hashlib.blake2b(
            self._seed + struct.pack("<IBqII", k, direction, step, msg_id, ordinal),
            digest_size=16).digest()
        u_loss, u_jitter, u_reorder, u_dup = (
            v / 4294967296.0 for v in struct.unpack("<4I", digest))
        if u_loss < p.loss:
            self.stats.dropped += 1
            return ()
        delay_s = max(0.0, p.latency_ms + p.jitter_ms * (2.0 * u_jitter - 1.0)) / 1000.0
        if u_reorder < p.reorder:
            delay_s += REORDER_HOLD_S + p.latency_ms / 1000.0
        if delay_s > 0.0:
            self.stats.delayed += 1
        if u_dup < p.duplicate:
            self.stats.duplicated += 1
            return (delay_s, delay_s + DUPLICATE_GAP_S)
        return (delay_s,)

    def describe(self) -> str:
        """One line for `mavswarm up`."""
        f = self.faults
        parts = []
        for name, p in (("uplink", f.uplink), ("downlink", f.downlink)):
            if not p.clean:
                parts.append(f"{name} loss {p.loss:.0%}, latency {p.latency_ms:g} +- "
                             f"{p.jitter_ms:g} ms, duplicate {p.duplicate:.0%}, reorder "
                             f"{p.reorder:.0%}, {len(p.outages)} outage(s)")
        if f.vehicles:
            parts.append(f"{len(f.vehicles)} vehicle(s) with their own settings")
        return f"link faults (seed {f.seed}): " + ("; ".join(parts) or "none")


# ------------------------------------------------------------------ command line
def add_link_arguments(parser: Any) -> None:
    """The link fault options of `mavswarm up` and `mavswarm bench run`."""
    g = parser.add_argument_group("link faults (every vehicle; see docs/faults.md)")
    g.add_argument("--link-loss", type=float, default=None, metavar="RATE",
                   help="fraction of MAVLink frames lost, 0-1")
    g.add_argument("--link-latency-ms", type=float, default=None, metavar="MS",
                   help="one-way latency (wall milliseconds)")
    g.add_argument("--link-jitter-ms", type=float, default=None, metavar="MS",
                   help="latency varies uniformly within +- this (default 20 when a latency "
                        "is given)")
    g.add_argument("--link-duplicate", type=float, default=None, metavar="RATE",
                   help="fraction of frames delivered twice")
    g.add_argument("--link-reorder", type=float, default=None, metavar="RATE",
                   help="fraction of frames overtaken by later ones")
    g.add_argument("--link-outage", action="append", default=None, metavar="START:END",
                   help="simulated seconds with no link at all (repeatable)")
    g.add_argument("--link-direction", choices=("both", "uplink", "downlink"), default="both",
                   help="which direction the options apply to")
    g.add_argument("--link-seed", type=int, default=None, help="seed of every frame's fate")


DEFAULT_JITTER_MS = 20.0


def link_faults_from_args(args: Any, base: LinkFaults | None = None) -> LinkFaults | None:
    """LinkFaults from parsed options on top of `base` (a session's); None if neither."""
    settings: dict[str, Any] = {}
    for option, key in (("link_loss", "loss"), ("link_latency_ms", "latency_ms"),
                        ("link_jitter_ms", "jitter_ms"), ("link_duplicate", "duplicate"),
                        ("link_reorder", "reorder")):
        value = getattr(args, option, None)
        if value is not None:
            settings[key] = value
    if "latency_ms" in settings and "jitter_ms" not in settings:
        settings["jitter_ms"] = min(DEFAULT_JITTER_MS, settings["latency_ms"])
    outages = getattr(args, "link_outage", None)
    if outages:
        windows = []
        for text in outages:
            start, sep, end = str(text).partition(":")
            try:
                windows.append([float(start), float(end)])
            except ValueError:
                raise LinkFaultError(f"--link-outage {text!r}: give START:END in simulated "
                                     "seconds, e.g. 30:60") from None
            if not sep:
                raise LinkFaultError(f"--link-outage {text!r}: give START:END")
        settings["outages"] = windows
    seed = getattr(args, "link_seed", None)
    if not settings and seed is None:
        return base
    base = base or LinkFaults()
    where = "--link options: "
    direction = getattr(args, "link_direction", "both")

    def apply(up: LinkProfile, down: LinkProfile) -> tuple[LinkProfile, LinkProfile]:
        if direction in ("both", "uplink"):
            up = LinkProfile.from_json(settings, where, up)
        if direction in ("both", "downlink"):
            down = LinkProfile.from_json(settings, where, down)
        return up, down

    if seed is not None and not 0 <= seed < 2**63:
        raise LinkFaultError(f"--link-seed must be a non-negative integer, got {seed}")
    up, down = apply(base.uplink, base.downlink)
    vehicles = {v: apply(*pair) for v, pair in base.vehicles.items()}  # the options win
    return replace(base, seed=base.seed if seed is None else seed, uplink=up, downlink=down,
                   vehicles=vehicles)

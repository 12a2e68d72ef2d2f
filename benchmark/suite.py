"""The shipped benchmark suite (125 generated sessions under `benchmark/sessions/`) and its
named subsets, and generation of the whole suite."""

from __future__ import annotations

import functools
import multiprocessing
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from benchmark.scenarios import FAMILIES, LEVELS, SESSION_INDICES, all_session_keys, session_id

__all__ = ["SESSIONS_DIR", "SMOKE_TASKS", "SUITES", "Draw", "generate_suite", "suite_keys",
           "suite_paths"]

SESSIONS_DIR = Path(__file__).resolve().parent / "sessions"
SUITES = ("smoke", "full")
SMOKE_SESSIONS = ("area_search-easy-1", "area_assignment_and_patrol-easy-1",
                  "target_assignment-easy-1")
SMOKE_TASKS = 6


def suite_paths(name: str) -> tuple[tuple[Path, ...], int | None]:
    """The session files of a suite and its per-session task limit."""
    ids: tuple[str, ...]
    limit: int | None
    if name == "smoke":
        ids, limit = SMOKE_SESSIONS, SMOKE_TASKS
    elif name == "full":
        ids, limit = tuple(session_id(*key) for key in all_session_keys()), None
    else:
        raise ValueError(f"unknown suite {name!r}; choose one of {', '.join(SUITES)}")
    paths = tuple(SESSIONS_DIR / f"{i}.json" for i in ids)
    missing = [p.name for p in paths if not p.exists()]
    if missing:
        raise ValueError(f"suite {name!r}: missing session files in {SESSIONS_DIR}: "
                         f"{', '.join(missing[:5])}; run `mavswarm bench generate --out "
                         f"{SESSIONS_DIR}`")
    return paths, limit


@dataclass(frozen=True)
class Draw:
    """What a researcher's suite is drawn with (the defaults draw the shipped suite).

    secret: seeds a private split (same distribution, other sessions); families, levels:
    the cells (default all); sessions_per_cell: indices 1..N (default 5); tasks: per session;
    templates: template-file folders added to the built-ins (only them with replace)."""

    secret: str = ""
    families: tuple[str, ...] = ()
    levels: tuple[str, ...] = ()
    sessions_per_cell: int = 0
    tasks: int = 0
    templates: tuple[Path, ...] = ()
    replace: bool = False
    drones: int = 0
    map_size_m: float = 0.0

    @property
    def is_default(self) -> bool:
        return self == Draw()


def suite_keys(draw: Draw) -> list[tuple[str, str, int]]:
    """The (family, level, index) keys a draw generates, family-major."""
    for name in draw.families:
        if name not in FAMILIES:
            raise ValueError(f"--families: unknown family {name!r} (families: "
                             f"{', '.join(FAMILIES)})")
    for name in draw.levels:
        if name not in LEVELS:
            raise ValueError(f"--levels: unknown level {name!r} (levels: {', '.join(LEVELS)})")
    if draw.sessions_per_cell < 0 or draw.tasks < 0:
        raise ValueError("--sessions-per-cell and --tasks-per-session must be >= 1")
    from benchmark.scenarios.levels import LEVEL_SPECS, sized_spec
    sized_spec(LEVEL_SPECS["easy"], draw.drones, draw.map_size_m)  # a bad size: said first
    per_cell = draw.sessions_per_cell or len(SESSION_INDICES)
    families = [f for f in FAMILIES if not draw.families or f in draw.families]
    levels = [lv for lv in LEVELS if not draw.levels or lv in draw.levels]
    return [(f, lv, i) for f in families for lv in levels for i in range(1, per_cell + 1)]


def _generate_one(key: tuple[str, str, int], out_dir: Path, verify: bool,
                  mavsdk_log: bool = False,
                  progress: Callable[[str], None] = print, draw: Draw = Draw()) -> Path:
    from benchmark.generate import (
        TASKS_PER_SESSION,
        catalogue_with,
        generate_session,
        write_session,
    )
    from mavlink_gateway import set_mavsdk_log
    set_mavsdk_log(mavsdk_log)
    catalogue = catalogue_with(draw.templates, replace=draw.replace)
    from benchmark.scenarios.placement import PlacementError
    try:
        session = generate_session(*key, verify=verify, progress=progress, secret=draw.secret,
                                   tasks=draw.tasks or TASKS_PER_SESSION, catalogue=catalogue,
                                   max_index=max(key[2], SESSION_INDICES[-1]),
                                   drones=draw.drones, map_size_m=draw.map_size_m)
    except PlacementError as error:
        if not (draw.drones or draw.map_size_m):
            raise
        raise ValueError(f"{error}: the level's entities do not fit; choose a larger "
                         f"--map-size-m or fewer --drones") from None
    return write_session(session, out_dir)


def _print_generated(path: Path) -> None:
    print(f"generated {path}", flush=True)


def generate_suite(out_dir: Path, *, only: Sequence[str] | None = None, verify: bool = True,
                   workers: int = 1, backend: str = "local", ray_address: str = "",
                   mavsdk_log: bool = False,
                   on_start: Callable[[int], None] | None = None,
                   on_generated: Callable[[Path], None] = _print_generated,
                   progress: Callable[[str], None] = print, draw: Draw = Draw()
                   ) -> list[Path]:
    """Generate the suite's session files (all 125, or the ids in `only`) into out_dir, in
    `workers` local processes or, with backend "ray", as Ray tasks (benchmark/backends.py).
    `on_start(n)` is told how many sessions will be generated, `on_generated(path)` each file
    as it is written, and `progress` (in this process) each redrawn task; `mavsdk_log`
    prints MAVSDK's own log lines."""
    keys = list(all_session_keys()) if draw.is_default else suite_keys(draw)
    if draw.templates:
        from benchmark.generate import catalogue_with
        catalogue_with(draw.templates, replace=draw.replace)  # bad files: said before any work
    if only:
        wanted = set(only)
        unknown = wanted - {f"{k[0]}-{k[1]}-{k[2]}" for k in keys}
        if unknown:
            raise ValueError(f"unknown session ids: {', '.join(sorted(unknown))}")
        keys = [k for k in keys if f"{k[0]}-{k[1]}-{k[2]}" in wanted]
    if on_start is not None:
        on_start(len(keys))
    if backend != "local" or ray_address:
        if not draw.is_default:
            raise ValueError("--backend ray draws the shipped suite only; drop --seed, "
                             "--families, --levels, --sessions-per-cell, --tasks-per-session "
                             "and --templates, or generate locally")
        from benchmark.backends import make_backend
        make_backend(backend, workers=workers, ray_address=ray_address)  # says what is wrong
        from benchmark.ray_backend import generate_on_ray
        return generate_on_ray(keys, out_dir, verify=verify, workers=workers,
                               address=ray_address, on_generated=on_generated)
    if workers <= 1:
        written = []
        for key in keys:
            path = _generate_one(key, out_dir, verify, mavsdk_log, progress, draw)
            on_generated(path)
            written.append(path)
        return written
    ctx = multiprocessing.get_context("spawn")
    one = functools.partial(_generate_one, out_dir=out_dir, verify=verify,
                            mavsdk_log=mavsdk_log, draw=draw)
    with ctx.Pool(workers) as pool:
        results = [pool.apply_async(one, (k,)) for k in keys]
        written = []
        for result in results:
            path = result.get()
            on_generated(path)
            written.append(path)
    return written

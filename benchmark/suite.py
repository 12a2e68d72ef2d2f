"""The shipped benchmark suite (125 generated sessions under `benchmark/sessions/`) and its
named subsets, and generation of the whole suite."""

from __future__ import annotations

import functools
import multiprocessing
from collections.abc import Callable, Sequence
from pathlib import Path

from benchmark.scenarios import all_session_keys, session_id

__all__ = ["SESSIONS_DIR", "SMOKE_TASKS", "SUITES", "generate_suite", "suite_paths"]

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


def _generate_one(key: tuple[str, str, int], out_dir: Path, verify: bool,
                  mavsdk_log: bool = False,
                  progress: Callable[[str], None] = print) -> Path:
    from benchmark.generate import generate_session, write_session
    from mavlink_gateway import set_mavsdk_log
    set_mavsdk_log(mavsdk_log)
    session = generate_session(*key, verify=verify, progress=progress)
    return write_session(session, out_dir)


def _print_generated(path: Path) -> None:
    print(f"generated {path}", flush=True)


def generate_suite(out_dir: Path, *, only: Sequence[str] | None = None, verify: bool = True,
                   workers: int = 1, backend: str = "local", ray_address: str = "",
                   mavsdk_log: bool = False,
                   on_start: Callable[[int], None] | None = None,
                   on_generated: Callable[[Path], None] = _print_generated,
                   progress: Callable[[str], None] = print) -> list[Path]:
    """Generate the suite's session files (all 125, or the ids in `only`) into out_dir, in
    `workers` local processes or, with backend "ray", as Ray tasks (benchmark/backends.py).
    `on_start(n)` is told how many sessions will be generated, `on_generated(path)` each file
    as it is written, and `progress` (in this process) each redrawn task; `mavsdk_log`
    prints MAVSDK's own log lines."""
    keys = list(all_session_keys())
    if only:
        wanted = set(only)
        unknown = wanted - {session_id(*k) for k in keys}
        if unknown:
            raise ValueError(f"unknown session ids: {', '.join(sorted(unknown))}")
        keys = [k for k in keys if session_id(*k) in wanted]
    if on_start is not None:
        on_start(len(keys))
    if backend != "local" or ray_address:
        from benchmark.backends import make_backend
        make_backend(backend, workers=workers, ray_address=ray_address)  # says what is wrong
        from benchmark.ray_backend import generate_on_ray
        return generate_on_ray(keys, out_dir, verify=verify, workers=workers,
                               address=ray_address, on_generated=on_generated)
    if workers <= 1:
        written = []
        for key in keys:
            path = _generate_one(key, out_dir, verify, mavsdk_log, progress)
            on_generated(path)
            written.append(path)
        return written
    ctx = multiprocessing.get_context("spawn")
    one = functools.partial(_generate_one, out_dir=out_dir, verify=verify,
                            mavsdk_log=mavsdk_log)
    with ctx.Pool(workers) as pool:
        results = [pool.apply_async(one, (k,)) for k in keys]
        written = []
        for result in results:
            path = result.get()
            on_generated(path)
            written.append(path)
    return written

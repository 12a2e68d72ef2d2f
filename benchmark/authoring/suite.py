"""The shipped benchmark suite (125 generated sessions under `benchmark/sessions/`), its
named subsets, and what a researcher's suite is drawn with (its generation, proved by the
oracle, is benchmark.running.generation)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from benchmark.authoring.scenarios import (
    FAMILIES,
    LEVELS,
    SESSION_INDICES,
    all_session_keys,
    session_id,
)
from benchmark.authoring.scenarios.levels import LEVEL_SPECS, sized_spec

__all__ = ["SESSIONS_DIR", "SMOKE_TASKS", "SUITES", "Draw", "suite_keys", "suite_paths"]

SESSIONS_DIR = Path(__file__).resolve().parent.parent / "sessions"
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
    sized_spec(LEVEL_SPECS["easy"], draw.drones, draw.map_size_m)  # a bad size: said first
    per_cell = draw.sessions_per_cell or len(SESSION_INDICES)
    families = [f for f in FAMILIES if not draw.families or f in draw.families]
    levels = [lv for lv in LEVELS if not draw.levels or lv in draw.levels]
    return [(f, lv, i) for f in families for lv in levels for i in range(1, per_cell + 1)]

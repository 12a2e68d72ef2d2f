"""A benchmark worker process gives the large blocks a task frees back to the system."""

from __future__ import annotations

import platform

import pytest

from benchmark.running.backends import LocalBackend, Message, Unit
from benchmark.running.worker_heap import return_large_blocks

GLIBC = platform.system() == "Linux" and platform.libc_ver()[0] == "glibc"


def _rss_mb() -> float:
    with open("/proc/self/status", encoding="ascii") as f:
        return next(int(line.split()[1]) for line in f if line.startswith("VmRSS")) / 1024.0


def churn(unit: Unit, handle: object) -> None:
    """What a session does to the heap: a large array freed, then many middling ones made
    and freed among small blocks that stay. Reports the MB still held once they are freed."""
    import numpy as np
    assert callable(handle)
    np.ones((8 << 20) // 8).sum()  # 8 MiB, freed at once
    before = _rss_mb()
    middling, small = [], []
    for _ in range(64):
        middling.append(np.ones((1 << 20) // 8))  # 1 MiB each
        small.append(np.ones(1024))  # 8 KiB, kept
    middling.clear()
    handle(("record", {"path": unit.path, "held_mb": _rss_mb() - before,
                       "small": len(small)}))


class _Hosted:
    """Work a worker process hosts several at once (benchmark.running.backends._host)."""

    def __call__(self, unit: Unit, handle: object) -> None:
        churn(unit, handle)

    async def hosted(self, unit: Unit, handle: object) -> None:
        churn(unit, handle)


def _held_mb(backend: LocalBackend, work: object) -> list[tuple[str, int]]:
    messages: list[Message] = []
    backend.run(work, [Unit("a", 0), Unit("b", 0)], messages.append)  # type: ignore[arg-type]
    held = sorted((m[1]["path"], round(m[1]["held_mb"])) for m in messages)
    assert [path for path, _ in held] == ["a", "b"], messages
    return held


@pytest.mark.skipif(not GLIBC, reason="the threshold is a glibc malloc setting")
def test_a_worker_hosting_several_units_returns_the_large_blocks_it_frees() -> None:
    held = _held_mb(LocalBackend(workers=2, cores=1, shared=True), _Hosted())
    # 64 MiB were freed; before, the worker kept nearly all of them (the freed 8 MiB array
    # had raised glibc's threshold, so the 1 MiB arrays came from the heap between the
    # small blocks that stay)
    assert all(mb < 16 for _, mb in held), held


@pytest.mark.skipif(not GLIBC, reason="the threshold is a glibc malloc setting")
def test_a_worker_of_one_unit_at_a_time_keeps_glibcs_own_threshold() -> None:
    # A process per unit keeps what it frees for its next arrays (no page faults to map
    # them again): the same churn leaves most of the 64 MiB with it.
    held = _held_mb(LocalBackend(workers=2), churn)
    assert all(mb > 32 for _, mb in held), held


@pytest.mark.skipif(not GLIBC, reason="the threshold is a glibc malloc setting")
def test_the_setting_is_taken_by_glibc() -> None:
    assert return_large_blocks() is True


def test_a_threshold_below_one_byte_is_refused() -> None:
    with pytest.raises(ValueError, match="threshold_bytes must be >= 1, got 0"):
        return_large_blocks(0)

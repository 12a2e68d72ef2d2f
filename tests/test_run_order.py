"""The order a run with several workers starts its sessions in: the longest first."""

from __future__ import annotations

import json
from pathlib import Path

from benchmark.running.run_order import SessionHead, session_heads
from benchmark.running.run_order import run_order as _run_order


def run_order(paths: list[Path], agent: str) -> list[Path]:
    return _run_order(paths, session_heads(paths), agent)


def _session(folder: Path, name: str, drones: int, calls_per_task: list[int]) -> Path:
    path = folder / f"{name}.json"
    path.write_text(json.dumps({
        "id": name,
        "drones": [{"id": f"d{i}"} for i in range(drones)],
        "tasks": [{"id": f"t{i}", "budget": {"tool_calls": calls}}
                  for i, calls in enumerate(calls_per_task)],
    }), encoding="utf-8")
    return path


def test_an_instant_agent_starts_the_largest_fleets_first(tmp_path: Path) -> None:
    small = _session(tmp_path, "small", 3, [500, 500])  # the most calls, the fewest drones
    large = _session(tmp_path, "large", 30, [10])
    middle = _session(tmp_path, "middle", 10, [50])
    assert run_order([small, large, middle], "oracle") == [large, middle, small]
    assert run_order([small, large, middle], "noop") == [large, middle, small]


def test_an_agent_that_thinks_starts_the_longest_chains_of_calls_first(tmp_path: Path) -> None:
    small = _session(tmp_path, "small", 3, [500, 500])
    large = _session(tmp_path, "large", 30, [10])
    middle = _session(tmp_path, "middle", 10, [50])
    tied = _session(tmp_path, "tied", 16, [50])  # as many calls as middle, more drones
    order = run_order([large, middle, small, tied], "react")
    assert order == [small, tied, middle, large]
    assert run_order([large, small], "external") == [small, large]


def test_unreadable_or_odd_files_sort_last_and_keep_their_order(tmp_path: Path) -> None:
    broken = tmp_path / "broken.json"
    broken.write_text("{not json", encoding="utf-8")
    odd = tmp_path / "odd.json"
    odd.write_text(json.dumps({"tasks": [{"budget": {"tool_calls": True}}, "x", {}],
                               "drones": "many"}), encoding="utf-8")
    missing = tmp_path / "missing.json"
    real = _session(tmp_path, "real", 3, [5])
    assert run_order([broken, odd, missing, real], "react") == [real, broken, odd, missing]
    assert run_order([broken, odd, missing, real], "oracle") == [real, broken, odd, missing]
    heads = session_heads([broken, odd, real])
    assert heads[broken] == SessionHead(None, 0, 0, 0)
    assert heads[odd] == SessionHead(None, 3, 0, 0)
    assert heads[real] == SessionHead("real", 1, 3, 5)

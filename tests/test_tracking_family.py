"""The target_tracking family: its worlds' moving targets stay clear of obstacles, and its
tracking templates are passed by the oracle (which reads the hidden motion, over MAVLink in
lockstep time), the same way twice, and by nothing that does not fly."""

from __future__ import annotations

from pathlib import Path

import pytest
import shapely

from benchmark.authoring.scenarios import LEVELS, generate_world
from benchmark.authoring.session_file import session_from_dict
from benchmark.authoring.templates.tracking import TEMPLATES, track_points
from benchmark.running.orchestrator import RunPlan, run_benchmark
from benchmark.running.results import read_records
from tests.bench_fixtures import small_session, write_json

KEYS = [t.key for t in TEMPLATES]


@pytest.mark.parametrize("level", LEVELS)
def test_moving_targets_run_on_tracks_clear_of_obstacles_inside_the_map(level: str) -> None:
    for index in (1, 2):
        world = generate_world("target_tracking", level, index)
        scenario = session_from_dict({**world, "tasks": []}).scenario
        width, height = world["map_size_m"]
        movers = [t for t in scenario.world.targets if t.kind == "moving"]
        assert movers and all(t.motion is not None for t in movers)
        assert {t.motion.mode for t in movers if t.motion} <= {"velocity", "path"}
        for target in movers:
            track = shapely.LineString(track_points(target)).buffer(target.radius_m)
            assert all(o.footprint.distance(track) >= 14.0 for o in scenario.world.obstacles)
            x0, y0, x1, y1 = track.bounds
            assert min(x0, y0) >= 0.0 and x1 <= width and y1 <= height


def _measured(record: dict) -> tuple:
    return (record["task"], record["sim_time_s"], record["end_state"],
            tuple((c["endpoint"], c["value"]) for c in record["checks"]))


@pytest.mark.mavsdk
def test_the_oracle_passes_every_tracking_template_and_noop_none(tmp_path: Path) -> None:
    path = write_json(tmp_path / "tracking.json",
                      small_session(KEYS, family="target_tracking", seed=3))
    records: dict[str, list[dict]] = {}
    for agent, out in (("oracle", "oracle"), ("oracle", "again"), ("noop", "noop")):
        run_benchmark(RunPlan(sessions=(path,), agent=agent, out_dir=tmp_path / out),
                      progress=print)
        records[out] = read_records(tmp_path / out / "results.jsonl")
    failed = [(r["template"], [c for c in r["checks"] if not c["passed"]])
              for r in records["oracle"] if not r["passed"]]
    assert not failed, failed
    assert sorted(r["template"] for r in records["oracle"]) == sorted(KEYS)
    # Same seed, same truth: a second run measures the very same values.
    assert [_measured(r) for r in records["oracle"]] == [_measured(r) for r in records["again"]]
    assert not any(r["passed"] for r in records["noop"])
    assert all(r["checks_passed"] == 0 for r in records["noop"])

"""How long `mavswarm bench compare` takes on five runs of the full suite.

    ./dev perf compare_speed [--runs 5] [--resamples 2000]

Synthesises one results.jsonl per run from the shipped suite's task list (125 sessions, 2,500
tasks, their real check endpoints), each run with its own seeded pass probability per task
and session, then times loading, comparing and writing compare.md/.json/.html, as the command
does. Prints the seconds of each phase and the sizes of what was written. Target: under 10 s.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _common import machine_line, table

from benchmark.authoring.suite import suite_paths
from benchmark.reporting.compare import compare_paths, write_compare


def _leaves(node: Any) -> Iterator[str]:
    if isinstance(node, dict):
        if "endpoint" in node:
            yield str(node["endpoint"])
        for child in node.get("checks", []):
            yield from _leaves(child)


def suite_tasks() -> list[dict[str, Any]]:
    """(session, family, level, task, template, category, leaf endpoints) of the full suite."""
    paths, _ = suite_paths("full")
    tasks = []
    for path in paths:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
        for task in data["tasks"]:
            tasks.append({"session": data["id"], "family": data["family"],
                          "level": data["level"], "task": task["id"],
                          "template": task["template"], "category": task["category"],
                          "endpoints": list(_leaves(task["checks"]))})
    return tasks


def write_run(folder: Path, agent: str, skill: float, tasks: list[dict[str, Any]]) -> Path:
    """One synthetic run: a task passes with a probability set by the agent's skill and the
    session's difficulty; its leaf checks pass at a matching rate."""
    rng = random.Random(agent)
    folder.mkdir(parents=True)
    lines = []
    session_ease: dict[str, float] = {}
    for t in tasks:
        ease = session_ease.setdefault(t["session"], rng.uniform(-0.15, 0.15))
        p = min(0.98, max(0.02, skill + ease))
        checks = [{"path": f"checks[{k}]", "endpoint": e, "passed": rng.random() < p + 0.1}
                  for k, e in enumerate(t["endpoints"])]
        passed = all(c["passed"] for c in checks) and rng.random() < p
        tokens = {"prompt": rng.randint(2000, 9000), "completion": rng.randint(100, 900),
                  "cost_usd": 0.001}
        record = {"key": f"{t['session']}/{t['task']}/{agent}/0", "session": t["session"],
                  "family": t["family"], "level": t["level"], "task": t["task"],
                  "template": t["template"], "category": t["category"], "agent": agent,
                  "trial": 0, "passed": passed, "checks": checks,
                  "checks_total": len(checks),
                  "checks_passed": sum(c["passed"] for c in checks), "finish": "finished",
                  "error": None, "tool_calls": rng.randint(1, 30), "clock": "lockstep",
                  "sim_time_s": round(rng.uniform(10, 400), 3),
                  "wall_time_s": round(rng.uniform(1, 60), 3), "tokens": tokens}
        lines.append(json.dumps(record))
    path = folder / "results.jsonl"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--resamples", type=int, default=2000)
    args = parser.parse_args()
    print(machine_line())
    tasks = suite_tasks()
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        started = time.perf_counter()
        folders = [root / f"agent{k}" for k in range(args.runs)]
        for k, folder in enumerate(folders):
            write_run(folder, f"agent{k}", 0.35 + 0.08 * k, tasks)
        synth_s = time.perf_counter() - started
        started = time.perf_counter()
        report = compare_paths(folders, resamples=args.resamples)
        compare_s = time.perf_counter() - started
        started = time.perf_counter()
        paths = write_compare(report, root / "out")
        write_s = time.perf_counter() - started
        sizes = {p.name: p.stat().st_size for p in paths}
    total = compare_s + write_s
    print(f"{args.runs} runs x {len(tasks)} tasks ({len({t['session'] for t in tasks})} "
          f"sessions), {args.resamples} bootstrap resamples; records synthesised in "
          f"{synth_s:.2f} s (not counted)")
    print(table(("phase", "seconds"), [("load + compare", f"{compare_s:.2f}"),
                                       ("write md/json/html", f"{write_s:.2f}"),
                                       ("total", f"{total:.2f}")]))
    print("written: " + ", ".join(f"{name} {size / 1024:.0f} KiB" for name, size in
                                  sizes.items()))
    for pair in report.pairs:
        t = pair.overall
        print(f"  {pair.run} vs {pair.baseline}: +{t.fail_to_pass} -{t.pass_to_fail}, "
              f"p = {t.mcnemar_p:.2g}, diff {pair.task_pass_rate_diff.value * 100:+.1f} pp "
              f"[{pair.task_pass_rate_diff.low * 100:+.1f}, "
              f"{pair.task_pass_rate_diff.high * 100:+.1f}]")
    print(f"target: under 10 s -> {'met' if total < 10.0 else 'NOT met'}")


if __name__ == "__main__":
    main()

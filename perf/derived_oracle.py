"""How often the oracle passes the shipped suite with plans derived from the checks alone
(hand-written plans off: MAVSWARM_ORACLE=derived).

    python perf/derived_oracle.py                 # stratified: 1 session per family x level
    python perf/derived_oracle.py --index 2 4     # other strata
    python perf/derived_oracle.py --full          # all 125 sessions (slow)

Prints the pass rate overall, per category and per template, and every failed task with its
failed checks (or the leaf the planner could not plan).
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SESSIONS = ROOT / "benchmark" / "sessions"


def _files(full: bool, indices: list[int]) -> list[Path]:
    files = sorted(SESSIONS.glob("*.json"))
    if full:
        return files
    return [f for f in files if int(f.stem.rsplit("-", 1)[1]) in indices]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--full", action="store_true", help="every session of the suite")
    parser.add_argument("--index", type=int, nargs="+", default=[1],
                        help="stratified sample: the sessions of these indices in every "
                             "family x level cell (1-5)")
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--mode", choices=("derived", "hand"), default="derived")
    args = parser.parse_args()
    files = _files(args.full, sorted(set(args.index)))
    env = {**os.environ, "MAVSWARM_ORACLE": args.mode,
           "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT),
                                                       os.environ.get("PYTHONPATH", "")]))}
    with tempfile.TemporaryDirectory() as tmp:
        wall0 = time.perf_counter()
        subprocess.run([sys.executable, "-m", "mavswarm", "bench", "run", "--agent", "oracle",
                        "--workers", str(args.workers), "--out", tmp, "--sessions",
                        *map(str, files)], env=env, check=True, cwd=ROOT,
                       stdout=subprocess.DEVNULL)
        wall_s = time.perf_counter() - wall0
        records = [json.loads(line) for line in
                   (Path(tmp) / "results.jsonl").read_text().splitlines() if line.strip()]
    by_cat: dict[str, list[bool]] = collections.defaultdict(list)
    by_tpl: dict[str, list[bool]] = collections.defaultdict(list)
    for r in records:
        by_cat[r["category"]].append(r["passed"])
        by_tpl[r["template"]].append(r["passed"])
    passed = sum(r["passed"] for r in records)
    scope = "full suite" if args.full else (
        f"stratified sample (index {', '.join(map(str, sorted(set(args.index))))})")
    print(f"oracle ({args.mode} plans), {scope}: {len(files)} sessions, {len(records)} tasks, "
          f"{wall_s:.0f} s wall")
    print(f"passed {passed}/{len(records)} = {100.0 * passed / max(len(records), 1):.1f} %")
    print("per category:")
    for cat, results in sorted(by_cat.items()):
        print(f"  {cat:28s} {sum(results):4d}/{len(results):<4d}")
    print("templates below 100 %:")
    for tpl, results in sorted(by_tpl.items()):
        if not all(results):
            print(f"  {tpl:32s} {sum(results):4d}/{len(results):<4d}")
    print("failed tasks:")
    for r in records:
        if not r["passed"]:
            failed = [c["endpoint"] for c in r["checks"] if not c["passed"]]
            print(f"  {r['session']} {r['task']} {r['template']}: {r['finish']} "
                  f"{(r.get('error') or '')[:160]} failed {failed}")


if __name__ == "__main__":
    main()

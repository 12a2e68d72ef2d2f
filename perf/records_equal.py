"""Do two benchmark runs hold the same results but for wall-clock time? Compares every task
record of two results folders (`bench run --out`) without the wall-time fields, and every
stored replay (the task window's ground truth and tool calls).

    ./dev perf records_equal runs/before runs/after

Prints the number of records and replays compared, a SHA-256 of each side's stable records,
and every difference; exits 1 when there is one. Run the same sessions before and after a
speed change (for instance with --workers 1 before and --workers auto after).
"""

from __future__ import annotations

import argparse
import gzip
import hashlib
import json
import sys
from pathlib import Path
from typing import Any

WALL_FIELDS = ("wall_time_s", "overhead_s")


def stable_records(folder: Path) -> dict[str, dict[str, Any]]:
    records = {}
    for line in (folder / "results.jsonl").read_text(encoding="utf-8").splitlines():
        if line.strip():
            record = json.loads(line)
            records[record["key"]] = {k: v for k, v in record.items() if k not in WALL_FIELDS}
    return records


def replays(folder: Path) -> dict[str, Any]:
    return {str(p.relative_to(folder)): json.loads(gzip.decompress(p.read_bytes()))
            for p in sorted((folder / "replay").rglob("*.json.gz"))}


def digest(records: dict[str, dict[str, Any]]) -> str:
    text = json.dumps([records[k] for k in sorted(records)], sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("before", type=Path)
    p.add_argument("after", type=Path)
    args = p.parse_args()
    a, b = stable_records(args.before), stable_records(args.after)
    ra, rb = replays(args.before), replays(args.after)
    problems = [f"only in {args.before}: {k}" for k in sorted(a.keys() - b.keys())]
    problems += [f"only in {args.after}: {k}" for k in sorted(b.keys() - a.keys())]
    for key in sorted(a.keys() & b.keys()):
        fields = sorted(f for f in a[key].keys() | b[key].keys()
                        if a[key].get(f) != b[key].get(f))
        if fields:
            problems.append(f"record {key} differs in {', '.join(fields)}")
    problems += [f"replay {k} differs or is missing" for k in sorted(ra.keys() | rb.keys())
                 if ra.get(k) != rb.get(k)]
    passed = sum(bool(r.get("passed")) for r in a.values())
    print(f"{len(a)} / {len(b)} records ({passed} passed), {len(ra)} / {len(rb)} replays; "
          f"stable records sha256 {digest(a)} / {digest(b)}")
    for line in problems[:50]:
        print("  " + line)
    print("equal but for wall time" if not problems else f"{len(problems)} difference(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())

"""How long `bench generate` takes: the whole 125-session suite drawn without proving, and
drawn with every task proved by the oracle (timed on a stratified sample of sessions and
extrapolated to 125, said so in the output).

    python perf/generate_speed.py                      # draw all 125, prove 5 sampled
    python perf/generate_speed.py --prove-sessions 10  # a larger sample
    python perf/generate_speed.py --prove-sessions 125 # prove the whole suite (slow)

Sessions are generated one after another in this process (`--workers 1`); proved sessions are
compared byte for byte with the shipped files (they must be equal).
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from benchmark.authoring.scenarios import FAMILIES, LEVELS, all_session_keys  # noqa: E402
from benchmark.authoring.session_file import dump_session  # noqa: E402
from benchmark.authoring.suite import SESSIONS_DIR  # noqa: E402
from benchmark.running.generation import generate_session  # noqa: E402
from mavlink_gateway import set_mavsdk_log  # noqa: E402


def _sample(count: int) -> list[tuple[str, str, int]]:
    """count keys spread over families, levels and indices: the k-th takes family k mod 5,
    level (k + k div 5) mod 5 and index 1 + k div 25 (so 5 keys cover every family and
    every level, 25 every cell)."""
    keys = list(all_session_keys())
    if count >= len(keys):
        return keys
    return [(FAMILIES[k % 5], LEVELS[(k + k // 5) % 5], 1 + (k // 25) % 5)
            for k in range(count)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--prove-sessions", type=int, default=5, metavar="K",
                        help="sessions generated with proving (a stratified sample; 125: all)")
    args = parser.parse_args()
    set_mavsdk_log(False)
    quiet = lambda _line: None  # noqa: E731
    keys = list(all_session_keys())
    t0 = time.perf_counter()
    for key in keys:
        generate_session(*key, verify=False, progress=quiet)
    draw_s = time.perf_counter() - t0
    print(f"cores: {os.cpu_count()}")
    print(f"drawn without proving: {len(keys)} sessions in {draw_s:.1f} s "
          f"({1000 * draw_s / len(keys):.0f} ms per session)")
    times, same = [], 0
    sample = _sample(args.prove_sessions)
    for key in sample:
        t1 = time.perf_counter()
        session = generate_session(*key, verify=True, progress=quiet)
        times.append(time.perf_counter() - t1)
        shipped = SESSIONS_DIR / f"{session['id']}.json"
        same += shipped.read_text(encoding="utf-8") == dump_session(session)
        print(f"  proved {session['id']}: {times[-1]:.1f} s", flush=True)
    total = sum(times)
    mean = statistics.fmean(times)
    print(f"proved: {len(sample)} sessions in {total:.1f} s (mean {mean:.1f} s, max "
          f"{max(times):.1f} s); {same} of {len(sample)} equal to the shipped files byte "
          f"for byte")
    if len(sample) < len(keys):
        print(f"extrapolated to {len(keys)} sessions: {mean * len(keys) / 60:.1f} min with 1 "
              f"worker, {mean * len(keys) / 60 / 2:.1f} min with --workers 2 "
              f"(from {len(sample)} sampled sessions)")


if __name__ == "__main__":
    main()

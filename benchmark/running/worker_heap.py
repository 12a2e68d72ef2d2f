"""The C heap of a process that hosts benchmark sessions: large blocks go back when freed.

glibc's malloc serves a block of at least its mmap threshold (128 KiB to start with) from a
mapping of its own, which it returns to the system when the block is freed; but each time
such a block is freed it raises the threshold to that block's size (up to 32 MiB). A session
frees large numpy arrays all the time (the oracle's routing grids and searches, the ground
truth's chunks joined for an evaluation, a replay's window), so soon every array up to
several MiB comes from the heap instead, and what a session frees there mostly stays with the
process: ten sessions hosted in two workers held 45.5 MB each at their peak, 32.2 MB with the
threshold fixed (`perf/think_latency.py`, docs/performance.md). Setting the threshold fixes it
where it starts (glibc then stops moving it), so freed large blocks leave the process again.
A worker that runs one session at a time (an agent that answers at once) keeps glibc's own
threshold instead: memory is not what limits it, and it reuses what it frees without mapping
the pages again and faulting them in (the oracle's 25 `-1` sessions: 4-10 % less CPU).
"""

from __future__ import annotations

import ctypes

__all__ = ["LARGE_BLOCK_BYTES", "return_large_blocks"]

M_MMAP_THRESHOLD = -3  # glibc's mallopt parameter
LARGE_BLOCK_BYTES = 128 * 1024  # glibc's own starting threshold


def return_large_blocks(threshold_bytes: int = LARGE_BLOCK_BYTES) -> bool:
    """Serve every block of at least `threshold_bytes` from a mapping of its own, returned to
    the system when freed, for the rest of this process. True when the C library took the
    setting (glibc); False where it has no such setting (nothing changes then)."""
    if threshold_bytes < 1:
        raise ValueError(f"threshold_bytes must be >= 1, got {threshold_bytes}")
    try:
        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError, TypeError):  # no C library to load, or no mallopt
        return False
    mallopt.argtypes = [ctypes.c_int, ctypes.c_int]
    mallopt.restype = ctypes.c_int
    return bool(mallopt(M_MMAP_THRESHOLD, threshold_bytes))

"""`mavswarm bench run --agent external`: the driver hosts the run. Its endpoint is started
before the units, told of every task they offer or end, and answers 204 once they are all
done; the run itself (records, resume, reports) is `run_benchmark`'s, as for any agent."""

from __future__ import annotations

import contextlib
import functools
import time
from collections.abc import Callable, Iterator
from typing import Any

from benchmark.running.hosted.board import Board
from benchmark.running.hosted.endpoint import Endpoint, Seats, on_hosted
from benchmark.running.hosted.unit_server import advertised_host

__all__ = ["LINGER_S", "hosting"]

LINGER_S = 0.5  # after the last task: /next answers 204 this long before the endpoint closes


@contextlib.contextmanager
def hosting(*, workers: int, units: int, host: str, port: int,
            say: Callable[[str], None] | None = None
            ) -> Iterator[Callable[[tuple[str, Any]], None]]:
    """Serve the endpoint while the block runs the benchmark's `units` ((session, trial)
    pairs) on `workers`; yields the handler of the units' ``("hosted", ...)`` messages
    (`run_benchmark`'s `on_message`)."""
    if not 0 <= port <= 65535:
        raise ValueError(f"--port must be 0 to 65535, got {port}")
    say = say or functools.partial(print, flush=True)
    board = Board(workers, units)
    seats = Seats(workers)
    endpoint = Endpoint(board, seats, host=host, port=port)
    endpoint.start()
    url = f"http://{advertised_host(host)}:{endpoint.port}"
    say(f"hosted run: endpoint {url} (agents: GET {url}/next for each task; 204 when all "
        "are done)")
    say(f"hosted run: MultiUAV-Plat clients use base URL {url} with X-API-Key "
        f"{' or '.join(seats.keys)}")
    try:
        yield on_hosted(board)
    finally:
        board.close()
        time.sleep(LINGER_S)
        endpoint.stop()

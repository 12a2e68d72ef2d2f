"""The order in which a parallel run hands out test files: the longest first.

`./dev test` runs the files on pytest-xdist workers (`--dist loadfile --no-loadscope-reorder`),
which take the files in the order of the collected items. A long file that starts last runs
alone at the end while the other workers idle, so the files are sorted by how long each took
in a recorded run (`tests/file_durations.json`, seconds of test time per file); a file not
recorded yet is estimated from its tests (a slow one counts SLOW_TEST_S, any other
FAST_TEST_S). Each file's tests keep their order.

`pytest --record-file-durations` (with any other options, e.g. `./dev test
--record-file-durations`) writes the file again from the run's reports, the files of the run
only replacing theirs.
"""

from __future__ import annotations

import collections
import json
from pathlib import Path

import pytest

__all__ = ["DURATIONS", "FileOrder", "add_option"]

DURATIONS = Path(__file__).with_name("file_durations.json")
SLOW_TEST_S = 5.0
FAST_TEST_S = 0.05
OPTION = "--record-file-durations"


def add_option(parser: pytest.Parser) -> None:
    """The option that records the durations (call from pytest_addoption)."""
    parser.addoption(OPTION, action="store_true",
                     help="write each file's test time to tests/file_durations.json, which "
                          "orders the files of a parallel run (longest first)")


def _recorded() -> dict[str, float]:
    try:
        data = json.loads(DURATIONS.read_text())
    except (OSError, ValueError):
        return {}
    return {str(k): float(v) for k, v in data.items()} if isinstance(data, dict) else {}


class FileOrder:
    """The plugin: sorts the selected items, and records durations when asked."""

    def __init__(self, config: pytest.Config) -> None:
        self._record = bool(config.getoption(OPTION))
        self._seconds: collections.defaultdict[str, float] = collections.defaultdict(float)

    @pytest.hookimpl(trylast=True)
    def pytest_collection_modifyitems(self, items: list[pytest.Item]) -> None:
        recorded = _recorded()
        estimate: collections.defaultdict[str, float] = collections.defaultdict(float)
        for item in items:
            slow = item.get_closest_marker("slow") is not None
            estimate[item.location[0]] += SLOW_TEST_S if slow else FAST_TEST_S

        def seconds(item: pytest.Item) -> float:
            path = item.location[0]
            return recorded.get(path, estimate[path])

        items.sort(key=lambda item: -seconds(item))  # stable: a file's tests keep their order

    def pytest_runtest_logreport(self, report: pytest.TestReport) -> None:
        if self._record:
            self._seconds[report.nodeid.split("::", 1)[0]] += report.duration

    def pytest_sessionfinish(self, session: pytest.Session) -> None:
        if not self._record or not self._seconds or hasattr(session.config, "workerinput"):
            return  # an xdist worker: its reports reach the controller, which records them
        merged = {**_recorded(), **{k: round(v, 1) for k, v in self._seconds.items()}}
        DURATIONS.write_text(json.dumps(dict(sorted(merged.items())), indent=1) + "\n")

"""The Python client the hosted-runs page shows, run as it is written (its code block
cut from docs/agents/hosted.md), plays a hosted run to the end."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from benchmark.running.results import read_records
from tests.cli_fixtures import ROOT
from tests.hosted_fixtures import session_file, start_host

pytestmark = [pytest.mark.mavsdk, pytest.mark.slow]


def readme_client() -> str:
    text = (ROOT / "docs" / "agents" / "hosted.md").read_text(encoding="utf-8")
    found = re.search(r"<!-- hosted-client -->\n```python\n(.*?)```", text, re.S)
    assert found is not None, "docs/agents/hosted.md has no hosted-client block"
    return found.group(1)


def test_the_readme_client_is_short_and_plays_a_hosted_run(tmp_path: Path) -> None:
    code = readme_client()
    assert len(code.splitlines()) <= 35
    client = tmp_path / "client.py"
    client.write_text(code)
    host = start_host([session_file(tmp_path)], tmp_path / "out")
    try:
        played = subprocess.run([sys.executable, str(client), host.url], capture_output=True,
                                text=True, timeout=120)
        status, printed = host.wait()
    finally:
        host.kill()
    assert played.returncode == 0, played.stderr
    assert played.stdout.count("took off") == 2
    assert status == 0, printed
    records = read_records(tmp_path / "out" / "results.jsonl")
    assert [(r["finish"], r["tool_calls"]) for r in records] == [("finished", 2)] * 2

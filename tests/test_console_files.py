"""Session files named in requests, against a real `mavswarm serve --session-dir DIR` with its
console: `POST /sessions/load {"path": ...}` and the editor's
`GET /console/api/editor/start?source=file&path=...` read regular .json files of at most
16 MiB from the session folders only; /dev/zero, a FIFO, a path that climbs out with `..`, a
symbolic link out of a folder, a huge file are refused at once with the reason, and the
server keeps answering. A session also comes in a body (an upload), and the editor never
writes into a FIFO."""

from __future__ import annotations

import json
import os
import subprocess
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest

from tests.cli_fixtures import MAVSWARM, ROOT, read_until, run_in_process
from tests.ports import unused_tcp_port

pytestmark = pytest.mark.mavsdk

OPERATOR = {"X-API-Key": "ok"}
SHIPPED = ROOT / "benchmark/sessions/area_search-easy-2.json"


def _world(ident: str) -> dict[str, object]:
    source = json.loads(SHIPPED.read_text())
    return {**source, "id": ident, "tasks": []}


@pytest.fixture(scope="module")
def served(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[str, Path, Path]]:
    """(base URL, the --session-dir folder, a folder outside every session folder); the
    server's working directory is the editor's save folder, so a session folder too."""
    work = tmp_path_factory.mktemp("work")
    folder = tmp_path_factory.mktemp("sessions")
    elsewhere = tmp_path_factory.mktemp("elsewhere")
    (work / "world.json").write_text(json.dumps(_world("served-world")))
    (folder / "good.json").write_text(json.dumps(_world("from-the-folder")))
    os.mkfifo(folder / "pipe.json")
    os.mkfifo(work / "pipe-save.json")
    (folder / "zero.json").symlink_to("/dev/zero")
    (folder / "away.json").symlink_to(elsewhere / "outside.json")
    with open(folder / "big.json", "wb") as big:
        big.truncate(17 * 1024 * 1024)
    (folder / "notes.txt").write_text("{}")
    (elsewhere / "outside.json").write_text(json.dumps(_world("outside")))
    port = unused_tcp_port()
    proc = subprocess.Popen(
        [*MAVSWARM, "serve", "--sessions", "world.json", "--session-dir", str(folder),
         "--port", str(port), "--key", "operator=ok", "--key", "agent=ak"],
        cwd=work, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1",
             "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])})
    try:
        read_until(proc, "web console:", 60)
        yield f"http://127.0.0.1:{port}", folder, elsewhere
    finally:
        proc.terminate()
        try:
            proc.wait(15)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(5)


def _refusals(folder: Path, elsewhere: Path) -> list[tuple[str, int, str]]:
    return [
        ("/dev/zero", 403, "outside the session folders"),
        ("../../../../etc/shadow", 403, "outside the session folders"),
        ("/etc/shadow", 403, "outside the session folders"),
        (str(elsewhere / "outside.json"), 403, "outside the session folders"),
        (str(folder / "zero.json"), 403, "outside the session folders"),  # a link out
        (str(folder / "away.json"), 403, "outside the session folders"),
        (str(folder / ".." / elsewhere.name / "outside.json"), 403, "outside"),
        (str(folder / "pipe.json"), 422, "is a FIFO, not a regular file"),
        (str(folder / "big.json"), 413, "at most 16777216 bytes"),
        ("pipe.json", 422, "a FIFO"),
        (str(folder / "missing.json"), 404, "no such session file"),
        (str(folder / "notes.txt"), 422, "ends in .json"),
        ("", 422, "path"),
        ("a\x00b.json", 422, "control character"),
    ]


def test_load_reads_only_regular_files_of_the_session_folders(
        served: tuple[str, Path, Path]) -> None:
    url, folder, elsewhere = served
    for path, status, words in _refusals(folder, elsewhere):
        answer = httpx.post(f"{url}/sessions/load", json={"path": path}, headers=OPERATOR,
                            timeout=10)
        assert answer.status_code == status, (path, answer.text)
        assert words in answer.json()["detail"], (path, answer.text)
    sessions = httpx.get(f"{url}/sessions", headers=OPERATOR).json()
    assert [s["id"] for s in sessions] == ["served-world"]  # nothing was loaded
    loaded = httpx.post(f"{url}/sessions/load", json={"path": "good.json"}, headers=OPERATOR,
                        timeout=60)
    assert loaded.status_code == 200 and loaded.json()["id"] == "from-the-folder", loaded.text
    again = httpx.post(f"{url}/sessions/load", json={"path": "world.json"}, headers=OPERATOR)
    assert again.status_code == 409 and "already live" in again.text  # the editor's folder
    agent = httpx.post(f"{url}/sessions/load", json={"path": "/dev/zero"},
                       headers={"X-API-Key": "ak"})
    assert agent.status_code == 403 and "role 'agent'" in agent.text


def test_the_editor_opens_files_of_the_session_folders_and_uploads(
        served: tuple[str, Path, Path]) -> None:
    url, folder, work = served
    start = f"{url}/console/api/editor/start"
    for path, status, words in _refusals(folder, work):
        answer = httpx.get(start, params={"source": "file", "path": path}, headers=OPERATOR,
                           timeout=10)
        assert answer.status_code == status, (path, answer.text)
        assert words in answer.json()["detail"], (path, answer.text)
    for path, ident in (("good.json", "from-the-folder"), (SHIPPED.name, "area_search-easy-2"),
                        ("world.json", "served-world")):
        answer = httpx.get(start, params={"source": "file", "path": path}, headers=OPERATOR)
        assert answer.status_code == 200 and answer.json()["id"] == ident, answer.text
    upload = httpx.post(f"{url}/console/api/editor/open", json=_world("uploaded"),
                        headers=OPERATOR)
    assert upload.status_code == 200 and upload.json()["id"] == "uploaded"
    bad_upload = httpx.post(f"{url}/console/api/editor/open", json={"schema": 3},
                            headers=OPERATOR)
    assert bad_upload.status_code == 422 and "schema" in bad_upload.json()["detail"]

    session = _world("saved-here")
    into_fifo = httpx.post(f"{url}/console/api/editor/save", headers=OPERATOR, timeout=10,
                           json={"path": "pipe-save.json", "session": session})
    assert into_fifo.status_code == 422 and "not a regular file" in into_fifo.json()["error"]
    saved = httpx.post(f"{url}/console/api/editor/save", headers=OPERATOR,
                       json={"path": "mine/saved.json", "session": session})
    assert saved.status_code == 200, saved.text
    written = Path(saved.json()["path"])
    assert written.parent.name == "mine" and json.loads(written.read_text())["id"] == "saved-here"
    reopened = httpx.get(start, params={"source": "file", "path": "mine/saved.json"},
                         headers=OPERATOR)
    assert reopened.status_code == 200 and reopened.json()["id"] == "saved-here"
    assert httpx.get(f"{url}/health").status_code == 200


def test_a_session_dir_that_is_not_a_folder_stops_serve(tmp_path: Path) -> None:
    run = run_in_process("serve", "--suite", "smoke", "--session-dir", str(tmp_path / "nowhere"),
                         cwd=tmp_path)
    assert run.returncode == 2 and "is not a folder" in run.stderr, run.stderr

"""The console's input bounds over real sockets, against `mavswarm up --web` and the console
`mavswarm serve` mounts at /console (real processes, uvicorn, httpx and a websockets client):
hostile bodies (NaN, a 5,000-digit number, invalid UTF-8, a lone surrogate, a seed of 2^64,
100,000 nested brackets) are a 422 naming the problem and change nothing; a 50 MB body is a
413 before it is read; a key of any text that is not a key is 401 on every route and closes
the WebSocket with 4401, a key of the wrong role 403 and 4403, an unknown live swarm 4404."""

from __future__ import annotations

import json
import os
import subprocess
from collections.abc import Iterator

import httpx
import pytest
from websockets.exceptions import ConnectionClosed, InvalidStatus
from websockets.sync.client import connect

from tests.cli_fixtures import MAVSWARM, ROOT, read_until, start_up
from tests.ports import unused_tcp_port, unused_udp_port

pytestmark = pytest.mark.mavsdk

KEY = "console-bounds-key"
SERVE_KEYS = {"agent": "ak", "operator": "ok", "admin": "adm"}
HOSTILE = {
    "NaN": b'{"loss": NaN}',
    "5,000 digits": b'{"loss": ' + b"9" * 5000 + b"}",
    "invalid UTF-8": b'{"loss": "\xff\xfe"}',
    "lone surrogate": b'{"loss": "\\ud800"}',
    "seed 2^64": b'{"seed": 18446744073709551616}',
    "100,000 brackets": b"[" * 100_000,
}
EXPECTED = {"NaN": "finite", "5,000 digits": "5000 digits", "invalid UTF-8": "UTF-8",
            "lone surrogate": "lone surrogate", "seed 2^64": "18446744073709551616",
            "100,000 brackets": "nests deeper"}


def _stop(proc: subprocess.Popen[str]) -> None:
    proc.terminate()
    try:
        proc.wait(15)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait(5)


@pytest.fixture(scope="module")
def up_web() -> Iterator[str]:
    """`mavswarm up --web` of two drones; the console's base URL."""
    port = unused_tcp_port()
    proc = start_up("--drones", "2", "--no-truth", "--api-port", "0", "--gcs-port", "0",
                    "--bind-port", str(unused_udp_port()), "--web", "--web-port", str(port),
                    "--web-key", KEY)
    try:
        read_until(proc, "web console:", 60)
        yield f"http://127.0.0.1:{port}"
    finally:
        _stop(proc)


@pytest.fixture(scope="module")
def serve_console(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[str, str]]:
    """`mavswarm serve` of a world without tasks with its console; (base URL, session id)."""
    folder = tmp_path_factory.mktemp("serve")
    source = json.loads((ROOT / "benchmark/sessions/area_search-easy-1.json").read_text())
    source["tasks"] = []
    path = folder / "world.json"
    path.write_text(json.dumps(source))
    port = unused_tcp_port()
    keys = [arg for role, key in SERVE_KEYS.items() for arg in ("--key", f"{role}={key}")]
    proc = subprocess.Popen([*MAVSWARM, "serve", "--sessions", str(path), "--port", str(port),
                             *keys], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True, env={**os.environ, "PYTHONUNBUFFERED": "1"})
    try:
        read_until(proc, "web console:", 60)
        yield f"http://127.0.0.1:{port}", source["id"]
    finally:
        _stop(proc)


def _ws(url: str, **headers: str) -> tuple[int, str]:
    """The close code and reason the live WebSocket at `url` answers (0: frames flowed;
    an HTTP status: the handshake was refused with it)."""
    try:
        with connect(url, additional_headers=headers or None, open_timeout=20) as socket:
            socket.recv(timeout=20)
            return 0, ""
    except ConnectionClosed as closed:
        assert closed.rcvd is not None, closed
        return closed.rcvd.code, closed.rcvd.reason
    except InvalidStatus as refused:
        return refused.response.status_code, ""


def _hostile_answers(base: str, headers: dict[str, str], live: str
                     ) -> dict[tuple[str, str], tuple[int, str]]:
    answers: dict[tuple[str, str], tuple[int, str]] = {}
    for name, body in HOSTILE.items():
        for method, path in (("PUT", f"/api/live/{live}/link-faults"),
                             ("POST", f"/api/live/{live}/command"),
                             ("POST", "/api/editor/validate"),
                             ("POST", "/api/editor/save")):
            r = httpx.request(method, f"{base}{path}", content=body, headers=headers,
                              timeout=30)
            answers[name, path] = (r.status_code, r.text[:300])
    return answers


@pytest.mark.parametrize("where", ["up", "serve"])
def test_hostile_bodies_are_refused_with_422_and_change_nothing(
        where: str, request: pytest.FixtureRequest) -> None:
    if where == "up":
        base, live = request.getfixturevalue("up_web"), "swarm"
        headers = {"X-API-Key": KEY}
    else:
        url, live = request.getfixturevalue("serve_console")
        base, headers = f"{url}/console", {"X-API-Key": SERVE_KEYS["operator"]}
    before = httpx.get(f"{base}/api/live/{live}/link-faults", headers=headers).json()
    answers = _hostile_answers(base, headers, live)
    for (name, path), (status, text) in answers.items():
        assert status == 422, (where, name, path, status, text)
        assert EXPECTED[name] in json.loads(text)["detail"], (name, path, text)
    after = httpx.get(f"{base}/api/live/{live}/link-faults", headers=headers).json()
    assert after["link_faults"] == before["link_faults"]
    assert httpx.get(f"{base}/api/info", headers=headers).status_code == 200


def test_a_50_mb_body_is_refused_before_it_is_read(up_web: str) -> None:
    headers = {"X-API-Key": KEY}
    body = b'{"x": "' + b"a" * (50 * 1024 * 1024) + b'"}'
    declared = httpx.post(f"{up_web}/api/editor/validate", content=body, headers=headers,
                          timeout=60)
    assert declared.status_code == 413 and "limit is 1048576" in declared.json()["detail"]

    def chunks() -> Iterator[bytes]:  # no Content-Length: counted as it streams
        for _ in range(50):
            yield b" " * (1024 * 1024)

    streamed = httpx.post(f"{up_web}/api/live/swarm/command", content=chunks(),
                          headers=headers, timeout=60)
    assert streamed.status_code == 413, streamed.text[:200]


def test_keys_of_any_text_are_401_on_every_route_and_the_websocket(up_web: str) -> None:
    ws = up_web.replace("http://", "ws://") + "/api/live/swarm/ws"
    routes = ["/api/info", "/api/live/swarm/scene", "/api/live/swarm/link-faults",
              "/api/truth", "/api/editor/choices", "/api/editor/start",
              "/api/runs/x/tasks", "/api/task/s/t", "/api/live/swarm/vehicles/d1/link"]
    for key in ("\xe9".encode("latin-1"), "\u00e9".encode(), "\u2603".encode(), b"wrong",
                b"\xff" * 300):
        for route in routes:
            r = httpx.get(f"{up_web}{route}", headers={b"X-API-Key": key})
            assert r.status_code == 401, (key, route, r.status_code, r.text[:200])
            assert r.json()["detail"] == "unknown API key"
        posted = httpx.post(f"{up_web}/api/live/swarm/command",
                            headers={b"X-API-Key": key}, json={"drone_id": "d1",
                                                              "tool": "take_off"})
        assert posted.status_code == 401
    for query in ("?key=%C3%A9", "?key=%E2%98%83", "?key=%ED%A0%80", "?key=wrong", ""):
        code, reason = _ws(ws + query)
        assert code == 4401, (query, code, reason)
        assert "API key" in reason
    assert _ws(ws, **{"X-API-Key": "wrong"})[0] == 4401
    assert _ws(up_web.replace("http://", "ws://") + f"/api/live/nope/ws?key={KEY}")[0] == 4404
    assert _ws(f"{ws}?key={KEY}") == (0, "")
    assert _ws(ws, **{"X-API-Key": KEY}) == (0, "")


def test_serve_console_refuses_agents_with_403_and_4403(serve_console: tuple[str, str]
                                                        ) -> None:
    url, live = serve_console
    base = f"{url}/console"
    ws = base.replace("http://", "ws://") + f"/api/live/{live}/ws"
    agent = {"X-API-Key": SERVE_KEYS["agent"]}
    for route in ("/api/info", f"/api/live/{live}/scene", f"/api/live/{live}/link-faults"):
        assert httpx.get(f"{base}{route}", headers=agent).status_code == 403
        unknown = {b"X-API-Key": b"\xc3\xa9"}
        assert httpx.get(f"{base}{route}", headers=unknown).status_code == 401
    refused = httpx.post(f"{base}/api/editor/validate", headers=agent, content=b"[" * 100_000)
    assert refused.status_code == 403  # the key is checked before the body is read
    code, reason = _ws(f"{ws}?key={SERVE_KEYS['agent']}")
    assert code == 4403 and "operator or admin" in reason
    assert _ws(f"{ws}?key=%C3%A9")[0] == 4401
    assert _ws(f"{ws}?key={SERVE_KEYS['admin']}") == (0, "")

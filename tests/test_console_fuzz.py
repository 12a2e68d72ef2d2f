"""Property-based fuzzing (hypothesis) of the web console as `mavswarm serve` mounts it, over a
real stepped swarm in-process: every console route, the live WebSocket's handshake, the
editor and the session-file routes (the console's editor, `POST /sessions/load`).

Inputs: the hostile bodies of the agent surfaces' fuzz (tests/test_hardening_api_fuzz.py),
command, link, editor and session bodies with hostile fields, keys of any text and bytes
(header or query parameter), hostile paths (devices, FIFOs, `..`, links out, huge files,
control characters) and query strings.

Invariants: never a 5xx; a missing or unknown key is 401 (the WebSocket closes with 4401),
an agent key 403 (4403), an unknown live swarm 4404 at the WebSocket; a refusal changes
nothing (the drones, the calls charged, the link settings, the live sessions, the files of
the editor's folder); every answer is JSON of bounded size. Runs derandomized, inside the
suite's seed-only draws (tests/conftest.py), so CI sees the same inputs every time.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import os
from collections import Counter
from collections.abc import Iterator
from pathlib import Path
from typing import Any
from urllib.parse import quote, unquote, urlencode

import pytest
from hypothesis import HealthCheck, event, example, given, settings
from hypothesis import strategies as st

from benchmark.server.session_runner import SessionRunner
from llm_tools.input_limits import MAX_BODY_BYTES
from tests.bench_fixtures import small_session
from tests.console_fixtures import KEYS, ConsoleServed, console_served
from tests.test_hardening_api import _snapshot
from tests.test_hardening_api_fuzz import BODIES, NUMBERS, TEXT, VALUES, dump

pytestmark = [pytest.mark.mavsdk]

FUZZ = settings(derandomize=True, database=None, deadline=None, print_blob=True,
                suppress_health_check=list(HealthCheck))
MAX_ANSWER_CHARS = 50_000
SHIPPED_NAME = "area_search-easy-2.json"

UNKNOWN_KEY = st.one_of(
    TEXT, st.binary(min_size=1, max_size=40).map(lambda b: b.decode("latin-1")),
    st.sampled_from(["\u00e9", "key-operator\u00e9", " key-operator", "KEY-OPERATOR"]),
).filter(lambda k: k not in KEYS.values())
KEY = st.integers(0, 9).flatmap(lambda n: (
    st.sampled_from([("staff", KEYS["operator"]), ("staff", KEYS["admin"])]) if n < 6
    else st.just(("agent", KEYS["agent"])) if n == 6
    else UNKNOWN_KEY.map(lambda k: ("unknown", k)) if n < 9
    else st.just(("unknown", None))))
"""(who, key): staff most of the time, so the routes behind the key check are reached."""


def _paths(folder: Path, outside: Path) -> st.SearchStrategy[Any]:
    return st.one_of(
        st.sampled_from(["/dev/zero", "/dev/urandom", "/proc/self/mem", "/etc/shadow",
                         "../../../../etc/shadow", "~/.ssh/id_rsa", "a\x00b.json",
                         "\ud800.json", str(folder / "pipe.json"), "pipe.json", "big.json",
                         "zero.json", "away.json", str(outside / "outside.json"),
                         str(folder / ".." / outside.name / "outside.json"), "x" * 5000,
                         "fuzz-saved.json", SHIPPED_NAME, "", "."]),
        TEXT, NUMBERS, st.none(), st.lists(TEXT, max_size=2))


def _session_bodies() -> st.SearchStrategy[Any]:
    world = small_session([])
    return st.one_of(
        st.just(world),
        st.builds(lambda key, value: {**world, key: value},
                  st.sampled_from(["seed", "id", "drones", "map_size_m", "tasks", "schema",
                                   "safety_margin_m", "targets", "obstacles"]), VALUES),
        st.builds(lambda value: {**world, "drones": [{**world["drones"][0], "position": {
            "x": value, "y": 1.0, "z": 0.0}}]}, NUMBERS),
    )


def _bodies(folder: Path, outside: Path, drones: list[str]) -> st.SearchStrategy[str]:
    paths, sessions = _paths(folder, outside), _session_bodies()
    drone = st.one_of(st.sampled_from(drones), TEXT, NUMBERS)
    objects = st.one_of(
        st.fixed_dictionaries({"drone_id": drone, "tool": st.one_of(st.sampled_from(
            ["take_off", "land", "move_to", "hover", "take_photo"]), TEXT, NUMBERS)},
            optional={"args": st.one_of(st.dictionaries(TEXT, VALUES, max_size=3), VALUES),
                      "extra": VALUES}),
        st.fixed_dictionaries({}, optional={
            "loss": NUMBERS, "seed": NUMBERS, "latency_ms": NUMBERS, "outages": VALUES,
            "uplink": st.dictionaries(st.sampled_from(["loss", "jitter_ms", "x"]), NUMBERS),
            "vehicles": st.dictionaries(drone.map(str), VALUES, max_size=2)}),
        st.fixed_dictionaries({"path": paths}),
        st.fixed_dictionaries({"session": sessions}),
        st.fixed_dictionaries({"path": paths, "session": sessions}),
        sessions,
    )
    oversized = st.integers(MAX_BODY_BYTES + 1, 3 * MAX_BODY_BYTES).map(
        lambda n: '{"session": "' + "x" * n + '"}')
    return st.one_of(objects.map(dump), BODIES, oversized)


def _routes(live: str, drones: list[str]) -> st.SearchStrategy[tuple[str, str, bool]]:
    """(method, path under the server, whether the route needs no key); path segments that
    route somewhere else (empty, '/', dot segments, a newline, which no mount matches) are
    left out."""
    text = TEXT.filter(lambda t: t.strip(".") != "" and "/" not in t and "\n" not in t)
    segment = st.one_of(st.just(live), text).map(lambda t: quote(t, safe="", errors="replace"))
    drone = st.one_of(st.sampled_from(drones), text).map(
        lambda t: quote(t, safe="", errors="replace"))
    c = "/console"
    return st.one_of(
        st.sampled_from([
            ("GET", f"{c}/api/info", False), ("GET", f"{c}/api/truth", False),
            ("GET", f"{c}/api/editor/choices", False), ("GET", f"{c}/api/editor/start", False),
            ("POST", f"{c}/api/editor/open", False), ("POST", f"{c}/api/editor/validate", False),
            ("POST", f"{c}/api/editor/save", False), ("POST", "/sessions/load", False)]),
        segment.map(lambda s: ("GET", f"{c}/api/live/{s}/scene", False)),
        segment.map(lambda s: ("POST", f"{c}/api/live/{s}/command", False)),
        st.builds(lambda m, s: (m, f"{c}/api/live/{s}/link-faults", False),
                  st.sampled_from(["GET", "PUT"]), segment),
        st.builds(lambda m, s, d: (m, f"{c}/api/live/{s}/vehicles/{d}/link", False),
                  st.sampled_from(["GET", "PUT"]), segment, drone),
        segment.map(lambda s: ("GET", f"{c}/api/runs/{s}/tasks", False)),
        st.builds(lambda s, t: ("GET", f"{c}/api/task/{s}/{t}", False), segment, segment),
        segment.map(lambda s: ("GET", f"{c}/static/{s}", True)),
    )


def _queries(folder: Path, outside: Path) -> st.SearchStrategy[dict[str, str]]:
    text = st.one_of(TEXT, NUMBERS.map(dump), _paths(folder, outside).map(str))
    return st.dictionaries(
        st.sampled_from(["source", "path", "family", "level", "index", "trial", "run", "agent",
                         "x"]),
        st.one_of(st.sampled_from(["file", "blank", "level", "area_search", "easy"]), text),
        max_size=4)


@contextlib.contextmanager
def console_loop(monkeypatch: pytest.MonkeyPatch, tmp_path: Path
                 ) -> Iterator[tuple[asyncio.AbstractEventLoop, ConsoleServed, Path, Path]]:
    """The console of `serve` (working directory: the editor's folder `tmp_path/work`, a
    --session-dir `tmp_path/sessions` holding a FIFO, a 17 MiB file and links out) in an
    event loop of its own, for property tests that send one request at a time."""
    work, folder, outside = tmp_path / "work", tmp_path / "sessions", tmp_path / "outside"
    for made in (work, folder, outside):
        made.mkdir()
    os.mkfifo(folder / "pipe.json")
    os.mkfifo(work / "fifo-save.json")
    with open(folder / "big.json", "wb") as big:
        big.truncate(17 * 1024 * 1024)
    (folder / "zero.json").symlink_to("/dev/zero")
    (outside / "outside.json").write_text(json.dumps(small_session([])))
    (folder / "away.json").symlink_to(outside / "outside.json")
    monkeypatch.chdir(work)
    loop = asyncio.new_event_loop()
    stack = contextlib.AsyncExitStack()

    async def start() -> ConsoleServed:
        runner = await stack.enter_async_context(SessionRunner())
        served = await stack.enter_async_context(console_served(session_dirs=(folder,)))
        served.hub.starter = runner.start
        return served

    try:
        yield loop, loop.run_until_complete(start()), folder, outside
    finally:
        loop.run_until_complete(stack.aclose())
        loop.close()


async def _state(served: ConsoleServed, work: Path) -> Any:
    """What a refusal must leave as it was."""
    live = served.live
    await asyncio.wait_for(live.swarm.wait_idle(), 30.0)
    files = sorted(str(p.relative_to(work)) for p in work.rglob("*"))
    return (_snapshot(live), list(served.hub.sessions), served.hub.current(),
            json.dumps(live.services.operator_link_faults(), sort_keys=True), files)


def _headers(key: str | None, in_header: bool) -> list[tuple[bytes, bytes]]:
    if key is None or not in_header:
        return []
    return [(b"x-api-key", key.encode("utf-8", "surrogatepass").replace(b"\r", b"")
             .replace(b"\n", b""))]


def _expected(kind: str, public: bool, status: int) -> None:
    if public:
        return
    if kind == "unknown":
        assert status == 401, status
    elif kind == "agent":
        assert status == 403, status


def test_console_routes_never_5xx_and_refusals_change_nothing(
        monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    with console_loop(monkeypatch, tmp_path) as (loop, served, folder, outside):
        live, client, work = served.live.id, served.client, Path.cwd()
        drones = list(served.live.gateway.drones)
        seen: Counter[tuple[str, int]] = Counter()

        @settings(FUZZ, max_examples=120)
        @given(route=_routes(live, drones), key=KEY, in_header=st.booleans(),
               body=_bodies(folder, outside, drones), query=_queries(folder, outside))
        def check(route: tuple[str, str, bool], key: tuple[str, str | None], in_header: bool,
                  body: str, query: dict[str, str]) -> None:
            method, path, public = route
            kind, value = key
            params = dict(query)
            if value is not None and not in_header:
                params["key"] = value
            url = path + ("?" + urlencode(params, errors="replace") if params else "")
            before = loop.run_until_complete(_state(served, work))
            content = body.encode("utf-8", "surrogatepass") if method in ("POST", "PUT") else b""
            r = loop.run_until_complete(client.request(
                method, url, content=content, headers=_headers(value, in_header)))
            event(f"{method} HTTP {r.status_code}")
            seen[path.split("/")[-1] or path, r.status_code] += 1
            assert r.status_code < 500, (method, url, r.status_code, r.text[:300])
            if not path.startswith("/console/") and not in_header:
                kind = "unknown"  # the REST API reads keys from the X-API-Key header only
            if len(content) > MAX_BODY_BYTES:  # refused before the key is looked at
                assert r.status_code == 413, r.text[:300]
            else:
                _expected(kind, public, r.status_code)
            assert len(r.text) < MAX_ANSWER_CHARS or public
            if not public:
                r.json()
            if r.status_code >= 400:
                after = loop.run_until_complete(_state(served, work))
                assert after == before, (method, url, r.status_code, r.text[:300])

        check()
        statuses = {status for _, status in seen}
        assert {200, 401, 403, 404, 413, 422} <= statuses, seen  # every kind of answer
        info = loop.run_until_complete(client.get(
            "/console/api/info", headers={"X-API-Key": KEYS["operator"]}))
        assert info.status_code == 200 and live in {s["id"] for s in info.json()["live"]}


async def _handshake(app: Any, path: str, query: bytes, headers: list[tuple[bytes, bytes]]
                     ) -> tuple[int, str]:
    """Open the WebSocket at `path` on the ASGI `app` as a server would hand it over: the
    close code and reason it answers with, or (0, "") when it accepted and sent a frame."""
    scope = {"type": "websocket", "asgi": {"version": "3.0"}, "http_version": "1.1",
             "scheme": "ws", "path": path, "raw_path": quote(path).encode(),
             "query_string": query, "root_path": "", "headers": headers,
             "client": ("127.0.0.1", 50000), "server": ("serve", 80), "subprotocols": [],
             "state": {}}
    inbox: asyncio.Queue[dict[str, Any]] = asyncio.Queue()
    await inbox.put({"type": "websocket.connect"})
    sent: list[dict[str, Any]] = []

    async def send(message: dict[str, Any]) -> None:
        sent.append(message)
        if message["type"] == "websocket.send":
            raise OSError("the client left")  # one frame is enough

    await asyncio.wait_for(app(scope, inbox.get, send), 20.0)
    kinds = [m["type"] for m in sent]
    if "websocket.send" in kinds:
        return 0, ""
    assert kinds == ["websocket.accept", "websocket.close"], sent
    close = sent[-1]
    assert len(close.get("reason", "").encode()) <= 123, close
    return close["code"], close.get("reason", "")


def test_websocket_handshake_refuses_with_the_close_code_of_its_status(
        monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    with console_loop(monkeypatch, tmp_path) as (loop, served, _, _):
        live = served.live.id
        names = st.one_of(st.just(live), TEXT.filter(lambda t: t != live)).map(
            lambda t: unquote(quote(t, safe="", errors="replace"))).filter(
            lambda t: t.strip(".") != "" and "/" not in t and "\n" not in t)

        seen: Counter[int] = Counter()

        @settings(FUZZ, max_examples=120)
        @given(key=KEY, in_header=st.booleans(), name=names,
               query=st.dictionaries(TEXT, TEXT, max_size=2))
        def check(key: tuple[str, str | None], in_header: bool, name: str,
                  query: dict[str, str]) -> None:
            kind, value = key
            params = {k: v for k, v in query.items() if k != "key"}
            if value is not None and not in_header:
                params["key"] = value
            before = loop.run_until_complete(_state(served, Path.cwd()))
            code, reason = loop.run_until_complete(_handshake(
                served.app, f"/console/api/live/{name}/ws",
                urlencode(params, errors="replace").encode(), _headers(value, in_header)))
            event(f"close {code}")
            seen[code] += 1
            expected = {"unknown": 4401, "agent": 4403}.get(kind)
            if expected is None:
                expected = 0 if name == live else 4404
            assert code == expected, (kind, value, name, code, reason)
            assert loop.run_until_complete(_state(served, Path.cwd())) == before

        check()
        assert set(seen) == {0, 4401, 4403, 4404}, seen


def _path_cases(folder: Path, outside: Path) -> dict[str, int]:
    """Paths a staff caller names and the status each is answered with (the shipped
    session: 200; loading it again: 409)."""
    return {"/dev/zero": 403, "/dev/urandom": 403, "/proc/self/mem": 403, "/etc/shadow": 403,
            "../../../../etc/shadow": 403, str(outside / "outside.json"): 403,
            str(folder / ".." / outside.name / "outside.json"): 403, "zero.json": 403,
            "away.json": 403, str(folder / "pipe.json"): 422, "pipe.json": 422,
            "~/.ssh/id_rsa": 422, "a\x00b.json": 422, "x" * 5000: 422, "": 422, ".": 422,
            "big.json": 413, "missing.json": 404, SHIPPED_NAME: 200}


def test_file_routes_answer_each_path_with_its_reason(monkeypatch: pytest.MonkeyPatch,
                                                     tmp_path: Path) -> None:
    with console_loop(monkeypatch, tmp_path) as (loop, served, folder, outside):
        client, work = served.client, Path.cwd()
        cases = _path_cases(folder, outside)
        paths = st.one_of(st.sampled_from(sorted(cases)), TEXT)
        save_paths = st.one_of(st.sampled_from([  # names no case looks for
            "/dev/zero", "/etc/passwd", "../../saved.json", "fifo-save.json", "saved.txt",
            str(outside / "saved.json"), "x" * 5000, "saved.json", "sub/saved.json"]), TEXT)
        seen: Counter[tuple[str, int]] = Counter()

        staff = ("staff", KEYS["operator"])

        # every answer the coverage check below asks for, whatever the draws
        @settings(FUZZ, max_examples=150)
        @example("load", staff, True, "/etc/shadow", "saved.json", {})
        @example("load", staff, True, "pipe.json", "saved.json", {})
        @example("load", staff, True, "big.json", "saved.json", {})
        @example("start", staff, True, "zero.json", "saved.json", {})
        @example("start", staff, True, "pipe.json", "saved.json", {})
        @example("start", staff, True, "big.json", "saved.json", {})
        @example("start", staff, True, SHIPPED_NAME, "saved.json", {})
        @given(route=st.sampled_from(["load", "start", "save"]), key=KEY,
               in_header=st.booleans(), path=paths, save_path=save_paths,
               session=_session_bodies())
        def check(route: str, key: tuple[str, str | None], in_header: bool, path: str,
                  save_path: str, session: Any) -> None:
            kind, value = key
            path = save_path if route == "save" else path
            params = {"key": value} if value is not None and not in_header else {}
            if route == "start":
                params.update(source="file", path=path)
            query = "?" + urlencode(params, errors="replace") if params else ""
            body = {"path": path} if route == "load" else {"path": path, "session": session}
            url = {"load": "/sessions/load", "start": "/console/api/editor/start",
                   "save": "/console/api/editor/save"}[route] + query
            before = loop.run_until_complete(_state(served, work))
            r = loop.run_until_complete(client.request(
                "GET" if route == "start" else "POST", url, headers=_headers(value, in_header),
                content=b"" if route == "start" else dump(body).encode(
                    "utf-8", "surrogatepass")))
            seen[route, r.status_code] += 1
            assert r.status_code < 500, (url, r.status_code, r.text[:300])
            if route == "load" and not in_header:
                kind = "unknown"  # the REST API reads keys from the X-API-Key header only
            _expected(kind, False, r.status_code)
            expected = cases.get(path)
            if kind == "staff" and route != "save" and expected is not None:
                allowed = {expected, 409} if route == "load" and expected == 200 else {expected}
                if "\x00" in path and route == "start":
                    allowed = {422}
                assert r.status_code in allowed, (route, path[:60], r.status_code, r.text[:300])
            if r.status_code >= 400:
                assert loop.run_until_complete(_state(served, work)) == before, r.text[:300]

        check()
        assert {("load", 403), ("load", 422), ("load", 413), ("start", 403), ("start", 422),
                ("start", 413), ("start", 200)} <= set(seen), seen

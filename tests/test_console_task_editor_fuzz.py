"""Property-based fuzzing (hypothesis) of the task and template editor's routes over a real
socket: template texts with any field replaced by a hostile value (or any text at all),
sessions with any field replaced, hostile bodies of the agent surfaces' fuzz and any key.

Invariants: never a 5xx; every answer is JSON; an agent's key is 403 and an unknown one 401
(an oversized body 413, whoever sends it); a refused template is never written; no proof
starts from a session that has no such task. Runs derandomized, like the console's other
fuzz tests."""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from console.app import ConsoleState
from console.auth import ConsoleAuth
from console.task_editor import BUILT_IN_DIR
from tests.bench_fixtures import small_session
from tests.console_server import serve_console
from tests.test_hardening_api_fuzz import BODIES, NUMBERS, TEXT, VALUES, dump

pytestmark = [pytest.mark.slow]

FUZZ = settings(derandomize=True, database=None, deadline=None, max_examples=200,
                suppress_health_check=list(HealthCheck))
KEYS = {"op": "operator", "ag": "agent"}
TEMPLATE = json.loads((BUILT_IN_DIR / "photo_at_point.json").read_text())
WORLD = small_session([])
ROUTES = ["validate", "instantiate", "save", "recheck", "proofs"]


def _replace_at(data: Any, path: list[int], value: Any) -> Any:
    """`data` with the node that `path` (indices into each level's keys or items) leads
    to replaced by `value`."""
    if not path or not isinstance(data, dict | list) or not data:
        return value
    if isinstance(data, dict):
        key = list(data)[path[0] % len(data)]
        return {**data, key: _replace_at(data[key], path[1:], value)}
    k = path[0] % len(data)
    return [*data[:k], _replace_at(data[k], path[1:], value), *data[k + 1:]]


TEMPLATE_TEXTS = st.one_of(
    st.builds(lambda path, value: dump(_replace_at(TEMPLATE, path, value)),
              st.lists(st.integers(0, 20), min_size=1, max_size=5), VALUES),
    TEXT, st.just(json.dumps(TEMPLATE)), st.just(json.dumps(TEMPLATE)))
SESSIONS = st.one_of(
    st.just(WORLD), st.just(WORLD),
    st.builds(lambda path, value: _replace_at(WORLD, path, value),
              st.lists(st.integers(0, 40), min_size=1, max_size=4), VALUES))


def _body(route: str, text: str, session: Any, count: Any, task_id: Any) -> str:
    if route in ("validate", "save"):
        return '{"text":' + json.dumps(text) + "}"
    if route == "instantiate":
        return ('{"session":' + dump(session) + ',"text":' + json.dumps(text)
                + ',"count":' + dump(count) + "}")
    if route == "recheck":
        return '{"session":' + dump(session) + "}"
    return '{"session":' + dump(session) + ',"task_id":' + dump(task_id) + "}"


@pytest.fixture(scope="module")
def served(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[str, Path]]:
    folder = tmp_path_factory.mktemp("editor")
    with serve_console(ConsoleState(ConsoleAuth(KEYS.get), editor_root=folder)) as url:
        yield url, folder


def _path(route: str) -> str:
    return {"recheck": "/api/editor/tasks/recheck",
            "proofs": "/api/editor/proofs"}.get(route, f"/api/editor/templates/{route}")


@FUZZ
@given(route=st.sampled_from(ROUTES), text=TEMPLATE_TEXTS, session=SESSIONS,
       count=st.one_of(st.integers(1, 3), st.integers(-3, 30), NUMBERS),
       task_id=st.one_of(TEXT, NUMBERS), raw=st.one_of(st.none(), st.none(), st.none(), BODIES),
       key=st.sampled_from(["op", "op", "op", "ag", "x"]))
def test_task_editor_routes_never_5xx(served: tuple[str, Path], route: str, text: str,
                                      session: Any, count: Any, task_id: Any,
                                      raw: str | None, key: str) -> None:
    url, folder = served
    body = raw if raw is not None else _body(route, text, session, count, task_id)
    before = sorted(p.name for p in (folder / "templates").glob("*")) if (
        folder / "templates").exists() else []
    answer = httpx.post(f"{url}{_path(route)}", content=body.encode("utf-8", "surrogatepass"),
                        headers={"X-API-Key": key, "Content-Type": "application/json"},
                        timeout=60)
    assert answer.status_code < 500, (route, body[:300], answer.text[:300])
    event(f"{route} {answer.status_code}")
    answer.json()
    if key != "op":  # an oversized body is refused (413) before anything reads it
        assert answer.status_code in ({"ag": 403, "x": 401}[key], 413)
    after = sorted(p.name for p in (folder / "templates").glob("*")) if (
        folder / "templates").exists() else []
    if not (route == "save" and answer.status_code == 200):
        assert after == before
    if route == "proofs":
        assert answer.status_code != 202  # the world has no task: nothing may fly

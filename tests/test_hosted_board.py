"""The driver's board of hosted tasks (`GET /next`'s semantics) on its own: a task on offer goes
to one caller only; with none on offer a caller waits while fewer tasks are out than sessions
can be hosted at once, and gets 409 (AllOut) after a short grace when that many are out; a
task ended or a unit closed frees its place; once the run is over every caller gets None."""

from __future__ import annotations

import asyncio
import time

import pytest

from benchmark.running.hosted import board as board_module
from benchmark.running.hosted.board import AllOut, Board, NotYet
from benchmark.running.hosted.offer import BudgetView, Notice, NoticeKind, TaskOffer


def _offer(key: str, session: str = "s", task: str = "t01") -> dict:
    offer = TaskOffer(session=session, task_id=task, trial=0, text="do it",
                      budget=BudgetView(tool_calls=5, sim_time_s=60.0), drones=["d1"], key=key,
                      base_url="http://h:1", tools_url="http://h:1/sessions/s/tools",
                      mcp_url="http://h:1/mcp")
    return Notice(kind=NoticeKind.OFFER, key=key, offer=offer).model_dump(mode="json")


def _notice(kind: NoticeKind, key: str = "") -> dict:
    return Notice(kind=kind, key=key).model_dump(mode="json")


async def _settle() -> None:
    for _ in range(3):  # posts are applied by the loop, as from another thread
        await asyncio.sleep(0)


@pytest.fixture(autouse=True)
def short_grace(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(board_module, "GRACE_S", 0.2)


async def test_each_task_goes_to_one_caller_and_a_second_one_waits_for_the_next() -> None:
    board = Board(workers=2, units=2)
    board.bind(asyncio.get_running_loop())
    board.post(_offer("k1"))
    await _settle()
    first = await board.take(1.0)
    assert first is not None and first.key == "k1"
    waiting = asyncio.create_task(board.take(5.0))  # one out of two: wait for an offer
    await asyncio.sleep(0.3)
    assert not waiting.done()
    board.post(_offer("k2", session="other"))
    second = await asyncio.wait_for(waiting, 2.0)
    assert second is not None and second.key == "k2"
    with pytest.raises(AllOut, match="already out"):  # two out of two
        await board.take(5.0)


async def test_a_task_ended_right_before_next_is_not_refused() -> None:
    board = Board(workers=1, units=1)
    board.bind(asyncio.get_running_loop())
    board.post(_offer("k1"))
    await _settle()
    assert (await board.take(1.0)) is not None
    started = time.monotonic()
    asking = asyncio.create_task(board.take(5.0))
    await asyncio.sleep(0.05)
    board.post(_notice(NoticeKind.ENDED, "k1"))  # the end arrives after the next ask...
    board.post(_offer("k2", task="t02"))
    nxt = await asyncio.wait_for(asking, 2.0)  # ...within the grace: the next task
    assert nxt is not None and nxt.task_id == "t02" and time.monotonic() - started < 1.0
    with pytest.raises(AllOut, match="t02"):
        await board.take(5.0)


async def test_closed_units_shrink_what_is_hosted_at_once_and_the_end_is_none() -> None:
    board = Board(workers=2, units=2)
    board.bind(asyncio.get_running_loop())
    board.post(_offer("k1"))
    await _settle()
    assert (await board.take(1.0)) is not None
    board.post(_notice(NoticeKind.CLOSED))  # the other session is done
    await _settle()
    assert board.at_once == 1
    with pytest.raises(AllOut):
        await board.take(5.0)
    with pytest.raises(NotYet):  # out: none; on offer: none; units left: one
        board.post(_notice(NoticeKind.ENDED, "k1"))
        await _settle()
        await board.take(0.1)
    waiting = asyncio.create_task(board.take(5.0))
    board.close()
    assert await asyncio.wait_for(waiting, 2.0) is None
    assert await board.take(0.0) is None
    assert board.counts()["over"] is True


async def test_a_bad_notice_is_refused_before_it_changes_anything() -> None:
    board = Board(workers=1, units=1)
    board.bind(asyncio.get_running_loop())
    with pytest.raises(ValueError, match="kind"):
        board.post({"kind": "teleport", "key": "k"})
    with pytest.raises(ValueError):
        board.post({**_offer("k1"), "extra": 1})
    await _settle()
    assert board.counts()["on_offer"] == 0

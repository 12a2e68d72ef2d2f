"""Truth event kinds are one StrEnum: every kind the emulator records and every kind a reader
asks for (checks, flight logs, the replay page's colours) is a member, stored as its word."""

from __future__ import annotations

import ast
import json
import re
from pathlib import Path

import pytest

from emulator.truth import TruthEvent, TruthLog, TruthRecorder
from emulator.truth_events import TruthEventKind

ROOT = Path(__file__).resolve().parents[1]


def _calls_with_literal_kind(path: Path) -> list[str]:
    """`x.event("word", ...)` / `record_event(t, id, "word", ...)` calls: a kind written as a
    bare string."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if not isinstance(node, ast.Call):
            continue
        name = getattr(node.func, "attr", None) or getattr(node.func, "id", None)
        position = {"event": 0, "record_event": 2}.get(str(name))
        if position is not None and len(node.args) > position:
            arg = node.args[position]
            if isinstance(arg, ast.Constant) and isinstance(arg.value, str):
                found.append(f"{path.relative_to(ROOT)}:{node.lineno}: {arg.value}")
    return found


def test_writers_use_the_enum() -> None:
    bare = [hit for package in ("emulator", "benchmark", "mavswarm", "console")
            for path in sorted((ROOT / package).rglob("*.py"))
            for hit in _calls_with_literal_kind(path)]
    assert bare == []


def test_values_are_the_stored_words() -> None:
    assert all(kind.value == kind.name.lower() for kind in TruthEventKind)
    assert json.dumps(TruthEventKind.OBSTACLE_STOP) == '"obstacle_stop"'


def test_a_kind_read_back_is_the_member(tmp_path: Path) -> None:
    rec = TruthRecorder(["d1"])
    rec.record_event(1.0, "d1", TruthEventKind.LANDED, position_m=[1.0, 2.0, 0.0])
    rec.record_event(2.0, "d1", "photo", index=1)  # type: ignore[arg-type]  # a word too
    log = TruthLog.load(rec.export(tmp_path / "t.truth.npz"))
    kinds = [e.kind for e in log.events()]
    assert kinds == [TruthEventKind.LANDED, TruthEventKind.PHOTO]
    assert all(type(k) is TruthEventKind for k in kinds)
    assert TruthEvent(**log.events()[0].to_json()) == log.events()[0]


def test_an_unknown_kind_is_refused_by_name() -> None:
    rec = TruthRecorder(["d1"])
    with pytest.raises(ValueError, match=r"truth event kind .*got 'armed'"):
        rec.record_event(1.0, "d1", "armed")  # type: ignore[arg-type]
    assert rec.events() == []


def test_the_replay_page_colours_known_kinds() -> None:
    source = (ROOT / "console/web/src/replay.js").read_text(encoding="utf-8")
    block = re.search(r"EVENT_COLORS = \{(.*?)\};", source, re.DOTALL)
    assert block is not None
    keys = re.findall(r"(\w+):", block.group(1))
    assert keys and set(keys) <= set(TruthEventKind)

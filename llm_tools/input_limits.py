"""Bounds on what callers may send, checked before a value reaches Python arithmetic.

Every surface that takes input from outside (the tool registry, the REST API, the MCP server)
parses and checks it here, so a hostile or broken value gets the same clear answer
everywhere: an `InputError` that names where the problem is (``waypoints[3].x``) and shows
at most a short preview of what was sent.

The bounds:

- a body is at most `MAX_BODY_BYTES` bytes of UTF-8 and nests at most `MAX_DEPTH` levels;
- a number is finite and within +/-`MAX_NUMBER_ABS` (an integer literal of more than
  `MAX_INTEGER_DIGITS` digits is refused without being converted);
- a string is at most `MAX_STRING_CHARS` characters of encodable Unicode (no lone surrogate,
  no control character other than tab and newline); an object key at most `MAX_NAME_CHARS`;
- a list has at most `MAX_ITEMS` items.

A session (a file or a body that carries one) is parsed with the same bounds but two:
`parse_json(..., max_bytes=..., max_number_abs=MAX_SESSION_NUMBER_ABS)`, since a session's
seed is a 64-bit integer and a file may be larger than a request body.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

__all__ = [
    "MAX_BODY_BYTES", "MAX_DEPTH", "MAX_INTEGER_DIGITS", "MAX_ITEMS", "MAX_NAME_CHARS",
    "MAX_NUMBER_ABS", "MAX_SESSION_NUMBER_ABS", "MAX_STRING_CHARS", "InputError",
    "check_bounds", "check_text",
    "parse_json", "parse_number", "preview",
]

MAX_BODY_BYTES = 1 << 20
MAX_DEPTH = 32
MAX_NUMBER_ABS = 1e9
MAX_SESSION_NUMBER_ABS = float(2**63)
"""The number bound of a session's JSON: its seed is a 64-bit integer."""
MAX_INTEGER_DIGITS = 30
MAX_STRING_CHARS = 10_000
MAX_NAME_CHARS = 64
MAX_ITEMS = 10_000
PREVIEW_CHARS = 40

_NUMBER_TEXT = re.compile(r"-?(?:0|[1-9][0-9]*)(?:\.[0-9]+)?(?:[eE][+-]?[0-9]+)?\Z")
_STRING_LITERAL = re.compile(r'"(?:[^"\\]|\\.)*"', re.DOTALL)
_BRACKET = re.compile(r"[\[\]{}]")
_BAD_CHAR = re.compile(r"[\ud800-\udfff\x00-\x08\x0b-\x1f\x7f]")


class InputError(ValueError):
    """Raised when input is not JSON or breaks a bound; `where` names the offending field
    and `http_status` is the status a web surface answers with (413 or 422)."""

    def __init__(self, where: str, problem: str, *, http_status: int = 422) -> None:
        super().__init__(f"{where} {problem}" if where else problem)
        self.where = where
        self.problem = problem
        self.http_status = http_status


@dataclass(frozen=True, slots=True)
class _LongInteger:
    """An integer literal too long to convert; check_bounds reports it with its field."""

    digits: int


def preview(value: Any, limit: int = PREVIEW_CHARS) -> str:
    """A short, safe description of any value: never huge, never raising."""
    if isinstance(value, _LongInteger):
        return f"an integer of {value.digits} digits"
    if isinstance(value, bool) or value is None:
        return repr(value)
    if isinstance(value, int):
        if value.bit_length() > 100:
            return f"an integer of about {int(value.bit_length() * 0.30103) + 1} digits"
        text = repr(value)
    elif isinstance(value, float):
        text = repr(value)
    elif isinstance(value, str):
        text = repr(value[: limit + 1])
    elif isinstance(value, list | tuple):
        return f"a list of {len(value)} items"
    elif isinstance(value, Mapping):
        return f"an object with {len(value)} keys"
    else:
        return f"a {type(value).__name__}"
    return text if len(text) <= limit else text[: limit - 3] + "..."


def check_text(text: str, where: str, *, limit: int = MAX_STRING_CHARS) -> None:
    """Raise InputError unless `text` is at most `limit` characters of encodable text."""
    if len(text) > limit:
        raise InputError(where, f"is {len(text)} characters long; the limit is {limit}")
    bad = _BAD_CHAR.search(text)
    if bad is not None:
        char = bad.group()
        kind = "a lone surrogate" if "\ud800" <= char <= "\udfff" else "a control character"
        raise InputError(where, f"holds {kind} (U+{ord(char):04X}) at character "
                         f"{bad.start()}; send valid Unicode text")


def _number_limit(max_abs: float) -> str:
    return f"numbers are limited to +/-{max_abs:g}"


def _check_number(value: int | float, where: str, max_abs: float) -> None:
    if isinstance(value, int):
        if value.bit_length() > 64 or abs(value) > max_abs:
            raise InputError(where, f"is {preview(value)}; {_number_limit(max_abs)}")
        return
    if not math.isfinite(value):
        raise InputError(where, f"must be a finite number, got {value}")
    if abs(value) > max_abs:
        raise InputError(where, f"is {value:g}; {_number_limit(max_abs)}")


def _join(where: str, key: str) -> str:
    return f"{where}.{key}" if where else key


def check_bounds(value: Any, where: str = "", *, max_number_abs: float = MAX_NUMBER_ABS
                 ) -> None:
    """Raise InputError for the first part of a JSON-like value that breaks a bound: depth,
    list length, key and string length and text, number magnitude (`max_number_abs`), or a
    non-JSON type. Iterative, so any Python value is safe to pass."""
    stack: list[tuple[Any, str, int]] = [(value, where, 0)]
    while stack:
        item, at, depth = stack.pop()
        if isinstance(item, bool) or item is None:
            continue
        if isinstance(item, _LongInteger):
            raise InputError(at or "a number",
                             f"is {preview(item)}; {_number_limit(max_number_abs)}")
        if isinstance(item, int | float):
            _check_number(item, at or "a number", max_number_abs)
        elif isinstance(item, str):
            check_text(item, at or "a string")
        elif isinstance(item, list | tuple | Mapping):
            if depth >= MAX_DEPTH:
                raise InputError(at or "the value", f"nests deeper than {MAX_DEPTH} levels")
            if len(item) > MAX_ITEMS:
                raise InputError(at or "the value", f"has {len(item)} items; the limit is "
                                 f"{MAX_ITEMS}")
            if isinstance(item, Mapping):
                for key, child in item.items():
                    if not isinstance(key, str):
                        raise InputError(at or "an object", f"has a non-text key "
                                         f"{preview(key)}")
                    check_text(key, f"a name in {at}" if at else "a name",
                               limit=MAX_NAME_CHARS)
                    stack.append((child, _join(at, key), depth + 1))
            else:
                stack.extend((child, f"{at}[{k}]", depth + 1) for k, child in enumerate(item))
        else:
            raise InputError(at or "the value", f"is {preview(item)}, not a JSON value")


def _depth_scan(text: str, what: str) -> None:
    if text.count("[") + text.count("{") <= MAX_DEPTH:
        return
    depth = 0
    for bracket in _BRACKET.finditer(_STRING_LITERAL.sub('""', text)):
        depth += 1 if bracket.group() in "[{" else -1
        if depth > MAX_DEPTH:
            raise InputError(what, f"nests deeper than {MAX_DEPTH} levels")


def _parse_int(literal: str) -> int | _LongInteger:
    digits = len(literal.lstrip("-"))
    return int(literal) if digits <= MAX_INTEGER_DIGITS else _LongInteger(digits)


def parse_json(raw: bytes | str, what: str = "the body", *, field_prefix: str = "",
               max_bytes: int = MAX_BODY_BYTES, max_number_abs: float = MAX_NUMBER_ABS
               ) -> Any:
    """Parse JSON text within the bounds above (`max_bytes` of text, numbers within
    +/-`max_number_abs`); raises InputError naming `what` for the text as a whole, or the
    field inside it (after `field_prefix`), on anything else."""
    size = len(raw) if isinstance(raw, bytes) else len(raw.encode("utf-8", "surrogatepass"))
    if size > max_bytes:
        raise InputError(what, f"is {size} bytes; the limit is {max_bytes}", http_status=413)
    if isinstance(raw, bytes):
        try:
            text = raw.decode("utf-8")
        except UnicodeDecodeError as error:
            raise InputError(what, f"is not UTF-8 text (byte {error.start})") from None
    else:
        text = raw
    _depth_scan(text, what)
    try:
        value = json.loads(text, parse_int=_parse_int)
    except json.JSONDecodeError as error:
        raise InputError(what, f"is not valid JSON ({error.msg} at character {error.pos})"
                         ) from None
    except RecursionError:  # only reachable when the interpreter's own stack is near full
        raise InputError(what, f"nests deeper than {MAX_DEPTH} levels") from None
    check_bounds(value, field_prefix, max_number_abs=max_number_abs)
    return value


def parse_number(value: Any, where: str) -> float:
    """A number from JSON or from a query string: a JSON number, or ASCII decimal text in
    JSON's number syntax (no '_', no other scripts' digits), finite and within bounds."""
    if isinstance(value, bool) or not isinstance(value, int | float | str | _LongInteger):
        raise InputError(where, f"must be a number, got {preview(value)}")
    if isinstance(value, str):
        text = value.strip()
        if len(text) > MAX_INTEGER_DIGITS + 10 or not _NUMBER_TEXT.match(text):
            raise InputError(where, f"must be a number, got {preview(value)}")
        number = float(text)
        if not math.isfinite(number) or abs(number) > MAX_NUMBER_ABS:
            raise InputError(where, f"is {preview(value)}; {_number_limit(MAX_NUMBER_ABS)}")
        return number
    check_bounds(value, where)  # a _LongInteger raises here
    assert isinstance(value, int | float)
    return float(value)

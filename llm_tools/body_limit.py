"""Request bodies on every HTTP surface (the agent REST API, the MCP server, the web console):
one size limit and one parser, so hostile input gets the same answer everywhere.

`BodyLimit` is an ASGI middleware that refuses bodies over a size limit with HTTP 413. A
declared Content-Length over the limit is refused before the body is read; a body that
arrives in chunks is counted as it streams, and the request is refused as soon as it passes
the limit, so no handler ever sees more than `max_bytes`.

`bound_inputs(app)` installs it with the answer to `InputError` (its 413 or 422 and the
message naming the field); `json_body(model)` is a FastAPI dependency giving a route its body
parsed by `input_limits.parse_json` (the bounds of tool arguments, or a session's) and, when
a pydantic model is given, validated by it (422 naming the field).
"""

from __future__ import annotations

import json
from collections.abc import Awaitable, Callable
from typing import Any, TypeVar

from pydantic import BaseModel, ValidationError
from starlette.applications import Starlette
from starlette.exceptions import HTTPException
from starlette.requests import Request
from starlette.responses import JSONResponse, Response
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from llm_tools.input_limits import MAX_BODY_BYTES, MAX_NUMBER_ABS, InputError, parse_json

__all__ = ["BodyLimit", "BodyTooLarge", "bound_inputs", "json_body"]

Model = TypeVar("Model", bound=BaseModel)


class BodyTooLarge(HTTPException):
    """Raised inside a request when its body passes the limit while streaming (an HTTP 413
    that Starlette's exception middleware answers)."""

    def __init__(self, max_bytes: int, seen: int) -> None:
        super().__init__(413, _detail(max_bytes, seen))


class BodyLimit:
    """Wraps `app`; bodies over `max_bytes` get 413 and never reach it."""

    def __init__(self, app: ASGIApp, *, max_bytes: int = MAX_BODY_BYTES) -> None:
        if max_bytes <= 0:
            raise ValueError(f"max_bytes must be positive, got {max_bytes}")
        self.app = app
        self.max_bytes = max_bytes

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        declared = _content_length(scope)
        if declared is not None and declared > self.max_bytes:
            await self._refuse(send, declared)
            return
        seen = 0
        started = False

        async def counted() -> Message:
            nonlocal seen
            message = await receive()
            if message["type"] == "http.request":
                seen += len(message.get("body", b""))
                if seen > self.max_bytes:
                    raise BodyTooLarge(self.max_bytes, seen)
            return message

        async def tracked(message: Message) -> None:
            nonlocal started
            if message["type"] == "http.response.start":
                started = True
            await send(message)

        try:
            await self.app(scope, counted, tracked)
        except BodyTooLarge:
            if not started:
                await self._refuse(send, seen)

    async def _refuse(self, send: Send, size: int) -> None:
        body = json.dumps({"detail": _detail(self.max_bytes, size)}).encode()
        headers: list[tuple[bytes, bytes]] = [(b"content-type", b"application/json"),
                                              (b"content-length", str(len(body)).encode())]
        await send({"type": "http.response.start", "status": 413, "headers": headers})
        await send({"type": "http.response.body", "body": body})


def _detail(max_bytes: int, size: int) -> str:
    return f"the body is {size} bytes or more; the limit is {max_bytes}"


def _content_length(scope: Scope) -> int | None:
    for name, value in scope.get("headers", []):
        if name == b"content-length":
            text = value.decode("latin-1").strip()
            return int(text) if text.isdigit() and len(text) < 20 else None
    return None


async def _input_error(_: Request, error: Exception) -> Response:
    assert isinstance(error, InputError)
    return JSONResponse({"detail": str(error)}, status_code=error.http_status)


def bound_inputs(app: Starlette, *, max_bytes: int = MAX_BODY_BYTES) -> None:
    """Bodies over `max_bytes` are refused (413) before a route reads them, and an
    `InputError` raised by a route is answered with its status and message."""
    app.add_middleware(BodyLimit, max_bytes=max_bytes)
    app.add_exception_handler(InputError, _input_error)


def _validation_error(error: ValidationError, what: str) -> InputError:
    first = error.errors(include_url=False, include_input=False)[0]
    where = ".".join(str(part) for part in first["loc"]) or what
    more = error.error_count() - 1
    return InputError("", f"{where}: {first['msg']}"
                      + (f" (and {more} more problems)" if more else ""))


def json_body(model: type[Model] | None = None, *, what: str = "the body",
              max_number_abs: float = MAX_NUMBER_ABS, empty: str | None = None
              ) -> Callable[[Request], Awaitable[Any]]:
    """A dependency: the request body parsed within the input bounds (InputError, 413/422,
    otherwise), then validated by `model` when given (422 naming the first bad field). An
    empty body is the JSON text `empty` when given, else refused."""

    async def parsed(request: Request) -> Any:
        raw = await request.body()
        if not raw.strip():
            if empty is None:
                raise InputError(what, "is empty; send a JSON object")
            raw = empty.encode()
        value = parse_json(raw, what, max_number_abs=max_number_abs)
        if model is None:
            return value
        try:
            return model.model_validate(value)
        except ValidationError as error:
            raise _validation_error(error, what) from None

    return parsed

"""A scripted OpenAI-compatible chat-completions server on real HTTP, for the tests whose model
client is in another process or goes through `--base-url` (the CLI, Ray workers, the openai SDK
end to end); agents in process are driven by `swarm_agents.llm.ScriptedChatModel` instead.

Each POST to /v1/chat/completions gets the next scripted reply: an assistant message (tool
calls, possibly malformed, or text), or a raw HTTP status/body. Requests are recorded as they
came over the wire. `answer` (a callable) instead makes each reply from its request, so
concurrent agents get the same replies in any order; `hold` (a callable given the request) may
block it until the test lets it go.
"""

from __future__ import annotations

import contextlib
import json
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any

from swarm_agents.llm.scripted import tool_call as call

__all__ = ["ScriptedLLM", "call", "scripted_llm"]


class ScriptedLLM:
    def __init__(self, replies: list[Any], *, answer: Callable[[dict[str, Any]], Any] | None = None,
                 hold: Callable[[dict[str, Any]], None] | None = None) -> None:
        self.replies = list(replies)
        self.answer = answer
        self.hold = hold
        self.requests: list[dict[str, Any]] = []
        self.base_url = ""
        self._lock = threading.Lock()

    def next_reply(self, request: dict[str, Any]) -> tuple[int, str]:
        if self.hold is not None:
            self.hold(request)
        with self._lock:
            return self._reply(request)

    def _reply(self, request: dict[str, Any]) -> tuple[int, str]:
        self.requests.append(request)
        if self.answer is not None:
            message: Any = self.answer(request)
        elif not self.replies:
            message = {"role": "assistant", "content": "",
                       "tool_calls": [call("finish", {"summary": "script ended"})]}
        else:
            message = self.replies.pop(0)
        if isinstance(message, tuple):  # (status, raw body)
            return message
        if isinstance(message, list):  # a bare list of tool calls
            message = {"role": "assistant", "content": "", "tool_calls": message}
        body = {"id": f"cmpl-{len(self.requests)}", "object": "chat.completion",
                "choices": [{"index": 0, "message": message, "finish_reason": "stop"}],
                "usage": {"prompt_tokens": 100, "completion_tokens": 20, "total_tokens": 120}}
        return 200, json.dumps(body)


@contextmanager
def scripted_llm(replies: list[Any], *, answer: Callable[[dict[str, Any]], Any] | None = None,
                 hold: Callable[[dict[str, Any]], None] | None = None
                 ) -> Iterator[ScriptedLLM]:
    llm = ScriptedLLM(replies, answer=answer, hold=hold)

    class Handler(BaseHTTPRequestHandler):
        def do_POST(self) -> None:
            length = int(self.headers.get("Content-Length", "0"))
            request = json.loads(self.rfile.read(length) or b"{}")
            if self.path != "/v1/chat/completions":
                status, body = 404, '{"error": "not found"}'
            else:
                status, body = llm.next_reply(request)
            data = body.encode()
            # An agent may be gone by now (its process killed while its request was held).
            with contextlib.suppress(BrokenPipeError, ConnectionResetError):
                self.send_response(status)
                self.send_header("Content-Type", "application/json")
                self.send_header("Content-Length", str(len(data)))
                self.end_headers()
                self.wfile.write(data)

        def log_message(self, *args: Any) -> None:
            pass

    server = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    llm.base_url = f"http://127.0.0.1:{server.server_address[1]}/v1"
    try:
        yield llm
    finally:
        server.shutdown()
        server.server_close()

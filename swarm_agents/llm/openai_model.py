"""The `ChatModel` of OpenAI-compatible chat completions (tools included), on the official
`openai` SDK: any server that speaks the chat-completions API (OpenAI, a hosted gateway,
llama.cpp, vLLM, Ollama...) at a base URL."""

from __future__ import annotations

import asyncio
import os
from collections.abc import AsyncIterator, Mapping, Sequence
from contextlib import asynccontextmanager
from dataclasses import dataclass
from typing import Any

import openai

from swarm_agents.llm.model import ChatModel, ModelError, ModelReply, Usage

__all__ = ["ModelConfig", "OpenAIChatModel", "opened"]

# Statuses the SDK retries itself before giving up (request timeout, conflict, rate limit,
# server errors); any other error status is final at once.
_RETRIED_STATUSES = frozenset({408, 409, 429})


@dataclass(frozen=True)
class ModelConfig:
    """Where the model is. Unset fields come from OPENAI_BASE_URL, OPENAI_MODEL and
    OPENAI_API_KEY."""

    base_url: str = ""
    model: str = ""
    api_key: str = ""
    temperature: float = 0.0
    timeout_s: float = 120.0
    retries: int = 2
    price_in_usd_per_mtok: float = 0.0  # per million prompt tokens (else MAVSWARM_PRICE_IN)
    price_out_usd_per_mtok: float = 0.0  # per million completion tokens (MAVSWARM_PRICE_OUT)
    max_completion_tokens: int | None = None  # per answer; None leaves it to the server

    def resolved(self) -> ModelConfig:
        base = self.base_url or os.environ.get("OPENAI_BASE_URL", "https://api.openai.com/v1")
        model = self.model or os.environ.get("OPENAI_MODEL", "")
        if not model:
            raise ValueError("no model: pass --model or set OPENAI_MODEL")
        if self.retries < 0:
            raise ValueError(f"retries must be 0 or more, got {self.retries!r}")
        if not self.timeout_s > 0:
            raise ValueError(f"timeout_s must be positive, got {self.timeout_s!r}")
        if self.max_completion_tokens is not None and self.max_completion_tokens < 1:
            raise ValueError("max_completion_tokens must be at least 1, got "
                             f"{self.max_completion_tokens!r}")
        key = self.api_key or os.environ.get("OPENAI_API_KEY", "")
        price_in = self.price_in_usd_per_mtok or float(os.environ.get("MAVSWARM_PRICE_IN", 0))
        price_out = self.price_out_usd_per_mtok or float(
            os.environ.get("MAVSWARM_PRICE_OUT", 0))
        return ModelConfig(base.rstrip("/"), model, key, self.temperature, self.timeout_s,
                           self.retries, price_in, price_out, self.max_completion_tokens)

    def cost_usd(self, prompt_tokens: int, completion_tokens: int) -> float:
        """The price of one answer's token use."""
        return (prompt_tokens * self.price_in_usd_per_mtok
                + completion_tokens * self.price_out_usd_per_mtok) / 1e6


class OpenAIChatModel:
    """Asks {base_url}/chat/completions (a `ChatModel`).

    The SDK retries transport failures, time-outs, rate limits and server errors
    (`config.retries` times, with back-off); an answer that is not a usable completion is asked
    again as many times. The message comes back as the server sent it (a dict), malformed tool
    calls included: reading them is the agent's business."""

    def __init__(self, config: ModelConfig) -> None:
        self.config = config.resolved()
        # Without a key no Authorization header is sent (local servers need none); the SDK
        # insists on a key, so it gets a stand-in that the omitted header never carries.
        self._headers: dict[str, Any] = ({} if self.config.api_key
                                         else {"Authorization": openai.omit})
        self._client = openai.AsyncOpenAI(
            base_url=self.config.base_url, api_key=self.config.api_key or "unused",
            timeout=self.config.timeout_s, max_retries=self.config.retries)

    async def close(self) -> None:
        await self._client.close()

    async def complete(self, messages: Sequence[Mapping[str, Any]],
                       tools: Sequence[Mapping[str, Any]]) -> ModelReply:
        request: dict[str, Any] = {"model": self.config.model, "messages": list(messages),
                                   "temperature": self.config.temperature,
                                   "extra_headers": self._headers}
        if tools:
            request["tools"] = list(tools)
        if self.config.max_completion_tokens is not None:
            # `max_tokens` is the name every OpenAI-compatible server understands.
            request["max_tokens"] = self.config.max_completion_tokens
        attempts = self.config.retries + 1
        problem = "no attempt"
        for attempt in range(attempts):
            if attempt:
                await asyncio.sleep(min(0.2 * 2 ** attempt, 5.0))
            try:
                completion = await self._client.chat.completions.create(**request)
            except openai.APIStatusError as error:
                detail = f"HTTP {error.status_code}: {error.response.text[:300]}"
                if error.status_code >= 500 or error.status_code in _RETRIED_STATUSES:
                    raise ModelError(_failed(attempts, detail)) from error
                raise ModelError(detail) from error
            except (openai.APITimeoutError, openai.APIConnectionError) as error:
                raise ModelError(_failed(attempts, f"{type(error).__name__}: {error}")) from error
            except (openai.APIResponseValidationError, ValueError) as error:
                problem = f"unusable response ({type(error).__name__}: {error})"
                continue
            answer = _answer(completion)
            if isinstance(answer, str):
                problem = answer
                continue
            message, (prompt, done) = answer
            return ModelReply(message, Usage(prompt, done, self.config.cost_usd(prompt, done)))
        raise ModelError(_failed(attempts, problem))


def _failed(attempts: int, problem: str) -> str:
    times = "once" if attempts == 1 else f"{attempts} times"
    return f"the model backend failed {times}: {problem}"


def _answer(completion: Any) -> tuple[dict[str, Any], tuple[int, int]] | str:
    """The assistant message and token use of a completion, or what makes it unusable."""
    if not isinstance(completion, openai.BaseModel):
        return f"unusable response (not a completion): {str(completion)[:200]}"
    data = completion.to_dict(mode="json", warnings=False)
    try:
        message = data["choices"][0]["message"]  # type: ignore[index]
        if not isinstance(message, dict):
            raise TypeError("message is not an object")
    except (KeyError, IndexError, TypeError) as error:
        return f"unusable response ({error}): {str(data)[:200]}"
    usage = data.get("usage")
    if not isinstance(usage, dict):
        usage = {}
    return message, (_count(usage.get("prompt_tokens")), _count(usage.get("completion_tokens")))


def _count(value: Any) -> int:
    """A token count as reported; anything that is not a count is 0."""
    try:
        return max(int(value or 0), 0)
    except (TypeError, ValueError):
        return 0


@asynccontextmanager
async def opened(model: ChatModel | ModelConfig) -> AsyncIterator[ChatModel]:
    """The model an agent asks during one run: a `ModelConfig` opens an `OpenAIChatModel`,
    closed when the run ends; a `ChatModel` is used as it is (its owner closes it)."""
    if not isinstance(model, ModelConfig):
        yield model
        return
    client = OpenAIChatModel(model)
    try:
        yield client
    finally:
        await client.close()

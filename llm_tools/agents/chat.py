"""A small client for OpenAI-compatible chat completions (tools included)."""

from __future__ import annotations

import asyncio
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import httpx

__all__ = ["ChatClient", "ModelConfig", "ModelError"]


class ModelError(RuntimeError):
    """Raised when the model backend cannot give a usable answer after retries."""


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

    def resolved(self) -> ModelConfig:
        base = self.base_url or os.environ.get("OPENAI_BASE_URL", "https://api.openai.com/v1")
        model = self.model or os.environ.get("OPENAI_MODEL", "")
        if not model:
            raise ValueError("no model: pass --model or set OPENAI_MODEL")
        key = self.api_key or os.environ.get("OPENAI_API_KEY", "")
        price_in = self.price_in_usd_per_mtok or float(os.environ.get("MAVSWARM_PRICE_IN", 0))
        price_out = self.price_out_usd_per_mtok or float(
            os.environ.get("MAVSWARM_PRICE_OUT", 0))
        return ModelConfig(base.rstrip("/"), model, key, self.temperature, self.timeout_s,
                           self.retries, price_in, price_out)

    def cost_usd(self, usage: Mapping[str, int]) -> float:
        """The price of one answer's token use."""
        return (usage["prompt"] * self.price_in_usd_per_mtok
                + usage["completion"] * self.price_out_usd_per_mtok) / 1e6


class ChatClient:
    """POSTs to {base_url}/chat/completions; returns (assistant message, usage)."""

    def __init__(self, config: ModelConfig) -> None:
        self.config = config.resolved()
        headers = {"Authorization": f"Bearer {self.config.api_key}"} if self.config.api_key \
            else {}
        self._http = httpx.AsyncClient(base_url=self.config.base_url, headers=headers,
                                       timeout=self.config.timeout_s)

    async def close(self) -> None:
        await self._http.aclose()

    async def complete(self, messages: Sequence[Mapping[str, Any]],
                       tools: Sequence[Mapping[str, Any]]
                       ) -> tuple[dict[str, Any], dict[str, int]]:
        body: dict[str, Any] = {"model": self.config.model, "messages": list(messages),
                                "temperature": self.config.temperature}
        if tools:
            body["tools"] = list(tools)
        problem = "no attempt"
        for attempt in range(self.config.retries + 1):
            if attempt:
                await asyncio.sleep(min(0.2 * 2 ** attempt, 5.0))
            try:
                response = await self._http.post("/chat/completions", json=body)
            except httpx.HTTPError as error:
                problem = f"{type(error).__name__}: {error}"
                continue
            if response.status_code >= 500 or response.status_code == 429:
                problem = f"HTTP {response.status_code}: {response.text[:200]}"
                continue
            if response.status_code >= 400:
                raise ModelError(f"HTTP {response.status_code}: {response.text[:300]}")
            try:
                data = response.json()
                message = data["choices"][0]["message"]
                if not isinstance(message, dict):
                    raise TypeError("message is not an object")
            except (ValueError, KeyError, IndexError, TypeError) as error:
                problem = f"unusable response ({error}): {response.text[:200]}"
                continue
            usage = data.get("usage") or {}
            return message, {"prompt": int(usage.get("prompt_tokens") or 0),
                             "completion": int(usage.get("completion_tokens") or 0)}
        raise ModelError(f"the model backend failed {self.config.retries + 1} times: {problem}")

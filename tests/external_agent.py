"""A scripted agent that makes the same decisions whatever surface it acts through: over REST
(httpx) or MCP (the official SDK client) as a separate process, or in-process on the tools.

It flies three drones of `target_assignment-easy-1` (d1, d2 take off together, fly, hover,
land together) with plain calls and `batch` calls, one bad call in a batch, and a
random think time before every step (seeded). Run as a process it prints the results as one
JSON line: per step, a call's result dict, or a batch's list of results.

    python -m tests.external_agent rest URL KEY SESSION --seed 3 --max-think-s 0.5
    python -m tests.external_agent mcp URL --seed 3 --max-think-s 0.5
"""

from __future__ import annotations

import argparse
import asyncio
import json
import random
import sys
from collections.abc import Awaitable, Callable
from typing import Any

Call = tuple[str, dict[str, Any]]
Step = tuple[str, list[Call]]  # ("call", [one call]) or ("batch", [calls side by side])

STEPS: list[Step] = [
    ("call", [("list_drones", {})]),
    ("batch", [("take_off", {"drone_id": "d1", "altitude_m": 10.0}),
               ("take_off", {"drone_id": "d2", "altitude_m": 12.0})]),
    ("call", [("move_towards", {"drone_id": "d1", "heading_deg": 90.0, "distance_m": 30.0})]),
    ("batch", [("move_towards", {"drone_id": "d2", "heading_deg": 0.0, "distance_m": 25.0}),
               ("hover", {"drone_id": "d1", "duration_s": 3.0}),
               ("take_off", {"drone_id": "d3"}),  # no altitude: this call's own error
               ("drone_state", {"drone_id": "d3"})]),
    ("call", [("hover", {"drone_id": "d1", "duration_s": 2.0})]),
    ("call", [("nearby", {"drone_id": "d2"})]),
    ("batch", [("land", {"drone_id": "d1"}), ("land", {"drone_id": "d2"})]),
    ("call", [("finish", {"summary": "flew d1 and d2 and landed them"})]),
]

Act = Callable[[str, dict[str, Any]], Awaitable[dict[str, Any]]]


def batch_arguments(calls: list[Call]) -> dict[str, Any]:
    return {"calls": [{"tool": name, "arguments": args} for name, args in calls]}


async def play(act: Act, rng: random.Random, max_think_s: float) -> list[Any]:
    """Make every decision through `act(tool, arguments)`, thinking a random time first."""
    results: list[Any] = []
    for kind, calls in STEPS:
        await asyncio.sleep(rng.uniform(0.0, max_think_s))
        if kind == "call":
            (name, args), = calls
            results.append(await act(name, args))
        else:
            batch = await act("batch", batch_arguments(calls))
            assert batch["status"] == "ok", batch
            results.append(batch["results"])
    return results


async def over_rest(url: str, key: str, session: str, rng: random.Random,
                    max_think_s: float) -> list[Any]:
    import httpx

    async with httpx.AsyncClient(base_url=url, timeout=120.0,
                                 headers={"X-API-Key": key}) as client:
        async def act(name: str, args: dict[str, Any]) -> dict[str, Any]:
            reply = await client.post(f"/sessions/{session}/tools/{name}", json=args)
            assert reply.status_code in (200, 422), reply.text
            return dict(reply.json())

        return await play(act, rng, max_think_s)


async def over_mcp(url: str, rng: random.Random, max_think_s: float) -> list[Any]:
    from mcp import Client

    async with Client(url) as client:
        async def act(name: str, args: dict[str, Any]) -> dict[str, Any]:
            result = await client.call_tool(name, args)
            assert result.structured_content is not None, result.content
            return dict(result.structured_content)

        return await play(act, rng, max_think_s)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("surface", choices=("rest", "mcp"))
    parser.add_argument("url")
    parser.add_argument("key", nargs="?")
    parser.add_argument("session", nargs="?")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--max-think-s", type=float, default=0.0)
    args = parser.parse_args(argv)
    rng = random.Random(args.seed)
    if args.surface == "rest":
        results = asyncio.run(over_rest(args.url, args.key, args.session, rng,
                                        args.max_think_s))
    else:
        results = asyncio.run(over_mcp(args.url, rng, args.max_think_s))
    sys.stdout.write(json.dumps(results) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""A scripted external agent for hosted runs, run as a process of its own: it takes every task
from a hosted run's `/next` and makes the calls a script gives for it, over REST or over MCP
(the official SDK's client), until `/next` answers 204.

    python tests/hosted_client.py rest|mcp ENDPOINT SCRIPT.json [--think-s S]

SCRIPT.json maps a task id to its calls, ``[[tool, arguments], ...]``. One JSON line per task
goes to stdout: ``{"task": id, "results": [[http_status, result], ...]}`` (MCP: status 200,
the structured result). `--think-s` sleeps that long before every call.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import sys
import time
from typing import Any

import httpx


def play_rest(task: dict[str, Any], calls: list[list[Any]], think_s: float) -> list[Any]:
    results = []
    with httpx.Client(headers={"X-API-Key": task["key"]}, timeout=120.0) as http:
        for name, arguments in calls:
            time.sleep(think_s)
            answer = http.post(f"{task['tools_url']}/{name}", json=arguments)
            results.append([answer.status_code, answer.json()])
    return results


async def play_mcp(task: dict[str, Any], calls: list[list[Any]], think_s: float) -> list[Any]:
    import httpx2
    from mcp import Client
    from mcp.client.streamable_http import streamable_http_client
    results = []
    http = httpx2.AsyncClient(headers={"X-API-Key": task["key"]}, timeout=120.0)
    async with http, Client(streamable_http_client(task["mcp_url"], http_client=http)) as mcp:
        for name, arguments in calls:
            await asyncio.sleep(think_s)
            result = await mcp.call_tool(name, arguments)
            results.append([200, result.structured_content])
    return results


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("surface", choices=("rest", "mcp"))
    parser.add_argument("endpoint")
    parser.add_argument("script")
    parser.add_argument("--think-s", type=float, default=0.0)
    args = parser.parse_args()
    with open(args.script, encoding="utf-8") as f:
        script = json.load(f)
    while True:
        answer = httpx.get(f"{args.endpoint}/next", timeout=60.0)
        if answer.status_code == 204:
            return 0
        if answer.status_code == 503:
            continue
        answer.raise_for_status()
        task = answer.json()
        calls = script.get(task["task_id"], [["finish", {}]])
        if args.surface == "rest":
            results = play_rest(task, calls, args.think_s)
        else:
            results = asyncio.run(play_mcp(task, calls, args.think_s))
        print(json.dumps({"task": task["task_id"], "results": results}), flush=True)


if __name__ == "__main__":
    sys.exit(main())

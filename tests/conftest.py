"""Shared fixtures: free UDP ports, running swarms, a MAVSDK client that finds them, a
headless Chromium for the console pages, and Hypothesis draws that are the same whatever the
session collected (tests/hypothesis_draws.py)."""

from __future__ import annotations

import asyncio
import concurrent.futures
import contextlib
import time
import weakref
from collections.abc import AsyncIterator, Awaitable, Callable, Iterator
from typing import Any

import pytest

from emulator.clock import ClockConfig
from emulator.scenario import Scenario, default_scenario
from emulator.swarm import PortPlan, Swarm
from tests import file_order
from tests.browser_fixtures import CHROMIUM_ARGS, chromium_path
from tests.hypothesis_draws import import_project_source, load_profile
from tests.ports import drop_registry, unused_udp_port

_executor_size: weakref.WeakKeyDictionary[asyncio.AbstractEventLoop, int] = (
    weakref.WeakKeyDictionary()
)


load_profile()  # before the test modules are imported: their @settings build on it


def pytest_collection_finish(session: pytest.Session) -> None:
    """The whole project is imported before the first test, so Hypothesis's pool of source
    literals is the same whatever test files were collected (tests/hypothesis_draws.py); a
    session without a Hypothesis test draws nothing and skips it."""
    if any(getattr(getattr(item, "obj", None), "is_hypothesis_test", False)
           for item in session.items):
        import_project_source()


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """A test that flies with MAVSDK or drives Chromium takes seconds: it is slow too, so
    `-m "not slow"` (the fast tier) leaves it out."""
    for item in items:
        if item.get_closest_marker("mavsdk") or item.get_closest_marker("browser"):
            item.add_marker(pytest.mark.slow)


def pytest_addoption(parser: pytest.Parser) -> None:
    file_order.add_option(parser)


def pytest_configure(config: pytest.Config) -> None:
    config.pluginmanager.register(file_order.FileOrder(config), "mavswarm-file-order")


def pytest_sessionfinish(session: pytest.Session) -> None:
    drop_registry()  # the xdist workers' record of the ports handed out (tests/ports.py)


@pytest.fixture
def udp_port() -> Callable[[], int]:
    """Call it for a fresh unused UDP port on 127.0.0.1."""
    return unused_udp_port


SwarmFactory = Callable[..., Awaitable[Swarm]]


@pytest.fixture
async def swarm_factory() -> AsyncIterator[SwarmFactory]:
    """`await swarm_factory(n)` starts a swarm on 127.0.0.1 and closes it after the test.

    The swarm binds an ephemeral port and sends to a fresh API port (`swarm.ports.api_port`);
    no GCS port. Keywords: `scenario` (default: `default_scenario(n)`), `speed` (real-time
    factor, default 20), `clock` (overrides `speed`), `telemetry_hz`.
    """
    swarms: list[Swarm] = []

    async def make(n: int = 1, *, scenario: Scenario | None = None, speed: float = 20.0,
                   clock: ClockConfig | None = None, **kwargs: object) -> Swarm:
        ports = PortPlan(bind_host="127.0.0.1", bind_port=0, api_port=unused_udp_port(),
                         gcs_port=0)
        swarm = Swarm(scenario or default_scenario(n), clock=clock or ClockConfig(speed=speed),
                      ports=ports, **kwargs)  # type: ignore[arg-type]
        await swarm.start()
        swarms.append(swarm)
        return swarm

    try:
        yield make
    finally:
        for swarm in reversed(swarms):
            await swarm.close()


@contextlib.asynccontextmanager
async def mavsdk_systems(port: int, n: int, *, timeout_s: float = 10.0,
                         url: str | None = None) -> AsyncIterator[list]:
    """A GROUND_STATION MAVSDK listening on `udpin://127.0.0.1:port`, until `n` systems are
    connected with an autopilot; yields them sorted by system id (mavsdk.asyncio Systems).

    Enlarges the loop's default executor first: the binding runs every blocking call on it.
    """
    from mavsdk.asyncio import ComponentType, Configuration, Mavsdk

    loop = asyncio.get_running_loop()
    workers = max(32, 2 * n + 8)
    if _executor_size.get(loop, 0) < workers:
        loop.set_default_executor(concurrent.futures.ThreadPoolExecutor(workers))
        _executor_size[loop] = workers
    config = Configuration.create_with_component_type(ComponentType.GROUND_STATION)
    async with Mavsdk(config) as mavsdk:
        await mavsdk.add_any_connection(url or f"udpin://127.0.0.1:{port}")
        deadline = time.monotonic() + timeout_s
        while True:
            ready = []
            for system in await mavsdk.get_systems():
                if await system.is_connected() and await system.has_autopilot():
                    ready.append((await system.get_system_id(), system))
            if len(ready) >= n:
                break
            if time.monotonic() > deadline:
                raise TimeoutError(f"MAVSDK found {len(ready)} of {n} systems in {timeout_s} s")
            await asyncio.sleep(0.05)
        ready.sort(key=lambda pair: pair[0])
        yield [system for _, system in ready]


@pytest.fixture
def mavsdk_client() -> Callable[..., contextlib.AbstractAsyncContextManager[list]]:
    """`async with mavsdk_client(swarm.ports.api_port, n) as systems:` (see mavsdk_systems)."""
    return mavsdk_systems


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    """One headless Chromium (Debian's, through Playwright) per test module."""
    from playwright.sync_api import sync_playwright
    path = chromium_path()
    with sync_playwright() as playwright:
        launched = playwright.chromium.launch(executable_path=path, args=CHROMIUM_ARGS)
        yield launched
        launched.close()

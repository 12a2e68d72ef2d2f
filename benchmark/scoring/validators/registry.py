"""Every check endpoint by name."""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType

from benchmark.scoring.validators.endpoint import Endpoint
from benchmark.scoring.validators.history import HISTORY_ENDPOINTS
from benchmark.scoring.validators.state import STATE_ENDPOINTS
from benchmark.scoring.validators.targets import TARGET_ENDPOINTS

__all__ = ["ENDPOINTS", "ENDPOINT_PREFIX", "endpoint_name"]

ENDPOINT_PREFIX = "/check/"


def _table(*groups: tuple[Endpoint, ...]) -> Mapping[str, Endpoint]:
    table: dict[str, Endpoint] = {}
    for group in groups:
        for endpoint in group:
            if endpoint.name in table:
                raise ValueError(f"check endpoint {endpoint.name!r} is defined twice")
            table[endpoint.name] = endpoint
    return MappingProxyType(table)


ENDPOINTS: Mapping[str, Endpoint] = _table(STATE_ENDPOINTS, TARGET_ENDPOINTS, HISTORY_ENDPOINTS)
"""Check endpoints by name (without the ``/check/`` prefix)."""


def endpoint_name(raw: str) -> str:
    """The registry name of an endpoint as written in a tree (a leading /check/ is dropped)."""
    name = raw.strip()
    return name[len(ENDPOINT_PREFIX):] if name.startswith(ENDPOINT_PREFIX) else name

"""The `bench run` options of a hosted run, kept apart from the servers so that every other
`mavswarm` command starts without loading them."""

from __future__ import annotations

import argparse

__all__ = ["DEFAULT_HOST", "DEFAULT_PORT", "add_hosted_arguments"]

DEFAULT_HOST = "127.0.0.1"
DEFAULT_PORT = 8770


def add_hosted_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--host", default=DEFAULT_HOST,
                        help="--agent external: the address the hosted run listens on "
                             f"(default {DEFAULT_HOST})")
    parser.add_argument("--port", type=int, default=DEFAULT_PORT,
                        help="--agent external: the endpoint's TCP port (0: a free one; "
                             f"default {DEFAULT_PORT})")

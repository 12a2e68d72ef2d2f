"""The `mavswarm` command, composed from each package's own subcommands.

  mavswarm up      a swarm of emulated PX4 quadrotors (emulator)
  mavswarm serve   live benchmark sessions over the REST API (benchmark.server)
  mavswarm mcp     one session's agent tools over MCP (benchmark.server)
  mavswarm bench   generate, run, report and import the benchmark (benchmark)
  mavswarm mqtt-bridge  any MAVLink fleet on an MQTT broker (mqtt_bus)
  mavswarm replay  recorded runs in the web console (console; `up --web`: the live view)

`--verbose` (up, serve, bench run, bench generate) prints MAVSDK's own log lines and the
packages' info logging; without it MAVSDK is silent.

Each package adds its subcommands with `add_parsers(subparsers)` and names the function that
runs them (`run`, taking the parsed options, returning the exit status); a package above may
add to a command below it (`extend_up`...). This module only assembles them, and imports only
the parts of the command asked for: `mavswarm up` does not load the benchmark or the REST
server (`--help` and an unknown command load every part).
"""

from __future__ import annotations

import argparse
import importlib
import logging
import signal
import sys
import threading
from collections.abc import Sequence
from typing import NoReturn

from mavlink_gateway import set_mavsdk_log

__all__ = ["OneLineParser", "build_parser", "main"]

PARTS: tuple[tuple[str, frozenset[str]], ...] = (
    ("emulator.cli:add_parsers", frozenset({"up"})),
    ("mqtt_bus.cli:extend_up", frozenset({"up"})),
    ("benchmark.server.serve:add_parsers", frozenset({"serve", "mcp"})),
    ("benchmark.cli:add_parsers", frozenset({"bench"})),
    ("mqtt_bus.cli:add_parsers", frozenset({"mqtt-bridge"})),
    ("console.cli:add_parsers", frozenset({"replay"})),
    ("console.cli:extend_up", frozenset({"up"})),
    ("console.cli:extend_serve", frozenset({"serve"})),
    ("console.cli:extend_bench", frozenset({"bench"})),
)
"""Every part of the command line, `module:function(subparsers)`, in the order they apply,
with the commands it defines or adds to."""

COMMANDS = frozenset().union(*(commands for _, commands in PARTS))


class OneLineParser(argparse.ArgumentParser):
    """An argument parser whose errors are one line (and exit 2), as every other error of the
    command is; the usage is one `--help` away. Subcommands' parsers are of this class too."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The whole command line, or the part of it `command` needs (a command that does not
    exist gets the whole, so that its error lists every command)."""
    parser = OneLineParser(prog="mavswarm", description=__doc__.split("\n\n")[0],
                           formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for part, commands in PARTS:
        if command not in COMMANDS or command in commands:
            module, function = part.split(":")
            getattr(importlib.import_module(module), function)(sub)
    return parser


def _command(argv: Sequence[str]) -> str | None:
    """The command named on the line (its first word: `mavswarm` itself takes no options but
    --help)."""
    return argv[0] if argv and not argv[0].startswith("-") else None


def _stop_on_ctrl_c() -> None:
    """Make Ctrl-C (SIGINT) stop the command, as every command says it does.

    A shell starts a command in the background (`mavswarm up &` in a script, a CI step) with
    SIGINT ignored, and Python then leaves it ignored: `kill -INT` would not stop a swarm, a
    server or a console left open. Python's own handler is put back (in the main thread, the
    only one that may set handlers)."""
    if threading.current_thread() is threading.main_thread() and \
            signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)


def main(argv: Sequence[str] | None = None) -> int:
    """Run `mavswarm` with `argv` (default: the process's arguments); the exit status."""
    _stop_on_ctrl_c()
    words = list(sys.argv[1:] if argv is None else argv)
    args = build_parser(_command(words)).parse_args(words)
    verbose = bool(getattr(args, "verbose", False))
    set_mavsdk_log(verbose)  # MAVSDK's own log lines: off unless --verbose
    if verbose:
        logging.basicConfig(level=logging.INFO, format="%(levelname)s %(name)s: %(message)s")
    return int(args.run(args))


if __name__ == "__main__":
    sys.exit(main())

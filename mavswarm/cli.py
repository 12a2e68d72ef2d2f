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
runs them (`run`, taking the parsed options, returning the exit status); this module only
assembles them.
"""

from __future__ import annotations

import argparse
import logging
import signal
import sys
import threading
from collections.abc import Sequence
from typing import NoReturn

from benchmark import cli as bench_cli
from benchmark.server import serve
from console import cli as console_cli
from emulator import cli as emulator_cli
from mavlink_gateway import set_mavsdk_log
from mqtt_bus import cli as mqtt_cli

__all__ = ["OneLineParser", "build_parser", "main"]


class OneLineParser(argparse.ArgumentParser):
    """An argument parser whose errors are one line (and exit 2), as every other error of the
    command is; the usage is one `--help` away. Subcommands' parsers are of this class too."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    """The whole command line."""
    parser = OneLineParser(prog="mavswarm", description=__doc__.split("\n\n")[0],
                           formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    emulator_cli.add_parsers(sub)
    mqtt_cli.extend_up(sub.choices["up"])
    serve.add_parsers(sub)
    bench_cli.add_parsers(sub)
    mqtt_cli.add_parsers(sub)
    console_cli.add_parsers(sub)
    console_cli.extend_parsers(sub)
    return parser


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
    args = build_parser().parse_args(argv)
    verbose = bool(getattr(args, "verbose", False))
    set_mavsdk_log(verbose)  # MAVSDK's own log lines: off unless --verbose
    if verbose:
        logging.basicConfig(level=logging.INFO, format="%(levelname)s %(name)s: %(message)s")
    return int(args.run(args))


if __name__ == "__main__":
    sys.exit(main())

"""The `mavswarm` command, composed from each package's own subcommands.

  mavswarm up      a swarm of emulated PX4 quadrotors (emulator)
  mavswarm serve   live benchmark sessions over the REST API (benchmark.server)
  mavswarm mcp     one session's agent tools over MCP (benchmark.server)
  mavswarm bench   generate, run, report and import the benchmark (benchmark)
  mavswarm replay  recorded runs in the web console (console; `up --web`: the live view)

Each package adds its subcommands with `add_parsers(subparsers)` and names the function that
runs them (`run`, taking the parsed options, returning the exit status); this module only
assembles them.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from benchmark import cli as bench_cli
from benchmark.server import serve
from console import cli as console_cli
from emulator import cli as emulator_cli

__all__ = ["build_parser", "main"]


def build_parser() -> argparse.ArgumentParser:
    """The whole command line."""
    parser = argparse.ArgumentParser(prog="mavswarm", description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    emulator_cli.add_parsers(sub)
    serve.add_parsers(sub)
    bench_cli.add_parsers(sub)
    console_cli.add_parsers(sub)
    console_cli.extend_parsers(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run `mavswarm` with `argv` (default: the process's arguments); the exit status."""
    args = build_parser().parse_args(argv)
    return int(args.run(args))


if __name__ == "__main__":
    sys.exit(main())

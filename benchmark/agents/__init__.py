"""Baseline agents of the benchmark (the oracle lives in `benchmark.oracle`)."""

from benchmark.agents.noop import NoopAgent

__all__ = ["NoopAgent"]

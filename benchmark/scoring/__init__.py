"""Scoring: the hidden validators that evaluate a task's check tree against the ground truth,
the benchmark metrics over result records, and descriptions of failed checks."""

__all__: list[str] = []

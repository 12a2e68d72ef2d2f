"""Exceptions raised by the hidden validators."""

from __future__ import annotations

__all__ = ["CheckDefinitionError", "EvaluationError"]


class CheckDefinitionError(ValueError):
    """A check tree cannot be used: bad structure, unknown endpoint or a bad parameter.

    The message starts with the path of the offending field, for example
    ``checks[2].parameters.tolerance: must be >= 0, got -1``.
    """


class EvaluationError(RuntimeError):
    """A leaf cannot be evaluated on the ground truth (for example no samples for a drone)."""

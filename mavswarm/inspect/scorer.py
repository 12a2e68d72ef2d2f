"""The scorer of the inspect tasks: the task's hidden checks run on the ground truth of its
window (`benchmark.scoring.validators`), as `bench run` runs them.

The value is CORRECT when the check tree passes, else INCORRECT. The metadata holds the check
ratio (leaves passed / leaves), the check tree (its definition, ``tree``, and every leaf's
verdict, ``leaves``, each naming its place in the tree by ``path``) and what ended the task.
A task that could not be run scores INCORRECT with the reason.
"""

from __future__ import annotations

from typing import Any

from inspect_ai.scorer import (
    CORRECT,
    INCORRECT,
    Metric,
    SampleScore,
    Score,
    Scorer,
    Target,
    accuracy,
    metric,
    scorer,
    stderr,
)
from inspect_ai.solver import TaskState

from benchmark.scoring.failed_checks import failed_leaves
from benchmark.scoring.validators import CheckContext, evaluate, leaf_count, tree_to_json
from mavswarm.inspect.solver import RECORD_KEY, take_truth

__all__ = ["check_ratio", "swarm_checks"]


@metric
def check_ratio() -> Metric:
    """Mean share of check leaves passed per task."""
    def compute(scores: list[SampleScore]) -> float:
        ratios = [float((s.score.metadata or {}).get("check_ratio", 0.0)) for s in scores]
        return sum(ratios) / len(ratios) if ratios else 0.0
    return compute


@scorer(metrics=[accuracy(), stderr(), check_ratio()])
def swarm_checks() -> Scorer:
    """Pass/fail of the task's hidden check tree on the ground truth of its window."""

    async def score(state: TaskState, target: Target) -> Score:
        record: dict[str, Any] = state.store.get(RECORD_KEY) or {}
        ended = {k: record.get(k) for k in ("finish", "error", "tool_calls", "sim_time_s",
                                            "tokens")}
        held = take_truth(state)
        if held is None or held.context is None or held.task.checks is None:
            why = record.get("error") or "the task was not flown (its solver did not finish)"
            return Score(value=INCORRECT, explanation=f"not scored: {why}",
                         metadata={"check_ratio": 0.0, "checks_passed": 0,
                                   "checks_total": 0, "checks": None, **ended})
        truth = held.context
        result = evaluate(held.task.checks, CheckContext(truth.history, truth.scenario,
                                                         truth.t0_s, truth.t1_s))
        leaves = [leaf.to_json() for leaf in result.leaves]
        total = leaf_count(held.task.checks)
        passed = sum(1 for leaf in result.leaves if leaf.passed)
        explanation = f"{passed}/{total} checks passed"
        failed = failed_leaves({"checks": leaves})
        if failed:
            explanation += "; failed: " + "; ".join(
                f"{f.endpoint}({f.subject}) measured {f.measured}"
                + (f", limits {f.threshold}" if f.threshold else "")
                + (f" ({f.note})" if f.note else "") for f in failed)
        return Score(value=CORRECT if result.passed else INCORRECT,
                     answer=record.get("finish"), explanation=explanation,
                     metadata={"check_ratio": passed / total if total else 0.0,
                               "checks_passed": passed, "checks_total": total,
                               "checks": {"tree": tree_to_json(held.task.checks),
                                          "leaves": leaves},
                               **ended})

    return score

"""The entry point inspect loads for the ``mavswarm/`` namespace
(``[project.entry-points.inspect_ai]`` in pyproject.toml): registers every task."""

from mavswarm.inspect.tasks import (  # noqa: F401
    area_assignment_and_patrol,
    area_search,
    full,
    resilience,
    sessions,
    smoke,
    target_assignment,
    target_tracking,
)

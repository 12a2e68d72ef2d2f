"""`bench generate --world FILE`: tasks drawn for a world of one's own."""

from __future__ import annotations

from pathlib import Path

from benchmark.generate import TASKS_PER_SESSION, catalogue_with, generate_for_world, write_session
from benchmark.session_file import read_session_json
from benchmark.suite import Draw

__all__ = ["generate_world_file"]


def generate_world_file(world_file: Path, out_dir: Path, draw: Draw, verify: bool) -> Path:
    """Draw the tasks for the world of a session file (its own tasks are replaced), prove
    them with the oracle when verify, and write the session into out_dir."""
    data = read_session_json(world_file)
    if not isinstance(data, dict):
        raise ValueError(f"{world_file}: the top level must be a JSON object")
    catalogue = catalogue_with(draw.templates, replace=draw.replace)
    session = generate_for_world(data, secret=draw.secret, verify=verify,
                                 tasks=draw.tasks or TASKS_PER_SESSION, catalogue=catalogue)
    return write_session(session, out_dir)

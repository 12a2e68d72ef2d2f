"""Helpers for the inspect_ai tests: the ``inspect`` command beside this interpreter, run so
that it finds the ``mavswarm/`` tasks of this tree.

inspect finds a package's tasks through the ``inspect_ai`` entry points of the installed
distributions. An editable install made before pyproject.toml declared them lacks them; then
the command runs with a folder holding a small distribution record whose entry points are
read from this tree's pyproject.toml. A current install already has them, and the record is
left out, and so is this tree itself where it holds the metadata of an editable install
(inspect finds no task when the same entry point is declared twice).
"""

from __future__ import annotations

import os
import sys
import tomllib
from importlib.metadata import entry_points
from pathlib import Path

from tests.cli_fixtures import ROOT

__all__ = ["INSPECT", "inspect_env"]

INSPECT = str(Path(sys.executable).with_name("inspect"))
OFFLINE_TOKENS = ROOT / "tests" / "offline_tokens"


def _entry_points_dist(folder: Path) -> Path:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    entries = project["entry-points"]["inspect_ai"]
    dist = folder / "mavswarm_tree_entry_points-0.dist-info"
    dist.mkdir(parents=True, exist_ok=True)
    (dist / "METADATA").write_text(
        "Metadata-Version: 2.1\nName: mavswarm-tree-entry-points\nVersion: 0\n")
    (dist / "entry_points.txt").write_text(
        "[inspect_ai]\n" + "".join(f"{name} = {target}\n" for name, target in entries.items()))
    return folder


def inspect_env(tmp: Path) -> dict[str, str]:
    """The environment for an ``inspect`` subprocess: this tree first on the path, its entry
    points, and tests/offline_tokens (see its sitecustomize) for mockllm's token counts."""
    paths = [str(OFFLINE_TOKENS)]
    if not any(ROOT.glob("*.egg-info")):  # an editable install's metadata would come twice
        paths.insert(0, str(ROOT))
    if not any(e.name == "mavswarm" for e in entry_points(group="inspect_ai")):
        paths.append(str(_entry_points_dist(tmp / "entry_points")))
    old = os.environ.get("PYTHONPATH")
    return {**os.environ, "PYTHONPATH": os.pathsep.join([*paths, *([old] if old else [])]),
            "INSPECT_LOG_DIR": str(tmp / "logs")}

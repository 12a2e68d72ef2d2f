"""Hypothesis draws that are the same on every run, whatever test files a session collected.

Two things decide what a @given test draws:

* its random seed: the suite's settings profile `mavswarm` is derandomized (a test's seed
  comes from its own source) with no example database, so a run never replays what an
  earlier one found; a test that needs other draws takes `@seed(n)`, and a regression found
  once is kept as an `@example`;
* Hypothesis's pool of literals: now and then it draws a literal found in the source of the
  project modules imported at the time (not in test files). `import_project_source()`
  imports every module of the project's packages before the first test, so the pool is the
  same whole-project pool whatever the session collected or imported on its way.

tests/conftest.py loads the profile and imports the project once collection is done
(`pytest_collection_finish`). An edit of the project's source may change the pool and so the
draws, as an edit of a test changes its derandomized seed.
"""

from __future__ import annotations

import importlib
import pkgutil
import tomllib
from pathlib import Path

from hypothesis import settings

__all__ = ["PROFILE", "import_project_source", "load_profile", "project_packages"]

PROFILE = "mavswarm"
ROOT = Path(__file__).resolve().parent.parent

settings.register_profile(
    PROFILE,
    derandomize=True,
    database=None,
    deadline=None,
    print_blob=True,
)


def load_profile() -> None:
    """Make the suite's profile the default of every @given test."""
    settings.load_profile(PROFILE)


def project_packages() -> list[str]:
    """The project's packages, as pyproject.toml's [tool.mypy] lists them."""
    with (ROOT / "pyproject.toml").open("rb") as f:
        return list(tomllib.load(f)["tool"]["mypy"]["files"])


def import_project_source() -> list[str]:
    """Import every module of the project's packages (not `__main__`); their names."""
    names: list[str] = []
    for package in project_packages():
        module = importlib.import_module(package)
        names.append(package)
        for info in pkgutil.walk_packages(module.__path__, f"{package}."):
            if info.name.rsplit(".", 1)[-1] == "__main__":
                continue
            importlib.import_module(info.name)
            names.append(info.name)
    return names

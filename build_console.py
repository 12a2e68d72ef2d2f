"""Build step for the mavswarm package: the web console's page script.

console/static/app.js is not in git: npm bundles it (esbuild, console/web's lockfile) from
console/web/src. Building the package (`python -m build`, `pip install .`) runs this first, so a
wheel always carries the page: the bundle is (re)built when it is missing or older than its
sources, and the build stops with a clear message when Node.js is not installed. An sdist carries
the built bundle, so a wheel built from it needs no Node.js.

`python build_console.py` does the same by hand (./dev runs it before every command).
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

from setuptools.command.build_py import build_py
from setuptools.command.sdist import sdist
from setuptools.errors import SetupError

__all__ = ["BuildPy", "Sdist", "build_bundle", "bundle_is_stale"]

ROOT = Path(__file__).resolve().parent
WEB = ROOT / "console" / "web"
BUNDLE = ROOT / "console" / "static" / "app.js"
NEEDS_NODE = ("building mavswarm needs Node.js with npm (https://nodejs.org/) to bundle the web "
              "console's page (console/static/app.js) from console/web")


def _sources(web: Path) -> list[Path]:
    return [web / "package.json", web / "package-lock.json",
            *(path for path in (web / "src").rglob("*") if path.is_file())]


def bundle_is_stale(web: Path = WEB, bundle: Path = BUNDLE) -> bool:
    """Whether the bundle is missing or older than any of its sources (when they are here)."""
    if not bundle.is_file():
        return True
    if not web.is_dir():
        return False  # an sdist's tree carries the bundle without its sources' node_modules
    built = bundle.stat().st_mtime
    return any(path.is_file() and path.stat().st_mtime > built for path in _sources(web))


def build_bundle(web: Path = WEB, bundle: Path = BUNDLE) -> None:
    """Bundle the page if it is missing or stale (`npm ci` first where node_modules is missing
    or older than the lockfile); SetupError, saying what to install, when that cannot be done."""
    if not bundle_is_stale(web, bundle):
        return
    if not (web / "package.json").is_file():
        raise SetupError(f"{bundle} is missing and so is its source folder {web}")
    npm = shutil.which("npm")
    if npm is None:
        raise SetupError(f"{NEEDS_NODE}; npm is not on PATH")
    modules = web / "node_modules"
    lock = web / "package-lock.json"
    if not modules.is_dir() or lock.stat().st_mtime > modules.stat().st_mtime:
        if modules.is_symlink():  # `npm ci` would empty the folder it links to
            raise SetupError(f"{modules} links to a folder older than {lock}: run `npm ci` "
                             "where it links to")
        _npm(npm, web, "ci", "--no-audit", "--no-fund", "--loglevel=error")
        modules.touch()
    _npm(npm, web, "run", "--silent", "build")
    if not bundle.is_file():
        raise SetupError(f"`npm run build` in {web} did not write {bundle}")


def _npm(npm: str, web: Path, *args: str) -> None:
    result = subprocess.run([npm, *args], cwd=web, check=False)
    if result.returncode != 0:
        raise SetupError(f"`npm {' '.join(args)}` in {web} failed (exit {result.returncode})")


class BuildPy(build_py):
    """setuptools' build_py, after bundling the console's page."""

    def run(self) -> None:
        build_bundle()
        super().run()


class Sdist(sdist):
    """setuptools' sdist, after bundling the console's page (the sdist ships it)."""

    def run(self) -> None:
        build_bundle()
        super().run()


if __name__ == "__main__":
    try:
        build_bundle()
    except SetupError as error:
        sys.exit(f"build_console: {error}")

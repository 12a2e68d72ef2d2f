"""Build step for the emulator's compiled hot path: mypyc compiles the pure-Python modules named
in NATIVE into C extensions, which run the same operations several times faster.

Each module `emulator/flight/NAME.py` is compiled as its own module, `emulator.flight._NAME_native`
(a shared library beside the source, not in git), with the SHA-256 of the source it was built
from. `emulator.flight.native` uses a compiled module only when that digest matches the source
now in the tree, so an edited source runs as plain Python until it is built again: the results
never depend on whether, or from what, the library was built. A machine without a C compiler, or
without mypy, keeps the pure-Python modules (the build says so and succeeds).

`python build_native.py` builds what is missing or stale (./dev runs it before every command);
`--force` builds again.
"""

from __future__ import annotations

import argparse
import hashlib
import importlib.machinery
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

__all__ = ["NATIVE", "build", "is_stale", "source_digest"]

ROOT = Path(__file__).resolve().parent
PACKAGE = ROOT / "emulator" / "flight"
NATIVE = ("solo", "cruise", "solo_battery")  # modules of emulator.flight compiled by mypyc
SUFFIX = importlib.machinery.EXTENSION_SUFFIXES[0]


def source_digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _library(name: str) -> Path:
    return PACKAGE / f"_{name}_native{SUFFIX}"


def _stamp(name: str) -> Path:
    return PACKAGE / f"_{name}_native.sha256"


def is_stale(name: str) -> bool:
    """Whether module NAME's library is missing or was built from another source."""
    stamp = _stamp(name)
    return (not _library(name).is_file() or not stamp.is_file()
            or stamp.read_text().strip() != source_digest(PACKAGE / f"{name}.py"))


def build(name: str) -> None:
    """Compile emulator/flight/NAME.py as emulator.flight._NAME_native; RuntimeError on failure."""
    source = PACKAGE / f"{name}.py"
    digest = source_digest(source)
    module = f"_{name}_native"
    with tempfile.TemporaryDirectory(prefix="mavswarm-native-") as tmp:
        work = Path(tmp)
        # the copy lives in a package of its own name, so the tree's other modules resolve
        # a copy of the package whose entries link to the tree's, plus the module to compile
        staged = work / "emulator" / "flight"
        staged.mkdir(parents=True)
        for entry in (ROOT / "emulator").iterdir():
            if entry.name not in ("flight", "__pycache__"):
                (work / "emulator" / entry.name).symlink_to(entry)
        for entry in PACKAGE.iterdir():
            if entry.suffix == ".py":
                (staged / entry.name).symlink_to(entry)
        text = source.read_text()
        (staged / f"{module}.py").write_text(
            f"{text}\n\nSOURCE_SHA256 = {digest!r}  # the source this module was compiled from\n")
        (work / "mypy.ini").write_text("[mypy]\npython_version = 3.11\n"
                                       "ignore_missing_imports = True\n")
        setup = work / "setup.py"
        setup.write_text(
            "from setuptools import setup\n"
            "from mypyc.build import mypycify\n"
            f"setup(name='{module}', ext_modules=mypycify(['emulator/flight/{module}.py'],"
            " opt_level='3'))\n")
        env = {**os.environ, "MYPYPATH": str(ROOT)}  # mavlink_vocabulary and the rest
        result = subprocess.run(
            [sys.executable, "setup.py", "--quiet", "build_ext", "--inplace"],
            cwd=work, env=env, capture_output=True, text=True, check=False)
        if result.returncode != 0:
            raise RuntimeError(f"mypyc could not compile {source.name}:\n"
                               f"{result.stdout[-2000:]}{result.stderr[-2000:]}")
        built = [*staged.glob(f"{module}*{SUFFIX}"), *work.glob(f"*{SUFFIX}")]
        if not built:
            raise RuntimeError(f"mypyc wrote no library for {source.name}")
        for library in built:
            shutil.copy2(library, PACKAGE / library.name)
    _stamp(name).write_text(digest + "\n")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--force", action="store_true", help="build even what is up to date")
    args = parser.parse_args()
    for name in NATIVE:
        if not args.force and not is_stale(name):
            continue
        try:
            build(name)
        except (RuntimeError, OSError, ImportError) as error:
            print(f"build_native: emulator/flight/{name}.py stays pure Python: {error}",
                  file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())

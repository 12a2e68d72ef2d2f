"""The package as pip users get it: `python -m build` on a copy of the checkout without the
console's bundle builds the sdist and, from it, a wheel that carries the page (build_console.py
bundles it); the wheel installed into a fresh virtual environment runs the smoke benchmark and
serves the console's page, importing nothing from the checkout.

Offline: the build runs without isolation (setuptools and build are dev dependencies), npm uses
the checkout's node_modules, and the fresh environment gets the dependencies from this one (a
.pth file) while the wheel is installed with --no-deps."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import sysconfig
import zipfile
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest

from tests.cli_fixtures import ROOT, read_until
from tests.ports import unused_tcp_port

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(shutil.which("npm") is None, reason="building the wheel needs npm"),
    pytest.mark.skipif(not (ROOT / "console" / "web" / "node_modules").is_dir(),
                       reason="console/web/node_modules is not installed (./dev installs it)"),
]

_NOT_COPIED = shutil.ignore_patterns(".git", ".venv*", "node_modules", "build", "dist", "runs",
                                     "site", "artifacts", "__pycache__", "*.egg-info", "*_cache",
                                     "app.js")
PACKAGE_DATA = ["console/static/app.js", "console/static/index.html", "console/static/style.css",
                "benchmark/sessions/area_search-easy-1.json",
                "benchmark/authoring/templates/files/area_sweep.json",
                "benchmark/authoring/template_files/template.schema.json",
                "mqtt_bus/mosquitto/mosquitto.conf", "mavswarm/py.typed"]


def _run(*args: str | Path, cwd: Path, env: dict[str, str] | None = None,
         timeout_s: float = 300) -> str:
    result = subprocess.run([str(arg) for arg in args], cwd=cwd, env=env, capture_output=True,
                            text=True, timeout=timeout_s, check=False)
    assert result.returncode == 0, f"{args} failed:\n{result.stdout}\n{result.stderr}"
    return result.stdout


@pytest.fixture(scope="module")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The wheel `python -m build` makes (through the sdist) from a copy of the checkout whose
    page was never built."""
    root = tmp_path_factory.mktemp("wheel")
    source = root / "source"
    shutil.copytree(ROOT, source, ignore=_NOT_COPIED)
    (source / "console" / "web" / "node_modules").symlink_to(
        ROOT / "console" / "web" / "node_modules")
    assert not (source / "console" / "static" / "app.js").exists()
    _run(sys.executable, "-m", "build", "--no-isolation", "--outdir", root / "dist", source,
         cwd=root)
    wheels = list((root / "dist").glob("mavswarm-*.whl"))
    assert len(wheels) == 1, wheels
    return wheels[0]


@pytest.fixture(scope="module")
def installed(wheel: Path) -> Iterator[tuple[Path, dict[str, str]]]:
    """A fresh virtual environment with the wheel installed (its bin folder) and the
    environment to run it in: no PYTHONPATH, so nothing comes from the checkout."""
    venv = wheel.parent.parent / "venv"
    _run(sys.executable, "-m", "venv", "--without-pip", venv, cwd=wheel.parent)
    bin_dir = venv / "bin"
    purelib = _run(bin_dir / "python", "-c", "import sysconfig; print(sysconfig.get_path("
                   "'purelib'))", cwd=venv).strip()
    # This environment's dependencies, after the venv's own packages (a .pth line appends a
    # folder without running that folder's own .pth files: the checkout's editable install
    # stays out).
    (Path(purelib) / "dependencies.pth").write_text(sysconfig.get_path("purelib") + "\n")
    _run(sys.executable, "-m", "pip", "--python", bin_dir / "python", "install", "--quiet",
         "--no-deps", "--no-index", wheel, cwd=venv)
    env = {key: value for key, value in os.environ.items() if key != "PYTHONPATH"}
    yield bin_dir, {**env, "PYTHONUNBUFFERED": "1", "VIRTUAL_ENV": str(venv)}


def test_the_wheel_carries_the_built_page_and_the_package_data(wheel: Path) -> None:
    names = set(zipfile.ZipFile(wheel).namelist())
    assert set(PACKAGE_DATA) <= names, sorted(set(PACKAGE_DATA) - names)
    assert not [name for name in names if name.startswith("console/web/")]
    page = zipfile.ZipFile(wheel).read("console/static/app.js")
    assert len(page) > 100_000  # the bundle, three.js included


def test_the_installed_wheel_imports_nothing_from_the_checkout(
        installed: tuple[Path, dict[str, str]], tmp_path: Path) -> None:
    bin_dir, env = installed
    where = _run(bin_dir / "python", "-c", "import benchmark, console, emulator, mavswarm; "
                 "print(console.__file__); print(benchmark.__file__)", cwd=tmp_path, env=env)
    for line in where.split():
        assert Path(line).is_relative_to(bin_dir.parent), where


def test_the_installed_wheel_runs_the_smoke_benchmark_and_serves_the_console(
        installed: tuple[Path, dict[str, str]], tmp_path: Path) -> None:
    bin_dir, env = installed
    out = tmp_path / "smoke"
    _run(bin_dir / "mavswarm", "bench", "run", "--agent", "oracle", "--suite", "smoke",
         "--out", out, cwd=tmp_path, env=env, timeout_s=600)
    assert (out / "results.jsonl").read_text().count("\n") == 18  # 3 sessions, 6 tasks each
    port = unused_tcp_port()
    proc = subprocess.Popen([bin_dir / "mavswarm", "replay", out, "--port", str(port)],
                            cwd=tmp_path, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)
    try:
        printed = read_until(proc, "http://", 60)
        assert "not built" not in printed
        base = f"http://127.0.0.1:{port}"
        page = httpx.get(f"{base}/", timeout=10)
        assert page.status_code == 200 and "app.js" in page.text
        script = httpx.get(f"{base}/static/app.js", timeout=10)
        assert script.status_code == 200 and len(script.content) > 100_000
    finally:
        proc.terminate()
        proc.wait(timeout=30)

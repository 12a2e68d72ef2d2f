"""`mavswarm bench compare`: several runs of the benchmark side by side, as paired
comparisons against a baseline with exact McNemar tests and session-clustered bootstrap
intervals (:mod:`benchmark.reporting.compare.stats`). :func:`write_compare` writes ``compare.md``,
``compare.json`` (shape: :class:`~benchmark.reporting.compare.model.CompareReport`) and
``compare.html``."""

from __future__ import annotations

from pathlib import Path

from benchmark.reporting.compare.build import build_compare, compare_paths
from benchmark.reporting.compare.markdown import render_compare_markdown
from benchmark.reporting.compare.model import CompareReport, compare_schema
from benchmark.reporting.compare.page import render_compare_html
from benchmark.reporting.compare.runs import CompareError, load_runs
from benchmark.reporting.inspector_links import DEFAULT_INSPECTOR_URL
from benchmark.reporting.report import write_text_atomic

__all__ = [
    "CompareError",
    "CompareReport",
    "build_compare",
    "compare_paths",
    "compare_schema",
    "load_runs",
    "write_compare",
]


def write_compare(report: CompareReport, out_dir: str | Path, *,
                  inspector_url: str = DEFAULT_INSPECTOR_URL,
                  serve_hint: str = "RESULTS_DIR ...") -> tuple[Path, Path, Path]:
    """Write ``compare.md``, ``compare.json`` and ``compare.html`` into `out_dir` (each
    through a temporary file); returns their paths. `serve_hint` is what the page tells the
    reader to pass to ``mavswarm replay``."""
    page = render_compare_html(report, inspector_url=inspector_url, serve_hint=serve_hint)
    directory = Path(out_dir)
    directory.mkdir(parents=True, exist_ok=True)
    paths = (directory / "compare.md", directory / "compare.json", directory / "compare.html")
    write_text_atomic(paths[0], render_compare_markdown(report))
    write_text_atomic(paths[1], report.model_dump_json(indent=2) + "\n")
    write_text_atomic(paths[2], page)
    return paths

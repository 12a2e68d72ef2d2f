"""Inline SVG charts of a comparison: diverging bars (fail->pass gains against pass->fail
losses), lines of rates over ordered categories (pass rate against difficulty per run) and
estimates with interval bars. Same conventions as :mod:`benchmark.reporting.charts`: one ``<svg>``
per
call, sized by its viewBox, every label escaped, a ``<title>`` tooltip on each mark."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from html import escape

from benchmark.reporting.charts import (
    AXIS_COLOR,
    FAIL_COLOR,
    GRID_COLOR,
    MUTED_COLOR,
    PASS_COLOR,
)
from benchmark.reporting.charts import shorten as _short
from benchmark.reporting.charts import svg_root as _svg
from benchmark.reporting.charts import svg_text as _text

__all__ = ["SERIES_COLORS", "Change", "Series", "Span", "category_lines", "diverging_bars",
           "interval_rows", "series_color"]

SERIES_COLORS = ("#3b6fd8", "#f4a259", "#7b61c9", "#2a9d8f", "#e76f51", "#8d99ae", "#b5838d",
                 "#6a994e")


def series_color(index: int) -> str:
    """The colour of the index-th series (runs in a comparison), cycling."""
    return SERIES_COLORS[index % len(SERIES_COLORS)]


@dataclass(frozen=True)
class Change:
    """One row of :func:`diverging_bars`: gains drawn right, losses left, both counts."""

    label: str
    gained: int
    lost: int
    caption: str = ""


def diverging_bars(rows: Sequence[Change], *, label: str, gained_name: str = "fail -> pass",
                   lost_name: str = "pass -> fail", width: float = 760.0,
                   label_width: float = 230.0) -> str:
    """Counts on both sides of a centre line: `gained` to the right in green, `lost` to the
    left in red, each with its number; the caption after the row."""
    row_h, top, caption_w = 26.0, 34.0, 150.0
    plot_w = width - label_width - caption_w
    centre = label_width + plot_w / 2
    peak = max((max(r.gained, r.lost) for r in rows), default=0) or 1
    half = plot_w / 2 - 26
    body = [_text(centre - 8, 14, f"\u2190 {lost_name}", anchor="end", size=11,
                  color=FAIL_COLOR, weight="600"),
            _text(centre + 8, 14, f"{gained_name} \u2192", size=11, color=PASS_COLOR,
                  weight="600"),
            f'<line x1="{centre:.1f}" y1="{top - 8:g}" x2="{centre:.1f}" '
            f'y2="{top + row_h * len(rows):g}" stroke="{AXIS_COLOR}"/>']
    for k, row in enumerate(rows):
        y = top + k * row_h
        up, down = half * row.gained / peak, half * row.lost / peak
        tip = escape(f"{row.label}: {row.gained} {gained_name}, {row.lost} {lost_name}"
                     f"{f' ({row.caption})' if row.caption else ''}")
        body.append(
            f'<g class="change"><title>{tip}</title>'
            + _text(label_width - 8, y + row_h / 2 + 4, _short(row.label, 34), anchor="end")
            + f'<rect class="gained" x="{centre:.1f}" y="{y + 4:.1f}" '
              f'width="{max(up, 1.0 if row.gained else 0.0):.1f}" height="{row_h - 8:g}" '
              f'rx="3" fill="{PASS_COLOR}"/>'
            + f'<rect class="lost" x="{centre - down:.1f}" y="{y + 4:.1f}" '
              f'width="{max(down, 1.0 if row.lost else 0.0):.1f}" height="{row_h - 8:g}" '
              f'rx="3" fill="{FAIL_COLOR}"/>'
            + _text(centre + up + 4, y + row_h / 2 + 4, f"+{row.gained}", size=11,
                    color=PASS_COLOR)
            + _text(centre - down - 4, y + row_h / 2 + 4, f"\u2212{row.lost}", anchor="end",
                    size=11, color=FAIL_COLOR)
            + _text(label_width + plot_w + 8, y + row_h / 2 + 4, row.caption, size=11,
                    color=MUTED_COLOR) + "</g>")
    return _svg(width, top + row_h * len(rows) + 6, body, label)


@dataclass(frozen=True)
class Series:
    """One line of :func:`category_lines`: a rate (or None) per category, with optional
    interval bounds drawn as whiskers."""

    name: str
    color: str
    rates: Sequence[float | None]
    lows: Sequence[float | None] = ()
    highs: Sequence[float | None] = ()


def category_lines(categories: Sequence[str], series: Sequence[Series], *, label: str,
                   x_label: str, y_label: str, width: float = 620.0) -> str:
    """Rates 0 .. 100 % against categories in the given order, one coloured line per series;
    a gap where a series has no value."""
    height, left, right, top, bottom = 300.0, 66.0, 20.0, 24.0 + 16.0 * len(series), 46.0
    height += 16.0 * len(series)
    plot_w, plot_h = width - left - right, height - top - bottom
    step = plot_w / max(len(categories), 1)

    def px(k: int) -> float:
        return left + step * (k + 0.5)

    def py(rate: float) -> float:
        return top + plot_h * (1.0 - min(1.0, max(0.0, rate)))

    body = []
    for tick in (0.0, 0.25, 0.5, 0.75, 1.0):
        body.append(f'<line x1="{left:g}" y1="{py(tick):.1f}" x2="{width - right:g}" '
                    f'y2="{py(tick):.1f}" stroke="{GRID_COLOR}"/>')
        body.append(_text(left - 6, py(tick) + 4, f"{tick * 100:.0f} %", anchor="end",
                          size=10, color=MUTED_COLOR))
    for k, name in enumerate(categories):
        body.append(_text(px(k), height - bottom + 16, name, anchor="middle", size=11,
                          color=MUTED_COLOR))
    body.append(_text(left + plot_w / 2, height - 8, x_label, anchor="middle",
                      color=MUTED_COLOR))
    body.append(_text(14, top + plot_h / 2, y_label, anchor="middle", color=MUTED_COLOR,
                      extra=f' transform="rotate(-90 14 {top + plot_h / 2:.1f})"'))
    for n, s in enumerate(series):
        body.append(f'<rect x="{left + 4:g}" y="{8 + 16 * n:g}" width="12" height="4" '
                    f'fill="{s.color}"/>')
        body.append(_text(left + 22, 14 + 16 * n, s.name, size=11))
    for n, s in enumerate(series):
        offset = (n - (len(series) - 1) / 2) * min(6.0, step / (2 * len(series) + 1))
        points = [(px(k) + offset, r) for k, r in enumerate(s.rates)]
        runs: list[list[tuple[float, float]]] = [[]]
        for x, r in points:
            if r is None:
                runs.append([])
            else:
                runs[-1].append((x, r))
        for part in runs:
            if len(part) > 1:
                path = " ".join(f"{x:.1f},{py(r):.1f}" for x, r in part)
                body.append(f'<polyline points="{path}" fill="none" stroke="{s.color}" '
                            f'stroke-width="2.5"/>')
        for k, (x, r) in enumerate(points):
            if r is None:
                continue
            low = s.lows[k] if k < len(s.lows) else None
            high = s.highs[k] if k < len(s.highs) else None
            whisker = ""
            span = ""
            if low is not None and high is not None:
                whisker = (f'<line x1="{x:.1f}" y1="{py(low):.1f}" x2="{x:.1f}" '
                           f'y2="{py(high):.1f}" stroke="{s.color}" stroke-width="1.5"/>')
                span = f" [{low * 100:.1f}, {high * 100:.1f}]"
            tip = escape(f"{s.name}, {categories[k]}: {r * 100:.1f} %{span}")
            body.append(f'<g class="point"><title>{tip}</title>{whisker}'
                        f'<circle cx="{x:.1f}" cy="{py(r):.1f}" r="4.5" fill="{s.color}"/></g>')
    return _svg(width, height, body, label)


@dataclass(frozen=True)
class Span:
    """One row of :func:`interval_rows`: an estimate with its interval."""

    label: str
    value: float
    low: float
    high: float
    color: str
    caption: str = ""


def interval_rows(rows: Sequence[Span], *, label: str, lo: float = 0.0, hi: float = 1.0,
                  signed: bool = False, width: float = 760.0, label_width: float = 230.0
                  ) -> str:
    """Estimates as dots with interval bars on a shared axis from `lo` to `hi` (rates, or
    differences in percentage points when `signed`); a line marks zero when it is in range."""
    row_h, top, caption_w = 26.0, 26.0, 170.0
    plot_w = width - label_width - caption_w

    def px(v: float) -> float:
        return label_width + plot_w * (min(hi, max(lo, v)) - lo) / (hi - lo)

    def tick_text(v: float) -> str:
        return f"{v * 100:+.0f} pp" if signed else f"{v * 100:.0f} %"

    body = []
    for k in range(5):
        v = lo + (hi - lo) * k / 4
        body.append(f'<line x1="{px(v):.1f}" y1="{top - 4:g}" x2="{px(v):.1f}" '
                    f'y2="{top + row_h * len(rows):g}" stroke="{GRID_COLOR}"/>')
        body.append(_text(px(v), top - 8, tick_text(v), anchor="middle", size=10,
                          color=MUTED_COLOR))
    if lo < 0.0 < hi:
        body.append(f'<line x1="{px(0.0):.1f}" y1="{top - 4:g}" x2="{px(0.0):.1f}" '
                    f'y2="{top + row_h * len(rows):g}" stroke="{AXIS_COLOR}" '
                    f'stroke-width="1.5"/>')
    for k, row in enumerate(rows):
        y = top + k * row_h + row_h / 2
        tip = escape(f"{row.label}: {tick_text(row.value)} [{tick_text(row.low)}, "
                     f"{tick_text(row.high)}]")
        body.append(f'<g class="span"><title>{tip}</title>'
                    + _text(label_width - 8, y + 4, _short(row.label, 34), anchor="end")
                    + f'<rect x="{px(row.low):.1f}" y="{y - 3:.1f}" '
                      f'width="{max(px(row.high) - px(row.low), 1.0):.1f}" height="6" rx="3" '
                      f'fill="{row.color}" fill-opacity="0.35"/>'
                    + f'<circle cx="{px(row.value):.1f}" cy="{y:.1f}" r="5" '
                      f'fill="{row.color}"/>'
                    + _text(label_width + plot_w + 8, y + 4, row.caption or tick_text(row.value),
                            size=11, color=MUTED_COLOR) + "</g>")
    return _svg(width, top + row_h * len(rows) + 6, body, label)

"""Small inline SVG charts for the HTML report: a heatmap, horizontal bars, a line chart, a
scatter plot and a sorted bar strip (and the drawing helpers the comparison's charts in
:mod:`benchmark.reporting.compare.charts` share). Each function returns one ``<svg>`` element as
text,
sized by its viewBox (it scales to the width of its container), with every label escaped and
a ``<title>`` tooltip on each mark. Nothing is loaded from anywhere.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from html import escape

__all__ = [
    "AXIS_COLOR",
    "FAIL_COLOR",
    "GRID_COLOR",
    "MUTED_COLOR",
    "PASS_COLOR",
    "Bar",
    "Point",
    "bar_strip",
    "hbars",
    "heatmap",
    "line_chart",
    "rate_color",
    "scatter",
    "shorten",
    "svg_root",
    "svg_text",
]

PASS_COLOR = "#2a9d5c"
FAIL_COLOR = "#d1495b"
AXIS_COLOR = "#8a94a6"
GRID_COLOR = "#e6e9ef"
TEXT_COLOR = "#1f2933"
MUTED_COLOR = "#66707f"
EMPTY_COLOR = "#eef0f4"
FONT = 'font-family="system-ui, -apple-system, Segoe UI, Roboto, sans-serif"'
# A red - amber - green scale for rates 0 .. 1.
_SCALE = ((0.0, (209, 73, 91)), (0.5, (244, 185, 66)), (1.0, (42, 157, 92)))


def rate_color(rate: float) -> str:
    """The scale's colour for a rate in 0 .. 1 (clamped)."""
    rate = min(1.0, max(0.0, rate))
    for (r0, c0), (r1, c1) in itertools.pairwise(_SCALE):
        if rate <= r1:
            t = (rate - r0) / (r1 - r0)
            rgb = (round(a + (b - a) * t) for a, b in zip(c0, c1, strict=True))
            return "#{:02x}{:02x}{:02x}".format(*rgb)
    return "#{:02x}{:02x}{:02x}".format(*_SCALE[-1][1])


def _svg(width: float, height: float, body: Sequence[str], label: str) -> str:
    return (f'<svg class="chart" viewBox="0 0 {width:g} {height:g}" role="img" '
            f'style="max-width: {width:g}px" '
            f'aria-label="{escape(label)}" {FONT} font-size="12" fill="{TEXT_COLOR}">'
            f'<title>{escape(label)}</title>{"".join(body)}</svg>')


def _text(x: float, y: float, text: str, *, anchor: str = "start", size: float = 12,
          color: str = TEXT_COLOR, weight: str = "normal", extra: str = "") -> str:
    return (f'<text x="{x:.1f}" y="{y:.1f}" text-anchor="{anchor}" font-size="{size:g}" '
            f'fill="{color}" font-weight="{weight}"{extra}>{escape(text)}</text>')


def _link(href: str | None, inner: str) -> str:
    return f'<a href="{escape(href)}" target="_blank">{inner}</a>' if href else inner


def _ink(rate: float) -> str:
    """Text colour readable on the scale's colour for `rate`."""
    return "#ffffff" if rate < 0.2 or rate > 0.8 else TEXT_COLOR


def heatmap(rows: Sequence[str], cols: Sequence[str],
            cells: Mapping[tuple[str, str], tuple[float, str]], *, label: str,
            summary_row: str = "", summary_col: str = "") -> str:
    """A grid of rates: ``cells[(row, col)] = (rate, caption)``; missing cells are grey.
    A row or column named like `summary_row` / `summary_col` is set apart by a gap."""
    top, cell_w, cell_h, gap = 28.0, 120.0, 54.0, 8.0
    left = 24.0 + 7.6 * max((len(r) for r in rows), default=4)
    col_x = {}
    x = left
    for col in cols:
        x += gap if col == summary_col else 0.0
        col_x[col] = x
        x += cell_w
    row_y = {}
    y = top
    for row in rows:
        y += gap if row == summary_row else 0.0
        row_y[row] = y
        y += cell_h
    body = [_text(col_x[c] + cell_w / 2, top - 10, c, anchor="middle", weight="600")
            for c in cols]
    for row in rows:
        body.append(_text(left - 10, row_y[row] + cell_h / 2 + 4, row, anchor="end",
                          weight="600"))
        for col in cols:
            cx, cy = col_x[col], row_y[row]
            cell = cells.get((row, col))
            if cell is None:
                body.append(f'<rect x="{cx + 2:.1f}" y="{cy + 2:.1f}" width="{cell_w - 4:g}" '
                            f'height="{cell_h - 4:g}" rx="6" fill="{EMPTY_COLOR}"/>')
                body.append(_text(cx + cell_w / 2, cy + cell_h / 2 + 4, "no tasks",
                                  anchor="middle", color=MUTED_COLOR, size=11))
                continue
            rate, caption = cell
            ink = _ink(rate)
            body.append(f'<g><title>{escape(f"{row} / {col}: {rate * 100:.1f} % ({caption})")}'
                        f'</title><rect x="{cx + 2:.1f}" y="{cy + 2:.1f}" '
                        f'width="{cell_w - 4:g}" height="{cell_h - 4:g}" rx="6" '
                        f'fill="{rate_color(rate)}"/>'
                        + _text(cx + cell_w / 2, cy + cell_h / 2 - 1, f"{rate * 100:.0f} %",
                                anchor="middle", size=16, color=ink, weight="700")
                        + _text(cx + cell_w / 2, cy + cell_h / 2 + 15, caption,
                                anchor="middle", size=10.5, color=ink) + "</g>")
    return _svg(x + 10, y + 8, body, label)


@dataclass(frozen=True)
class Bar:
    """One bar of :func:`hbars`: a label, a rate in 0 .. 1 and a caption (e.g. 3 / 4)."""

    label: str
    rate: float
    caption: str = ""
    href: str | None = None


def hbars(bars: Sequence[Bar], *, label: str, label_width: float = 230.0,
          width: float = 760.0) -> str:
    """Horizontal bars of rates (0 .. 100 %), one row each, coloured by the rate."""
    row_h, top = 24.0, 22.0
    caption_w = 16.0 + 6.4 * max((len(b.caption) + 9 for b in bars), default=10)
    plot_w = width - label_width - caption_w
    body = []
    for tick in (0.0, 0.25, 0.5, 0.75, 1.0):
        x = label_width + plot_w * tick
        body.append(f'<line x1="{x:.1f}" y1="{top - 4:g}" x2="{x:.1f}" '
                    f'y2="{top + row_h * len(bars):g}" stroke="{GRID_COLOR}"/>')
        body.append(_text(x, top - 8, f"{tick * 100:.0f} %", anchor="middle", size=10,
                          color=MUTED_COLOR))
    for k, bar in enumerate(bars):
        y = top + k * row_h
        w = max(plot_w * min(1.0, max(0.0, bar.rate)), 1.5)
        tip = escape(f"{bar.label}: {bar.rate * 100:.1f} % ({bar.caption})")
        body.append(_link(bar.href, (
            f'<g><title>{tip}</title>'
            + _text(label_width - 8, y + row_h / 2 + 4, _short(bar.label, 34), anchor="end")
            + f'<rect x="{label_width:g}" y="{y + 4:.1f}" width="{plot_w:.1f}" '
              f'height="{row_h - 8:g}" rx="3" fill="{EMPTY_COLOR}"/>'
            + f'<rect x="{label_width:g}" y="{y + 4:.1f}" width="{w:.1f}" '
              f'height="{row_h - 8:g}" rx="3" fill="{rate_color(bar.rate)}"/>'
            + _text(label_width + plot_w + 8, y + row_h / 2 + 4,
                    f"{bar.rate * 100:.1f} %  {bar.caption}", size=11, color=MUTED_COLOR)
            + "</g>")))
    return _svg(width, top + row_h * len(bars) + 6, body, label)


def _short(text: str, limit: int) -> str:
    return text if len(text) <= limit else text[: limit - 1] + "\u2026"


def line_chart(points: Sequence[tuple[int, float]], *, label: str, x_label: str,
               y_label: str) -> str:
    """A line through (k, rate) points, rates 0 .. 100 % on the y axis, integer k on x."""
    width, height, left, right, top, bottom = 560.0, 280.0, 66.0, 20.0, 22.0, 44.0
    plot_w, plot_h = width - left - right, height - top - bottom
    ks = [k for k, _ in points] or [1]
    k_min, k_max = min(ks), max(ks)
    span_lo, span_hi = (k_min - 0.5, k_max + 0.5) if k_min == k_max else (k_min, k_max)

    def px(k: float) -> float:
        return left + plot_w * (k - span_lo) / (span_hi - span_lo)

    def py(rate: float) -> float:
        return top + plot_h * (1.0 - min(1.0, max(0.0, rate)))

    body = []
    for tick in (0.0, 0.25, 0.5, 0.75, 1.0):
        body.append(f'<line x1="{left:g}" y1="{py(tick):.1f}" x2="{width - right:g}" '
                    f'y2="{py(tick):.1f}" stroke="{GRID_COLOR}"/>')
        body.append(_text(left - 6, py(tick) + 4, f"{tick * 100:.0f} %", anchor="end",
                          size=10, color=MUTED_COLOR))
    for k in range(k_min, k_max + 1):
        body.append(_text(px(k), height - bottom + 16, str(k), anchor="middle", size=10,
                          color=MUTED_COLOR))
    body.append(_text(left + plot_w / 2, height - 6, x_label, anchor="middle",
                      color=MUTED_COLOR))
    body.append(_text(14, top + plot_h / 2, y_label, anchor="middle", color=MUTED_COLOR,
                      extra=f' transform="rotate(-90 14 {top + plot_h / 2:.1f})"'))
    if len(points) > 1:
        path = " ".join(f"{px(k):.1f},{py(r):.1f}" for k, r in points)
        body.append(f'<polyline points="{path}" fill="none" stroke="#3b6fd8" '
                    f'stroke-width="2.5"/>')
    for k, rate in points:
        body.append(f'<g><title>{escape(f"pass^{k} = {rate * 100:.1f} %")}</title>'
                    f'<circle cx="{px(k):.1f}" cy="{py(rate):.1f}" r="5" fill="#3b6fd8"/>'
                    + _text(px(k), py(rate) - 10, f"{rate * 100:.1f} %", anchor="middle",
                            size=11, weight="600") + "</g>")
    return _svg(width, height, body, label)


@dataclass(frozen=True)
class Point:
    """One mark of :func:`scatter`: position, colour, tooltip and an optional link."""

    x: float
    y: float
    color: str
    title: str
    href: str | None = None


def _log_ticks(low: float, high: float) -> list[float]:
    first, last = math.floor(math.log10(low)), math.ceil(math.log10(high))
    return [10.0 ** e for e in range(first, last + 1)]


def _tick_text(value: float, unit: str) -> str:
    if unit == "s" and value < 1.0:
        return f"{value * 1000:g} ms"
    return f"{value:g} {unit}"


def scatter(points: Sequence[Point], *, label: str, x_label: str, y_label: str,
            unit: str = "s", legend: Sequence[tuple[str, str]] = ()) -> str:
    """Points on log-log axes (values at or below zero are drawn at the lowest tick)."""
    width, height, left, right, top, bottom = 760.0, 380.0, 70.0, 24.0, 30.0, 48.0
    plot_w, plot_h = width - left - right, height - top - bottom
    xs = [p.x for p in points if p.x > 0] or [1.0]
    ys = [p.y for p in points if p.y > 0] or [1.0]
    x_ticks = _log_ticks(min(xs), max(xs) * 1.0001)
    y_ticks = _log_ticks(min(ys), max(ys) * 1.0001)
    if len(x_ticks) < 2:
        x_ticks.append(x_ticks[-1] * 10)
    if len(y_ticks) < 2:
        y_ticks.append(y_ticks[-1] * 10)
    lx0, lx1 = math.log10(x_ticks[0]), math.log10(x_ticks[-1])
    ly0, ly1 = math.log10(y_ticks[0]), math.log10(y_ticks[-1])

    def px(v: float) -> float:
        return left + plot_w * (math.log10(max(v, x_ticks[0])) - lx0) / (lx1 - lx0)

    def py(v: float) -> float:
        return top + plot_h * (1.0 - (math.log10(max(v, y_ticks[0])) - ly0) / (ly1 - ly0))

    body = [f'<rect x="{left:g}" y="{top:g}" width="{plot_w:g}" height="{plot_h:g}" '
            f'fill="none" stroke="{AXIS_COLOR}"/>']
    for t in x_ticks:
        body.append(f'<line x1="{px(t):.1f}" y1="{top:g}" x2="{px(t):.1f}" '
                    f'y2="{top + plot_h:g}" stroke="{GRID_COLOR}"/>')
        body.append(_text(px(t), top + plot_h + 16, _tick_text(t, unit), anchor="middle",
                          size=10, color=MUTED_COLOR))
    for t in y_ticks:
        body.append(f'<line x1="{left:g}" y1="{py(t):.1f}" x2="{left + plot_w:g}" '
                    f'y2="{py(t):.1f}" stroke="{GRID_COLOR}"/>')
        body.append(_text(left - 6, py(t) + 4, _tick_text(t, unit), anchor="end", size=10,
                          color=MUTED_COLOR))
    body.append(_text(left + plot_w / 2, height - 8, x_label, anchor="middle",
                      color=MUTED_COLOR))
    body.append(_text(16, top + plot_h / 2, y_label, anchor="middle", color=MUTED_COLOR,
                      extra=f' transform="rotate(-90 16 {top + plot_h / 2:.1f})"'))
    for k, (name, color) in enumerate(legend):
        x = left + 8 + k * 90
        body.append(f'<circle cx="{x:g}" cy="{top - 14:g}" r="5" fill="{color}"/>')
        body.append(_text(x + 10, top - 10, name, size=11))
    for p in points:
        body.append(_link(p.href, f'<circle class="mark" cx="{px(p.x):.1f}" '
                                  f'cy="{py(p.y):.1f}" r="5" fill="{p.color}" '
                                  f'fill-opacity="0.75" stroke="#ffffff" stroke-width="1">'
                                  f'<title>{escape(p.title)}</title></circle>'))
    return _svg(width, height, body, label)


def bar_strip(values: Sequence[tuple[Sequence[float], str, str | None]], *, label: str,
              colors: Sequence[str], series: Sequence[str], y_unit: str = "",
              decimals: int = 0) -> str:
    """Vertical bars, one per item, largest first: ``(stacked parts, tooltip, href)``.
    Suits anything from a handful of items to a few thousand (bars thin to hairlines)."""
    width, height, left, right, top, bottom = 560.0, 260.0, 70.0, 12.0, 30.0, 30.0
    plot_w, plot_h = width - left - right, height - top - bottom
    ordered = sorted(values, key=lambda v: -sum(v[0]))
    peak = max((sum(parts) for parts, _, _ in ordered), default=0.0) or 1.0
    step = plot_w / max(len(ordered), 1)
    body = []
    for tick in (0.0, 0.5, 1.0):
        y = top + plot_h * (1.0 - tick)
        body.append(f'<line x1="{left:g}" y1="{y:.1f}" x2="{width - right:g}" y2="{y:.1f}" '
                    f'stroke="{GRID_COLOR}"/>')
        body.append(_text(left - 6, y + 4, f"{peak * tick:,.{decimals}f}{y_unit}",
                          anchor="end", size=10, color=MUTED_COLOR))
    for k, (name, color) in enumerate(zip(series, colors, strict=True)):
        x = left + 6 + k * 110
        body.append(f'<rect x="{x:g}" y="{top - 20:g}" width="10" height="10" '
                    f'fill="{color}"/>')
        body.append(_text(x + 14, top - 11, name, size=11))
    for k, (parts, tip, href) in enumerate(ordered):
        x, y = left + k * step, top + plot_h
        marks = []
        for part, color in zip(parts, colors, strict=False):
            h = plot_h * part / peak
            y -= h
            marks.append(f'<rect x="{x:.2f}" y="{y:.2f}" width="{max(step * 0.85, 0.6):.2f}" '
                         f'height="{h:.2f}" fill="{color}"/>')
        body.append(_link(href, f'<g><title>{escape(tip)}</title>{"".join(marks)}</g>'))
    body.append(_text(left + plot_w / 2, height - 8, f"{len(ordered)} tasks, largest first",
                      anchor="middle", size=11, color=MUTED_COLOR))
    return _svg(width, height, body, label)



# The drawing helpers, for charts defined elsewhere.
svg_root = _svg
svg_text = _text
shorten = _short

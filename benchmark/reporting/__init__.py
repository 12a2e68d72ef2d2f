"""Reporting: Markdown, JSON and HTML reports of result records, charts, comparisons of runs,
replay data and links into the run inspector."""

__all__: list[str] = []

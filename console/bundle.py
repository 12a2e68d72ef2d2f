"""Whether the console's page is built: its script (console/static/app.js) is bundled by npm
from console/web, so a checkout installed with pip but without npm has none. Commands that
serve the console say so, with how to build it, next to the URL they print; the page says the
same in the browser (console/static/index.html)."""

from __future__ import annotations

from importlib import resources

__all__ = ["BUILD_HINT", "bundle_problem"]

BUILD_HINT = ("build it with ./dev in the source checkout, or "
              "`cd console/web && npm ci && npm run build`, then reload the page")


def bundle_problem() -> str | None:
    """What is wrong with the page's bundle (None: it is there)."""
    if (resources.files("console") / "static" / "app.js").is_file():
        return None
    return f"the web console's page is not built (console/static/app.js is missing): {BUILD_HINT}"

"""Task templates: the catalogue the generator draws from (see `base` for the framework)."""

from benchmark.authoring.templates import (
    assignment,
    basic,
    battery,
    communication,
    coordination,
    delivery,
    navigation,
    resilience,
    search,
    tracking,
)
from benchmark.authoring.templates.base import (
    CATEGORIES,
    SessionView,
    TaskDraft,
    Template,
    TemplateUnfit,
)

__all__ = ["CATALOGUE", "CATEGORIES", "SessionView", "TaskDraft", "Template", "TemplateUnfit",
           "template"]

CATALOGUE: tuple[Template, ...] = (
    *basic.TEMPLATES, *navigation.TEMPLATES, *search.TEMPLATES, *coordination.TEMPLATES,
    *assignment.TEMPLATES, *delivery.TEMPLATES, *communication.TEMPLATES, *battery.TEMPLATES,
    *tracking.TEMPLATES, *resilience.TEMPLATES,
)

_BY_KEY = {t.key: t for t in CATALOGUE}
if len(_BY_KEY) != len(CATALOGUE):
    raise RuntimeError("two task templates share a key")


def template(key: str) -> Template:
    try:
        return _BY_KEY[key]
    except KeyError:
        raise KeyError(f"unknown task template {key!r}") from None

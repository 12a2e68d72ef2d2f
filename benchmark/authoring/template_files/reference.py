"""Template files in MultiUAV-Plat's layout, read as they are.

A MultiUAV-Plat user's templates come either as one template object per file or as a
catalogue: one JSON object mapping each template key to its template (the layout of the
reference's ``templates/task_templates.json``). A template object holds ``name``, ``content``,
``content_aliases``, ``category`` ("Basic Operations", "Multi-Drone Coordination" ...),
``difficulty``, ``suitable_task``, ``exclude_in_random_generation``, ``related_apis``,
``commands`` and the hidden check tree ``execution_check_apis`` (endpoints written
``/check/<name>``). Each becomes a `TemplateFile`:

- entity groups from the placeholders ending in ``_id`` or ``_name`` whose first word is
  ``drone``, ``target`` or ``obstacle`` (``{drone_id}``, ``{drone_1_name}``, ``{target_3_id}``
  ...), drawn as the reference draws them: distinct when the session has enough entities of the
  kind, otherwise each group picks any (``distinct: when_enough``); targets from every target;
- phrasings: ``content`` then ``content_aliases``; ``{name}`` and ``{creator}`` give the
  template's name and creator;
- ``suitable_task``: the families it names (``all``, an empty list or only unknown names: every
  family);
- the check tree with ``/check/`` stripped; parameters no endpoint declares (the reference
  ignores them) are dropped;
- the budget from the tree: steps from ``commands``, flight from the positions, targets and
  areas the checks name.

The reference solution (``related_apis``) is not used: the oracle plans from the checks. A
template marked ``exclude_in_random_generation`` is not drawn (the reference's generator skips
it too). Errors name the file, the template key and the field.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from benchmark.authoring.template_files.model import CATEGORIES, FAMILIES

__all__ = ["ReferenceTemplateError", "is_reference_layout", "reference_templates"]

_ENTITY = re.compile(r"\{((drone|target|obstacle)(?:_[0-9]+)?)_(?:id|name)\}")
_KINDS = {"drone": "drone", "target": "target", "obstacle": "obstacle"}
_CATEGORY_ALIASES = {"tracking": "target_tracking", "multi_drone": "multi_drone_coordination",
                     "battery": "battery_management", "basic": "basic_operations"}
_POSITION_ENDPOINTS = {"drone_has_visited_position", "drone_position", "target_is_reached",
                       "target_is_reached_by_drone", "target_in_photo_taken_by_drone",
                       "drone_in_target", "drone_has_moved_distance",
                       "drone_has_moved_directed_distance", "moving_target_tracked"}
_AREA_ENDPOINTS = {"target_is_fully_searched", "target_searched_area_percentage"}
_SESSION_ENDPOINTS = {"task_progress", "task_done"}
_HOVER_ALLOWANCE_S = 40.0


class ReferenceTemplateError(ValueError):
    """A template in the reference's layout that cannot be read (file, key, field, reason)."""


def is_reference_layout(raw: Any) -> bool:
    """Whether parsed JSON is a reference template or a catalogue of them."""
    if not isinstance(raw, Mapping) or "format" in raw:
        return False
    if "content" in raw or "execution_check_apis" in raw:
        return True
    return bool(raw) and all(isinstance(v, Mapping) and ("content" in v
                                                         or "execution_check_apis" in v)
                             for v in raw.values())


def reference_templates(raw: Mapping[str, Any], path: Path
                        ) -> list[tuple[str, dict[str, Any]]]:
    """(where, template-file object in ``mavswarm.template/1``) of each template of a reference
    file, in file order; excluded templates left out. `where` names the file and the key."""
    single = "content" in raw or "execution_check_apis" in raw
    items = [(path.stem, raw)] if single else list(raw.items())
    out = []
    for key, template in items:
        where = f"{path}: {key}" if not single else str(path)
        if not isinstance(template, Mapping):
            raise ReferenceTemplateError(f"{where}: expected a template object")
        if template.get("exclude_in_random_generation") is True:
            continue
        out.append((where, _convert(str(key), template, where)))
    return out


def _ident(key: str, where: str) -> str:
    ident = re.sub(r"[^a-z0-9]+", "_", key.lower()).strip("_")
    if not ident or not ident[0].isalpha():
        ident = f"t_{ident}"
    if ident == "t_":
        raise ReferenceTemplateError(f"{where}: the key gives no usable template id")
    return ident


def _category(value: Any, where: str) -> str:
    word = re.sub(r"[^a-z0-9]+", "_", str(value or "").lower()).strip("_")
    word = _CATEGORY_ALIASES.get(word, word)
    if word not in CATEGORIES:
        raise ReferenceTemplateError(
            f"{where}: category: {value!r} is not one of Basic Operations, Navigation, Search, "
            f"Multi-Drone Coordination, Delivery, Communication, Battery Management, Tracking "
            f"(or {', '.join(CATEGORIES)})")
    return word


def _families(value: Any) -> list[str]:
    names = [value] if isinstance(value, str) else list(value or [])
    if "all" in names:
        return []
    return [n for n in FAMILIES if n in names]


def _strings(template: Mapping[str, Any], where: str) -> list[str]:
    content = template.get("content")
    if not isinstance(content, str) or not content.strip():
        raise ReferenceTemplateError(f"{where}: content: missing or empty (the task's text)")
    aliases = template.get("content_aliases") or []
    if not isinstance(aliases, list) or not all(isinstance(a, str) for a in aliases):
        raise ReferenceTemplateError(f"{where}: content_aliases: expected a list of texts")
    return [content, *(a for a in aliases if a.strip())]


def _groups(texts: list[str]) -> list[dict[str, str]]:
    seen: dict[str, str] = {}
    for text in texts:
        for m in _ENTITY.finditer(text):
            seen.setdefault(m.group(1), _KINDS[m.group(2)])
    order = {"drone": 0, "target": 1, "obstacle": 2}
    return [{"group": g, "kind": k}
            for g, k in sorted(seen.items(), key=lambda item: (order[item[1]], item[0]))]


def _leaves(node: Any) -> list[Mapping[str, Any]]:
    if isinstance(node, Mapping):
        if "endpoint" in node:
            return [node]
        return [leaf for child in node.get("checks") or [] for leaf in _leaves(child)]
    if isinstance(node, list):
        return [leaf for child in node for leaf in _leaves(child)]
    return []


def _budget(leaves: list[Mapping[str, Any]], commands: Any) -> dict[str, Any]:
    names = [str(leaf.get("endpoint", "")) for leaf in leaves]
    diagonals = 1.0 + 0.5 * sum(n in _POSITION_ENDPOINTS for n in names)
    diagonals += 2.0 * sum(n in _AREA_ENDPOINTS for n in names)
    diagonals += 8.0 * sum(n in _SESSION_ENDPOINTS for n in names)
    hover_s = _HOVER_ALLOWANCE_S * sum(n == "drone_has_hovered" for n in names)
    steps = max(len(commands) if isinstance(commands, list) else 0, 2 * len(leaves), 2)
    budget: dict[str, Any] = {"steps": steps, "flight_diagonals": diagonals}
    if hover_s:
        budget["hover_s"] = hover_s
    return budget


def _convert(key: str, template: Mapping[str, Any], where: str) -> dict[str, Any]:
    from benchmark.authoring.importer import reference_tree

    phrasings = _strings(template, where)
    notes: list[str] = []
    checks = reference_tree(template.get("execution_check_apis"), "execution_check_apis", notes)
    leaves = _leaves(checks)
    if not leaves:
        raise ReferenceTemplateError(f"{where}: execution_check_apis: the template has no "
                                     f"checks (a task without checks cannot be scored)")
    texts = phrasings + [str(leaf.get("parameters")) for leaf in leaves]
    difficulty = template.get("difficulty")
    values = [{"name": "name", "kind": "choice",
               "options": [str(template.get("name") or key)]},
              {"name": "creator", "kind": "choice",
               "options": [str(template.get("creator") or "unknown")]}]
    return {
        "format": "mavswarm.template/1", "id": _ident(key, where),
        "category": _category(template.get("category"), where),
        "difficulty": difficulty if difficulty in ("easy", "medium", "hard") else "medium",
        "description": str(template.get("description") or template.get("name") or ""),
        "families": _families(template.get("suitable_task")),
        "entities": _groups(texts), "distinct": "when_enough", "values": values,
        "phrasings": phrasings, "checks": checks,
        "budget": _budget(leaves, template.get("commands")),
    }

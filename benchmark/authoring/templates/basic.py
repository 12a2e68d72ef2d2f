"""Basic operations: take-off, altitude, heading, a round trip home, a new home.

These templates are files of the template file format (`benchmark/authoring/templates/files/`,
`benchmark.authoring.template_files`): they draw exactly what the code they replaced drew, so the
shipped suite is unchanged."""

from __future__ import annotations

from benchmark.authoring.template_files.loader import load_template
from benchmark.authoring.templates.common import FILES

__all__ = ["FILES", "TEMPLATES"]

KEYS = ("takeoff_hold", "climb_and_face", "altitude_change", "round_trip_home", "new_home")

TEMPLATES = tuple(load_template(FILES / f"{key}.json") for key in KEYS)

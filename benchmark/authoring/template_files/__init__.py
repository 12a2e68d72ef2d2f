"""Task templates as files (``mavswarm.template/1``): the pydantic model and its JSON Schema,
the placeholder grammar (ours and the reference's), reading and writing files.

``python -m benchmark.authoring.template_files`` rewrites `template.schema.json` from the model."""

from pathlib import Path

from benchmark.authoring.template_files.loader import (
    TemplateFileError,
    dump_template,
    load_template,
    load_templates,
    read_template,
    read_templates,
    template_of,
)
from benchmark.authoring.template_files.model import FORMAT, TemplateFile, json_schema

__all__ = ["FORMAT", "SCHEMA_PATH", "TemplateFile", "TemplateFileError", "dump_template",
           "json_schema", "load_template", "load_templates", "read_template", "read_templates",
           "schema_text",
           "template_of"]

SCHEMA_PATH = Path(__file__).resolve().parent / "template.schema.json"


def schema_text() -> str:
    """The JSON Schema file's text, as generated from the model."""
    import json
    return json.dumps(json_schema(), indent=2, sort_keys=True) + "\n"

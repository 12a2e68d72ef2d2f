"""Rewrite template.schema.json from the pydantic model."""

from benchmark.authoring.template_files import SCHEMA_PATH, schema_text

SCHEMA_PATH.write_text(schema_text(), encoding="utf-8")
print(f"wrote {SCHEMA_PATH}")

"""Seeded generation of the benchmark's session worlds: 3 families x 5 levels x 5 indices."""

from benchmark.authoring.scenarios.families import FAMILIES, FamilySpec, family_spec, target_count
from benchmark.authoring.scenarios.generator import (
    SCHEMA,
    SESSION_INDICES,
    all_session_keys,
    generate_world,
    session_id,
    session_seed,
)
from benchmark.authoring.scenarios.levels import LEVELS, LevelSpec, level_spec
from benchmark.authoring.scenarios.placement import PlacementError

__all__ = [
    "FAMILIES",
    "LEVELS",
    "SCHEMA",
    "SESSION_INDICES",
    "FamilySpec",
    "LevelSpec",
    "PlacementError",
    "all_session_keys",
    "family_spec",
    "generate_world",
    "level_spec",
    "session_id",
    "session_seed",
    "target_count",
]

"""The JSON Schema shipped for correspondence files (ursim_core.correspondences.schema)."""

from __future__ import annotations

import jsonschema

from ursim_core.correspondences import correspondences_schema


def test_shipped_schema_is_valid_draft_2020_12():
    schema = correspondences_schema(1)
    jsonschema.Draft202012Validator.check_schema(schema)
    assert schema["properties"]["version"] == {"const": 1}

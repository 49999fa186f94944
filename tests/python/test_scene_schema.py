"""The JSON Schema documents what the parser accepts: every example scene is
valid against it, and the structural errors of the malformed set are not."""
import json
import pathlib

import jsonschema
import pytest

from conftest import EXAMPLES, ROOT
from test_scene_errors import CASES

SCHEMA = json.loads((ROOT / "solver" / "scene" / "scene.schema.json").read_text())


@pytest.mark.parametrize("scene", sorted(EXAMPLES.glob("*/*.json")), ids=lambda p: p.name)
def test_examples_are_valid(scene):
    errors = list(jsonschema.Draft202012Validator(SCHEMA).iter_errors(json.loads(scene.read_text())))
    assert errors == []


# Errors the schema can express (others need the parser: names, tree, physics).
STRUCTURAL = ["not an object", "unknown top-level key", "unknown body key", "missing field", "wrong type",
              "unknown joint type", "wrong vector length", "wrong format", "parameter beyond 1e20", "body at 1e308",
              "axis whose length overflows", "element count beyond 32 bits", "iterations beyond 32 bits",
              "fractional integer", "control character in the description", "NUL in a parameter description",
              "non-character in a unit", "scene name too long"]


@pytest.mark.parametrize("case", STRUCTURAL)
def test_schema_rejects_structural_errors(case):
    text = dict((c[0], c[1]) for c in CASES)[case]
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate(json.loads(text), SCHEMA)

"""Reading the result.json files tests produce, each validated against `remap schema report`."""

from __future__ import annotations

import contextlib
import functools
import io
import json
from pathlib import Path


@functools.cache
def validator():
    import jsonschema

    from brdfremap.core.cli import main

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        assert main(["schema", "report"]) == 0
    schema = json.loads(buf.getvalue())
    jsonschema.Draft202012Validator.check_schema(schema)
    return jsonschema.Draft202012Validator(schema)


def read_result(path: str | Path) -> dict:
    """The document, after checking it against the published schema (every error listed)."""
    doc = json.loads(Path(path).read_text())
    errors = [f"{'/'.join(map(str, e.absolute_path))}: {e.message}" for e in validator().iter_errors(doc)]
    assert not errors, f"{path} does not validate against `remap schema report`: {errors[:5]}"
    return doc

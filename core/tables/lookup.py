"""A material through a remap table: checked against what the table was built for, then the target's
parameters read from its map, with no render."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

from pydantic import Field

from ..data.errors import ConfigError
from ..data.model import Strict
from ..data.schemas import Material, ModelSpec
from ..job.job import Lookup
from .table import Table, TableMap, outside


LOOKUP_SCHEMA_VERSION = 1


class TableRef(Strict):
    name: str
    file: str = Field(description="Where the table was read.")
    digest: str
    method: str = Field(description="The map that gave the parameters.")


class TargetRef(Strict):
    adapter: str
    model: str


class LookupRecord(Strict):
    """`lookup.json`: a lookup written with `--no-render`, its parameters straight from the table."""

    schema_version: int = LOOKUP_SCHEMA_VERSION
    tool: str
    table: TableRef
    source: Material
    target: TargetRef
    params: dict[str, Any] = Field(description="The target's parameters (RGB as lists).")
    axis_values: dict[str, Any] = Field(description="The source's values on the table's axes.")
    expected_error: float | None = Field(description="What the table's direct fits reach about these values.")
    outside: list[str] = Field(description="Source values outside the table's range (clamped), in words.")
    lookup_seconds: float
    files: list[str] = Field(description="The native material's files written beside it.")
    textures: dict[str, Any] | None = Field(description="A textured source's record (its maps), if one.")


@dataclass
class Answer:
    lookup: Lookup
    """The parameters, as a job carries them."""
    values: dict[str, Any]
    """The source's axis values."""
    seconds: float
    """The map's evaluation alone."""


def axis_values(table: Table, material: Material, source_spec: ModelSpec, file: str | None,
                prefix: str = "params") -> dict[str, Any]:
    """The material's values on the table's axes, once it is shown to be what the table was built
    for: the same model, and the same values of every parameter that is not an axis (but one that
    does nothing in either)."""
    src = table.spec.source
    if (material.adapter, material.model) != (src.adapter, src.model):
        raise ConfigError(f"is {material.adapter}:{material.model}, and the table {table.name!r} maps "
                          f"{src.adapter}:{src.model}: use a table built for this model", file=file, field="model")
    params = source_spec.complete(material.params, file=file, prefix=prefix)
    for name, value in source_spec.active(params).items():
        if name in table.spec.axes or name not in table.source_params:
            continue
        if source_spec.is_inert(name, params) and source_spec.is_inert(name, table.source_params):
            continue  # it does nothing in either (a coat's roughness without a coat): not a difference
        if not _same(value, table.source_params[name]):
            raise ConfigError(f"is {_text(value)}, and the table {table.name!r} was built for {_text(table.source_params[name])} "
                              f"(its axes: {', '.join(table.spec.axes)}): build a table for this value (its spec's "
                              f"source.params) or with {name} as an axis", file=file, field=f"{prefix}.{name}")
    return {name: list(params[name]) if isinstance(params[name], tuple) else params[name] for name in table.spec.axes}


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, str) or isinstance(b, str):
        return a == b
    xs = list(a) if isinstance(a, (list, tuple)) else [a]
    ys = list(b) if isinstance(b, (list, tuple)) else [b]
    return len(xs) == len(ys) and all(math.isclose(float(x), float(y), rel_tol=1e-6, abs_tol=1e-9)
                                      for x, y in zip(xs, ys))


def _text(v: Any) -> str:
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(f"{float(x):g}" for x in v) + "]"
    return f"{v:g}" if isinstance(v, float) else str(v)


def look_up(table: Table, tmap: TableMap, values: dict[str, Any]) -> Answer:
    """The target's parameters for these axis values; values outside the grid are clamped and said."""
    t0 = time.perf_counter()
    params, expected = tmap.params(values)
    seconds = time.perf_counter() - t0
    lookup = Lookup(table=table.name, digest=table.digest, method=tmap.method, params=params,
                    expected_error=expected, outside=outside(table, values))
    return Answer(lookup, values, seconds)


def write_answer(folder, resolved, answer: Answer, adapter, table_file: str) -> list:
    """A lookup without renders: the native material and `lookup.json`, each written aside and
    moved in (`lookup.json` last)."""
    import tempfile
    from pathlib import Path

    from .. import __version__
    from ..data.atomic import why, write_bytes_atomic, write_json_atomic

    job, spec = resolved.job, resolved.target_spec
    params = spec.active(resolved.base)
    texturing = resolved.textured(resolved, None, adapter, dict(resolved.base)) if resolved.textured else None
    try:
        with tempfile.TemporaryDirectory(prefix="brdfremap-") as tmp:
            files = []
            if texturing is None:
                made = [Path(p) for p in adapter.write_native(spec, dict(resolved.base), Path(tmp))]
            else:
                for name, data in texturing.files.items():
                    (Path(tmp) / name).write_bytes(data)
                made = [Path(tmp) / n for n in texturing.files] + [Path(p) for p in adapter.write_native(
                    spec, texturing.params, Path(tmp), textures=texturing.native)]
                params = spec.active(texturing.params)
            files = [write_bytes_atomic(Path(folder) / p.name, p.read_bytes()) for p in made]
    except OSError as exc:
        raise ConfigError(f"cannot write the native material: {why(exc)}", file=str(folder)) from None
    lk = answer.lookup
    doc = LookupRecord(tool=f"brdf-remap {__version__}",
                       table=TableRef(name=lk.table, file=table_file, digest=lk.digest, method=lk.method),
                       source=job.source, target=TargetRef(adapter=job.target.adapter, model=job.target.model),
                       params={k: list(v) if isinstance(v, tuple) else v for k, v in params.items()},
                       axis_values=answer.values, expected_error=lk.expected_error, outside=lk.outside,
                       lookup_seconds=answer.seconds, files=[p.name for p in files],
                       textures=texturing.record.model_dump(mode="json") if texturing else None)
    files.append(write_json_atomic(Path(folder) / "lookup.json", doc.model_dump(mode="json")))
    return files

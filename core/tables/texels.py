"""A textured source through a table, texel by texel: its images read to linear values on a common
resolution, every texel looked up through the map baked on a fine grid (in blocks), and the target's maps."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..data.errors import ConfigError
from ..data.schemas import Material, ModelSpec
from ..data.textures import read_values, resized
from .dense import DenseMap
from .outputs import param_bounds
from .table import Table, TableMap, outside

UNIFORM = 1e-4
"""A target map whose values span less than this fraction of the parameter's range is a constant."""


@dataclass
class Inputs:
    """The source's axis values per texel (N, or N x 3), and the texture's size."""

    values: dict[str, np.ndarray]
    width: int
    height: int
    textured: list[str]
    notes: list[str] = field(default_factory=list)
    source_maps: dict[str, np.ndarray] = field(default_factory=dict)
    """Each textured input's values, H x W (x 3), as read."""


def read_inputs(table: Table, material: Material, source_spec: ModelSpec, file: str | None = None) -> Inputs:
    """The material's textures (each of an axis of the table) and its constants, texel by texel;
    a texture smaller than the largest is resampled to it, and said."""
    loose = [n for n in material.textures if n not in table.spec.axes]
    if loose:
        name = loose[0]
        raise ConfigError(f"is an image, and the table {table.name!r} holds {name} at one value (its axes: "
                          f"{', '.join(table.spec.axes)}): build a table with {name} as an axis", file=file,
                          field=f"textures.{name}")
    maps = {n: read_values(t, source_spec.param(n).kind, where=f"{material.name or 'material'}: {n}")
            for n, t in material.textures.items()}
    if not maps:
        raise ConfigError("has no texture to remap texel by texel", file=file, field="textures")
    width = max(m.shape[1] for m in maps.values())
    height = max(m.shape[0] for m in maps.values())
    notes = []
    for n, m in list(maps.items()):
        if m.shape[:2] != (height, width):
            notes.append(f"{n}: {m.shape[1]} x {m.shape[0]} resampled to {width} x {height}, the largest texture's size")
            maps[n] = resized(m, width, height)
    params = source_spec.complete(material.params, file=file)
    values: dict[str, np.ndarray] = {}
    for name in table.spec.axes:
        if name in maps:
            m = maps[name]
            values[name] = m.reshape(-1, 3) if m.ndim == 3 else m.reshape(-1)
        else:
            v = np.asarray(params[name], np.float32)
            values[name] = np.broadcast_to(v, (width * height, *v.shape))
    return Inputs(values, width, height, sorted(maps), notes, maps)


def mean_values(inputs: Inputs) -> dict[str, Any]:
    """The texture's mean on each axis: the uniform material that stands for it in the report."""
    out: dict[str, Any] = {}
    for k, v in inputs.values.items():
        m = np.asarray(v, np.float64).mean(axis=0)
        out[k] = [float(x) for x in m] if m.ndim else float(m)
    return out


@dataclass
class Remapped:
    """The target's values texel by texel: a map per varying parameter, a constant per uniform one."""

    maps: dict[str, np.ndarray]
    constants: dict[str, Any]
    outside: list[str]
    seconds: float


def remap_texels(table: Table, tmap: TableMap, inputs: Inputs) -> Remapped:
    """Every texel looked up through the table's map (baked on a fine grid)."""
    t0 = time.perf_counter()
    pred = DenseMap(tmap).predict(inputs.values)
    seconds = time.perf_counter() - t0
    maps, constants = {}, {}
    bounds = param_bounds(table.outputs)
    for name, v in pred.items():
        lo, hi = bounds[name]
        if float(np.ptp(v)) <= UNIFORM * (hi - lo):
            mean = np.clip(v.mean(axis=0, dtype=np.float64), lo, hi)  # float32's 1e-4 is below 1e-4
            constants[name] = [float(x) for x in mean] if mean.ndim else float(mean)
        else:
            shape = (inputs.height, inputs.width) + ((3,) if v.ndim == 2 else ())
            maps[name] = v.reshape(shape)
    return Remapped(maps, constants, outside(table, inputs.values), seconds)

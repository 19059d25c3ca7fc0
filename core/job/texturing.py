"""A textured source's job, past its uniform lookup: every texel remapped through the table, the
target's maps as files beside its native material, and the textured source and result rendered
on the probe sphere by their own renderers and compared.

A target parameter that varies over the texture but that the target renderer takes only as a
number (its model does not list it as `texturable`) is written as its mean, and the record says so."""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from pydantic import Field

from ..data.errors import RenderError
from ..data.metrics import beyond_noise, delta_e_itp, relative_rmse
from ..data.model import Strict
from ..data.scene import Lighting, ProbeScene
from ..data.textures import Texture, TextureMap, decode, encode, kind_of_file, mean_value
from ..host.protocol import Adapter, check_image
from ..data.schemas import ParamKind

CHECK_RESOLUTION, CHECK_SPP = 64, 32
"""The textured check's least resolution and samples (each side twice, for its noise): the scene's
resolution and four times its samples (128 px and 64 spp for the default probe), at least these;
under the studio environment half the resolution (at least this) and four times the samples
(every direction lights each pixel), as the held-out environment is rendered."""


class MapRecord(Strict):
    param: str
    file: str = Field(description="The map's file beside result.json.")
    colorspace: str = Field(description="srgb (a colour map, 16-bit PNG) or linear (a data map).")
    low: float = Field(description="Its lowest value (any channel).")
    high: float = Field(description="Its highest value.")


class TexturedCheck(Strict):
    """The textured source and the textured result on the probe sphere, each by its own renderer."""

    condition: Lighting = Field(description="scene (the job's lights: where the highlight runs over the texture) or "
                                       "environment (the studio: every texel lit).")
    resolution: int
    spp: int
    error: float = Field(description="Relative RMSE of the textured result against the textured source.")
    perceptual: float = Field(description="Mean ΔE_ITP over the lit pixels.")
    noise_floor: float
    beyond_noise: float


class Textured(Strict):
    """`result.json`'s record of a textured source remapped texel by texel through a table."""

    table: str
    inputs: dict[str, str] = Field(description="Each textured source input and its image file.")
    width: int
    height: int
    maps: list[MapRecord] = Field(description="The target's maps, written beside the native material.")
    constants: dict[str, Any] = Field(default_factory=dict, description="Target parameters uniform over the "
                                                                        "texture (written as numbers).")
    values: dict[str, Any] = Field(default_factory=dict, description="The native material's numbers: the lookup's, "
                                                                    "with the constants and the held means.")
    held: dict[str, str] = Field(default_factory=dict, description="Target parameters that vary over the texture "
                                                                   "but the target takes only as a number: their "
                                                                   "mean is written, and why.")
    outside: list[str] = Field(default_factory=list, description="Texel values outside the table's range (clamped).")
    notes: list[str] = Field(default_factory=list)
    seconds: float = Field(description="The texel-by-texel remap (reading and writing the images aside).")
    checks: list[TexturedCheck] = Field(default_factory=list, description="The textured check under each condition.")
    check_skipped: str = Field("", description="Why the textured check was not rendered.")


@dataclass
class Texturing:
    record: Textured
    files: dict[str, bytes]
    native: dict[str, Texture]
    """Target parameter -> its map (a file name of ``files``), for the native material."""
    params: dict[str, Any]
    """The native material's numbers: the fit's, with the constants and held means."""
    images: tuple[np.ndarray, np.ndarray] | None = None
    """The textured source and result under the studio environment (the check's images)."""


def texture_result(resolved, source: Adapter | None, target: Adapter, params: dict[str, Any]) -> Texturing:
    """Remap the job's textures through its table, and render the textured check (not without a
    ``source`` adapter: `remap --table --no-render`)."""
    from ..tables import TableMap, read_table
    from ..tables.texels import read_inputs, remap_texels

    job = resolved.job
    lk = job.lookup
    table = read_table(lk.file)
    if table.digest != lk.digest:
        raise RenderError(f"the table {lk.file} changed since the job was planned: run the command again")
    inputs = read_inputs(table, job.source, resolved.source_spec)
    t0 = time.perf_counter()
    out = remap_texels(table, TableMap(table, lk.method), inputs)
    spec = resolved.target_spec
    held = {n: f"{spec.name} takes {n} only as a number: its mean over the texture is written"
            for n in out.maps if n not in spec.texturable or not target.textures}
    numbers = {**out.constants, **{n: mean_value(out.maps[n]) for n in held}}
    native_params = {**params, **{n: spec.param(n).clip(v) for n, v in numbers.items()}}
    maps = {n: m for n, m in out.maps.items() if n not in held}
    held = {n: why for n, why in held.items() if not spec.is_inert(n, native_params)}  # one that does nothing: unsaid
    filt = next(iter(job.source.textures.values())).filter
    files, native, records, written = {}, {}, [], {}
    for name, values in maps.items():
        p = spec.param(name)
        suffix, space = kind_of_file(p.lower, p.upper, p.kind == ParamKind.RGB)
        fname = f"map-{name}{suffix}"
        files[fname] = encode(values, suffix, space)
        native[name] = Texture(file=fname, colorspace=space, filter=filt)  # type: ignore[arg-type]
        records.append(MapRecord(param=name, file=fname, colorspace=space, low=float(values.min()),
                                 high=float(values.max())))
        if source is not None:  # the check renders the maps as written (a 16-bit PNG's values), not as computed
            written[name] = decode(files[fname], suffix, space, p.kind)
    seconds = time.perf_counter() - t0
    checks, skipped, images = ([], "not rendered (--no-render)", None) if source is None else \
        _check(resolved, source, target, inputs, written, native_params, filt)
    record = Textured(table=table.name, inputs={n: t.file for n, t in job.source.textures.items()},
                      width=inputs.width, height=inputs.height, maps=records, constants=out.constants,
                      values=_plain(spec.active(native_params)), held=held,
                      outside=out.outside, notes=inputs.notes, seconds=seconds, checks=checks, check_skipped=skipped)
    return Texturing(record, files, native, native_params, images)


def textured_findings(record: Textured, threshold: float, resolve_limit: float) -> list:
    """What the textured check and the remap say for the verdict: the conditions (resolved by their
    noise) where the textured result is over the threshold beyond the noise; the means written and
    the texels clamped, as a note."""
    from ..data.findings import TexturedAbove, TexturedCondition, TexturedNotes

    above = [TexturedCondition(condition=c.condition, error=c.error, beyond_noise=c.beyond_noise)
             for c in record.checks if c.noise_floor <= resolve_limit and c.beyond_noise > threshold]
    out: list = [TexturedAbove(conditions=above, threshold=threshold)] if above else []
    if record.held or record.outside:
        out.append(TexturedNotes(held=list(record.held.values()), outside=list(record.outside)))
    return out


def _plain(params: dict[str, Any]) -> dict[str, Any]:
    return {k: list(v) if isinstance(v, tuple) else v for k, v in params.items()}


def _check(resolved, source: Adapter, target: Adapter, inputs, maps: dict[str, np.ndarray],
           params: dict[str, Any], filt: str):
    """Both textured materials on the probe sphere under the job's lights and under the studio
    environment, each side twice (its noise)."""
    from ..data.scene import EnvironmentLight

    job = resolved.job
    why = _cannot_check(resolved, source, target)
    if why:
        return [], why, None
    first = job.scene.view_scenes()[0]
    spp = max(CHECK_SPP, job.scene.spp * 4)
    base = first.with_(resolution=max(CHECK_RESOLUTION, first.resolution), spp=spp)
    # As a held-out environment: half the resolution at four times the samples (the scene check's cost).
    studio = base.model_copy(update={"lights": [EnvironmentLight(type="environment", map="studio")],
                                     "resolution": max(CHECK_RESOLUTION, base.resolution // 2),
                                     "spp": 4 * spp, "name": "textured check: studio"})
    src_maps = {n: TextureMap(inputs.source_maps[n], t.filter) for n, t in job.source.textures.items()}
    tgt_maps = {n: TextureMap(v, filt) for n, v in maps.items()}
    checks, images = [], None
    for condition, scene in ((Lighting.SCENE, base), (Lighting.ENVIRONMENT, studio)):
        if source.scene_problem(scene) or target.scene_problem(scene):
            continue
        src, src_noise = _pair(source, job.source.model, resolved.source_params, src_maps, scene, 0, "source")
        tgt, tgt_noise = _pair(target, job.target.model, params, tgt_maps, scene, 2, "target")
        err, floor = relative_rmse(src, tgt), float(np.hypot(src_noise, tgt_noise))
        checks.append(TexturedCheck(condition=condition, resolution=scene.resolution, spp=2 * scene.spp, error=err,
                                    perceptual=delta_e_itp(src, tgt), noise_floor=floor,
                                    beyond_noise=beyond_noise(err, floor)))
        images = (src, tgt)
    return checks, "", images


def _pair(adapter: Adapter, model: str, params, maps, scene: ProbeScene, offset: int, who: str):
    """The mean of two renders at other seeds, and its noise (their difference / 2)."""
    a, b = (check_image(adapter.render_textured(model, dict(params), maps, sc), sc, f"{who} textured")
            for sc in (scene.with_(seed=scene.seed + offset), scene.with_(seed=scene.seed + offset + 1)))
    return (a + b) / 2, relative_rmse(a, b) / 2


def _cannot_check(resolved, source: Adapter, target: Adapter) -> str:
    job = resolved.job
    for adapter, name in ((source, job.source.adapter), (target, job.target.adapter)):
        if not adapter.textures:
            return f"adapter {name!r} does not render textures"
    loose = [n for n in job.source.textures if n not in resolved.source_spec.texturable]
    if loose:
        return f"{job.source.model} takes {', '.join(loose)} only as a number in its renderer"
    return ""

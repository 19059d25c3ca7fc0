"""A textured source's job, texel by texel: every texel remapped through the job's table, the
target's maps as files beside its native material, and the textured source and result rendered
on the probe sphere by their own renderers and compared. A room above the job and the tables
(it uses both): a textured job is resolved with `texture_result` as its step
(`core.job.texturing.TexturedStep`), which the job calls where it runs."""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from ..data.errors import RenderError
from ..data.metrics import beyond_noise, delta_e_itp, relative_rmse
from ..data.scene import Lighting, ProbeScene
from ..data.schemas import ParamKind
from ..data.textures import Texture, TextureMap, decode, encode, kind_of_file, mean_value
from ..host.model import Model
from ..host.protocol import Adapter, check_image
from ..job.texturing import MapRecord, TexturedCheck, Textured, Texturing
from ..tables import TableMap, read_table
from ..tables.texels import read_inputs, remap_texels

CHECK_RESOLUTION, CHECK_SPP = 64, 32
"""The textured check's least resolution and samples (each side twice, for its noise): the scene's
resolution and four times its samples (128 px and 64 spp for the default probe), at least these;
under the studio environment half the resolution (at least this) and four times the samples
(every direction lights each pixel), as the held-out environment is rendered."""


def texture_result(resolved, source: Adapter | None, target: Adapter, params: dict[str, Any]) -> Texturing:
    """Remap the job's textures through its table, and render the textured check (not without a
    ``source`` adapter: `remap --table --no-render`)."""
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
        src, src_noise = _pair(source, resolved.source_spec, resolved.source_params, src_maps, scene, 0, "source")
        tgt, tgt_noise = _pair(target, resolved.target_spec, params, tgt_maps, scene, 2, "target")
        err, floor = relative_rmse(src, tgt), float(np.hypot(src_noise, tgt_noise))
        checks.append(TexturedCheck(condition=condition, resolution=scene.resolution, spp=2 * scene.spp, error=err,
                                    perceptual=delta_e_itp(src, tgt), noise_floor=floor,
                                    beyond_noise=beyond_noise(err, floor)))
        images = (src, tgt)
    return checks, "", images


def _pair(adapter: Adapter, model: Model, params, maps, scene: ProbeScene, offset: int, who: str):
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

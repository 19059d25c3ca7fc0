"""A converted library as one USD layer, `library.usda`, through usd-core: one Material per converted
material under /Library/Materials, each bound to a sphere (in a row along +x, as `library.gltf`'s).
Its universal surface is a UsdPreviewSurface: the fitted material itself for the
`threejs:usd_preview_surface` target, otherwise an approximation by the exporters' conventions
(the model's neutral reading), said so in the material's documentation. A target MaterialX describes
also gets its `mtlx` surface, the shader written directly in USD: a MaterialX shader as fitted, Cycles'
Principled BSDF as OpenPBR by the correspondence. Maps are UsdUVTexture (and MaterialX image nodes) reading the library's
`textures/`."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

from brdfremap.core.data.atomic import write_text_atomic
from brdfremap.core.data.schemas import Value
from brdfremap.core.host.model import Model
from brdfremap.core.library.formats import Converted, clip_into

from . import author
from .preview import UsdPreviewSurface

SPACING = 2.5
"""Spheres of radius 1, this far apart along +x."""


@dataclass
class MtlxSurface:
    """How a target model is written as a MaterialX shader in USD (its nodedef: open_pbr_surface's by
    default): its inputs for the model's parameters, and which input each map drives as it is."""

    inputs: Callable[[dict[str, Value]], dict[str, Value]]
    direct: dict[str, str] = field(default_factory=dict)
    nodedef: str = "ND_open_pbr_surface_surfaceshader"


@dataclass
class UsdWriter:
    adapter: str
    load_models: Callable[[], dict[str, Model]]
    """The adapter's models (imported when a library is written, not when the plugin registers)."""
    mtlx: dict[str, Callable[[], MtlxSurface]] = field(default_factory=dict)
    """Target models MaterialX describes, by name: Cycles' Principled BSDF as OpenPBR by the correspondence,
    a MaterialX shader as itself."""
    preview_maps: dict[str, dict[str, str]] = field(default_factory=dict)
    """Per target model, the maps its UsdPreviewSurface approximation takes as they are (its parameter:
    the approximation's)."""
    name: str = "USD library (library.usda)"
    models: tuple[str, ...] = ()

    def write(self, folder: Path, items: list[Converted]) -> list[Path]:
        Gf, Sdf, Usd, UsdGeom, UsdShade = author.pxr()
        stage = Usd.Stage.CreateInMemory()
        UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
        root = UsdGeom.Xform.Define(stage, "/Library")
        stage.SetDefaultPrim(root.GetPrim())
        models = self.load_models()
        used: set[str] = set()
        for i, item in enumerate(items):
            name = _valid(item.name, i, used)
            material = self._material(stage, f"/Library/Materials/{name}", models[item.model], item)
            author.sphere_mesh(stage, f"/Library/Spheres/{name}", material, SPACING * i)
        stage.GetRootLayer().documentation = (f"brdf-remap: {len(items)} materials converted to {self.adapter}, "
                                              "each bound to a sphere")
        return [write_text_atomic(Path(folder) / "library.usda", stage.GetRootLayer().ExportToString())]

    def _material(self, stage, path: str, model: Model, item: Converted):
        params = model.complete(item.params)
        preview, how = _preview(model, params, f"{self.adapter}:{item.model}")
        carried = self.preview_maps.get(item.model, {})
        maps = {carried[p]: t for p, t in item.textures.items() if p in carried}
        left = sorted(set(item.textures) - set(carried))
        doc = f"source material: {item.name}; UsdPreviewSurface: {how}" + (
            f"; maps not carried by it: {', '.join(left)}" if left else "")
        material = author.preview_surface(stage, path, preview, maps, doc=doc)
        if item.model in self.mtlx:
            spec = self.mtlx[item.model]()
            types = _types(spec.nodedef)
            shader = author.mtlx_surface(stage, material, spec.nodedef, spec.inputs(params), types)
            for pname, tex in sorted(item.textures.items()):
                if pname in spec.direct:
                    author.mtlx_image(stage, path, shader, spec.direct[pname], tex, types[spec.direct[pname]])
        return material


def _preview(model: Model, params: dict[str, Value], name: str) -> tuple[dict[str, Value], str]:
    """The UsdPreviewSurface of a converted material, and what it is: the material itself, or an
    approximation by its neutral reading (or the specification's defaults where it has none)."""
    from brdfremap.adapters.threejs.models import USD_PREVIEW

    if isinstance(model, UsdPreviewSurface):
        return params, "fitted"
    reading = model.appearance(params)
    if reading is None:
        return USD_PREVIEW.complete({}), (f"the specification's defaults, a placeholder ({name} has no neutral "
                                          "reading to approximate it by)")
    values: dict[str, Any] = USD_PREVIEW.from_appearance(reading, USD_PREVIEW.complete({}))
    clip_into(USD_PREVIEW, values)
    return USD_PREVIEW.complete(values), (f"an approximation of {name} by the exporters' conventions (not fitted; "
                                          "the fitted material is this material's mtlx surface where it has one, "
                                          "else the target's own library)")


def _valid(name: str, i: int, used: set[str]) -> str:
    """A prim name for the material, unique in the library ("a/b" and "a b" both make "a_b": the
    second is "a_b_2")."""
    from pxr import Tf

    base = Tf.MakeValidIdentifier(name) if name else f"material_{i}"
    out, n = base, 1
    while out in used:
        n += 1
        out = f"{base}_{n}"
    used.add(out)
    return out


def _types(nodedef: str) -> dict[str, str]:
    """A MaterialX shader's inputs and their types."""
    from brdfremap.adapters.materialx.mxlib import standard_libraries

    lib = standard_libraries()
    return {i.getName(): i.getType() for i in lib.getNodeDef(nodedef).getActiveInputs()}

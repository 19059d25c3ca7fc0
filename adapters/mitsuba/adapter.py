"""Mitsuba 3 in process. Scenes are built once per (model, discrete choices, probe scene)
and numeric parameters are updated in place through ``mi.traverse`` between renders."""

from __future__ import annotations

import importlib.util
from collections import OrderedDict
from pathlib import Path
from typing import Any
from xml.sax.saxutils import quoteattr

import numpy as np

from brdfremap.core.atomic import write_text_atomic
from brdfremap.core.errors import ConfigError, RenderError
from brdfremap.core.protocol import Adapter
from brdfremap.core.scene import ProbeScene
from brdfremap.core.schemas import Value

from .models import MODELS
from .variant import as_dict, choose_variant

EXT_IOR = 1.000277  # Mitsuba's default exterior medium (air)


def _rgb(v: Value) -> dict:
    return {"type": "rgb", "value": list(v)}  # type: ignore[arg-type]


def bsdf_dict(model: str, p: dict[str, Value]) -> dict[str, Any]:
    """The Mitsuba BSDF dictionary of a model and its complete parameters."""
    if model == "roughconductor":
        d = {"type": "roughconductor", "distribution": p["distribution"], "alpha": p["alpha"],
             "specular_reflectance": _rgb(p["specular_reflectance"])}
        if p["material"] == "none":
            d.update(eta=_rgb(p["eta"]), k=_rgb(p["k"]))
        else:
            d["material"] = p["material"]
        return d
    if model == "roughplastic":
        return {"type": "roughplastic", "distribution": p["distribution"], "alpha": p["alpha"],
                "int_ior": p["int_ior"], "ext_ior": EXT_IOR, "nonlinear": False,
                "diffuse_reflectance": _rgb(p["diffuse_reflectance"]),
                "specular_reflectance": _rgb(p["specular_reflectance"])}
    if model == "diffuse":
        return {"type": "diffuse", "reflectance": _rgb(p["reflectance"])}
    if model == "principled":
        d: dict[str, Any] = {"type": "principled", "base_color": _rgb(p["base_color"])}
        for name in ("metallic", "roughness", "specular", "spec_tint", "anisotropic", "sheen", "sheen_tint",
                     "clearcoat", "clearcoat_gloss"):
            d[name] = p[name]
        return d
    raise ConfigError(f"mitsuba adapter has no model {model!r}")


def _traverse_value(model: str, name: str, v: Value) -> tuple[str, Any]:
    """Traverse key (relative to the BSDF) and value for a numeric parameter."""
    if model == "roughplastic" and name == "int_ior":
        return "eta", float(v) / EXT_IOR  # type: ignore[arg-type]
    return name, v


def bsdf_xml(model: str, p: dict[str, Value]) -> str:
    """The material as a Mitsuba 3 XML ``<bsdf>`` element."""
    d = bsdf_dict(model, p)
    lines = [f"<bsdf type={quoteattr(d.pop('type'))}>"]
    for key, v in d.items():
        if isinstance(v, dict):
            lines.append(f'    <rgb name="{key}" value="{", ".join(f"{x:.6g}" for x in v["value"])}"/>')
        elif isinstance(v, bool):
            lines.append(f'    <boolean name="{key}" value="{str(v).lower()}"/>')
        elif isinstance(v, str):
            lines.append(f'    <string name="{key}" value={quoteattr(v)}/>')
        else:
            lines.append(f'    <float name="{key}" value="{v:.6g}"/>')
    lines.append("</bsdf>")
    return "\n".join(lines) + "\n"


class MitsubaAdapter(Adapter):
    name = "mitsuba"
    summary = "Mitsuba 3, in process (llvm_ad_rgb when a working libLLVM is found, else scalar_rgb)"
    install_hint = "pip install 'brdf-remap[mitsuba]'"
    models = MODELS
    max_scenes = 8

    @classmethod
    def unavailable_reason(cls) -> str | None:
        if importlib.util.find_spec("mitsuba") is None:
            return "the mitsuba package is not installed"
        return None

    def __init__(self) -> None:
        self.choice = choose_variant()
        try:
            import mitsuba as mi
        except ImportError as exc:
            raise RenderError(f"cannot import mitsuba: {exc}") from exc
        try:
            mi.set_variant(self.choice.variant)
        except Exception as exc:
            raise RenderError(f"mitsuba cannot use variant {self.choice.variant!r}: {exc}") from exc
        self.mi = mi
        # key -> (scene, traverse handle, parameter -> traverse key, values currently set)
        self._scenes: OrderedDict[tuple, tuple[Any, Any, dict[str, str], dict[str, Value]]] = OrderedDict()

    @classmethod
    def environment(cls) -> dict[str, Any]:
        import importlib.metadata

        return {"renderer": f"Mitsuba {importlib.metadata.version('mitsuba')}", **as_dict(choose_variant())}

    def describe(self) -> dict[str, Any]:
        return {"renderer": f"Mitsuba {self.mi.__version__}", **as_dict(self.choice)}

    def scene_dict(self, model: str, params: dict[str, Value], scene: ProbeScene) -> dict[str, Any]:
        mi = self.mi
        cam = scene.camera
        return {
            "type": "scene",
            # Direct lighting only; a point light is reached by emitter sampling alone.
            "integrator": {"type": "direct", "emitter_samples": 1, "bsdf_samples": 0},
            "sensor": {
                "type": "perspective", "fov": cam.fov, "fov_axis": "x",
                "to_world": mi.ScalarTransform4f().look_at(origin=list(cam.position), target=list(cam.target),
                                                           up=list(cam.up)),
                "film": {"type": "hdrfilm", "width": scene.resolution, "height": scene.resolution,
                         "rfilter": {"type": "box"}, "pixel_format": "rgb"},
                "sampler": {"type": "multijitter", "sample_count": scene.spp, "seed": scene.seed},
            },
            "probe": {"type": "sphere", "center": list(scene.sphere.center), "radius": scene.sphere.radius,
                      "bsdf": bsdf_dict(model, params)},
            "light": {"type": "point", "position": list(scene.light.position),
                      "intensity": {"type": "rgb", "value": [scene.light.intensity] * 3}},
        }

    def _scene(self, model: str, params: dict[str, Value], scene: ProbeScene):
        spec = self.models[model]
        key = (model, tuple(params[p.name] for p in spec.parameters if p.kind == "choice"), scene.cache_key())
        if key in self._scenes:
            self._scenes.move_to_end(key)
            return self._scenes[key]
        try:
            sc = self.mi.load_dict(self.scene_dict(model, params, scene))
        except Exception as exc:
            raise RenderError(f"mitsuba could not build the {model} scene: {exc}") from exc
        handle = self.mi.traverse(sc)
        keys = {}
        for p in spec.parameters:
            if p.kind == "choice":
                continue
            tname, _ = _traverse_value(model, p.name, p.default)
            for cand in (f"probe.bsdf.{tname}.value", f"probe.bsdf.{tname}"):
                if cand in handle:
                    keys[p.name] = cand
                    break
        self._scenes[key] = (sc, handle, keys, dict(params))
        if len(self._scenes) > self.max_scenes:
            self._scenes.popitem(last=False)
        return self._scenes[key]

    def render(self, model: str, params: dict[str, Value], scene: ProbeScene, lobe: str | None = None) -> np.ndarray:
        spec = self.models[model]
        p = spec.with_lobe(params, lobe)
        sc, handle, keys, current = self._scene(model, p, scene)
        changed = False
        for name, key in keys.items():
            if not spec.is_active(name, p) or current.get(name) == p[name]:
                continue
            _, v = _traverse_value(model, name, p[name])
            handle[key] = list(v) if isinstance(v, tuple) else float(v)  # type: ignore[arg-type]
            current[name] = p[name]
            changed = True
        if changed:
            # Only when something moved: some BSDFs (roughplastic) redo costly set-up on update.
            handle.update()
        try:
            img = self.mi.render(sc, seed=scene.seed, spp=scene.spp)
        except Exception as exc:
            raise RenderError(f"mitsuba render failed ({model}, {params}): {exc}") from exc
        return np.array(img, dtype=np.float32)[..., :3]

    def write_native(self, model: str, params: dict[str, Value], out_dir: Path) -> list[Path]:
        text = f"<!-- brdf-remap: Mitsuba 3 {model} -->\n" + bsdf_xml(model, params)
        return [write_text_atomic(Path(out_dir) / "material.xml", text)]

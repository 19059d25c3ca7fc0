"""Mitsuba 3 in process. Scenes are built once per (model, discrete choices, probe scene)
and numeric parameters are updated in place through ``mi.traverse`` between renders."""

from __future__ import annotations

import importlib.util
from collections import OrderedDict
from pathlib import Path
from typing import Any
from xml.sax.saxutils import quoteattr

import numpy as np
from brdfremap.core.run import interrupt
from brdfremap.core.data.appearance import (
    Appearance,
    as_rgb,
    dielectric_f0,
    eta_k_from_reflectivity,
    reflectivity_edge_tint,
)
from brdfremap.core.data.atomic import write_text_atomic
from brdfremap.core.data.errors import ConfigError, RenderError
from brdfremap.core.protocol import Adapter, ModelChoice
from brdfremap.core.data.scene import PointLight, ProbeScene
from brdfremap.core.data.schemas import ParamKind, TRANSMISSION_DEPTH, Value
from brdfremap.core.data.textures import ColourSpace, Texture, TextureMap

from . import appearance as _appearance
from .appearance import EXT_IOR
from .blend import SLOTS, blend_appearance, component
from .bsdfs import conductor_preset, register_bsdfs, trim_scale
from .envmap import mitsuba_rows
from .models import MODELS
from .variant import as_dict, choose_variant


def _rgb(v: Value) -> dict:
    return {"type": "rgb", "value": list(v)}  # type: ignore[arg-type]


def emitters(scene: ProbeScene, mi) -> dict[str, Any]:
    """The scene's lights as Mitsuba emitters: a point light is `point` (intensity in W/sr), the
    environment `envmap` with an identity transform (`core.data.environment`'s orientation is Mitsuba's),
    its map's rows resampled as Mitsuba reads them (`envmap.mitsuba_rows`)."""
    from brdfremap.core.data.environment import radiance

    out: dict[str, Any] = {}
    for i, light in enumerate(scene.lights):
        if isinstance(light, PointLight):
            out["light" if i == 0 else f"light{i}"] = {
                "type": "point", "position": list(light.position),
                "intensity": {"type": "rgb", "value": [light.intensity] * 3}}
        else:
            rows = mitsuba_rows(radiance(light.map, light.scale, light.rotation))
            out["environment"] = {"type": "envmap", "bitmap": mi.Bitmap(rows)}
    return out


def integrator(scene: ProbeScene, transmissive: bool) -> dict[str, Any]:
    """Direct light alone for an opaque sphere (a point light reached by emitter sampling, an
    environment by BSDF sampling too: a sharp lobe sees it no other way); paths deep enough to pass
    through a transmissive one, without Russian roulette (the same expectation as Cycles' bounces,
    no extra noise). The emitters are never seen directly: the background stays black."""
    if transmissive:
        return {"type": "path", "max_depth": TRANSMISSION_DEPTH, "rr_depth": TRANSMISSION_DEPTH,
                "hide_emitters": True}
    out: dict[str, Any] = {"type": "direct", "emitter_samples": 1, "bsdf_samples": 0}
    if scene.environment is not None:
        out.update(bsdf_samples=1, hide_emitters=True)
    return out


def _conductor_ior(p: dict[str, Value]) -> dict[str, Any]:
    """A conductor's Fresnel: eta and k, reflectivity and edge tint, or a named preset."""
    if p["material"] == "none":
        return {"eta": _rgb(p["eta"]), "k": _rgb(p["k"])}
    if p["material"] == "reflectivity":
        return {"reflectivity": _rgb(p["reflectivity"]), "edge_tint": _rgb(p["edge_tint"])}
    return {"material": p["material"]}


def _conductor(kind: str, p: dict[str, Value]) -> dict[str, Any]:
    return {"type": kind, "specular_reflectance": _rgb(p["specular_reflectance"]), **_conductor_ior(p)}


def _roughconductor(p: dict[str, Value]) -> dict[str, Any]:
    d = {**_conductor("roughconductor", p), "distribution": p["distribution"]}
    if p["anisotropy"] == "anisotropic":
        d.update(alpha_u=p["alpha_u"], alpha_v=p["alpha_v"])
    else:
        d["alpha"] = p["alpha"]
    return d


def _plastic(kind: str, p: dict[str, Value]) -> dict[str, Any]:
    d = {"type": kind, "int_ior": p["int_ior"], "ext_ior": EXT_IOR, "nonlinear": False,
         "diffuse_reflectance": _rgb(p["diffuse_reflectance"]),
         "specular_reflectance": _rgb(p["specular_reflectance"])}
    if kind == "roughplastic":
        d.update(distribution=p["distribution"], alpha=p["alpha"])
    return d


def _dielectric(kind: str, p: dict[str, Value]) -> dict[str, Any]:
    d = {"type": kind, "int_ior": p["int_ior"], "ext_ior": EXT_IOR,
         "specular_reflectance": _rgb(p["specular_reflectance"]),
         "specular_transmittance": _rgb(p["specular_transmittance"])}
    if kind == "roughdielectric":
        d.update(distribution=p["distribution"], alpha=p["alpha"])
    return d


def _legacy(model: str, p: dict[str, Value]) -> dict[str, Any]:
    """Mitsuba 0.5's Ward and Phong (this project's plugins)."""
    d = {"type": model, "ensure_energy_conservation": p["ensure_energy_conservation"] == "true",
         "specular_reflectance": _rgb(p["specular_reflectance"]),
         "diffuse_reflectance": _rgb(p["diffuse_reflectance"])}
    if model == "ward":
        d.update(variant=p["variant"], alpha=p["alpha"])
    else:
        d["exponent"] = p["exponent"]
    return d


def _as_conductor(p: dict[str, Value]) -> dict[str, Any]:
    return {"type": "ashikhmin_shirley", "form": "conductor", "alpha": p["alpha"],
            "specular_reflectance": _rgb(p["specular_reflectance"]), **_conductor_ior(p)}


def _as_plastic(p: dict[str, Value]) -> dict[str, Any]:
    return {"type": "ashikhmin_shirley", "form": "plastic", "alpha": p["alpha"], "int_ior": p["int_ior"],
            "ext_ior": EXT_IOR, "diffuse_reflectance": _rgb(p["diffuse_reflectance"]),
            "specular_reflectance": _rgb(p["specular_reflectance"])}


def _principled(p: dict[str, Value]) -> dict[str, Any]:
    d: dict[str, Any] = {"type": "principled", "base_color": _rgb(p["base_color"])}
    d.update({ps.name: p[ps.name] for ps in MODELS["principled"].parameters if ps.name != "base_color"})
    return d


def _same_slots(p: dict[str, Value]) -> bool:
    """Whether a blend's two BSDFs are the same model with the same values (Mitsuba loads them as one)."""
    return bsdf_dict(*component(SLOTS[0], p)) == bsdf_dict(*component(SLOTS[1], p))


def _blend(p: dict[str, Value]) -> dict[str, Any]:
    d: dict[str, Any] = {"type": "blendbsdf", "weight": p["weight"]}
    for slot in SLOTS:
        model, sub = component(slot, p)
        d[slot] = BUILDERS[model](sub)
    return d


BUILDERS = {
    "roughconductor": _roughconductor,
    "conductor": lambda p: _conductor("conductor", p),
    "roughplastic": lambda p: _plastic("roughplastic", p),
    "plastic": lambda p: _plastic("plastic", p),
    "diffuse": lambda p: {"type": "diffuse", "reflectance": _rgb(p["reflectance"])},
    "dielectric": lambda p: _dielectric("dielectric", p),
    "roughdielectric": lambda p: _dielectric("roughdielectric", p),
    "thindielectric": lambda p: _dielectric("thindielectric", p),
    "principled": _principled,
    "ward": lambda p: _legacy("ward", p),
    "phong": lambda p: _legacy("phong", p),
    "ashikhmin_shirley": _as_conductor,
    "ashikhmin_shirley_plastic": _as_plastic,
    "blendbsdf": _blend,
}
"""Each model's Mitsuba BSDF dictionary from its complete parameters."""


def bsdf_dict(model: str, p: dict[str, Value]) -> dict[str, Any]:
    """The Mitsuba BSDF dictionary of a model and its complete parameters."""
    if model not in BUILDERS:
        raise ConfigError(f"mitsuba adapter has no model {model!r}")
    return BUILDERS[model](p)


RELATIVE_IOR = {"roughplastic", "plastic", "dielectric", "roughdielectric", "thindielectric"}
"""Mitsuba's plastics and glasses traverse eta = int_ior / ext_ior."""


def traverse_values(model: str, spec, p: dict[str, Value]) -> dict[str, Any]:
    """The BSDF's traverse keys (relative to the BSDF) and values for the active numeric parameters."""
    if model == "blendbsdf":
        return _blend_traverse(p)
    out: dict[str, Any] = {}
    for ps in spec.parameters:
        if ps.kind == ParamKind.CHOICE or not spec.is_active(ps.name, p):
            continue
        v = p[ps.name]
        out[ps.name] = list(v) if isinstance(v, tuple) else float(v)  # type: ignore[arg-type]
    if "int_ior" in out and model in RELATIVE_IOR:
        out["eta"] = out.pop("int_ior") / EXT_IOR
    if model == "ashikhmin_shirley" and "reflectivity" in out:
        eta, k = eta_k_from_reflectivity(out.pop("reflectivity"), out.pop("edge_tint"))
        out["eta"], out["k"] = [float(x) for x in eta], [float(x) for x in k]
    return out


def _blend_traverse(p: dict[str, Value]) -> dict[str, Any]:
    out: dict[str, Any] = {"weight": float(p["weight"])}  # type: ignore[arg-type]
    for slot in SLOTS:
        model, sub = component(slot, p)
        out.update({f"{slot}.{k}": v for k, v in traverse_values(model, MODELS[model], sub).items()})
    return out


def energy_notes(model: str, p: dict[str, Value]) -> list[str]:
    """What Mitsuba 0.5's energy-conservation safeguard does to these parameters, if anything."""
    if model not in ("ward", "phong", "ashikhmin_shirley_plastic") or p.get("ensure_energy_conservation") == "false":
        return []
    if model == "ashikhmin_shirley_plastic":
        pairs = [("specular_reflectance", p["specular_reflectance"], (0.0,) * 3),
                 ("diffuse_reflectance", p["diffuse_reflectance"], (0.0,) * 3)]
    else:
        pairs = [("specular_reflectance + diffuse_reflectance", p["specular_reflectance"], p["diffuse_reflectance"])]
    notes = []
    for label, a, b in pairs:
        s = trim_scale(a, b)
        if s < 1.0:
            peak = max(x + y for x, y in zip(a, b))  # type: ignore[arg-type]
            notes.append(f"{model} trims its reflectance: max({label}) = {peak:.3g} > 1, so the renderer scales "
                         f"it by {s:.3g} (Mitsuba 0.5's energy-conservation safeguard); any larger value renders "
                         "the same, so the fitted value is not the one that renders")
    return notes


ONE_SIDED = {"roughconductor", "conductor", "roughplastic", "plastic", "diffuse", "principled", "ward", "phong",
             "ashikhmin_shirley", "ashikhmin_shirley_plastic", "blendbsdf"}
"""Models Mitsuba shades on the front side only: written inside a `twosided` (a principled one
only without `spec_trans`: Mitsuba nests no transmissive BSDF there) (Blender's and
MaterialX's surfaces are two-sided; the probe sees front faces only, so the fit is the same)."""


def bitmap_file(tex: Texture) -> dict[str, Any]:
    """A texture file as Mitsuba's `bitmap`: an sRGB-encoded one decoded (raw false), a data map read as
    it is (raw true)."""
    return {"type": "bitmap", "filename": tex.file, "raw": tex.colorspace == ColourSpace.LINEAR,
            "filter_type": "nearest" if tex.filter == "nearest" else "bilinear"}


def textured_dict(model: str, p: dict[str, Value], textures: dict[str, dict[str, Any]]) -> dict[str, Any]:
    """The BSDF dictionary with these parameters' properties replaced by textures (each a
    property of the model's own name: `texturable` lists only those)."""
    d = bsdf_dict(model, p)
    for name, tex in textures.items():
        if name not in d:
            raise ConfigError(f"mitsuba {model}: {name} is not a texture input")
        d[name] = tex
    return d


def bsdf_xml(model: str, p: dict[str, Value], two_sided: bool = True,
             textures: dict[str, Texture] | None = None) -> str:
    """The material as a Mitsuba 3 XML ``<bsdf>`` element; an opaque one inside a ``twosided``;
    ``textures`` as `bitmap` textures of their (relative) file names."""
    d = textured_dict(model, p, {k: bitmap_file(t) for k, t in (textures or {}).items()})
    if two_sided and model in ONE_SIDED and not float(p.get("spec_trans", 0.0)) > 0.0:  # type: ignore[arg-type]
        d = {"type": "twosided", "bsdf": d}
    return "\n".join(_xml_element(d, None, "")) + "\n"


def _xml_element(d: dict[str, Any], name: str | None, indent: str) -> list[str]:
    named = f" name={quoteattr(name)}" if name else ""
    tag = "texture" if d["type"] == "bitmap" else "bsdf"
    lines = [f"{indent}<{tag} type={quoteattr(d['type'])}{named}>"]
    inner = indent + "    "
    for key, v in d.items():
        if key == "type":
            continue
        if isinstance(v, dict) and v.get("type") == "rgb":
            lines.append(f'{inner}<rgb name="{key}" value="{", ".join(f"{x:.6g}" for x in v["value"])}"/>')
        elif isinstance(v, dict):
            lines += _xml_element(v, key, inner)
        elif isinstance(v, bool):
            lines.append(f'{inner}<boolean name="{key}" value="{str(v).lower()}"/>')
        elif isinstance(v, str):
            lines.append(f'{inner}<string name="{key}" value={quoteattr(v)}/>')
        else:
            lines.append(f'{inner}<float name="{key}" value="{v:.6g}"/>')
    lines.append(f"{indent}</{tag}>")
    return lines


def _reraise_interrupt(exc: Exception) -> None:
    """Ctrl-C inside a Python plugin called from Mitsuba's C++ (or inside Dr.Jit's custom op that
    mi.render is) comes back as another error, with the interrupt in its text or its chain."""
    interrupt.check()  # a signal that came during the render: raised as itself (Ctrl-C, SIGTERM)
    seen: BaseException | None = exc
    for _ in range(8):
        if seen is None:
            break
        if isinstance(seen, KeyboardInterrupt) or "KeyboardInterrupt" in str(seen):
            raise KeyboardInterrupt from exc
        seen = seen.__cause__ or seen.__context__


def probe_transform(mi, scene: ProbeScene):
    """The probe sphere's placement, its pole along the image's up (+y): dp/du (an anisotropic
    BSDF's tangent) then runs along the latitudes, as the Cycles probe's tangent does."""
    s = scene.sphere
    return (mi.ScalarTransform4f().translate(list(s.center)) @ mi.ScalarTransform4f().rotate([1, 0, 0], -90.0)
            @ mi.ScalarTransform4f().scale(s.radius))


class MitsubaAdapter(Adapter):
    name = "mitsuba"
    version = "4"  # 2: the pole along +y; 3: environment rows as Mitsuba reads them, paths through glass; 4: glass tint per crossing
    summary = "Mitsuba 3, in process (llvm_ad_rgb when a working libLLVM is found, else scalar_rgb)"
    install_hint = "pip install 'brdf-remap[mitsuba]'"
    models = MODELS
    light_types = frozenset({"point", "environment"})
    calibration = ("diffuse", {"reflectance": 0.8})
    glasses = {"smooth": ("dielectric", {"int_ior": 1.5}),
               "rough": ("roughdielectric", {"distribution": "ggx", "alpha": 0.1, "int_ior": 1.5})}
    metals = {kind: ("roughconductor", {"material": "none", "distribution": "ggx", "alpha": a, "eta": (1.66, 0.88, 0.52),
                                        "k": (9.22, 6.27, 4.84)}) for kind, a in (("smooth", 0.01), ("rough", 0.09))}
    textures = True
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
        # Mitsuba logs to stdout, where a user's report goes (`remap ... | tee`): its warnings
        # ("sample count rounded up" at a high spp, hundreds in a sweep) are not ours to print there.
        mi.logger().set_log_level(mi.LogLevel.Error)
        try:
            register_bsdfs()
        except Exception as exc:
            raise RenderError(f"cannot register the ward/phong/ashikhmin_shirley plugins: {exc}") from exc
        # key -> (scene, traverse handle, parameter -> traverse key, values currently set)
        self._scenes: OrderedDict[tuple, tuple[Any, Any, dict[str, str], dict[str, Value]]] = OrderedDict()

    @classmethod
    def environment(cls) -> dict[str, Any]:
        import importlib.metadata

        return {"renderer": f"Mitsuba {importlib.metadata.version('mitsuba')}", **as_dict(choose_variant())}

    @classmethod
    def identity(cls) -> str:
        import importlib.metadata

        v = importlib.metadata.version
        return f"{cls.version} mitsuba-{v('mitsuba')} drjit-{v('drjit')} {choose_variant().variant}"

    def describe(self) -> dict[str, Any]:
        return {"renderer": f"Mitsuba {self.mi.__version__}", **as_dict(self.choice)}

    def scene_dict(self, model: str, params: dict[str, Value], scene: ProbeScene) -> dict[str, Any]:
        mi = self.mi
        cam = scene.camera
        return {
            "type": "scene",
            "integrator": integrator(scene, self.models[model].transmissive(params)),
            "sensor": {
                "type": "perspective", "fov": cam.fov, "fov_axis": "x",
                "to_world": mi.ScalarTransform4f().look_at(origin=list(cam.position), target=list(cam.target),
                                                           up=list(cam.up)),
                "film": {"type": "hdrfilm", "width": scene.resolution, "height": scene.resolution,
                         "rfilter": {"type": "box"}, "pixel_format": "rgb"},
                "sampler": {"type": "multijitter", "sample_count": scene.spp, "seed": scene.seed},
            },
            "probe": {"type": "sphere", "to_world": probe_transform(mi, scene),
                      "bsdf": bsdf_dict(model, params)},
            **emitters(scene, mi),
        }

    def _scene(self, model: str, params: dict[str, Value], scene: ProbeScene):
        spec = self.models[model]
        shared = model == "blendbsdf" and _same_slots(params)
        key = (model, tuple(params[p.name] for p in spec.parameters if p.kind == ParamKind.CHOICE), spec.transmissive(params),
               shared, scene.cache_key())
        if key in self._scenes:
            self._scenes.move_to_end(key)
            return self._scenes[key]
        try:
            sc = self.mi.load_dict(self.scene_dict(model, params, scene))
        except Exception as exc:
            _reraise_interrupt(exc)
            raise RenderError(f"mitsuba could not build the {model} scene: {exc}") from exc
        handle = self.mi.traverse(sc)
        keys = {}
        for tname in traverse_values(model, spec, params):
            # Mitsuba makes a blend's two identical BSDFs one object, under bsdf_0's name.
            same = tname.replace(f"{SLOTS[1]}.", f"{SLOTS[0]}.", 1) if shared else tname
            for cand in (f"probe.bsdf.{tname}.value", f"probe.bsdf.{tname}", f"probe.bsdf.{same}.value",
                         f"probe.bsdf.{same}"):
                if cand in handle:
                    keys[tname] = cand
                    break
            else:
                raise RenderError(f"mitsuba {model}: the BSDF exposes no parameter {tname!r} to update")
        self._scenes[key] = (sc, handle, keys, traverse_values(model, spec, params))
        if len(self._scenes) > self.max_scenes:
            self._scenes.popitem(last=False)
        return self._scenes[key]

    def render(self, model: str, params: dict[str, Value], scene: ProbeScene, lobe: str | None = None) -> np.ndarray:
        spec = self.models[model]
        p = spec.with_lobe(params, lobe)
        sc, handle, keys, current = self._scene(model, p, scene)
        changed = False
        for tname, v in traverse_values(model, spec, p).items():
            if current.get(tname) == v:
                continue
            handle[keys[tname]] = v
            current[tname] = v
            changed = True
        if changed:
            # Only when something moved: some BSDFs (roughplastic) redo costly set-up on update.
            handle.update()
        try:
            img = self.mi.render(sc, seed=scene.seed, spp=scene.spp)
        except Exception as exc:
            _reraise_interrupt(exc)
            raise RenderError(f"mitsuba render failed ({model}, {params}): {exc}") from exc
        return np.array(img, dtype=np.float32)[..., :3]

    def render_textured(self, model: str, params: dict[str, Value], maps: dict[str, TextureMap],
                        scene: ProbeScene) -> np.ndarray:
        """A scene of its own with `bitmap` textures of the values as they are (raw); not cached."""
        mi = self.mi
        bitmaps = {name: {"type": "bitmap", "raw": True, "wrap_mode": "repeat",
                          "filter_type": "nearest" if m.filter == "nearest" else "bilinear",
                          "bitmap": mi.Bitmap(np.ascontiguousarray(
                              m.values[..., None] if m.values.ndim == 2 else m.values, dtype=np.float32))}
                   for name, m in maps.items()}
        doc = self.scene_dict(model, params, scene)
        doc["probe"]["bsdf"] = textured_dict(model, params, bitmaps)
        try:
            img = mi.render(mi.load_dict(doc), seed=scene.seed, spp=scene.spp)
        except Exception as exc:
            _reraise_interrupt(exc)
            raise RenderError(f"mitsuba textured render failed ({model}, textures {sorted(maps)}): {exc}") from exc
        return np.array(img, dtype=np.float32)[..., :3]

    def derived(self, model: str, params: dict[str, Value]) -> dict[str, Value]:
        p = params
        if model in ("roughconductor", "conductor", "ashikhmin_shirley"):
            if p["material"] == "reflectivity":
                return {"reflectivity": p["reflectivity"], "edge_tint": p["edge_tint"]}
            eta, k = (p["eta"], p["k"]) if p["material"] == "none" else conductor_preset(str(p["material"]))
            r, g = reflectivity_edge_tint(eta, k)
            return {"reflectivity": as_rgb(r), "edge_tint": as_rgb(g)}
        if model in ("roughplastic", "plastic", "ashikhmin_shirley_plastic"):
            return {"specular_f0": dielectric_f0(float(p["int_ior"]) / EXT_IOR)}  # type: ignore[arg-type]
        if model in ("ward", "phong"):
            s = trim_scale(p["specular_reflectance"], p["diffuse_reflectance"]) \
                if p["ensure_energy_conservation"] == "true" else 1.0
            return {"energy_scale": s,
                    "effective_specular_reflectance": tuple(s * x for x in p["specular_reflectance"]),  # type: ignore
                    "effective_diffuse_reflectance": tuple(s * x for x in p["diffuse_reflectance"])}  # type: ignore
        return {}

    def appearance(self, model: str, params: dict[str, Value]) -> Appearance | None:
        if model == "blendbsdf":
            return blend_appearance(params, self.appearance)
        return _appearance.appearance(model, params, conductor_preset)

    def from_appearance(self, model: str, appearance: Appearance, base: dict[str, Value]) -> dict[str, Value]:
        return _appearance.from_appearance(model, appearance)

    def model_for(self, appearance: Appearance) -> ModelChoice:
        return ModelChoice(*_appearance.model_for(appearance))

    def alternatives(self, appearance: Appearance) -> list[ModelChoice]:
        return [ModelChoice(*x) for x in _appearance.alternatives(appearance)]

    def notes(self, model: str, params: dict[str, Value]) -> list[str]:
        return energy_notes(model, params)

    def write_native(self, model: str, params: dict[str, Value], out_dir: Path,
                     textures: dict[str, Texture] | None = None) -> list[Path]:
        text = f"<!-- brdf-remap: Mitsuba 3 {model} -->\n"
        if model in ("ward", "phong", "ashikhmin_shirley", "ashikhmin_shirley_plastic"):
            text += ("<!-- a Python plugin: call brdfremap.adapters.mitsuba.register_bsdfs() after "
                     "mitsuba.set_variant() before loading -->\n")
        text += bsdf_xml(model, params, textures=textures)
        return [write_text_atomic(Path(out_dir) / "material.xml", text)]

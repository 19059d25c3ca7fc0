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
from brdfremap.core.data.appearance import Appearance
from brdfremap.core.data.atomic import write_text_atomic
from brdfremap.core.data.errors import ConfigError, RenderError
from brdfremap.core.protocol import Adapter, ModelChoice
from brdfremap.core.data.scene import PointLight, ProbeScene
from brdfremap.core.data.schemas import Native, ParamKind, TRANSMISSION_DEPTH, Value
from brdfremap.core.data.textures import ColourSpace, Texture, TextureMap

from . import appearance as _appearance
from .blend import SLOTS
from .bsdfs import register_bsdfs
from .envmap import mitsuba_rows
from .model import MitsubaModel
from .models import MODELS
from .variant import as_dict, choose_variant


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


def model_of(model: MitsubaModel | str) -> MitsubaModel:
    """One of Mitsuba's models, by itself or by name (scripts name it)."""
    if isinstance(model, MitsubaModel):
        return model
    name = getattr(model, "name", model)
    if name not in MODELS:
        raise ConfigError(f"adapter 'mitsuba' has no model {name!r} (models: {', '.join(sorted(MODELS))})")
    return MODELS[name]


def bsdf_dict(model: MitsubaModel | str, p: dict[str, Value]) -> dict[str, Any]:
    """The Mitsuba BSDF dictionary of a model and its complete parameters."""
    return model_of(model).bsdf(p)


def bitmap_file(tex: Texture) -> dict[str, Any]:
    """A texture file as Mitsuba's `bitmap`: an sRGB-encoded one decoded (raw false), a data map read as
    it is (raw true)."""
    return {"type": "bitmap", "filename": tex.file, "raw": tex.colorspace == ColourSpace.LINEAR,
            "filter_type": "nearest" if tex.filter == "nearest" else "bilinear"}


def textured_dict(model: MitsubaModel, p: dict[str, Value], textures: dict[str, dict[str, Any]]) -> dict[str, Any]:
    """The BSDF dictionary with these parameters' properties replaced by textures (each a
    property of the model's own name: `texturable` lists only those)."""
    d = model.bsdf(p)
    for name, tex in textures.items():
        if name not in d:
            raise ConfigError(f"mitsuba {model.name}: {name} is not a texture input")
        d[name] = tex
    return d


def bsdf_xml(model: MitsubaModel | str, p: dict[str, Value], two_sided: bool = True,
             textures: dict[str, Texture] | None = None) -> str:
    """The material as a Mitsuba 3 XML ``<bsdf>`` element; an opaque one inside a ``twosided``
    (`MitsubaModel.wrapped`); ``textures`` as `bitmap` textures of their (relative) file names."""
    model = model_of(model)
    d = textured_dict(model, p, {k: bitmap_file(t) for k, t in (textures or {}).items()})
    if two_sided and model.wrapped(p):
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
    mirror = ("conductor", {"material": "none", "eta": 0.0, "k": 10.0})  # an imaginary IOR: |r| = 1 at every angle
    textures = True
    natives = True
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

    def scene_dict(self, model: MitsubaModel | str, params: dict[str, Value], scene: ProbeScene) -> dict[str, Any]:
        mi, model = self.mi, model_of(model)
        cam = scene.camera
        return {
            "type": "scene",
            "integrator": integrator(scene, model.transmissive(params)),
            "sensor": {
                "type": "perspective", "fov": cam.fov, "fov_axis": "x",
                "to_world": mi.ScalarTransform4f().look_at(origin=list(cam.position), target=list(cam.target),
                                                           up=list(cam.up)),
                "film": {"type": "hdrfilm", "width": scene.resolution, "height": scene.resolution,
                         "rfilter": {"type": "box"}, "pixel_format": "rgb"},
                "sampler": {"type": "multijitter", "sample_count": scene.spp, "seed": scene.seed},
            },
            "probe": {"type": "sphere", "to_world": probe_transform(mi, scene),
                      "bsdf": model.bsdf(params)},
            **emitters(scene, mi),
        }

    def _scene(self, model: MitsubaModel, params: dict[str, Value], scene: ProbeScene):
        shared = model.shared(params)
        key = (model.name, tuple(params[p.name] for p in model.parameters if p.kind == ParamKind.CHOICE),
               model.transmissive(params), shared, scene.cache_key())
        if key in self._scenes:
            self._scenes.move_to_end(key)
            return self._scenes[key]
        try:
            sc = self.mi.load_dict(self.scene_dict(model, params, scene))
        except Exception as exc:
            _reraise_interrupt(exc)
            raise RenderError(f"mitsuba could not build the {model.name} scene: {exc}") from exc
        handle = self.mi.traverse(sc)
        keys = {}
        for tname in model.traverse(params):
            # Mitsuba makes a blend's two identical BSDFs one object, under bsdf_0's name.
            same = tname.replace(f"{SLOTS[1]}.", f"{SLOTS[0]}.", 1) if shared else tname
            for cand in (f"probe.bsdf.{tname}.value", f"probe.bsdf.{tname}", f"probe.bsdf.{same}.value",
                         f"probe.bsdf.{same}"):
                if cand in handle:
                    keys[tname] = cand
                    break
            else:
                raise RenderError(f"mitsuba {model.name}: the BSDF exposes no parameter {tname!r} to update")
        self._scenes[key] = (sc, handle, keys, model.traverse(params))
        if len(self._scenes) > self.max_scenes:
            self._scenes.popitem(last=False)
        return self._scenes[key]

    def render(self, model: MitsubaModel | str, params: dict[str, Value], scene: ProbeScene,
               lobe: str | None = None) -> np.ndarray:
        model = model_of(model)
        p = model.with_lobe(params, lobe)
        sc, handle, keys, current = self._scene(model, p, scene)
        changed = False
        for tname, v in model.traverse(p).items():
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
            raise RenderError(f"mitsuba render failed ({model.name}, {params}): {exc}") from exc
        return np.array(img, dtype=np.float32)[..., :3]

    def render_textured(self, model: MitsubaModel | str, params: dict[str, Value], maps: dict[str, TextureMap],
                        scene: ProbeScene) -> np.ndarray:
        """A scene of its own with `bitmap` textures of the values as they are (raw); not cached."""
        mi, model = self.mi, model_of(model)
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
            raise RenderError(f"mitsuba textured render failed ({model.name}, textures {sorted(maps)}): {exc}") from exc
        return np.array(img, dtype=np.float32)[..., :3]

    def render_native(self, native: Native, scene: ProbeScene, lobe: str | None = None,
                      transmissive: bool = False) -> np.ndarray:
        """A BSDF as its scene file writes it (`Native.element`, loaded by Mitsuba as it is), on the probe
        sphere. A lobe of it cannot be told apart (a RenderError): its fit is one stage."""
        mi = self.mi
        if lobe is not None:
            raise RenderError(f"mitsuba: a BSDF rendered as written has no {lobe} lobe of its own to render")
        key = ("native", native.sha256, transmissive, scene.cache_key())
        if key not in self._scenes:
            from .reader import check_element

            check_element(native.element, native.file)  # a plugin is loaded by its type's file name
            try:
                bsdf = mi.load_string(native.element)
                doc = self.scene_dict("diffuse", model_of("diffuse").complete({}), scene)
                doc["integrator"] = integrator(scene, transmissive)
                doc["probe"]["bsdf"] = bsdf
                self._scenes[key] = (mi.load_dict(doc), None, {}, {})
            except Exception as exc:
                _reraise_interrupt(exc)
                raise RenderError(f"mitsuba could not load {native.name!r} of {native.file} as written: "
                                  f"{str(exc).splitlines()[0] if str(exc) else type(exc).__name__}") from exc
            if len(self._scenes) > self.max_scenes:
                self._scenes.popitem(last=False)
        self._scenes.move_to_end(key)
        try:
            img = mi.render(self._scenes[key][0], seed=scene.seed, spp=scene.spp)
        except Exception as exc:
            _reraise_interrupt(exc)
            raise RenderError(f"mitsuba render of {native.name!r} as written failed: {exc}") from exc
        return np.array(img, dtype=np.float32)[..., :3]

    def candidates(self) -> list[ModelChoice]:
        return [ModelChoice("principled", {}, "no reading: Mitsuba's principled BSDF, its most general model"),
                ModelChoice("roughconductor", {"material": "none"}, "no reading: a rough conductor"),
                ModelChoice("roughplastic", {}, "no reading: a rough plastic")]

    def model_for(self, appearance: Appearance) -> ModelChoice:
        return ModelChoice(*_appearance.model_for(appearance))

    def alternatives(self, appearance: Appearance) -> list[ModelChoice]:
        return [ModelChoice(*x) for x in _appearance.alternatives(appearance)]

    def write_native(self, model: MitsubaModel | str, params: dict[str, Value], out_dir: Path,
                     textures: dict[str, Texture] | None = None) -> list[Path]:
        model = model_of(model)
        text = f"<!-- brdf-remap: Mitsuba 3 {model.name} -->\n"
        if model.plugin:
            text += ("<!-- a Python plugin: call brdfremap.adapters.mitsuba.register_bsdfs() after "
                     "mitsuba.set_variant() before loading -->\n")
        text += bsdf_xml(model, params, textures=textures)
        return [write_text_atomic(Path(out_dir) / "material.xml", text)]

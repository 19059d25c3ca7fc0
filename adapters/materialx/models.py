"""The MaterialX adapter's models: each surface shader MaterialX ships that users write, one `Model` built
from its nodedef in MaterialX's standard libraries (`nodedefs`: its inputs, defaults and ranges), with
what the tool adds by hand: which inputs a fit varies, its neutral reading and converted start (through
the correspondence to Blender's Principled BSDF, `correspondence`), the fixed rule an importer applies,
and what MaterialX's real-time GLSL renders of it only approximately.

A model's native form is a MaterialX document: its shader node and a material (`document`). The
renderer generates and compiles one program per model from a document of the defaults
(`program_document`) and sets a render's values as that program's uniforms (`uniforms`)."""

from __future__ import annotations

import functools
from collections.abc import Iterator, Mapping
from typing import Any, Callable, ClassVar

from brdfremap.core.data.appearance import Appearance
from brdfremap.core.data.schemas import Need, ParamKind, Value
from brdfremap.core.host.model import Model, Rule

from .correspondence import as_they_are, from_principled, principled_values

SHADER = "brdfremap_shader"
"""The shader node's name in the documents the adapter renders: its inputs' uniforms are
``brdfremap_shader_<input>``."""
GLASS = {"transmission_weight": 1.0}


def _principled():
    from brdfremap.adapters.cycles.models import PRINCIPLED

    return PRINCIPLED


def _clipped(spec, values: dict[str, Any]) -> dict[str, Value]:
    out = {}
    for name, v in values.items():
        p = spec.param(name)
        out[name] = p.clip(tuple(v) if isinstance(v, (list, tuple)) else v)
    return out


def mx_type(kind: ParamKind, choices: tuple[str, ...]) -> str:
    """The MaterialX type of a parameter (`nodedefs`: floats, colours, booleans, integers)."""
    if kind == ParamKind.RGB:
        return "color3"
    if kind == ParamKind.SCALAR:
        return "float"
    return "boolean" if choices == ("false", "true") else "integer"


def value_string(v: Value) -> str:
    if isinstance(v, tuple):
        return ", ".join(f"{float(x):.9g}" for x in v)
    return v if isinstance(v, str) else f"{float(v):.9g}"


class MaterialXModel(Model):
    """A MaterialX surface shader as a model (see the module)."""

    category: ClassVar[str] = ""
    """The shader's node (`open_pbr_surface`)."""
    nodedef: ClassVar[str] = ""
    flags: ClassVar[dict[str, dict[str, Any]]] = {}
    """What the tool says of its inputs beyond the nodedef: fitted (`fit`), fitted where the source
    carries one (`fit_when_carried`), for a need (`fit_for`), inert, held (`ParamSpec`'s fields)."""
    approximated: ClassVar[dict[str, tuple[Callable[[Value], bool], str]]] = {}
    """Inputs whose values MaterialX's GLSL renders only approximately: which values, and how."""

    @classmethod
    def build(cls, library) -> "MaterialXModel":
        """The model from its nodedef in ``library`` (MaterialX's standard libraries)."""
        from .nodedefs import parameters

        nodedef = library.getNodeDef(cls.nodedef)
        if nodedef is None:
            raise ValueError(f"MaterialX's libraries have no {cls.nodedef}")
        specs = parameters(nodedef, cls.flags)
        return cls(name=cls.category, parameters=specs, **cls.extra(),
                   description=f"MaterialX {cls.category} ({nodedef.getVersionString() or 'its'} nodedef "
                               f"{cls.nodedef}) as MaterialX's own GLSL renders it")

    @classmethod
    def extra(cls) -> dict[str, Any]:
        """The ModelSpec fields beyond the parameters (smooth_when, transmits_with)."""
        return {}

    # -- its native form --------------------------------------------------------------------
    def uniforms(self, params: dict[str, Value]) -> dict[str, list[str]]:
        """Each parameter as the renderer's uniform of that input: [MaterialX type, value]."""
        return {p.name: [mx_type(p.kind, p.choices), value_string(params[p.name])] for p in self.parameters
                if p.name in params}

    def program_document(self) -> str:
        """A document of this shader at its defaults: what the renderer compiles once."""
        return _document(self.category, {}, SHADER, self.uniforms)

    def document(self, params: dict[str, Value], name: str = "brdfremap") -> str:
        """The material as a MaterialX document: its shader node, every input away from its default."""
        given = {k: v for k, v in params.items() if v != self.param(k).default}
        return _document(self.category, given, f"{name}_shader", self.uniforms, material=name)

    # -- conversions ---------------------------------------------------------------------------
    def principled(self, params: dict[str, Value]) -> dict[str, Value]:
        """Blender's Principled BSDF values of these parameters by the correspondence, within its bounds (the
        Principled BSDF's defaults for what the correspondence does not map)."""
        return _principled().complete(self._mapped(params)[0])

    def _mapped(self, params: dict[str, Value]) -> tuple[dict[str, Value], list[str]]:
        """The Principled values the correspondence maps, clipped to its bounds, and this material's
        inputs away from their defaults it has no counterpart for."""
        values, loose = principled_values(self.category, params)
        return _clipped(_principled(), values), [n for n in loose if n in self.names and params[n] != self.param(n).default]

    def appearance(self, params: dict[str, Value]) -> Appearance:
        """As Blender's Principled BSDF of the correspondence reads (a MaterialX metal: Schlick's Fresnel
        from its colour, with an F82 tint; every lobe's energy kept, as MaterialX's GLSL compensates it)."""
        return _principled().appearance(self.principled(params))

    def from_appearance(self, appearance: Appearance, base: dict[str, Value]) -> dict[str, Value]:
        spec = _principled()
        values = spec.from_appearance(appearance, spec.complete({}))
        return from_principled(self.category, {k: v for k, v in values.items() if k in spec.names and k != "distribution"})

    def rule_for(self, target: Model, params: dict[str, Value]) -> Rule | None:
        """Blender's Principled BSDF by the correspondence: the values Blender's MaterialX importer and
        exporter map by name (only those: the rest stays the fit's), and the inputs it has no name for."""
        from brdfremap.adapters.cycles.models import Principled

        if not isinstance(target, Principled):
            return None
        values, loose = self._mapped(params)
        unmapped = f"; not mapped: {', '.join(loose)}" if loose else ""
        return Rule(name=f"MaterialX's {self.category} to Blender's Principled BSDF by name (docs/materialx.md)"
                         + unmapped, params=values, inputs=as_they_are(self.category, params))

    def approximations(self, params: dict[str, Value]) -> list[str]:
        return [why for name, (drawn, why) in self.approximated.items() if name in params and drawn(params[name])]


def _document(category: str, params: dict[str, Value], shader_name: str, uniforms, material: str = "brdfremap") -> str:
    from .mxlib import mx

    m = mx()
    doc = m.createDocument()
    shader = doc.addNode(category, shader_name, "surfaceshader")
    for name, (kind, text) in uniforms(params).items():
        shader.addInput(name, kind).setValueString(text)
    doc.addMaterialNode(material, shader)
    return m.writeToXmlString(doc)


TRANSMISSION = ("MaterialX's GLSL draws transmission as the environment refracted once through the sphere "
                "(mx_surface_transmission): a point light is not seen through it")


def _positive(v: Value) -> bool:
    return max(v) > 0.0 if isinstance(v, tuple) else float(v) > 0.0  # type: ignore[arg-type]


def _below_one(v: Value) -> bool:
    return min(v) < 1.0 if isinstance(v, tuple) else float(v) < 1.0  # type: ignore[arg-type]


SUBSURFACE = (_positive, "MaterialX's GLSL draws subsurface scattering as a wrapped diffuse of its colour and radius "
                         "(mx_subsurface_scattering_approx): no light travels under the surface")
TRANSMITS = (_positive, TRANSMISSION)
OPAQUE = (_below_one, "MaterialX's GLSL renders here without transparency (its program is made once, opaque): a "
                      "coverage below 1 is drawn opaque")

# --------------------------------------------------------------------------------------- the models
_CARRIED = {"fit_when_carried": True}


class OpenPbr(MaterialXModel):
    """OpenPBR Surface."""

    category = "open_pbr_surface"
    nodedef = "ND_open_pbr_surface_surfaceshader"
    flags = {"base_color": {"fit": True, "held_when": GLASS}, "base_metalness": {"fit": True, "held_when": GLASS},
             "specular_roughness": {"fit": True}, "specular_weight": {"fit": True},
             "specular_ior": {"fit_when": GLASS}, "specular_color": {"fit_for": (Need.EDGE_TINT,)},
             "specular_roughness_anisotropy": _CARRIED, "coat_weight": _CARRIED,
             "coat_roughness": {**_CARRIED, "inert_when": {"coat_weight": 0.0}},
             "coat_ior": {"inert_when": {"coat_weight": 0.0}}, "coat_color": {"inert_when": {"coat_weight": 0.0}},
             "fuzz_weight": _CARRIED, "fuzz_roughness": {**_CARRIED, "inert_when": {"fuzz_weight": 0.0}},
             "fuzz_color": {"inert_when": {"fuzz_weight": 0.0}},
             "base_diffuse_roughness": {"fit_for": (Need.ROUGH_DIFFUSE,)}}
    approximated = {"subsurface_weight": SUBSURFACE, "transmission_weight": TRANSMITS, "geometry_opacity": OPAQUE}

    @classmethod
    def extra(cls) -> dict[str, Any]:
        return {"smooth_when": {"specular_roughness": 0.0}, "transmits_with": "transmission_weight"}


class StandardSurface(MaterialXModel):
    """Autodesk Standard Surface."""

    category = "standard_surface"
    nodedef = "ND_standard_surface_surfaceshader"
    flags = {"base_color": {"fit": True, "held_when": {"transmission": 1.0}},
             "metalness": {"fit": True, "held_when": {"transmission": 1.0}},
             "specular_roughness": {"fit": True}, "specular": {"fit": True},
             "specular_IOR": {"fit_when": {"transmission": 1.0}}, "specular_color": {"fit_for": (Need.EDGE_TINT,)},
             "specular_anisotropy": _CARRIED, "specular_rotation": {**_CARRIED, "inert_when": {"specular_anisotropy": 0.0}},
             "coat": _CARRIED, "coat_roughness": {**_CARRIED, "inert_when": {"coat": 0.0}},
             "coat_IOR": {"inert_when": {"coat": 0.0}}, "coat_color": {"inert_when": {"coat": 0.0}},
             "sheen": _CARRIED, "sheen_roughness": {**_CARRIED, "inert_when": {"sheen": 0.0}},
             "sheen_color": {"inert_when": {"sheen": 0.0}},
             "diffuse_roughness": {"fit_for": (Need.ROUGH_DIFFUSE,)}}
    approximated = {"subsurface": SUBSURFACE, "transmission": TRANSMITS, "opacity": OPAQUE}

    @classmethod
    def extra(cls) -> dict[str, Any]:
        return {"smooth_when": {"specular_roughness": 0.0}, "transmits_with": "transmission"}


class GltfPbr(MaterialXModel):
    """glTF's metallic-roughness material as MaterialX defines it."""

    category = "gltf_pbr"
    nodedef = "ND_gltf_pbr_surfaceshader"
    flags = {"base_color": {"fit": True, "held_when": {"transmission": 1.0}},
             "metallic": {"fit": True, "held_when": {"transmission": 1.0}}, "roughness": {"fit": True},
             "ior": {"fit_when": {"transmission": 1.0}, "inert_when": {"metallic": 1.0}},
             "clearcoat": _CARRIED, "clearcoat_roughness": {**_CARRIED, "inert_when": {"clearcoat": 0.0}},
             "anisotropy_strength": _CARRIED,
             "anisotropy_rotation": {**_CARRIED, "inert_when": {"anisotropy_strength": 0.0}}}
    approximated = {"transmission": TRANSMITS, "alpha": OPAQUE}

    @classmethod
    def extra(cls) -> dict[str, Any]:
        return {"smooth_when": {"roughness": 0.0}, "transmits_with": "transmission"}


class UsdPreview(MaterialXModel):
    """USD's UsdPreviewSurface as MaterialX defines it."""

    category = "UsdPreviewSurface"
    nodedef = "ND_UsdPreviewSurface_surfaceshader"
    flags = {"diffuseColor": {"fit": True}, "metallic": {"fit": True}, "roughness": {"fit": True},
             "clearcoat": _CARRIED, "clearcoatRoughness": {**_CARRIED, "inert_when": {"clearcoat": 0.0}}}
    approximated = {"opacity": OPAQUE}

    @classmethod
    def extra(cls) -> dict[str, Any]:
        return {"smooth_when": {"roughness": 0.0}}


class DisneyPrincipled(MaterialXModel):
    """Disney's principled BSDF (Burley 2012) as MaterialX defines it."""

    category = "disney_principled"
    nodedef = "ND_disney_principled"
    flags = {"baseColor": {"fit": True}, "metallic": {"fit": True}, "roughness": {"fit": True},
             "specular": {"fit": True, "inert_when": {"metallic": 1.0}}, "anisotropic": _CARRIED,
             "sheen": _CARRIED, "clearcoat": _CARRIED, "clearcoatGloss": {**_CARRIED, "inert_when": {"clearcoat": 0.0}}}
    approximated = {"specTrans": TRANSMITS}

    @classmethod
    def extra(cls) -> dict[str, Any]:
        return {"smooth_when": {"roughness": 0.0}, "transmits_with": "specTrans"}


KINDS: tuple[type[MaterialXModel], ...] = (OpenPbr, StandardSurface, GltfPbr, UsdPreview, DisneyPrincipled)


class Models(Mapping):
    """The adapter's models by name, built from MaterialX's libraries the first time they are asked for
    (reading the nodedefs takes MaterialX and a fraction of a second: `remap --help` needs neither);
    none where the materialx package is missing (the adapter then says why it is unavailable), and
    only those whose nodedef the installed libraries have."""

    @functools.cached_property
    def _models(self) -> dict[str, MaterialXModel]:
        from brdfremap.core.data.errors import ConfigError

        from .mxlib import standard_libraries

        try:
            library = standard_libraries()
        except ConfigError:  # no materialx package: `MaterialXAdapter.unavailable_reason` says so
            return {}
        return {kind.category: kind.build(library) for kind in KINDS if library.getNodeDef(kind.nodedef) is not None}

    def __getitem__(self, name: str) -> MaterialXModel:
        return self._models[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._models)

    def __len__(self) -> int:
        return len(self._models)


MODELS = Models()


def model_of_category(category: str) -> MaterialXModel | None:
    """The model of a shader node's category (`open_pbr_surface`), or None."""
    return MODELS.get(category)

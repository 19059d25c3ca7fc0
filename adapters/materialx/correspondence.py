"""How MaterialX's surface shaders correspond to Blender's Principled BSDF (the `cycles` adapter's
`principled` model), both ways: the fixed rule an exporter applies (Blender's own MaterialX
export maps by these names). Data and arithmetic on parameter dictionaries, no MaterialX import.

Used three ways, none of them to render a MaterialX material (MaterialX renders its own,
`adapters/materialx/adapter.py`): a material's neutral reading (Principled's, through this table),
the fixed rule's values that a remap to Principled starts from and is compared with, and the
converted start of a fit to a MaterialX shader (the other direction).

Blender's Principled BSDF follows OpenPBR: the same base colour and metalness, roughness
(α = roughness² in both), specular IOR; Blender's Specular IOR Level is 0.5 for the IOR as given,
where OpenPBR's specular weight is 1, so level = weight / 2. Autodesk Standard Surface, glTF PBR,
UsdPreviewSurface and Disney's principled map the same way by their own names. Coat, sheen
(OpenPBR's fuzz), anisotropy, transmission, subsurface weight and diffuse roughness map by name:
the lobes' models differ in detail (OpenPBR's fuzz is not Blender's microfiber sheen; its roughness
anisotropy is not Disney's), which is what a fit between renderers measures."""

from __future__ import annotations

from typing import Any

# shader category -> {principled parameter: (shader input, its weight)}; a colour may be the
# product of two inputs (a colour and a weight).
TO_PRINCIPLED: dict[str, dict[str, tuple[str, ...]]] = {
    "open_pbr_surface": {"base_color": ("base_color", "base_weight"), "metallic": ("base_metalness",),
                         "roughness": ("specular_roughness",), "ior": ("specular_ior",),
                         "specular_ior_level": ("specular_weight",), "specular_tint": ("specular_color",),
                         "coat_weight": ("coat_weight",), "coat_roughness": ("coat_roughness",),
                         "coat_ior": ("coat_ior",), "coat_tint": ("coat_color",), "sheen_weight": ("fuzz_weight",),
                         "sheen_tint": ("fuzz_color",), "sheen_roughness": ("fuzz_roughness",),
                         "anisotropic": ("specular_roughness_anisotropy",),
                         "transmission_weight": ("transmission_weight",), "subsurface_weight": ("subsurface_weight",),
                         "subsurface_radius": ("subsurface_radius_scale",), "subsurface_scale": ("subsurface_radius",),
                         "subsurface_anisotropy": ("subsurface_scatter_anisotropy",),
                         "thin_film_thickness": ("thin_film_thickness",), "thin_film_ior": ("thin_film_ior",),
                         "diffuse_roughness": ("base_diffuse_roughness",)},
    "standard_surface": {"base_color": ("base_color", "base"), "metallic": ("metalness",),
                         "roughness": ("specular_roughness",), "ior": ("specular_IOR",),
                         "specular_ior_level": ("specular",), "specular_tint": ("specular_color",),
                         "coat_weight": ("coat",), "coat_roughness": ("coat_roughness",),
                         "coat_ior": ("coat_IOR",), "coat_tint": ("coat_color",), "sheen_weight": ("sheen",),
                         "sheen_tint": ("sheen_color",), "sheen_roughness": ("sheen_roughness",),
                         "anisotropic": ("specular_anisotropy",), "anisotropic_rotation": ("specular_rotation",),
                         "transmission_weight": ("transmission",), "subsurface_weight": ("subsurface",),
                         "subsurface_radius": ("subsurface_radius",), "subsurface_scale": ("subsurface_scale",),
                         "subsurface_anisotropy": ("subsurface_anisotropy",),
                         "thin_film_thickness": ("thin_film_thickness",), "thin_film_ior": ("thin_film_IOR",),
                         "diffuse_roughness": ("diffuse_roughness",)},
    "gltf_pbr": {"base_color": ("base_color",), "metallic": ("metallic",), "roughness": ("roughness",),
                 "ior": ("ior",), "specular_ior_level": ("specular",), "specular_tint": ("specular_color",),
                 "coat_weight": ("clearcoat",), "coat_roughness": ("clearcoat_roughness",),
                 "transmission_weight": ("transmission",)},
    "UsdPreviewSurface": {"base_color": ("diffuseColor",), "metallic": ("metallic",), "roughness": ("roughness",),
                          "ior": ("ior",), "coat_weight": ("clearcoat",), "coat_roughness": ("clearcoatRoughness",)},
    "disney_principled": {"base_color": ("baseColor",), "metallic": ("metallic",), "roughness": ("roughness",),
                          "ior": ("ior",), "specular_ior_level": ("specular",), "anisotropic": ("anisotropic",),
                          "sheen_weight": ("sheen",), "coat_weight": ("clearcoat",),
                          "coat_roughness": ("clearcoatGloss",), "transmission_weight": ("specTrans",)},
}
TRANSMISSION_TINT = {"open_pbr_surface": "transmission_color", "standard_surface": "transmission_color"}
"""Shaders whose transmitted light has a colour of its own: Blender's Principled BSDF tints it by
Base Color, so a glass's Base Color is this colour (mixed with the base colour by the
transmission weight). glTF and UsdPreviewSurface tint it by the base colour, as Blender does."""
SUBSURFACE_TINT = {"open_pbr_surface": "subsurface_color", "standard_surface": "subsurface_color"}
"""Shaders whose subsurface scattering has a colour of its own: Blender's Principled BSDF scatters Base
Color, mixed here with this colour by the subsurface weight, as a glass's by its transmission."""
GATED = {"open_pbr_surface": {"thin_film_thickness": "thin_film_weight"}}
"""A Principled parameter that is the shader's value only while another input of the shader is
positive (OpenPBR's thin film has a weight; Blender's is off at thickness 0)."""
SCALE: dict[str, dict[str, float]] = {
    "open_pbr_surface": {"specular_ior_level": 0.5, "anisotropic": 1.0 / 0.9, "thin_film_thickness": 1000.0},
    "standard_surface": {"specular_ior_level": 0.5, "anisotropic": 1.0 / 0.9},
    "gltf_pbr": {"specular_ior_level": 0.5},
}
"""Principled parameters that are the shader's value times this: Specular IOR Level 0.5 is a weight
of 1; MaterialX's roughness anisotropy a makes the axes' α ratio 1 − a (mx_roughness_anisotropy;
OpenPBR's alike), Disney's (Blender's) 1 − 0.9 a; OpenPBR's thin film is in micrometres, Blender's in
nanometres. Disney's specular 0.5 is F0 4 %, Blender's level
0.5 at IOR 1.5 the same: as it is."""
ONE_MINUS = {"disney_principled": {"coat_roughness"}}
"""Principled parameters that are one minus the shader's value (Disney's clearcoat gloss)."""
QUIET = {"normal", "tangent", "geometry_normal", "geometry_coat_normal", "geometry_tangent", "geometry_coat_tangent",
         "coat_normal", "clearcoat_normal", "alpha_mode", "alpha_cutoff", "opacityMode", "opacityThreshold",
         "displacement", "occlusion"}
"""Inputs that say nothing about a sphere's reflectance (geometry, alpha modes): never listed."""


def principled_values(category: str, params: dict[str, Any]) -> tuple[dict[str, Any], list[str]]:
    """The fixed rule: a shader's complete parameters as the Principled BSDF values it maps (unclipped),
    and the shader's inputs it has no counterpart for (the caller says those away from their defaults)."""
    table = TO_PRINCIPLED[category]
    scale, inverted = SCALE.get(category, {}), ONE_MINUS.get(category, set())
    out: dict[str, Any] = {}
    for pname, names in table.items():
        v = params[names[0]]
        if len(names) == 2:  # a colour times its weight
            v = tuple(c * float(params[names[1]]) for c in v)
        if pname in inverted:
            v = 1.0 - float(v)
        gate = GATED.get(category, {}).get(pname)
        if gate is not None and float(params[gate]) <= 0.0:
            v = 0.0
        out[pname] = v * scale[pname] if pname in scale else v
    for tints, weight in ((TRANSMISSION_TINT, "transmission_weight"), (SUBSURFACE_TINT, "subsurface_weight")):
        # Blender's Principled BSDF transmits and scatters Base Color; these shaders a colour of their own.
        tint, w = tints.get(category), float(out.get(weight, 0.0))
        if tint is not None and w > 0.0:
            out["base_color"] = tuple((1 - w) * b + w * t for b, t in zip(out["base_color"], params[tint]))
    return out, [name for name in params if name not in _used(category) and name not in QUIET]


def as_they_are(category: str, params: dict[str, Any]) -> dict[str, str]:
    """The Principled parameters that are one input of the shader as it is (no weight other than 1, no
    scale, no inversion, no gate, a base colour no transmission or subsurface tint mixes into): Principled's
    name, the shader's."""
    tinted = any(float(params.get(TO_PRINCIPLED[category].get(w, ("",))[0], 0.0)) > 0.0 and tints.get(category)
                 for tints, w in ((TRANSMISSION_TINT, "transmission_weight"), (SUBSURFACE_TINT, "subsurface_weight")))
    out = {}
    for pname, names in TO_PRINCIPLED[category].items():
        if pname in SCALE.get(category, {}) or pname in ONE_MINUS.get(category, set()) \
                or pname in GATED.get(category, {}) or (pname == "base_color" and tinted):
            continue
        if len(names) == 1 or float(params.get(names[1], 0.0)) == 1.0:
            out[pname] = names[0]
    return out


def _used(category: str) -> set[str]:
    names = {n for names in TO_PRINCIPLED[category].values() for n in names}
    extra = {TRANSMISSION_TINT.get(category), SUBSURFACE_TINT.get(category), *GATED.get(category, {}).values()}
    return names | (extra - {None})


def from_principled(category: str, principled: dict[str, Any]) -> dict[str, Any]:
    """A Principled BSDF's values as this shader's inputs (the rule's other direction): each input
    the table names, its weight 1 where a colour has one."""
    scale, inverted = SCALE.get(category, {}), ONE_MINUS.get(category, set())
    out: dict[str, Any] = {}
    for pname, names in TO_PRINCIPLED[category].items():
        if pname not in principled:
            continue
        v = principled[pname]
        if pname in scale:
            v = v / scale[pname]
        if pname in inverted:
            v = 1.0 - float(v)
        out[names[0]] = tuple(v) if isinstance(v, (list, tuple)) else v
        if len(names) == 2:
            out[names[1]] = 1.0
        gate = GATED.get(category, {}).get(pname)
        if gate is not None:
            out[gate] = 1.0 if float(v) > 0.0 else 0.0
    tint = TRANSMISSION_TINT.get(category)
    if tint is not None and float(principled.get("transmission_weight", 0.0)) > 0.0:
        out[tint] = tuple(principled["base_color"])  # what Blender tints a glass by
    return out


def open_pbr_inputs(params: dict) -> dict[str, object]:
    """A Principled BSDF's values as open_pbr_surface inputs (the writer's direction), every input the
    table names."""
    return from_principled("open_pbr_surface", params)


DIRECT = as_they_are("open_pbr_surface", {"base_weight": 1.0})
"""Principled parameters that are one open_pbr_surface input as they are (an image can drive it
directly; base_weight stays 1)."""

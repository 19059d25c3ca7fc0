"""How MaterialX's surface shaders correspond to Blender's Principled BSDF (the `cycles`
adapter's `principled` model), both ways. Data, no MaterialX import.

Blender's Principled BSDF follows OpenPBR: the same base colour and metalness, roughness
(α = roughness² in both), specular IOR; Blender's Specular IOR Level is 0.5 for the IOR as
given, where OpenPBR's specular weight is 1, so level = weight / 2. Autodesk Standard Surface,
glTF PBR and UsdPreviewSurface map the same way by their own names. A shader input with no
counterpart is listed per material when it is away from its default. Coat (IOR, colour),
sheen (OpenPBR's fuzz), anisotropy, transmission, subsurface weight and diffuse roughness map by
name, as Blender's own MaterialX export maps them: the lobes' models differ in detail (OpenPBR's
fuzz is not Blender's microfiber sheen; its roughness anisotropy is not Disney's), which a fit
between renderers would measure. OpenPBR has no anisotropy rotation (a tangent input instead)."""

from __future__ import annotations

# shader category -> {principled parameter: (shader input, scale)}; base colour may be the
# product of two inputs (a weight and a colour).
TO_PRINCIPLED: dict[str, dict[str, tuple[str, ...]]] = {
    "open_pbr_surface": {"base_color": ("base_color", "base_weight"), "metallic": ("base_metalness",),
                         "roughness": ("specular_roughness",), "ior": ("specular_ior",),
                         "specular_ior_level": ("specular_weight",), "specular_tint": ("specular_color",),
                         "coat_weight": ("coat_weight",), "coat_roughness": ("coat_roughness",),
                         "coat_ior": ("coat_ior",), "coat_tint": ("coat_color",), "sheen_weight": ("fuzz_weight",),
                         "sheen_tint": ("fuzz_color",), "sheen_roughness": ("fuzz_roughness",),
                         "anisotropic": ("specular_roughness_anisotropy",),
                         "transmission_weight": ("transmission_weight",), "subsurface_weight": ("subsurface_weight",),
                         "diffuse_roughness": ("base_diffuse_roughness",)},
    "standard_surface": {"base_color": ("base_color", "base"), "metallic": ("metalness",),
                         "roughness": ("specular_roughness",), "ior": ("specular_IOR",),
                         "specular_ior_level": ("specular",), "specular_tint": ("specular_color",),
                         "coat_weight": ("coat",), "coat_roughness": ("coat_roughness",),
                         "coat_ior": ("coat_IOR",), "coat_tint": ("coat_color",), "sheen_weight": ("sheen",),
                         "sheen_tint": ("sheen_color",), "sheen_roughness": ("sheen_roughness",),
                         "anisotropic": ("specular_anisotropy",), "anisotropic_rotation": ("specular_rotation",),
                         "transmission_weight": ("transmission",), "subsurface_weight": ("subsurface",),
                         "diffuse_roughness": ("diffuse_roughness",)},
    "gltf_pbr": {"base_color": ("base_color",), "metallic": ("metallic",), "roughness": ("roughness",),
                 "ior": ("ior",), "specular_ior_level": ("specular",), "specular_tint": ("specular_color",),
                 "coat_weight": ("clearcoat",), "coat_roughness": ("clearcoat_roughness",),
                 "transmission_weight": ("transmission",)},
    "UsdPreviewSurface": {"base_color": ("diffuseColor",), "metallic": ("metallic",), "roughness": ("roughness",),
                          "ior": ("ior",), "coat_weight": ("clearcoat",), "coat_roughness": ("clearcoatRoughness",)},
}
TRANSMISSION_TINT = {"open_pbr_surface": "transmission_color", "standard_surface": "transmission_color"}
"""Shaders whose transmitted light has a colour of its own: Blender's Principled BSDF tints it by
Base Color, so a glass's Base Color is this colour (mixed with the base colour by the
transmission weight). glTF and UsdPreviewSurface tint it by the base colour, as Blender does."""
HALF = {"specular_ior_level"}
SCALE = {"anisotropic": 1.0 / 0.9}
"""Principled parameters that are the shader's value times this: MaterialX's roughness anisotropy
a makes the axes' α ratio 1 − a (mx_roughness_anisotropy; OpenPBR's alike), Disney's (Blender's)
1 − 0.9 a (clipped to 1 on reading)."""
"""Principled parameters that are half the shader's weight (Specular IOR Level 0.5 = weight 1)."""
QUIET = {"normal", "tangent", "geometry_normal", "geometry_coat_normal", "geometry_tangent", "geometry_coat_tangent",
         "coat_normal", "alpha_mode", "alpha_cutoff", "opacityMode", "opacityThreshold", "displacement"}
"""Inputs that say nothing about a sphere's reflectance (geometry, alpha modes): never listed."""


def open_pbr_inputs(params: dict) -> dict[str, object]:
    """A Principled BSDF's values as open_pbr_surface inputs (the writer's direction)."""
    return {"base_color": tuple(params["base_color"]), "base_weight": 1.0, "base_metalness": params["metallic"],
            "specular_roughness": params["roughness"], "specular_ior": params["ior"],
            "specular_weight": 2.0 * params["specular_ior_level"], "specular_color": tuple(params["specular_tint"]),
            "coat_weight": params["coat_weight"], "coat_roughness": params["coat_roughness"],
            "coat_ior": params["coat_ior"], "coat_color": tuple(params["coat_tint"]),
            "fuzz_weight": params["sheen_weight"], "fuzz_color": tuple(params["sheen_tint"]),
            "fuzz_roughness": params["sheen_roughness"], "specular_roughness_anisotropy": 0.9 * params["anisotropic"],
            "transmission_weight": params["transmission_weight"], "subsurface_weight": params["subsurface_weight"],
            "transmission_color": tuple(params["base_color"]),  # what Blender tints a glass by
            "base_diffuse_roughness": params["diffuse_roughness"]}


DIRECT = {"base_color": "base_color", "metallic": "base_metalness", "roughness": "specular_roughness",
          "ior": "specular_ior", "specular_tint": "specular_color", "coat_weight": "coat_weight",
          "coat_roughness": "coat_roughness", "transmission_weight": "transmission_weight"}
"""Principled parameters that are one open_pbr_surface input as they are (an image can drive it
directly; base_weight stays 1)."""

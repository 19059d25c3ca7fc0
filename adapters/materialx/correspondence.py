"""How MaterialX's surface shaders correspond to Blender's Principled BSDF (the `cycles`
adapter's `principled` model), both ways. Data, no MaterialX import.

Blender's Principled BSDF follows OpenPBR: the same base colour and metalness, roughness
(α = roughness² in both), specular IOR; Blender's Specular IOR Level is 0.5 for the IOR as
given, where OpenPBR's specular weight is 1, so level = weight / 2. Autodesk Standard Surface,
glTF PBR and UsdPreviewSurface map the same way by their own names. A shader input with no
counterpart is listed per material when it is away from its default."""

from __future__ import annotations

# shader category -> {principled parameter: (shader input, scale)}; base colour may be the
# product of two inputs (a weight and a colour).
TO_PRINCIPLED: dict[str, dict[str, tuple[str, ...]]] = {
    "open_pbr_surface": {"base_color": ("base_color", "base_weight"), "metallic": ("base_metalness",),
                         "roughness": ("specular_roughness",), "ior": ("specular_ior",),
                         "specular_ior_level": ("specular_weight",), "specular_tint": ("specular_color",),
                         "coat_weight": ("coat_weight",), "coat_roughness": ("coat_roughness",)},
    "standard_surface": {"base_color": ("base_color", "base"), "metallic": ("metalness",),
                         "roughness": ("specular_roughness",), "ior": ("specular_IOR",),
                         "specular_ior_level": ("specular",), "specular_tint": ("specular_color",),
                         "coat_weight": ("coat",), "coat_roughness": ("coat_roughness",)},
    "gltf_pbr": {"base_color": ("base_color",), "metallic": ("metallic",), "roughness": ("roughness",),
                 "ior": ("ior",), "specular_ior_level": ("specular",), "specular_tint": ("specular_color",),
                 "coat_weight": ("clearcoat",), "coat_roughness": ("clearcoat_roughness",)},
    "UsdPreviewSurface": {"base_color": ("diffuseColor",), "metallic": ("metallic",), "roughness": ("roughness",),
                          "ior": ("ior",), "coat_weight": ("clearcoat",), "coat_roughness": ("clearcoatRoughness",)},
}
HALF = {"specular_ior_level"}
"""Principled parameters that are half the shader's weight (Specular IOR Level 0.5 = weight 1)."""
QUIET = {"normal", "tangent", "geometry_normal", "geometry_coat_normal", "geometry_tangent", "geometry_coat_tangent",
         "coat_normal", "alpha_mode", "alpha_cutoff", "opacityMode", "opacityThreshold", "displacement"}
"""Inputs that say nothing about a sphere's reflectance (geometry, alpha modes): never listed."""


def open_pbr_inputs(params: dict) -> dict[str, object]:
    """A Principled BSDF's values as open_pbr_surface inputs (the writer's direction)."""
    return {"base_color": tuple(params["base_color"]), "base_weight": 1.0, "base_metalness": params["metallic"],
            "specular_roughness": params["roughness"], "specular_ior": params["ior"],
            "specular_weight": 2.0 * params["specular_ior_level"], "specular_color": tuple(params["specular_tint"]),
            "coat_weight": params["coat_weight"], "coat_roughness": params["coat_roughness"]}

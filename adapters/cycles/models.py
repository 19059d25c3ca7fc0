"""Blender Cycles material models as data (no bpy import here).

Blender's roughness r is the square root of the microfacet α (α = r²)."""

from __future__ import annotations

from brdfremap.core.data.schemas import LobeSpec, ModelSpec, Need, ParamSpec

# Lobes are isolated natively by render passes (Diffuse Direct x Diffuse Color, Glossy
# Direct x Glossy Color), so no overrides: editing the material to hide a lobe changes the
# other one (Specular IOR Level 0 shifts the diffuse term by about 10 %). Base Color shapes
# both lobes: it is the diffuse albedo and, through Metallic, the metal's specular colour;
# Metallic too: it fades the diffuse lobe out. The engine refits shared parameters on the
# full image in the second stage.
PASS_LOBES_PRINCIPLED = {
    "diffuse": LobeSpec(params=("base_color", "metallic", "sheen_weight", "sheen_roughness")),  # Sheen: a diffuse closure
    "specular": LobeSpec(params=("base_color", "metallic", "roughness", "ior", "specular_ior_level", "specular_tint",
                                 "anisotropic", "anisotropic_rotation", "coat_weight", "coat_roughness")),
}


def _unit(name, default, fit=True, desc="", upper=1.0, **kw):
    return ParamSpec(name=name, kind="scalar", lower=0.0, upper=upper, default=default, fit=fit, description=desc, **kw)


# A fully metallic Principled BSDF is the F82-tint conductor of Base Color and Specular Tint:
# the dielectric's IOR and Specular IOR Level no longer reach the image (checked: identical
# renders in Blender 5.0; tests/test_cycles.py keeps checking it).
METAL = {"metallic": 1.0}
ISOTROPIC = {"anisotropic": 0.0}
GLASS = {"transmission_weight": 1.0}
NO_COAT, NO_SHEEN, NO_SSS, NO_FILM = ({"coat_weight": 0.0}, {"sheen_weight": 0.0}, {"subsurface_weight": 0.0},
                                      {"thin_film_thickness": 0.0})


PRINCIPLED = ModelSpec(
    name="principled",
    smooth_when={"roughness": 0.0},
    transmits_with="transmission_weight",
    description="Principled BSDF (multiscatter GGX by default). Lobes by render passes.",
    parameters=(
        ParamSpec(name="distribution", kind="choice", default="multi_ggx", choices=("multi_ggx", "ggx"), explore=True,
                  description="Microfacet distribution of the Principled BSDF."),
        ParamSpec(name="base_color", kind="rgb", default=(0.8, 0.8, 0.8), held_when=GLASS,
                  description="Base Color (a glass's tint, in and out: held, carried from the source)."),
        _unit("metallic", 0.0, desc="Metallic.", held_when=GLASS),
        _unit("roughness", 0.5, desc="Roughness (α = roughness²)."),
        ParamSpec(name="ior", kind="scalar", lower=1.0, upper=3.0, default=1.5, fit=False, inert_when=METAL,
                  fit_when=GLASS, description="IOR of the dielectric specular (use Specular IOR Level to fit F0; "
                                              "a glass's is fitted: it refracts what the glass transmits)."),
        _unit("specular_ior_level", 0.5, upper=1.0, desc="Specular IOR Level (0.5 = the IOR as given; a glass "
              "ignores it).", inert_when=METAL, held_when=GLASS),
        ParamSpec(name="specular_tint", kind="rgb", default=(1.0, 1.0, 1.0), fit=False, fit_for=(Need.EDGE_TINT,),
                  description="Specular Tint (a metal's: its F82 tint, the colour of its edge)."),
        _unit("anisotropic", 0.0, fit=False, fit_when_carried=True, desc="Anisotropic (the probe's tangent runs "
              "along the sphere's latitudes, its pole at the image's top)."),
        _unit("anisotropic_rotation", 0.0, fit=False, fit_when_carried=True, inert_when=ISOTROPIC,
              desc="Anisotropic Rotation (a fraction of a turn of the tangent about the normal)."),
        _unit("coat_weight", 0.0, fit=False, fit_when_carried=True, desc="Coat Weight."),
        _unit("coat_roughness", 0.03, fit=False, fit_when_carried=True, desc="Coat Roughness.", inert_when=NO_COAT),
        ParamSpec(name="coat_ior", kind="scalar", lower=1.0, upper=4.0, default=1.5, fit=False, inert_when=NO_COAT,
                  description="Coat IOR."),
        ParamSpec(name="coat_tint", kind="rgb", default=(1.0, 1.0, 1.0), fit=False, inert_when=NO_COAT,
                  description="Coat Tint (the colour light takes through the coat)."),
        _unit("sheen_weight", 0.0, fit=False, fit_when_carried=True, desc="Sheen Weight."),
        _unit("sheen_roughness", 0.5, fit=False, fit_when_carried=True, desc="Sheen Roughness.", inert_when=NO_SHEEN),
        ParamSpec(name="sheen_tint", kind="rgb", default=(1.0, 1.0, 1.0), fit=False, inert_when=NO_SHEEN,
                  description="Sheen Tint."),
        _unit("diffuse_roughness", 0.0, fit=False, fit_for=(Need.ROUGH_DIFFUSE,),
              desc="Diffuse Roughness (0: Lambertian)."),
        _unit("subsurface_weight", 0.0, fit=False, desc="Subsurface Weight (the probe sphere is 2 units across: "
              "radii well below it look like a softened diffuse)."),
        ParamSpec(name="subsurface_radius", kind="rgb", lower=0.0, upper=100.0, default=(1.0, 0.2, 0.1), fit=False,
                  inert_when=NO_SSS, description="Subsurface Radius per channel (times Subsurface Scale)."),
        ParamSpec(name="subsurface_scale", kind="scalar", lower=0.0, upper=100.0, default=0.05, fit=False,
                  inert_when=NO_SSS, description="Subsurface Scale (scene units)."),
        ParamSpec(name="subsurface_method", kind="choice", default="random_walk", inert_when=NO_SSS,
                  choices=("random_walk", "random_walk_skin", "burley"),
                  description="Subsurface Method (Blender's default: Random Walk; its IOR only the skin variant "
                              "reads)."),
        ParamSpec(name="subsurface_ior", kind="scalar", lower=1.01, upper=3.8, default=1.4, fit=False,
                  inert_when=NO_SSS, active_when={"subsurface_method": ("random_walk_skin",)},
                  description="Subsurface IOR (the Random Walk (Skin) method's)."),
        _unit("subsurface_anisotropy", 0.0, fit=False, desc="Subsurface Anisotropy (the random walks').",
              inert_when=NO_SSS, active_when={"subsurface_method": ("random_walk", "random_walk_skin")}),
        _unit("transmission_weight", 0.0, fit=False, desc="Transmission Weight (what is seen through the sphere is "
              "what surrounds it: an environment, or the black background)."),
        ParamSpec(name="thin_film_thickness", kind="scalar", lower=0.0, upper=100000.0, default=0.0, fit=False,
                  description="Thin Film Thickness (nm)."),
        ParamSpec(name="thin_film_ior", kind="scalar", lower=1.0, upper=3.0, default=1.33, fit=False,
                  inert_when=NO_FILM, description="Thin Film IOR."),
        _unit("alpha", 1.0, fit=False, desc="Alpha (coverage: below 1 the black background shows through)."),
    ),
    lobes=PASS_LOBES_PRINCIPLED,
    texturable=("base_color", "metallic", "roughness", "ior", "specular_ior_level", "specular_tint", "anisotropic",
                "anisotropic_rotation", "coat_weight", "coat_roughness", "coat_ior", "coat_tint", "sheen_weight",
                "sheen_roughness", "sheen_tint", "diffuse_roughness", "subsurface_weight", "subsurface_radius",
                "subsurface_scale", "subsurface_ior", "subsurface_anisotropy", "transmission_weight",
                "thin_film_thickness", "thin_film_ior", "alpha"),
)
"""Every reflection input of Blender 5.0's Principled BSDF but Emission (the probe measures
reflection) and Tangent (the probe's own: along the latitudes). Past the first nine they are held
(`--fix` them), and a value a source carries is rendered; the coat's, sheen's and anisotropy's
weight and roughness are fitted when the source has that lobe (`fit_when_carried`)."""

GLOSSY = ModelSpec(
    name="glossy",
    smooth_when={"roughness": 0.0},
    description="Glossy BSDF: a microfacet lobe with a constant colour (no Fresnel).",
    parameters=(
        ParamSpec(name="distribution", kind="choice", default="ggx", explore=True,
                  choices=("beckmann", "ggx", "ashikhmin_shirley", "multi_ggx"), description="Distribution."),
        ParamSpec(name="color", kind="rgb", default=(0.8, 0.8, 0.8), linear_in=("full", "specular"), description="Color."),
        _unit("roughness", 0.3, desc="Roughness (α = roughness²)."),
    ),
    lobes={"diffuse": LobeSpec(empty=True), "specular": LobeSpec(params=("color", "roughness"))},
    texturable=("color", "roughness"),
)

DIFFUSE = ModelSpec(
    name="diffuse",
    description="Diffuse BSDF (Lambertian at roughness 0).",
    parameters=(
        ParamSpec(name="color", kind="rgb", default=(0.8, 0.8, 0.8), linear_in=("full", "diffuse"), description="Color."),
        _unit("roughness", 0.0, fit=False, fit_for=(Need.ROUGH_DIFFUSE,), desc="Oren-Nayar roughness."),
    ),
    lobes={"diffuse": LobeSpec(params=("color", "roughness")), "specular": LobeSpec(empty=True)},
    texturable=("color", "roughness"),
)

METALLIC = ModelSpec(
    name="metallic",
    smooth_when={"roughness": 0.0},
    description="Metallic BSDF with the physical conductor Fresnel (complex IOR per channel).",
    parameters=(
        ParamSpec(name="distribution", kind="choice", default="multi_ggx", choices=("beckmann", "ggx", "multi_ggx"),
                  explore=True, description="Distribution."),
        ParamSpec(name="ior", kind="rgb", lower=0.0, upper=8.0, default=(0.2, 0.4, 1.4), description="IOR (eta)."),
        ParamSpec(name="extinction", kind="rgb", lower=0.0, upper=10.0, default=(3.9, 2.4, 1.6),
                  description="Extinction (k)."),
        _unit("roughness", 0.3, desc="Roughness (α = roughness²)."),
    ),
    lobes={"diffuse": LobeSpec(empty=True), "specular": LobeSpec(params=("ior", "extinction", "roughness"))},
    texturable=("ior", "extinction", "roughness"),
    complex_ior=("ior", "extinction"),
)

MODELS = {m.name: m for m in (PRINCIPLED, GLOSSY, DIFFUSE, METALLIC)}

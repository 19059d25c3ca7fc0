"""The parameters Mitsuba's models share (no mitsuba import here)."""

from __future__ import annotations

from brdfremap.core.data.schemas import LobeSpec, ParamSpec

# Mitsuba 3's complex IOR database (names accepted by `material=` of conductors).
CONDUCTOR_PRESETS = (
    "none", "a-C", "Ag", "Al", "AlAs", "AlAs_palik", "AlSb", "AlSb_palik", "Au", "Be", "Cr", "CsI", "Cu",
    "Cu_palik", "Cu2O", "CuO", "d-C", "Hg", "HgTe", "Ir", "K", "Li", "MgO", "Mo", "Na_palik", "Nb", "Ni_palik",
    "Rh", "Se", "SiC", "SnTe", "Ta", "Te", "ThF4", "TiC", "TiN", "TiO2", "VC", "V_palik", "VN", "W",
)
DISTRIBUTION = ParamSpec(name="distribution", kind="choice", default="beckmann", choices=("beckmann", "ggx"),
                         explore=True, description="Microfacet distribution.")
ALPHA = ParamSpec(name="alpha", kind="scalar", lower=1e-4, upper=1.0, default=0.1, scale="log", typical=(0.002, 1.0),
                  description="Microfacet roughness α (Mitsuba's convention, not Blender's √α).")
SPEC_REFL = ParamSpec(name="specular_reflectance", kind="rgb", default=(1.0, 1.0, 1.0), fit=False,
                      linear_in=("specular",), description="Multiplier on the specular term (physically 1).")
ETA = ParamSpec(name="eta", kind="rgb", lower=0.0, upper=8.0, default=(1.0, 1.0, 1.0),
                active_when={"material": ("none",)}, description="Real part of the complex IOR (RGB).")
K = ParamSpec(name="k", kind="rgb", lower=0.0, upper=10.0, default=(3.0, 3.0, 3.0),
              active_when={"material": ("none",)}, description="Imaginary part of the complex IOR (RGB).")
BASE_COLOUR = ParamSpec(name="diffuse_reflectance", kind="rgb", default=(0.5, 0.5, 0.5), linear_in=("diffuse",),
                        description="Base colour.")
INT_IOR = ParamSpec(name="int_ior", kind="scalar", lower=1.01, upper=3.0, default=1.49,
                    description="Interior index of refraction of the coating (exterior: air).")


def lobes(*specular: str) -> dict[str, LobeSpec]:
    """A diffuse and a specular lobe, each seen alone by zeroing the other's reflectance."""
    return {
        "diffuse": LobeSpec(params=("diffuse_reflectance",), overrides={"specular_reflectance": (0.0, 0.0, 0.0)}),
        "specular": LobeSpec(params=specular, overrides={"diffuse_reflectance": (0.0, 0.0, 0.0)}),
    }


ANISOTROPY = ParamSpec(name="anisotropy", kind="choice", default="isotropic", choices=("isotropic", "anisotropic"),
                       description="One roughness (alpha), or one along the tangent and one across (alpha_u, "
                                   "alpha_v; the probe's tangent runs along the sphere's latitudes, its pole at the "
                                   "image's top).")
ISOTROPIC, ANISOTROPIC = {"anisotropy": ("isotropic",)}, {"anisotropy": ("anisotropic",)}


def alpha_param(name: str, desc: str, when: dict) -> ParamSpec:
    return ALPHA.model_copy(update={"name": name, "description": desc, "active_when": when})


CONDUCTOR_PRESET = ParamSpec(name="material", kind="choice", default="none", choices=CONDUCTOR_PRESETS,
                             description="Named conductor from Mitsuba's IOR database; 'none' uses eta and k.")


AS_ALPHA = ParamSpec(name="alpha", kind="scalar", lower=0.01, upper=1.0, default=0.1, scale="log",
                     description="Roughness α; the Phong exponent is n = 2/α² − 2 (Mitsuba 0.5's `as`).")

"""A tiny analytic adapter in numpy: the example of authoring an adapter.

It renders the probe scene itself (Lambert + a Gaussian-in-angle specular lobe), so it
needs nothing but numpy. brdf-remap's own tests use it as a fast, exact renderer for the
optimiser; it is never the evidence that remapping works with real renderers."""

from __future__ import annotations

import math

import numpy as np

from brdfremap.core import Adapter, Appearance, LobeSpec, Model, ParamSpec, ProbeScene
from brdfremap.core.testing import box_filtered, point_light_irradiance

class Toy(Model):
    """The toy model in one place: its parameters (below) and its neutral reading, which gives a
    remap its informed start (optional for a model): the toy's lobe is Gaussian in the half-vector
    angle like Beckmann's, and its specular weight stands in for the normal-incidence reflectance."""

    def appearance(self, params):
        return Appearance(kind="dielectric", alpha=params["alpha"], distribution="beckmann",
                          specular=(params["specular"],) * 3, diffuse=tuple(params["diffuse"]))

    def from_appearance(self, appearance, base):
        out = {"diffuse": appearance.diffuse, "specular": sum(appearance.specular) / 3}
        if appearance.alpha is not None:
            out["alpha"] = appearance.alpha
        return out


TOY = Toy(
    name="toy",
    description="Lambert + a Gaussian-in-angle specular lobe.",
    parameters=(
        ParamSpec(name="diffuse", kind="rgb", default=(0.5, 0.5, 0.5)),
        ParamSpec(name="specular", kind="scalar", lower=0.0, upper=2.0, default=0.5),
        ParamSpec(name="alpha", kind="scalar", lower=0.01, upper=1.0, default=0.2, scale="log"),
        ParamSpec(name="unused", kind="scalar", default=0.5, fit=False),
    ),
    lobes={
        "diffuse": LobeSpec(params=("diffuse",), overrides={"specular": 0.0}),
        "specular": LobeSpec(params=("specular", "alpha"), overrides={"diffuse": (0.0, 0.0, 0.0)}),
    },
)


class ToyAdapter(Adapter):
    name = "toy"
    summary = "analytic numpy sphere (example adapter package)"
    models = {"toy": TOY}
    calibration = ("toy", {"diffuse": 0.8, "specular": 0.0})

    def __init__(self):
        self.calls = 0

    def render(self, model, params, scene: ProbeScene, lobe=None):
        """The sphere shaded along each pixel's ray, and near the silhouette averaged over the pixel's area
        (`box_filtered`: a renderer's box pixel filter; one ray at each centre fails `remap check`'s sampling)."""
        self.calls += 1
        p = self.as_model(model).with_lobe(params, lobe)  # the tool passes the model; a script may name it
        return box_filtered(scene, lambda hits: self._shade(p, scene, hits)).astype(np.float32)

    @staticmethod
    def _shade(p, scene: ProbeScene, hits):
        a = p["alpha"]
        image = np.zeros((*hits.mask.shape, 3))
        for light in scene.point_lights:  # the lights add up
            e, l = point_light_irradiance(scene, hits, light)
            h = l + hits.view
            h /= np.linalg.norm(h, axis=-1, keepdims=True)
            cos_h = np.clip((h * hits.normal).sum(-1), 1e-6, 1.0)
            tan2 = (1 - cos_h**2) / cos_h**2
            spec = p["specular"] * np.exp(-tan2 / a**2) / (math.pi * a**2 * cos_h**4) / 4
            image += (np.asarray(p["diffuse"]) / math.pi + spec[..., None]) * e[..., None]
        return image

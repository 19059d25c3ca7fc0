"""The probe scene as data: every adapter realises it in the same physical units."""

from __future__ import annotations

import math
from pathlib import Path

from pydantic import ConfigDict, Field, field_validator, model_validator

from .model import Strict


class _Strict(Strict):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)  # a scene's numbers are finite


MAX_SPP = 65536
MAX_SEED = 2**31 - 2
"""Renderers take a signed 32-bit seed; the noise floor renders seed + 1 too."""


class Sphere(_Strict):
    center: tuple[float, float, float] = Field((0.0, 0.0, 0.0), description="Centre of the probe sphere (scene units).")
    radius: float = Field(2.0, gt=0, description="Radius of the probe sphere (scene units).")


def _dot(a, b) -> float:
    return sum(x * y for x, y in zip(a, b))


class Camera(_Strict):
    """A pinhole camera looking at ``target`` from ``distance`` along +z (the view axis)."""

    distance: float = Field(6.5, gt=0, description="Distance from the target along +z.")
    target: tuple[float, float, float] = Field((0.0, 0.0, 0.0), description="Point the camera looks at.")
    fov: float = Field(40.0, gt=0, lt=180, description="Horizontal field of view in degrees.")
    up: tuple[float, float, float] = Field((0.0, 1.0, 0.0), description="Up vector of the image.")

    @model_validator(mode="after")
    def _up(self) -> "Camera":
        n = math.hypot(*self.up)
        if n == 0 or abs(self.up[2]) / n > 0.999:  # the camera looks along -z
            raise ValueError("up: must not be zero nor along the view axis (z): e.g. [0, 1, 0]")
        return self

    @property
    def position(self) -> tuple[float, float, float]:
        tx, ty, tz = self.target
        return (tx, ty, tz + self.distance)


class PointLight(_Strict):
    """An isotropic point light, placed in spherical coordinates around the view axis (+z)."""

    r: float = Field(5.2, gt=0, description="Distance from the origin.")
    theta: float = Field(45.0, ge=0, le=180, description="Polar angle from +z (the view direction), degrees.")
    phi: float = Field(125.0, description="Azimuth in the image plane from +x towards +y, degrees.")
    intensity: float = Field(30.0, gt=0, description="Radiant intensity in W/sr (white).")

    @property
    def position(self) -> tuple[float, float, float]:
        t, p = math.radians(self.theta), math.radians(self.phi)
        return (self.r * math.sin(t) * math.cos(p), self.r * math.sin(t) * math.sin(p), self.r * math.cos(t))


class ProbeScene(_Strict):
    """The fixed scene every remap renders: a sphere lit by one point light, black background,
    direct lighting only. Images are linear scene-referred RGB, float32, H x W x 3."""

    name: str = Field("probe", description="A label for reports.")
    note: str = Field("", description="Free text: what this scene is for.")
    sphere: Sphere = Field(default_factory=Sphere)
    camera: Camera = Field(default_factory=Camera)
    light: PointLight = Field(default_factory=PointLight)
    resolution: int = Field(128, ge=8, le=4096, description="Image width and height in pixels.")
    spp: int = Field(16, ge=1, le=MAX_SPP, description="Samples per pixel.")
    seed: int = Field(0, ge=0, le=MAX_SEED, description="Sampler seed; renders with the same seed are repeatable "
                                                       "(the noise floor also renders seed + 1).")

    @field_validator("note")
    @classmethod
    def _strip(cls, v: str) -> str:
        return v.strip()

    @model_validator(mode="after")
    def _outside(self) -> "ProbeScene":
        """The camera and the light outside the sphere, and the sphere in the camera's view, or the
        image is black."""
        c, r = self.sphere.center, self.sphere.radius
        for name, pos in (("camera.distance", self.camera.position), ("light.r", self.light.position)):
            d = math.dist(pos, c)
            if d <= r:
                raise ValueError(f"{name}: puts it {d:g} from the sphere's centre, inside the sphere (radius {r:g}): "
                                 "move it out")
        eye = self.camera.position
        forward = [t - e for t, e in zip(self.camera.target, eye)]
        to_sphere = [x - e for x, e in zip(c, eye)]
        angle = math.degrees(math.acos(max(-1.0, min(1.0, _dot(forward, to_sphere) / (
            math.hypot(*forward) * math.hypot(*to_sphere))))))
        reach = self.camera.fov / 2 + math.degrees(math.asin(min(1.0, r / math.dist(eye, c))))
        if angle >= reach:
            raise ValueError(f"camera.target: the sphere is {angle:.0f} degrees off the view axis, outside the camera's "
                             f"view (it reaches {reach:.0f}): aim the camera at it")
        return self

    def overridden(self, *, resolution: int | None = None, spp: int | None = None,
                   seed: int | None = None) -> "ProbeScene":
        """This scene with the given values replaced, validated (a ValidationError names the field)."""
        given = {k: v for k, v in (("resolution", resolution), ("spp", spp), ("seed", seed)) if v is not None}
        return ProbeScene.model_validate({**self.model_dump(), **given}) if given else self

    def with_(self, **changes) -> "ProbeScene":
        return self.model_copy(update={k: v for k, v in changes.items() if v is not None})

    def document(self) -> dict:
        """The scene in physical units with positions resolved: what renderers outside this
        package receive (`{scene_json}`, the Cycles worker)."""
        cam = self.camera
        return {
            "units": {"length": "scene units", "light_intensity": "W/sr (radiant intensity)",
                      "fov": "degrees, horizontal", "image": "linear RGB radiance, float32"},
            "sphere": {"center": list(self.sphere.center), "radius": self.sphere.radius},
            "camera": {"position": list(cam.position), "target": list(cam.target), "up": list(cam.up), "fov": cam.fov},
            "light": {"type": "point", "position": list(self.light.position), "intensity": self.light.intensity},
            "background": [0.0, 0.0, 0.0],
            "integrator": "direct lighting only",
            "width": self.resolution, "height": self.resolution, "spp": self.spp, "seed": self.seed,
        }

    def cache_key(self) -> str:
        return self.model_dump_json(exclude={"name", "note"})


def load_scene(path: str | Path) -> ProbeScene:
    from .configio import load_yaml_model

    return load_yaml_model(path, ProbeScene, "a scene")

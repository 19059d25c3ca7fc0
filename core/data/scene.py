"""The probe scene as data: every adapter realises it in the same physical units."""

from __future__ import annotations

import json
import math
from pathlib import Path
from enum import StrEnum
from typing import Annotated, Any, Literal, Union

from pydantic import ConfigDict, Field, ValidationInfo, field_validator, model_validator

from .model import UNION_TAGS, Strict


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
    def _up(self) -> Camera:
        n = math.hypot(*self.up)
        if n == 0 or abs(self.up[2]) / n > 0.999:  # the camera looks along -z
            raise ValueError("up: must not be zero nor along the view axis (z): e.g. [0, 1, 0]")
        return self

    @property
    def position(self) -> tuple[float, float, float]:
        tx, ty, tz = self.target
        return (tx, ty, tz + self.distance)


class LightType(StrEnum):
    """The kinds of light a scene holds (an adapter declares those it renders: `light_types`)."""

    POINT = "point"
    ENVIRONMENT = "environment"


class Lighting(StrEnum):
    """The lighting a result is judged under: the fit's scene, each held-out condition, and the job's
    own scene where the fit ran elsewhere."""

    SCENE = "scene"
    GRAZING = "grazing"
    RIM = "rim"
    HEADLIGHT = "headlight"
    ENVIRONMENT = "environment"
    GIVEN = "given"


class PointLight(_Strict):
    """An isotropic point light, placed in spherical coordinates around the view axis (+z)."""

    type: Literal["point"] = "point"
    r: float = Field(5.2, gt=0, description="Distance from the origin.")
    theta: float = Field(45.0, ge=0, le=180, description="Polar angle from +z (the view direction), degrees.")
    phi: float = Field(125.0, description="Azimuth in the image plane from +x towards +y, degrees.")
    intensity: float = Field(30.0, gt=0, description="Radiant intensity in W/sr (white).")

    @property
    def position(self) -> tuple[float, float, float]:
        t, p = math.radians(self.theta), math.radians(self.phi)
        return (self.r * math.sin(t) * math.cos(p), self.r * math.sin(t) * math.sin(p), self.r * math.cos(t))

    def document(self) -> dict[str, Any]:
        return {"type": "point", "position": list(self.position), "intensity": self.intensity}

    def key(self) -> dict[str, Any]:
        return self.model_dump(mode="json")


class EnvironmentLight(_Strict):
    """Light from every direction, infinitely far: an equirectangular map of radiance (see
    `core.data.environment` for its orientation). Only surfaces see it: the background stays black."""

    type: Literal["environment"]
    map: str = Field("studio", description="'studio' (built in: key, fill and rim lights), 'constant' (radiance 1 "
                                           "everywhere), a built-in disc of light ('probe-disc', 'grazing-disc', "
                                           "'rim-disc', 'headlight-disc': scale is its irradiance), a "
                                           "built-in soft box over a backdrop ('probe-backdrop', 'grazing-backdrop', "
                                           "'rim-backdrop', 'headlight-backdrop': likewise), "
                                           "or the path of an equirectangular EXR or HDR of linear "
                                           "radiance, twice as wide as high (relative to the scene file).")
    scale: float = Field(1.0, gt=0, le=1e6, description="Multiplies the map's radiance.")
    rotation: float = Field(0.0, ge=-360, le=360, description="Turns the map about the up axis (+y), degrees: a "
                                                              "feature moves this far in azimuth.")

    @field_validator("map")
    @classmethod
    def _map(cls, v: str, info: ValidationInfo) -> str:
        from . import environment

        if environment.is_builtin(v):
            return v
        path = Path(v).expanduser()
        base = (info.context or {}).get("base_dir")
        if not path.is_absolute() and base is not None:
            path = Path(base) / path
        problem = environment.check_file(path)
        if problem:
            raise ValueError(f"{v}: {problem}")
        return str(path.resolve())

    def document(self) -> dict[str, Any]:
        from .environment import realise

        return {"type": "environment", "file": str(realise(self.map, self.scale, self.rotation)),
                "convention": "equirectangular: u = atan2(x, -z) / 2pi (mod 1) from the left, v = acos(y) / pi "
                              "from the top; scale and rotation applied"}

    def key(self) -> dict[str, Any]:
        from .environment import digest

        return {**self.model_dump(mode="json"), "map": digest(self.map)}


Light = Annotated[Union[PointLight, EnvironmentLight], Field(discriminator="type")]
UNION_TAGS.update({"point", "environment"})
MAX_LIGHTS, MAX_VIEWS = 16, 8


def _typed_lights(lights: Any) -> Any:
    """Lights written without a type are point lights (the scene files before there were others)."""
    if not isinstance(lights, list):
        return lights
    return [{"type": "point", **x} if isinstance(x, dict) and "type" not in x else x for x in lights]


class View(_Strict):
    """A camera and the lights it sees the sphere under."""

    camera: Camera = Field(default_factory=Camera)
    lights: list[Light] = Field(min_length=1, max_length=MAX_LIGHTS, description="Point lights and at most one "
                                                                                  "environment.")

    @field_validator("lights", mode="before")
    @classmethod
    def _types(cls, v: Any) -> Any:
        return _typed_lights(v)


class ProbeScene(_Strict):
    """The fixed scene every remap renders: a sphere under its lights (point lights, an
    environment map), black background, direct lighting only. Images are linear scene-referred
    RGB, float32, H x W x 3; a scene with further `views` renders each one below the first
    (height × number of views)."""

    name: str = Field("probe", description="A label for reports.")
    note: str = Field("", description="Free text: what this scene is for.")
    sphere: Sphere = Field(default_factory=Sphere)
    camera: Camera = Field(default_factory=Camera)
    lights: list[Light] = Field(default_factory=lambda: [PointLight()], min_length=1, max_length=MAX_LIGHTS,
                                description="The lights of the first view: point lights and at most one environment.")
    views: list[View] = Field(default_factory=list, max_length=MAX_VIEWS - 1,
                              description="Further views, each a camera and its lights, rendered below the first and "
                                          "fitted together with it.")
    resolution: int = Field(128, ge=8, le=4096, description="Image width and height in pixels (of each view).")
    spp: int = Field(16, ge=1, le=MAX_SPP, description="Samples per pixel.")
    seed: int = Field(0, ge=0, le=MAX_SEED, description="Sampler seed; renders with the same seed are repeatable "
                                                       "(the noise floor also renders seed + 1).")

    @model_validator(mode="before")
    @classmethod
    def _one_light(cls, data: Any) -> Any:
        """`light:` (one point light, the scene files before lists) is the list of that one."""
        if isinstance(data, dict) and "light" in data:
            if "lights" in data:
                raise ValueError("light: give either `light` (one point light) or `lights` (a list), not both")
            data = {**{k: v for k, v in data.items() if k != "light"}, "lights": [data["light"]]}
        if isinstance(data, dict) and "lights" in data:
            data = {**data, "lights": _typed_lights(data["lights"])}
        return data

    @field_validator("note")
    @classmethod
    def _strip(cls, v: str) -> str:
        return v.strip()

    @model_validator(mode="after")
    def _outside(self) -> ProbeScene:
        """In every view, the camera and the point lights outside the sphere, the sphere in the
        camera's view, at most one environment."""
        for i, view in enumerate(self.all_views()):
            prefix = "" if i == 0 else f"views.{i - 1}."
            _check_view(self.sphere, view.camera, view.lights, prefix)
        return self

    def all_views(self) -> list[View]:
        return [View(camera=self.camera, lights=self.lights), *self.views]

    def view_scenes(self) -> list[ProbeScene]:
        """One single-view scene per view: what adapters render."""
        if not self.views:
            return [self]
        return [self.model_copy(update={"camera": v.camera, "lights": v.lights, "views": []})
                for v in self.all_views()]

    def light_types(self) -> set[str]:
        return {light.type for view in self.all_views() for light in view.lights}

    @property
    def point_lights(self) -> list[PointLight]:
        return [x for x in self.lights if isinstance(x, PointLight)]

    @property
    def environment(self) -> EnvironmentLight | None:
        return next((x for x in self.lights if isinstance(x, EnvironmentLight)), None)

    def overridden(self, *, resolution: int | None = None, spp: int | None = None,
                   seed: int | None = None) -> ProbeScene:
        """This scene with the given values replaced, validated (a ValidationError names the field)."""
        given = {k: v for k, v in (("resolution", resolution), ("spp", spp), ("seed", seed)) if v is not None}
        return ProbeScene.model_validate({**self.model_dump(), **given}) if given else self

    def with_(self, **changes) -> ProbeScene:
        return self.model_copy(update={k: v for k, v in changes.items() if v is not None})

    def document(self) -> dict:
        """A single-view scene in physical units with positions resolved: what renderers outside
        this package receive (`{scene_json}`, the Cycles worker). ``light`` repeats a scene's only
        point light, as documents before `lights` had it."""
        if self.views:
            raise ValueError("document: a scene of several views is rendered view by view (view_scenes)")
        cam = self.camera
        doc = {
            "units": {"length": "scene units", "light_intensity": "W/sr (radiant intensity)",
                      "environment": "W m^-2 sr^-1 (radiance)",
                      "fov": "degrees, horizontal", "image": "linear RGB radiance, float32"},
            "sphere": {"center": list(self.sphere.center), "radius": self.sphere.radius},
            "camera": {"position": list(cam.position), "target": list(cam.target), "up": list(cam.up), "fov": cam.fov},
            "lights": [light.document() for light in self.lights],
            "background": [0.0, 0.0, 0.0],
            "integrator": "direct lighting only",
            "width": self.resolution, "height": self.resolution, "spp": self.spp, "seed": self.seed,
        }
        if len(self.lights) == 1 and isinstance(self.lights[0], PointLight):
            doc["light"] = self.lights[0].document()
        return doc

    def cache_key(self) -> str:
        """Everything that determines a render (a map file by its content), as JSON."""
        doc = self.model_dump(mode="json", exclude={"name", "note", "lights", "views"})
        doc["views"] = [{"camera": v.camera.model_dump(mode="json"), "lights": [x.key() for x in v.lights]}
                        for v in self.all_views()]
        return json.dumps(doc, sort_keys=True, separators=(",", ":"))


def _check_view(sphere: Sphere, camera: Camera, lights: list, prefix: str) -> None:
    c, r = sphere.center, sphere.radius
    placed = [(f"{prefix}camera.distance", camera.position)]
    placed += [(f"{prefix}lights.{i}.r", x.position) for i, x in enumerate(lights) if isinstance(x, PointLight)]
    for name, pos in placed:
        d = math.dist(pos, c)
        if d <= r:
            raise ValueError(f"{name}: puts it {d:g} from the sphere's centre, inside the sphere (radius {r:g}): "
                             "move it out")
    if sum(isinstance(x, EnvironmentLight) for x in lights) > 1:
        raise ValueError(f"{prefix}lights: more than one environment in a view: keep one (renderers take one)")
    eye = camera.position
    forward = [t - e for t, e in zip(camera.target, eye)]
    to_sphere = [x - e for x, e in zip(c, eye)]
    angle = math.degrees(math.acos(max(-1.0, min(1.0, _dot(forward, to_sphere) / (
        math.hypot(*forward) * math.hypot(*to_sphere))))))
    reach = camera.fov / 2 + math.degrees(math.asin(min(1.0, r / math.dist(eye, c))))
    if angle >= reach:
        raise ValueError(f"{prefix}camera.target: the sphere is {angle:.0f} degrees off the view axis, outside the "
                         f"camera's view (it reaches {reach:.0f}): aim the camera at it")


def load_scene(path: str | Path) -> ProbeScene:
    from .configio import load_yaml_model

    return load_yaml_model(path, ProbeScene, "a scene", context={"base_dir": Path(path).parent})

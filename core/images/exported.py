"""What `remap scene export` writes and an images source reads back: the shots (the probe scene and each
held-out condition, one scene each), their files, and the manifest that ties them together.

A shot is identified by what it shows (`view_key`: the sphere, the camera, the lights), not by its
resolution, samples or seed: a fit asks for the probe at its seed and the next, a held-out condition
at half the resolution, and an images source answers each from the one shot that shows it."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Literal

from pydantic import Field

from ..data.configio import load_yaml_model
from ..data.errors import ConfigError
from ..data.model import Strict
from ..data.scene import PointLight, ProbeScene
from ..host.check import ALBEDO, BRIGHT  # the calibration material, and the bright shot's scale
from ..job.fitscene import back_light
from ..job.validation import CONDITIONS, scenes

FORMAT = "brdf-remap scene export"
MANIFEST = "scenes.json"
CALIBRATION = "calibration"
"""The folder (beside a material's) of the white Lambertian's images."""
SEEDS = 2
"""Each shot is rendered with two seeds (the scene's and the next): their difference is the noise."""


class Shot(Strict):
    name: str = Field(pattern=r"^[a-z0-9_-]+$", description="The shot's name: its images are NAME.seed0.exr and "
                                                             "NAME.seed1.exr (in the folder: no path).")
    label: str = Field(description="What it shows, in words.")
    scene: ProbeScene = Field(description="Its one view at the resolution and samples to render (seed 0; seed1: +1).")
    calibration_only: bool = Field(False, description="Rendered of the calibration material only.")

    def file(self, seed: int) -> str:
        return f"{self.name}.seed{seed}.exr"


class Manifest(Strict):
    """The export's index (`scenes.json`): every shot, and where each format's file of it is."""

    format: Literal["brdf-remap scene export"] = FORMAT
    version: Literal[1] = 1
    albedo: float = ALBEDO
    shots: list[Shot]
    files: dict[str, dict[str, str]] = Field(default_factory=dict, description="Format -> shot -> file (relative).")

    def shot(self, name: str) -> Shot:
        return next(s for s in self.shots if s.name == name)

    @property
    def material_shots(self) -> list[Shot]:
        return [s for s in self.shots if not s.calibration_only]


def _one_point(scene: ProbeScene) -> PointLight | None:
    lights = scene.view_scenes()[0].lights
    return lights[0] if len(lights) == 1 and isinstance(lights[0], PointLight) else None


def view_key(scene: ProbeScene) -> str:
    """What a scene shows (sphere, camera, lights: not its size, samples or seed), as JSON. A single point
    light's intensity is left out: its image is the light's intensity times one image (`gain`)."""
    first = scene.view_scenes()[0]
    lights = [{k: round(v, 6) if isinstance(v, float) else v for k, v in x.key().items()} for x in first.lights]
    if _one_point(first) is not None:
        lights = [{k: v for k, v in lights[0].items() if k != "intensity"}]
    return json.dumps({"sphere": first.sphere.model_dump(mode="json"), "camera": first.camera.model_dump(mode="json"),
                       "lights": lights}, sort_keys=True, separators=(",", ":"))


def gain(shot: Shot, scene: ProbeScene) -> float:
    """What the shot's image is multiplied by to show ``scene`` (`view_key`'s): its one point light's
    intensity over the shot's (light is linear: a fit's back view is the back shot scaled)."""
    want, have = _one_point(scene), _one_point(shot.scene)
    return 1.0 if want is None or have is None else want.intensity / have.intensity


def shots(scene: ProbeScene, spp: int) -> list[Shot]:
    """The probe (the scene's own lights), each held-out condition as a fit would judge an opaque source
    under it (`core.job.validation.CONDITIONS`, placed about this sphere), the back light of a fit's second
    view (`core.job.fitscene.back_light`) and the calibration's bright probe: every one at the scene's
    resolution and ``spp``, seed 0."""
    first = scene.view_scenes()[0].with_(spp=spp, seed=0)
    out = [Shot(name="probe", label="the probe: the scene's own lights", scene=first.with_(name="probe"))]
    for cond, a, _ in scenes(first, CONDITIONS, fit_lights=first.lights):  # the studio turned if the probe is it
        out.append(Shot(name=str(cond.name), label=cond.label, scene=first.model_copy(update={
            "lights": list(a.lights), "name": str(cond.name)})))
    out.append(Shot(name="back", label="the fit's back light: 100 degrees from the view, opposite the probe's "
                                       "(the rim and grazing reflection a front light does not show)",
                    scene=first.model_copy(update={"lights": [back_light(first)], "name": "back"})))
    light = next((x for x in first.lights if isinstance(x, PointLight)), None)
    if light is not None:
        bright = light.model_copy(update={"intensity": light.intensity * BRIGHT})
        out.append(Shot(name="bright", label=f"the probe's light {BRIGHT:g} times brighter (calibration only: "
                                             "pixels far above 1)", calibration_only=True,
                        scene=first.model_copy(update={"lights": [bright], "name": "bright"})))
    return out


def find_manifest(folder: Path) -> tuple[Path, Manifest]:
    """The export's manifest a folder of images belongs to: in it or in a folder above (at most three up)."""
    for where in [folder, *list(folder.resolve().parents)[:3]]:
        path = where / MANIFEST
        if path.is_file():
            return path, load_yaml_model(path, Manifest, "a scene export manifest")
    raise ConfigError(f"no {MANIFEST} in it or above it: render the scenes of `remap scene export DIR` into "
                      f"DIR/renders/MATERIAL (see DIR/SHEET.md)", file=str(folder))

"""The adapter contract. An adapter renders the probe scene with one material model."""

from __future__ import annotations

import abc
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, ClassVar

import numpy as np

from ..data.appearance import Appearance
from ..data.errors import ConfigError, RemapError, RenderError
from ..data.scene import ProbeScene
from ..data.schemas import Native, Value
from ..data.textures import Texture, TextureMap
from .model import Model


@dataclass(frozen=True)
class ModelChoice:
    model: str
    fix: dict[str, Value]
    why: str


class Adapter(abc.ABC):
    """Base class for renderer adapters.

    Class attributes are read without constructing the adapter (so listing adapters imports
    no renderer); the constructor may import the renderer and start workers.
    """

    name: ClassVar[str]
    version: ClassVar[str] = "1"
    """This adapter's own version: bump it when a change would change its renders (it is part of
    every job's key, so stored results made with the old renders are redone)."""
    summary: ClassVar[str] = ""
    install_hint: ClassVar[str] = ""
    models: ClassVar[dict[str, Model]] = {}
    """Its models by name, each one object (`core.host.model.Model`: parameters, conversions, and
    what the adapter adds, its native form); the protocol's methods are passed one of them."""
    light_types: ClassVar[frozenset[str]] = frozenset({"point"})
    """The light types of `core.data.scene` this adapter realises, in the same units and orientation
    as every other (its calibration tests cover each)."""
    textures: ClassVar[bool] = False
    """Whether it renders textures (`render_textured`) and writes them into its native files, for the
    parameters each model lists as `texturable`."""
    natives: ClassVar[bool] = False
    """Whether it renders a material from its own file as written (`render_native`: a .blend's node
    tree, whatever a reader makes of it)."""
    native_lobes: ClassVar[bool] = False
    """Whether `render_native` renders the lobes of any material apart (Cycles' render passes); else a
    source rendered as written is fitted in one stage."""
    fixed_scenes: ClassVar[bool] = False
    """Whether it renders only the scenes it was given (a source of images: `core.images`): its fit runs on
    the job's scene as given, and a held-out condition it has no image of is unchecked."""
    calibration: ClassVar[tuple[str, dict] | None] = None
    """A white diffuse material of albedo 0.8 (model, params), which `remap check` renders against
    the analytic radiance; None: the adapter has none to offer."""
    glasses: ClassVar[dict[str, tuple[str, dict]]] = {}
    """Clear glasses of IOR 1.5 (model, params) by kind: "smooth" (perfectly smooth), "rough" (GGX,
    α 0.1). An adapter that declares them renders light through a sphere (`ModelSpec.transmits`);
    `remap check` and the verdict compare them with another adapter's."""
    mirror: ClassVar[tuple[str, dict] | None] = None
    """A perfect mirror (model, params): reflectance 1 at every angle, perfectly smooth (a conductor of a purely
    imaginary IOR, or a white metal of roughness 0), which `remap check` renders under the studio environment
    against its analytic image: the specular path (reflection directions, the environment as reflected, its
    scale), whose fault a fit would read as the model's. None: the adapter offers none (with an environment
    light, its glossy row is not run)."""
    transmission_limit: ClassVar[str] = ""
    """What keeps this renderer's light through a sphere from being a path tracer's, where it is a
    property of the renderer rather than a fault to fix (a real-time renderer's screen-space
    transmission): `remap check` says it where the glass check fails, instead of advice for a path
    tracer. Empty: none."""
    dielectrics: ClassVar[dict[str, tuple[str, dict]]] = {}
    """A glossy grey dielectric by kind: "glossy" (base colour 0.5, GGX α 0.09, IOR 1.5), declared only
    where the adapter's model is the same BRDF as another adapter's (glTF's metallic-roughness: Cycles'
    Principled BSDF, three.js). A glossy dielectric's held-out error is judged beyond how far two
    adapters' glossy dielectrics differ where both declare one, else beyond their white Lambertians."""
    metals: ClassVar[dict[str, tuple[str, dict]]] = {}
    """Aluminium (η 1.66, 0.88, 0.52; k 9.22, 6.27, 4.84) by kind: "smooth" (GGX, α 0.01), "rough"
    (GGX, α 0.09). A metal's held-out error is judged beyond how far two adapters' metals of its
    kind differ, as a dielectric's is beyond their white Lambertians (`core.job.agreement`)."""

    @classmethod
    def scene_problem(cls, scene: ProbeScene) -> str | None:
        """Why this adapter cannot render ``scene`` (a fact, no advice), or None: checked before
        any render. The default refuses a light type it does not declare. Must be cheap: no renderer import."""
        missing = sorted(scene.light_types() - set(cls.light_types))
        if missing:
            return f"has no {' or '.join(missing)} light (it renders {', '.join(sorted(cls.light_types))} lights)"
        return None

    @classmethod
    def unavailable_reason(cls) -> str | None:
        """Why this adapter cannot run here, or None. Must be cheap: no renderer import."""
        return None

    @classmethod
    def as_model(cls, which: "Model | str") -> Model:
        """One of its models, given as itself or by name (a script or a test names it; the tool
        passes the object). An unknown name is a ConfigError listing the models."""
        if isinstance(which, Model):
            return which
        if which not in cls.models:
            raise ConfigError(f"adapter {cls.name!r} has no model {which!r} (models: {', '.join(sorted(cls.models))})")
        return cls.models[which]

    @abc.abstractmethod
    def render(self, model: Model, params: dict[str, Value], scene: ProbeScene, lobe: str | None = None) -> np.ndarray:
        """Render the probe scene: linear float32 H x W x 3, no tone mapping.

        ``model`` is one of `models` (the shipped adapters also take its name, through `as_model`).
        ``params`` is complete and validated (see ``ModelSpec.complete``). ``lobe`` is None for
        the full material, or "diffuse" / "specular" for that lobe alone."""

    def render_textured(self, model: Model, params: dict[str, Value], maps: dict[str, TextureMap],
                        scene: ProbeScene) -> np.ndarray:
        """Render the probe sphere with some parameters driven by images (``maps``, of `texturable`
        parameters, their values used as they are: no colour conversion), laid over the sphere by
        `core.data.textures`' texture coordinates; the other parameters as ``params`` gives them. Only
        for an adapter whose ``textures`` is true."""
        raise RenderError(f"adapter {self.name!r} does not render textures")

    def render_native(self, native: Native, scene: ProbeScene, lobe: str | None = None,
                      transmissive: bool = False) -> np.ndarray:
        """Render the probe sphere with a material as its own file holds it (``native``: the file, the
        material's name in it), as `render` does a model's; ``lobe`` as `render`'s, where the renderer
        separates lobes of any material (render passes), else a RenderError. Only for an adapter whose
        ``natives`` is true."""
        raise RenderError(f"adapter {self.name!r} does not render a material from its own file")

    def for_native(self, native: Native) -> "Adapter":
        """This adapter as it renders one material of its own file (``native``): itself, or one that
        answers for that material alone (a source of images: its shots decide which scenes it renders,
        its folder's calibration images are its white Lambertian)."""
        return self

    def noise_of(self, scene: ProbeScene) -> float | None:
        """Where a second seed cannot be rendered (a source of images given with one): the relative RMSE two
        renders of ``scene`` would differ by, estimated; None: measured by rendering two seeds."""
        return None

    def native_findings(self) -> list:
        """What a result must say of the material this adapter renders (`for_native`): a source of images
        uncalibrated, or its noise estimated. Findings of `core.data.findings`."""
        return []

    def candidates(self) -> "list[ModelChoice]":
        """The models a material with no reading is fitted to when the user names only this adapter
        (`Material.native` with no model), the most general first, each with why: the first is fitted,
        the others where it comes back a mismatch or unreliable, and the best is kept. Must not render."""
        return []

    def render_batch(self, requests: list[tuple[Model, dict[str, Value], ProbeScene, str | None]]) -> list[np.ndarray]:
        """Several renders (model, params, scene, lobe) at once; an adapter with several workers
        runs them in parallel. The default renders them one after the other."""
        return [self.render(*r) for r in requests]

    @classmethod
    def identity(cls) -> str:
        """What determines this adapter's renders besides a job's inputs, as one string: its
        `version`, and the renderer's version and configuration where those vary between
        machines. Part of every job's key (a renderer upgraded, or a worker configured otherwise,
        gets its results redone). Must be cheap: no renderer import."""
        return cls.version

    @classmethod
    def environment(cls) -> dict[str, Any]:
        """Facts for `remap adapters` without rendering (version, variant and why). May be slow-ish."""
        return {}

    def describe(self) -> dict[str, Any]:
        """Runtime facts for reports (renderer version, variant, device)."""
        return {}

    def model_for(self, appearance: Appearance) -> "ModelChoice | None":
        """The model a material of this appearance converts to when the user names only this
        adapter (`remap convert --to ADAPTER`), with the choices to hold (a distribution the
        source has) and why, in words; None: no choice without a model named. Must not render."""
        return None

    def alternatives(self, appearance: Appearance) -> "list[ModelChoice]":
        """Other models than `model_for`'s choice that may follow a material of this appearance
        closer, best first, each with why in words: fitted too where the first choice comes back a
        mismatch or unreliable (`remap convert`), and the best result kept. Must not render."""
        return []

    def write_native(self, model: Model, params: dict[str, Value], out_dir: Path,
                     textures: dict[str, Texture] | None = None) -> list[Path]:
        """Write the material in the renderer's own form; return the files written. ``textures``
        (an adapter whose ``textures`` is true): parameters read from images already in ``out_dir``
        (their `file` a name there), referenced by the material as relative paths."""
        return []

    def close(self) -> None:
        """Release workers and renderer state."""

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def plugin_call(fn: Callable[..., Any], who: str, *args: Any) -> Any:
    """``fn(*args)``, a plugin's own code: an error of the tool's kind passes as it is, any other
    exception (a bug in the plugin, its renderer's own error type) becomes a RenderError naming the
    adapter, one line instead of a traceback."""
    try:
        return fn(*args)
    except RemapError:
        raise
    except Exception as exc:
        first = (str(exc).strip().splitlines() or [""])[0]
        raise RenderError(f"{who}: its render raised {type(exc).__name__}{': ' + first if first else ''} (raise "
                          "brdfremap.core.RenderError with a message for a failure it knows)") from exc


def check_image(img: Any, scene: ProbeScene, who: str) -> np.ndarray:
    """Enforce the contract on an adapter's output; a bad image is a RenderError, never a bad fit."""
    arr = np.asarray(img)
    want = (scene.resolution, scene.resolution, 3)
    if arr.shape != want:
        raise RenderError(f"{who}: image has shape {arr.shape}, expected {want}")
    arr = arr.astype(np.float32, copy=False)
    if not np.isfinite(arr).all():
        bad = int((~np.isfinite(arr)).sum())
        raise RenderError(f"{who}: image has {bad} NaN or Inf values")
    return arr

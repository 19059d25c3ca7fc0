"""The renders of one remap, from two adapters: every image checked, cached and counted.

`ProbeRenders` is what the engine asks for (`core.engine.Renders`): the problem at a
resolution and sampling (the target's render function there, the source's images), the
render noise of each side, and what the target renderer does to fitted values."""

from __future__ import annotations

import collections
from typing import Any

import numpy as np

from ..data.account import purpose
from ..data.appearance import Appearance
from ..data.metrics import relative_rmse
from ..data.scene import Lighting, ProbeScene
from ..data.schemas import Lobe, Native, Value
from ..host.model import Model
from ..engine.levels import Level
from ..engine.results import Agreement, Validation
from ..engine.schedule import highlight_pixels
from ..host.protocol import Adapter, check_image, plugin_call
from .agreement import agreement, reference_kind
from .cache import RenderCache, render_key
from .validation import held_out_scenes, point_resolution, validate


def _round(v: Value) -> Value:
    if isinstance(v, tuple):
        return tuple(float(f"{x:.9g}") for x in v)
    if isinstance(v, float):
        return float(f"{v:.9g}")
    return v


def rounded(params: dict[str, Value]) -> dict[str, Value]:
    """Parameters as the cache keys and reports write them (9 significant digits)."""
    return {k: _round(v) for k, v in params.items()}


def _first_view(scene: ProbeScene) -> str:
    """The key of a scene's first view: its lights, camera, size and samples."""
    return scene.view_scenes()[0].cache_key()


class CachedRenderer:
    """One adapter's model, rendered through a cache; ``cache.misses`` counts real renders."""

    @classmethod
    def source(cls, adapter: Adapter, name: str, model: Model, scene: ProbeScene,
               native: Native | None) -> "CachedRenderer":
        """A job's source: its model's renders, or its own file's (`NativeRenderer`)."""
        return cls(adapter, name, model, scene) if native is None else NativeRenderer(adapter, name, model, scene,
                                                                                      native)

    def __init__(self, adapter: Adapter, name: str, model: Model, scene: ProbeScene):
        self.adapter, self.name, self.model, self.scene = adapter, name, model, scene
        self.cache = RenderCache()
        self.by_resolution: collections.Counter[tuple[int, int]] = collections.Counter()  # (resolution, spp)
        self.who = f"adapter {name!r} model {model.name!r}"

    def _key(self, params: dict[str, Value], lobe: str | None, scene: ProbeScene) -> str:
        return render_key(self.name, self.model.name, rounded(params), scene.cache_key(), lobe)

    def __call__(self, params: dict[str, Value], lobe: str | None = None, scene: ProbeScene | None = None):
        sc = scene or self.scene
        if sc.views:  # each view rendered (and cached) alone, stacked top to bottom
            return np.concatenate([self(params, lobe, view) for view in sc.view_scenes()], axis=0)

        def render():
            self.by_resolution[sc.resolution, sc.spp] += 1
            return check_image(self._render(params, lobe, sc), sc, self.who)

        return self.cache.get_or_render(self._key(params, lobe, sc), render)

    def _render(self, params: dict[str, Value], lobe: str | None, scene: ProbeScene) -> np.ndarray:
        return plugin_call(self.adapter.render, self.who, self.model, dict(params), scene, lobe)

    separates_lobes = True
    """Whether it renders the lobes its source model declares (`ModelSpec.lobes`) apart."""

    def many(self, items: list[tuple[dict[str, Value], str | None]], scene: ProbeScene | None = None) -> None:
        """Render the uncached ones of several requests in one batch (in parallel where the adapter can)."""
        sc = scene or self.scene
        if sc.views:
            for view in sc.view_scenes():
                self.many(items, view)
            return
        todo, seen = [], set()
        for params, lobe in items:
            key = self._key(params, lobe, sc)
            if key not in self.cache and key not in seen:
                seen.add(key)
                todo.append((key, params, lobe))
        if len(todo) < 2:
            return
        requests = [(self.model, dict(p), sc, lobe) for _, p, lobe in todo]
        images = plugin_call(self.adapter.render_batch, self.who, requests)
        for (key, _, _), img in zip(todo, images):
            self.by_resolution[sc.resolution, sc.spp] += 1
            checked = check_image(img, sc, self.who)
            self.cache.get_or_render(key, lambda: checked)

    def renders_by_resolution(self) -> dict[str, int]:
        """Renders by "32px", "128px" (the scene's samples) and e.g. "128px@64spp" (more samples)."""
        spp = self.scene.spp
        return {f"{res}px" + ("" if n == spp else f"@{n}spp"): v for (res, n), v in sorted(self.by_resolution.items())}


class NativeRenderer(CachedRenderer):
    """A source material rendered from its own file as written (`Material.native`), through a cache:
    ``params`` are its reading's and change nothing of the image (the transmission of `AS_WRITTEN`
    decides the paths traced)."""

    def __init__(self, adapter: Adapter, name: str, model: Model, scene: ProbeScene, native: Native):
        super().__init__(adapter, name, model, scene)
        self.native = native
        self.who = f"adapter {name!r} material {native.name!r} of {native.file}"

    def _key(self, params: dict[str, Value], lobe: str | None, scene: ProbeScene) -> str:
        return render_key(self.name, f"native:{self.native.sha256}", {"material": self.native.name},
                          scene.cache_key(), lobe)

    def _render(self, params: dict[str, Value], lobe: str | None, scene: ProbeScene) -> np.ndarray:
        transmissive = self.native.transmits or self.model.transmissive(params)
        return plugin_call(self.adapter.render_native, self.who, self.native, scene, lobe, transmissive)

    def many(self, items, scene=None) -> None:
        """One at a time (a material of a file is rendered by the adapter's own worker)."""

    @property
    def separates_lobes(self) -> bool:  # type: ignore[override]
        """Where the adapter tells any material's lobes apart (`Adapter.native_lobes`: Cycles' render
        passes); else none (the fit is one stage)."""
        return bool(getattr(self.adapter, "native_lobes", False))


class _AtScene:
    """The target at one scene, as the engine calls it: render(params, lobe), and many(...)."""

    def __init__(self, target: CachedRenderer, scene: ProbeScene):
        self.target, self.scene = target, scene

    def __call__(self, params: dict[str, Value], lobe: str | None = None) -> np.ndarray:
        return self.target(params, lobe, scene=self.scene)

    def many(self, items: list[tuple[dict[str, Value], str | None]]) -> None:
        self.target.many(items, scene=self.scene)


class ProbeRenders:
    """`core.engine.Renders` for a source material and a target model."""

    def __init__(self, source: CachedRenderer, source_params: dict[str, Value], source_spec: Model,
                 target: CachedRenderer, scene: ProbeScene, given: ProbeScene | None = None,
                 given_noise: float = 0.0, resolve_limit: float | None = None, sharp: bool = False,
                 look: Appearance | None | type[Ellipsis] = ..., transmits: bool | None = None):
        self.source, self.source_params, self.source_spec = source, dict(source_params), source_spec
        self.transmits = transmits if transmits is not None else \
            source_spec is not None and source_spec.transmissive(self.source_params)
        """Whether light passes through the source (`Resolved.source_transmits`)."""
        if look is ...:  # not given: read here (a job passes `Resolved.look`, read once)
            look = None if source_spec is None else source_spec.appearance(self.source_params)
        self.look = look
        """The source's neutral reading (`Resolved.look`): which reference material the renderers' floor
        is measured on."""
        self.target, self.scene = target, scene
        self.job_scene = given if given is not None else scene
        """The job's scene: the held-out lights take its camera, size and samples."""
        self.sharp = sharp
        """The fit ran with the job's point light as a disc (`core.job.fitscene`): the held-out point
        lights are discs too, and the job's own (which cannot resolve the source) are not checked."""
        self.other_lights = not sharp and _first_view(self.job_scene.with_(spp=scene.spp)) != _first_view(scene)
        """The fit ran under other lights than the job's (`core.job.fitscene`): those are checked too.
        (A fit at more samples of the same lights, or with a back light's view added below them,
        measured the job's scene already.)"""
        self.given_noise = given_noise
        """Two source renders' difference on the job's scene, measured before the fit."""
        self.resolve_limit = resolve_limit
        """A held-out condition noisier than this is rendered again at more samples where they can resolve it."""
        self._levels: dict[tuple[str, bool], Level] = {}
        self._noise: float | None = None

    def level(self, scene: ProbeScene, lobes: bool = True) -> Level:
        key = (scene.cache_key(), lobes)
        if key not in self._levels:
            with purpose("source"):
                full, found = self._source_images(scene, lobes)
            self._levels[key] = Level(_AtScene(self.target, scene), full, found, scene.spp)
        return self._levels[key]

    def _source_images(self, scene: ProbeScene, lobes: bool) -> tuple[np.ndarray, dict[str, Any]]:
        """The source's full image and its lobes (None: cannot isolate; zeros: has no such lobe).
        The lobes come first: an adapter whose render yields every lobe at once (Cycles' passes)
        then serves the full image from it, where a full image alone is rendered without them."""
        if not lobes:
            return self.source(self.source_params, scene=scene), {}
        specs = {lobe: self.source_spec.lobes.get(lobe) if self.source.separates_lobes else None for lobe in Lobe}
        rendered = {lobe: self.source(self.source_params, lobe, scene=scene)
                    for lobe, spec in specs.items() if spec is not None and not spec.empty}
        full = self.source(self.source_params, scene=scene)
        found = {lobe: None if spec is None else np.zeros_like(full) if spec.empty else rendered[lobe]
                 for lobe, spec in specs.items()}
        return full, found

    def source_image(self) -> np.ndarray:
        return self.level(self.scene).source

    def source_noise(self) -> float:
        if self._noise is None:
            with purpose("source"):
                second = self.source(self.source_params, scene=self.scene.with_(seed=self.scene.seed + 1))
                estimate = self.source.adapter.noise_of(self.scene)  # one image given: no second seed
                self._noise = relative_rmse(self.source_image(), second) if estimate is None else estimate
        return self._noise

    def scene_chosen(self) -> bool:
        """Whether the fit's scene was chosen for the source (more samples, the studio); a back light's
        view added below the job's scene is not such a choice."""
        return _first_view(self.scene) != _first_view(self.job_scene)

    def target_noise(self, params: dict[str, Value]) -> float:
        first = self.target(params, scene=self.scene)
        return relative_rmse(first, self.target(params, scene=self.scene.with_(seed=self.scene.seed + 1)))

    def validation(self, params: dict[str, Value]) -> Validation:
        """Source and target under the held-out conditions (`core.job.validation`), through the caches."""

        def problems(scene: ProbeScene) -> str | None:
            for side in (self.source, self.target):
                why = side.adapter.scene_problem(scene)
                if why:  # of its type (`core.data.findings.Unrendered`: the condition is then unchecked)
                    return type(why)(f"adapter {side.name!r} {why}")
            return None

        # Held-out lights take the job's scene (its camera, size and samples), not a fit scene made
        # finer for a sharp source: their samples follow what the user asked for.
        return validate(lambda sc: self.source(self.source_params, scene=sc), lambda sc: self.target(params, scene=sc),
                        self.job_scene, problems, given=self.other_lights,
                        given_noise=self.given_noise, fit_lights=self.scene.view_scenes()[0].lights,
                        resolution=self.point_resolution(), sharp=self.sharp, transmissive=self.transmits,
                        # A source of images has the samples it was given: more of the target's resolve nothing.
                        resolve_limit=None if self.source.adapter.fixed_scenes else self.resolve_limit,
                        source_noise=self.source.adapter.noise_of)

    def held_out(self) -> list[tuple[str, str, ProbeScene]]:
        """Every held-out condition of this job (`core.job.validation.held_out_scenes`) the target renders:
        (name, label, its first scene)."""
        found = held_out_scenes(self.job_scene, self.other_lights, self.scene.view_scenes()[0].lights,
                                self.point_resolution(), self.sharp, self.transmits)
        return [(c.name, c.label, a) for c, a, _ in found if not self.target.adapter.scene_problem(a)]

    def target_at(self, params: dict[str, Value], scene: ProbeScene) -> np.ndarray:
        return self.target(params, scene=scene)

    def point_resolution(self) -> int:
        """The frontal point-light conditions' resolution, from the source's highlight (its specular
        lobe where it isolates one) on the job's scene (`core.job.validation.point_resolution`); the
        scene's when the fit ran elsewhere, the job's lights are not point lights, or the source
        lets light through."""
        if self.other_lights or self.job_scene.views or self.job_scene.environment is not None \
                or self.transmits:
            return self.job_scene.resolution
        level = self.level(self.scene)
        spec = level.source_lobes.get("specular")  # a plastic's highlight, not its diffuse shading
        image = (spec if spec is not None and float(np.max(spec)) > 0 else level.source)[:self.scene.resolution]
        px = highlight_pixels(image) * (self.job_scene.resolution / self.scene.resolution) ** 2
        return point_resolution(self.job_scene, px)

    def agreement(self, params: dict[str, Value], validation: Validation, threshold: float, judged) -> Agreement:
        transmissive = self.transmits or self.target.model.transmissive(params)
        first = self.scene.view_scenes()[0]  # adapters render one view at a time
        fit = (first.with_(seed=first.seed + 2), first.with_(seed=first.seed + 3))
        conditions = [(Lighting.SCENE, "fit scene", fit)] + [
            (c.condition, c.label, validation.scenes[c.condition]) for c in validation.checks]
        kind = reference_kind(self.look)
        return agreement(self.source.adapter, self.target.adapter, transmissive, conditions, threshold, judged, kind)

    def notes(self, params: dict[str, Value]) -> list[str]:
        return list(self.target.model.notes(params))

    def approximations(self, params: dict[str, Value]) -> list[tuple[str, str]]:
        return [("source", d) for d in self.source_spec.approximations(self.source_params)] + \
            [("target", d) for d in self.target.model.approximations(params)]

    def target_renders(self) -> int:
        return self.target.cache.misses

    def source_renders(self) -> int:
        return self.source.cache.misses

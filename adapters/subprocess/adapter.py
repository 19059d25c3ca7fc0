"""Any renderer that runs from a command line, described by a YAML file.

Each render writes the probe scene and the parameters to files, runs the command (an argv
list: placeholders are substituted inside single arguments, never through a shell), and
reads the image it wrote. A persistent renderer is started once and answers JSON lines."""

from __future__ import annotations

import hashlib
import itertools
import importlib.util
import json
import os
import shutil
import signal
import subprocess
import sys
import threading
from pathlib import Path
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import numpy as np
from brdfremap.core.data.errors import ConfigError, RenderError, RenderTimeoutError
from brdfremap.core.data.imageio import HALF_EPS, pixel_format, read_rgb
from brdfremap.core.host.model import Model
from brdfremap.core.protocol import Adapter
from brdfremap.core.data.scene import ProbeScene
from brdfremap.core.data.schemas import Value, format_value
from brdfremap.core.data.scratch import scratch_dir
from brdfremap.core.run.workerproc import JsonLinesWorker, die_with_parent

from .definition import RendererDef, load_definition
from .template import sample_vars, scene_vars, substitute


def which(exe: str) -> str | None:
    """PATH lookup that also searches this Python's bin folder (a venv's console scripts,
    such as `mitsuba`, are there even when the venv is not activated)."""
    path = os.environ.get("PATH", "") + os.pathsep + str(Path(sys.executable).parent)
    return shutil.which(exe, path=path)


def _kill_group(proc: subprocess.Popen) -> None:
    try:
        os.killpg(proc.pid, signal.SIGKILL)  # the whole group: the renderer's helpers too
    except (ProcessLookupError, PermissionError):
        pass


def _srgb_to_linear(x: np.ndarray) -> np.ndarray:
    return np.where(x <= 0.04045, x / 12.92, ((x + 0.055) / 1.055) ** 2.4).astype(np.float32)


class SubprocessAdapter(Adapter):
    """Base of the classes made by ``adapter_class`` for each YAML definition."""

    definition: RendererDef
    source_file: Path

    @classmethod
    def scene_problem(cls, scene: ProbeScene) -> str | None:
        """A command-line renderer gets one point light (its ``{light_*}`` placeholders)."""
        problem = super().scene_problem(scene)
        if problem is None and any(len(v.lights) > 1 for v in scene.all_views()):
            return "takes one point light per view (its {light_*} placeholders)"
        return problem

    @classmethod
    def unavailable_reason(cls) -> str | None:
        d = cls.definition
        for req in d.requires:
            kind, colon, module = req.partition(":")
            if colon and kind == "py":
                if importlib.util.find_spec(module) is None:
                    return f"Python module {module!r} is not installed"
            elif which(req) is None:
                return f"executable {req!r} not found on PATH"
        exe = d.command[0]
        if "{" not in exe and which(exe) is None and not (cls.source_file.parent / exe).exists():
            return f"executable {exe!r} not found on PATH"
        return None

    def __init__(self) -> None:
        d = self.definition
        self.here = str(self.source_file.parent.resolve())
        self.template = None
        if d.scene_template:
            tpath = self.source_file.parent / d.scene_template
            try:
                self.template = tpath.read_text(encoding="utf-8")
            except OSError as exc:
                raise ConfigError(f"cannot read the scene template: {exc}", file=str(self.source_file),
                                  field="scene_template") from exc
        self.work = scratch_dir(f"external-{d.name}")
        self.env = {**os.environ, **d.env}
        self.worker = None
        if d.mode == "persistent":
            argv = [substitute(a, {"python": sys.executable, "here": self.here}, "command") for a in d.command]
            argv[0] = which(argv[0]) or argv[0]
            self.worker = JsonLinesWorker(argv, name=f"renderer {d.name!r}", env=self.env, cwd=self.here,
                                          start_timeout=d.start_timeout, request_timeout=d.timeout)
        self._ids = itertools.count(1)
        self._running: set[subprocess.Popen] = set()
        self._lock = threading.Lock()
        self._stopping = threading.Event()
        self.warned_depth = False

    def describe(self) -> dict[str, Any]:
        return {"renderer": f"external: {self.definition.name}", "definition": str(self.source_file),
                "mode": self.definition.mode}

    # -- one render ------------------------------------------------------------------
    def _value(self, v: Value) -> str:
        if isinstance(v, tuple):
            return self.definition.rgb_format.format(r=f"{v[0]:.9g}", g=f"{v[1]:.9g}", b=f"{v[2]:.9g}")
        return v if isinstance(v, str) else f"{v:.9g}"

    def _fail(self, model, params, what: str, stderr: str = "", timed_out: float | None = None) -> RenderError:
        """The error naming the renderer, the material and the renderer's last words; a
        `RenderTimeoutError` when the render was stopped after ``timed_out`` seconds."""
        shown = ", ".join(f"{k}={format_value(v)}" for k, v in params.items())
        tail = "".join(f"\n  stderr: {line}" for line in stderr.strip().splitlines()[-8:])
        message = f"renderer {self.definition.name!r} ({model}: {shown}): {what}{tail}"
        return RenderError(message) if timed_out is None else RenderTimeoutError(message, seconds=timed_out)

    def render(self, model: Model | str, params: dict[str, Value], scene: ProbeScene,
               lobe: str | None = None) -> np.ndarray:
        model = self.as_model(model).name  # the definition's models and its files name it
        d = self.definition
        p = self.models[model].with_lobe(params, lobe)
        job = self.work / f"r{next(self._ids)}"
        try:
            job.mkdir()
            output = job / f"image.{d.output_format}"
            values = self._request_files(model, p, scene, job, output)
            stderr = ""
            if self.worker is not None:
                request = {"op": "render", "model": model,
                           "params": {k: list(v) if isinstance(v, tuple) else v for k, v in p.items()},
                           "scene": scene.document(), "output": str(output)}
                try:
                    self.worker.request(request)
                except RenderError as exc:
                    seconds = exc.seconds if isinstance(exc, RenderTimeoutError) else None  # a timeout stays typed
                    raise self._fail(model, p, exc.message, timed_out=seconds) from None
            else:
                stderr = self._run_once(model, p, values)
            return self._read(model, p, output, scene, stderr)
        except OSError as exc:  # the scratch folder's filesystem is full, or gone
            raise self._fail(model, p, f"cannot write its request files in {self.work}: {exc.strerror or exc}") \
                from None
        finally:
            shutil.rmtree(job, ignore_errors=True)

    def render_batch(self, requests):
        """One-shot renders run ``jobs`` at once (a renderer waiting on its files or its start-up
        leaves the cores idle); a persistent renderer answers one at a time."""
        jobs = min(len(requests), self.definition.jobs or os.cpu_count() or 1)
        if self.worker is not None or jobs < 2:
            return super().render_batch(requests)
        pool = ThreadPoolExecutor(max_workers=jobs, thread_name_prefix=f"render-{self.definition.name}")
        self._stopping.clear()
        try:
            return list(pool.map(lambda r: self.render(*r), requests))
        except BaseException:  # a failed render, Ctrl-C: nothing new starts, the others' process groups go
            self._stopping.set()
            pool.shutdown(wait=False, cancel_futures=True)
            with self._lock:
                running = list(self._running)
            for proc in running:
                _kill_group(proc)
            raise
        finally:
            pool.shutdown(wait=True, cancel_futures=True)
            self._stopping.clear()

    def write_native(self, model: Model | str, params: dict[str, Value], out_dir: Path) -> list[Path]:
        """The model's `native:` text with the fitted values, when the definition gives one."""
        model = self.as_model(model).name
        native = self.definition.models[model].native
        if native is None:
            return []
        values = {"model": model, **{f"p_{k}": self._value(v) for k, v in params.items()}}
        path = Path(out_dir) / native.file
        path.write_text(substitute(native.text, values, f"models.{model}.native.text"), encoding="utf-8")
        return [path]

    def _request_files(self, model: str, p: dict[str, Value], scene: ProbeScene, job: Path,
                       output: Path) -> dict[str, str]:
        """Write the scene and parameters (and the filled scene template) for one render; return
        the placeholders' values."""
        d = self.definition
        scene_json, params_json = job / "scene.json", job / "params.json"
        scene_json.write_text(json.dumps(scene.document(), indent=1))
        params_json.write_text(json.dumps({"model": model, "params": {
            k: list(v) if isinstance(v, tuple) else v for k, v in p.items()}}, indent=1))
        values = {"scene_json": str(scene_json), "params_json": str(params_json), "output": str(output),
                  "model": model, "width": str(scene.resolution), "height": str(scene.resolution),
                  **sample_vars(scene.spp), "seed": str(scene.seed), "python": sys.executable, "here": self.here}
        if self.template is not None:
            tvars = {**scene_vars(scene), "model": model, **{f"p_{k}": self._value(v) for k, v in p.items()}}
            tvars.update({k: substitute(text, tvars, f"models.{model}.template_vars.{k}")
                          for k, text in d.models[model].template_vars.items()})
            scene_file = job / f"scene{Path(d.scene_template).suffix}"
            scene_file.write_text(substitute(self.template, tvars, f"scene_template {d.scene_template}"))
            values["scene_file"] = str(scene_file)
        return values

    def _argv(self, p: dict[str, Value], values: dict[str, str]) -> list[str]:
        argv: list[str] = []
        for arg in self.definition.command:
            if arg == "{defines}":
                for k, v in p.items():
                    argv += [t.replace("{key}", k).replace("{value}", self._value(v)) for t in self.definition.define]
            else:
                argv.append(substitute(arg, values, "command"))
        found = which(argv[0])
        if found:
            argv[0] = found
        return argv

    def _start(self, model, p, argv: list[str]) -> subprocess.Popen:
        try:
            return subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                    text=True, env=self.env, cwd=self.here, start_new_session=True,
                                    preexec_fn=die_with_parent)
        except OSError as exc:
            raise self._fail(model, p, f"cannot run {argv[0]!r}: {exc}") from None

    def _run_once(self, model, p, values) -> str:
        argv = self._argv(p, values)
        with self._lock:  # started and registered together, or not at all once a batch is stopping
            if self._stopping.is_set():
                raise self._fail(model, p, "not started: another render of its batch failed")
            proc = self._start(model, p, argv)
            self._running.add(proc)
        try:
            out, err = proc.communicate(timeout=self.definition.timeout)
        except subprocess.TimeoutExpired:
            _kill_group(proc)
            out, err = proc.communicate()
            raise self._fail(model, p, f"timed out after {self.definition.timeout:g} s (process group killed)",
                             err or out, timed_out=self.definition.timeout) from None
        except BaseException:  # Ctrl-C, SIGTERM: the renderer (and its helpers) stop with remap
            _kill_group(proc)
            proc.communicate()
            raise
        finally:
            with self._lock:
                self._running.discard(proc)
        if proc.returncode != 0:
            raise self._fail(model, p, f"exit code {proc.returncode}", err or out)
        return err or out

    def _read(self, model, p, output: Path, scene: ProbeScene, stderr: str) -> np.ndarray:
        if not output.exists() or output.stat().st_size == 0:
            raise self._fail(model, p, f"wrote no image at {output.name}{_what_it_wrote(output)}", stderr)
        self._check_depth(output)
        pixels, why, nch = read_rgb(output)
        if pixels is None and 0 < nch < 3:
            raise self._fail(model, p, f"image has {nch} channels, need RGB", stderr)
        if pixels is None:
            what = "unreadable image" if nch == 0 else "truncated or corrupt image"
            raise self._fail(model, p, f"{what}: {why}", stderr)
        img = np.asarray(pixels, dtype=np.float32)
        want = (scene.resolution, scene.resolution)
        if img.shape[:2] != want:
            raise self._fail(model, p, f"image is {img.shape[1]}x{img.shape[0]}, expected {want[1]}x{want[0]}", stderr)
        if not np.isfinite(img).all():
            raise self._fail(model, p, f"image has {int((~np.isfinite(img)).sum())} NaN or Inf values", stderr)
        if self.definition.output_format == "png":
            img = _srgb_to_linear(img)  # an 8-bit PNG is display-encoded
        return img

    def _check_depth(self, output: Path) -> None:
        """Say once if a float format stores too few bits: a finite difference of a fraction of a
        percent, and a lobe sum, are lost in rounding (8-bit PNG is display-encoded, and known)."""
        fmt = pixel_format(output)
        if self.definition.output_format == "png" or fmt in ("float", "double", ""):
            return
        with self._lock:
            if self.warned_depth:
                return
            self.warned_depth = True
        print(f"note: renderer {self.definition.name!r} writes {fmt} pixels to {output.suffix}: they round at "
              f"{HALF_EPS:.2%}, far below the render noise and a fit's steps, so they serve; 32-bit float, where "
              "the renderer can write it, leaves nothing to round", file=sys.stderr)

    def close(self) -> None:
        if self.worker is not None:
            self.worker.close()
        shutil.rmtree(self.work, ignore_errors=True)


_REQUEST_FILES = ("scene.json", "params.json")


def _what_it_wrote(output: Path) -> str:
    """The files the renderer did write beside the expected image, if any (image.exr.png)."""
    try:
        found = sorted(f.name for f in output.parent.iterdir()
                       if f.name not in _REQUEST_FILES and f.name.partition(".")[:2] != ("scene", "."))
    except OSError:
        return ""
    return f" (it wrote: {', '.join(found[:8])})" if found else " (it wrote no file there)"


def adapter_class(path: str | Path) -> type[SubprocessAdapter]:
    """A new adapter class for one YAML definition (validated now, run later)."""
    path = Path(path)
    d = load_definition(path)
    return type(f"External_{d.name}", (SubprocessAdapter,), {
        "name": d.name, "definition": d, "source_file": path, "models": d.model_specs(),
        "version": _version(path, d),
        "summary": d.description or f"external renderer ({d.mode}) from {path}",
        "install_hint": f"see {path}",
        "calibration": (d.calibration.model, dict(d.calibration.params)) if d.calibration else None,
    })


def _version(path: Path, d: RendererDef) -> str:
    """The definition's own content (and its scene template's): a job's key changes with them."""
    h = hashlib.sha256(path.read_bytes())
    if d.scene_template:
        try:
            h.update((path.parent / d.scene_template).read_bytes())
        except OSError:
            pass  # reported when the adapter is constructed
    return h.hexdigest()[:12]


def search_dirs() -> list[Path]:
    dirs = [Path(p) for p in os.environ.get("BRDFREMAP_RENDERERS", "").split(os.pathsep) if p]
    # Not the current folder: a downloaded bundle (materials and a configs/renderers beside them)
    # must not be able to choose the program a remap runs.
    dirs += [Path.home() / ".config" / "brdfremap" / "renderers"]
    return [d for d in dict.fromkeys(dirs) if d.is_dir()]


def broken_definition(path: Path, error: str) -> type[Adapter]:
    """A stand-in for a definition file that does not validate: `remap adapters` lists it
    as unavailable with the error, and choosing it reports the same."""

    class Broken(Adapter):
        name = Path(path).stem
        summary = f"external renderer definition {path}"
        install_hint = f"fix {path}"
        models: dict = {}

        @classmethod
        def unavailable_reason(cls) -> str | None:
            return f"invalid definition: {error}"

        def render(self, model, params, scene, lobe=None):  # pragma: no cover - never constructed
            raise RenderError(error)

    return Broken

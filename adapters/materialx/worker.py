"""The MaterialX renderer's worker: MaterialX's own GLSL shader generator and renderer
(`PyMaterialXGenGlsl`, `PyMaterialXRenderGlsl.GlslRenderer`) on a virtual display of its own, serving
render requests as JSON lines.

Run as ``python -m brdfremap.adapters.materialx.worker``: on Linux it starts an X server (Xvfb) on a free
display that dies with it and opens an OpenGL context there (Mesa's llvmpipe: the CPU; elsewhere the
system's own); it answers one JSON line per request and exits when stdin closes. Requests:
``{"op": "render", "document", "shader", "values", "sphere", "resolution", "views", "out"}``: the first
material of a MaterialX document (XML text) on the probe sphere, one image per view stacked downwards,
written to ``out`` as raw float32 RGB; ``values`` sets the shader node's inputs as uniforms (a new
document generates and compiles a shader once; another value of an input does not);
an environment light names its maps (float32 ``.npy`` files: radiance, and irradiance over π), loaded
the first time its ``key`` is seen; ``{"op": "ping"}``, ``{"op": "quit"}``.

Knows no material model: the adapter writes the document and names the values."""

from __future__ import annotations

import ctypes
import json
import math
import os
import shutil
import subprocess
import sys
import traceback
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
MAX_LIGHTS = 16
"""The most point lights a view holds (a scene's limit, `core.data.scene.MAX_LIGHTS`)."""


def start_display(scratch: Path) -> subprocess.Popen | None:
    """On Linux an X server of our own on a free display (``-displayfd``), killed with this process, and
    DISPLAY set to it; elsewhere None (MaterialX's renderer opens a hidden window of the system's own)."""
    from brdfremap.core.run.workerproc import die_with_parent

    if not sys.platform.startswith("linux"):
        return None
    read, write = os.pipe()
    log = open(scratch / "xvfb.log", "wb")
    try:
        server = subprocess.Popen(["Xvfb", "-displayfd", str(write), "-screen", "0", "64x64x24", "-nolisten", "tcp",
                                   "-noreset"], pass_fds=(write,), stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                  stderr=log, preexec_fn=die_with_parent)
    except FileNotFoundError:
        raise RuntimeError("Xvfb is not installed (apt-get install xvfb)") from None
    finally:
        log.close()
        os.close(write)
    with os.fdopen(read) as f:
        number = f.readline().strip()
    if not number:
        said = (scratch / "xvfb.log").read_text(errors="replace").strip().splitlines()
        raise RuntimeError(f"Xvfb did not start{': ' + said[-1] if said else ''}")
    os.environ["DISPLAY"] = f":{number}"
    return server


def stop_display(server: subprocess.Popen | None) -> None:
    """The X server ended as it ends itself (its lock and socket files removed), killed if it will not."""
    if server is None:
        return
    server.terminate()
    try:
        server.wait(timeout=5)
    except subprocess.TimeoutExpired:
        server.kill()


def sphere_obj(path: Path) -> None:
    """The probe's unit sphere (`core.data.sphere`: its texture coordinates and latitudes) as an OBJ file;
    the renderer's world matrix places and scales it."""
    from brdfremap.core.data.sphere import sphere_mesh

    m = sphere_mesh(rings=128, segments=256)
    lines = [f"v {x:.7f} {y:.7f} {z:.7f}" for x, y, z in m["POSITION"]]
    lines += [f"vn {x:.7f} {y:.7f} {z:.7f}" for x, y, z in m["NORMAL"]]
    lines += [f"vt {u:.7f} {1.0 - v:.7f}" for u, v in m["TEXCOORD_0"]]  # OBJ's v runs up
    idx = m["indices"].astype(np.int64).reshape(-1, 3) + 1
    lines += [f"f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}" for a, b, c in idx]
    path.write_text("\n".join(lines) + "\n")


class Renderer:
    """One GlslRenderer, its lights, its environments and the program of the last document."""

    def __init__(self, scratch: Path):
        import MaterialX as mx
        import MaterialX.PyMaterialXGenGlsl as mx_glsl
        import MaterialX.PyMaterialXGenShader as mx_gen
        import MaterialX.PyMaterialXRender as mx_render
        import MaterialX.PyMaterialXRenderGlsl as mx_rglsl

        self.mx, self.mx_gen, self.mx_render = mx, mx_gen, mx_render
        self.search = mx.getDefaultDataSearchPath()
        self.search.append(mx.FilePath(str(HERE)))
        self.lib = mx.createDocument()
        mx.loadLibraries(mx.getDefaultDataLibraryFolders(), mx.getDefaultDataSearchPath(), self.lib)
        self.lib.getImplementation("IM_point_light_genglsl").setFile("glsl/mx_point_light.glsl")
        self.gen = mx_glsl.GlslShaderGenerator.create()
        cms = mx_gen.DefaultColorManagementSystem.create(self.gen.getTarget())
        cms.loadLibrary(self.lib)
        self.gen.setColorManagementSystem(cms)
        self.context = self._context()
        self.renderer = mx_rglsl.GlslRenderer.create(16, 16, mx_render.BaseType.FLOAT)
        self.renderer.initialize()
        self.renderer.setImageHandler(mx_rglsl.GLTextureHandler.create(mx_render.StbImageLoader.create()))
        geometry = self.renderer.getGeometryHandler()
        geometry.addLoader(mx_render.TinyObjLoader.create())
        sphere_obj(scratch / "sphere.obj")
        if not geometry.loadGeometry(mx.FilePath(str(scratch / "sphere.obj")), False):
            raise RuntimeError("MaterialX could not load the probe sphere")
        self.lights_doc = mx.createDocument()
        self.lights_doc.importLibrary(self.lib)
        self.lights = [self.lights_doc.addNode("point_light", f"light{i}", "lightshader") for i in range(MAX_LIGHTS)]
        self.handler = mx_render.LightHandler.create()
        self.handler.registerLights(self.lights_doc, self.lights[:1], self.context)
        self.renderer.setLightHandler(self.handler)
        self.environments: dict[str, tuple] = {}
        self.black = self._image(np.zeros((1, 2, 3), np.float32))
        self.program_key: tuple[str, str] | None = None
        self.shader_name = ""
        self.uniforms: set[str] = set()
        self.background: np.ndarray | None = None

    def _context(self):
        ctx = self.mx_gen.GenContext(self.gen)
        ctx.registerSourceCodeSearchPath(self.search)
        opts = ctx.getOptions()
        opts.hwSpecularEnvironmentMethod = self.mx_gen.HwSpecularEnvironmentMethod.SPECULAR_ENVIRONMENT_FIS
        opts.hwMaxActiveLightSources = MAX_LIGHTS
        opts.targetColorSpaceOverride = "lin_rec709"
        opts.fileTextureVerticalFlip = True
        return ctx

    def _image(self, px: np.ndarray):
        """A MaterialX image holding these float32 RGB pixels (top row first)."""
        h, w, _ = px.shape
        img = self.mx_render.Image.create(w, h, 3, self.mx_render.BaseType.FLOAT)
        img.createResourceBuffer()
        buf = np.ctypeslib.as_array((ctypes.c_float * (w * h * 3)).from_address(img.getResourceBuffer()))
        buf[:] = np.ascontiguousarray(px, np.float32).ravel()
        return img

    def environment(self, key: str, radiance: str, irradiance: str) -> None:
        """An environment's radiance and irradiance maps, kept under ``key`` for the worker's life (a
        texture the GL handler keeps by the image's address: a freed image's address reused would show
        the old texture)."""
        if key not in self.environments:
            self.environments[key] = (self._image(np.load(radiance)), self._image(np.load(irradiance)))

    def program(self, document: str, shader: str) -> None:
        """The program of this document's first material, generated and compiled where it is new; the
        uniforms it declares for its shader node's inputs (`set_values` sets no other)."""
        if (document, shader) == self.program_key:
            return
        mx = self.mx
        doc = mx.createDocument()
        doc.importLibrary(self.lib)
        mx.readFromXmlString(doc, document)
        valid, why = doc.validate()
        if not valid:
            raise ValueError(f"the document is not valid MaterialX: {why.strip().splitlines()[0]}")
        materials = doc.getMaterialNodes()
        if not materials:
            raise ValueError("the document has no material")
        generated = self.gen.generate("brdfremap", materials[0], self.context)
        self.renderer.createProgram(generated)
        self.renderer.validateInputs()
        block = generated.getStage(self.mx_gen.PIXEL_STAGE).getUniformBlock(self.mx_gen.HW_PUBLIC_UNIFORMS)
        self.uniforms = {block[i].getVariable() for i in range(block.size())}
        self.program_key, self.shader_name, self._doc = (document, shader), shader, doc

    def set_values(self, values: dict[str, list[str]]) -> None:
        """Each input's value as its uniform; an input the program does not declare is an error (the
        renderer would ignore it, and the image would silently show the default)."""
        for name, (kind, text) in values.items():
            uniform = f"{self.shader_name}_{name}"
            if uniform not in self.uniforms:
                raise ValueError(f"the shader node {self.shader_name!r} of the document has no input {name!r} "
                                 "(a value for it would change nothing)")
            self.renderer.updateUniform(uniform, self.mx.Value.createValueFromStrings(text, kind))

    def _camera(self, camera: dict, sphere: dict) -> None:
        mx, cam = self.mx, self.renderer.getCamera()
        cam.setViewMatrix(self.mx_render.Camera.createViewMatrix(
            mx.Vector3(*camera["position"]), mx.Vector3(*camera["target"]), mx.Vector3(*camera["up"])))
        near = 0.01 * camera["distance"]
        half = near * math.tan(math.radians(camera["fov"]) / 2.0)
        cam.setProjectionMatrix(self.mx_render.Camera.createPerspectiveMatrix(-half, half, -half, half, near,
                                                                              1000.0 * camera["distance"]))
        r = sphere["radius"]
        cam.setWorldMatrix(mx.Matrix44.createScale(mx.Vector3(r, r, r)) *
                           mx.Matrix44.createTranslation(mx.Vector3(*sphere["center"])))

    def _lights(self, lights: list[dict]) -> None:
        points = [x for x in lights if x["type"] == "point"]
        for node, light in zip(self.lights, points):
            node.setInputValue("position", self.mx.Vector3(*light["position"]))
            node.setInputValue("color", self.mx.Color3(1.0, 1.0, 1.0))
            node.setInputValue("intensity", float(light["intensity"]))
            node.setInputValue("decay_rate", 2.0)
        self.handler.setLightSources(self.lights[:len(points)])
        env = next((x for x in lights if x["type"] == "environment"), None)
        if env is not None:
            self.environment(env["key"], env["radiance"], env["irradiance"])
        radiance, irradiance = self.environments[env["key"]] if env else (self.black, self.black)
        self.handler.setEnvRadianceMap(radiance)
        self.handler.setEnvIrradianceMap(irradiance)
        self.handler.setEnvSampleCount(int(env["samples"]) if env else 1)
        self.handler.setIndirectLighting(env is not None)

    def _capture(self, size: int) -> np.ndarray:
        self.renderer.setSize(size, size)
        self.renderer.render()
        img = self.renderer.captureImage(None)
        w, h, c = img.getWidth(), img.getHeight(), img.getChannelCount()
        px = np.ctypeslib.as_array((ctypes.c_float * (w * h * c)).from_address(img.getResourceBuffer()))
        return px.reshape(h, w, c)[::-1, :, :3].astype(np.float32)  # GL's rows run upwards

    def _clear_colour(self) -> np.ndarray:
        """The renderer's background colour (GlslRenderer clears to a grey that Python cannot change),
        read once from a view that misses the sphere: pixels of exactly this colour are background."""
        if self.background is None:
            self._camera({"position": [0.0, 0.0, 10.0], "target": [0.0, 0.0, 20.0], "up": [0.0, 1.0, 0.0],
                          "fov": 10.0, "distance": 10.0}, {"center": [0.0, 0.0, 0.0], "radius": 1.0})
            self.background = self._capture(4)[0, 0].copy()
        return self.background

    def render_view(self, view: dict, sphere: dict, resolution: int) -> np.ndarray:
        """One view, `supersample`² samples a pixel (a box filter, as the path tracers' pixels), the
        background black."""
        clear = self._clear_colour()
        self._camera(view["camera"], sphere)
        self._lights(view["lights"])
        k = int(view["supersample"])
        px = self._capture(resolution * k)
        px = np.where(np.any(px != clear, axis=-1, keepdims=True), px, 0.0)
        return px.reshape(resolution, k, resolution, k, 3).mean(axis=(1, 3), dtype=np.float64).astype(np.float32)

    def render(self, req: dict) -> None:
        self.program(req["document"], req["shader"])
        self.set_values(req.get("values", {}))
        images = [self.render_view(v, req["sphere"], int(req["resolution"])) for v in req["views"]]
        np.concatenate(images, axis=0).tofile(req["out"])


def _answer(channel, doc: dict) -> None:
    channel.write(json.dumps(doc) + "\n")
    channel.flush()


def serve(channel, renderer: Renderer, hello: dict) -> None:
    _answer(channel, hello)
    for line in sys.stdin:
        if not line.strip():
            continue
        req = json.loads(line)
        rid, op = req.get("id"), req.get("op")
        if op == "quit":
            return
        try:
            if op == "render":
                renderer.render(req)
            _answer(channel, {"id": rid, "ok": True})
        except Exception as exc:  # one request's failure is its answer; the worker serves the next
            traceback.print_exc(file=sys.stderr)
            first = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
            _answer(channel, {"id": rid, "ok": False, "error": f"{type(exc).__name__}: {first}"})


def main() -> None:
    channel = os.fdopen(os.dup(sys.stdout.fileno()), "w")
    os.dup2(sys.stderr.fileno(), sys.stdout.fileno())  # the library's prints must not corrupt the protocol
    server = scratch = None
    try:
        from brdfremap.core.data.scratch import scratch_dir

        scratch = scratch_dir("materialx-worker")
        server = start_display(scratch)
        import MaterialX as mx

        renderer = Renderer(scratch)
    except Exception as exc:  # no display, no GL context, no MaterialX: the adapter reports it in one line
        traceback.print_exc(file=sys.stderr)
        first = (str(exc).strip().splitlines() or [""])[0]
        _answer(channel, {"ok": False, "error": f"{type(exc).__name__}: {first}"})
        _end(server, scratch)
        return
    try:
        serve(channel, renderer, {"ok": True, "materialx": mx.getVersionString(),
                                  "display": os.environ.get("DISPLAY", "")})
    finally:
        _end(server, scratch)


def _end(server: subprocess.Popen | None, scratch: Path | None) -> None:
    stop_display(server)
    if scratch is not None:
        shutil.rmtree(scratch, ignore_errors=True)


if __name__ == "__main__":
    main()
    os._exit(0)  # the GL context and MaterialX's objects are the system's to free: their destructors at exit can abort

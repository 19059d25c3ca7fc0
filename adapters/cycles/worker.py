"""The Cycles worker: one Blender (bpy) process serving render requests as JSON lines.

Protocol: one JSON object per line on stdin, one JSON answer per line on the protocol
channel (the process's original stdout; Blender's own prints are sent to stderr so they
cannot corrupt it). Requests: {"op": "render", "model", "params", "scene", "out"},
{"op": "save_blend", "model", "params", "path"}, {"op": "save_scene", "model", "params", "scene", "path"},
{"op": "ping"}, {"op": "quit"}.
Run as ``python -m brdfremap.adapters.cycles.worker``; it exits when stdin closes."""

from __future__ import annotations

import json
import math
import os
import sys
import time
import traceback

LOBE_PASSES = ("use_pass_diffuse_direct", "use_pass_diffuse_color", "use_pass_glossy_direct", "use_pass_glossy_color")


SPHERE_SEGMENTS = 512


class ProbeSpheres:
    """The probe sphere of one scene build: the exact point, and the mesh an anisotropic
    material needs (made the first time one does)."""

    def __init__(self, scene, sphere: dict):
        self.scene, self.sphere = scene, sphere
        self.mesh_probe = None
        self._point(scene, sphere)

    def _point(self, scene, sphere: dict) -> None:
        """An exact sphere: one point of a point cloud (Cycles intersects it analytically)."""
        import bpy

        mesh = bpy.data.meshes.new("probe-centre")
        mesh.vertices.add(1)
        mesh.vertices[0].co = (0.0, 0.0, 0.0)
        mesh.update()
        obj = bpy.data.objects.new("probe", mesh)
        obj.location = tuple(sphere["center"])
        scene.collection.objects.link(obj)
        tree = bpy.data.node_groups.new("probe-sphere", "GeometryNodeTree")
        tree.interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
        tree.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
        gin, gout = tree.nodes.new("NodeGroupInput"), tree.nodes.new("NodeGroupOutput")
        points = tree.nodes.new("GeometryNodeMeshToPoints")
        points.inputs["Radius"].default_value = sphere["radius"]
        self.set_material = tree.nodes.new("GeometryNodeSetMaterial")
        tree.links.new(gin.outputs[0], points.inputs["Mesh"])
        tree.links.new(points.outputs[0], self.set_material.inputs["Geometry"])
        tree.links.new(self.set_material.outputs[0], gout.inputs[0])
        mod = obj.modifiers.new("probe-sphere", "NODES")
        mod.node_group = tree
        self.probe = obj

    def _mesh(self, scene, sphere: dict) -> None:
        """The probe for anisotropic materials: a smooth UV-sphere mesh of 512 x 256 faces, its pole
        along the image's up (+y). The point of a point cloud has no tangent (an anisotropic BSDF
        renders black on it); the mesh's default tangent (radial about the object's Z, from its
        generated coordinates) runs along the latitudes, as Mitsuba's sphere's dp/du does with the
        same orientation. Isotropic, it renders as the point does to 0.05 % RMSE at 128² (below
        the 0.17 % noise of 256 spp: bench/anisotropy.py), but not bit for bit from one process
        to the next (1e-7: the threaded BVH build), so the exact point stays the probe of
        everything else."""
        import bpy

        from brdfremap.adapters.cycles.sphere_mesh import uv_loops, uv_sphere

        mesh = bpy.data.meshes.new("probe-mesh")
        verts, faces = uv_sphere(SPHERE_SEGMENTS, SPHERE_SEGMENTS // 2)
        mesh.from_pydata(verts.tolist(), [], faces)
        mesh.uv_layers.new(name="UVMap").data.foreach_set("uv", uv_loops(SPHERE_SEGMENTS, SPHERE_SEGMENTS // 2).ravel())
        mesh.shade_smooth()
        mesh.materials.append(None)
        obj = bpy.data.objects.new("probe-mesh", mesh)
        obj.location = tuple(sphere["center"])
        obj.rotation_euler = (-math.pi / 2, 0.0, 0.0)  # the object's Z (the pole) along the scene's +y
        obj.scale = (sphere["radius"],) * 3
        obj.hide_render = True
        scene.collection.objects.link(obj)
        self.mesh_probe = obj

    def use(self, mat, anisotropic: bool) -> None:
        """The material on the probe this render needs, the other probe hidden: the mesh for an
        anisotropic material (a tangent) or a textured one (texture coordinates)."""
        if anisotropic and self.mesh_probe is None:
            self._mesh(self.scene, self.sphere)
        if anisotropic:
            if self.mesh_probe.data.materials[0] != mat:
                self.mesh_probe.data.materials[0] = mat
        elif self.set_material.inputs["Material"].default_value != mat:
            self.set_material.inputs["Material"].default_value = mat
        if self.mesh_probe is not None and self.mesh_probe.hide_render != (not anisotropic):
            self.mesh_probe.hide_render = not anisotropic
            self.probe.hide_render = anisotropic


class SceneBuilder:
    """The probe scene in Blender: built from the request's scene when its geometry changes
    (camera, world, lights, the sphere and its passes), its per-render settings on every request."""

    def setup_scene(self, sc_json: dict) -> None:
        # Resolution, samples and seed change between the coarse, polish and final levels of
        # one fit: set them on every request; rebuild only when the geometry changes.
        per_render = ("width", "height", "spp", "seed")
        key = json.dumps({k: v for k, v in sc_json.items() if k not in per_render}, sort_keys=True)
        if key != self.scene_key:
            # A build that fails half-way (it starts from factory settings) must not leave the
            # old key behind: the next request would skip the rebuild and find nodes gone.
            self.scene_key = None
            self._build(sc_json)
            self.scene_key = key
        scene = self.bpy.context.scene
        scene.render.resolution_x, scene.render.resolution_y = sc_json["width"], sc_json["height"]
        scene.cycles.samples = sc_json["spp"]
        scene.cycles.seed = sc_json["seed"]

    def _build(self, sc_json: dict) -> None:
        bpy = self.bpy
        bpy.ops.wm.read_factory_settings(use_empty=True)
        self.materials, self.natives = {}, {}
        scene = bpy.context.scene
        r = scene.render
        r.engine = "CYCLES"
        r.resolution_percentage = 100
        r.use_compositing = False
        r.use_sequencer = False
        r.film_transparent = False
        cy = scene.cycles
        cy.device = "CPU"
        cy.use_animated_seed = False
        cy.use_denoising = False
        cy.use_adaptive_sampling = False
        cy.pixel_filter_type = "BOX"
        cy.filter_width = 1.0
        self.depth = None  # set per request (set_depth)
        # Nothing that trades the expectation for less noise (they act on bounces only: an opaque
        # sphere, lit directly, is unchanged): light through a glass is a refractive caustic,
        # factory settings clamp indirect samples at 10 and blur glossy bounces.
        cy.caustics_reflective = cy.caustics_refractive = True
        cy.sample_clamp_direct = cy.sample_clamp_indirect = 0.0
        cy.blur_glossy = 0.0
        scene.view_settings.view_transform = "Standard"
        scene.view_settings.look = "None"
        scene.view_settings.exposure = 0.0
        scene.view_settings.gamma = 1.0
        self._world(scene, next((x for x in sc_json["lights"] if x["type"] == "environment"), None))
        self._camera(scene, sc_json["camera"])
        for i, light in enumerate(x for x in sc_json["lights"] if x["type"] == "point"):
            self._light(scene, light, "probe-light" if i == 0 else f"probe-light{i}")
        self.probes = ProbeSpheres(scene, sc_json["sphere"])
        # A few lights: nothing for a light tree to choose between (bench/cycles_render.py).
        cy.use_light_tree = False
        self.passes = None  # the lobe passes are switched on per request (see render)
        ims = r.image_settings
        ims.media_type = "MULTI_LAYER_IMAGE"  # Blender 5.0: before the file format
        ims.file_format = "OPEN_EXR_MULTILAYER"
        ims.color_depth = "32"
        ims.exr_codec = "NONE"
        r.use_file_extension = False

    def _camera(self, scene, cam: dict) -> None:
        from mathutils import Matrix, Vector

        bpy = self.bpy
        data = bpy.data.cameras.new("probe-camera")
        data.sensor_fit = "HORIZONTAL"
        data.angle = math.radians(cam["fov"])
        obj = bpy.data.objects.new("probe-camera", data)
        obj.location = tuple(cam["position"])
        forward = (Vector(cam["target"]) - Vector(cam["position"])).normalized()
        right = forward.cross(Vector(cam["up"])).normalized()
        up = right.cross(forward)
        # Blender cameras look down their local -Z with +Y up.
        obj.rotation_mode = "QUATERNION"
        obj.rotation_quaternion = Matrix((right, up, -forward)).transposed().to_quaternion()
        scene.collection.objects.link(obj)
        scene.camera = obj

    def _world(self, scene, env: dict | None) -> None:
        """Black, or the environment map: the direction d of the scene's convention (u = atan2(x, -z)
        / 2pi, v = acos(y) / pi: core.data.environment) is (d_z, d_x, d_y) in Blender's equirectangular
        lookup (u = 0.5 - atan2(y, x) / 2pi, up +z; found alike by trying every axis order and sign
        against the analytic image: tests/adapters/test_lights.py). Unseen by the camera (a transparent film: the background stays black)."""
        bpy = self.bpy
        world = bpy.data.worlds.new("probe-world")
        scene.world = world
        world.use_nodes = True
        tree = world.node_tree
        bg = tree.nodes.get("Background")
        if env is None:
            bg.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
            bg.inputs["Strength"].default_value = 0.0
            return
        scene.render.film_transparent = True
        coords, split, join = (tree.nodes.new(t) for t in ("ShaderNodeTexCoord", "ShaderNodeSeparateXYZ",
                                                           "ShaderNodeCombineXYZ"))
        tree.links.new(coords.outputs["Generated"], split.inputs[0])
        for src, dst in (("Z", "X"), ("X", "Y"), ("Y", "Z")):
            tree.links.new(split.outputs[src], join.inputs[dst])
        tex = tree.nodes.new("ShaderNodeTexEnvironment")
        tex.image = bpy.data.images.load(env["file"], check_existing=False)
        tex.image.colorspace_settings.name = "Linear Rec.709"
        tex.interpolation = "Linear"
        tex.projection = "EQUIRECTANGULAR"
        tree.links.new(join.outputs[0], tex.inputs["Vector"])
        tree.links.new(tex.outputs["Color"], bg.inputs["Color"])
        bg.inputs["Strength"].default_value = 1.0
        world.cycles.sampling_method = "MANUAL"
        world.cycles.sample_map_resolution = max(tex.image.size[0], 64)

    def _light(self, scene, light: dict, name: str) -> None:
        bpy = self.bpy
        data = bpy.data.lights.new(name, "POINT")
        # Blender's point-light power in W is 4π × the radiant intensity in W/sr.
        data.energy = 4.0 * math.pi * light["intensity"]
        data.shadow_soft_size = 0.0
        data.color = (1.0, 1.0, 1.0)
        if hasattr(data, "use_soft_falloff"):
            data.use_soft_falloff = False
        obj = bpy.data.objects.new(name, data)
        obj.location = tuple(light["position"])
        scene.collection.objects.link(obj)


def _nodes_of(tree, seen=None):
    """A node tree's nodes, those of the node groups it uses included (each group once)."""
    seen = set() if seen is None else seen
    for node in tree.nodes:
        yield node
        group = getattr(node, "node_tree", None)
        if node.type == "GROUP" and group is not None and group.name not in seen:
            seen.add(group.name)
            yield from _nodes_of(group, seen)


class MaterialNodes:
    """Materials as node trees: one per model, reused and updated in place; a textured one made
    for its request and dropped after it."""

    def new_material(self, model: str, name: str):
        """A material whose surface is the model's BSDF node: (material, node)."""
        from brdfremap.adapters.cycles.material import FIXED_PROPS, NODES

        mat = self.bpy.data.materials.new(name)
        mat.use_nodes = True
        nodes = mat.node_tree.nodes
        for n in list(nodes):
            if n.type != "OUTPUT_MATERIAL":
                nodes.remove(n)
        bsdf = nodes.new(NODES[model][0])
        for prop, value in FIXED_PROPS.get(model, {}).items():
            setattr(bsdf, prop, value)
        out = next(n for n in nodes if n.type == "OUTPUT_MATERIAL")
        mat.node_tree.links.new(bsdf.outputs[0], out.inputs["Surface"])
        return mat, bsdf

    @staticmethod
    def set_values(bsdf, model: str, params: dict) -> None:
        from brdfremap.adapters.cycles.material import NODES, enum_value, socket, socket_value

        _, inputs, props = NODES[model]
        from brdfremap.adapters.cycles.models import MODELS

        for pname, prop in props.items():
            # A caller naming fewer (cycles-subprocess.yaml) gets the model's default, not the last request's.
            value = enum_value(params.get(pname, MODELS[model].param(pname).default))
            if getattr(bsdf, prop) != value:
                setattr(bsdf, prop, value)
        for pname, sock in inputs.items():
            if pname in params:  # a caller naming fewer inputs (cycles-subprocess.yaml) leaves Blender's defaults
                socket(bsdf, sock).default_value = socket_value(model, pname, params[pname])

    def link_textures(self, mat, bsdf, model: str, textures: dict) -> None:
        """An Image Texture node on each textured input (the mesh's UV map; colour space and
        interpolation as given)."""
        from brdfremap.adapters.cycles.material import NODES, socket

        tree = mat.node_tree
        for i, (pname, tex) in enumerate(sorted(textures.items())):
            image = self.bpy.data.images.load(tex["file"], check_existing=False)
            image.colorspace_settings.name = "sRGB" if tex["colorspace"] == "srgb" else "Non-Color"
            node = tree.nodes.new("ShaderNodeTexImage")
            node.image, node.label = image, pname
            node.interpolation = "Closest" if tex.get("filter") == "nearest" else "Linear"
            node.location = (-400, -300 * i)
            tree.links.new(node.outputs["Color"], socket(bsdf, NODES[model][1][pname]))

    def drop(self, mat) -> None:
        """A material made for one request, with its images."""
        images = [n.image for n in mat.node_tree.nodes if n.type == "TEX_IMAGE" and n.image is not None]
        self.bpy.data.materials.remove(mat)
        for image in images:
            self.bpy.data.images.remove(image)

    def material(self, model: str, params: dict):
        if model not in self.materials:
            self.materials[model] = self.new_material(model, f"brdf-remap {model}")
        mat, bsdf = self.materials[model]
        self.set_values(bsdf, model, params)
        return mat


class BlenderState(SceneBuilder, MaterialNodes):
    """What the worker keeps between requests, and the requests it answers (render, save, read)."""

    def __init__(self):
        import bpy

        self.bpy = bpy
        self.scene_key = None
        self.passes = None
        self.materials = {}
        self.natives = {}
        self.probes = None
        self.depth = None

    def render(self, req: dict) -> dict:
        t0 = time.perf_counter()
        self.setup_scene(req["scene"])
        textured = req.get("textures") or {}
        if textured:
            mat, bsdf = self.new_material(req["model"], "brdf-remap textured")
            self.set_values(bsdf, req["model"], req["params"])
            self.link_textures(mat, bsdf, req["model"], textured)
        else:
            mat = self.material(req["model"], req["params"])
        self.probes.use(mat, bool(textured) or float(req["params"].get("anisotropic", 0.0)) > 0.0
                        or int(req.get("depth", 0)) > 0)
        try:
            return self._render(req, t0)
        finally:
            if textured:
                self.drop(mat)

    def set_depth(self, depth: int) -> None:
        """Bounces after the camera ray's first hit: none for an opaque sphere (direct light alone),
        ``depth`` of every kind for a transmissive one (into the sphere, through it and out)."""
        if depth == self.depth:
            return
        cy = self.bpy.context.scene.cycles
        for attr in ("max_bounces", "diffuse_bounces", "glossy_bounces", "transmission_bounces",
                     "volume_bounces", "transparent_max_bounces"):
            setattr(cy, attr, depth)
        self.depth = depth

    def _render(self, req: dict, t0: float) -> dict:
        scene = self.bpy.context.scene
        self.set_depth(int(req.get("depth", 0)))
        scene.render.filepath = req["out"]
        # The lobe passes only when a lobe is asked for: accumulating them costs about 13 % of a
        # render (measured at 128² and 32², 16 spp).
        passes = bool(req.get("passes", True))
        if passes != self.passes:
            vl = scene.view_layers[0]
            for attr in LOBE_PASSES:
                setattr(vl, attr, passes)
            self.passes = passes
        self.bpy.ops.render.render(write_still=True)
        if not os.path.exists(req["out"]):
            raise RuntimeError(f"Blender did not write {req['out']}")
        return {"seconds": time.perf_counter() - t0}

    def render_saved(self, req: dict) -> dict:
        """A material of a saved .blend (a library this tool wrote), appended and rendered on the
        probe mesh (its UV map: the material may read textures), then removed again."""
        t0 = time.perf_counter()
        self.setup_scene(req["scene"])
        with self.bpy.data.libraries.load(req["path"], link=False, relative=False) as (src, dst):
            if req["name"] not in src.materials:
                raise KeyError(f"{req['path']} holds no material {req['name']!r} (it holds {list(src.materials)})")
            dst.materials = [req["name"]]
        mat = dst.materials[0]
        missing = [n.image.filepath for n in mat.node_tree.nodes if n.type == "TEX_IMAGE" and n.image is not None
                   and not n.image.has_data and not os.path.exists(self.bpy.path.abspath(n.image.filepath,
                                                                                         library=n.image.library))]
        if missing:
            raise FileNotFoundError(f"the material's images are not found: {missing}")
        self.probes.use(mat, True)
        try:
            return self._render(req, t0)
        finally:
            self.drop(mat)

    def render_native(self, req: dict) -> dict:
        """A material of a user's .blend as the file holds it (its whole node tree, node groups and
        images), appended once and kept for the next request of the same file's content, on the probe
        mesh (its UV map, tangents and generated coordinates)."""
        t0 = time.perf_counter()
        self.setup_scene(req["scene"])
        key = (req["path"], req["name"], req["sha256"])
        if key not in self.natives:
            self.natives[key] = self.append(req["path"], req["name"])
        self.probes.use(self.natives[key], True)
        return self._render(req, t0)

    def append(self, path: str, name: str):
        """A material appended from a .blend (running nothing the file holds: no driver's expression, no
        script), its images checked."""
        self.bpy.context.preferences.filepaths.use_scripts_auto_execute = False
        with self.bpy.data.libraries.load(path, link=False, relative=False) as (src, dst):
            if name not in src.materials:
                raise KeyError(f"{path} holds no material {name!r} (it holds {list(src.materials)})")
            dst.materials = [name]
        mat = dst.materials[0]
        missing = [n.image.filepath for n in _nodes_of(mat.node_tree) if n.type == "TEX_IMAGE" and n.image is not None
                   and n.image.source == "FILE" and n.image.packed_file is None and not os.path.exists(
                       self.bpy.path.abspath(n.image.filepath, library=n.image.library))]
        if missing:
            raise FileNotFoundError(f"material {name!r}: its images are not found: {missing}")
        return mat

    def save_blend(self, req: dict) -> dict:
        textures = req.get("textures") or {}
        if not textures:
            mat = self.material(req["model"], req["params"])
            mat.name = req.get("name", mat.name)
            self.bpy.data.libraries.write(req["path"], {mat}, fake_user=True)
            return {}
        mat, bsdf = self.new_material(req["model"], req.get("name", "brdf-remap"))
        self.set_values(bsdf, req["model"], req["params"])
        self.link_textures(mat, bsdf, req["model"], textures)
        # Image paths relative to the .blend ("//name.png"): the textures travel with it.
        self.bpy.data.libraries.write(req["path"], {mat}, fake_user=True, path_remap="RELATIVE")
        self.drop(mat)
        return {}

    def save_scene(self, req: dict) -> dict:
        """The probe scene as this worker renders it (camera, sphere, lights, world, render settings) with a
        material of a model on the sphere, saved as a .blend a user opens and renders (`remap scene
        export`); the environment's map packed into it."""
        self.setup_scene(req["scene"])
        mat = self.material(req["model"], req["params"])
        mat.name = "material"
        self.probes.use(mat, True)
        scene = self.bpy.context.scene
        for attr in LOBE_PASSES:  # a user's render: the image alone, one EXR
            setattr(scene.view_layers[0], attr, False)
        ims = scene.render.image_settings
        ims.media_type = "IMAGE"
        ims.file_format, ims.color_depth = "OPEN_EXR", "32"
        for image in self.bpy.data.images:
            if image.source == "FILE" and not image.packed_file:
                image.pack()
        self.bpy.ops.wm.save_as_mainfile(filepath=req["path"], copy=True, compress=True)
        self.scene_key, self.passes = None, None  # packed, its output changed: rebuilt at the next request
        return {}

    def save_library(self, req: dict) -> dict:
        """One .blend holding a material per item, each under the item's name (Blender keeps 63
        bytes of a name: the names it kept are answered)."""
        mats, names = set(), []
        for item in req["items"]:
            mat, bsdf = self.new_material(item["model"], item["name"])
            self.set_values(bsdf, item["model"], item["params"])
            self.link_textures(mat, bsdf, item["model"], item.get("textures") or {})
            mats.add(mat)
            names.append(mat.name)
        self.bpy.data.libraries.write(req["path"], mats, fake_user=True, path_remap="RELATIVE")
        for mat in mats:
            self.drop(mat)
        return {"names": names}

    def read_blend(self, req: dict) -> dict:
        """Every material of a .blend, read without running anything the file holds (scripts off)."""
        from brdfremap.adapters.cycles.blendread import read_materials

        self.bpy.context.preferences.filepaths.use_scripts_auto_execute = False
        self.bpy.ops.wm.open_mainfile(filepath=req["path"], load_ui=False, use_scripts=False)
        # the probe scene is gone: rebuilt at the next render
        self.scene_key, self.materials, self.natives = None, {}, {}
        return {"materials": read_materials(self.bpy)}


def main() -> int:
    proto = os.fdopen(os.dup(1), "w", buffering=1, encoding="utf-8")
    os.dup2(2, 1)  # Blender prints progress on stdout: keep it off the protocol channel
    sys.stdout = sys.stderr

    def send(msg: dict) -> None:
        proto.write(json.dumps(msg) + "\n")
        proto.flush()

    try:
        import bpy

        state = BlenderState()
        send({"ok": True, "ready": True, "blender": bpy.app.version_string, "pid": os.getpid()})
    except Exception as exc:
        send({"ok": False, "error": f"cannot start Blender: {type(exc).__name__}: {exc}"})
        return 1
    for line in sys.stdin:
        if not line.strip():
            continue
        req = None
        try:
            req = json.loads(line)
            op = req.get("op")
            if op == "quit":
                send({"id": req.get("id"), "ok": True})
                break
            if op == "ping":
                result = {}
            elif op == "render":
                result = state.render(req)
            elif op == "save_blend":
                result = state.save_blend(req)
            elif op == "render_native":
                result = state.render_native(req)
            elif op == "render_saved":
                result = state.render_saved(req)
            elif op == "save_scene":
                result = state.save_scene(req)
            elif op == "save_library":
                result = state.save_library(req)
            elif op == "read_blend":
                result = state.read_blend(req)
            else:
                raise ValueError(f"unknown op {op!r}")
            send({"id": req.get("id"), "ok": True, **result})
        except Exception as exc:
            traceback.print_exc()
            send({"id": req.get("id") if isinstance(req, dict) else None, "ok": False,
                  "error": f"{type(exc).__name__}: {exc}"})
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Render a brdf-remap probe scene exported as USD (`remap scene export --format usd`) with Blender's
Cycles, as a user outside the tool would: this script does not import brdfremap.

    python render_usd_blender.py SCENE.usda OUT.exr --spp 64 --seed 0 [--material material.json]

It needs the ``bpy`` module (Blender 5.0 as a Python module: pip install bpy==5.0.*). The image is
linear scene-referred RGB radiance in float32 (an OpenEXR): no view transform, no denoiser, a box
pixel filter one pixel wide, direct lighting only, the environment unseen behind the sphere: the
settings brdf-remap's own Cycles adapter renders with.

``--material`` replaces the sphere's material by a Principled BSDF whose inputs a JSON file gives by
their Blender 5.0 socket names: {"Base Color": [0.8, 0.2, 0.1], "Metallic": 0.0, "Roughness": 0.4,
"Coat Weight": 0.5, "distribution": "MULTI_GGX"}.

The stage's conventions (brdf-remap's USD writer) and what Blender's importer makes of them:
point lights are normalized SphereLights with treatAsPoint and intensity = 4 x the radiant
intensity in W/sr, which Blender imports as point lights of pi x intensity W (4 pi x W/sr: right);
the environment is a DomeLight in the OpenEXR latitude-longitude orientation, which Blender turns
into its world (Y up to Z up, rotated to its own equirectangular lookup: right); the render size,
samples and seed are in the layer's customLayerData (``brdfremap``)."""

from __future__ import annotations

import argparse
import json
import re
import sys
import time
from pathlib import Path


def parse_args(argv: list[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scene", type=Path, help="the probe scene (.usda)")
    parser.add_argument("out", type=Path, help="the image to write (.exr)")
    parser.add_argument("--spp", type=int, default=None, help="samples per pixel (default: the scene's)")
    parser.add_argument("--seed", type=int, default=None, help="the sampler's seed (default: the scene's)")
    parser.add_argument("--resolution", type=int, default=None, help="image width and height (default: the scene's)")
    parser.add_argument("--material", type=Path, default=None, help="a JSON file of Principled BSDF inputs")
    parser.add_argument("--bounces", type=int, default=0,
                        help="bounces after the first hit: 0 (direct light) for an opaque material, a few for a "
                             "transmissive one")
    return parser.parse_args(argv)


def scene_settings(path: Path) -> dict:
    """The stage's render settings (customLayerData ``brdfremap``): resolution, spp, seed. Read from the
    layer's text header (a .usda) so that no second USD library is loaded beside Blender's."""
    head = path.read_text(encoding="utf-8", errors="replace")[:20000]
    block = re.search(r"dictionary brdfremap = \{(.*?)\n\s*\}", head, re.S)
    found = {}
    for key in ("resolution", "spp", "seed"):
        m = re.search(rf"\bint {key} = (\d+)", block.group(1)) if block else None
        if m:
            found[key] = int(m.group(1))
    return found


def import_stage(bpy, path: Path) -> None:
    """The stage into an empty scene. The world must exist before the import: Blender makes a dome
    light into the scene's world only if there is one. Light intensities as written (scale 1), metres
    as metres (the stage's metersPerUnit), the mesh as authored (no subdivision), UsdPreviewSurface as a
    Principled BSDF."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.world = bpy.data.worlds.new("probe-world")
    scene.world.use_nodes = True
    background = scene.world.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    background.inputs["Strength"].default_value = 0.0
    result = bpy.ops.wm.usd_import(
        filepath=str(path), scale=1.0, apply_unit_conversion_scale=True, light_intensity_scale=1.0,
        import_lights=True, create_world_material=True, import_cameras=True, import_meshes=True,
        import_shapes=True, import_materials=True, import_usd_preview=True, import_subdivision=False,
        import_visible_only=True, import_render=True, import_guide=False, import_proxy=False,
        set_frame_range=False, create_collection=False)
    if "FINISHED" not in result:
        raise RuntimeError(f"Blender could not import {path}: {result}")


def the_one(objects, kind: str, what: str):
    found = [o for o in objects if o.type == kind]
    if len(found) != 1:
        raise RuntimeError(f"the stage should hold one {what}: found {[o.name for o in found]}")
    return found[0]


def principled_material(bpy, path: Path):
    """A material whose surface is one Principled BSDF, its inputs from the JSON file: socket names
    ("Base Color", "Coat Weight") or the node's own settings ("distribution": "MULTI_GGX"). Its tangent
    runs along the sphere's latitudes about the stage's up axis (the mesh's local +Y), as brdf-remap's
    probe has it for an anisotropic material (Blender's default tangent turns about the local Z)."""
    values = json.loads(path.read_text(encoding="utf-8"))
    mat = bpy.data.materials.new(path.stem)
    mat.use_nodes = True
    tree = mat.node_tree
    for node in [n for n in tree.nodes if n.type != "OUTPUT_MATERIAL"]:
        tree.nodes.remove(node)
    bsdf = tree.nodes.new("ShaderNodeBsdfPrincipled")
    tangent = tree.nodes.new("ShaderNodeTangent")
    tangent.direction_type, tangent.axis = "RADIAL", "Y"
    tree.links.new(tangent.outputs["Tangent"], bsdf.inputs["Tangent"])
    out = next(n for n in tree.nodes if n.type == "OUTPUT_MATERIAL")
    tree.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    for name, value in values.items():
        set_input(bsdf, name, value, path)
    return mat


def set_input(bsdf, name: str, value, path: Path) -> None:
    """One input by its socket name (found by looking at each: Blender 5.0's ``inputs[name]`` misses
    "Subsurface IOR"), or one of the node's enum settings."""
    socket = next((s for s in bsdf.inputs if s.name == name or s.identifier == name), None)
    if socket is None:
        prop = bsdf.bl_rna.properties.get(name)
        if prop is None or prop.type != "ENUM":
            names = [s.name for s in bsdf.inputs if s.enabled]
            raise KeyError(f"{path}: {name!r} is not an input of the Principled BSDF: {names}")
        setattr(bsdf, name, str(value).upper())
        return
    if socket.type == "RGBA":
        rgb = [float(x) for x in value] if isinstance(value, (list, tuple)) else [float(value)] * 3
        socket.default_value = (*rgb[:3], 1.0)
    elif socket.type == "VECTOR":
        socket.default_value = [float(x) for x in value]
    else:
        socket.default_value = value


def set_material(sphere, mat) -> None:
    sphere.data.materials.clear()
    sphere.data.materials.append(mat)
    for poly_slot in sphere.material_slots:
        poly_slot.link = "DATA"


def setup_cycles(scene, resolution: int, spp: int, seed: int, bounces: int) -> None:
    """Cycles as brdf-remap's adapter sets it up: CPU, fixed samples, no denoiser, a 1-pixel box filter,
    nothing clamped or blurred, the Standard view transform (unused by an EXR, which stays linear),
    the background transparent (black: the dome lights the sphere but is not seen)."""
    r = scene.render
    r.engine = "CYCLES"
    r.resolution_x = r.resolution_y = resolution
    r.resolution_percentage = 100
    r.pixel_aspect_x = r.pixel_aspect_y = 1.0
    r.use_compositing = r.use_sequencer = False
    r.film_transparent = True
    cy = scene.cycles
    cy.device = "CPU"
    cy.samples = spp
    cy.seed = seed
    cy.use_animated_seed = False
    cy.use_denoising = False
    cy.use_adaptive_sampling = False
    cy.pixel_filter_type = "BOX"
    cy.filter_width = 1.0
    cy.caustics_reflective = cy.caustics_refractive = True
    cy.sample_clamp_direct = cy.sample_clamp_indirect = 0.0
    cy.blur_glossy = 0.0
    cy.use_light_tree = False
    for attr in ("max_bounces", "diffuse_bounces", "glossy_bounces", "transmission_bounces", "volume_bounces",
                 "transparent_max_bounces"):
        setattr(cy, attr, bounces)
    view = scene.view_settings
    view.view_transform, view.look, view.exposure, view.gamma = "Standard", "None", 0.0, 1.0


def sample_the_world(bpy, world) -> None:
    """Importance-sample the environment at its map's resolution (as brdf-remap's adapter does)."""
    images = [n.image for n in world.node_tree.nodes if n.type == "TEX_ENVIRONMENT" and n.image is not None]
    world.cycles.sampling_method = "MANUAL"
    world.cycles.sample_map_resolution = max([64, *[im.size[0] for im in images]])
    for image in images:
        image.colorspace_settings.name = "Linear Rec.709"  # radiance, not a colour to decode


def write_exr(scene, out: Path) -> None:
    ims = scene.render.image_settings
    ims.media_type = "IMAGE"  # Blender 5.0: before the file format
    ims.file_format = "OPEN_EXR"
    ims.color_mode = "RGB"
    ims.color_depth = "32"
    ims.exr_codec = "ZIP"
    scene.render.use_file_extension = False
    scene.render.filepath = str(out)


def main(argv: list[str]) -> int:
    args = parse_args(argv)
    import bpy

    settings = scene_settings(args.scene)
    resolution = args.resolution or settings.get("resolution")
    spp, seed = args.spp or settings.get("spp", 16), args.seed if args.seed is not None else settings.get("seed", 0)
    if not resolution:
        raise SystemExit(f"{args.scene}: no brdfremap resolution in its customLayerData: give --resolution")
    import_stage(bpy, args.scene.resolve())
    scene = bpy.context.scene
    scene.camera = the_one(scene.objects, "CAMERA", "camera")
    scene.camera.data.dof.use_dof = False
    for light in (o.data for o in scene.objects if o.type == "LIGHT"):
        light.use_soft_falloff = False  # a point light of radius 0 as brdf-remap's adapter has it
    sphere = the_one(scene.objects, "MESH", "sphere mesh")
    if args.material is not None:
        set_material(sphere, principled_material(bpy, args.material))
    sample_the_world(bpy, scene.world)
    setup_cycles(scene, resolution, spp, seed, args.bounces)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    write_exr(scene, args.out.resolve())
    t0 = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    if not args.out.exists():
        raise SystemExit(f"Blender did not write {args.out}")
    print(f"{args.out}: {resolution}x{resolution}, {spp} spp, seed {seed}, {time.perf_counter() - t0:.1f} s",
          file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

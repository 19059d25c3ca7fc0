"""Blender's own glTF export of a textured Principled BSDF (a test's and a bench's real glTF file):
the demo's worn-copper colour (sRGB) and roughness (non-colour) images on Base Color and Roughness,
Metallic 1, on a sphere, exported as .glb by `bpy.ops.export_scene.gltf`.

    python export_worn_copper.py IMAGES_FOLDER OUT.glb      (with bpy installed)"""

import sys

import bpy

images, out = sys.argv[1], sys.argv[2]
bpy.ops.wm.read_factory_settings(use_empty=True)
m = bpy.data.materials.new("worn copper")
m.use_nodes = True
nt = m.node_tree
p = next(n for n in nt.nodes if n.type == "BSDF_PRINCIPLED")
for file, socket, space in ((images + "/worn-copper-colour.png", "Base Color", "sRGB"),
                            (images + "/worn-copper-roughness.png", "Roughness", "Non-Color")):
    n = nt.nodes.new("ShaderNodeTexImage")
    n.image = bpy.data.images.load(file)
    n.image.colorspace_settings.name = space
    nt.links.new(n.outputs["Color"], p.inputs[socket])
p.inputs["Metallic"].default_value = 1.0
bpy.ops.mesh.primitive_uv_sphere_add()
bpy.context.active_object.data.materials.append(m)
bpy.ops.export_scene.gltf(filepath=out, export_format="GLB")

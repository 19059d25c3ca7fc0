"""Writes everyday.blend: six materials a Blender artist uses every day and a Principled BSDF inside a
node group, with the wood's image beside it (wood.png, made here). Run with the bpy module:

    python tests/data/blend/everyday.py OUT_FOLDER
"""

import math
import sys
from pathlib import Path

import bpy

out = Path(sys.argv[-1])
out.mkdir(parents=True, exist_ok=True)
bpy.ops.wm.read_factory_settings(use_empty=True)


def material(name):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    m.use_fake_user = True
    tree = m.node_tree
    for n in list(tree.nodes):
        if n.type != "OUTPUT_MATERIAL":
            tree.nodes.remove(n)
    return m, tree, next(n for n in tree.nodes if n.type == "OUTPUT_MATERIAL")


def principled(tree, out_node, **inputs):
    b = tree.nodes.new("ShaderNodeBsdfPrincipled")
    for k, v in inputs.items():
        b.inputs[k.replace("_", " ")].default_value = v
    tree.links.new(b.outputs[0], out_node.inputs["Surface"])
    return b


m, tree, o = material("gold")
principled(tree, o, Base_Color=(1.0, 0.766, 0.336, 1.0), Metallic=1.0, Roughness=0.3)

m, tree, o = material("coated paint")
b = principled(tree, o, Base_Color=(0.5, 0.04, 0.03, 1.0), Roughness=0.5)
b.inputs["Coat Weight"].default_value = 1.0
b.inputs["Coat Roughness"].default_value = 0.1

m, tree, o = material("clear glass")
g = tree.nodes.new("ShaderNodeBsdfGlass")
g.inputs["IOR"].default_value = 1.5
g.inputs["Roughness"].default_value = 0.0
tree.links.new(g.outputs[0], o.inputs["Surface"])

# A wood: dark and light rings along u, in sRGB.
size = 256
img = bpy.data.images.new("wood", size, size)
px = []
for y in range(size):
    for x in range(size):
        t = 0.5 + 0.5 * math.sin(x / size * 2 * math.pi * 32 + 0.6 * math.sin(y / size * 2 * math.pi * 4))
        px += [0.42 + 0.25 * t, 0.22 + 0.14 * t, 0.08 + 0.06 * t, 1.0]
img.pixels[:] = px
img.filepath_raw = str(out / "wood.png")
img.file_format = "PNG"
img.save()
m, tree, o = material("wood")
b = principled(tree, o, Roughness=0.5)
tex = tree.nodes.new("ShaderNodeTexImage")
tex.image = bpy.data.images.load(str(out / "wood.png"))
tree.links.new(tex.outputs["Color"], b.inputs["Base Color"])

m, tree, o = material("mix diffuse glossy")
d = tree.nodes.new("ShaderNodeBsdfDiffuse")
d.inputs["Color"].default_value = (0.6, 0.2, 0.1, 1.0)
gl = tree.nodes.new("ShaderNodeBsdfAnisotropic")  # Blender 4+'s Glossy BSDF
gl.inputs["Roughness"].default_value = 0.2
lw = tree.nodes.new("ShaderNodeLayerWeight")
lw.inputs["Blend"].default_value = 0.3
mix = tree.nodes.new("ShaderNodeMixShader")
tree.links.new(lw.outputs["Fresnel"], mix.inputs[0])
tree.links.new(d.outputs[0], mix.inputs[1])
tree.links.new(gl.outputs[0], mix.inputs[2])
tree.links.new(mix.outputs[0], o.inputs["Surface"])

m, tree, o = material("emission")
e = tree.nodes.new("ShaderNodeEmission")
e.inputs["Color"].default_value = (1.0, 0.5, 0.2, 1.0)
e.inputs["Strength"].default_value = 2.0
tree.links.new(e.outputs[0], o.inputs["Surface"])

group = bpy.data.node_groups.new("blue plastic", "ShaderNodeTree")
group.interface.new_socket("Shader", in_out="OUTPUT", socket_type="NodeSocketShader")
gout = group.nodes.new("NodeGroupOutput")
gb = group.nodes.new("ShaderNodeBsdfPrincipled")
gb.inputs["Base Color"].default_value = (0.05, 0.12, 0.6, 1.0)
gb.inputs["Roughness"].default_value = 0.35
group.links.new(gb.outputs[0], gout.inputs[0])
m, tree, o = material("grouped plastic")
node = tree.nodes.new("ShaderNodeGroup")
node.node_tree = group
tree.links.new(node.outputs[0], o.inputs["Surface"])

bpy.ops.wm.save_as_mainfile(filepath=str(out / "everyday.blend"), relative_remap=True)

"""How each model maps onto Blender shader nodes. Shared by the worker (which applies it
with bpy) and the adapter (which writes the Python snippet); imports no bpy."""

from __future__ import annotations

from brdfremap.core.data.schemas import Value

def _nodes() -> tuple[dict, dict, set]:
    from .models import MODELS

    nodes = {name: (m.node, dict(m.inputs), dict(m.props)) for name, m in MODELS.items()}
    fixed = {name: dict(m.fixed_props) for name, m in MODELS.items() if m.fixed_props}
    vectors = {(name, p) for name, m in MODELS.items() for p in m.vector_inputs}
    return nodes, fixed, vectors


NODES, FIXED_PROPS, VECTOR_SOCKETS = _nodes()
"""Each model's node (its type, {param: node input name}, {choice param: node property}), the node
properties set once, and the RGB parameters on 3-float vector sockets rather than RGBA colour
sockets: each model's own (`models`), by name, for the worker and the Python snippet."""


def socket(node, name: str):
    """A node's input by name. Not ``node.inputs[name]``: Blender 5.0 does not find "Subsurface IOR"
    that way (another input's name, "IOR", is a suffix of it), though the socket is there."""
    found = next((s for s in node.inputs if s.identifier == name or s.name == name), None)
    if found is None:
        raise KeyError(f"the {node.bl_label} node has no input {name!r} in this Blender")
    return found


def socket_value(model: str, name: str, v: Value):
    """Colour sockets take RGBA, vector sockets three floats."""
    if isinstance(v, (tuple, list)):
        return tuple(v) if (model, name) in VECTOR_SOCKETS else (*v, 1.0)
    return v


def enum_value(v: str) -> str:
    return v.upper()


def python_snippet(model: str, params: dict[str, Value], name: str = "brdf-remap", textures=None) -> str:
    """A short bpy script that recreates the material (its textures read from beside the script)."""
    node_type, inputs, props = NODES[model]
    lines = [
        "# Recreates the remapped material in Blender (Cycles). Run in Blender's Python console",
        "# or with: blender --background --python this_file.py",
        "import bpy",
        "",
        f"mat = bpy.data.materials.new({name!r})",
        "nodes, links = mat.node_tree.nodes, mat.node_tree.links",
        "for n in list(nodes):",
        "    if n.type != 'OUTPUT_MATERIAL':",
        "        nodes.remove(n)",
        f"bsdf = nodes.new({node_type!r})",
        "",
        "",
        "def socket(name):  # by name: bsdf.inputs['Subsurface IOR'] is not found in Blender 5.0",
        "    return next(s for s in bsdf.inputs if s.name == name)",
        "",
        "",
    ]
    for prop, value in FIXED_PROPS.get(model, {}).items():
        lines.append(f"bsdf.{prop} = {value!r}")
    for pname, prop in props.items():
        lines.append(f"bsdf.{prop} = {enum_value(str(params[pname]))!r}")
    for pname, sock in inputs.items():
        v = socket_value(model, pname, params[pname])
        shown = "(" + ", ".join(f"{x:.6g}" for x in v) + ")" if isinstance(v, tuple) else f"{v:.6g}"
        lines.append(f"socket({sock!r}).default_value = {shown}")
    if textures:
        lines += ["", "import os", "", "here = os.path.dirname(os.path.abspath(__file__))"]
    for i, (pname, tex) in enumerate(sorted((textures or {}).items())):
        space = "sRGB" if tex.colorspace == "srgb" else "Non-Color"
        interp = "Closest" if tex.filter == "nearest" else "Linear"
        lines += ["tex = nodes.new('ShaderNodeTexImage')",
                  f"tex.image = bpy.data.images.load(os.path.join(here, {tex.file!r}))",
                  f"tex.image.colorspace_settings.name = {space!r}",
                  f"tex.interpolation, tex.label, tex.location = {interp!r}, {pname!r}, (-400, {-300 * i})",
                  f"links.new(tex.outputs['Color'], socket({inputs[pname]!r}))"]
    lines += [
        "out = next(n for n in nodes if n.type == 'OUTPUT_MATERIAL')",
        "links.new(bsdf.outputs[0], out.inputs['Surface'])",
        "",
    ]
    return "\n".join(lines)

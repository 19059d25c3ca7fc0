"""Reading the materials of an open .blend (runs inside the Blender worker, given ``bpy``).

A material converts when its active output's Surface is one of the adapter's BSDF nodes
(Principled, Glossy, Diffuse, Metallic): the unconnected inputs' values become the model's
parameters; an input driven by a texture or a node graph is listed (and its constant value
used); an input the model has no parameter for is listed when it is away from its default."""

from __future__ import annotations

from brdfremap.adapters.cycles.material import NODES, socket as input_socket

BY_TYPE = {"BSDF_PRINCIPLED": "principled", "BSDF_GLOSSY": "glossy", "BSDF_DIFFUSE": "diffuse",
           "BSDF_METALLIC": "metallic"}
QUIET = {"Weight", "Normal", "Tangent", "Coat Normal"}
"""Inputs that say nothing about a sphere's reflectance when left unconnected."""


def read_materials(bpy) -> list[dict]:
    defaults: dict[str, dict[str, object]] = {}
    out = []
    for mat in bpy.data.materials:
        if getattr(mat, "is_grease_pencil", False):
            continue
        out.append(_material(bpy, mat, defaults))
    return out


def _material(bpy, mat, defaults) -> dict:
    entry = {"name": mat.name, "model": None, "params": {}, "problem": "", "textured": [], "notes": [],
             "textures": {}}
    tree = mat.node_tree if mat.use_nodes else None
    outputs = [n for n in tree.nodes if n.type == "OUTPUT_MATERIAL"] if tree else []
    output = next((n for n in outputs if n.is_active_output), outputs[0] if outputs else None)
    if output is None:
        entry["problem"] = "no node tree with a Material Output (a legacy material)"
        return entry
    links = output.inputs["Surface"].links
    if not links:
        entry["problem"] = "nothing is connected to the Material Output's Surface"
        return entry
    node = links[0].from_node
    model = BY_TYPE.get(node.type)
    if model is None:
        entry["problem"] = f"its surface is a {node.bl_label} node ({node.type}): not a BSDF this tool reads"
        return entry
    entry["model"] = model
    _, inputs, props = NODES[model]
    for pname, prop in props.items():
        entry["params"][pname] = str(getattr(node, prop)).lower()
    for pname, sock in inputs.items():
        socket = input_socket(node, sock)
        if socket.is_linked:
            entry["textured"].append(f"{pname} <- {_source(socket.links[0].from_node)}")
            tex, why = _image(bpy, socket.links[0])
            if tex is not None:
                entry["textures"][pname] = tex
            else:
                entry["notes"].append(f"{pname}: {why}: read as its constant")
        entry["params"][pname] = _plain(socket.default_value)
    mapped = set(inputs.values())
    base = defaults.setdefault(node.bl_idname, _defaults(bpy, node.bl_idname))
    for socket in node.inputs:
        if socket.name in mapped or not socket.enabled:
            continue
        if socket.is_linked:
            entry["notes"].append(f"{socket.name} <- {_source(socket.links[0].from_node)}: no counterpart in the "
                                  f"{model!r} model, ignored")
        elif socket.name not in QUIET and hasattr(socket, "default_value") and \
                _differs(_plain(socket.default_value), base.get(socket.name)):
            entry["notes"].append(f"{socket.name} = {_shown(socket.default_value)} has no counterpart in the "
                                  f"{model!r} model: ignored")
    return entry


LINEAR_SPACES = {"Non-Color", "Linear Rec.709", "Raw", "Linear"}


def _image(bpy, link) -> tuple[dict | None, str]:
    """An Image Texture node's file, colour space and interpolation, when its Color drives the input
    directly from the mesh's UV map and a file of its own; else None and why not."""
    node = link.from_node
    if node.type != "TEX_IMAGE" or node.image is None:
        return None, f"driven by a {node.bl_label} node, not an image"
    image = node.image
    if link.from_socket.name != "Color":
        return None, f"driven by the {link.from_socket.name} of image {image.name!r}"
    if node.inputs["Vector"].is_linked:
        return None, f"image {image.name!r} is read through a coordinate node graph, not the UV map as it is"
    if node.projection != "FLAT" or image.source != "FILE":
        return None, f"image {image.name!r} is not a flat image file ({node.projection.lower()}, {image.source.lower()})"
    if image.packed_file is not None:
        return None, f"image {image.name!r} is packed in the .blend: unpack it (File > External Data > Unpack)"
    space = image.colorspace_settings.name
    if space != "sRGB" and space not in LINEAR_SPACES:
        return None, f"image {image.name!r} is in colour space {space!r} (sRGB or Non-Color are read)"
    path = bpy.path.abspath(image.filepath, library=image.library)
    return {"file": path, "colorspace": "srgb" if space == "sRGB" else "linear",
            "filter": "nearest" if node.interpolation == "Closest" else "linear"}, ""


def _defaults(bpy, idname: str) -> dict[str, object]:
    """A fresh node's input values: what counts as 'left at its default'."""
    mat = bpy.data.materials.new("brdf-remap defaults")
    mat.use_nodes = True
    node = mat.node_tree.nodes.new(idname)
    out = {s.name: _plain(s.default_value) for s in node.inputs if hasattr(s, "default_value")}
    bpy.data.materials.remove(mat)
    return out


def _source(node) -> str:
    if node.type == "TEX_IMAGE" and node.image is not None:
        return f"image {node.image.name!r}"
    return f"{node.bl_label} node {node.name!r}"


def _plain(v):
    """A socket's value as JSON: 7 significant digits (what a user typed into a 32-bit float)."""
    try:
        vals = [float(f"{float(x):.7g}") for x in v]
    except TypeError:
        return float(f"{float(v):.7g}") if isinstance(v, (int, float)) else v
    return vals[:3] if len(vals) == 4 else vals


def _differs(a, b) -> bool:
    if isinstance(a, list) and isinstance(b, list):
        return any(abs(x - y) > 1e-6 for x, y in zip(a, b))
    if isinstance(a, float) and isinstance(b, float):
        return abs(a - b) > 1e-6
    return a != b


def _shown(v) -> str:
    p = _plain(v)
    return "(" + ", ".join(f"{x:.4g}" for x in p) + ")" if isinstance(p, list) else f"{p:.4g}"

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
    """The material's reading where its surface is one of the models' nodes, and whether Cycles must
    render it from the file as it is (``native``): no reading (a Mix Shader, a node group, any other
    node), or one that leaves something out (an input driven by a texture or a graph, an input with no
    counterpart); ``transmits`` where light may pass through it."""
    entry = {"name": mat.name, "model": None, "params": {}, "problem": "", "textured": [], "notes": [],
             "textures": {}, "native": False, "transmits": False}
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
    used = _upstream(output)
    entry["transmits"] = _transmits(used) or output.inputs["Volume"].is_linked
    entry["driven"] = _spatial(used)
    entry["files"] = _files(bpy, used)
    node = links[0].from_node
    model = BY_TYPE.get(node.type)
    if node.type in AS_PRINCIPLED:
        _read_as(node, entry, *AS_PRINCIPLED[node.type])
        return entry
    if model is None:
        entry["native"] = True
        entry["notes"].append(f"its surface is the {node.bl_label} node {node.name!r}: no reading, rendered by "
                              "Cycles as the file holds it")
        return entry
    entry["model"] = model
    _read(bpy, node, model, entry, defaults)
    entry["native"] = bool(entry["textured"] or entry["notes"])
    return entry


AS_PRINCIPLED = {
    "BSDF_GLASS": ({"base_color": "Color", "roughness": "Roughness", "ior": "IOR"},
                   {"transmission_weight": 1.0, "metallic": 0.0, "distribution": "ggx"}),
}
"""Surface nodes read as a Principled BSDF by correspondence (the reading chooses the target and starts the
fit; Cycles renders the node itself): {param: input}, and the Principled values that make it that node."""


def _read_as(node, entry: dict, inputs: dict[str, str], fixed: dict) -> None:
    entry.update(model="principled", native=True)
    entry["params"].update(fixed)
    for pname, sock in inputs.items():
        socket = input_socket(node, sock)
        if socket.is_linked:
            entry["textured"].append(f"{pname} <- {_source(socket.links[0].from_node)}")
        entry["params"][pname] = _plain(socket.default_value)
    entry["notes"].append(f"its surface is the {node.bl_label} node {node.name!r}: read as a Principled BSDF "
                          f"({', '.join(f'{k} {v}' for k, v in fixed.items())}) to choose the target and start the "
                          "fit; rendered by Cycles as the file holds it")


TRANSMITTING = {"BSDF_GLASS", "BSDF_REFRACTION", "BSDF_TRANSLUCENT", "BSDF_TRANSPARENT", "SUBSURFACE_SCATTERING",
                "BSDF_HAIR", "BSDF_HAIR_PRINCIPLED", "BSDF_SHEEN_VOLUME", "PRINCIPLED_VOLUME"}
"""Nodes through which light may pass (a Principled BSDF: by its transmission or subsurface weight)."""


def _upstream(output) -> list:
    """The nodes the output's Surface and Volume use (through links; inside a node group, every node the
    group's own output uses), each once: what renders, not what the tree also holds."""
    found, todo = {}, [link.from_node for name in ("Surface", "Volume") for link in output.inputs[name].links]
    while todo:
        node = todo.pop()
        if node.as_pointer() in found:
            continue
        found[node.as_pointer()] = node
        todo += [link.from_node for sock in node.inputs for link in sock.links]
        group = getattr(node, "node_tree", None) if node.type == "GROUP" else None
        if group is not None:
            todo += [link.from_node for n in group.nodes if n.type == "GROUP_OUTPUT" for sock in n.inputs
                     for link in sock.links]
    return list(found.values())


def _transmits(nodes) -> bool:
    for node in nodes:
        if node.type in TRANSMITTING:
            return True
        if node.type == "BSDF_PRINCIPLED" and any(
                input_socket(node, name).is_linked or input_socket(node, name).default_value > 0.0
                for name in ("Transmission Weight", "Subsurface Weight")):
            return True
    return False


def _files(bpy, nodes) -> list[str]:
    """The files the material reads besides its .blend: its images (not packed) and the libraries its node
    groups are linked from (their content is part of its key)."""
    out = []
    for node in nodes:
        image = getattr(node, "image", None) if node.type == "TEX_IMAGE" else None
        if image is not None and image.source == "FILE" and image.packed_file is None:
            out.append(bpy.path.abspath(image.filepath, library=image.library))
        group = getattr(node, "node_tree", None) if node.type == "GROUP" else None
        if group is not None and group.library is not None:
            out.append(bpy.path.abspath(group.library.filepath))
    return sorted(set(out))


def _spatial(nodes) -> list[str]:
    """The texture and attribute nodes the material uses: what makes it vary over the surface (a Fresnel or
    Layer Weight varies with the angle only, which a uniform material can follow)."""
    return [_source(node) for node in nodes if node.type.startswith("TEX_") or node.type in ("ATTRIBUTE",
                                                                                          "VERTEX_COLOR")]


def _read(bpy, node, model: str, entry: dict, defaults) -> None:
    """The node's unconnected inputs as the model's parameters; what it cannot carry in the notes."""
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

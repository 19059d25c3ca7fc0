"""A UsdShade material's surface shader read as a source: a UsdPreviewSurface as the
`threejs:usd_preview_surface` model (every input of the specification, textures through UsdUVTexture
with their colour spaces, read as their means), and a MaterialX shader written directly in USD
(`ND_open_pbr_surface_surfaceshader`, `ND_standard_surface_surfaceshader` ...) by the MaterialX
reader's semantics (`adapters/materialx`)."""

from __future__ import annotations

import functools
from brdfremap.core.data.errors import ConfigError
from brdfremap.core.data.schemas import Material
from brdfremap.core.data.textures import colour_to_linear
from brdfremap.core.library.formats import Entry, clip_into

from .preview import INPUTS, WORKFLOWS
from .textures import read_texture

QUIET = {"normal", "displacement", "occlusion", "opacityMode", "opacityThreshold"}
"""Inputs that say nothing about a smooth sphere's reflection: listed only when driven or set away
from their defaults (`_away`)."""
INVISIBLE = ("opacity 0: UsdPreviewSurface's consumers draw it fully transparent (three.js's USDLoader and "
             "Blender's importer blend by alpha; the specification has no transmission), so there is nothing to "
             "match; remap the stage's MaterialX/OpenPBR surface of it where it has one")
LINEAR = {"", "lin_rec709", "lin_srgb", "raw", "Raw", "linear", "scene-linear Rec.709-sRGB"}


@functools.cache
def preview_defaults() -> dict[str, object]:
    """UsdPreviewSurface's inputs and their defaults, from its definition in MaterialX's standard
    library (usd-core's wheel ships no shader definitions)."""
    from brdfremap.adapters.materialx.mxlib import standard_libraries

    lib = standard_libraries()  # held: a node definition's values are read through its document
    nodedef = lib.getNodeDef("ND_UsdPreviewSurface_surfaceshader")
    return {i.getName(): _plain(i.getValue()) for i in nodedef.getActiveInputs()}


def _plain(value):
    return tuple(float(x) for x in value.asTuple()) if hasattr(value, "asTuple") else value


def surface(material):
    """The material's surface shader: its MaterialX one where it has one, else its universal one;
    and the shader's id."""
    shader = material.ComputeSurfaceSource("mtlx")[0]  # the universal output where there is no mtlx one
    if shader and shader.GetPrim().IsValid():
        return shader, shader.GetIdAttr().Get() or ""
    return None, ""


def read_preview(shader, name: str, file: str, spec) -> Entry:
    """A UsdPreviewSurface as the `usd_preview_surface` model's parameters."""
    defaults = preview_defaults()
    notes: list[str] = ["rendered as three.js's USDLoader reads UsdPreviewSurface (the real-time consumer here)"]
    textured: list[str] = []
    params: dict = {}
    try:
        for pname, iname in INPUTS.items():
            value = _input(shader.GetInput(iname), name, iname, notes, textured)
            if value is None:
                continue
            if pname == "use_specular_workflow":
                value = WORKFLOWS[1 if int(value) else 0]
            params[pname] = value
        notes += clip_into(spec, params)
    except ConfigError as exc:
        return Entry(name=name, file=file, problem=str(exc))
    if float(params.get("opacity", 1.0)) <= 0.0:
        return Entry(name=name, file=file, problem=INVISIBLE)
    notes += _others(shader, defaults, name)
    if not any(shader.GetInput(i) and shader.GetInput(i).GetAttr().HasAuthoredValue() for i in INPUTS.values()):
        notes.append("none of its inputs is authored here: the specification's defaults")
    return Entry(name=name, file=file, notes=notes, textured=textured,
                 material=Material(adapter="threejs", model=spec.name, params=params, name=name))


def _input(inp, name: str, iname: str, notes: list[str], textured: list[str]):
    """An input's value: its authored value (a colour in another colour space made linear), the
    mean of the texture that drives it, or None (unauthored: the model's default, the specification's)."""
    if not inp:  # an input the shader does not have is an invalid (false) UsdShade.Input
        return None
    sources = inp.GetConnectedSources()[0]
    if sources:
        return read_texture(inp, sources[0], name, iname, notes, textured)
    value = inp.Get()
    if value is None:
        return None
    if isinstance(value, str):  # a token or string where the specification has a number
        raise ConfigError(f"{name}: inputs:{iname} is {value!r}, where UsdPreviewSurface takes a number: give it "
                          "a number or remove it")
    if hasattr(value, "__len__"):
        rgb = tuple(_r(x) for x in value)
        space = inp.GetAttr().GetColorSpace() if inp.GetAttr().HasColorSpace() else ""
        if space not in LINEAR:
            linear = colour_to_linear(rgb, space, where=f"{name}: inputs:{iname}")
            notes.append(f"inputs:{iname} is in {space}: read as ({', '.join(f'{x:.4g}' for x in linear)}) in linear "
                         "Rec.709, the renderers' working space")
            return tuple(linear)
        return rgb
    return _r(value) if not isinstance(value, (bool, int)) else int(value)


def _r(x) -> float:
    """USD keeps 32-bit floats: 0.76 comes back as 0.7599999905; 7 digits are what was written."""
    return float(f"{float(x):.7g}")


def _others(shader, defaults: dict[str, object], name: str) -> list[str]:
    """Notes on the shader's inputs the model does not read: unknown to the specification (one line
    naming it), emission, and geometry inputs driven or away from their defaults."""
    known = set(INPUTS.values())
    out = []
    for inp in shader.GetInputs():
        iname = inp.GetBaseName()
        if iname in known:
            continue
        if iname not in defaults:
            out.append(f"inputs:{iname} is not an input of UsdPreviewSurface (its specification's are "
                       f"{', '.join(sorted(defaults))}): ignored")
        elif iname == "emissiveColor" and (inp.GetConnectedSources()[0] or any(float(x) for x in inp.Get() or ())):
            out.append("its emission (inputs:emissiveColor) is not read: the probe measures reflection")
        elif _away(inp, defaults[iname]):
            out.append(f"inputs:{iname} is {'driven by a shader' if inp.GetConnectedSources()[0] else 'set'}: not "
                       "read (the probe is a smooth sphere)")
    return out


def _away(inp, default) -> bool:
    if inp.GetConnectedSources()[0]:
        return True
    value = inp.Get()
    if value is None:
        return False
    if isinstance(value, str) or isinstance(default, str):  # a token (opacityMode "presence") or an asset
        return str(value) != str(default)
    given = [float(x) for x in value] if hasattr(value, "__len__") else [float(value)]
    want = [float(x) for x in default] if isinstance(default, tuple) else [float(default)]
    return given != want


def read_mtlx_shader(shader, node_id: str, name: str, file: str) -> Entry:
    """A MaterialX shader written directly in USD, read as the MaterialX reader reads the same
    node in a document: its inputs copied into one (connections listed as textured, read at their
    defaults), then the reader's correspondence."""
    from brdfremap.adapters.materialx.mxlib import mx, standard_libraries
    from brdfremap.adapters.materialx.reader import material_entry, needs_document

    m = mx()
    lib = standard_libraries()
    nodedef = lib.getNodeDef(node_id)
    if nodedef is None or nodedef.getType() != "surfaceshader":
        return Entry(name=name, file=file, problem=f"shader {node_id!r} is not a surface shader of MaterialX's "
                                                   "standard libraries: no reader here")
    doc = m.createDocument()
    doc.setDataLibrary(lib)  # the definitions by reference (importing them costs 26 ms a shader)
    node = doc.addNode(nodedef.getNodeString(), doc.createValidChildName("usd_shader"), "surfaceshader")
    textured, notes = [], []
    for inp in shader.GetInputs():
        iname = inp.GetBaseName()
        declared = nodedef.getActiveInput(iname)
        if declared is None:
            notes.append(f"inputs:{iname} is not an input of {node_id}: ignored")
        elif inp.GetConnectedSources()[0]:
            textured.append(f"{iname} <- {inp.GetConnectedSources()[0][0].source.GetPath()} (read at its default)")
        elif inp.Get() is not None:
            node.setInputValue(iname, _mx_value(m, inp.Get(), declared.getType()), declared.getType())
    entry = needs_document(material_entry(m, doc.addMaterialNode(doc.createValidChildName("usd_material"), node), file,
                                          name=name))
    return entry.model_copy(update={"notes": [*entry.notes, *notes], "textured": [*entry.textured, *textured]})


def _mx_value(m, value, kind: str):
    if kind == "color3":
        return m.Color3(*[float(x) for x in value])
    if kind in ("vector3", "color4", "vector2", "vector4"):
        return {"vector3": m.Vector3, "color4": m.Color4, "vector2": m.Vector2, "vector4": m.Vector4}[kind](
            *[float(x) for x in value])
    if kind == "integer":
        return int(value)
    if kind == "boolean":
        return bool(value)
    if kind == "float":
        return float(value)
    return str(value)


PREVIEW_IDS = ("UsdPreviewSurface", "ND_UsdPreviewSurface_surfaceshader")
"""A UsdPreviewSurface by its USD id and by MaterialX's node definition (three.js reads both as one)."""

"""Converted libraries as one MaterialX document (`library.mtlx`), validated against the standard
libraries before it is written:

- `MaterialXWriter`: a library remapped to a MaterialX shader (`--to materialx:open_pbr_surface`): each
  material its fitted shader node and a material, matched in MaterialX's own renderer;
- `PrincipledAsOpenPbr`: a library converted to Blender's Principled BSDF, also as OpenPBR by the fixed
  correspondence (Blender's Principled follows OpenPBR): its values under OpenPBR's names, not matched
  (the document says so; remap to materialx:open_pbr_surface for a matched one)."""

from __future__ import annotations

from pathlib import Path

from brdfremap.core.data.atomic import write_text_atomic
from brdfremap.core.data.errors import RenderError
from brdfremap.core.library.formats import Converted

from .correspondence import DIRECT, open_pbr_inputs
from .mxlib import mx, standard_libraries


def _image(m, doc, shader, name: str, target: str, kind: str, tex) -> None:
    """An `image` node reading a map (its file relative to the document) into a shader input."""
    node = doc.addNode("image", doc.createValidChildName(f"{name}_{target}"), kind)
    f = node.addInput("file", "filename")
    f.setValueString(tex.file)
    f.setColorSpace("srgb_texture" if tex.colorspace == "srgb" else "lin_rec709")
    if tex.filter == "nearest":
        node.setInputValue("filtertype", "closest")
    inp = shader.getInput(target) or shader.addInput(target, kind)
    inp.removeAttribute("value")
    inp.setConnectedNode(node)


def _validated(m, doc, folder: Path) -> list[Path]:
    check = m.createDocument()
    check.copyContentFrom(doc)
    check.importLibrary(standard_libraries())
    valid, why = check.validate()
    if not valid:
        raise RenderError(f"the MaterialX library did not validate: {why.strip().splitlines()[0]}")
    return [write_text_atomic(Path(folder) / "library.mtlx", m.writeToXmlString(doc))]


class MaterialXWriter:
    """Materials remapped to MaterialX shaders: each its fitted shader and a material."""

    name = "MaterialX library (fitted shaders)"
    adapter = "materialx"
    models: tuple[str, ...] = ()

    def write(self, folder: Path, items: list[Converted]) -> list[Path]:
        from .models import MODELS, mx_type, value_string

        m = mx()
        doc = m.createDocument()
        doc.setDocString("brdf-remap: materials remapped to MaterialX shaders, each fitted to its source in "
                         "MaterialX's own renderer")
        for item in items:
            model = MODELS[item.model]
            params = model.complete(item.params)
            name = doc.createValidChildName(item.name)
            shader = doc.addNode(model.category, doc.createValidChildName(f"{name}_shader"), "surfaceshader")
            for p in model.parameters:
                if params[p.name] != p.default:
                    shader.addInput(p.name, mx_type(p.kind, p.choices)).setValueString(value_string(params[p.name]))
            for pname, tex in sorted(item.textures.items()):
                _image(m, doc, shader, name, pname, mx_type(model.param(pname).kind, ()), tex)
            doc.addMaterialNode(name, shader).setDocString(f"source material: {item.name}")
        return _validated(m, doc, folder)


class PrincipledAsOpenPbr:
    """A library converted to Blender's Principled BSDF, also as OpenPBR by the correspondence."""

    name = "MaterialX library (Principled's values as open_pbr_surface)"
    adapter = "cycles"
    models = ("principled",)

    def write(self, folder: Path, items: list[Converted]) -> list[Path]:
        from brdfremap.adapters.cycles.models import PRINCIPLED

        from .models import MODELS, mx_type

        openpbr = MODELS["open_pbr_surface"]
        m = mx()
        doc = m.createDocument()
        doc.setDocString("brdf-remap: materials converted to Blender's Principled BSDF, written as OpenPBR by name "
                         "(Blender's Principled BSDF follows OpenPBR); not matched in MaterialX's renderer: "
                         "remap --to materialx:open_pbr_surface for documents fitted there")
        for item in items:  # each a Principled BSDF (`models`: the library hands it no other)
            params = PRINCIPLED.complete(item.params)
            name = doc.createValidChildName(item.name)
            shader = doc.addNode("open_pbr_surface", doc.createValidChildName(f"{name}_shader"), "surfaceshader")
            for key, v in open_pbr_inputs(params).items():
                shader.setInputValue(key, m.Color3(*v) if isinstance(v, tuple) else float(v))
            for pname, tex in sorted(item.textures.items()):
                if pname in DIRECT:  # an input the correspondence scales (Specular IOR Level) keeps its number
                    target = openpbr.param(DIRECT[pname])
                    _image(m, doc, shader, name, target.name, mx_type(target.kind, target.choices), tex)
            material = doc.addMaterialNode(name, shader)
            loose = sorted(set(item.textures) - set(DIRECT))
            material.setDocString(f"source material: {item.name}" + (
                f"; maps not read here (no open_pbr_surface input takes them as they are, see library.blend): "
                f"{', '.join(loose)}, written as their value at the textures' mean" if loose else ""))
        return _validated(m, doc, folder)

"""A library converted to Cycles' Principled BSDF, also as one MaterialX document: an
open_pbr_surface and a surfacematerial per material, validated against the standard libraries
before it is written."""

from __future__ import annotations

from pathlib import Path

from brdfremap.core.data.atomic import write_text_atomic
from brdfremap.core.data.errors import RenderError
from brdfremap.core.library.formats import Converted

from .correspondence import DIRECT, open_pbr_inputs
from .reader import mx, standard_libraries


def _image(m, doc, shader, name: str, pname: str, tex) -> None:
    """An `image` node reading a map (its file relative to the document) into the shader input that
    takes the parameter as it is; an input the correspondence scales (Specular IOR Level) keeps its number."""
    target = DIRECT.get(pname)
    if target is None:
        return
    kind = "color3" if pname in ("base_color", "specular_tint") else "float"
    node = doc.addNode("image", doc.createValidChildName(f"{name}_{pname}"), kind)
    f = node.addInput("file", "filename")
    f.setValueString(tex.file)
    f.setColorSpace("srgb_texture" if tex.colorspace == "srgb" else "lin_rec709")
    if tex.filter == "nearest":
        node.setInputValue("filtertype", "closest")
    inp = shader.getInput(target) or shader.addInput(target, kind)
    inp.removeAttribute("value")
    inp.setConnectedNode(node)


class MaterialXWriter:
    name = "MaterialX library (open_pbr_surface)"
    adapter = "cycles"
    models = ("principled",)

    def write(self, folder: Path, items: list[Converted]) -> list[Path]:
        from brdfremap.adapters.cycles.models import PRINCIPLED

        m = mx()
        doc = m.createDocument()
        doc.setDocString("brdf-remap: converted materials as OpenPBR (Blender's Principled BSDF follows OpenPBR)")
        for item in items:  # each a Principled BSDF (`models`: the library hands it no other)
            params = PRINCIPLED.complete(item.params)
            name = doc.createValidChildName(item.name)
            shader = doc.addNode("open_pbr_surface", doc.createValidChildName(f"{name}_shader"), "surfaceshader")
            for key, v in open_pbr_inputs(params).items():
                shader.setInputValue(key, m.Color3(*v) if isinstance(v, tuple) else float(v))
            for pname, tex in sorted(item.textures.items()):
                _image(m, doc, shader, name, pname, tex)
            material = doc.addMaterialNode(name, shader)
            loose = sorted(set(item.textures) - set(DIRECT))
            material.setDocString(f"source material: {item.name}" + (
                f"; maps not read here (no open_pbr_surface input takes them as they are, see library.blend): "
                f"{', '.join(loose)}, written as their value at the textures' mean" if loose else ""))
        check = m.createDocument()
        check.copyContentFrom(doc)
        check.importLibrary(standard_libraries())
        valid, why = check.validate()
        if not valid:
            raise RenderError(f"the MaterialX library did not validate: {why.strip().splitlines()[0]}")
        return [write_text_atomic(Path(folder) / "library.mtlx", m.writeToXmlString(doc))]

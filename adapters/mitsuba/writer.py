"""A converted library as one Mitsuba 3 XML file: a `<bsdf id=...>` per material, loadable with
`mitsuba.load_file` and by `<include filename="library.xml"/>` in a scene."""

from __future__ import annotations

from pathlib import Path
from xml.sax.saxutils import quoteattr

from brdfremap.core.data.atomic import write_text_atomic
from brdfremap.core.library.formats import Converted

from .adapter import bsdf_xml
from .models import MODELS

PYTHON_PLUGINS = ("ward", "phong", "ashikhmin_shirley", "ashikhmin_shirley_plastic")


class MitsubaLibraryWriter:
    name = "Mitsuba 3 library (XML)"
    adapter = "mitsuba"
    models: tuple[str, ...] = ()

    def write(self, folder: Path, items: list[Converted]) -> list[Path]:
        lines = ['<?xml version="1.0" encoding="utf-8"?>',
                 "<!-- brdf-remap: converted materials, one <bsdf> per source material (its id is the source's "
                 "name). Load it with mitsuba.load_file or <include filename=\"library.xml\"/>. -->"]
        if any(i.model in PYTHON_PLUGINS for i in items):
            lines.append("<!-- Some are Python plugins: call brdfremap.adapters.mitsuba.register_bsdfs() after "
                         "mitsuba.set_variant() before loading. -->")
        lines.append('<scene version="3.0.0">')
        for item in items:
            params = MODELS[item.model].complete(item.params)
            body = bsdf_xml(item.model, params, textures=item.textures).strip().splitlines()
            body[0] = body[0].replace("<bsdf ", f"<bsdf id={quoteattr(item.name)} ", 1)
            lines += ["    " + line for line in body]
        lines.append("</scene>")
        return [write_text_atomic(Path(folder) / "library.xml", "\n".join(lines) + "\n")]

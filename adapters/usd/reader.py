"""USD stages as libraries, through usd-core (`.usd`, `.usda`, `.usdc`, `.usdz`): every UsdShade
Material of the stage as it opens is an entry, and so is every material a variant the stage does not
select makes different (named "copper [example_material=usdpreview_copper]"); a material's MaterialX
surface is read by the MaterialX reader's semantics, its universal UsdPreviewSurface as the
`threejs:usd_preview_surface` model; a `.mtlx` document the stage references is read from the file
beside it (usd-core has no UsdMtlx). A layer the stage cannot load is one line, and the other
materials are read all the same."""

from __future__ import annotations

from pathlib import Path

from brdfremap.core.library.formats import Entry

from . import stage as _stage
from .shaders import PREVIEW_IDS, read_mtlx_shader, read_preview, surface


class UsdReader:
    name = "USD (.usd, .usda, .usdc, .usdz)"
    suffixes = (".usd", ".usda", ".usdc", ".usdz")

    def accepts(self, path: Path) -> bool:
        return True

    def read(self, path: Path) -> list[Entry]:
        stage = _stage.open_stage(path)
        file = str(path)
        entries = [Entry(name=f"{path.name}: layer", file=file, problem=p, unreadable=True)
                   for p in _stage.problems(stage)]
        documents: dict = {}
        base = _materials(stage, file, documents)
        found = dict(base)
        previous = None
        for variant in _stage.variants(stage):
            _stage.select(stage, variant, previous)
            previous = variant
            for key, entry in _materials(stage, file, documents).items():
                if key not in base or _differs(base[key], entry):
                    found[(key, variant.label)] = entry.model_copy(update={"name": f"{entry.name} [{variant.label}]"})
        _stage.select(stage, None, previous)
        return entries + _named(found)


def _materials(stage, file: str, documents: dict) -> dict:
    """The stage's materials as it is composed now, by a key that stays the same across variants:
    ('prim', path) for a UsdShade Material, ('mtlx', document, material) for one a `.mtlx` holds
    (``documents``: each referenced document's entries, read once)."""
    from pxr import UsdShade

    out: dict = {}
    for prim in stage.Traverse():
        if prim.IsA(UsdShade.Material):
            out[("prim", str(prim.GetPath()))] = _entry(UsdShade.Material(prim), prim.GetName(), file)
    for ref in _stage.mtlx_references(stage):
        if ref not in documents:
            documents[ref] = _mtlx_entries(ref, file)
        for entry in documents[ref]:
            out[("mtlx", str(ref.file), entry.name)] = entry
    return out


def _entry(material, name: str, file: str) -> Entry:
    from brdfremap.adapters.threejs.models import USD_PREVIEW

    shader, node_id = surface(material)
    if shader is None:
        return Entry(name=name, file=file, problem="no surface shader (outputs:surface and outputs:mtlx:surface "
                                                   "connect to nothing)")
    if node_id in PREVIEW_IDS:
        return read_preview(shader, name, file, USD_PREVIEW)
    if node_id.startswith("ND_"):
        return read_mtlx_shader(shader, node_id, name, file)
    return Entry(name=name, file=file, problem=f"shader {node_id or shader.GetPath()!s} has no reader here (known: "
                                               "UsdPreviewSurface, and MaterialX's surface shaders by their ND_ ids)")


def _mtlx_entries(ref, file: str) -> list[Entry]:
    """The materials of a referenced `.mtlx` document (all of them, or the one the reference names)."""
    from brdfremap.adapters.materialx.reader import MaterialXReader
    from brdfremap.core.data.errors import ConfigError

    shown = ref.file.name
    if not ref.file.is_file():
        return [Entry(name=shown, file=file, problem=f"{ref.prim} references the MaterialX document {ref.file}, "
                                                      "which is not there (usd-core reads no .mtlx through USD: "
                                                      "the tool reads it from its file)", unreadable=True)]
    try:
        entries = MaterialXReader().read(ref.file)
    except ConfigError as exc:
        return [Entry(name=shown, file=file, problem=str(exc), unreadable=True)]
    from pxr import Sdf

    target = Sdf.Path(ref.target) if ref.target else Sdf.Path.emptyPath
    wanted = target.name if target.pathElementCount > 2 else ""  # /MaterialX/Materials/gold: that one
    note = f"from {shown}, which {ref.prim} references (read from the file: usd-core has no UsdMtlx)"
    return [e.model_copy(update={"notes": [note, *e.notes]}) for e in entries if not wanted or e.name == wanted]


def _differs(a: Entry, b: Entry) -> bool:
    return (a.material, a.problem) != (b.material, b.problem)


def _named(found: dict) -> list[Entry]:
    """The entries, a material whose name another in the stage shares named by its parent too
    ("usdpreview/plastic")."""
    counts: dict[str, int] = {}
    for e in found.values():
        counts[e.name] = counts.get(e.name, 0) + 1
    out = []
    for key, e in found.items():
        prim_key = key[0] if isinstance(key[0], tuple) else key
        if counts[e.name] > 1 and prim_key[0] == "prim":
            parent = prim_key[1].rsplit("/", 2)[-2]
            e = e.model_copy(update={"name": f"{parent}/{e.name}"})
        elif counts[e.name] > 1 and prim_key[0] == "mtlx":
            e = e.model_copy(update={"name": f"{Path(prim_key[1]).stem}/{e.name}"})
        out.append(e)
    return out

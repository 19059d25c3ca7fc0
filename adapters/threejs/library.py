"""glTF files: a converted library written as `library.gltf` (every material under its source's
name, each on a sphere of its own in a row, so any viewer shows them), and a reader of `.gltf` and
`.glb` materials (through pygltflib) as `threejs:gltf_pbr` sources."""

from __future__ import annotations

import hashlib
import json
import urllib.parse
from pathlib import Path
from typing import Any

from brdfremap.core.data.atomic import write_text_atomic
from brdfremap.core.data.errors import ConfigError
from brdfremap.core.data.schemas import Material, Native, Value
from brdfremap.core.library.entries import Converted, Entry
from brdfremap.core.data.textures import ColourSpace, Filter, Texture, mean_value, read_values, texture

from . import gltf, images, textures
from .models import MODELS
from .spheres import sphere_document


def material_document(doc: dict[str, Any], index: int, embedded: bool = True) -> dict[str, Any]:
    """One material of a glTF document, alone in a document of its own (as the adapter renders one),
    with the textures, images and samplers it reads, numbered anew. Its images must be embedded as
    data URIs (as this tool writes them): the page reads nothing else; ``embedded`` false: they are files,
    which the adapter embeds (`ThreeJsAdapter.render_native`)."""
    mat = json.loads(json.dumps(doc["materials"][index]))
    out: dict[str, Any] = {"asset": {"version": "2.0"}, "materials": [mat]}
    refs = _texture_refs(mat)
    if refs:
        imgs, samplers, texs = [], [], []
        for ref in refs:
            tex = dict(doc["textures"][ref["index"]])
            for key, pool, into in (("source", doc.get("images", []), imgs),
                                    ("sampler", doc.get("samplers", []), samplers)):
                if key in tex:
                    item = pool[tex[key]]
                    if key == "source" and embedded and \
                            urllib.parse.urlparse(str(item.get("uri", ""))).scheme != "data":
                        raise ConfigError(f"images[{tex[key]}] is not embedded as a data URI: render the file's "
                                          "materials as this tool writes them")
                    if item not in into:
                        into.append(item)
                    tex[key] = into.index(item)
            if tex not in texs:
                texs.append(tex)
            ref["index"] = texs.index(tex)
        out.update(textures=texs, images=imgs, samplers=samplers)
    used = sorted(_extensions_in(mat))
    if used:
        out["extensionsUsed"] = used
    return out


def _extensions_in(node: Any) -> set[str]:
    """Every extension a material uses, its own and its texture references' (KHR_texture_transform): GLTFLoader
    reads only those the document lists as used."""
    if isinstance(node, list):
        return set().union(*(_extensions_in(v) for v in node)) if node else set()
    if not isinstance(node, dict):
        return set()
    own = set(node.get("extensions") or {}) if isinstance(node.get("extensions"), dict) else set()
    return own.union(*(_extensions_in(v) for v in node.values()))


def _texture_refs(node: Any) -> list[dict[str, Any]]:
    """Every texture reference ({"index": n, ...} under a glTF `...Texture` key) in a material."""
    if not isinstance(node, dict):
        return []
    found = [v for k, v in node.items() if k in gltf.TEXTURES and isinstance(v, dict) and "index" in v]
    return found + [r for k, v in node.items() if k not in gltf.TEXTURES for r in _texture_refs(v)]


class GltfLibraryWriter:
    name = "glTF 2.0 library (library.gltf)"
    adapter = "threejs"
    models: tuple[str, ...] = ("gltf_pbr",)

    def write(self, folder: Path, items: list[Converted]) -> list[Path]:
        spec = MODELS["gltf_pbr"]
        kinds = textures.kinds(spec)
        maps = [textures.maps_from_files(folder, i.textures, kinds) for i in items]
        doc = sphere_document([(i.name, i.params) for i in items], spec, maps)
        return [write_text_atomic(Path(folder) / "library.gltf", json.dumps(doc, indent=1) + "\n")]


def read_document(path: Path) -> tuple[dict[str, Any], bytes | None]:
    """A .gltf or .glb file's JSON (pygltflib reads both), and a .glb's binary chunk."""
    from pygltflib import GLTF2

    try:
        g = GLTF2.load(str(path))
    except Exception as exc:  # pygltflib raises what its parser meets: JSON, struct and key errors alike
        raise ConfigError(f"cannot read it as glTF (is the file whole?): "
                          f"{str(exc).splitlines()[0] if str(exc) else type(exc).__name__}", file=str(path)) from None
    if g is None:
        raise ConfigError("cannot read it as glTF (not a .gltf or .glb file)", file=str(path))
    return json.loads(g.to_json()), g.binary_blob()


class GltfReader:
    """glTF materials as `threejs:gltf_pbr` sources. A base colour, metallic or roughness driven by its
    core texture is read as its factor times the image's mean, and (of factor 1) as that texture,
    which a table of `gltf_pbr` remaps texel by texel; every other texture-driven input is listed and
    read as its factor."""

    name = "glTF 2.0 (.gltf, .glb)"
    suffixes = (".gltf", ".glb")

    def accepts(self, path: Path) -> bool:
        return True

    def read(self, path: Path) -> list[Entry]:
        doc, blob = read_document(path)
        version = str((doc.get("asset") or {}).get("version", ""))
        if version.partition(".")[0] != "2":
            raise ConfigError(f"is glTF {version or 'of no version'}: this reads glTF 2.0", file=str(path),
                              field="asset.version")
        return [self._entry(m, i, Path(path), doc, blob) for i, m in enumerate(doc.get("materials") or [])]

    @staticmethod
    def _entry(m: Any, i: int, path: Path, doc: dict[str, Any], blob: bytes | None) -> Entry:
        """One material's entry; a malformed one (a factor that is not a number ...) is an entry that
        cannot be converted, saying which and why, so the file's other materials still are."""
        name = m.get("name") if isinstance(m, dict) and isinstance(m.get("name"), str) and m["name"] else \
            f"material {i}"
        try:
            return GltfReader._read_entry(m, i, name, path, doc, blob)
        except (TypeError, ValueError, AttributeError) as exc:
            return Entry(name=name, file=str(path), problem=f"materials[{i}] is malformed glTF ({_first_line(exc)}): "
                                                            "check it with the Khronos glTF validator")

    @staticmethod
    def _read_entry(m: dict[str, Any], index: int, name: str, path: Path, doc: dict[str, Any],
                    blob: bytes | None) -> Entry:
        params, notes, textured = gltf.read_material(m)
        maps, constants, said = _maps(m, doc, blob, path, name)
        params.update(constants)
        spec = MODELS["gltf_pbr"]
        clipped = {k: spec.param(k).clip(tuple(v) if isinstance(v, (list, tuple)) else v) for k, v in params.items()}
        notes += [f"{k} {_shown(params[k])} is outside the model's bounds: read as {_shown(v)}"
                  for k, v in clipped.items() if _shown(v) != _shown(params[k])]
        entry = Entry(name=name, file=str(path), notes=notes + said, textured=textured,
                      material=Material(adapter="threejs", model="gltf_pbr", name=name, params=clipped,
                                        textures=maps))
        return _as_written(doc, blob, path, entry, index) if textured or notes or said else entry


def _as_written(doc: dict[str, Any], blob: bytes | None, path: Path, entry: Entry, index: int) -> Entry:
    """A material the reading does not carry whole (a texture, an extension or input it does not read), rendered
    by three.js's GLTFLoader from the file's own material ``index`` (`Material.native`: the material alone in a
    document, each image it reads named by its file, which `ThreeJsAdapter.render_native` embeds), as any glTF
    viewer shows it; where an image cannot be read, as read, and said."""
    try:
        alone, files = _alone(doc, blob, path, index)
    except ConfigError as exc:
        return entry.model_copy(update={"notes": [*entry.notes, f"not rendered as written: {exc}"]})
    text = json.dumps(alone, sort_keys=True)
    digest = hashlib.sha256(text.encode())
    for f in files:
        digest.update(f.read_bytes())
    exts = doc["materials"][index].get("extensions") or {}
    through = exts.get("KHR_materials_transmission") or {}
    transmits = float(through.get("transmissionFactor", 0.0)) > 0.0 or "transmissionTexture" in through
    native = Native(file=str(path.resolve()), name=entry.name, sha256=digest.hexdigest(), element=text,
                    driven=tuple(entry.textured), transmits=transmits)
    return entry.model_copy(update={"material": entry.material.model_copy(update={"native": native})})


def _alone(doc: dict[str, Any], blob: bytes | None, path: Path, index: int) -> tuple[dict[str, Any], list[Path]]:
    """Material ``index`` alone in a document, each image it reads (a file beside the glTF or a .glb's buffer view,
    written to the cache by content) named by its absolute path; and those files."""
    used = {images.item(doc, "textures", ref["index"]).get("source") for ref in _texture_refs(doc["materials"][index])}
    imgs = list(doc.get("images") or [])
    files = []
    for i in sorted(x for x in used if isinstance(x, int)):
        file = images.image_file(doc, blob, path.parent, i).resolve()
        files.append(file)
        imgs[i] = {k: v for k, v in imgs[i].items() if k not in ("uri", "bufferView", "mimeType")} | {"uri": str(file)}
    return material_document({**doc, "images": imgs} if imgs else doc, index, embedded=False), files


def _maps(m: dict[str, Any], doc: dict[str, Any], blob: bytes | None, path: Path,
          name: str) -> tuple[dict[str, Texture], dict[str, Value], list[str]]:
    """The material's core textures: those of factor 1 as textures of their parameters (a table remaps
    them texel by texel); each one's constant, its factor times its image's mean (what a material
    without the texture would be on average, as a Mitsuba bitmap's constant is its mean); and notes."""
    wanted, notes = gltf.mapped_textures(m)
    kinds = textures.kinds(MODELS["gltf_pbr"])
    out: dict[str, Texture] = {}
    constants: dict[str, Value] = {}
    for param, index, channel, factor in wanted:
        try:
            tex = _map(doc, blob, path, index, channel, f"{name}: {param}")
            mean = mean_value(read_values(tex, kinds[param], where=f"{name}: {param}"))
        except ConfigError as exc:
            notes.append(f"{param}: {exc}: read as its factor")
            continue
        constants[param] = tuple(f * v for f, v in zip(factor, mean)) if isinstance(mean, tuple) else factor[0] * mean
        if all(f == 1.0 for f in factor):
            out[param] = tex
        else:
            notes.append(f"{param}: its texture is scaled by a factor of {_shown(tuple(factor))}: read as the "
                         f"factor times the image's mean, {_shown(constants[param])}, not texel by texel")
    return out, constants, notes


def _map(doc: dict[str, Any], blob: bytes | None, path: Path, index: int, channel: int | None,
         where: str) -> Texture:
    """Texture ``index`` as a texture of one parameter: its image's file, its sampler's filter (a grey
    image's channel is its grey: `read_values`)."""
    tex = images.item(doc, "textures", index)
    file = images.image_file(doc, blob, path.parent, tex.get("source"))
    which = tex.get("sampler")
    sampler = images.item(doc, "samplers", which) if which is not None else {}
    filt = Filter.NEAREST if sampler.get("magFilter") == textures.NEAREST else Filter.LINEAR
    space = ColourSpace.SRGB if channel is None else ColourSpace.LINEAR
    return texture(file, space, filt, channel=channel, where=where)


def _first_line(exc: BaseException) -> str:
    return (str(exc).strip().splitlines() or [type(exc).__name__])[0]


def _shown(v: Value) -> str:
    return ", ".join(f"{float(x):.4g}" for x in (v if isinstance(v, (list, tuple)) else [v]))

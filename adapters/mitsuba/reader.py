"""Mitsuba 3 scene files as libraries: every `<bsdf>` of a scene, read without Mitsuba.

As Mitsuba reads them: `<default>` values and `$name` substitution, `<include>`d files,
`<ref>`s followed, `twosided` (and bump and normal maps, opacity masks) unwrapped with a
note, RGB and uniform spectra, named IORs and conductor presets, and Mitsuba's own defaults
for what a BSDF leaves out. A BSDF of a type the adapter has no model for is listed with the
reason; the rest go on. Parsed with the standard library's XML parser: no entity or external
reference is resolved, and nothing a file names is run."""

from __future__ import annotations

import hashlib
import math
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from brdfremap.core.data.errors import ConfigError
from brdfremap.core.library.formats import Entry, clip_into
from brdfremap.core.data.schemas import Material, Native, ParamKind, Value
from brdfremap.core.data.textures import LUMA, Texture, read_values, texture

from .blend import COMPONENTS, SLOTS
from .models import MODELS
from .spectra import read_spectrum

NAMED_IOR = {"vacuum": 1.0, "helium": 1.00004, "hydrogen": 1.00013, "air": 1.000277, "carbon dioxide": 1.00045,
             "water": 1.3330, "acetone": 1.36, "ethanol": 1.361, "carbon tetrachloride": 1.461, "glycerol": 1.4729,
             "benzene": 1.501, "silicone oil": 1.52045, "bromine": 1.661, "water ice": 1.31, "fused quartz": 1.458,
             "pyrex": 1.470, "acrylic glass": 1.49, "polypropylene": 1.49, "bk7": 1.5046, "sodium chloride": 1.544,
             "amber": 1.55, "pet": 1.5750, "diamond": 2.419}
WRAPPERS = {"twosided": "two-sided (unwrapped)", "bumpmap": "its bump map is ignored",
            "normalmap": "its normal map is ignored", "mask": "its opacity mask is ignored"}
NO_RENDERER = {
    "hair": "hair is drawn along fibres (a curve's tangent), and the probe is a sphere: no renderer here draws it as its "
            "author's scene does",
    "polarizer": "a polarizer acts on the polarization of light, which the adapter's RGB variant does not carry: no "
                 "renderer here shows what it does",
    "retarder": "a retarder acts on the polarization of light, which the adapter's RGB variant does not carry: no "
                "renderer here shows what it does",
    "measured_polarized": "a polarized measured BRDF (a pBSDF file) renders only in Mitsuba's polarized spectral "
                          "variants, and the adapter renders in an RGB one: no renderer here renders it",
    "null": "a null BSDF is not a surface: nothing to remap"}
"""BSDF types listed as unsupported, and why: what no renderer here renders."""
AS_WRITTEN = {"measured": "", "pplastic": "roughplastic"}
"""BSDF types the adapter's variant renders that no model reads exactly: rendered by Mitsuba from the element as
written (`Material.native`), each with the model that reads it to start the fit ("": none)."""
ALPHAS = MODELS["roughconductor"]
"""Where alpha_u and alpha_v are described (for a model that reads them as one alpha)."""
CONVERTED = {"principled": ("eta",)}
"""Properties read into another parameter of the model (below)."""
IGNORED = {"sample_visible", "nonlinear"}
_SUBST = re.compile(r"\$([A-Za-z_][A-Za-z0-9_]*)")


class MitsubaXmlReader:
    name = "Mitsuba 3 scene (XML)"
    suffixes = (".xml",)

    def accepts(self, path: Path) -> bool:
        try:
            with open(path, "rb") as f:
                head = f.read(4096)
        except OSError:
            return True  # read() names the file and the reason
        return b"<scene" in head

    def read(self, path: Path) -> list[Entry]:
        doc = _Document(path)
        return [_entry(doc, elem, name, str(path)) for elem, name in doc.bsdfs()]


class _Document:
    """A scene with its includes inlined, `$name` substituted and BSDFs and textures by id."""

    def __init__(self, path: Path):
        self.path = path
        self.root = _parse(path)
        if self.root.tag != "scene":
            raise ConfigError(f"the root element is <{self.root.tag}>, not <scene>: not a Mitsuba scene", file=str(path))
        self.search = [path.parent]
        """Where file names are looked up, as Mitsuba's file resolver does: each `<path>` (relative to
        the file that gives it; the last first), then the scene's folder."""
        self._paths(self.root, path)
        self._inline(self.root, path, depth=0)
        defaults = {d.get("name", ""): d.get("value", "") for d in self.root.findall("default")}
        for elem in self.root.iter():
            for k, v in elem.attrib.items():
                if "$" in v:
                    elem.set(k, _substitute(v, defaults, path))
        self.ids = {e.get("id"): e for e in self.root.iter() if e.get("id") and e.tag in ("bsdf", "texture")}

    def _inline(self, parent: ET.Element, path: Path, depth: int) -> None:
        for i, child in enumerate(list(parent)):
            if child.tag != "include":
                continue
            if depth > 8:
                raise ConfigError("includes nest deeper than 8 (a loop?)", file=str(path))
            inc = path.parent / child.get("filename", "")
            sub = _parse(inc)
            self._paths(sub, inc)
            self._inline(sub, inc, depth + 1)
            parent.remove(child)
            for j, e in enumerate(sub):
                parent.insert(i + j, e)

    def _paths(self, root: ET.Element, path: Path) -> None:
        # Mitsuba puts each <path> ahead of what it had (the last given is looked in first).
        for p in root.findall("path"):
            self.search.insert(0, path.parent / p.get("value", ""))

    def find(self, name: str) -> Path:
        """A file the scene names, found as Mitsuba finds it (the first search folder that has it);
        a file found nowhere is a ConfigError naming the folders."""
        for folder in self.search:
            candidate = folder / name
            if candidate.is_file():
                return candidate.resolve()
        where = ", ".join(str(f) for f in dict.fromkeys(self.search))
        raise ConfigError(f"{name!r} is not found (looked in {where})", file=str(self.path))

    def bsdfs(self) -> list[tuple[ET.Element, str]]:
        """Every material of the scene: top-level BSDFs by id, anonymous ones inside shapes named
        after their shape (a shape's `<ref>` to a top-level one adds nothing)."""
        out, n = [], 0
        for elem in self.root:
            if elem.tag == "bsdf":
                n += 1
                out.append((elem, elem.get("id") or f"bsdf {n}"))
            elif elem.tag == "shape":
                for b in elem.findall("bsdf"):
                    shape = elem.get("id") or f"{elem.get('type', 'shape')} {len(out) + 1}"
                    out.append((b, b.get("id") or shape))
        return out

    def ref(self, elem: ET.Element) -> ET.Element:
        target = self.ids.get(elem.get("id", ""))
        if target is None:
            raise ConfigError(f"<ref id={elem.get('id')!r}> names nothing in the scene", file=str(self.path))
        return target


def _parse(path: Path) -> ET.Element:
    try:
        return ET.parse(path).getroot()
    except ET.ParseError as exc:
        line, col = exc.position
        what = str(exc).rsplit(": line ", 1)[0]  # the parser's words, without the position given apart
        raise ConfigError(f"malformed XML: {what}", file=str(path), field=f"line {line}, column {col + 1}") from None
    except OSError as exc:
        raise ConfigError(f"cannot read: {exc.strerror or exc}", file=str(path)) from None


def _substitute(text: str, defaults: dict[str, str], path: Path) -> str:
    def one(m: re.Match) -> str:
        if m.group(1) not in defaults:
            raise ConfigError(f"${m.group(1)} is used but no <default name={m.group(1)!r}> gives it a value",
                              file=str(path))
        return defaults[m.group(1)]

    return _SUBST.sub(one, text)


class Notes(list):
    """A reading's notes, and which of them say it left part of the material out (`drop`): such a material is
    rendered by Mitsuba from its element as written."""

    def __init__(self):
        super().__init__()
        self.dropped: list[str] = []

    def drop(self, text: str) -> None:
        self.append(text)
        self.dropped.append(text)


def _entry(doc: _Document, elem: ET.Element, name: str, file: str) -> Entry:
    notes = Notes()
    written = elem
    elem = _unwrap(doc, elem, notes)
    kind = model = elem.get("type", "")
    if kind in NO_RENDERER:
        return Entry(name=name, file=file, problem=f"{kind}: {NO_RENDERER[kind]}", notes=notes)
    if kind in AS_WRITTEN:
        return _as_written(doc, written, name, file, notes, AS_WRITTEN[kind],
                           f"a Mitsuba {kind} BSDF: no model reads it exactly")
    if model not in MODELS:
        if kind not in MATERIAL_PLUGINS:
            return Entry(name=name, file=file, problem=f"{kind!r} is not a BSDF Mitsuba ships (known: "
                                                       f"{', '.join(sorted(MATERIAL_PLUGINS))})", notes=notes)
        return _as_written(doc, written, name, file, notes, "", f"Mitsuba BSDF type {kind!r} has no model here")
    textures: dict[str, Texture] = {}
    try:
        params, textured = _blend_params(doc, elem, notes) if model == "blendbsdf" else \
            _params(doc, elem, model, notes, textures)
    except ConfigError as exc:
        if model != "blendbsdf":
            return Entry(name=name, file=file, problem=str(exc), notes=notes)
        return _as_written(doc, written, name, file, notes, "", str(exc))
    maps = [f"its {w.get('type', '')[:-3]} map" for w in written.iter("bsdf") if w.get("type") in SURFACE_MAPS]
    try:
        native = _native(doc, written, name, textured + maps) if notes.dropped else None
    except ConfigError as exc:  # a file it names is missing: Mitsuba could not load it either
        native = None
        notes.append(f"not rendered as written: {exc}")
    material = Material(adapter="mitsuba", model=model, params=params, name=name, textures=textures, native=native)
    return Entry(name=name, file=file, material=material, notes=notes, textured=textured)


SURFACE_MAPS = ("bumpmap", "normalmap")
"""Wrappers that make a material vary over the surface (said as such where a uniform target is fitted to it)."""


def _as_written(doc: _Document, elem: ET.Element, name: str, file: str, notes: Notes, reading: str,
                why: str) -> Entry:
    """A BSDF rendered as written, with the reading ``reading`` ("": none) of its properties where one is given."""
    try:
        native = _native(doc, elem, name, ())
    except ConfigError as exc:
        return Entry(name=name, file=file, problem=f"{why}, and Mitsuba cannot load it as written: {exc}", notes=notes)
    params: dict = {}
    model = ""
    if reading:
        inner = _unwrap(doc, elem, Notes())
        as_read = ET.Element("bsdf", {**inner.attrib, "type": reading})
        as_read.extend(list(inner))
        try:
            params, _ = _params(doc, as_read, reading, notes)
            model = reading
        except ConfigError as exc:
            notes.append(f"not read as {reading}: {exc}")
    if not model and native.transmits:
        params = {"transmission": 1.0}  # `AS_WRITTEN`'s: light passes
    notes.append(f"{why}: rendered by Mitsuba as written" + (f", read as {model} to start the fit" if model else ""))
    material = Material(adapter="mitsuba", model=model, params=params, name=name, native=native)
    return Entry(name=name, file=file, material=material, notes=notes)


def _native(doc: _Document, elem: ET.Element, name: str, driven) -> Native:
    """The element as Mitsuba loads it on its own: `<ref>`s replaced by what they name (their ids dropped: one
    `<ref>` used twice is two copies), every file it names made absolute (found as Mitsuba finds it), each
    plugin one Mitsuba ships for a material (`check_element`); its key the text with each file's content in
    place of its path (a moved scene keeps its results, an edited image is fitted again)."""
    copy = _resolved(doc, elem, depth=0)
    copy.set("version", "3.0.0")
    driven = driven or [f"{t.get('name', 'texture')} <- {t.get('type', 'texture')}" + "".join(
        f" {s.get('value')!r}" for s in t.iter("string") if s.get("name") == "filename") for t in copy.iter("texture")]
    keyed = []
    for e in copy.iter():
        e.attrib.pop("id", None)
        attr = "filename" if e.get("filename") else \
            "value" if e.tag == "string" and e.get("name") == "filename" and e.get("value") else None
        if attr is None:
            continue
        found = doc.find(e.get(attr))
        try:
            content = hashlib.sha256(found.read_bytes()).hexdigest()
        except OSError as exc:
            raise ConfigError(f"cannot read {found}: {exc.strerror or exc}", file=str(doc.path)) from None
        e.set(attr, str(found))
        keyed.append((str(found), content))
    text = ET.tostring(copy, encoding="unicode")
    check_element(text, str(doc.path))
    text_key = text
    for path, content in keyed:
        text_key = text_key.replace(path, content)
    digest = hashlib.sha256(text_key.encode())
    transmits = any(e.get("type") in TRANSMITTING for e in copy.iter("bsdf"))
    return Native(file=str(doc.path.resolve()), name=name, sha256=digest.hexdigest(), element=text,
                  driven=tuple(driven), transmits=transmits)


TRANSMITTING = {"dielectric", "roughdielectric", "thindielectric", "polarizer", "retarder", "null", "mask"}
MATERIAL_PLUGINS = frozenset({
    "diffuse", "dielectric", "thindielectric", "roughdielectric", "conductor", "roughconductor", "plastic",
    "roughplastic", "pplastic", "measured", "principled", "principledthin", "blendbsdf", "mask", "twosided",
    "bumpmap", "normalmap", "null", "hair", "polarizer", "retarder", "circular", "measured_polarized",
    "ward", "phong", "ashikhmin_shirley", "ashikhmin_shirley_plastic",  # the tool's own Python BSDFs
    "bitmap", "checkerboard", "mesh_attribute", "volume",  # textures
    "regular", "irregular", "uniform", "srgb", "d65", "blackbody", "rawconstant"})  # spectra
"""The plugin types a material element rendered as written may name: those Mitsuba ships for a BSDF, its
textures and spectra. Mitsuba loads a plugin by its type's file name, unchecked: a type such as
``../../evil`` would load (and run) a library of that name, so any other type is refused."""


def check_element(text: str, file: str) -> None:
    """A ConfigError naming the first plugin type of a material element that is not one of
    `MATERIAL_PLUGINS` (the Mitsuba adapter checks again before it loads one)."""
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise ConfigError(f"a material element rendered as written is not XML: {exc}", file=file) from None
    for e in root.iter():
        kind = e.get("type")
        if kind is not None and kind not in MATERIAL_PLUGINS:
            raise ConfigError(f"<{e.tag} type={kind!r}> is not a plugin Mitsuba ships for a material (known: "
                              f"{', '.join(sorted(MATERIAL_PLUGINS))}): not loaded", file=file)


def _resolved(doc: _Document, elem: ET.Element, depth: int) -> ET.Element:
    if depth > 16:
        raise ConfigError("<ref>s nest deeper than 16 (a loop?)", file=str(doc.path))
    target = doc.ref(elem) if elem.tag == "ref" else elem
    out = ET.Element(target.tag, dict(target.attrib))
    if elem.tag == "ref" and elem.get("name"):
        out.set("name", elem.get("name"))
    out.text = target.text
    for child in target:
        out.append(_resolved(doc, child, depth + 1))
    return out


def _unwrap(doc: _Document, elem: ET.Element, notes: Notes) -> ET.Element:
    for _ in range(8):
        if elem.tag == "ref":
            elem = doc.ref(elem)
        kind = elem.get("type", "")
        if kind not in WRAPPERS:
            return elem
        (notes.append if kind == "twosided" else notes.drop)(f"{kind}: {WRAPPERS[kind]}")
        inner = [c for c in elem if c.tag in ("bsdf", "ref")]
        if not inner:
            return elem
        elem = inner[0]
    return elem


def _params(doc: _Document, elem: ET.Element, model: str, notes: Notes,
            textures: dict | None = None) -> tuple[dict, list[str]]:
    """The model's parameters from the BSDF's properties (Mitsuba's defaults for the rest); a
    `bitmap` on an input the model takes as an image into ``textures`` (when given)."""
    spec = MODELS[model]
    params: dict = {}
    textured: list[str] = []
    aniso = {}
    for prop in elem:
        name = prop.get("name", "")
        if prop.tag in ("texture", "ref"):
            textured.append(_texture(doc, prop, name))
            if name in spec.names or name in ("alpha_u", "alpha_v"):
                constant, tex = _textured_input(doc, prop, name, ALPHAS if name not in spec.names else spec, notes,
                                                textures is not None)
                if constant is not None:
                    (aniso if name in ("alpha_u", "alpha_v") else params)[name] = constant
                if tex is not None:
                    textures[name] = tex  # type: ignore[index]
            continue
        value = _value(doc, prop, name, notes)
        if name in ("alpha_u", "alpha_v"):
            aniso[name] = value
        elif name in ("int_ior", "ext_ior") and isinstance(value, str):
            params[name] = _named_ior(value)
        elif name in spec.names or name in CONVERTED.get(model, ()):
            params[name] = value
        elif name not in IGNORED:
            notes.drop(f"{name} = {prop.get('value')} has no counterpart in the {model!r} model: ignored")
    if aniso and "anisotropy" in spec.names:
        params.update(anisotropy="anisotropic", alpha_u=float(aniso.get("alpha_u", 0.1)),
                      alpha_v=float(aniso.get("alpha_v", 0.1)))
    elif aniso:
        au, av = float(aniso.get("alpha_u", 0.1)), float(aniso.get("alpha_v", 0.1))
        params["alpha"] = math.sqrt(au * av)
        notes.drop(f"anisotropic (alpha_u {au:g}, alpha_v {av:g}): {model} is isotropic here, read as alpha "
                     f"{params['alpha']:.4g}")
    params = spec.from_file(params, notes)
    ext = params.pop("ext_ior", None)
    if ext is not None and abs(float(ext) - NAMED_IOR["air"]) > 1e-3:
        notes.append(f"ext_ior {float(ext):g} is read as air (the model's exterior)")
    notes += clip_into(spec, params)
    return params, textured


def _blend_params(doc: _Document, elem: ET.Element, notes: Notes) -> tuple[dict, list[str]]:
    """A blendbsdf's weight and its two BSDFs, each under its slot's name (`bsdf_1.alpha`)."""
    inner = [_unwrap(doc, c, notes) for c in elem if c.tag in ("bsdf", "ref") and c.get("name") != "weight"]
    if len(inner) != 2:
        raise ConfigError(f"a blendbsdf needs two BSDFs inside, this one has {len(inner)}")
    params: dict = {}
    textured: list[str] = []
    for slot, child in zip(SLOTS, inner):
        kind = child.get("type", "")
        if kind not in COMPONENTS:
            raise ConfigError(f"a blend of {kind!r} is not supported (a blend's BSDFs: {', '.join(COMPONENTS)})")
        sub, tex = _params(doc, child, kind, notes)
        params[slot] = kind
        params.update({f"{slot}.{k}": v for k, v in sub.items()})
        textured += [f"{slot}.{t}" for t in tex]
    for prop in elem:
        if prop.get("name") == "weight" and prop.tag in ("texture", "ref"):
            textured.append(_texture(doc, prop, "weight"))
        elif prop.get("name") == "weight":
            params["weight"] = _value(doc, prop, "weight", notes)
    notes += clip_into(MODELS["blendbsdf"], params)
    return params, textured


def _value(doc: _Document, prop: ET.Element, name: str, notes: Notes):
    v = prop.get("value", "")
    if prop.tag == "spectrum":
        got = read_spectrum(prop, name, doc.find)
        if got.note:
            notes.append(got.note)
        return got.rgb
    try:
        if prop.tag in ("float", "integer"):
            return float(v)
        if prop.tag in ("rgb", "color"):
            return _colour(v)
    except ValueError:
        raise ConfigError(f"{name}: <{prop.tag} value={v!r}> is not a number or three (Mitsuba would not load it)") \
            from None
    if prop.tag == "boolean":
        return "true" if v.strip().lower() in ("true", "1") else "false"
    return v


def _colour(text: str) -> tuple[float, float, float]:
    vals = [float(x) for x in re.split(r"[,\s]+", text.strip()) if x]
    if len(vals) not in (1, 3):
        raise ValueError(text)
    return (vals[0],) * 3 if len(vals) == 1 else tuple(vals)  # type: ignore[return-value]


def _texture(doc: _Document, prop: ET.Element, name: str) -> str:
    tex = doc.ref(prop) if prop.tag == "ref" else prop
    file = next((s.get("value") for s in tex.iter("string") if s.get("name") == "filename"), None)
    what = f"{tex.get('type', 'texture')} {file!r}" if file else tex.get("type", "texture")
    return f"{name} <- {what}"


LINEAR_FILES = (".exr", ".hdr", ".pfm")
"""Image files Mitsuba reads as linear values; it decodes the others (PNG, JPEG...) as sRGB unless `raw`."""


def _textured_input(doc: _Document, prop: ET.Element, name: str, spec, notes: Notes,
                    maps: bool) -> tuple[Value | None, Texture | None]:
    """A textured input's constant (a bitmap's mean, a checkerboard's; None: the model's default) and,
    when ``maps`` and the model takes it as an image laid as it is, its bitmap as a texture."""
    tex = doc.ref(prop) if prop.tag == "ref" else prop
    kind = spec.param(name).kind
    if tex.get("type") == "checkerboard":
        if any(c.tag in ("texture", "ref") for c in tex):
            notes.drop(f"{name}: a checkerboard of textures is read as the model's default")
            return None, None
        colours = {c.get("name"): _value(doc, c, f"{name}.{c.get('name')}", notes) for c in tex
                   if c.get("name") in ("color0", "color1")}
        c0, c1 = (_rgb(colours.get(k, d)) for k, d in (("color0", 0.4), ("color1", 0.2)))
        mean = tuple((a + b) / 2 for a, b in zip(c0, c1))
        notes.drop(f"{name}: a checkerboard texture is read as its mean, {_shown(mean)}")
        return (mean if kind == ParamKind.RGB else float(np.dot(mean, LUMA))), None
    image = _bitmap(doc, tex, name, notes)
    if image is None:
        return None, None
    try:
        values = read_values(image, kind, where=f"{name} of a BSDF in {doc.path}")
    except ConfigError as exc:
        notes.drop(f"{name}: its image cannot be read ({exc}): read as the model's default")
        return None, None
    mean = tuple(float(x) for x in values.reshape(-1, 3).mean(axis=0)) if kind == ParamKind.RGB else float(values.mean())
    plain = not any(t.get("name") == "to_uv" for t in tex if t.tag == "transform") and \
        {s.get("name"): s.get("value", "") for s in tex.iter("string")}.get("wrap_mode", "repeat") == "repeat"
    if maps and plain and name in spec.texturable:
        return mean, image
    why = "only an image laid as it is over the UV map is remapped texel by texel" if not plain else \
        f"the {spec.name} model does not take {name} as an image" if name not in spec.texturable else ""
    notes.drop(f"{name}: its image is read as its mean, {_shown(mean)}" + (f" ({why})" if why else ""))
    return mean, None


def _rgb(v) -> tuple[float, float, float]:
    if isinstance(v, tuple):
        return v  # type: ignore[return-value]
    try:
        return (float(v),) * 3
    except (TypeError, ValueError):
        raise ConfigError(f"{v!r} is not a colour (give a number, an <rgb> or a <spectrum>)") from None


def _shown(v) -> str:
    return "(" + ", ".join(f"{x:.4g}" for x in v) + ")" if isinstance(v, tuple) else f"{v:.4g}"


def _bitmap(doc: _Document, tex: ET.Element, name: str, notes: Notes) -> Texture | None:
    """A `bitmap` texture's file (found as Mitsuba finds it), how its values are read and filtered;
    None (and a note) for another texture or a file not found."""
    strings = {s.get("name"): s.get("value", "") for s in tex.iter("string")}
    if tex.get("type") != "bitmap" or not strings.get("filename"):
        notes.drop(f"{name}: a {tex.get('type', 'texture')} texture is read as the model's default (only a bitmap's "
                     "image or a checkerboard is read)")
        return None
    try:
        path = doc.find(strings["filename"])
    except ConfigError:
        notes.drop(f"{name}: its image {strings['filename']!r} is not found (beside the scene or in its <path>s): "
                     "read as the model's default")
        return None
    raw = any(b.get("name") == "raw" and b.get("value", "").strip().lower() in ("true", "1") for b in tex.iter("boolean"))
    space = "linear" if raw or path.suffix.lower() in LINEAR_FILES else "srgb"
    filt = "nearest" if strings.get("filter_type") == "nearest" else "linear"
    return texture(path, space, filt, where=f"{name} of a BSDF in {doc.path}")


def _named_ior(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        pass
    if text.lower() not in NAMED_IOR:
        raise ConfigError(f"unknown named IOR {text!r} (known: {', '.join(NAMED_IOR)})")
    return NAMED_IOR[text.lower()]

"""MaterialX documents as libraries, through the `materialx` package: documents of older
versions are upgraded on reading, each is validated against the standard libraries, and every
material's surface shader (standard_surface, open_pbr_surface, gltf_pbr, UsdPreviewSurface) is
read as the Cycles Principled BSDF by the correspondence in `correspondence.py`."""

from __future__ import annotations

import functools
import re
from pathlib import Path

from brdfremap.core.data.errors import ConfigError
from brdfremap.core.library.formats import Entry, clip_into
from brdfremap.core.data.schemas import Material
from brdfremap.core.data.textures import colour_to_linear

from .correspondence import HALF, SCALE, QUIET, TO_PRINCIPLED, TRANSMISSION_TINT
from .versions import upgrade_inputs

NOTE = ("read as Blender Cycles' Principled BSDF by the {shader} correspondence (Blender's Principled BSDF "
        "follows OpenPBR): MaterialX has no renderer of its own here")


def mx():
    try:
        import MaterialX
    except ImportError:
        raise ConfigError("reading MaterialX needs the materialx package: pip install 'materialx==1.39.*'") from None
    return MaterialX


@functools.cache
def standard_libraries():
    """MaterialX's standard libraries, loaded once (about 0.3 s): callers import them into their own
    documents and never change this one."""
    m = mx()
    lib = m.createDocument()
    m.loadLibraries(m.getDefaultDataLibraryFolders(), m.getDefaultDataSearchPath(), lib)
    return lib


class MaterialXReader:
    name = "MaterialX (.mtlx)"
    suffixes = (".mtlx",)

    def accepts(self, path: Path) -> bool:
        return True

    def read(self, path: Path) -> list[Entry]:
        m = mx()
        doc = m.createDocument()
        try:
            m.readFromXmlFile(doc, str(path))  # upgrades an older document's structure to this version
        except Exception as exc:  # the library's parse and file errors share no base class
            raise ConfigError(f"cannot read it as MaterialX: {str(exc).splitlines()[0]}", file=str(path)) from None
        upgraded = {n.getName(): upgrade_inputs(n) for n in doc.getNodes() if n.getType() == "surfaceshader"}
        doc.importLibrary(standard_libraries())
        valid, why = doc.validate()
        if not valid:
            first = why.strip().splitlines()[0]
            raise ConfigError(f"is not valid MaterialX: {first}", file=str(path), field=_line_of(path, first))
        return [material_entry(m, mat, str(path), upgraded) for mat in doc.getMaterialNodes()]


def material_entry(m, mat, file: str, upgraded: dict[str, list[str]] | None = None, name: str = "") -> Entry:
    """One material node of a document (its surface shader by the correspondence), as an entry;
    ``upgraded``: notes on a shader's inputs an upgrade renamed. Also how a MaterialX shader written
    directly in USD is read (`adapters/usd`)."""
    upgraded = upgraded or {}
    name = name or mat.getName()
    shaders = [s for s in m.getShaderNodes(mat) if s.getType() == "surfaceshader"]
    if not shaders:
        return Entry(name=name, file=file, problem="no surface shader")
    shader = shaders[0]
    category = shader.getCategory()
    if category not in TO_PRINCIPLED:
        return Entry(name=name, file=file, problem=f"shader {category!r} has no correspondence here (known: "
                                                    f"{', '.join(TO_PRINCIPLED)})")
    try:
        params, textured, notes = _principled(shader, category)
    except ConfigError as exc:  # one material's value (an unknown colour space): that material, not the file
        return Entry(name=name, file=file, problem=str(exc))
    notes[:0] = [NOTE.format(shader=category), *upgraded.get(shader.getName(), [])]
    textures = _textures(shader, category, name, notes)
    params.update(_means(textures, name, notes))
    return Entry(name=name, file=file, notes=notes, textured=textured,
                 material=Material(adapter="cycles", model="principled", params=params, name=name,
                                   textures=textures))


def _principled(shader, category: str) -> tuple[dict, list[str], list[str]]:
    """The Principled values of a shader node, the inputs driven by a graph, and the notes."""
    from brdfremap.adapters.cycles.models import PRINCIPLED

    nodedef = shader.getNodeDef()
    used, textured = set(), []

    def value(name: str):
        used.add(name)
        inp = shader.getInput(name)
        if inp is not None and (inp.getConnectedNode() is not None or inp.hasNodeGraphString()
                                or inp.hasOutputString() or inp.hasInterfaceName()):
            textured.append(f"{name} <- {_source(inp)}")
            inp = None
        given = inp is not None and inp.hasValueString()
        got = inp.getValue() if given else nodedef.getActiveInput(name).getValue()
        if not hasattr(got, "asTuple"):
            return _r(got)
        # MaterialX keeps 32-bit floats: 0.944 comes back as 0.94400000572; 7 digits are what was written.
        rgb = tuple(_r(x) for x in got.asTuple())
        space = inp.getActiveColorSpace() if given else ""
        if given and inp.getType() in ("color3", "color4") and space not in ("", *WORKING):
            linear = tuple(_r(x) for x in colour_to_linear(rgb, space, where=f"{shader.getName()}: {name}"))
            notes.append(f"{name} ({', '.join(f'{x:.4g}' for x in rgb)}) is in {space}: read as "
                         f"({', '.join(f'{x:.4g}' for x in linear)}) in linear Rec.709, the renderers' working space")
            return linear
        return rgb

    notes: list[str] = []

    params: dict = {}
    for pname, names in TO_PRINCIPLED[category].items():
        vals = [value(n) for n in names]
        v = vals[0]
        if len(vals) == 2:  # a colour times its weight
            v = tuple(c * float(vals[1]) for c in v)
        params[pname] = v / 2.0 if pname in HALF else v * SCALE[pname] if pname in SCALE else v
    tint = TRANSMISSION_TINT.get(category)
    weight = float(params.get("transmission_weight", 0.0))
    if tint is not None and weight > 0.0:
        # Blender's Principled BSDF tints its transmission by Base Color; these shaders by a colour of its own.
        colour = value(tint)
        params["base_color"] = tuple((1 - weight) * b + weight * t for b, t in zip(params["base_color"], colour))
        notes.append(f"transmission_weight {weight:g}: Base Color takes {tint} ({', '.join(f'{x:.4g}' for x in colour)})"
                     " in that proportion, as Blender's Principled BSDF tints what it transmits by Base Color")
    notes += clip_into(PRINCIPLED, params) + _unused(shader, nodedef, used)
    return params, textured, notes


SRGB_SPACES = {"srgb_texture", "srgb_tx", "sRGB"}
LINEAR_SPACES = {"", "lin_rec709", "raw", "Raw", "linear", "lin_srgb", "scene-linear Rec.709-sRGB"}


IMAGES = {"image", "tiledimage", "gltf_image", "gltf_colorimage"}
CHANNELS = {"outx": 0, "outy": 1, "outz": 2}
"""A `separate3` of an image: which of its channels each output is (a glTF occlusion-roughness-metallic
image's roughness is its `outy`, its metallic its `outz`)."""


def _image_node(inp) -> tuple[object | None, int | None, str]:
    """The image node an input reads (directly, or one channel of it through a `separate3`), the
    channel it reads (None: its colour), and why it cannot be read as it is ('' if it can)."""
    node = inp.getConnectedNode() if inp is not None else None
    channel = None
    if node is not None and node.getCategory() == "separate3":
        channel = CHANNELS.get(inp.getOutputString())
        up = node.getInput("in")
        node = up.getConnectedNode() if up is not None else None
    if node is None or node.getCategory() not in IMAGES:
        return None, None, ""
    if node.getCategory() == "gltf_colorimage" and inp.getOutputString() not in ("", "outcolor"):
        return node, None, "it reads the image's alpha"
    if channel is None and node.getType() == "float":
        channel = 0  # MaterialX reads a float image's first channel
    return node, channel, ""


def _textures(shader, category: str, name: str, notes: list[str]) -> dict:
    """The inputs an image node drives directly (`image`, `tiledimage`, glTF's `gltf_image` and
    `gltf_colorimage`, or one channel of one through a `separate3`; default texture coordinates, no
    tiling, transform or factor), each of a Principled parameter that is that one input as it is, as
    textures."""
    from brdfremap.core.data.textures import texture

    out = {}
    for pname, inputs in TO_PRINCIPLED[category].items():
        node, channel, why = _image_node(shader.getInput(inputs[0]))
        if node is None:
            continue
        why = why or _unusable(shader, node, pname, inputs)
        f = node.getInput("file")
        path = Path(f.getResolvedValueString()) if f is not None and not why else None
        if path is not None and not path.is_absolute():
            path = Path(shader.getDocument().getSourceUri()).parent / path
        if path is not None and not path.is_file():
            why = f"its image {f.getValueString()!r} is not found"
        space = f.getActiveColorSpace() if f is not None else ""
        if not why and space not in SRGB_SPACES | LINEAR_SPACES:
            why = f"its image is in colour space {space!r} (srgb_texture or lin_rec709 are read)"
        if why:
            notes.append(f"{pname}: {why}: read as its constant")
            continue
        filt = node.getInput("filtertype")
        out[pname] = texture(path, "srgb" if space in SRGB_SPACES else "linear",
                             "nearest" if filt is not None and filt.getValueString() == "closest" else "linear",
                             channel=channel, where=f"{name}: {pname}")
    return out


def _means(textures: dict, name: str, notes: list[str]) -> dict:
    """Each texture's mean, the constant its input converts with where no table maps it (as a Mitsuba
    bitmap's is); one that cannot be read is dropped from ``textures``, and said."""
    from brdfremap.adapters.cycles.models import PRINCIPLED
    from brdfremap.core.data.textures import mean_value, read_values

    out = {}
    for pname, tex in list(textures.items()):
        try:
            values = read_values(tex, PRINCIPLED.param(pname).kind, where=f"{name}: {pname}")
        except ConfigError as exc:
            notes.append(f"{pname}: {exc}: read as its constant")
            del textures[pname]
            continue
        out[pname] = PRINCIPLED.param(pname).clip(mean_value(values))
    return out


def _unusable(shader, node, pname: str, inputs: tuple[str, ...]) -> str:
    if len(inputs) > 1:
        weight = shader.getInput(inputs[1])
        if weight is not None and (weight.getConnectedNode() is not None or
                                   (weight.hasValueString() and abs(float(weight.getValue()) - 1.0) > 1e-6)):
            return f"its image is scaled by {inputs[1]} (only an image read as it is is remapped texel by texel)"
    if pname in HALF or pname in SCALE:
        return "its image is scaled into the Principled value (only an image read as it is is remapped)"
    tc = node.getInput("texcoord")
    if tc is not None and (tc.getConnectedNode() is not None or tc.hasNodeGraphString()):
        return "its image is read through other texture coordinates"
    if node.getCategory() == "tiledimage":
        tiles = node.getInput("uvtiling")
        if tiles is not None and tiles.hasValueString() and tiles.getValueString().replace(" ", "") not in ("1,1",):
            return "its image is tiled"
    return _gltf_unusable(node)


def _gltf_unusable(node) -> str:
    """A glTF image node read as it is: its factor 1, its texture transform the identity (glTF's
    KHR_texture_transform as MaterialX writes it)."""
    nodedef = node.getNodeDef()
    for name in ("factor", "color", "scale", "rotate", "offset", "pivot"):
        inp = node.getInput(name)
        default = nodedef.getActiveInput(name) if nodedef is not None else None
        if inp is None or default is None:
            continue
        if inp.getConnectedNode() is not None or (inp.hasValueString() and inp.getValue() != default.getValue()):
            return f"its image's {name} is not the identity (only an image read as it is is remapped texel by texel)"
    return ""


WORKING = ("lin_rec709", "lin_srgb")
"""MaterialX's names for linear Rec.709, the space both renderers' RGB values are in."""


def _line_of(path: Path, message: str) -> str | None:
    """'line N' of what a MaterialX message names: the element (`name="..."`), and within it the
    input it quotes ('specular_anisotropy'), where the file shows them; else None."""
    element = re.search(r'name="([^"]+)"', message)
    if not element:
        return None
    try:
        lines = path.read_text(errors="replace").splitlines()
    except OSError:
        return None
    at = next((i for i, line in enumerate(lines) if f'name="{element.group(1)}"' in line), None)
    if at is None:
        return None
    quoted = re.search(r"Input '([^']+)'", message)
    if quoted:
        at = next((i for i in range(at, len(lines)) if f'name="{quoted.group(1)}"' in lines[i]), at)
    return f"line {at + 1}"


def _r(x) -> float:
    return float(f"{float(x):.7g}")


def _source(inp) -> str:
    node = inp.getConnectedNode()
    if node is None:
        return f"node graph {inp.getNodeGraphString() or inp.getInterfaceName()!r}"
    if node.getCategory() in ("image", "tiledimage"):
        f = node.getInput("file")
        return f"{node.getCategory()} {f.getValueString() if f is not None else ''!r}"
    return f"{node.getCategory()} node {node.getName()!r}"


def _unused(shader, nodedef, used: set[str]) -> list[str]:
    """Inputs given away from their default that the Principled model has no counterpart for."""
    out = []
    for inp in shader.getInputs():
        name = inp.getName()
        if name in used or name in QUIET:
            continue
        default = nodedef.getActiveInput(name)
        shown = inp.getValueString() if inp.hasValueString() else "a node graph"
        if default is None or not inp.hasValueString() or inp.getValueString() != default.getValueString():
            out.append(f"{name} = {shown} has no counterpart in the Principled model here: ignored")
    return out

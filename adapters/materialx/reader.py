"""MaterialX documents as libraries, through the `materialx` package: documents of older versions are
upgraded on reading, each is validated against the standard libraries, and every material's surface
shader is a material of the `materialx` adapter's model of that shader (open_pbr_surface,
standard_surface, gltf_pbr, UsdPreviewSurface, disney_principled): its inputs as the document gives
them (colours in another colour space made linear), rendered by MaterialX's own GLSL. An input an
image drives directly is a texture (its mean the value where no table maps it); one another graph
drives is read at its default, and said."""

from __future__ import annotations

import hashlib
import re
from pathlib import Path

from brdfremap.core.data.errors import ConfigError
from brdfremap.core.data.schemas import Material, Native
from brdfremap.core.data.textures import colour_to_linear
from brdfremap.core.library.formats import Entry, clip_into

from .mxlib import mx, standard_libraries
from .versions import upgrade_inputs

WORKING = ("lin_rec709", "lin_srgb")
"""MaterialX's names for linear Rec.709, the space the renderers' RGB values are in."""
SRGB_SPACES = {"srgb_texture", "srgb_tx", "sRGB"}
LINEAR_SPACES = {"", "lin_rec709", "raw", "Raw", "linear", "lin_srgb", "scene-linear Rec.709-sRGB"}
IMAGES = {"image", "tiledimage", "gltf_image", "gltf_colorimage"}
CHANNELS = {"outx": 0, "outy": 1, "outz": 2}
"""A `separate3` of an image: which of its channels each output is (a glTF occlusion-roughness-metallic
image's roughness is its `outy`, its metallic its `outz`)."""


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
        return [needs_document(_as_written(m, path, material_entry(m, mat, str(path), upgraded), _partly_read(m, mat)))
                for mat in doc.getMaterialNodes()]


def needs_document(entry: Entry) -> Entry:
    """A material with no reading that is not rendered as written either (its images missing, or a MaterialX shader
    in USD, which is not a document to render): refused, saying why."""
    if entry.material is None or entry.material.model or entry.material.native is not None:
        return entry
    why = entry.notes[-1] if entry.notes else "no model reads it"
    return Entry(name=entry.name, file=entry.file, problem=f"{why}; it is rendered only as written, from its .mtlx "
                                                           "document with every image it names")


def _partly_read(m, mat) -> bool:
    """Whether the material's reading leaves part of its shader out: a nodedef of the document's own whose
    graph is more than one shader of a model (a mix of shaders, a shader a node feeds)."""
    from .models import MODELS

    shaders = [s for s in m.getShaderNodes(mat) if s.getType() == "surfaceshader"]
    if not shaders or MODELS.get(shaders[0].getCategory()) is not None:
        return False
    nodedef = shaders[0].getNodeDef()
    graph = nodedef.getImplementation() if nodedef is not None else None
    if graph is None or not graph.isA(m.NodeGraph):
        return False
    inner = {n.getName() for n in graph.getNodes() if n.getType() == "surfaceshader"}
    return len(inner) != 1 or any(o.getNodeName() not in inner for o in graph.getOutputs())


TRANSMITTING = {"dielectric_bsdf", "generalized_schlick_bsdf", "translucent_bsdf", "subsurface_bsdf"}
"""pbrlib's BSDFs that may let light through a surface (the first two unless their scatter_mode is R)."""


def _transmits(doc, name: str) -> bool:
    """Whether material ``name``'s own node graphs hold a BSDF that lets light through (its renders then take the
    paths through the sphere, its held-out lights a backdrop seen through it)."""
    doc.setDataLibrary(standard_libraries())  # the standard nodedefs, for their defaults (a BSDF's scatter_mode)
    mat = doc.getNode(name)
    graphs = [nd.getImplementation() for s in mx().getShaderNodes(mat) for nd in [s.getNodeDef()] if nd is not None]
    nodes = [n for g in graphs if g is not None and g.isA(mx().NodeGraph) for n in g.getNodes()]
    return any(n.getCategory() in TRANSMITTING and _scatter_mode(n) != "R" for n in nodes)


def _scatter_mode(node) -> str:
    """A BSDF node's scatter_mode as set, else its nodedef's default ('' where it has none)."""
    inp = node.getInput("scatter_mode")
    if inp is None and node.getNodeDef() is not None:
        inp = node.getNodeDef().getActiveInput("scatter_mode")
    return inp.getValueString() if inp is not None else ""


def _as_written(m, path: Path, entry: Entry, partly: bool = False) -> Entry:
    """A material an image or a node graph drives, or whose reading leaves part of it out (``partly``), rendered
    by MaterialX from the document as written (`Material.native`: the document with this material alone, its
    file names made absolute), where every file it names is there; else as read, and said."""
    if entry.material is None or (not entry.textured and entry.material.model and not partly):
        return entry
    path = path.resolve()
    raw = m.createDocument()
    m.readFromXmlFile(raw, str(path))
    m.flattenFilenames(raw, m.FileSearchPath(str(path.parent)))
    for other in raw.getMaterialNodes():
        if other.getName() != entry.name:
            raw.removeNode(other.getName())
    files = [Path(i.getValueString()) for e in raw.traverseTree() if e.isA(m.Input) and e.getType() == "filename"
             for i in [e] if i.getValueString()]
    missing = [str(f) for f in files if not f.is_file()]
    if missing:
        return entry.model_copy(update={"notes": [*entry.notes, f"not rendered as written: its images "
                                                  f"{', '.join(missing)} are not found"]})
    text = m.writeToXmlString(raw)
    digest = hashlib.sha256(text.encode())
    for f in files:
        digest.update(f.read_bytes())
    native = Native(file=str(path.resolve()), name=entry.name, sha256=digest.hexdigest(), element=text,
                    driven=tuple(entry.textured), transmits=_transmits(raw, entry.name))
    return entry.model_copy(update={"material": entry.material.model_copy(update={"native": native})})


def material_entry(m, mat, file: str, upgraded: dict[str, list[str]] | None = None, name: str = "") -> Entry:
    """One material node of a document (its surface shader as the materialx adapter's model of it), as
    an entry; ``upgraded``: notes on a shader's inputs an upgrade renamed. Also how a MaterialX shader
    written directly in USD is read (`adapters/usd`)."""
    from .models import MODELS

    upgraded = upgraded or {}
    name = name or mat.getName()
    shaders = [s for s in m.getShaderNodes(mat) if s.getType() == "surfaceshader"]
    if not shaders:
        return Entry(name=name, file=file, problem="no surface shader")
    shader = shaders[0]
    model = MODELS.get(shader.getCategory())
    if model is None:
        return _unread(shader, name, file)
    notes = list(upgraded.get(shader.getName(), []))
    try:
        params, textured = _inputs(shader, model, notes)
    except ConfigError as exc:  # one material's value (an unknown colour space): that material, not the file
        return Entry(name=name, file=file, problem=str(exc))
    textures, laid = _textures(shader, model, name, notes)
    params.update(_means(textures, model, name, notes))
    params.update(_means(laid, model, name, notes))
    notes += clip_into(model, params)
    return Entry(name=name, file=file, notes=notes, textured=textured,
                 material=Material(adapter="materialx", model=model.name, params=params, name=name, textures=textures))


HAIR_BSDFS = {"chiang_hair_bsdf"}
"""MaterialX's hair BSDFs (1.39): lit along a fibre."""
HAIR = "hair is drawn along fibres (a curve's tangent), and the probe is a sphere: no renderer here draws it as its " \
       "author's scene does"


def _unread(shader, name: str, file: str) -> Entry:
    """A shader no model reads, implemented by a node graph: read as the one shader of a model in it where there is
    one, else a material with no reading, rendered as written by MaterialX (`_as_written`); hair, or a shader with
    no graph, is refused, one line."""
    from .models import MODELS

    category = shader.getCategory()
    nodedef = shader.getNodeDef()
    graph = nodedef.getImplementation() if nodedef is not None else None
    if graph is None or not graph.isA(mx().NodeGraph):
        return Entry(name=name, file=file, problem=f"shader {category!r} is not a surface this tool renders (known: "
                                                   f"{', '.join(sorted(MODELS))}), and no node graph implements it")
    hair = sorted({n.getCategory() for n in graph.getNodes()} & HAIR_BSDFS)
    if hair:
        return Entry(name=name, file=file, problem=f"shader {category!r} is {', '.join(hair)}: {HAIR}")
    said = f"shader {category!r} is implemented by a node graph"
    inner = [n for n in graph.getNodes() if n.getType() == "surfaceshader" and MODELS.get(n.getCategory()) is not None]
    if len(inner) != 1:
        return Entry(name=name, file=file, notes=[f"{said}: rendered as written, and fitted without a reading (no one "
                                                  "shader of a model in it)"],
                     material=Material(adapter="materialx", model="", name=name))
    model = MODELS.get(inner[0].getCategory())
    whole = all(o.getNodeName() == inner[0].getName() for o in graph.getOutputs())
    how = "the whole of it: read as it" if whole else \
        "not all of it: rendered as written, and read as it for the target model and the fit's start"
    notes = [f"{said}; its {inner[0].getCategory()} {inner[0].getName()!r} is {how} (its inputs the node's values)"]
    try:
        params, driven = _inputs(inner[0], model, notes, outer=shader)
    except ConfigError as exc:  # one material's value (an unknown colour space): that material, not the file
        return Entry(name=name, file=file, problem=str(exc))
    notes += clip_into(model, params)
    return Entry(name=name, file=file, notes=notes, textured=driven,
                 material=Material(adapter="materialx", model=model.name, params=params, name=name))


def _inputs(shader, model, notes: list[str], outer=None) -> tuple[dict, list[str]]:
    """The values the shader node gives its inputs that are the model's parameters (linear colours),
    and the inputs a graph drives (read at their defaults, unless an image: `_textures`). ``outer``: the
    node of a nodedef whose graph holds ``shader``: an input bound to its interface reads the node's value
    (or the nodedef's default)."""
    params, textured = {}, []
    for inp in shader.getInputs():
        pname = inp.getName()
        if pname not in model.names:
            continue
        if outer is not None and inp.hasInterfaceName():
            nodedef = outer.getNodeDef()
            bound = outer.getActiveInput(inp.getInterfaceName()) or \
                (nodedef.getActiveInput(inp.getInterfaceName()) if nodedef is not None else None)
            if bound is not None and bound.hasValueString() and bound.getConnectedNode() is None:
                params[pname] = _value(outer, bound, notes)
            else:
                textured.append(f"{pname} <- {inp.getInterfaceName()} of {outer.getName()!r}")
            continue
        if inp.getConnectedNode() is not None or inp.hasNodeGraphString() or inp.hasOutputString() \
                or inp.hasInterfaceName():
            textured.append(f"{pname} <- {_source(inp)}")
            continue
        if inp.hasValueString():
            params[pname] = _value(shader, inp, notes)
    return params, textured


def _value(shader, inp, notes: list[str]):
    got = inp.getValue()
    if isinstance(got, bool):
        return "true" if got else "false"
    if isinstance(got, int):
        return str(got)
    if not hasattr(got, "asTuple"):
        return _r(got)
    # MaterialX keeps 32-bit floats: 0.944 comes back as 0.94400000572; 7 digits are what was written.
    rgb = tuple(_r(x) for x in got.asTuple())
    space = inp.getActiveColorSpace()
    if inp.getType() in ("color3", "color4") and space not in ("", *WORKING):
        linear = tuple(_r(x) for x in colour_to_linear(rgb, space, where=f"{shader.getName()}: {inp.getName()}"))
        notes.append(f"{inp.getName()} ({', '.join(f'{x:.4g}' for x in rgb)}) is in {space}: read as "
                     f"({', '.join(f'{x:.4g}' for x in linear)}) in linear Rec.709, the renderers' working space")
        return linear
    return rgb


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


def _textures(shader, model, name: str, notes: list[str]) -> tuple[dict, dict]:
    """The inputs an image node drives directly (`image`, `tiledimage`, glTF's `gltf_image` and
    `gltf_colorimage`, or one channel of one through a `separate3`; default texture coordinates, no
    tiling, transform or factor), as textures of the parameter of that name; and those whose image is
    laid otherwise (tiled, transformed), whose mean is their reading all the same."""
    from brdfremap.core.data.textures import texture

    from .correspondence import QUIET

    out, laid = {}, {}
    for inp in shader.getInputs():
        if inp.getName() not in model.names or inp.getName() in QUIET:  # an occlusion map: not reflectance
            continue
        node, channel, why = _image_node(inp)
        if node is None:
            continue
        laid_out = "" if why else _unusable(node)
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
            notes.append(f"{inp.getName()}: {why}: read at its default")
            continue
        if laid_out:
            notes.append(f"{inp.getName()}: {laid_out}: read as its image's mean")
        filt = node.getInput("filtertype")
        (laid if laid_out else out)[inp.getName()] = texture(path, "srgb" if space in SRGB_SPACES else "linear",
                                     "nearest" if filt is not None and filt.getValueString() == "closest" else "linear",
                                     channel=channel, where=f"{name}: {inp.getName()}")
    return out, laid


def _means(textures: dict, model, name: str, notes: list[str]) -> dict:
    """Each texture's mean, the constant its input converts with where no table maps it (as a Mitsuba
    bitmap's is); one that cannot be read is dropped from ``textures``, and said."""
    from brdfremap.core.data.textures import mean_value, read_values

    out = {}
    for pname, tex in list(textures.items()):
        try:
            values = read_values(tex, model.param(pname).kind, where=f"{name}: {pname}")
        except ConfigError as exc:
            notes.append(f"{pname}: {exc}: read at its default")
            del textures[pname]
            continue
        out[pname] = model.param(pname).clip(mean_value(values))
    return out


def _unusable(node) -> str:
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
    if node.getCategory() in IMAGES:
        f = node.getInput("file")
        return f"{node.getCategory()} {f.getValueString() if f is not None else ''!r}"
    return f"{node.getCategory()} node {node.getName()!r}"

"""Materials authored in USD through usd-core: a UsdPreviewSurface (every input its parameters give,
textures as UsdUVTexture), a MaterialX shader written directly in USD (an OpenPBR prim), and the
one-triangle layer a renderer's USD loader reads a material from."""

from __future__ import annotations

from typing import Any

from brdfremap.core.data.errors import ConfigError
from brdfremap.core.data.schemas import Value

from .preview import INPUTS, WORKFLOWS

PREVIEW_TYPES = {"diffuseColor": "Color3f", "specularColor": "Color3f", "useSpecularWorkflow": "Int"}
MTLX_TYPES = {"color3": "Color3f", "float": "Float", "integer": "Int", "boolean": "Bool"}
"""A MaterialX shader input's type as the value type it is written with in USD."""
"""UsdPreviewSurface inputs that are not floats (Sdf value type names)."""
PREVIEW_TEXTURED = {"diffuse_color": ("diffuseColor", "rgb"), "metallic": ("metallic", "r"),
                    "roughness": ("roughness", "r")}
"""Parameters a UsdUVTexture drives as they are: the input and the texture's output."""


def pxr():
    """usd-core's modules, or a ConfigError saying how to install it."""
    try:
        from pxr import Gf, Sdf, Usd, UsdGeom, UsdShade
    except ImportError:
        raise ConfigError("reading and writing USD needs usd-core: pip install 'usd-core==25.11'") from None
    return Gf, Sdf, Usd, UsdGeom, UsdShade


def _value(Gf, Sdf, kind: str, v: Value):
    if kind == "Color3f":
        return Sdf.ValueTypeNames.Color3f, Gf.Vec3f(*[float(x) for x in v])  # type: ignore[union-attr]
    if kind == "Int":
        return Sdf.ValueTypeNames.Int, int(v)  # type: ignore[arg-type]
    return Sdf.ValueTypeNames.Float, float(v)  # type: ignore[arg-type]


def preview_surface(stage, path: str, params: dict[str, Value], textures: dict[str, Any] | None = None,
                    doc: str = ""):
    """A Material at ``path`` whose universal surface is a UsdPreviewSurface of these (complete)
    parameters: every input authored (a renderer's defaults may not be the specification's: three.js
    takes an unauthored roughness as 1), but specularColor only in the specular workflow, where the
    specification reads it. ``textures``: {parameter: texture file relative to the layer, colour space}."""
    Gf, Sdf, Usd, UsdGeom, UsdShade = pxr()
    material = UsdShade.Material.Define(stage, path)
    shader = UsdShade.Shader.Define(stage, f"{path}/PreviewSurface")
    shader.CreateIdAttr("UsdPreviewSurface")
    for pname, name in INPUTS.items():
        v = params[pname]
        if pname == "use_specular_workflow":
            v = WORKFLOWS.index(v)  # type: ignore[arg-type]
        elif pname == "specular_color" and params["use_specular_workflow"] == "metallic":
            continue
        typ, val = _value(Gf, Sdf, PREVIEW_TYPES.get(name, "Float"), v)
        shader.CreateInput(name, typ).Set(val)
    for pname, tex in sorted((textures or {}).items()):
        if pname in PREVIEW_TEXTURED:
            _uv_texture(stage, path, shader, pname, tex, *PREVIEW_TEXTURED[pname])
    material.CreateSurfaceOutput().ConnectToSource(shader.ConnectableAPI(), "surface")
    if doc:
        material.GetPrim().SetDocumentation(doc)
    return material


def _uv_texture(stage, path: str, shader, pname: str, tex, input_name: str, output: str) -> None:
    """A UsdUVTexture of ``tex`` (its file, relative to the layer, and colour space) reading the
    primvar ``st``, into ``input_name``."""
    Gf, Sdf, Usd, UsdGeom, UsdShade = pxr()
    reader_path = f"{path}/st"
    if not stage.GetPrimAtPath(reader_path):
        st = UsdShade.Shader.Define(stage, reader_path)
        st.CreateIdAttr("UsdPrimvarReader_float2")
        st.CreateInput("varname", Sdf.ValueTypeNames.String).Set("st")
        st.CreateOutput("result", Sdf.ValueTypeNames.Float2)
    node = UsdShade.Shader.Define(stage, f"{path}/{pname}_texture")
    node.CreateIdAttr("UsdUVTexture")
    node.CreateInput("file", Sdf.ValueTypeNames.Asset).Set(tex.file)
    node.CreateInput("sourceColorSpace", Sdf.ValueTypeNames.Token).Set("sRGB" if tex.colorspace == "srgb" else "raw")
    node.CreateInput("st", Sdf.ValueTypeNames.Float2).ConnectToSource(
        UsdShade.Shader(stage.GetPrimAtPath(reader_path)).ConnectableAPI(), "result")
    kind = Sdf.ValueTypeNames.Float3 if output == "rgb" else Sdf.ValueTypeNames.Float
    out = node.CreateOutput(output, kind)
    shader.GetInput(input_name).ConnectToSource(out)


def mtlx_surface(stage, material, node_id: str, inputs: dict[str, Value], types: dict[str, str]):
    """A MaterialX shader written directly in USD (``node_id``: ND_open_pbr_surface_surfaceshader),
    the material's `mtlx` surface; ``types`` each input's MaterialX type (a choice's value its text:
    "true", "1")."""
    Gf, Sdf, Usd, UsdGeom, UsdShade = pxr()
    shader = UsdShade.Shader.Define(stage, material.GetPath().AppendChild("MaterialXSurface"))
    shader.CreateIdAttr(node_id)
    for name, v in inputs.items():
        kind = MTLX_TYPES.get(types.get(name, "float"), "Float")
        if kind == "Bool":
            shader.CreateInput(name, Sdf.ValueTypeNames.Bool).Set(v == "true")
            continue
        typ, val = _value(Gf, Sdf, kind, v)
        shader.CreateInput(name, typ).Set(val)
    material.CreateSurfaceOutput("mtlx").ConnectToSource(shader.ConnectableAPI(), "surface")
    return shader


def probe_layer(params: dict[str, Value]) -> str:
    """A USD layer (text) of one triangle bound to a UsdPreviewSurface of these parameters: what a
    renderer's USD loader reads the material from."""
    Gf, Sdf, Usd, UsdGeom, UsdShade = pxr()
    stage = Usd.Stage.CreateInMemory()
    mesh = UsdGeom.Mesh.Define(stage, "/Probe/Triangle")
    mesh.CreatePointsAttr([Gf.Vec3f(0, 0, 0), Gf.Vec3f(1, 0, 0), Gf.Vec3f(0, 1, 0)])
    mesh.CreateFaceVertexCountsAttr([3])
    mesh.CreateFaceVertexIndicesAttr([0, 1, 2])
    material = preview_surface(stage, "/Probe/Looks/Material", params)
    UsdShade.MaterialBindingAPI.Apply(mesh.GetPrim()).Bind(material)
    stage.SetDefaultPrim(stage.GetPrimAtPath("/Probe"))
    return stage.GetRootLayer().ExportToString()


def sphere_layer(params: dict[str, Value], textures: dict[str, Any] | None = None) -> str:
    """A USD layer (text) of a unit sphere bound to a UsdPreviewSurface of these parameters (a
    converted material's native file)."""
    Gf, Sdf, Usd, UsdGeom, UsdShade = pxr()
    stage = Usd.Stage.CreateInMemory()
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    material = preview_surface(stage, "/Material/Looks/Material", params, textures)
    sphere_mesh(stage, "/Material/Sphere", material)
    stage.SetDefaultPrim(stage.GetPrimAtPath("/Material"))
    return stage.GetRootLayer().ExportToString()


def mtlx_image(stage, path: str, shader, input_name: str, tex, kind: str) -> None:
    """A MaterialX image node written in USD (ND_image_color3 / ND_image_float) reading ``tex`` (its
    file relative to the layer, its colour space) into a MaterialX shader's input."""
    Gf, Sdf, Usd, UsdGeom, UsdShade = pxr()
    node = UsdShade.Shader.Define(stage, f"{path}/{input_name}_image")
    node.CreateIdAttr(f"ND_image_{kind}")
    f = node.CreateInput("file", Sdf.ValueTypeNames.Asset)
    f.Set(tex.file)
    f.GetAttr().SetColorSpace("srgb_texture" if tex.colorspace == "srgb" else "lin_rec709")
    out = node.CreateOutput("out", Sdf.ValueTypeNames.Color3f if kind == "color3" else Sdf.ValueTypeNames.Float)
    shader.GetInput(input_name).ConnectToSource(out)


SPHERE_CLASS = "/_brdf_remap_sphere"
"""The one sphere mesh a layer holds, as a class every sphere inherits."""


def sphere_mesh(stage, path: str, material, x: float = 0.0):
    """A UV sphere of radius 1 at (x, 0, 0) as a Mesh (Blender's USD importer binds no material to a
    UsdGeom.Sphere), with the probe's texture coordinates as primvar `st` (t up, as USD reads
    images), bound to ``material``; its points are the layer's one sphere class's."""
    Gf, Sdf, Usd, UsdGeom, UsdShade = pxr()
    if not stage.GetPrimAtPath(SPHERE_CLASS):
        _sphere_class(stage)
    mesh = UsdGeom.Mesh.Define(stage, path)
    mesh.GetPrim().GetInherits().AddInherit(SPHERE_CLASS)
    if x:
        mesh.AddTranslateOp().Set(Gf.Vec3d(x, 0.0, 0.0))
    UsdShade.MaterialBindingAPI.Apply(mesh.GetPrim()).Bind(material)
    return mesh


def _sphere_class(stage) -> None:
    from brdfremap.core.data.sphere import sphere_mesh as uv_sphere

    Gf, Sdf, Usd, UsdGeom, UsdShade = pxr()
    prim = stage.CreateClassPrim(SPHERE_CLASS)
    prim.SetTypeName("Mesh")
    mesh = UsdGeom.Mesh(prim)
    m = uv_sphere(32, 64)
    tris = m["indices"].reshape(-1, 3)
    mesh.CreatePointsAttr([Gf.Vec3f(*map(float, p)) for p in m["POSITION"]])
    mesh.CreateNormalsAttr([Gf.Vec3f(*map(float, n)) for n in m["NORMAL"]])
    mesh.SetNormalsInterpolation(UsdGeom.Tokens.vertex)
    mesh.CreateFaceVertexCountsAttr([3] * len(tris))
    mesh.CreateFaceVertexIndicesAttr([int(i) for i in tris.reshape(-1)])
    mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
    st = UsdGeom.PrimvarsAPI(mesh).CreatePrimvar("st", Sdf.ValueTypeNames.TexCoord2fArray, UsdGeom.Tokens.vertex)
    st.Set([Gf.Vec2f(float(u), 1.0 - float(v)) for u, v in m["TEXCOORD_0"]])

"""USD through usd-core, without rendering: a stage's materials read (UsdPreviewSurface as the
specification means it, MaterialX shaders written in USD as the MaterialX reader reads them, variants,
`.mtlx` references), bad stages one line each, and `library.usda` written and read back."""

from pathlib import Path

import pytest

pytest.importorskip("pxr")

from brdfremap.adapters.cycles.models import PRINCIPLED  # noqa: E402
from brdfremap.adapters.materialx.reader import standard_libraries  # noqa: E402
from brdfremap.adapters.threejs.models import USD_PREVIEW  # noqa: E402
from brdfremap.adapters.usd.preview import INPUTS  # noqa: E402
from brdfremap.adapters.usd.reader import UsdReader  # noqa: E402
from brdfremap.adapters.usd.writer import MtlxSurface, UsdWriter  # noqa: E402
from brdfremap.adapters.materialx.models import MODELS  # noqa: E402
from brdfremap.core.data.errors import ConfigError  # noqa: E402
from brdfremap.core.data.textures import Texture  # noqa: E402
from brdfremap.core.library.formats import Converted, collect_formats  # noqa: E402
from helpers import ROOT  # noqa: E402

DATA = ROOT / "tests" / "data" / "usd"


def _read(name: str) -> dict:
    return {e.name: e for e in UsdReader().read(DATA / name)}


def test_the_model_s_defaults_are_the_specification_s():
    nodedef = standard_libraries().getNodeDef("ND_UsdPreviewSurface_surfaceshader")
    for pname, iname in INPUTS.items():
        want = nodedef.getActiveInput(iname).getValue()
        have = USD_PREVIEW.param(pname).default
        if pname == "use_specular_workflow":
            assert have == ("specular" if want else "metallic")
        elif hasattr(want, "asTuple"):
            assert tuple(have) == pytest.approx(want.asTuple()), pname
        else:
            assert have == pytest.approx(want), pname


def test_a_stage_s_materials_are_read_as_their_inputs_say():
    got = _read("previews.usda")
    gold = got["gold"]
    assert gold.material.adapter == "threejs" and gold.material.model == "usd_preview_surface"
    assert gold.material.params == {"diffuse_color": (1.0, 0.76, 0.33), "metallic": 1.0, "roughness": 0.3}
    assert any("inputs:roughnes is not an input of UsdPreviewSurface" in n for n in gold.notes)  # a typo, named
    assert any("emission" in n for n in gold.notes)
    paint = got["paint"].material.params
    assert paint["diffuse_color"] == pytest.approx((0.214, 0.0331, 0.0331), abs=1e-3)  # sRGB made linear
    assert paint["clearcoat"] == 1.0 and 0.0 < paint["roughness"] < 1.0  # the texture's mean
    assert got["paint"].textured == ["roughness <- UsdUVTexture 'rough.png'"]
    assert got["specular"].material.params["use_specular_workflow"] == "specular"
    assert USD_PREVIEW.notes(USD_PREVIEW.complete(got["specular"].material.params))  # three.js ignores it: said
    openpbr = got["openpbr"]  # a MaterialX shader written in USD: MaterialX's own model of it, rendered by MaterialX
    assert (openpbr.material.adapter, openpbr.material.model) == ("materialx", "open_pbr_surface")
    assert openpbr.material.params["coat_weight"] == 0.5
    assert any("no_such_input" in n for n in openpbr.notes)
    assert "MyRendererSurface" in got["other"].problem and "\n" not in got["other"].problem


def test_a_variant_that_changes_a_material_is_an_entry_of_its_own():
    got = _read("previews.usda")
    assert got["gold"].material.params["roughness"] == 0.3  # the stage's own selection
    assert got["gold [finish=brushed]"].material.params["roughness"] == 0.6
    assert not [n for n in got if n.startswith("paint [")]  # a variant that does not change it: no entry


@pytest.mark.parametrize("name, words", [("missing_layer.usda", "Could not load sublayer"),
                                         ("cycle_a.usda", "has cycles")])
def test_a_bad_layer_is_one_line_and_the_other_materials_still_read(name, words):
    entries = UsdReader().read(DATA / name)
    bad = [e for e in entries if e.unreadable]
    assert len(bad) == 1 and words in bad[0].problem and "\n" not in bad[0].problem
    if name == "missing_layer.usda":
        assert {"gold", "paint", "openpbr"} <= {e.name for e in entries if e.material is not None}


def test_a_referenced_mtlx_document_is_read_from_its_file_or_said_missing():
    got = _read("mtlx_reference.usda")
    gold = got["gold"].material
    assert gold.adapter == "materialx" and MODELS[gold.model].principled(MODELS[gold.model].complete(gold.params))[
        "metallic"] == 1.0
    assert any("usd-core has no UsdMtlx" in n for n in got["gold"].notes)
    assert got["not_here.mtlx"].unreadable and "not there" in got["not_here.mtlx"].problem


def test_a_file_that_is_not_usd_is_one_line():
    with pytest.raises(ConfigError) as err:
        UsdReader().read(DATA / "not_usd.usda")
    assert "cannot read it as USD" in str(err.value) and "\n" not in str(err.value)


def test_the_usd_formats_are_registered():
    formats = collect_formats()
    assert formats.reader_for(Path("x.usdz")).name.startswith("USD")
    for adapter, model in (("cycles", "principled"), ("mitsuba", "roughconductor"), ("threejs", "usd_preview_surface")):
        assert any(w.name.startswith("USD") for w in formats.writers_for(adapter, {model})), adapter
    assert not any(w.name.startswith("glTF") for w in formats.writers_for("threejs", {"usd_preview_surface"}))


def _library(tmp_path, adapter: str, models: dict, items: list[Converted], **kw) -> Path:
    tmp_path.mkdir(parents=True, exist_ok=True)
    (path,) = UsdWriter(adapter, lambda: models, **kw).write(tmp_path, items)
    return path


def test_library_usda_holds_one_material_per_result_and_reads_back(tmp_path):
    from pxr import Usd, UsdShade

    preview = {"diffuse_color": (0.9, 0.6, 0.2), "metallic": 1.0, "roughness": 0.25}
    principled = {"base_color": (0.6, 0.1, 0.1), "metallic": 0.0, "roughness": 0.4, "coat_weight": 0.3}
    three = _library(tmp_path / "t", "threejs", {"usd_preview_surface": USD_PREVIEW},
                     [Converted("brass", "usd_preview_surface", preview, tmp_path)])
    stage = Usd.Stage.Open(str(three))
    assert [p.GetName() for p in stage.Traverse() if p.IsA(UsdShade.Material)] == ["brass"]
    assert USD_PREVIEW.complete(_read_back(three)["brass"].material.params) == USD_PREVIEW.complete(preview)
    from brdfremap.adapters.materialx.correspondence import DIRECT, open_pbr_inputs

    cycles = _library(tmp_path / "c", "cycles", {"principled": PRINCIPLED},
                      [Converted("red paint", "principled", principled, tmp_path),
                       Converted("red paint 2", "principled", {**principled, "roughness": 0.5}, tmp_path),
                       Converted("red/paint", "principled", principled, tmp_path)],
                      mtlx={"principled": lambda: MtlxSurface(open_pbr_inputs, DIRECT)})
    stage = Usd.Stage.Open(str(cycles))
    materials = [UsdShade.Material(p) for p in stage.Traverse() if p.IsA(UsdShade.Material)]
    assert [m.GetPrim().GetName() for m in materials] == ["red_paint", "red_paint_2", "red_paint_3"]
    assert "approximation" in materials[0].GetPrim().GetDocumentation()
    back = _read_back(cycles)["red_paint"].material  # its mtlx surface, the fitted Principled as OpenPBR, read first
    assert (back.adapter, back.model) == ("materialx", "open_pbr_surface")
    again = MODELS["open_pbr_surface"].principled(MODELS["open_pbr_surface"].complete(back.params))
    for k, v in principled.items():  # the correspondence both ways: the Principled values come back
        assert again[k] == pytest.approx(v, abs=1e-6), k


def _read_back(path: Path) -> dict:
    return {e.name: e for e in UsdReader().read(path)}


def test_maps_are_written_as_uv_textures_with_their_colour_space(tmp_path):
    from pxr import Usd, UsdShade

    tex = {"base_color": Texture(file="textures/a/base.png", colorspace="srgb"),
           "roughness": Texture(file="textures/a/rough.png", colorspace="linear")}
    path = _library(tmp_path, "cycles", {"principled": PRINCIPLED},
                    [Converted("worn", "principled", {"base_color": (0.5, 0.5, 0.5)}, tmp_path, tex)],
                    preview_maps={"principled": {"base_color": "diffuse_color", "roughness": "roughness"}})
    stage = Usd.Stage.Open(str(path))
    shaders = {UsdShade.Shader(p).GetIdAttr().Get(): UsdShade.Shader(p) for p in stage.Traverse() if p.IsA(UsdShade.Shader)}
    uv = [UsdShade.Shader(p) for p in stage.Traverse() if p.IsA(UsdShade.Shader)
          and UsdShade.Shader(p).GetIdAttr().Get() == "UsdUVTexture"]
    spaces = sorted((s.GetInput("file").Get().path, s.GetInput("sourceColorSpace").Get()) for s in uv)
    assert spaces == [("textures/a/base.png", "sRGB"), ("textures/a/rough.png", "raw")]
    surface = shaders["UsdPreviewSurface"]
    assert surface.GetInput("diffuseColor").HasConnectedSource() and surface.GetInput("roughness").HasConnectedSource()


def test_a_token_input_is_compared_as_a_token_and_a_string_for_a_number_is_one_line(tmp_path):
    stage = tmp_path / "tokens.usda"
    stage.write_text('''#usda 1.0
def Material "cutout"
{
    token outputs:surface.connect = </cutout/S.outputs:surface>
    def Shader "S"
    {
        uniform token info:id = "UsdPreviewSurface"
        token inputs:opacityMode = "presence"
        float inputs:roughness = 0.3
        token outputs:surface
    }
}
def Material "wrong"
{
    token outputs:surface.connect = </wrong/S.outputs:surface>
    def Shader "S"
    {
        uniform token info:id = "UsdPreviewSurface"
        string inputs:metallic = "yes"
        token outputs:surface
    }
}
''')
    entries = {e.name: e for e in UsdReader().read(stage)}
    assert entries["cutout"].material.params["roughness"] == pytest.approx(0.3)
    assert any("opacityMode" in n for n in entries["cutout"].notes), entries["cutout"].notes
    assert entries["wrong"].material is None
    assert "inputs:metallic is 'yes'" in entries["wrong"].problem and "\n" not in entries["wrong"].problem

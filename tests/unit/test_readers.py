"""Library readers without a render: Mitsuba XML (no Mitsuba needed), MaterialX (the materialx
package), the project's YAML; their errors name the file."""

from pathlib import Path

import pytest
from brdfremap.core.data.errors import ConfigError
from brdfremap.core.library.formats import collect_formats, expand_inputs, read_all

DATA = Path(__file__).resolve().parents[1] / "data"


@pytest.fixture(scope="module")
def formats():
    return collect_formats()


def _read(formats, *paths):
    return {e.name: e for e in read_all(expand_inputs([str(p) for p in paths], formats), formats)}


def test_every_bsdf_of_a_mitsuba_scene_is_read_as_mitsuba_reads_it(formats):
    got = _read(formats, DATA / "scenes" / "mixed.xml")
    assert len(got) == 11  # ten at the top level, and an anonymous one inside a shape named after it
    assert got["gold"].material.params == {"material": "Au", "alpha": 0.15}  # <default> and $rough
    assert got["tinted mirror"].material.params["specular_reflectance"] == (0.8, 0.7, 0.6)
    # Mitsuba's default conductor (no preset, no eta/k) is a perfect mirror: eta 0, k 1.
    assert got["tinted mirror"].material.params["eta"] == (0.0, 0.0, 0.0)
    assert got["green plastic"].material.params["int_ior"] == 1.49  # "acrylic glass"
    assert "twosided" in got["green plastic"].notes[0]
    assert got["glossy white"].material.model == "plastic"  # smooth: fitted under the studio environment
    assert got["smooth silver"].material.model == "conductor"
    assert got["glossy white"].material.params["diffuse_reflectance"] == (0.7, 0.7, 0.7)  # a uniform spectrum
    assert got["wood"].textured == ["reflectance <- bitmap 'textures/wood.png'"]
    steel = got["brushed steel"].material.params
    assert (steel["anisotropy"], steel["alpha_u"], steel["alpha_v"]) == ("anisotropic", 0.05, 0.3)
    assert got["rubber ball"].material.model == "roughplastic"
    assert got["glass"].material.model == "dielectric" and got["glass"].material.params["int_ior"] == 1.5
    mix = got["mix"].material.params
    assert (mix["bsdf_0"], mix["bsdf_1"]) == ("diffuse", "roughconductor") and 0 < mix["weight"] < 1


@pytest.mark.parametrize("text, words", [
    ("<scene version='3.0.0'><bsdf type='diffuse' id='a'></scene>", "line 1, column"),
    ("<scene version='3.0.0'><bsdf type='roughconductor' id='a'><float name='alpha' value='$r'/></bsdf></scene>",
     "$r is used but no <default name='r'>"),
    ("<scene version='3.0.0'><shape type='sphere'><ref id='nope'/></shape>"
     "<bsdf type='twosided' id='t'><ref id='nope'/></bsdf></scene>", "<ref id='nope'> names nothing"),
    ("<scene version='3.0.0'><include filename='missing.xml'/></scene>", "missing.xml: cannot read"),
])
def test_a_broken_scene_is_one_error_naming_the_file(tmp_path, formats, text, words):
    path = tmp_path / "s.xml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=words.replace("$", r"\$").replace("(", r"\(")):
        _read(formats, path)


def test_includes_are_read_and_entities_are_not_expanded(tmp_path, formats):
    (tmp_path / "lib.xml").write_text("<scene version='3.0.0'><bsdf type='diffuse' id='inc'/></scene>")
    (tmp_path / "main.xml").write_text("<scene version='3.0.0'><include filename='lib.xml'/>"
                                       "<bsdf type='diffuse' id='own'/></scene>")
    assert set(_read(formats, tmp_path / "main.xml")) == {"inc", "own"}
    (tmp_path / "evil.xml").write_text('<?xml version="1.0"?><!DOCTYPE s [<!ENTITY x SYSTEM "file:///etc/passwd">]>'
                                       "<scene version='3.0.0'><bsdf type='diffuse' id='&x;'/></scene>")
    with pytest.raises(ConfigError):  # an external entity is not resolved: the parser refuses it
        _read(formats, tmp_path / "evil.xml")


def _rule(entry):
    """The fixed rule's Principled values of an entry read from MaterialX (the correspondence)."""
    from brdfremap.adapters.materialx.models import MODELS

    model = MODELS[entry.material.model]
    return model.principled(model.complete(entry.material.params))


def test_materialx_documents_are_read_as_their_own_shaders(formats):
    """Each material is the materialx adapter's model of its shader, its inputs as written; Blender's
    Principled BSDF is the fixed rule's reading of it, not what is rendered."""
    got = _read(formats, DATA / "materialx")
    assert len(got) == 9 and all(e.material.adapter == "materialx" for e in got.values())
    assert {e.material.model for e in got.values()} == {"open_pbr_surface", "standard_surface", "gltf_pbr",
                                                         "UsdPreviewSurface"}
    copper = got["copper"].material.params  # a MaterialX 1.38 document, upgraded on reading
    assert copper["metalness"] == 1.0 and copper["base_color"] == (0.955, 0.638, 0.538)
    blue = got["blue_plastic"].material.params
    assert blue["base"] == 0.9 and blue["sheen"] == 0.3
    rule = _rule(got["blue_plastic"])
    assert rule["base_color"] == pytest.approx((0.045, 0.135, 0.54))  # base (0.9) times base_color
    assert rule["sheen_weight"] == 0.3  # as Blender's MaterialX export maps it
    assert got["wood"].textured == ["base_color <- image 'wood.png'"]
    assert _rule(got["gold"])["anisotropic"] > 0  # specular_roughness_anisotropy
    assert _rule(got["chrome"])["metallic"] == 1.0 and got["clay"].material.params["roughness"] == 0.8


def test_an_invalid_materialx_document_is_one_error(tmp_path, formats):
    bad = tmp_path / "bad.mtlx"
    bad.write_text('<?xml version="1.0"?><materialx version="1.39"><open_pbr_surface name="s" '
                   'type="surfaceshader"><input name="base_color" type="color3" value="oops" /></open_pbr_surface>'
                   '</materialx>')
    with pytest.raises(ConfigError, match="bad.mtlx"):
        _read(formats, bad)
    bad.write_text("not xml at all")
    with pytest.raises(ConfigError, match="bad.mtlx: cannot read it as MaterialX"):
        _read(formats, bad)


def test_a_folder_reads_the_materials_it_holds_and_names_stay_unique(tmp_path, formats, root):
    (tmp_path / "gold.yaml").write_text((root / "configs/materials/gold.yaml").read_text())
    (tmp_path / "exp.yaml").write_text("kind: sweep\nname: not a material\n")  # skipped in a folder
    (tmp_path / "notes.txt").write_text("ignored")
    (tmp_path / "lib.xml").write_text("<scene version='3.0.0'><bsdf type='diffuse' id='gold'/></scene>")
    got = _read(formats, tmp_path)
    assert set(got) == {"lib/gold", "gold/gold"}  # two golds: each named after its file
    with pytest.raises(ConfigError, match="not found"):
        expand_inputs([str(tmp_path / "nope.xml")], formats)
    with pytest.raises(ConfigError, match="no reader for this kind of file"):
        read_all([tmp_path / "notes.txt"], formats)


def test_openpbr_before_1_0_is_read_with_its_renames_noted(formats):
    """A published MaterialX 1.38 document (OpenPBR's own brushed aluminium) with OpenPBR's pre-1.0
    input names: read, each rename and left-out input noted."""
    got = _read(formats, DATA / "openpbr" / "open_pbr_aluminum_brushed.mtlx")["Aluminum_Brushed"]
    assert got.material.params["specular_roughness_anisotropy"] == pytest.approx(0.9)  # its anisotropy, renamed
    assert _rule(got)["anisotropic"] == pytest.approx(1.0)  # 0.9 / 0.9: Disney's (Blender's) anisotropy
    assert any("specular_anisotropy is read as specular_roughness_anisotropy" in n for n in got.notes)
    assert any(n.startswith("specular_rotation = 0.25 is left out") for n in got.notes)


def test_materialx_colours_are_read_from_their_colour_space(formats):
    """OpenPBR's examples are in ACEScg: a colour is turned into linear Rec.709 as MaterialX's own
    acescg_to_lin_rec709 does (the matrix of its colour-management library)."""
    banana = _read(formats, DATA / "openpbr" / "open_pbr_banana.mtlx")["Banana"]
    assert banana.material.params["base_color"] == pytest.approx((0.6350, 0.5314, 0.1112), abs=2e-4)
    assert any("is in acescg" in n for n in banana.notes)
    copper = _read(formats, DATA / "openpbr" / "open_pbr_copper.mtlx")["Copper"]  # lin_rec709: as written
    assert copper.material.params["base_color"] == (0.988, 0.688, 0.448)
    assert not any("colour space" in n or "is in " in n for n in copper.notes)


def test_a_file_that_cannot_be_read_is_listed_and_the_others_are_read(tmp_path, formats):
    bad = tmp_path / "a_broken.mtlx"
    bad.write_text('<?xml version="1.0"?>\n<materialx version="1.39">\n  <open_pbr_surface name="s" type="surfaceshader">\n'
                   '    <input name="no_such_input" type="float" value="1" />\n  </open_pbr_surface>\n</materialx>\n')
    paths = [bad, DATA / "openpbr" / "open_pbr_tire.mtlx"]
    with pytest.raises(ConfigError, match="a_broken.mtlx"):
        read_all(paths, formats)
    got = {e.name: e for e in read_all(paths, formats, keep_going=True)}
    assert got["a_broken"].unreadable and "line 4" in got["a_broken"].problem and "no_such_input" in \
        got["a_broken"].problem
    assert got["Tire"].material is not None


def test_a_materialx_glass_is_tinted_by_its_transmission_colour(formats):
    """OpenPBR and Standard Surface tint a glass by transmission_color; Blender's Principled BSDF by
    Base Color: a clear water stays clear (not the default base colour's 0.8 grey)."""
    water = _rule(_read(formats, DATA / "openpbr" / "open_pbr_water.mtlx")["Water"])
    assert water["base_color"] == (1.0, 1.0, 1.0) and water["transmission_weight"] == 1.0
    honey = _read(formats, DATA / "openpbr" / "open_pbr_honey_liquid.mtlx")["Honey_liquid"]
    assert honey.material.params["transmission_color"] == pytest.approx((0.8309, 0.5709, 0.0372), abs=2e-4)  # ACEScg, read linear
    assert _rule(honey)["base_color"] == pytest.approx((0.8309, 0.5709, 0.0372), abs=2e-4)


def test_a_materialx_gltf_glass_transmits(formats, corpus):
    """MaterialX's own glTF glass (`transmission` 1): a transmissive model, and a Principled glass by
    the fixed rule."""
    from brdfremap.adapters.materialx.models import MODELS

    entry = _read(formats, corpus / "materialx" / "GltfPbr" / "gltf_pbr_glass.mtlx")["PBR_Glass"]
    assert MODELS["gltf_pbr"].transmissive(entry.material.params)
    assert _rule(entry)["transmission_weight"] == 1.0 and _rule(entry)["ior"] == 1.52

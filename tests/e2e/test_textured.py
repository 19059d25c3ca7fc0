"""Textured materials end to end: read from the files they live in (a Mitsuba scene with bitmaps, a
.blend with Image Texture nodes, a MaterialX document with image nodes), remapped texel by texel
through a table, written as libraries whose materials read their maps, and those libraries opened
in the target renderer again."""

import json
import subprocess
import sys

import numpy as np
import yaml
from brdfremap.core.cli import main
from brdfremap.core.data.imageio import read_image
from brdfremap.core.data.metrics import relative_rmse
from brdfremap.core.data.scene import EnvironmentLight, ProbeScene
from brdfremap.core.tables.build import fit_candidates
from brdfremap.core.tables.table import write_table
from helpers import ROOT, one_line_error, remap
from reports import read_result
from tablekit import principled_table

DATA = ROOT / "tests" / "data" / "textured"
FAST = ["--resolution", "32", "--spp", "8", "--validate", "none", "--quiet"]
SMALL_TABLE = {
    "kind": "table", "name": "metal to Mitsuba principled",
    "source": {"adapter": "mitsuba", "model": "roughconductor",
               "params": {"distribution": "beckmann", "eta": 0, "k": 1}},
    "axes": {"alpha": {"range": [0.05, 0.4], "steps": 3, "scale": "log"},
             "specular_reflectance": {"range": [0.5, 1.0], "steps": 2}},
    "target": {"adapter": "mitsuba", "model": "principled"},
    "holdout": 0, "scene": {"resolution": 32}, "options": {"validation": "none"},
}


def _studio(resolution: int, spp: int) -> ProbeScene:
    return ProbeScene().overridden(resolution=resolution, spp=spp).model_copy(
        update={"lights": [EnvironmentLight(type="environment", map="studio")]})


def _textured(out, name="worn metal"):
    doc = json.loads((out / "convert.json").read_text())
    row = next(m for m in doc["materials"] if m["name"] == name)
    return row, read_result(out / "materials" / row["slot"] / "result.json")


def test_the_mitsuba_reader_gives_each_bitmap_its_colour_space_and_filter():
    from brdfremap.adapters.mitsuba.reader import MitsubaXmlReader

    entries = {e.name: e for e in MitsubaXmlReader().read(DATA / "scene.xml")}
    tex = entries["worn metal"].material.textures
    assert set(tex) == {"alpha", "specular_reflectance"}
    assert (tex["alpha"].colorspace, tex["specular_reflectance"].colorspace) == ("linear", "srgb")  # raw, or sRGB
    assert tex["alpha"].filter == "nearest" and tex["alpha"].file == str(DATA / "roughness.png")
    assert len(tex["alpha"].sha256) == 64 and not entries["plain gold"].material.textures


def test_a_textured_metal_converts_through_a_table_to_mitsuba_and_the_library_renders_its_maps(
        tmp_path, mitsuba_adapter):
    spec = tmp_path / "spec.yaml"
    spec.write_text(yaml.safe_dump(SMALL_TABLE))
    assert main(["table", "build", str(spec), "--out", str(tmp_path / "table"), "--quiet"]) == 0
    out = tmp_path / "lib"
    assert main(["convert", str(DATA / "scene.xml"), "--to", "mitsuba", "--table", str(tmp_path / "table"),
                 "--out", str(out), *FAST]) == 0
    row, report = _textured(out)
    assert row["model"] == "principled" and "texel by texel" in row["model_why"]
    t = report["textures"]
    assert (t["width"], t["height"]) == (8, 8) and {m["param"] for m in t["maps"]} == {"base_color", "roughness"}
    assert t["held"] and "specular" in next(iter(t["held"]))  # Mitsuba's principled takes specular as a number
    assert [c["condition"] for c in t["checks"]] == ["scene", "environment"]
    assert all(0 < c["error"] < 0.5 for c in t["checks"])
    # The library's material, loaded by Mitsuba from library.xml with its bitmaps, renders as the check's result.
    import mitsuba as mi

    xml = (out / "library.xml").read_text()
    assert '<string name="filename" value="textures/' in xml
    resolver = mi.file_resolver()
    kept = [str(resolver[i]) for i in range(len(resolver))]  # Mitsuba's own folders (its plugins among them)
    resolver.prepend(str(out))
    try:
        scene_doc = mitsuba_adapter.scene_dict("principled", mitsuba_adapter.models["principled"].complete({}),
                                               _studio(64, 128))
        scene_doc["probe"]["bsdf"] = mi.load_string(_bsdf_of(xml, "worn metal"))
        img = np.array(mi.render(mi.load_dict(scene_doc), seed=7, spp=128))[..., :3]
    finally:  # as it was: clear() alone would leave later renders without Mitsuba's plugins
        resolver.clear()
        for folder in kept:
            resolver.append(folder)
    ref = read_image(out / "materials" / row["slot"] / "target-textured.exr")
    assert relative_rmse(ref, img) < 3 * max(t["checks"][1]["noise_floor"], 0.01)
    plain = _textured(out, "plain gold")[1]
    assert plain["textures"] is None and plain["job"]["lookup"] is None  # fitted as ever


def _bsdf_of(xml: str, name: str) -> str:
    """One `<bsdf id=NAME>` element of a library, as a document of its own."""
    import xml.etree.ElementTree as ET

    elem = next(e for e in ET.fromstring(xml) if e.get("id") == name)
    elem.set("version", "3.0.0")
    del elem.attrib["id"]
    return ET.tostring(elem, encoding="unicode")


def test_a_textured_metal_converts_to_a_blend_whose_material_renders_its_maps(tmp_path, mitsuba_adapter,
                                                                              cycles_adapter):
    table = tmp_path / "table"
    table.mkdir()
    write_table(table / "table.json", principled_table(tmp_path))
    out = tmp_path / "lib"
    assert main(["convert", str(DATA / "scene.xml"), "--to", "cycles", "--table", str(table), "--out", str(out),
                 "--only", "worn metal", *FAST]) == 0
    row, report = _textured(out)
    t = report["textures"]
    studio = next(c for c in t["checks"] if c["condition"] == "environment")
    ref = read_image(out / "materials" / row["slot"] / "target-textured.exr")
    scene = _studio(studio["resolution"], studio["spp"])
    for blend, name in ((out / "library.blend", "worn metal"), (out / "materials" / row["slot"] / "material.blend",
                                                               "brdf-remap")):
        img = cycles_adapter.render_saved(blend, name, scene)
        assert relative_rmse(ref, img) < 3 * max(studio["noise_floor"], 0.01), blend
    assert 'colorspace="srgb_texture"' in (out / "library.mtlx").read_text()
    assert (out / "textures" / row["slot"] / "map-base_color.png").exists()
    from brdfremap.adapters.cycles.library import BlendReader

    back = BlendReader().read(out / "library.blend")[0].material  # and read back: its maps are textures again
    assert set(back.textures) == {"base_color", "roughness"} and back.textures["base_color"].colorspace == "srgb"


def test_without_a_table_a_textured_material_keeps_its_constants_and_says_why(tmp_path, mitsuba_adapter):
    out = tmp_path / "lib"
    assert main(["convert", str(DATA / "scene.xml"), "--to", "mitsuba", "--only", "worn metal", "--out", str(out),
                 *FAST]) == 0
    row, report = _textured(out)
    assert report["textures"] is None and any("no --table maps mitsuba:roughconductor" in n for n in row["notes"])


def test_a_textured_material_file_through_a_table_without_renders(tmp_path):
    table = tmp_path / "table"
    table.mkdir()
    write_table(table / "table.json", principled_table(tmp_path))
    material = tmp_path / "m.yaml"
    material.write_text(yaml.safe_dump({
        "adapter": "mitsuba", "model": "roughconductor", "params": {"distribution": "beckmann", "eta": 0, "k": 1},
        "textures": {"alpha": {"file": str(DATA / "roughness.png"), "colorspace": "linear"},
                     "specular_reflectance": {"file": str(DATA / "reflectance.png"), "colorspace": "srgb"}}}))
    done = remap("--table", table, "--source", material, "--out", tmp_path / "o", "--no-render")
    assert done.returncode == 0, done.stderr[-2000:]
    doc = json.loads((tmp_path / "o" / "lookup.json").read_text())
    assert {m["param"] for m in doc["textures"]["maps"]} == {"base_color", "roughness"}
    assert (tmp_path / "o" / "material.blend").exists() and (tmp_path / "o" / "map-roughness.exr").exists()
    # A fit cannot take a textured source: one line says what to do.
    one_line_error(remap("--adapter", "cycles", "--model", "principled", "--source", material, "--out",
                         tmp_path / "f"), "textures", "--table")


BLEND_SCRIPT = """
import sys, bpy
bpy.ops.wm.read_factory_settings(use_empty=True)
m = bpy.data.materials.new("painted")
m.use_nodes = True
tree = m.node_tree
b = tree.nodes["Principled BSDF"]
for socket, file, space in (("Base Color", sys.argv[-3], "sRGB"), ("Roughness", sys.argv[-2], "Non-Color")):
    tex = tree.nodes.new("ShaderNodeTexImage")
    tex.image = bpy.data.images.load(file)
    tex.image.colorspace_settings.name = space
    tree.links.new(tex.outputs["Color"], b.inputs[socket])
mapped = tree.nodes.new("ShaderNodeTexImage")
mapped.image = bpy.data.images.load(sys.argv[-3])
coords = tree.nodes.new("ShaderNodeMapping")
tree.links.new(coords.outputs[0], mapped.inputs["Vector"])
tree.links.new(mapped.outputs["Color"], b.inputs["Specular Tint"])
m.use_fake_user = True
bpy.ops.wm.save_as_mainfile(filepath=sys.argv[-1])
"""


def test_a_blend_image_texture_and_a_materialx_image_are_read_as_textures(tmp_path, cycles_adapter):
    from brdfremap.adapters.cycles.library import BlendReader
    from brdfremap.adapters.materialx.reader import MaterialXReader

    blend = tmp_path / "painted.blend"
    made = subprocess.run([sys.executable, "-c", BLEND_SCRIPT, str(DATA / "reflectance.png"),
                           str(DATA / "roughness.png"), str(blend)], capture_output=True, text=True)
    assert made.returncode == 0, made.stderr[-2000:]
    (entry,) = BlendReader().read(blend)
    tex = entry.material.textures
    assert set(tex) == {"base_color", "roughness"} and tex["roughness"].colorspace == "linear"
    assert any("specular_tint" in n and "coordinate node graph" in n for n in entry.notes)

    doc = tmp_path / "looks.mtlx"
    doc.write_text(MTLX.format(colour=DATA / "reflectance.png", rough=DATA / "roughness.png"))
    (look,) = MaterialXReader().read(doc)
    tex = look.material.textures
    assert set(tex) == {"base_color", "specular_roughness"} and tex["base_color"].colorspace == "srgb"  # its inputs
    assert tex["specular_roughness"].colorspace == "linear" and tex["specular_roughness"].filter == "nearest"


MTLX = """<?xml version="1.0"?>
<materialx version="1.39">
  <image name="colour" type="color3">
    <input name="file" type="filename" value="{colour}" colorspace="srgb_texture" />
  </image>
  <image name="rough" type="float">
    <input name="file" type="filename" value="{rough}" />
    <input name="filtertype" type="string" value="closest" />
  </image>
  <standard_surface name="look_shader" type="surfaceshader">
    <input name="base_color" type="color3" nodename="colour" />
    <input name="specular_roughness" type="float" nodename="rough" />
  </standard_surface>
  <surfacematerial name="look" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="look_shader" />
  </surfacematerial>
</materialx>
"""


def test_convert_takes_the_table_whose_direct_fits_come_closest(tmp_path):
    """Two tables map the textured metal to Cycles: convert keeps the one whose fits reach the least
    error at the textures' mean (as a fit keeps the model that fits best), and says so; the order
    the tables were given in does not matter."""
    from brdfremap.core.library.convert import (
        Destination,
        Item,
        TableUse,
        _through_table,
    )
    from brdfremap.core.library.formats import collect_formats, read_all
    from brdfremap.core.host.plugins import collect_adapters
    from brdfremap.core.data.settings import Settings
    from brdfremap.core.tables import TableMap

    registry = collect_adapters()
    loose = principled_table(tmp_path)  # its fits: 10 %
    close = loose.model_copy(update={"name": "closer", "points": [
        p.model_copy(update={"error": 0.02}) for p in loose.points]})
    close = close.model_copy(update={"candidates": fit_candidates(close)})
    uses = [TableUse(f"{t.name}.json", t, TableMap(t)) for t in (loose, close)]
    entry = next(e for e in read_all([DATA / "scene.xml"], collect_formats()) if e.name == "worn metal")
    for order in (uses, uses[::-1]):
        item = Item(entry, "worn-metal")
        assert _through_table(item, Destination.parse("cycles", registry), registry, ProbeScene(), Settings(), order)
        assert item.task.job.lookup.table == "closer" and item.model == "principled"
        assert "'closer'" in item.why and "its fits reach 2.0%" in item.why
        assert "'synthetic principled' (principled) 10.0%" in item.why


def test_materialx_own_gltf_boombox_reads_its_packed_textures_and_goes_through_a_table(corpus, tmp_path,
                                                                                        mitsuba_adapter,
                                                                                        cycles_adapter):
    """MaterialX's own glTF example (the corpus's boombox): its base colour a `gltf_colorimage`, its
    roughness and metallic the green and blue of one `gltf_image` through a `separate3`. Read as
    textures (their constants the images' means), and remapped to Mitsuba texel by texel through the
    shipped Principled table (its clearcoat roughness of 0, which does nothing without a coat, is not
    a difference from the table's 0.03)."""
    from brdfremap.adapters.materialx.reader import MaterialXReader

    doc = corpus / "materialx" / "GltfPbr" / "gltf_pbr_boombox.mtlx"
    (box,) = MaterialXReader().read(doc)
    tex = box.material.textures
    assert {k: (t.channel, t.colorspace) for k, t in tex.items()} == {
        "base_color": (None, "srgb"), "roughness": (1, "linear"), "metallic": (2, "linear"), "emissive": (None, "srgb")}
    assert box.material.params["metallic"] < 0.2 and max(box.material.params["base_color"]) < 0.3  # black plastic
    table = ROOT / "configs" / "tables" / "built" / "cycles-principled-to-mitsuba-principled.json"
    assert main(["convert", str(doc), "--to", "mitsuba", "--table", str(table), "--out", str(tmp_path / "o"),
                 *FAST]) == 0
    row = json.loads((tmp_path / "o" / "convert.json").read_text())["materials"][0]
    assert "texel by texel" in row["model_why"], row
    result = read_result(tmp_path / "o" / "materials" / row["slot"] / "result.json")
    assert (result["textures"]["width"], result["textures"]["height"]) == (2048, 2048)
    assert any("roughness 0 below the table's range" in o for o in result["textures"]["outside"])  # said

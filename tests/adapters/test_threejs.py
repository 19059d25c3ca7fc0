"""The three.js adapter with real three.js in Debian's headless Chromium: the conventions
(`remap check`), a white Lambertian against the analytic radiance and Mitsuba and Cycles under each
light type, a crash, glTF written (the Khronos validator, three.js's GLTFLoader, Blender's importer)
and glTF read."""

import json
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest

from brdfremap.adapters.threejs.adapter import ThreeJsAdapter
from brdfremap.adapters.threejs.library import GltfReader, material_document, sphere_document
from brdfremap.core.data.errors import RenderError
from brdfremap.core.data.metrics import relative_rmse
from brdfremap.core.data.scene import EnvironmentLight, PointLight, ProbeScene
from brdfremap.core.data.textures import TextureMap
from brdfremap.core.host import check
from brdfremap.core.testing import analytic_lambert, sphere_hits
from conftest import ROOT, need_adapter
from helpers import checker, remap

VALIDATOR = os.path.join(os.path.dirname(sys.modules["brdfremap.adapters.threejs.adapter"].__file__), "web",
                         "validate.mjs")


@pytest.fixture(scope="module")
def three():
    need_adapter(ThreeJsAdapter)
    adapter = ThreeJsAdapter()
    yield adapter
    adapter.close()


def validate(path) -> dict:
    if shutil.which("node") is None:
        if os.environ.get("CI"):
            pytest.fail("Node.js must be installed in CI (make system-deps installs it)")
        pytest.skip("Node.js is not installed")
    out = subprocess.run(["node", VALIDATOR, str(path)], capture_output=True, text=True, timeout=120, check=True)
    return json.loads(out.stdout)["issues"]


def _white(adapter):
    model, given = adapter.calibration
    return model, adapter.models[model].complete(given)


def test_remap_check_passes_the_six_conventions_and_says_why_a_glass_cannot(three):
    model, glass = three.glasses["smooth"]
    mirror, given = three.mirror
    rows = check.run(three.render, three.models, _white(three), (model, three.models[model].complete(glass)),
                     environment=True, transmission_limit=three.transmission_limit,
                     mirror=(mirror, three.models[mirror].complete(given)))
    by = {r.name.split(":")[0]: r for r in rows}
    assert all(r.passed for n, r in by.items() if n != "transmission"), rows
    assert float(by["units"].detail.split("%")[0]) < 0.5  # a fraction of a percent from the analytic radiance
    glass = by["transmission"]
    assert glass.passed is False and glass.by_design and "screen-space" in glass.fix


@pytest.mark.parametrize("light, res, to_analytic", [
    (PointLight(), 128, 0.002),  # the probe light
    (PointLight(theta=120.0), 128, 0.04),  # the rim: 3.3 % at the terminator, as Mitsuba and Cycles are
    (EnvironmentLight(type="environment", map="constant", scale=0.35), 64, 0.002),
    (EnvironmentLight(type="environment", map="studio"), 64, 0.01),  # asymmetric: pins the orientation
])
def test_a_white_lambertian_under_each_light_type(three, mitsuba_adapter, light, res, to_analytic):
    scene = ProbeScene(lights=[light], resolution=res, spp=256)
    img = three.render(*_white(three), scene)
    inner = sphere_hits(scene).interior
    ref = analytic_lambert(scene, 0.8)[inner]
    assert relative_rmse(ref, img[inner]) < to_analytic
    mi = mitsuba_adapter.render("diffuse", mitsuba_adapter.models["diffuse"].complete({"reflectance": 0.8}), scene)
    assert relative_rmse(mi[inner], img[inner]) < 0.02
    assert img[0, 0].max() == 0  # the environment is not seen behind the sphere


def test_a_crashed_browser_is_a_render_error_with_its_console_and_the_next_render_starts_another(three):
    scene = ProbeScene(resolution=32)
    first = three.render(*_white(three), scene)
    page = three.page

    def crash():
        page._page.evaluate("() => { console.error('about to fail'); }")
        page._page.close()  # the tab is gone, as after a renderer crash

    page._in_thread(crash)
    with pytest.raises(RenderError, match="threejs: the render failed") as err:
        three.render(*_white(three), scene)
    assert "about to fail" in str(err.value)
    assert np.array_equal(three.render(*_white(three), scene), first)  # a fresh browser, the same image


MATERIALS = [
    ("gold", {"base_color": (1.0, 0.78, 0.34), "metallic": 1.0, "roughness": 0.3}),
    ("red paint", {"base_color": (0.6, 0.05, 0.03), "metallic": 0.0, "roughness": 0.5, "clearcoat": 1.0,
                   "clearcoat_roughness": 0.05, "ior": 1.45}),
    ("velvet", {"base_color": (0.2, 0.0, 0.3), "metallic": 0.0, "roughness": 0.8, "sheen_color": (0.8, 0.5, 0.9),
                "sheen_roughness": 0.4}),
    ("brushed", {"base_color": (0.9, 0.9, 0.9), "metallic": 1.0, "roughness": 0.4, "anisotropy": 0.6,
                 "anisotropy_rotation": 0.25}),
]


def test_a_written_gltf_validates_and_renders_in_three_js_as_it_was_fitted(three, tmp_path):
    spec = three.models["gltf_pbr"]
    doc = sphere_document(MATERIALS, spec)
    path = tmp_path / "library.gltf"
    path.write_text(json.dumps(doc))
    issues = validate(path)
    assert issues["numErrors"] == 0 and issues["numWarnings"] == 0, issues["messages"]
    assert sorted(doc["extensionsUsed"]) == ["KHR_materials_anisotropy", "KHR_materials_clearcoat",
                                             "KHR_materials_ior", "KHR_materials_sheen"]
    assert "extensions" not in doc["materials"][0]  # the gold needs none
    scene = ProbeScene(resolution=48)
    for i, (name, params) in enumerate(MATERIALS):
        direct = three.render("gltf_pbr", spec.complete(params), scene)
        loaded = three.render_document(material_document(json.loads(path.read_text()), i), scene)
        assert np.array_equal(direct, loaded), name
    entries = GltfReader().read(path)  # and read back as sources, the same parameters
    assert [e.name for e in entries] == [m for m, _ in MATERIALS]
    for e, (_, params) in zip(entries, MATERIALS):
        got = e.material.params
        for k, v in params.items():
            assert np.allclose(got[k], v, atol=1e-6), (e.name, k, got[k], v)


def test_blender_imports_the_written_gltf(tmp_path, cycles_adapter):
    spec = ThreeJsAdapter.models["gltf_pbr"]
    path = tmp_path / "library.gltf"
    path.write_text(json.dumps(sphere_document(MATERIALS, spec)))
    code = ("import bpy, sys\n"
            "bpy.ops.wm.read_factory_settings(use_empty=True)\n"
            f"bpy.ops.import_scene.gltf(filepath={str(path)!r})\n"
            "print('MATERIALS', sorted(m.name for m in bpy.data.materials if m.users))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    assert "MATERIALS ['brushed', 'gold', 'red paint', 'velvet']" in out.stdout


def test_a_gltf_with_textures_and_unknown_extensions_is_read_with_notes(tmp_path):
    doc = {"asset": {"version": "2.0"}, "extensionsUsed": ["KHR_materials_volume", "KHR_texture_transform"],
           "textures": [{"source": 0}], "images": [{"uri": "brass.png"}],
           "materials": [{"name": "brass", "pbrMetallicRoughness": {
               "baseColorFactor": [0.9, 0.7, 0.3, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.35,
               "baseColorTexture": {"index": 0}}, "extensions": {"KHR_materials_volume": {"thicknessFactor": 1}}},
               {"pbrMetallicRoughness": {"roughnessFactor": 3.0}}]}
    path = tmp_path / "m.gltf"
    path.write_text(json.dumps(doc))
    brass, second = GltfReader().read(path)
    assert brass.material.params["base_color"] == (0.9, 0.7, 0.3) and brass.material.params["roughness"] == 0.35
    assert brass.textured == ["base_color <- texture 0"]
    assert any("KHR_materials_volume" in n for n in brass.notes)
    assert second.name == "material 1" and second.material.params["roughness"] == 1.0
    assert any("outside the model's bounds" in n for n in second.notes)


SAMPLE = ROOT / "tests" / "data" / "gltf" / "MetalRoughSpheresNoTextures-materials.gltf"
QUICK = ["--resolution", "48", "--spp", "16", "--quiet"]


def test_a_library_converted_to_three_js_is_one_valid_gltf_of_its_fits(tmp_path, mitsuba_adapter, three):
    lib = tmp_path / "lib"
    lib.mkdir()
    (lib / "gold.yaml").write_text("name: gold\nadapter: mitsuba\nmodel: roughconductor\n"
                                   "params: {distribution: ggx, material: Au, alpha: 0.2}\n")
    (lib / "plastic.yaml").write_text("name: red plastic\nadapter: mitsuba\nmodel: roughplastic\n"
                                      "params: {distribution: ggx, alpha: 0.2, diffuse_reflectance: [0.5, 0.05, 0.04]}\n")
    proc = remap("convert", lib, "--to", "threejs", "--out", tmp_path / "out", *QUICK, "--validate", "none")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    path = tmp_path / "out" / "library.gltf"
    issues = validate(path)
    assert issues["numErrors"] == 0 and issues["numWarnings"] == 0, issues["messages"]
    doc = json.loads(path.read_text())
    by_name = {m["name"]: i for i, m in enumerate(doc["materials"])}
    assert set(by_name) == {"gold", "red plastic"} and len(doc["nodes"]) == 2
    summary = json.loads((tmp_path / "out" / "convert.json").read_text())
    scene = ProbeScene(resolution=48)
    for row in summary["materials"]:  # each material in the file renders as its fit's parameters do
        result = json.loads((tmp_path / "out" / "materials" / row["slot"] / "result.json").read_text())
        fitted = three.render("gltf_pbr", three.models["gltf_pbr"].complete(result["params"]), scene)
        assert np.array_equal(three.render_document(material_document(doc, by_name[row["name"]]), scene), fitted)


def test_a_gltf_sample_assets_materials_convert_to_cycles(tmp_path, cycles_adapter, three):
    """Khronos' MetalRoughSpheresNoTextures (factor-only materials): a grey dielectric and a gold metal
    of it, read from glTF and remapped to Cycles' Principled BSDF."""
    proc = remap("convert", SAMPLE, "--to", "cycles:principled", "--only", "mat_3", "--only", "mat_94", "--out",
                 tmp_path / "out", *QUICK, "--validate", "none")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    rows = {r["name"]: r for r in json.loads((tmp_path / "out" / "convert.json").read_text())["materials"]}
    assert set(rows) == {"mat_3", "mat_94"}
    for name, row in rows.items():
        assert row["status"] not in ("failed", "unsupported"), row
        assert row["relative_rmse"] < 0.1, row
        result = json.loads((tmp_path / "out" / "materials" / row["slot"] / "result.json").read_text())
        metallic = result["params"]["metallic"]
        assert (metallic > 0.9) if name == "mat_94" else (metallic < 0.2), (name, result["params"])


def test_remap_check_threejs_exits_0_and_calls_the_glass_a_limit():
    need_adapter(ThreeJsAdapter)
    proc = remap("check", "threejs")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "limit   transmission" in proc.stdout and "screen-space" in proc.stdout
    assert proc.stdout.count("  pass    ") == len(check.TITLES) - 1  # every row but the glass (a limit)


# --- Textures: the tables' texel-by-texel path into glTF ------------------------------------------------

TEX_SCENE = ProbeScene().overridden(resolution=64, spp=64)


def test_three_js_lays_a_texture_on_the_sphere_as_mitsuba_does(three, mitsuba_adapter):
    tex = checker()
    white = {"base_color": 0.5, "metallic": 0.0, "roughness": 1.0, "specular": 0.0}
    mi = mitsuba_adapter.render_textured("diffuse", {"reflectance": (0.5,) * 3},
                                         {"reflectance": TextureMap(tex, "nearest")}, TEX_SCENE)
    th = three.render_textured("gltf_pbr", white, {"base_color": TextureMap(tex, "nearest")}, TEX_SCENE)
    same = relative_rmse(mi, th)
    assert same < 0.02, same
    for wrong in (tex[::-1], tex[:, ::-1], np.roll(tex, tex.shape[1] // 12, axis=1)):  # flipped, mirrored, turned
        off = three.render_textured("gltf_pbr", white, {"base_color": TextureMap(wrong, "nearest")}, TEX_SCENE)
        assert relative_rmse(mi, off) > 10 * same


def _srgb8(v: float) -> float:
    """A linear value as an 8-bit sRGB PNG holds it, decoded."""
    e = round((1.055 * v ** (1 / 2.4) - 0.055 if v > 0.0031308 else 12.92 * v) * 255) / 255
    return ((e + 0.055) / 1.055) ** 2.4 if e > 0.04045 else e / 12.92


def test_the_written_sphere_has_the_probes_texture_coordinates_and_tangents():
    from brdfremap.core.data.sphere import sphere_mesh

    m = sphere_mesh()
    pos, uv, tangent = m["POSITION"], m["TEXCOORD_0"], m["TANGENT"]
    front = np.argmin(np.linalg.norm(pos - [0, 0, 1], axis=1))  # facing a viewer on +z: u 0.75, v 0.5
    assert np.allclose(uv[front], [0.75, 0.5], atol=1e-6) and np.allclose(tangent[front], [1, 0, 0, 1], atol=1e-6)
    right = np.argmin(np.linalg.norm(pos - [1, 0, 0], axis=1))  # +x: u 0 (or 1, the seam), v 0.5
    assert uv[right][0] in (0.0, 1.0) and uv[right][1] == pytest.approx(0.5)
    assert np.all(uv[pos[:, 1] > 0.9999][:, 1] < 1e-6)  # the top pole at v = 0, an image's top row
    tri = m["indices"].reshape(-1, 3)[1000]  # counter-clockwise seen from outside: its normal outward
    a, b, c = pos[tri]
    assert np.dot(np.cross(b - a, c - a), a + b + c) > 0


def test_anisotropy_turns_the_same_way_on_a_textured_sphere(three):
    """A textured sphere's tangent frame is the plain sphere's (its v is turned over for glTF's images,
    which without tangents of its own would mirror an anisotropy's rotation)."""
    spec = three.models["gltf_pbr"]
    given = {"base_color": 0.9, "metallic": 1.0, "roughness": 0.4, "anisotropy": 0.7, "anisotropy_rotation": 0.125}
    q = _srgb8(0.9)
    plain = three.render("gltf_pbr", spec.complete({**given, "base_color": q}), TEX_SCENE)
    textured = three.render_textured("gltf_pbr", given, {"base_color": TextureMap(np.full((4, 4, 3), 0.9, np.float32))},
                                     TEX_SCENE)
    mirrored = three.render("gltf_pbr", spec.complete({**given, "base_color": q, "anisotropy_rotation": 0.875}),
                            TEX_SCENE)
    assert relative_rmse(plain, mirrored) > 0.05  # the rotation shows
    assert relative_rmse(plain, textured) < 0.01


@pytest.mark.parametrize("anisotropic, rotation", [(0.5, 0.0), (0.8, 0.0), (0.5, 0.125)])
def test_an_anisotropic_metal_renders_as_in_cycles_through_the_appearance(three, cycles_adapter, anisotropic,
                                                                          rotation):
    """Blender's anisotropic Principled metal, turned into glTF's KHR_materials_anisotropy by the
    appearance (the two α's ratio), renders in three.js as in Cycles: within 5 % (the isotropic one is
    2.1 % apart). The sphere's tangents make it so: three.js's own frame (from the texture coordinates'
    screen derivatives) rendered these 65-79 % off, twice the light."""
    scene = ProbeScene().overridden(resolution=64, spp=256)
    cp = cycles_adapter.models["principled"].complete({"base_color": 0.9, "metallic": 1.0, "roughness": 0.4,
                                                       "anisotropic": anisotropic,
                                                       "anisotropic_rotation": rotation})
    gltf = three.models["gltf_pbr"]
    tp = gltf.complete(gltf.from_appearance(cycles_adapter.models["principled"].appearance(cp), {}))
    assert tp["anisotropy"] > 0.3 and tp["anisotropy_rotation"] == pytest.approx(rotation)
    assert relative_rmse(cycles_adapter.render("principled", cp, scene), three.render("gltf_pbr", tp, scene)) < 0.05


def test_a_constant_texture_renders_as_its_8_bit_value(three):
    spec = three.models["gltf_pbr"]
    given = {"base_color": 0.6, "metallic": 1.0, "roughness": 0.45}
    maps = {"roughness": TextureMap(np.full((4, 4), 0.45, np.float32)),
            "base_color": TextureMap(np.full((4, 4, 3), 0.6, np.float32))}
    textured = three.render_textured("gltf_pbr", given, maps, TEX_SCENE)
    held = three.render("gltf_pbr", spec.complete({**given, "base_color": _srgb8(0.6), "roughness": 115 / 255}),
                        TEX_SCENE)
    assert relative_rmse(held, textured) < 1e-4  # the texture's 8 bits, and nothing else, differ from the factors
    rougher = three.render_textured("gltf_pbr", given, {**maps, "roughness": TextureMap(np.full((4, 4), 0.6,
                                                                                                 np.float32))}, TEX_SCENE)
    assert relative_rmse(held, rougher) > 0.05  # the texture, not the factor, is what rendered


def _textured_materials():
    h, w = 32, 64
    ramp = np.broadcast_to(np.linspace(0.1, 0.9, w, dtype=np.float32), (h, w)).copy()
    return [("plain gold", {"base_color": (1.0, 0.77, 0.34), "metallic": 1.0, "roughness": 0.3}, {}),
            ("worn", {"base_color": 0.5, "metallic": 1.0, "roughness": 0.5, "ior": 1.6},
             {"base_color": TextureMap(checker(seed=2, rows=4, cols=8, texel=8)), "roughness": TextureMap(ramp),
              "metallic": TextureMap(np.where(ramp > 0.5, 1.0, 0.0).astype(np.float32), "nearest")}),
            ("rough print", {"base_color": 0.5, "metallic": 0.0, "roughness": 0.6},
             {"base_color": TextureMap(checker(seed=3, rows=4, cols=8, texel=8), "nearest")})]


def test_a_textured_gltf_validates_and_renders_as_its_textured_check(three, tmp_path):
    spec = three.models["gltf_pbr"]
    mats = _textured_materials()
    doc = sphere_document([(n, p) for n, p, _ in mats], spec, [m for _, _, m in mats])
    path = tmp_path / "library.gltf"
    path.write_text(json.dumps(doc))
    issues = validate(path)
    assert issues["numErrors"] == issues["numWarnings"] == issues["numInfos"] == 0, issues["messages"]
    worn = doc["materials"][1]["pbrMetallicRoughness"]
    assert worn["baseColorFactor"] == [1.0, 1.0, 1.0, 1.0] and worn["roughnessFactor"] == worn["metallicFactor"] == 1.0
    assert len(doc["images"]) == 3 and "baseColorTexture" not in doc["materials"][0]["pbrMetallicRoughness"]
    assert "TEXCOORD_0" not in doc["meshes"][0]["primitives"][0]["attributes"]  # only where a texture is read
    assert doc["materials"][2]["pbrMetallicRoughness"]["baseColorTexture"]["index"] == 2
    samplers = [doc["samplers"][t["sampler"]]["magFilter"] for t in doc["textures"]]
    assert samplers == [9729, 9728, 9728]  # linear; nearest where either packed map is; nearest
    for i, (name, params, maps) in enumerate(mats):
        alone = material_document(json.loads(path.read_text()), i)
        assert len(alone.get("images", [])) == (2 if "roughness" in maps else len(maps)), name  # its own, numbered anew
        assert all(t["source"] < len(alone["images"]) and t["sampler"] < len(alone["samplers"])
                   for t in alone.get("textures", []))
        want = three.render_textured("gltf_pbr", params, maps, TEX_SCENE) if maps else \
            three.render("gltf_pbr", spec.complete(params), TEX_SCENE)
        assert np.array_equal(three.render_document(alone, TEX_SCENE), want), name


def test_blender_imports_a_textured_gltf_with_its_images(tmp_path, cycles_adapter):
    spec = ThreeJsAdapter.models["gltf_pbr"]
    mats = _textured_materials()
    path = tmp_path / "library.gltf"
    path.write_text(json.dumps(sphere_document([(n, p) for n, p, _ in mats], spec, [m for _, _, m in mats])))
    code = ("import bpy\n"
            "bpy.ops.wm.read_factory_settings(use_empty=True)\n"
            f"bpy.ops.import_scene.gltf(filepath={str(path)!r})\n"
            "m = bpy.data.materials['worn']\n"
            "p = next(n for n in m.node_tree.nodes if n.type == 'BSDF_PRINCIPLED')\n"
            "print('LINKED', sorted(s.name for s in p.inputs if s.is_linked))\n"
            "print('IMAGES', sorted((i.size[0], i.size[1]) for i in bpy.data.images if i.users))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    assert "LINKED ['Base Color', 'Metallic', 'Roughness']" in out.stdout, out.stdout[-2000:]
    assert "IMAGES [(64, 32), (64, 32), (64, 32)]" in out.stdout, out.stdout[-2000:]


TABLE = ROOT / "configs" / "tables" / "built" / "mitsuba-roughconductor-to-threejs-gltf.json"
GLTF_TABLE = ROOT / "configs" / "tables" / "built" / "threejs-gltf-to-cycles-principled.json"


def test_a_textured_mitsuba_metal_converts_to_gltf_texel_by_texel(tmp_path, mitsuba_adapter, three):
    """The demo scene's worn copper (its roughness and colour maps) through the shipped table: its maps
    in library.gltf as glTF textures, the file valid, and it renders as its textured check did."""
    from brdfremap.core.data.imageio import read_image
    from brdfremap.core.data.scene import EnvironmentLight

    out = tmp_path / "out"
    proc = remap("convert", ROOT / "examples" / "library" / "scene.xml", "--to", "threejs", "--only", "worn copper",
                 "--table", TABLE, "--out", out, *QUICK)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    path = out / "library.gltf"
    issues = validate(path)
    assert issues["numErrors"] == issues["numWarnings"] == issues["numInfos"] == 0, issues["messages"]
    doc = json.loads(path.read_text())
    pbr = doc["materials"][0]["pbrMetallicRoughness"]
    assert doc["materials"][0]["name"] == "worn copper" and len(doc["images"]) == 2
    assert {"baseColorTexture", "metallicRoughnessTexture"} <= set(pbr)
    row = json.loads((out / "convert.json").read_text())["materials"][0]
    folder = out / "materials" / row["slot"]
    record = json.loads((folder / "result.json").read_text())["textures"]
    assert record["table"] == "Mitsuba roughconductor (Beckmann) -> three.js glTF PBR"
    assert {m["param"] for m in record["maps"]} == {"base_color", "roughness"}  # a metal: metallic 1, held
    assert "KHR_materials_ior" not in json.dumps(doc)  # a full metal's IOR does nothing: not written
    studio = next(c for c in record["checks"] if c["condition"] == "environment")
    scene = ProbeScene(resolution=studio["resolution"], lights=[EnvironmentLight(type="environment", map="studio")])
    rendered = three.render_document(material_document(doc, 0), scene)
    assert np.array_equal(rendered, read_image(folder / "target-textured.exr"))  # the file is what was checked
    assert relative_rmse(read_image(folder / "source-textured.exr"), rendered) == pytest.approx(studio["error"], rel=1e-4)
    # And back: the written glTF, read as a source, goes into Cycles texel by texel through the other table.
    back = remap("convert", path, "--to", "cycles:principled", "--table", GLTF_TABLE, "--out", tmp_path / "back", *QUICK,
                 "--validate", "none")
    assert back.returncode == 0, back.stdout + back.stderr
    row = json.loads((tmp_path / "back" / "convert.json").read_text())["materials"][0]
    assert "texel by texel" in row["model_why"], row


def _png(values: np.ndarray) -> bytes:
    from brdfremap.core.data.textures import encode

    return encode(values, ".png", "linear", bits=8)


def test_a_gltfs_core_textures_are_read_from_files_data_uris_and_a_glb(tmp_path, monkeypatch):
    """Base colour, metallic and roughness driven by their core textures (of factor 1) are read as
    textures (the packed image's green and blue channels), wherever the image is: a file beside the
    glTF, a data URI, a .glb's binary chunk; embedded ones are written once, by content, to the cache."""
    import base64

    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    ramp = np.broadcast_to(np.linspace(0.0, 1.0, 16, dtype=np.float32), (8, 16))
    packed = np.stack([np.ones_like(ramp), ramp, 1.0 - ramp], axis=-1)
    (tmp_path / "orm.png").write_bytes(_png(packed))
    colour = "data:image/png;base64," + base64.b64encode(_png(np.full((8, 16, 3), 0.5, np.float32))).decode()
    doc = {"asset": {"version": "2.0"}, "images": [{"uri": colour}, {"uri": "orm.png"}, {"uri": "https://x/y.png"}],
           "samplers": [{"magFilter": 9728, "minFilter": 9728}],
           "textures": [{"source": 0}, {"source": 1, "sampler": 0}, {"source": 2}],
           "materials": [
               {"name": "packed", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0},
                                                           "metallicRoughnessTexture": {"index": 1}}},
               {"name": "scaled", "pbrMetallicRoughness": {"metallicFactor": 0.5,
                                                           "metallicRoughnessTexture": {"index": 1}}},
               {"name": "remote", "pbrMetallicRoughness": {"baseColorTexture": {"index": 2}}}]}
    path = tmp_path / "m.gltf"
    path.write_text(json.dumps(doc))
    packed_entry, scaled, remote = GltfReader().read(path)
    maps = packed_entry.material.textures
    assert set(maps) == {"base_color", "roughness", "metallic"}
    assert (maps["roughness"].channel, maps["metallic"].channel, maps["base_color"].channel) == (1, 2, None)
    assert maps["roughness"].filter == "nearest" and maps["base_color"].colorspace == "srgb"
    assert maps["roughness"].file == str((tmp_path / "orm.png").resolve())
    assert os.path.dirname(maps["base_color"].file) == str(tmp_path / "cache" / "brdfremap" / "gltf-images")
    from brdfremap.core.data.textures import read_values
    assert np.allclose(read_values(maps["roughness"], "scalar")[0], np.round(np.linspace(0, 1, 16) * 255) / 255)
    assert np.allclose(read_values(maps["metallic"], "scalar")[0], 1 - np.round(np.linspace(0, 1, 16) * 255) / 255)
    assert packed_entry.material.params["roughness"] == pytest.approx(0.5, abs=0.01)  # constants: the images' means
    assert packed_entry.material.params["metallic"] == pytest.approx(0.5, abs=0.01)
    assert set(scaled.material.textures) == {"roughness"}  # its metallic is 0.5 x the texture: not texel by texel,
    assert scaled.material.params["metallic"] == pytest.approx(0.25, abs=0.01)  # but 0.5 x the image's mean
    assert any("scaled by a factor of 0.5" in n for n in scaled.notes)
    assert remote.material.textures == {} and any("https://x/y.png" in n for n in remote.notes)  # never fetched
    (tmp_path / "sub").mkdir()  # an image outside the glTF's folder is not read
    (tmp_path / "sub" / "m.gltf").write_text(json.dumps(doc).replace('"orm.png"', '"../orm.png"'))
    outside = GltfReader().read(tmp_path / "sub" / "m.gltf")[0]
    assert set(outside.material.textures) == {"base_color"}
    assert any("outside the glTF's folder" in n for n in outside.notes)
    _glb(doc, tmp_path / "m.glb", [base64.b64decode(colour.partition(",")[2]), (tmp_path / "orm.png").read_bytes()])
    glb = GltfReader().read(tmp_path / "m.glb")[0].material.textures  # its images in the binary chunk
    assert {k: t.sha256 for k, t in glb.items()} == {k: t.sha256 for k, t in maps.items()}


def _glb(doc: dict, path, images: list[bytes]) -> None:
    """``doc`` as a .glb whose images are buffer views of its binary chunk (glTF 2.0's GLB layout)."""
    import struct

    blob, views = b"", []
    for data in images:
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data)})
        blob += data + b"\0" * (-len(data) % 4)
    doc = {**doc, "bufferViews": views, "buffers": [{"byteLength": len(blob)}],
           "images": [{"bufferView": i, "mimeType": "image/png"} for i in range(len(images))]}
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    body = struct.pack("<I4s", len(text), b"JSON") + text + struct.pack("<I4s", len(blob), b"BIN\0") + blob
    path.write_bytes(struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body)


EXPORT = ROOT / "tests" / "data" / "gltf" / "export_worn_copper.py"
"""Blender's own glTF export of a textured Principled BSDF (a script run with bpy)."""


def test_a_glb_from_blenders_exporter_converts_to_cycles_texel_by_texel(tmp_path, cycles_adapter, three,
                                                                        monkeypatch):
    """A textured Principled BSDF exported by Blender's own glTF exporter (its roughness packed in the
    metallicRoughness image's green, the images inside the .glb) read back and remapped to Cycles
    through the shipped table: its maps are the table's, and its textured check is rendered."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    glb = tmp_path / "worn-copper.glb"
    out = subprocess.run([sys.executable, str(EXPORT), str(ROOT / "examples" / "library" / "textures"), str(glb)],
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0 and glb.is_file(), out.stderr[-2000:]
    (entry,) = GltfReader().read(glb)
    assert set(entry.material.textures) == {"base_color", "metallic", "roughness"}
    proc = remap("convert", glb, "--to", "cycles:principled", "--table", GLTF_TABLE, "--out", tmp_path / "out",
                 *QUICK, env={"XDG_CACHE_HOME": str(tmp_path / "cache")})
    assert proc.returncode == 0, proc.stdout + proc.stderr
    row = json.loads((tmp_path / "out" / "convert.json").read_text())["materials"][0]
    assert row["status"] not in ("failed", "unsupported"), row
    record = json.loads((tmp_path / "out" / "materials" / row["slot"] / "result.json").read_text())["textures"]
    assert record["table"] == "three.js glTF PBR -> Cycles Principled" and (record["width"], record["height"]) == (256, 256)
    assert {"base_color", "metallic", "roughness"} <= {m["param"] for m in record["maps"]}
    assert {c["condition"] for c in record["checks"]} == {"scene", "environment"}
    assert all(c["error"] < 0.15 for c in record["checks"]), record["checks"]
    assert (tmp_path / "out" / "library.blend").is_file()
    # Without a table: a uniform material fitted to the .glb's material as three.js renders it from the file, its
    # start the textures' constants (the images' means, a copper colour, not the factors' white), and its line
    # says so.
    plain = remap("convert", glb, "--to", "cycles:principled", "--out", tmp_path / "flat", "--resolution", "48",
                  "--spp", "16", "--validate", "none", env={"XDG_CACHE_HOME": str(tmp_path / "cache")})
    assert plain.returncode == 0, plain.stdout + plain.stderr
    assert "worn copper (textured: a uniform material fitted to its rendering) -> principled" in \
        plain.stdout + plain.stderr
    colour = entry.material.params["base_color"]
    assert colour[0] > colour[1] > colour[2] and colour[0] < 0.95, colour


def test_a_malformed_or_hostile_gltf_is_said_per_material_and_never_read_past_its_images(tmp_path, monkeypatch):
    """Each bad texture is a note naming its field, a malformed material an entry that cannot convert
    (the file's others still do); a device, a text file or a second buffer without a URI is not read
    as an image."""
    import base64

    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    (tmp_path / "notes.txt").write_text("not an image")
    png = _png(np.full((2, 2, 3), 0.5, np.float32))
    doc = {"asset": {"version": "2.0"},
           "buffers": [{"byteLength": len(png), "uri": "data:application/octet-stream;base64," +
                        base64.b64encode(png).decode()}, {"byteLength": 4}, {"uri": "/dev/zero", "byteLength": 8},
                       {"uri": "pipe.bin", "byteLength": 8}],
           "bufferViews": [{"buffer": 1, "byteLength": 4}, {"buffer": 0, "byteOffset": 64, "byteLength": 4096},
                           {"buffer": 2, "byteLength": 8}, {"buffer": 0, "byteLength": len(png)},
                           {"buffer": 3, "byteLength": 8}],
           "images": [{"uri": "notes.txt"}, {"bufferView": 0}, {"bufferView": 1}, {"bufferView": 2},
                      {"uri": "file:///etc/passwd"}, {"bufferView": 3}, {"bufferView": 4}],
           "textures": [{"source": i} for i in range(7)],
           "materials": [{"name": f"m{i}", "pbrMetallicRoughness": {"baseColorTexture": {"index": i}}}
                         for i in range(7)] + [{"name": "bad", "pbrMetallicRoughness": {"baseColorFactor": [0.5]}}]}
    os.mkfifo(tmp_path / "pipe.bin")  # a pipe beside the file: never opened (it would block)
    path = tmp_path / "hostile.gltf"
    path.write_text(json.dumps(doc))
    entries = GltfReader().read(path)
    said = {e.name: " ".join(e.notes) + e.problem for e in entries}
    assert "images[0] (" in said["m0"] and "is neither a PNG nor a JPEG" in said["m0"]
    assert "buffers[1] has no uri" in said["m1"]
    assert "bufferViews[1] runs past the end of buffers[0]" in said["m2"]
    assert "buffers[2].uri: /dev/zero is outside the glTF's folder" in said["m3"]
    assert "nothing is fetched" in said["m4"]
    assert "pipe.bin is not a file" in said["m6"]
    assert [e.name for e in entries if e.material and e.material.textures] == ["m5"]  # the one good image
    bad = entries[-1]
    assert bad.material is None and "materials[7] is malformed glTF" in bad.problem

"""UsdPreviewSurface rendered by three.js's own USDLoader in Debian's headless Chromium (the layer the
tool writes is the layer three.js parses), calibrated against glTF's material in the same three.js;
`library.usda` imported by Blender's USD importer."""

import json
import subprocess
import sys

import numpy as np
import pytest

pytest.importorskip("pxr")

from brdfremap.adapters.threejs.adapter import ThreeJsAdapter  # noqa: E402
from brdfremap.core.data.metrics import relative_rmse  # noqa: E402
from brdfremap.core.data.scene import EnvironmentLight, ProbeScene  # noqa: E402
from conftest import need_adapter  # noqa: E402

SAME = [({"diffuse_color": (0.8,) * 3, "metallic": 0.0, "roughness": 1.0, "ior": 1.5},
         {"base_color": (0.8,) * 3, "metallic": 0.0, "roughness": 1.0, "ior": 1.5}),
        ({"diffuse_color": (0.95, 0.64, 0.54), "metallic": 1.0, "roughness": 0.2},
         {"base_color": (0.95, 0.64, 0.54), "metallic": 1.0, "roughness": 0.2}),
        ({"diffuse_color": (0.6, 0.1, 0.1), "roughness": 0.3, "ior": 1.45, "clearcoat": 1.0, "clearcoat_roughness": 0.05},
         {"base_color": (0.6, 0.1, 0.1), "metallic": 0.0, "roughness": 0.3, "ior": 1.45, "clearcoat": 1.0,
          "clearcoat_roughness": 0.05})]


@pytest.fixture(scope="module")
def three():
    need_adapter(ThreeJsAdapter)
    adapter = ThreeJsAdapter()
    yield adapter
    adapter.close()


@pytest.mark.parametrize("scene", [ProbeScene(resolution=48),
                                   ProbeScene(lights=[EnvironmentLight(type="environment", map="studio")], resolution=32)],
                         ids=["probe", "studio"])
def test_usd_preview_surface_renders_as_the_same_gltf_material_in_three_js(three, scene):
    """The calibration: three.js's USDLoader and GLTFLoader make the same MeshPhysicalMaterial of the
    same metallic-roughness inputs, so UsdPreviewSurface inherits the glTF path's calibration against
    Mitsuba and Cycles (tests/adapters/test_threejs.py)."""
    usd, gltf = three.models["usd_preview_surface"], three.models["gltf_pbr"]
    for u, g in SAME:
        a, b = three.render(usd, usd.complete(u), scene), three.render(gltf, gltf.complete(g), scene)
        assert a.mean() > 1e-3 and relative_rmse(a, b) < 1e-6, (u, relative_rmse(a, b))


def test_unwritten_specular_colour_leaves_a_dielectric_s_reflection_alone(three):
    """specularColor is written only in the specular workflow: three.js reads it as a tint of every
    dielectric's reflectance, and the specification's default (black) would remove it."""
    usd = three.models["usd_preview_surface"]
    p = usd.complete({"diffuse_color": (0.0,) * 3, "roughness": 0.3})
    assert three.render(usd, p, ProbeScene(resolution=32)).mean() > 1e-3


def test_the_written_material_usda_renders_as_the_fit_did(three, tmp_path):
    usd = three.models["usd_preview_surface"]
    p = usd.complete({"diffuse_color": (0.9, 0.5, 0.2), "metallic": 1.0, "roughness": 0.3})
    (path,) = three.write_native(usd, p, tmp_path)
    scene = ProbeScene(resolution=32)
    assert path.name == "material.usda"
    assert np.array_equal(three.render_layer(path.read_text(), scene), three.render(usd, p, scene))


BLENDER_IMPORT = """
import bpy, json, sys
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.wm.usd_import(filepath=sys.argv[-1])
out = {}
for m in bpy.data.materials:
    if m.users:
        p = next(n for n in m.node_tree.nodes if n.type == "BSDF_PRINCIPLED")
        out[m.name] = {k: (list(p.inputs[k].default_value)[:3] if k == "Base Color" else p.inputs[k].default_value)
                       for k in ("Base Color", "Metallic", "Roughness", "Coat Weight")}
print("IMPORTED", json.dumps(out))
"""


def test_blender_s_usd_importer_imports_library_usda(tmp_path, cycles_adapter):
    from brdfremap.adapters.cycles.models import PRINCIPLED
    from brdfremap.adapters.materialx.correspondence import DIRECT, open_pbr_inputs
    from brdfremap.adapters.usd.writer import MtlxSurface, UsdWriter
    from brdfremap.core.library.formats import Converted

    items = [Converted("red paint", "principled", {"base_color": (0.6, 0.1, 0.1), "roughness": 0.4,
                                                   "coat_weight": 0.3}, tmp_path),
             Converted("gold", "principled", {"base_color": (1.0, 0.77, 0.34), "metallic": 1.0, "roughness": 0.2},
                       tmp_path)]
    (path,) = UsdWriter("cycles", lambda: {"principled": PRINCIPLED},
                        mtlx={"principled": lambda: MtlxSurface(open_pbr_inputs, DIRECT)}).write(tmp_path, items)
    out = subprocess.run([sys.executable, "-c", BLENDER_IMPORT, str(path)], capture_output=True, text=True,
                         timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    got = json.loads(out.stdout.split("IMPORTED ", 1)[1].splitlines()[0])
    assert sorted(got) == ["gold", "red_paint"]  # Blender reads the UsdPreviewSurface (not OpenPBR in USD)
    assert got["gold"]["Metallic"] == 1.0 and got["gold"]["Roughness"] == pytest.approx(0.2, abs=1e-6)
    assert got["red_paint"]["Base Color"] == pytest.approx([0.6, 0.1, 0.1], abs=1e-6)
    assert got["red_paint"]["Coat Weight"] == pytest.approx(0.3, abs=1e-6)

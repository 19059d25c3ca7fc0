"""The Blender extension, as a user installs and runs it: its zip built by Blender's own extension
tool, installed into a Blender (`bpy`) process of its own with a fresh user folder, and each operator
run headless on a real `.blend` and on corpus files, the conversions made by this checkout's tool
(draft quality: a first look, its verdicts rough)."""

import json
import os
import subprocess
import sys
import tomllib
import zipfile

import pytest
from helpers import ROOT

sys.path.insert(0, str(ROOT / "extension"))
import build  # noqa: E402  the extension's build script

DRIVER = ROOT / "tests" / "tools" / "extension_driver.py"


@pytest.fixture(scope="module")
def extension_zip(tmp_path_factory):
    return build.build(tmp_path_factory.mktemp("dist"))


def test_the_zip_builds_validates_and_its_version_is_the_tool_s(extension_zip, tmp_path):
    names = zipfile.ZipFile(extension_zip).namelist()
    assert {"blender_manifest.toml", "__init__.py", "operators.py", "panel.py"} <= set(names), names
    manifest = tomllib.loads((build.SOURCE / "blender_manifest.toml").read_text())
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert manifest["version"] == project["project"]["version"]
    assert extension_zip.name == f"brdf_remap-{manifest['version']}.zip"
    bad = tmp_path / "bad"
    bad.mkdir()
    for f in build.SOURCE.iterdir():
        if f.is_file():
            (bad / f.name).write_bytes(f.read_bytes())
    text = (bad / "blender_manifest.toml").read_text()
    (bad / "blender_manifest.toml").write_text(text.replace('type = "add-on"', 'type = "add-on"\ncolour = "red"'))
    with pytest.raises(SystemExit, match="'colour' is not a documented manifest key"):
        build.build(tmp_path / "out", bad)
    (bad / "blender_manifest.toml").write_text(text.replace("between renderers so that they look the same",
                                                            "between renderers."))
    with pytest.raises(SystemExit, match="tagline"):  # Blender's own tool checks the values
        build.build(tmp_path / "out", bad)


def _images(folder):
    """A gold sphere's images of the exported probe and back shots, rendered by Mitsuba from the exported XML."""
    from brdfremap.core.cli import main

    assert main(["scene", "export", str(folder), "--format", "mitsuba", "--resolution", "32", "--spp", "64"]) == 0
    (folder / "gold.xml").write_text('<scene version="3.0.0"><bsdf type="roughconductor" id="material"><string '
                                     'name="material" value="Au"/><float name="alpha" value="0.2"/></bsdf></scene>')
    gold = folder / "renders" / "gold"
    done = subprocess.run([sys.executable, str(ROOT / "examples" / "outside" / "render_mitsuba.py"),
                           str(folder / "mitsuba"), str(gold), "--material", str(folder / "gold.xml"), "--shot", "probe",
                           "--shot", "back"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-2000:]
    return gold


def test_every_operator_works_headless_on_real_files(extension_zip, tmp_path, corpus, cycles_adapter):
    env = {**os.environ, "BLENDER_USER_RESOURCES": str(tmp_path / "blender-user")}
    mitsuba = corpus / "mitsuba-data" / "docs" / "scenes" / "bsdf_roughconductor_copper.xml"
    mtlx = corpus / "materialx" / "StandardSurface" / "standard_surface_copper.mtlx"
    images = _images(tmp_path / "export")  # a folder of images rendered elsewhere: one of its images is picked
    run = subprocess.run([sys.executable, str(DRIVER), str(extension_zip), str(tmp_path), sys.executable,
                          str(mitsuba), str(mtlx), str(images / "probe.seed0.exr")], capture_output=True, text=True,
                         timeout=1800, env=env)
    assert "RESULT " in run.stdout, (run.stdout + run.stderr)[-4000:]
    log = json.loads(run.stdout.split("RESULT ", 1)[1].splitlines()[0])
    print(json.dumps({k: v.get("panel") for k, v in log.items() if isinstance(v, dict) and "panel" in v}, indent=1))
    assert {"remap", "export", "import_matched", "accept", "discard", "cancel", "report"} <= set(log["operators"])

    copy = log["remap copy"]
    assert copy["result"] == ["FINISHED"] and copy["panel"][1].startswith("copper: ")
    assert log["before accept"] == {"copper": {"users": 1, "bsdf": "BSDF_GLOSSY"},
                                    "red paint": {"users": 1, "bsdf": "BSDF_PRINCIPLED"},
                                    "empty": {"users": 1, "bsdf": None}}  # nothing changed yet
    after = log["accept copy"]["materials"]
    assert after["copper"] == {"users": 1, "bsdf": "BSDF_GLOSSY"}  # a copy: the original stays
    assert after["copper (metallic)"]["bsdf"] == "BSDF_METALLIC"

    unsupported = log["remap unsupported"]
    assert unsupported["result"] == ["FINISHED"] and "accept" not in unsupported["panel"][0]  # nothing to accept
    assert unsupported["panel"][1].startswith("empty: unsupported, –"), unsupported["panel"]  # with its reason

    placed = log["accept in place"]["materials"]
    assert placed["red paint"] == {"users": 1, "bsdf": "BSDF_METALLIC"}  # the sphere uses the remap
    assert placed["red paint (before remap)"]["users"] == 0

    assert {"scene.brdf-remap/threejs/library.gltf", "scene.brdf-remap/mitsuba/library.xml",
            "scene.brdf-remap/materialx-open_pbr_surface/library.mtlx"} <= set(log["exported"]), log["exported"]  # by the .blend
    for target in ("GLTF", "MITSUBA", "MATERIALX"):
        assert "1 material(s)" in log[f"export {target}"]["panel"][0], log[f"export {target}"]

    for name in ("mitsuba", "images", "mtlx"):
        before, after = log[f"import {name}"]["materials"], log[f"accept {name}"]["materials"]
        added = set(after) - set(before)
        assert added, (name, log[f"import {name}"]["panel"])
        assert all(after[m]["bsdf"] in ("BSDF_PRINCIPLED", "BSDF_METALLIC", "BSDF_GLOSSY", "BSDF_DIFFUSE")
                   for m in added), after

    drawn = log["panel"]  # what the material panel lays out after the MaterialX import
    assert {"prop: brdf_remap_scope", "menu: Remap as a copy", "menu: Remap in place", "menu: Export matched",
            "operator: brdf_remap.import_matched", "operator: brdf_remap.report"} <= set(drawn), drawn
    assert "label: Copper: " + log["accept mtlx"]["panel"][1].split(": ", 1)[1] in drawn
    assert drawn.count("image") == 3  # its source, remap and error side by side
    assert [[p.rsplit("/", 1)[1] for p in r] for r in log["images"]] == [["source.png", "target.png", "error.png"]]

    missing = log["no tool"]
    assert missing["result"] == ["CANCELLED"]
    assert "no-such-python" in missing["panel"][0] and "preferences" in missing["panel"][0]  # above the last results
    assert "\n" not in missing["error"].strip() and "Traceback" not in missing["error"]
    assert log["cancel"]["exit"] is not None and not log["cancel"]["summary"]  # stopped, nothing claimed
    assert not {"remap", "export"} & set(log["after disable"])

"""`remap convert` end to end: real files in, real renders, native libraries out that the target
renderer loads, and the report opened in a real headless Chromium."""

import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from brdfremap.core.cli import main
from helpers import ROOT, one_line_error, open_in_chromium, remap
from reports import read_result

DATA = ROOT / "tests" / "data"
FAST = ["--resolution", "32", "--spp", "8", "--quiet"]
FORMATS_ONLY = [*FAST, "--validate", "none"]
"""For tests of what is read and written: the held-out lights are the mixed scene's test's."""


def _summary(out: Path) -> dict:
    from brdfremap.core.library.records import ConvertSummary

    doc = json.loads((out / "convert.json").read_text())
    ConvertSummary.model_validate(doc)  # what `remap schema convert` publishes
    return doc


def test_a_mitsuba_scene_of_mixed_bsdfs_converts_to_one_blend_and_a_report(tmp_path, mitsuba_adapter,
                                                                            cycles_adapter, capsys):
    from brdfremap.adapters.cycles.library import BlendReader

    out = tmp_path / "lib"
    code = main(["convert", str(DATA / "scenes" / "mixed.xml"), "--to", "cycles", "--out", str(out), *FAST])
    s = _summary(out)
    assert code == 0 and s["converted"] == 11 and s["failed"] == 0  # glass, a blend and mirrors included
    status = {m["name"]: (m["status"], m["reason"]) for m in s["materials"]}
    assert not {n for n, (st, _) in status.items() if st in ("unsupported", "failed")}
    # A mirror shows the point light as a point at most: fitted under the studio environment.
    silver = next(m for m in s["materials"] if m["name"] == "smooth silver")
    assert "perfectly smooth" in read_result(out / "materials" / silver["slot"] / "result.json")["fit_scene"]["why"]
    assert {m["name"]: m["model"] for m in s["materials"]}["gold"] == "metallic"  # a metal: the Metallic BSDF
    # The .blend holds every converted material under its source's name.
    converted = {m["name"] for m in s["materials"] if m["slot"]}
    in_blend = {e.name: e for e in BlendReader().read(out / "library.blend")}
    assert set(in_blend) == converted
    gold = next(m for m in s["materials"] if m["name"] == "gold")
    fitted = read_result(out / "materials" / gold["slot"] / "result.json")["params"]
    assert in_blend["gold"].material.params["roughness"] == pytest.approx(fitted["roughness"], rel=1e-5)
    for m in s["materials"]:
        if m["slot"]:
            read_result(out / "materials" / m["slot"] / "result.json")
    page = open_in_chromium(out / "index.html")
    assert page["errors"] == [] and page["broken"] == [] and page["images"] == 3 * 11
    assert set(page["rows"]) == set(status)
    assert f"report      {out}/index.html" in capsys.readouterr().out


BLEND_SCRIPT = """
import sys, bpy
bpy.ops.wm.read_factory_settings(use_empty=True)
for i in range(10):
    m = bpy.data.materials.new(f"principled {i:02d}")
    m.use_nodes = True
    b = m.node_tree.nodes["Principled BSDF"]
    b.inputs["Base Color"].default_value = (0.1 + 0.08 * i, 0.5, 0.9 - 0.08 * i, 1.0)
    b.inputs["Metallic"].default_value = 1.0 if i % 3 == 0 else 0.0
    b.inputs["Roughness"].default_value = 0.2 + 0.05 * i
    m.use_fake_user = True
bpy.ops.wm.save_as_mainfile(filepath=sys.argv[-1])
"""


def test_a_blend_of_ten_principled_materials_converts_to_mitsuba_xml_that_mitsuba_loads(tmp_path, mitsuba_adapter,
                                                                                       cycles_adapter):
    blend = tmp_path / "made.blend"
    made = subprocess.run([sys.executable, "-c", BLEND_SCRIPT, str(blend)], capture_output=True, text=True)
    assert made.returncode == 0 and blend.exists(), made.stderr[-2000:]
    out = tmp_path / "lib"
    assert main(["convert", str(blend), "--to", "mitsuba", "--out", str(out), *FORMATS_ONLY]) == 0
    s = _summary(out)
    assert s["converted"] == 10
    models = {m["name"]: m["model"] for m in s["materials"]}
    assert models["principled 00"] == "roughconductor" and models["principled 01"] == "roughplastic"
    mi = mitsuba_adapter.mi
    (tmp_path / "use.xml").write_text(
        "<scene version='3.0.0'><include filename='lib/library.xml'/>"
        + "".join(f"<shape type='sphere'><ref id='principled {i:02d}'/></shape>" for i in range(10)) + "</scene>")
    scene = mi.load_file(str(tmp_path / "use.xml"))
    assert sorted(sh.bsdf().id() for sh in scene.shapes()) == [f"principled {i:02d}" for i in range(10)]
    assert open_in_chromium(out / "index.html")["errors"] == []


ONE_PER_SHADER = ["--only", "gold", "--only", "copper", "--only", "green_plastic", "--only", "clay"]


@pytest.mark.parametrize("to, models", [("mitsuba", {"roughconductor", "roughplastic"}),
                                        ("mitsuba:roughplastic", {"roughplastic"})])
def test_materialx_of_each_shader_type_converts_to_mitsuba(tmp_path, mitsuba_adapter, cycles_adapter, to, models):
    out = tmp_path / "lib"
    assert main(["convert", str(DATA / "materialx"), "--to", to, "--out", str(out), *ONE_PER_SHADER,
                 *FORMATS_ONLY]) == 0
    s = _summary(out)
    # The adapter's first choices, or Mitsuba's principled BSDF where a first choice came back a mismatch
    # or unreliable and the principled BSDF was kept over it (said on the material's line).
    first = {m["tried"][0]["model"] if m["tried"] else m["model"] for m in s["materials"]}
    assert s["converted"] == 4 and first == models
    assert all(m["model"] in models or "kept over" in m["model_why"] for m in s["materials"])
    assert {Path(m["file"]).name for m in s["materials"]} == {"open_pbr.mtlx", "standard_surface.mtlx",
                                                            "gltf_pbr.mtlx", "usd_preview.mtlx"}
    mitsuba_adapter.mi.load_file(str(out / "library.xml"))


def test_a_library_converted_to_principled_is_also_valid_materialx(tmp_path, cycles_adapter):
    import MaterialX as mx
    from brdfremap.adapters.materialx.reader import standard_libraries

    out = tmp_path / "lib"
    assert main(["convert", str(DATA / "materialx"), "--to", "cycles:principled", "--out", str(out), *FORMATS_ONLY,
                 "--only", "red_plastic", "--only", "chrome"]) == 0
    doc = mx.createDocument()
    mx.readFromXmlFile(doc, str(out / "library.mtlx"))
    assert sorted(m.getName() for m in doc.getMaterialNodes()) == ["chrome", "red_plastic"]
    doc.importLibrary(standard_libraries())
    assert doc.validate()[0]


def _table(out: Path) -> list:
    return [{k: v for k, v in m.items() if k not in ("seconds", "resumed")} for m in _summary(out)["materials"]]


def test_killed_and_rerun_every_material_once_and_dask_gives_the_same(tmp_path, mitsuba_adapter):
    """kill -9 halfway and rerun: the stored materials are reused, the others run once; a Dask
    LocalCluster of two worker processes gives the same results."""
    from distributed import LocalCluster

    src = ROOT / "examples" / "library" / "scene.xml"
    out = tmp_path / "lib"
    cmd = [sys.executable, "-m", "brdfremap.core.cli", "convert", str(src), "--to", "mitsuba", "--out", str(out),
           "--resolution", "64"]
    proc = subprocess.Popen([*cmd, "--quiet"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 120
    while len(list((out / "materials").glob("*/result.json")) if (out / "materials").exists() else []) < 3:
        assert proc.poll() is None and time.time() < deadline, proc.communicate()
        time.sleep(0.02)
    proc.send_signal(signal.SIGKILL)
    proc.communicate()
    stored = len(list((out / "materials").glob("*/result.json")))
    rerun = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert rerun.returncode == 0, rerun.stderr
    lines = [line for line in rerun.stderr.splitlines() if line.startswith("[")]
    assert sum("[resumed]" in line for line in lines) == stored and len(lines) == 10
    assert not [p for p in (out / "materials").rglob(".staging-*")]
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        assert main(["convert", str(src), "--to", "mitsuba", "--out", str(tmp_path / "dask"), "--resolution", "64",
                     "--quiet", "--scheduler", cluster.scheduler_address]) == 0
    assert _table(tmp_path / "dask") == _table(out)


@pytest.mark.parametrize("args, words", [
    (["--to", "arnold"], "--to: unknown adapter 'arnold'"),
    (["--to", "cycles:glass"], "--to: adapter 'cycles' has no model 'glass'"),
    (["--to", "mitsuba", "--only", "nonesuch"], "--only: no material named 'nonesuch'"),
])
def test_bad_input_is_exit_2_and_one_line(tmp_path, args, words):
    proc = remap("convert", ROOT / "examples" / "library" / "scene.xml", "--out", tmp_path / "o", *args)
    one_line_error(proc, words)
    assert not (tmp_path / "o").exists()


def test_a_file_that_cannot_be_read_is_a_failure_and_the_others_convert(tmp_path):
    """A malformed file among good ones: listed as failed with its file, line and reason (exit 1),
    the others converted, as for a failed material."""
    (tmp_path / "broken.xml").write_text("<scene version='3.0.0'><bsdf></scene>")
    (tmp_path / "good.xml").write_text("<scene version='3.0.0'><bsdf type='diffuse' id='grey'/></scene>")
    proc = remap("convert", tmp_path / "broken.xml", tmp_path / "good.xml", "--to", "mitsuba", "--out",
                 tmp_path / "o", *FORMATS_ONLY)
    assert proc.returncode == 1 and "Traceback" not in proc.stderr, proc.stderr
    rows = {m["name"]: m for m in _summary(tmp_path / "o")["materials"]}
    assert rows["broken"]["status"] == "failed" and "broken.xml: line 1" in rows["broken"]["reason"] and \
        "malformed XML" in rows["broken"]["reason"] and "\n" not in rows["broken"]["reason"]
    assert rows["grey"]["status"] == "ok"
    assert "failed: broken" in proc.stdout


def test_one_material_in_two_files_is_fitted_once_and_kept_under_each_name(tmp_path, mitsuba_adapter):
    """A library's shared material (the corpus's ground plane is in 35 files): one job, its result in
    each material's folder under that material's own file and name; a rerun resumes both."""
    for name in ("a", "b"):
        (tmp_path / f"{name}.xml").write_text("<scene version='3.0.0'><bsdf type='roughplastic' id='grey'>"
                                              "<rgb name='diffuse_reflectance' value='0.4'/></bsdf></scene>")
    out = tmp_path / "lib"
    args = ["convert", str(tmp_path / "a.xml"), str(tmp_path / "b.xml"), "--to", "mitsuba", "--out", str(out), *FAST]
    assert main(args) == 0
    rows = {m["name"]: m for m in _summary(out)["materials"]}
    reports = {n: read_result(out / "materials" / m["slot"] / "result.json") for n, m in rows.items()}
    assert set(reports) == {"a/grey", "b/grey"} and reports["a/grey"]["key"] == reports["b/grey"]["key"]
    assert [reports[n]["source"]["file"].split(":")[0] for n in ("a/grey", "b/grey")] == [
        str(tmp_path / "a.xml"), str(tmp_path / "b.xml")]
    assert reports["a/grey"]["seconds"] == reports["b/grey"]["seconds"]  # one fit, kept twice
    assert main(args) == 0 and all(m["resumed"] for m in _summary(out)["materials"])


def test_a_mismatch_is_fitted_again_to_the_targets_other_model_and_the_better_kept(tmp_path, mitsuba_adapter,
                                                                                    cycles_adapter):
    """Issue 43: MaterialX's glTF default (a white metal read as a reflectance) goes to Mitsuba's rough
    conductor first, a mismatch (about 42 %: a complex IOR's Fresnel is not Schlick's); Mitsuba's
    principled BSDF, tried next, follows it closer and is kept, the choice said on its line."""
    mtlx = ROOT.parent / "shared" / "corpus" / "materialx" / "GltfPbr" / "gltf_pbr_default.mtlx"
    if not mtlx.exists():
        pytest.skip(f"the public corpus is not beside the checkout ({mtlx})")
    out = tmp_path / "out"
    assert main(["convert", str(mtlx), "--to", "mitsuba", "--out", str(out), "--quiet", "--resolution", "32",
                 "--spp", "8"]) == 0
    (row,) = json.loads((out / "convert.json").read_text())["materials"]
    tried = {t["model"]: t for t in row["tried"]}
    assert set(tried) == {"roughconductor", "principled"}, row
    kept = next(t for t in row["tried"] if t["kept"])
    assert kept["relative_rmse"] == min(t["relative_rmse"] for t in row["tried"]) and row["model"] == kept["model"]
    assert row["slot"] == kept["slot"] and (out / "materials" / kept["slot"] / "result.json").exists()
    assert ("kept over" if kept["model"] == "principled" else "none closer") in row["model_why"]
    assert f'id="{row["name"]}"' in (out / "library.xml").read_text() or row["name"] in (out / "library.xml").read_text()

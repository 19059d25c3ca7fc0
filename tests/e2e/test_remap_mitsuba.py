"""`remap` end to end with real Mitsuba renders."""

import json

import numpy as np
import pytest

from brdfremap.core.cli import main
from reports import read_result
from brdfremap.core.data.imageio import read_image


def _run(tmp_path, root, material, *args):
    out = tmp_path / "out"
    code = main(["--source", str(root / "configs/materials" / material), "--out", str(out), "--quiet", *args])
    assert code == 0
    return out, read_result(out / "result.json")


def test_gold_beckmann_to_ggx_writes_the_contract(tmp_path, root, mitsuba_adapter):
    out, r = _run(tmp_path, root, "gold.yaml", "--adapter", "mitsuba", "--model", "roughconductor",
                  "--fix", "distribution=ggx")
    for name in ("source.exr", "target.exr", "source.png", "target.png", "error.png", "material.xml"):
        assert (out / name).stat().st_size > 0
    assert r["params"]["distribution"] == "ggx" and r["params"]["material"] == "Au"
    assert "eta" not in r["params"]  # inactive with a preset
    assert isinstance(r["params"]["alpha"], float) and 0.05 < r["params"]["alpha"] < 0.15
    m = r["metrics"]
    # Beckmann -> GGX cannot match exactly (heavier GGX tails): a floor near 20 %.
    assert 0.10 < m["relative_rmse"] < 0.30 and m["perceptual"] > 0
    assert isinstance(r["renders"], int) and 3 <= r["renders"] <= 60
    assert r["seconds"] > 0 and r["scheme"] == "auto" and r["scheme_used"] == "two"
    assert r["reliable"] is False and "model mismatch" in r["reason"]
    src, tgt = read_image(out / "source.exr"), read_image(out / "target.exr")
    assert src.shape == tgt.shape == (256, 128, 3)  # the fit scene's two views: the probe, lit from behind below
    assert np.isclose(np.linalg.norm(tgt - src) / np.linalg.norm(src), m["relative_rmse"], rtol=1e-4)
    xml = (out / "material.xml").read_text()
    assert '<string name="distribution" value="ggx"/>' in xml and f'{r["params"]["alpha"]:.6g}' in xml


def test_identity_ggx_recovers_alpha_within_one_percent(tmp_path, root, mitsuba_adapter):
    _, r = _run(tmp_path, root, "aluminium-ggx.yaml", "--adapter", "mitsuba", "--model", "roughconductor",
                "--start", "defaults", "--validate", "none", "--fit-same-model")  # the fit's renders alone
    assert r["start"] == {"informed": False, "params": {}, "rule": ""}
    assert abs(r["params"]["alpha"] / 0.3 - 1) < 0.01
    assert r["metrics"]["relative_rmse"] <= r["metrics"]["noise_floor"]
    assert r["stages"][0]["start_error"] > 10 * r["metrics"]["noise_floor"]  # it did not start at the answer
    assert r["reliable"] is True
    # From the informed start (the same model: the source's own α) it only has to confirm it.
    _, informed = _run(tmp_path / "informed", root, "aluminium-ggx.yaml", "--adapter", "mitsuba",
                       "--model", "roughconductor", "--validate", "none", "--fit-same-model")
    assert informed["start"] == {"informed": True, "params": {"distribution": "ggx", "alpha": 0.3}, "rule": ""}
    assert informed["metrics"]["relative_rmse"] <= informed["metrics"]["noise_floor"]
    assert informed["renders"] < r["renders"] / 2 and informed["reliable"] is True


@pytest.mark.parametrize("scheme", ["one", "two", "three"])
def test_roughplastic_schemes(tmp_path, root, mitsuba_adapter, scheme):
    _, r = _run(tmp_path, root, "blue-plastic.yaml", "--adapter", "mitsuba", "--model", "roughplastic",
                "--scheme", scheme, "--resolution", "64", "--fit-same-model")
    assert r["scheme_used"] == scheme
    assert list(dict.fromkeys(s["name"].split("@")[0] for s in r["stages"] if s["kept"])) == {"one": ["all"], "two": ["specular", "diffuse"],
                                                "three": ["specular", "diffuse", "joint"]}[scheme]
    assert r["metrics"]["relative_rmse"] < 0.01
    assert abs(r["params"]["alpha"] / 0.12 - 1) < 0.05


def test_a_two_stage_result_off_the_full_image_minimum_is_refined_jointly(tmp_path, root, mitsuba_adapter):
    """A rough red plastic, Beckmann to GGX: the lobe-wise fits merge 4.1 % away from a joint
    minimum near 2.2 %; the verdict's Gauss-Newton step sees it and two joint rounds reach it
    (one round stopped at 3.1 %; before the 0.2-point threshold none ran on grey α 0.2)."""
    mat = tmp_path / "red.yaml"
    mat.write_text("name: red\nadapter: mitsuba\nmodel: roughplastic\nparams: {distribution: beckmann, "
                   "diffuse_reflectance: [0.6, 0.08, 0.05], alpha: 0.5, int_ior: 1.3}\n")
    out = tmp_path / "out"
    assert main(["--source", str(mat), "--out", str(out), "--quiet", "--adapter", "mitsuba",
                 "--model", "roughplastic", "--fix", "distribution=ggx", "--fit-scene", "one-view"]) == 0
    r = read_result(out / "result.json")
    assert r["scheme_used"] == "two"
    assert [s["name"] for s in r["stages"] if s["name"].startswith("joint")] == ["joint-refine", "joint-refine #2"]
    assert any("joint refinement took it from" in n and "in 2 rounds" in n for n in r["notes"])
    assert r["metrics"]["relative_rmse"] < 0.025


def test_cross_model_plastic_to_principled(tmp_path, root, mitsuba_adapter):
    _, r = _run(tmp_path, root, "blue-plastic.yaml", "--adapter", "mitsuba", "--model", "principled",
                "--resolution", "64")
    assert r["scheme_used"] == "one" and any("declares no lobes" in n for n in r["notes"])
    assert r["metrics"]["relative_rmse"] < 0.25
    b = r["params"]["base_color"]
    assert b[2] > b[1] > b[0]  # still blue


def test_mitsuba_cli_wrapper_agrees_with_the_in_process_adapter(tmp_path, root, mitsuba_adapter):
    _, inproc = _run(tmp_path / "a", root, "copper.yaml", "--adapter", "mitsuba", "--model", "roughconductor",
                     "--fix", "distribution=ggx")
    _, cli = _run(tmp_path / "b", root, "copper.yaml", "--adapter", str(root / "configs/renderers/mitsuba-cli.yaml"),
                  "--model", "roughconductor", "--fix", "distribution=ggx")
    assert cli["target"]["adapter"] == "mitsuba-cli"
    assert abs(cli["params"]["alpha"] / inproc["params"]["alpha"] - 1) < 0.02
    assert abs(cli["metrics"]["relative_rmse"] - inproc["metrics"]["relative_rmse"]) < 0.01


def test_joint_rounds_that_do_not_realise_the_predicted_gain_leave_a_note_not_a_flag(mitsuba_adapter):
    """AlSb α 0.05 (Ashikhmin-Shirley) to Ward, as Fig. 5 fits it: the verdict's Gauss-Newton step
    predicted about 0.2 % from 0.52 %, two joint rounds reached 0.51 %. A prediction that steps
    cannot realise is no reason to call the result unreliable; it is reported as a note."""
    from brdfremap.core.job.execute import AdapterPool, execute
    from brdfremap.core.job.job import Job, Target, resolve
    from brdfremap.core.host.plugins import collect_adapters
    from brdfremap.core.data.schemas import Material
    from brdfremap.core.engine import Tuning
    from brdfremap.core.data.settings import Settings

    reg = collect_adapters()
    src = Material(adapter="mitsuba", model="ashikhmin_shirley", params={"material": "AlSb", "alpha": 0.05})
    job = Job(source=src, target=Target(adapter="mitsuba", model="ward", fix={"diffuse_reflectance": 0.0}),
              settings=Settings(jacobian_updates=0, start="defaults", validation="none",  # the probe's verdict
                                fit_scene="one-view"),  # as Fig. 5 fits it
              tuning=Tuning(min_highlight_px=0))  # the 32 px coarse level the case was measured with
    pool = AdapterPool(reg)
    pool.open["mitsuba"] = mitsuba_adapter  # the session's adapter: not closed here
    r = execute(resolve(job, reg), pool).report
    assert [s.name for s in r.stages if s.name.startswith("joint")]  # the rounds ran
    assert r.metrics.relative_rmse < 0.006
    assert "not at a minimum" not in r.reason and r.reliable, r.reason
    assert [f.kind for f in r.findings if f.kind == "prediction_not_realised"], r.notes


def test_the_same_job_into_the_same_folder_is_reused_and_force_fits_again(tmp_path, root, mitsuba_adapter, capsys):
    args = ["--adapter", "mitsuba", "--model", "roughconductor", "--fix", "distribution=ggx", "--resolution", "64"]
    out, first = _run(tmp_path, root, "gold.yaml", *args)
    capsys.readouterr()
    _, again = _run(tmp_path, root, "gold.yaml", *args)
    assert again == first and "the stored result of this same job" in capsys.readouterr().out
    _, forced = _run(tmp_path, root, "gold.yaml", *args, "--force")
    assert forced["params"] == first["params"] and forced["seconds"] != first["seconds"]
    # Another job into the folder replaces the result, and the files it does not have go.
    import hashlib

    (out / "material.blend").write_bytes(b"from an earlier Cycles result")
    doc = read_result(out / "result.json")
    doc["files"].append({"name": "material.blend", "sha256": hashlib.sha256(b"from an earlier Cycles result")
                         .hexdigest(), "bytes": 29})  # what brdf-remap wrote (a file it did not is never removed)
    (out / "result.json").write_text(json.dumps(doc))
    _, other = _run(tmp_path, root, "gold.yaml", *args[:-1], "48")
    assert other["key"] != first["key"] and not (out / "material.blend").exists()


def test_remap_render_writes_the_adapters_image(tmp_path, root, mitsuba_adapter):
    from brdfremap.core.data.scene import ProbeScene

    mat = root / "configs/materials/gold.yaml"
    assert main(["render", str(mat), "--out", str(tmp_path / "g.exr"), "--resolution", "48", "--quiet"]) == 0
    scene = ProbeScene(resolution=48)
    want = mitsuba_adapter.render("roughconductor", mitsuba_adapter.models["roughconductor"].complete(
        {"distribution": "beckmann", "material": "Au", "alpha": 0.1}), scene)
    assert np.array_equal(read_image(tmp_path / "g.exr"), want)
    assert main(["render", str(mat), "--out", str(tmp_path / "g.png"), "--resolution", "48", "--quiet"]) == 0
    assert (tmp_path / "g.png").stat().st_size > 0
    assert main(["render", str(mat), "--out", str(tmp_path / "g.jpg")]) == 2
    assert main(["render", str(mat), "--out", str(tmp_path / "d.exr"), "--lobe", "diffuse", "--quiet"]) == 2  # no such lobe
    assert main(["render", str(mat), "--out", str(tmp_path / "s.exr"), "--lobe", "specular", "--quiet"]) == 0

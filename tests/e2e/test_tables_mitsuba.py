"""`remap table build` and `remap --table` end to end with real Mitsuba renders: a small table of a
Fresnel-free rough metal to Ward, built, resumed, looked up with and without renders, and built
again on a Dask cluster."""

import json

import pytest
import yaml

from brdfremap.core.cli import main
from brdfremap.core.tables import read_table
from brdfremap.core.tables.table import TABLE_SCHEMA_VERSION
from helpers import one_line_error, remap
from reports import read_result

SPEC = {
    "kind": "table", "name": "metal to ward",
    "source": {"adapter": "mitsuba", "model": "roughconductor",
               "params": {"distribution": "beckmann", "eta": 0, "k": 1}},
    "axes": {"alpha": {"range": [0.05, 0.4], "steps": 4, "scale": "log"},
             "specular_reflectance": {"range": [0.3, 1.0], "steps": 3}},
    "target": {"adapter": "mitsuba", "model": "ward", "fix": {"diffuse_reflectance": 0}},
    "holdout": 3,
    "continuation": True,
    "scene": {"resolution": 48},
    "options": {"validation": "none"},
}
MATERIAL = {"adapter": "mitsuba", "model": "roughconductor",
            "params": {"distribution": "beckmann", "eta": 0, "k": 1, "alpha": 0.15,
                       "specular_reflectance": [0.9, 0.5, 0.3]}}


def _write(path, doc):
    path.write_text(yaml.safe_dump(doc))
    return path


def test_build_resume_and_look_up(tmp_path, mitsuba_adapter, capsys):
    spec, out = _write(tmp_path / "spec.yaml", SPEC), tmp_path / "table"
    assert main(["table", "build", str(spec), "--out", str(out), "--quiet"]) == 0
    printed = capsys.readouterr().out
    assert "12 points" in printed and "chosen" in printed
    table = read_table(out)
    assert len(table.points) == 12 and len(table.holdout) == 3
    # Each kind of map, with alpha (shared by the channels) read channel by channel and at the mean grey level.
    assert set(table.candidates) == {"multilinear", "polynomial", "rbf", "multilinear-mean", "polynomial-mean",
                                     "rbf-mean"}
    assert {c.channels for c in table.candidates.values()} == {"weighted", "mean"}
    assert all(c.median_ratio is not None and len(c.holdout_errors) == 3 for c in table.candidates.values())
    assert table.chosen in table.candidates and [o.label for o in table.outputs] == [
        "specular_reflectance", "alpha", "error"]
    for p in table.points:  # every point an ordinary stored remap
        read_result(out / "points" / p.id / "result.json")
    # Ward follows the source: its reflectance rises with the source's, its roughness with alpha.
    by = {(round(p.values["alpha"], 3), round(p.values["specular_reflectance"][0], 3)): p.params
          for p in table.points}
    assert by[(0.05, 1.0)]["specular_reflectance"][0] > by[(0.05, 0.3)]["specular_reflectance"][0]
    assert by[(0.4, 0.65)]["alpha"] > by[(0.05, 0.65)]["alpha"]
    assert (out / "points.csv").read_text().count("\n") == 16
    # Each point refitted from its neighbours' map, kept where as good; the refits stored beside the points.
    assert all((out / "points" / p.id / "continued" / "result.json").exists() for p in table.points)
    kept = [p for p in table.points if p.continued]
    assert kept and all(p.error <= 1.02 * p.first_error + 0.5 * p.noise_floor for p in kept)

    # Again: every fit and check is reused, and the table is the same.
    assert main(["table", "build", str(spec), "--out", str(out), "--quiet"]) == 0
    again = read_table(out)
    assert [p.params for p in again.points] == [p.params for p in table.points] and again.chosen == table.chosen

    material = _write(tmp_path / "m.yaml", MATERIAL)
    assert main(["--table", str(out), "--source", str(material), "--out", str(tmp_path / "instant"), "--quiet"]) == 0
    report = read_result(tmp_path / "instant" / "result.json")
    assert report["job"]["lookup"]["digest"] == table.digest and report["fitted"] == []
    assert report["renders"] <= 3 and report["metrics"]["relative_rmse"] < 0.05
    assert any(f["kind"] == "table_lookup" for f in report["findings"])
    shown = capsys.readouterr().out
    assert "table " in shown and "nothing fitted" in shown

    assert main(["--table", str(out / "table.json"), "--source", str(material), "--out", str(tmp_path / "bare"),
                 "--no-render", "--quiet"]) == 0
    from brdfremap.core.tables.lookup import LookupRecord

    doc = json.loads((tmp_path / "bare" / "lookup.json").read_text())
    LookupRecord.model_validate(doc)  # what `remap schema lookup` publishes
    assert doc["params"]["alpha"] == report["params"]["alpha"] and doc["lookup_seconds"] < 0.01
    assert (tmp_path / "bare" / "material.xml").exists() and not (tmp_path / "bare" / "result.json").exists()


def test_coloured_points_are_fitted_as_jobs_and_offered_as_corrections(tmp_path, mitsuba_adapter, capsys):
    """`colours: N`: N coloured source materials fitted beside the grid (ordinary stored jobs), and
    each map offered with their correction where it gains, judged on the held-out materials."""
    small = {**SPEC, "axes": {"alpha": {"range": [0.1, 0.3], "steps": 2},
                              "specular_reflectance": {"range": [0.3, 1.0], "steps": 3}},
             "holdout": 2, "colours": 6, "continuation": False, "scene": {"resolution": 32}}
    spec, out = _write(tmp_path / "spec.yaml", small), tmp_path / "table"
    assert main(["table", "build", str(spec), "--out", str(out), "--quiet"]) == 0
    assert "6 coloured points fitted" in capsys.readouterr().out
    table = read_table(out)
    assert table.schema_version == TABLE_SCHEMA_VERSION and len(table.colours) == 6
    for p in table.colours:
        read_result(out / "colours" / p.id / "result.json")
        assert len(set(p.values["specular_reflectance"])) == 3  # not grey
    corrected = {m: c for m, c in table.candidates.items() if c.correction}
    assert corrected and all(m.endswith("+colours") and c.median_ratio is not None for m, c in corrected.items())
    assert all(set(c.correction) == {"specular_reflectance"} for c in corrected.values())  # alpha is shared


def test_path_following_refits_along_an_axis_and_keeps_only_lower_fits(tmp_path, mitsuba_adapter, capsys):
    """`follow: [alpha]`: each grid point fitted again from its neighbour's fit along alpha, up then
    down, and each coloured point from the grid's map: stored jobs, each point's fit the lowest of
    its fits, and every refit counted once in the build's renders."""
    small = {**SPEC, "axes": {"alpha": {"range": [0.1, 0.3], "steps": 3},
                              "specular_reflectance": {"range": [0.5, 1.0], "steps": 2}},
             "holdout": 2, "colours": 2, "continuation": False, "follow": ["alpha"], "scene": {"resolution": 32}}
    spec, out = _write(tmp_path / "spec.yaml", small), tmp_path / "table"
    assert main(["table", "build", str(spec), "--out", str(out), "--quiet"]) == 0
    assert "continued from their neighbours along alpha" in capsys.readouterr().out
    table = read_table(out)
    assert table.schema_version == TABLE_SCHEMA_VERSION
    by_index = {tuple(p.index): p for p in table.points}
    for p in table.points:  # up from the lowest alpha, down from the highest
        folder = out / "points" / p.id
        ups, downs = folder / "alpha-up" / "result.json", folder / "alpha-down" / "result.json"
        assert ups.exists() == (p.index[0] > 0) and downs.exists() == (p.index[0] < 2)
        fits = [read_result(f) for f in (folder / "result.json", folder / "remedy" / "result.json", ups, downs)
                if f.exists()]
        assert p.error == min(f["metrics"]["relative_rmse"] for f in fits)  # the lowest of its fits
        assert p.continued == (p.error < fits[0]["metrics"]["relative_rmse"])
        if p.index[0] == 1:  # the first step up starts from the fit below it as it stood (its first or remedy)
            below = out / "points" / by_index[(0, p.index[1])].id
            starts = [read_result(f)["params"] for f in (below / "result.json", below / "remedy" / "result.json")
                      if f.exists()]
            start = read_result(ups)["job"]["start"]
            assert any(all(start[k] == pytest.approx(s[k]) for k in start) for s in starts)
    for p in table.colours:
        fits = [read_result(out / "colours" / p.id / f / "result.json") for f in (".", "followed")]
        assert p.error == min(f["metrics"]["relative_rmse"] for f in fits)
    stored = sum(read_result(f)["renders"] for f in out.rglob("result.json"))
    assert table.build.renders == stored  # every fit, refit and check counted once


def test_lookup_errors_are_one_line(tmp_path):
    # A table another model's material cannot use; an edited table; a value the table was not built for.
    from tablekit import write_synthetic

    out = write_synthetic(tmp_path)
    other = _write(tmp_path / "gold.yaml", {**MATERIAL, "params": {**MATERIAL["params"], "material": "Au"}})
    one_line_error(remap("--table", out, "--source", other, "--out", tmp_path / "o"), "params.material", "was built for")
    doc = json.loads((out / "table.json").read_text())
    doc["chosen"] = "rbf"
    (out / "table.json").write_text(json.dumps(doc))
    good = _write(tmp_path / "m.yaml", MATERIAL)
    one_line_error(remap("--table", out, "--source", good, "--out", tmp_path / "o"), "edited after it was built")
    one_line_error(remap("--table", tmp_path / "nowhere", "--source", good, "--out", tmp_path / "o"), "not found")
    one_line_error(remap("--source", good, "--out", tmp_path / "o"), "--adapter", "--table")
    one_line_error(remap("table", "bild"), "build, show")


def test_a_table_built_on_a_dask_cluster_is_the_same(tmp_path, mitsuba_adapter):
    """Two worker processes of a real LocalCluster fit the points: the same fits as in this process."""
    from distributed import LocalCluster

    small = {**SPEC, "axes": {"alpha": {"range": [0.1, 0.3], "steps": 2},
                              "specular_reflectance": {"range": [0.5, 1.0], "steps": 2}}, "holdout": 0,
             "continuation": False}
    spec = _write(tmp_path / "spec.yaml", small)
    assert main(["table", "build", str(spec), "--out", str(tmp_path / "here"), "--quiet"]) == 0
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        assert main(["table", "build", str(spec), "--out", str(tmp_path / "there"), "--quiet", "--scheduler",
                     cluster.scheduler_address]) == 0
    here, there = read_table(tmp_path / "here"), read_table(tmp_path / "there")
    # The same fits to the last bits but one: Dask's workers run BLAS on one thread, this process on
    # as many as it has, and a sum in another order can end an ulp apart (0.5570345170122838 for ...839).
    assert [p.params for p in there.points] == [_approx(p.params) for p in here.points]
    assert there.build.ran_in.startswith("dask at") and here.chosen == there.chosen


def _approx(params: dict) -> dict:
    return {k: v if isinstance(v, str) else pytest.approx(v, rel=1e-12, abs=1e-15) for k, v in params.items()}

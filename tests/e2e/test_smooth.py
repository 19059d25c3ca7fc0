"""A perfectly smooth material (issue 20): a mirror shows a point light as a point at most, so the
fit runs under the studio environment, and the rough target comes out near its smoothest."""

from brdfremap.core.cli import main
from reports import read_result


def test_a_smooth_silver_is_fitted_under_the_environment(tmp_path, mitsuba_adapter):
    src = tmp_path / "silver.yaml"
    src.write_text("adapter: mitsuba\nmodel: conductor\nparams: {material: Ag}\n")
    out = tmp_path / "out"
    assert main(["--source", str(src), "--adapter", "mitsuba", "--model", "roughconductor", "--fix", "material=Ag",
                 "--out", str(out), "--quiet", "--resolution", "48", "--validate", "none"]) in (0, 1)
    r = read_result(out / "result.json")
    assert "perfectly smooth" in r["fit_scene"]["why"]
    assert r["params"]["alpha"] < 0.02 and r["metrics"]["relative_rmse"] < 0.1

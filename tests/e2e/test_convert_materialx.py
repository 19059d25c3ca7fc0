"""MaterialX documents as their authors render them (issue 52), end to end through `remap convert`:
a document rendered by MaterialX's own GLSL and fitted to Blender's Principled BSDF from the fixed rule,
whose error the report gives beside the fit's; a document to its own model returned as it is, with no
fit; Blender's Principled fitted to OpenPBR in MaterialX's renderer, written as documents that validate.
Small scenes and few samples: the figures at full size are bench/materialx_corpus.py's."""

import json
from pathlib import Path

import pytest

from brdfremap.adapters.materialx.adapter import MaterialXAdapter
from brdfremap.core.cli import main
from conftest import need_adapter
from helpers import ROOT

FAST = ["--resolution", "48", "--spp", "16", "--quiet"]


def _convert(inputs, to: str, out: Path, *flags: str) -> dict:
    code = main(["convert", *map(str, inputs), "--to", to, "--out", str(out), *FAST, *flags])
    assert code == 0, code
    return json.loads((out / "convert.json").read_text())


def _result(out: Path, row: dict) -> dict:
    return json.loads((out / "materials" / row["slot"] / "result.json").read_text())


def test_a_document_fitted_to_principled_starts_from_the_rule_and_reports_its_error(corpus, tmp_path, cycles_adapter):
    need_adapter(MaterialXAdapter)
    doc = corpus / "materialx" / "StandardSurface" / "standard_surface_copper.mtlx"
    summary = _convert([doc], "cycles:principled", tmp_path / "o", "--validate", "none")
    (row,) = summary["materials"]
    result = _result(tmp_path / "o", row)
    assert (result["source"]["adapter"], result["source"]["model"]) == ("materialx", "standard_surface")
    assert result["start"]["rule"].startswith("MaterialX's standard_surface to Blender's Principled BSDF")
    assert result["renders"] > 0 and result["source_renders"] > 0  # both renderers drew it
    rule, fit = result["metrics"]["start_error"], result["metrics"]["relative_rmse"]
    assert fit <= rule  # the fit never worse than the rule it started from
    html = (tmp_path / "o" / "index.html").read_text()
    assert "the fixed rule (MaterialX&#39;s standard_surface" in html and f"{100 * rule:.2f} %" in html
    assert {"library.blend", "library.mtlx", "library.usda"} <= set(summary["libraries"])
    assert "not matched in MaterialX" in (tmp_path / "o" / "library.mtlx").read_text()  # Principled as OpenPBR: said


def test_a_document_to_its_own_model_is_returned_with_nothing_fitted(corpus, tmp_path):
    """The pearl (OpenPBR, random-walk subsurface in a path tracer) to OpenPBR: its own values, ok, one
    source render for the images and none of the target's; the library holds the document's values."""
    need_adapter(MaterialXAdapter)
    import MaterialX as mx

    pearl = corpus / "materialx" / "OpenPbr" / "open_pbr_pearl.mtlx"
    summary = _convert([pearl], "materialx", tmp_path / "o")
    (row,) = summary["materials"]
    result = _result(tmp_path / "o", row)
    assert row["status"] == "ok" and result["renders"] == 0 and result["source_renders"] == 1
    assert result["metrics"]["relative_rmse"] == 0.0 and [f["kind"] for f in result["findings"]] == ["same_material"]
    assert result["params"]["subsurface_weight"] == 1.0 and result["params"]["coat_ior"] == pytest.approx(1.68)
    doc = mx.createDocument()
    mx.readFromXmlFile(doc, str(tmp_path / "o" / "library.mtlx"))
    shader = doc.getNodes()[0]
    assert shader.getCategory() == "open_pbr_surface" and shader.getInputValue("coat_ior") == pytest.approx(1.68)


def test_principled_fitted_to_openpbr_writes_documents_that_validate(tmp_path, cycles_adapter):
    """Blender's Principled copper to MaterialX's OpenPBR, judged in MaterialX's renderer: `library.mtlx` holds
    the fitted values and validates; `library.usda` holds the same shader written in USD."""
    need_adapter(MaterialXAdapter)
    import MaterialX as mx
    from brdfremap.adapters.materialx.mxlib import standard_libraries

    summary = _convert([ROOT / "configs" / "materials" / "cycles-copper.yaml"], "materialx:open_pbr_surface",
                       tmp_path / "o", "--validate", "none")
    (row,) = summary["materials"]
    result = _result(tmp_path / "o", row)
    assert row["status"] in ("ok", "mismatch") and result["metrics"]["relative_rmse"] < 0.05, row
    doc = mx.createDocument()
    mx.readFromXmlFile(doc, str(tmp_path / "o" / "library.mtlx"))
    doc.importLibrary(standard_libraries())
    assert doc.validate()[0]
    shader = next(n for n in doc.getNodes() if n.getCategory() == "open_pbr_surface")
    assert shader.getInputValue("specular_roughness") == pytest.approx(result["params"]["specular_roughness"], abs=1e-6)
    assert "ND_open_pbr_surface_surfaceshader" in (tmp_path / "o" / "library.usda").read_text()

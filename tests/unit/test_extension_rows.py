"""The extension's panel lines from `convert.json` (extension/brdf_remap/results.py, no bpy): a converted
material says what its verdict tells (a uniform target for a textured source), a refused one why."""

import importlib.util
import sys
from pathlib import Path

from helpers import ROOT


def _results():
    spec = importlib.util.spec_from_file_location("panel_results", ROOT / "extension" / "brdf_remap" / "results.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # a dataclass looks its module up there
    spec.loader.exec_module(module)
    return module


def test_a_panel_line_says_the_verdict_of_a_converted_material_and_the_reason_of_a_refused_one(tmp_path):
    results = _results()
    summary = {"materials": [
        {"name": "wood", "status": "mismatch", "relative_rmse": 0.226, "model": "principled", "reason": "",
         "slot": "wood-1", "verdict": "the target is uniform where the source is not (base_color <- image 'wood.png')"},
        {"name": "gold", "status": "ok", "relative_rmse": 0.0, "model": "principled", "reason": "", "slot": "gold-1",
         "verdict": ""},
        {"name": "empty", "status": "unsupported", "relative_rmse": None, "model": None,
         "reason": "nothing is connected to the Material Output's Surface", "slot": None}]}
    lines = {r.name: r.line() for r in results.rows(summary, Path(tmp_path))}
    assert lines["wood"] == ("mismatch, 22.60% (principled): the target is uniform where the source is not "
                             "(base_color <- image 'wood.png')")
    assert lines["gold"] == "ok, 0.00% (principled)"
    assert lines["empty"] == "unsupported, –: nothing is connected to the Material Output's Surface"

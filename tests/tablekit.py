"""A remap table made without renders, for the tests of tables and lookups."""

import json

import yaml

from brdfremap.core.data.scene import ProbeScene
from brdfremap.core.tables import Layout, load_table_spec
from brdfremap.core.tables.outputs import outputs_for
from brdfremap.core.tables.table import TABLE_SCHEMA_VERSION, BuildRecord, PointRecord, PointVerdict, Table

SPEC = {
    "kind": "table", "name": "t",
    "source": {"adapter": "mitsuba", "model": "roughconductor", "params": {"distribution": "beckmann", "eta": 0,
                                                                            "k": 1}},
    "axes": {"alpha": {"range": [0.05, 0.4], "steps": 4, "scale": "log"},
             "specular_reflectance": {"range": [0.3, 1.0], "steps": 3}},
    "target": {"adapter": "mitsuba", "model": "ward", "fix": {"diffuse_reflectance": 0}},
    "holdout": 4,
}


def synthetic_table(tmp_path, axes: dict | None = None) -> Table:
    """A table whose 'fits' follow a known rule: Ward's reflectance = 0.9 x the source's, alpha = 1.1 x
    (``axes``: the spec's axes instead of SPEC's)."""
    path = tmp_path / "synthetic-spec.yaml"
    path.write_text(yaml.safe_dump(json.loads(json.dumps({**SPEC, **({"axes": axes} if axes else {})}))))
    spec = load_table_spec(path)
    layout = Layout(spec.axes, {"alpha": "scalar", "specular_reflectance": "rgb"})
    from brdfremap.adapters.mitsuba.models import MODELS

    ward = MODELS["ward"]
    points = []
    for i, (idx, v) in enumerate(layout.grid()):
        params = {"variant": "balanced", "ensure_energy_conservation": "true", "diffuse_reflectance": [0, 0, 0],
                  "specular_reflectance": [0.9 * c for c in v["specular_reflectance"]], "alpha": 1.1 * v["alpha"]}
        points.append(PointRecord(id=f"g{i}", index=list(idx), values=v, params=params, error=0.01 + v["alpha"] / 10,
                                  verdict="ok", used=True))
    points[5] = points[5].model_copy(update={"used": False, "left_out": "not at a minimum", "verdict": PointVerdict.UNRELIABLE,
                                             "params": {**points[5].params, "alpha": 0.9}})
    table = Table(schema_version=TABLE_SCHEMA_VERSION, tool="test", name="synthetic", spec=spec, scene=ProbeScene(),
                  source_kinds=layout.kinds, source_params={"distribution": "beckmann", "material": "none",
                                                             "eta": [0, 0, 0], "k": [1, 1, 1]},
                  target_params=ward.complete({"diffuse_reflectance": 0.0}), versions={"mitsuba": "2"},
                  outputs=outputs_for(ward, ["specular_reflectance", "alpha"], layout.separable), points=points,
                  holdout=[], candidates={}, chosen="polynomial", chosen_why="test",
                  build=BuildRecord(points=len(points), used=len(points) - 1, flagged=1, left_out=1, holdout=0, renders=0, seconds=0,
                                    wall_seconds=0, ran_in="test"))
    from brdfremap.core.tables.build import fit_candidates

    return table.model_copy(update={"candidates": fit_candidates(table)})


def write_synthetic(tmp_path):
    """The synthetic table written as `remap table build` writes one: its folder."""
    from brdfremap.core.tables.table import write_table

    folder = tmp_path / "synthetic"
    folder.mkdir()
    write_table(folder / "table.json", synthetic_table(tmp_path))
    return folder


def principled_table(tmp_path) -> Table:
    """A table from a Fresnel-free Beckmann metal to Cycles' Principled BSDF whose 'fits' are the
    exporters' conversion (Base Color = the reflectance, Roughness = sqrt(alpha), Metallic 1): a
    table of the right shape for the textured path, made without a fit."""
    from brdfremap.adapters.cycles.models import PRINCIPLED
    from brdfremap.core.tables.build import fit_candidates

    doc = json.loads(json.dumps(SPEC))
    doc.update(name="synthetic principled", target={"adapter": "cycles", "model": "principled",
                                                    "fix": {"distribution": "multi_ggx"}}, holdout=0)
    path = tmp_path / "principled-spec.yaml"
    path.write_text(yaml.safe_dump(doc))
    spec = load_table_spec(path)
    layout = Layout(spec.axes, {"alpha": "scalar", "specular_reflectance": "rgb"})
    base = PRINCIPLED.complete({"distribution": "multi_ggx", "metallic": 1.0})
    points = []
    for i, (idx, v) in enumerate(layout.grid()):
        params = {**{k: list(x) if isinstance(x, tuple) else x for k, x in base.items()},
                  "base_color": list(v["specular_reflectance"]), "roughness": v["alpha"] ** 0.5}
        points.append(PointRecord(id=f"g{i}", index=list(idx), values=v, params=params, error=0.1, verdict="mismatch",
                                  used=True))
    table = Table(schema_version=TABLE_SCHEMA_VERSION, tool="test", name="synthetic principled", spec=spec,
                  scene=ProbeScene(),
                  source_kinds=layout.kinds, source_params={"distribution": "beckmann", "material": "none",
                                                             "eta": [0, 0, 0], "k": [1, 1, 1]},
                  target_params=base, versions={"mitsuba": "2", "cycles": "1"},
                  outputs=outputs_for(PRINCIPLED, ["base_color", "metallic", "roughness"], True), points=points,
                  holdout=[], candidates={}, chosen="polynomial", chosen_why="test",
                  build=BuildRecord(points=12, used=12, flagged=0, left_out=0, holdout=0, renders=0, seconds=0,
                                    wall_seconds=0, ran_in="test"))
    return table.model_copy(update={"candidates": fit_candidates(table)})

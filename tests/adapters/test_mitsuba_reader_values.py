"""The Mitsuba XML reader's values are the ones Mitsuba itself uses: for every BSDF of every scene
of the corpus (and the project's own spectral files), the reader's material, built as a Mitsuba
BSDF, traverses to what Mitsuba gives loading the file in `scalar_rgb` (to 1e-3)."""

import json
import subprocess
import sys
from pathlib import Path

import pytest
from brdfremap.adapters.mitsuba.adapter import bsdf_dict
from brdfremap.adapters.mitsuba.models import MODELS
from brdfremap.core.library.formats import collect_formats, read_all

pytest.importorskip("mitsuba")
TOOLS = Path(__file__).resolve().parents[1] / "tools"
DATA = Path(__file__).resolve().parents[1] / "data"
LEAVES_NOT_READ = {"eta"}
"""Traverse leaves with no parameter of their own here: a principled's eta is read as its specular
(the same F0), compared through that."""


def mitsuba_values(items: list[dict]) -> list[dict]:
    run = subprocess.run([sys.executable, str(TOOLS / "mitsuba_values.py")], input=json.dumps(items),
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-2000:]
    return json.loads(run.stdout)


def _as_list(v):
    return v if isinstance(v, list) else [v] * 3


WRAPPER_LEAVES = {"scale"}
"""A bump map's own strength: the wrapper is unwrapped with a note."""


def _textures_as_constants(theirs: dict) -> dict:
    """A checkerboard's two colours as its mean (the reader's constant); a bitmap's texels, not a
    constant, left out."""
    out = {k: v for k, v in theirs.items() if "." not in k and k not in WRAPPER_LEAVES}
    for k in {k.split(".", 1)[0] for k in theirs if k.endswith(".color0")}:
        c0, c1 = _as_list(theirs[f"{k}.color0"]), _as_list(theirs[f"{k}.color1"])
        out[k] = [(a + b) / 2 for a, b in zip(c0, c1)]
    return out


def differences(theirs: dict, ours: dict) -> list[str]:
    out = []
    for leaf, v in _textures_as_constants(theirs).items():
        if leaf in LEAVES_NOT_READ and leaf not in ours:
            continue
        if leaf not in ours:
            out.append(f"{leaf}: Mitsuba has {v}, the reading has nothing")
            continue
        a, b = _as_list(v), _as_list(ours[leaf])
        if len(a) != len(b) or any(abs(x - y) > 1e-3 * max(1.0, abs(x)) for x, y in zip(a, b)):
            out.append(f"{leaf}: Mitsuba {v}, the reading {ours[leaf]}")
    return out


def _files(corpus: Path) -> list[Path]:
    return sorted((corpus / "mitsuba-data" / "docs" / "scenes").glob("*.xml")) + [DATA / "scenes" / "spectral.xml"]


def _read_as_itself(material) -> bool:
    """A reading of the BSDF's own type: not one with no reading, nor one read as another type to start a fit
    (`AS_WRITTEN`: a pplastic read as a roughplastic), which Mitsuba renders as written."""
    from brdfremap.adapters.mitsuba.reader import AS_WRITTEN

    native = material.native
    return bool(material.model) and (native is None or not any(f'type="{k}"' in native.element for k in AS_WRITTEN))


def test_every_value_read_is_the_one_mitsuba_uses(corpus):
    formats = collect_formats()
    reader = next(r for r in formats.readers if ".xml" in r.suffixes)
    files = _files(corpus)
    entries = {f: [e for e in reader.read(f) if e.material is not None and _read_as_itself(e.material)] for f in files}
    theirs = mitsuba_values([{"file": str(f), "ids": [e.name for e in entries[f]]} for f in files])
    ours_items, where = [], []
    for f in files:
        for e in entries[f]:
            params = MODELS[e.material.model].complete(e.material.params)
            ours_items.append({"dict": bsdf_dict(e.material.model, params)})
            where.append((f, e.name))
    ours = dict(zip(where, mitsuba_values(ours_items)))
    compared, problems = 0, []
    for f, got in zip(files, theirs):
        if "error" in got:
            continue  # Mitsuba cannot load it in scalar_rgb (a polarized or measured BSDF): nothing to compare
        for e in entries[f]:
            mine = ours[(f, e.name)]
            if "error" in mine:
                problems.append(f"{f.name} {e.name}: our BSDF does not load: {mine['error']}")
                continue
            if e.name not in got or not got[e.name]:
                continue  # an anonymous BSDF (named after its shape): Mitsuba gives it no id to find
            compared += 1
            problems += [f"{f.name} {e.name}: {d}" for d in differences(got[e.name], mine["bsdf"])]
    assert not problems, "\n".join(problems)
    assert compared >= 40

"""What Mitsuba itself reads: each BSDF's parameters as `mi.traverse` shows them after loading in
`scalar_rgb` (run in a process of its own, so the tests' own Mitsuba variant is left alone).

Reads a JSON list on stdin, each item {"file": scene.xml, "ids": [BSDF ids]} or
{"dict": a BSDF dictionary} (one, as "bsdf"); prints, per item, {id: {leaf: value}} or
{"error": why Mitsuba cannot load it}. A leaf is the traverse key without the BSDF's id and the
wrappers' names (twosided's brdf_0, a bump map's nested_bsdf), and without `.value`."""

import json
import re
import sys

import mitsuba as mi

mi.set_variant("scalar_rgb")
mi.set_log_level(mi.LogLevel.Error)
WRAPPER = re.compile(r"^(brdf_0|nested_bsdf|bsdf)\.")


def leaves(params, prefix: str) -> dict:
    out = {}
    for key in params.keys():
        if not key.startswith(prefix + "."):
            continue
        leaf = key[len(prefix) + 1:]
        while WRAPPER.match(leaf):
            leaf = WRAPPER.sub("", leaf, count=1)
        leaf = leaf.removesuffix(".value")
        try:
            v = params[key]
            v = [float(x) for x in v] if hasattr(v, "__len__") else float(v)
        except (TypeError, ValueError):
            continue
        out[leaf] = v
    return out


def one(item: dict) -> dict:
    try:
        if "file" in item:
            scene = mi.load_file(item["file"])
            params = mi.traverse(scene)
            return {i: leaves(params, i) for i in item["ids"]}
        return {"bsdf": leaves(mi.traverse(mi.load_dict({"type": "scene", "bsdf": item["dict"]})), "bsdf")}
    except Exception as exc:  # Mitsuba's own refusal is the answer
        return {"error": str(exc).strip().splitlines()[-1][:300]}


print(json.dumps([one(item) for item in json.load(sys.stdin)]))

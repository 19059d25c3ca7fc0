"""Blender Cycles as an external renderer in brdf-remap's persistent protocol.

An example of the renderer side of `mode: persistent` (see cycles-subprocess.yaml):
greet with one JSON line {"ok": true}, then answer each request line
{"op": "render", "scene": {...}, "model": ..., "params": {...}, "output": path} with
{"ok": true} once the float32 EXR is at `output`, or {"ok": false, "error": ...}.
Only the protocol channel may use stdout, so Blender's chatter is sent to stderr."""

import json
import os
import sys
import traceback

proto = os.fdopen(os.dup(1), "w", buffering=1)
os.dup2(2, 1)
sys.stdout = sys.stderr


def send(msg):
    proto.write(json.dumps(msg) + "\n")
    proto.flush()


# The scene set-up (units, exact sphere, black world, direct light) is the Cycles adapter's.
from brdfremap.adapters.cycles.worker import BlenderState  # noqa: E402

state = BlenderState()
send({"ok": True})
for line in sys.stdin:
    req = None
    try:
        req = json.loads(line)
        if req.get("op") == "quit":
            break
        # The full image only (this protocol isolates no lobe): no lobe passes to accumulate.
        state.render({"scene": req["scene"], "model": req["model"], "params": req["params"], "out": req["output"],
                      "passes": False})
        send({"id": req.get("id"), "ok": True})
    except Exception as exc:  # report, keep serving
        traceback.print_exc()
        send({"id": (req or {}).get("id"), "ok": False, "error": f"{type(exc).__name__}: {exc}"})

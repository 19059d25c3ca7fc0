"""A misbehaving external renderer for the subprocess adapter's fault tests.

Renders the analytic Lambert sphere of the scene it is given (a correct renderer), unless
the material's `fault` parameter asks for one of the faults the adapter must survive."""

import json
import os
import subprocess
import sys
import time

import numpy as np


def image(scene_doc, albedo):
    from brdfremap.core.data.scene import Camera, PointLight, ProbeScene, Sphere
    from brdfremap.core.testing import box_filtered_lambert

    cam, light = scene_doc["camera"], scene_doc["light"]
    # Rebuild a ProbeScene from the resolved document (camera on +z of its target, as the probe has).
    dist = float(np.linalg.norm(np.subtract(cam["position"], cam["target"])))
    lp = np.asarray(light["position"], float)
    r = float(np.linalg.norm(lp))
    scene = ProbeScene(
        sphere=Sphere(center=scene_doc["sphere"]["center"], radius=scene_doc["sphere"]["radius"]),
        camera=Camera(distance=dist, target=cam["target"], fov=cam["fov"], up=cam["up"]),
        light=PointLight(r=r, theta=float(np.degrees(np.arccos(lp[2] / r))),
                         phi=float(np.degrees(np.arctan2(lp[1], lp[0]))), intensity=light["intensity"]),
        resolution=scene_doc["width"], spp=scene_doc["spp"], seed=scene_doc["seed"])
    return box_filtered_lambert(scene, albedo)  # a pixel integrates its area, as a renderer's box filter does


def write(path, pixels):
    import OpenImageIO as oiio

    h, w, c = pixels.shape
    out = oiio.ImageOutput.create(path)
    out.open(path, oiio.ImageSpec(w, h, c, "float"))
    out.write_image(np.ascontiguousarray(pixels, np.float32))
    out.close()


def render(scene_doc, params, output):
    fault = params.get("fault", "none")
    print(f"fake renderer: fault={fault}", file=sys.stderr, flush=True)
    if fault == "exit":
        print("fake renderer: cannot parse the material", file=sys.stderr)
        sys.exit(3)
    if fault == "hang":
        token = os.environ.get("FAKE_HANG_TOKEN", "")  # names this run's helper for the test that looks for it
        subprocess.Popen([sys.executable, "-c", "import time; time.sleep(120)", token])  # a helper to be killed too
        time.sleep(120)
    if fault == "no_output":
        return
    img = image(scene_doc, params.get("albedo", [0.8] * 3))
    if fault == "nan":
        img[5, 5, 1] = np.nan
    if fault == "wrong_size":
        img = img[:-4, :-4]
    write(output, img)
    if fault == "truncated":
        with open(output, "r+b") as f:
            f.truncate(os.path.getsize(output) // 2)
    if fault == "garbage":
        with open(output, "wb") as f:
            f.write(b"this is not an image")


def main():
    if sys.argv[1] == "--persistent":
        print(json.dumps({"ok": True}), flush=True)
        for line in sys.stdin:
            req = json.loads(line)
            if req.get("op") == "quit":
                break
            if req["params"].get("fault") == "die":
                print("fake renderer: segfault-like death", file=sys.stderr, flush=True)
                os._exit(11)
            if req["params"].get("fault") == "stray":  # a chatty renderer: JSON that answers nothing
                print(json.dumps({"progress": 0.5}), flush=True)
                print(json.dumps({"id": -1, "ok": True}), flush=True)
            render(req["scene"], req["params"], req["output"])
            print(json.dumps({"id": req.get("id"), "ok": True}), flush=True)
        return
    pairs = list(zip(sys.argv[1::2], sys.argv[2::2]))
    args = dict(pairs)
    if os.environ.get("FAKE_ARGV_LOG"):
        with open(os.environ["FAKE_ARGV_LOG"], "a") as f:
            f.write(json.dumps(sys.argv[1:]) + "\n")
    scene_doc = json.load(open(args["--scene"]))
    params = json.load(open(args["--params"]))["params"]
    render(scene_doc, params, args["--out"])


if __name__ == "__main__":
    main()

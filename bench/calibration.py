"""Cross-renderer calibration: a white (0.8) Lambertian sphere in every adapter.

    python bench/calibration.py

Prints each adapter's relative RMSE against Mitsuba (whole image) and against the analytic
radiance (interior pixels, where no pixel straddles the silhouette), at 128², 64 spp."""

from __future__ import annotations

from common import open_adapters, registry

from brdfremap.core.data.metrics import relative_rmse
from brdfremap.core.data.scene import ProbeScene
from brdfremap.core.testing import analytic_lambert, sphere_hits

WHITE = {"mitsuba": ("diffuse", {"reflectance": 0.8}), "cycles": ("diffuse", {"color": 0.8})}


def main():
    reg = registry()
    scene = ProbeScene(spp=64)
    ref = analytic_lambert(scene, 0.8)
    inner = sphere_hits(scene).interior
    with open_adapters(reg, ["mitsuba", "cycles"]) as adapters:
        images = {}
        for name in ("mitsuba", "cycles"):
            model, given = WHITE[name]
            spec = reg.get(name).models[model]
            images[name] = adapters[name].render(model, spec.complete(given), scene)
        print(f"{'adapter':<10} {'vs mitsuba (whole image)':>26} {'vs analytic (interior)':>24}")
        for name, img in images.items():
            print(f"{name:<10} {relative_rmse(images['mitsuba'], img):26.3%} "
                  f"{relative_rmse(ref[inner], img[inner]):24.3%}")


if __name__ == "__main__":
    main()
